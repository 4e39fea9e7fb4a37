//! The split driver's controller configured **in place** (issue 21: no large value
//! moves through configuration): [`BxCan::can1_in`] and its siblings write the
//! controller field by field into storage the caller lends — the slot of a `static`
//! `twocan_core::split::State`, through `State::split_with` — then run the whole
//! configuration there: initialization mode, options and timing (RM0410 §40.4.1), the
//! filter banks and the thread-side map from the plan, read where it lies (a `const`
//! plan in flash, [`crate::const_plan!`], or a run-time one in the planner's `static`
//! scratch, [`crate::planner::plan_in`]), and normal mode (§40.4.2). Neither the
//! controller, nor the map, nor the plan is ever a value on the stack, so the stack of
//! the configuration is a few hundred bytes whatever `K`.
//!
//! ```no_run
//! use twocan_bxcan::regs::CanRegs;
//! use twocan_bxcan::{const_plan, BxCan, Config, PlanOptions};
//! use twocan_core::split::State;
//! use twocan_core::{FifoQueue, Filter};
//!
//! const CONFIG: Config = match Config::from_bitrate(54_000_000, 500_000) {
//!     Ok(c) => c,
//!     Err(_) => panic!("no timing"),
//! };
//! const FILTERS: [Filter; 1] = [Filter::pass_all()];
//! // A map with no lookup key (K = 0): the plan has no merged slot.
//! type Hw = BxCan<CanRegs, CanRegs, 0>;
//! static CAN: State<Hw, 8, FifoQueue<4>, 0, 0> = State::new();
//!
//! // SAFETY: CAN1's register block (RM0410 §2.2.2), owned by this driver only.
//! let regs = unsafe { CanRegs::new(twocan_bxcan::regs::CAN1_BASE) };
//! let plan = const_plan!(FILTERS, PlanOptions::new(14));
//! let parts = CAN
//!     .split_with(|slot| BxCan::can1_in(slot, regs, &CONFIG, plan).map_err(|f| f.error))
//!     .unwrap();
//! # let _ = parts;
//! ```

use core::cell::UnsafeCell;
use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;
use core::sync::atomic::{AtomicBool, AtomicU32, AtomicU8};

use twocan_core::{AtomicLastError, Error, Frame, LastErrorCode, Mode, Registers};

use super::BxCan;
use crate::config::Config;
use crate::controller::{enter_configuration, Failed};
use crate::filter_block;
use crate::filters::{FmiMap, PlanRef};
use crate::instance::Instance;
use crate::mode;
use crate::regs::{btr, BTR, TX_MAILBOXES};

/// What an in-place constructor gives back when the configuration fails: the storage
/// it was lent (uninitialised again) and the register handles, so that the caller can
/// try again (e.g. after a [`Error::Timeout`] of a mode request) or use them otherwise.
pub struct Unconfigured<
    's,
    R: Registers,
    F: Registers,
    const K: usize,
    const M: usize,
    const SWITCH: bool,
> {
    /// The storage, uninitialised.
    pub slot: &'s mut MaybeUninit<BxCan<R, F, K, M, SWITCH>>,
    /// The instance's registers.
    pub regs: R,
    /// CAN1's filter registers, for CAN2 and a dual CAN1.
    pub filter_regs: Option<F>,
}

/// The result of an in-place constructor: the configured controller, in its storage,
/// or why not with everything it was given back.
pub type InPlace<'s, R, F, const K: usize, const M: usize, const SWITCH: bool> =
    Result<&'s mut BxCan<R, F, K, M, SWITCH>, Failed<Unconfigured<'s, R, F, K, M, SWITCH>>>;

impl<R: Registers, const K: usize, const M: usize, const SWITCH: bool> BxCan<R, R, K, M, SWITCH> {
    /// CAN1 (the master, its own whole register block), configured in `slot` with
    /// `config` and the filters of `plan`, on the bus when this returns `Ok`: the
    /// sequence of [`crate::Can::can1`], [`crate::Init::set_filters`],
    /// [`crate::Init::enable`] and [`crate::Can::into_split`], without moving the
    /// controller (see `split::in_place` in the source). `K`: the lookup capacity of the
    /// controller's filter map (0 for a plan without merged slots).
    ///
    /// Errors, with the slot and the registers back ([`Unconfigured`]):
    /// [`Error::Timeout`] when initialization or normal mode is not acknowledged (no
    /// clock; `enable` waits for 11 recessive bits on CANRX, RM0410 §40.4.2);
    /// [`Error::FilterSpace`] when the plan needs more lookup keys than `K`;
    /// [`Error::InvalidArgument`] when it has more banks than the instance owns; the
    /// start bank errors of [`crate::Can::can1`].
    #[allow(clippy::result_large_err)]
    pub fn can1_in<'s, 'p>(
        slot: &'s mut MaybeUninit<Self>,
        regs: R,
        config: &Config,
        plan: impl Into<PlanRef<'p>>,
    ) -> InPlace<'s, R, R, K, M, SWITCH> {
        Self::configure_in(slot, regs, None, Instance::Can1, config, plan.into())
    }

    /// CAN3 (F76x/F77x: its own 14 filter banks), as [`BxCan::can1_in`].
    #[allow(clippy::result_large_err)]
    pub fn can3_in<'s, 'p>(
        slot: &'s mut MaybeUninit<Self>,
        regs: R,
        config: &Config,
        plan: impl Into<PlanRef<'p>>,
    ) -> InPlace<'s, R, R, K, M, SWITCH> {
        Self::configure_in(slot, regs, None, Instance::Can3, config, plan.into())
    }
}

impl<R: Registers, F: Registers, const K: usize, const M: usize, const SWITCH: bool>
    BxCan<R, F, K, M, SWITCH>
{
    /// CAN1 as the master of a dual set-up (control registers `regs`, the shared filter
    /// block `filters`; see [`crate::Can::can1_dual`]), as [`BxCan::can1_in`].
    #[allow(clippy::result_large_err)]
    pub fn can1_dual_in<'s, 'p>(
        slot: &'s mut MaybeUninit<Self>,
        regs: R,
        filters: F,
        config: &Config,
        plan: impl Into<PlanRef<'p>>,
    ) -> InPlace<'s, R, F, K, M, SWITCH> {
        Self::configure_in(
            slot,
            regs,
            Some(filters),
            Instance::Can1,
            config,
            plan.into(),
        )
    }

    /// CAN2 (the slave: its filters in CAN1's block, banks `CAN2SB..28`; see
    /// [`crate::Can::can2`]), as [`BxCan::can1_in`].
    #[allow(clippy::result_large_err)]
    pub fn can2_in<'s, 'p>(
        slot: &'s mut MaybeUninit<Self>,
        regs: R,
        can1_filters: F,
        config: &Config,
        plan: impl Into<PlanRef<'p>>,
    ) -> InPlace<'s, R, F, K, M, SWITCH> {
        Self::configure_in(
            slot,
            regs,
            Some(can1_filters),
            Instance::Can2,
            config,
            plan.into(),
        )
    }

    /// Writes the controller into `slot` field by field, then configures it there.
    #[allow(clippy::result_large_err)]
    fn configure_in<'s>(
        slot: &'s mut MaybeUninit<Self>,
        regs: R,
        filter_regs: Option<F>,
        instance: Instance,
        config: &Config,
        plan: PlanRef<'_>,
    ) -> InPlace<'s, R, F, K, M, SWITCH> {
        let p = slot.as_mut_ptr();
        // SAFETY: `p` points to `slot`'s storage, valid for writes and aligned; each
        // field is written once through `addr_of_mut!` (no reference to the
        // uninitialised value is made), the map in place through its own writer.
        // Every field of `BxCan` is written below, so the value is initialised
        // afterwards.
        unsafe {
            addr_of_mut!((*p).regs).write(regs);
            addr_of_mut!((*p).filter_regs).write(filter_regs);
            addr_of_mut!((*p).instance).write(instance);
            addr_of_mut!((*p).config).write(*config);
            // `UnsafeCell<T>` has the layout of `T`.
            FmiMap::<K, M>::write_empty(UnsafeCell::raw_get(addr_of_mut!((*p).fmi)));
            addr_of_mut!((*p).tokens).write([const { AtomicU32::new(0) }; TX_MAILBOXES]);
            addr_of_mut!((*p).loads).write([const { AtomicU32::new(0) }; TX_MAILBOXES]);
            addr_of_mut!((*p).load_count).write(AtomicU32::new(0));
            addr_of_mut!((*p).displacing).write(AtomicU8::new(0));
            addr_of_mut!((*p).aborting).write(AtomicU8::new(0));
            addr_of_mut!((*p).displaced).write(UnsafeCell::new([Frame::default(); TX_MAILBOXES]));
            addr_of_mut!((*p).last_error).write(AtomicLastError::new(LastErrorCode::None));
            addr_of_mut!((*p).wait).write(AtomicU32::new(config.get_wait_iterations()));
            addr_of_mut!((*p).listen_only).write(AtomicBool::new(false));
            addr_of_mut!((*p).generation).write(AtomicU32::new(0));
            addr_of_mut!((*p).discarded).write(AtomicU32::new(0));
            addr_of_mut!((*p).fed).write(AtomicU8::new(0));
        }
        // SAFETY: every field was written just above.
        let hw = unsafe { slot.assume_init_mut() };
        match hw.configure_here(plan) {
            Ok(()) => {
                // SAFETY: `slot` is initialised (above) and lent for `'s`; the
                // reference `hw` is not used any more.
                Ok(unsafe { &mut *p })
            }
            Err(error) => {
                // SAFETY: the value is initialised; the register handles are moved
                // out once, and the rest of it (plain data and atomics, no `Drop`) is
                // abandoned: the storage counts as uninitialised again.
                let (regs, filter_regs) = unsafe {
                    (
                        core::ptr::read(addr_of_mut!((*p).regs)),
                        core::ptr::read(addr_of_mut!((*p).filter_regs)),
                    )
                };
                Err(Failed {
                    error,
                    value: Unconfigured {
                        slot,
                        regs,
                        filter_regs,
                    },
                })
            }
        }
    }

    /// The configuration of a controller written in place: initialization mode and the
    /// configuration registers, the map then the banks (a plan the map cannot hold is
    /// refused before any bank changes), normal mode, and what the split driver reads
    /// from the registers (listen-only, the FIFOs the banks feed).
    fn configure_here(&mut self, plan: PlanRef<'_>) -> Result<(), Error> {
        let config = self.config;
        enter_configuration(
            &self.regs,
            self.filter_regs.as_ref(),
            self.instance,
            &config,
        )?;
        self.fmi.get_mut().fill(plan)?;
        let instance = self.instance;
        let chip = config.get_chip();
        let programmed = match &self.filter_regs {
            Some(f) => filter_block::program(f, chip, instance, plan),
            None => filter_block::program(&self.regs, chip, instance, plan),
        };
        programmed.map_err(|_| Error::InvalidArgument)?;
        mode::request(&self.regs, Mode::Normal, config.get_wait_iterations())?;
        let listen_only = self.regs.read32(BTR) & (btr::SILM | btr::LBKM) == btr::SILM;
        *self.listen_only.get_mut() = listen_only;
        let fed = match &self.filter_regs {
            Some(f) => filter_block::fed_fifos(f, chip, instance),
            None => filter_block::fed_fifos(&self.regs, chip, instance),
        };
        *self.fed.get_mut() = fed;
        Ok(())
    }
}
