//! The bxCAN controller: configuration entry points ([`Can::can1`], [`Can::can2`],
//! [`Can::can3`]), the initialization-mode value [`Init`], and
//! the configured controller that [`Can::into_split`] hands to the portable driver.

use twocan_core::{Error, LastErrorCode, Mode, Registers};

use crate::config::Config;
use crate::filter_block;
use crate::filters::{Fifo, FilterPlan, FmiMap, PlanRef, LOOKUP_KEYS, MAX_FMI};
use crate::instance::Instance;
use crate::mode;
use crate::planner::{self, FifoPolicy, PlanOptions, Scratch};
use crate::regs::{esr, ier, mcr, BTR, IER, MCR};

/// Register reads spent waiting for an aborted mailbox to become empty (notes "Abort":
/// a pending or scheduled mailbox is aborted at once; one on the bus finishes first, and
/// is then not waited for).
pub const ABORT_WAIT_ITERATIONS: u32 = 16;

/// An operation that failed, with the value it consumed, so nothing is lost: convert it
/// into [`Error`] with `?` or take [`Failed::value`] back.
#[derive(Debug)]
pub struct Failed<T> {
    /// Why.
    pub error: Error,
    /// What the operation was given back.
    pub value: T,
}

impl<T> From<Failed<T>> for Error {
    fn from(f: Failed<T>) -> Error {
        f.error
    }
}

/// A bxCAN instance over its registers `R` (volatile [`twocan_core::Mmio`] on target, the
/// behavioural model on the host). `F` reaches the filter registers of CAN1 for CAN2
/// (see [`Can::can2`]); CAN1 and CAN3 use their own registers and `F` is unused.
#[derive(Debug)]
///
/// `K` is how many identifiers of merged filters the driver can map back to the user's
/// filter index ([`FmiMap`], 6 bytes each, [`LOOKUP_KEYS`] by default); change it with
/// [`Init::with_lookup_capacity`].
pub struct Can<
    R: Registers,
    F: Registers = R,
    const K: usize = LOOKUP_KEYS,
    const M: usize = MAX_FMI,
> {
    pub(crate) regs: R,
    pub(crate) filter_regs: Option<F>,
    pub(crate) instance: Instance,
    pub(crate) config: Config,
    pub(crate) fmi: FmiMap<K, M>,
}

/// A controller in initialization mode (RM0410 §40.4.1), configured but off the bus.
/// Install filters with [`Init::set_filters`], then go on the bus with [`Init::enable`].
#[must_use = "the controller stays in initialization mode, off the bus, until `enable` is called"]
#[derive(Debug)]
pub struct Init<
    R: Registers,
    F: Registers = R,
    const K: usize = LOOKUP_KEYS,
    const M: usize = MAX_FMI,
> {
    can: Can<R, F, K, M>,
}

// The error values hand the whole controller back (nothing is lost on a timeout); its
// size (mostly the FMI map) only moves on that error path.
#[allow(clippy::result_large_err)]
impl<R: Registers> Can<R, R> {
    /// Configures CAN1 (the master, owner of the dual filter block): requests
    /// initialization mode (leaving sleep), waits for INAK (bounded), writes `CAN_MCR`
    /// options, `CAN_BTR`, `CAN_IER` and, if configured, `CAN_FMR.CAN2SB`.
    ///
    /// Errors: [`Error::Timeout`] when INAK does not come (no clock, stuck peripheral),
    /// with the registers handed back in [`Failed::value`]; [`Error::InvalidArgument`],
    /// before any register is touched, when the part ([`Config::chip`]) has no such
    /// instance (CAN2 on an F103, CAN3 on an F446).
    pub fn can1(regs: R, config: &Config) -> Result<Init<R, R>, Failed<Can<R, R>>> {
        Can::configured(regs, None, Instance::Can1, config)
    }

    /// Configures CAN3 (F76x/F77x: single CAN with its own 14 filter banks); as
    /// [`Can::can1`].
    pub fn can3(regs: R, config: &Config) -> Result<Init<R, R>, Failed<Can<R, R>>> {
        Can::configured(regs, None, Instance::Can3, config)
    }
}

#[allow(clippy::result_large_err)]
impl<R: Registers, F: Registers> Can<R, F> {
    /// Configures CAN1 as the master of a dual set-up: `regs` reach its control and
    /// mailbox registers only ([`crate::regs::ControlRegs`] on target) and `filters`
    /// the filter block it shares with CAN2 ([`crate::regs::FilterRegs`], lent as
    /// `&'static` to both). So no register is owned twice: CAN1's control block by
    /// CAN1, CAN2's by CAN2, the filter block by the shared `static`.
    pub fn can1_dual(
        regs: R,
        filters: F,
        config: &Config,
    ) -> Result<Init<R, F>, Failed<Can<R, F>>> {
        Can::configured(regs, Some(filters), Instance::Can1, config)
    }

    /// Configures CAN2 (the slave): `regs` are CAN2's registers, `can1_filters` reaches
    /// CAN1's register block, used for the filter registers only (`CAN_FMR` ..
    /// `CAN_F27R2`, RM0410 §40.9.4: CAN2 has none of its own). CAN1 must be clocked;
    /// CAN2 owns banks `CAN2SB..28`.
    ///
    /// `CAN2SB` belongs to CAN1's configuration (the register is CAN1's); a start bank
    /// in CAN2's own `config` ([`Config::can2_start_bank`]) is a check: it must agree
    /// with the value in the shared block, or this returns [`Error::InvalidArgument`]
    /// before touching a register (so CAN2 never runs on banks its planner did not
    /// expect).
    pub fn can2(
        regs: R,
        can1_filters: F,
        config: &Config,
    ) -> Result<Init<R, F>, Failed<Can<R, F>>> {
        Can::configured(regs, Some(can1_filters), Instance::Can2, config)
    }
}

#[allow(clippy::result_large_err)]
impl<R: Registers, F: Registers, const K: usize, const M: usize> Can<R, F, K, M> {
    fn new(regs: R, filter_regs: Option<F>, instance: Instance, config: &Config) -> Self {
        Can {
            regs,
            filter_regs,
            instance,
            config: *config,
            fmi: FmiMap::empty(),
        }
    }

    /// A new controller of `instance`, configured: the registers are written before
    /// the value is built, and the value is built once, in the result (no move of the
    /// map through this call's frame).
    fn configured(
        regs: R,
        filter_regs: Option<F>,
        instance: Instance,
        config: &Config,
    ) -> Result<Init<R, F, K, M>, Failed<Can<R, F, K, M>>> {
        match enter_configuration(&regs, filter_regs.as_ref(), instance, config) {
            Ok(()) => Ok(Init {
                can: Can::new(regs, filter_regs, instance, config),
            }),
            Err(error) => Err(Failed {
                error,
                value: Can::new(regs, filter_regs, instance, config),
            }),
        }
    }

    fn configure(mut self, config: &Config) -> Result<Init<R, F, K, M>, Failed<Can<R, F, K, M>>> {
        let (regs, filter_regs) = (&self.regs, self.filter_regs.as_ref());
        if let Err(error) = check_start_bank(regs, filter_regs, self.instance, config) {
            return Err(Failed { error, value: self });
        }
        self.config = *config;
        match write_configuration(&self.regs, self.filter_regs.as_ref(), self.instance, config) {
            Ok(()) => Ok(Init { can: self }),
            Err(error) => Err(Failed { error, value: self }),
        }
    }

    /// Re-enters initialization mode with a new configuration (the filters stay).
    pub fn reconfigure(self, config: &Config) -> Result<Init<R, F, K, M>, Failed<Can<R, F, K, M>>> {
        self.configure(config)
    }

    /// Software master reset (`CAN_MCR.RESET`, RM0410 §40.9.2): every register of the
    /// controller back to its reset value (the controller asleep), the filter block left
    /// alone; waits (bounded) for the sleep acknowledge `CAN_MSR.SLAK`. Gives the
    /// register handles back, to configure the instance again from scratch.
    ///
    /// Errors: [`Error::Timeout`] when `SLAK` does not come, with this value handed back.
    #[allow(clippy::result_large_err, clippy::type_complexity)]
    pub fn master_reset(self) -> Result<(R, Option<F>), Failed<Can<R, F, K, M>>> {
        self.regs.write32(MCR, mcr::RESET);
        let bound = self.bound();
        match mode::wait_msr(
            &self.regs,
            crate::regs::msr::SLAK,
            crate::regs::msr::SLAK,
            bound,
        ) {
            Ok(()) => Ok(self.release()),
            Err(error) => Err(Failed { error, value: self }),
        }
    }

    /// Gives the register handles back (CAN1's for CAN2's filters as the second value).
    pub fn release(self) -> (R, Option<F>) {
        (self.regs, self.filter_regs)
    }

    /// The instance.
    pub fn instance(&self) -> Instance {
        self.instance
    }

    /// The operating mode the acknowledge bits (`CAN_MSR.INAK`, `SLAK`) show now.
    pub fn mode(&self) -> Mode {
        mode::current(&self.regs)
    }

    /// The configuration in force.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The registers (for inspection; writing them behind the driver's back voids its
    /// bookkeeping).
    pub fn registers(&self) -> &R {
        &self.regs
    }

    /// The registers, mutably (see [`Can::registers`]).
    pub fn registers_mut(&mut self) -> &mut R {
        &mut self.regs
    }

    /// The banks (`start..end`, hardware numbering) this instance owns now.
    pub fn bank_range(&self) -> (usize, usize) {
        match &self.filter_regs {
            Some(f) => filter_block::banks_of(f, self.config.get_chip(), self.instance),
            None => filter_block::banks_of(&self.regs, self.config.get_chip(), self.instance),
        }
    }

    /// Planner options for this instance: its bank count and `fifo`.
    pub fn plan_options(&self, fifo: FifoPolicy) -> PlanOptions {
        let (s, e) = self.bank_range();
        PlanOptions::new((e - s) as u8).fifo(fifo)
    }

    /// Compiles `filters` for this instance's banks and its lookup capacity `K`
    /// ([`planner::plan_for`]): the plan installs, or the list is refused with the
    /// counts. The planner's working memory is on the stack (about 90 KB): on a host;
    /// firmware uses [`Can::plan_in`] (or a `const` plan, [`crate::const_plan!`]).
    pub fn plan(
        &self,
        filters: &[twocan_core::Filter],
        fifo: FifoPolicy,
    ) -> Result<FilterPlan<K>, crate::filters::PlanError> {
        planner::plan_for::<K>(filters, self.plan_options(fifo))
    }

    /// [`Can::plan`] with the working memory in `scratch` (kept in a `static` by
    /// firmware that plans at run time, see [`Scratch`]); the plan stays in it.
    pub fn plan_in<'s>(
        &self,
        filters: &[twocan_core::Filter],
        fifo: FifoPolicy,
        scratch: &'s mut Scratch<K>,
    ) -> Result<&'s FilterPlan<K>, crate::filters::PlanError> {
        planner::plan_in(filters, self.plan_options(fifo), scratch)
    }

    fn bound(&self) -> u32 {
        self.config.get_wait_iterations()
    }

    fn write_filters(&mut self, plan: PlanRef<'_>) -> Result<(), Error> {
        // The map first: a plan the map cannot hold is refused before any bank changes.
        let fmi = plan.fmi_map_sized::<K, M>()?;
        let instance = self.instance;
        let chip = self.config.get_chip();
        let r = match &mut self.filter_regs {
            Some(f) => filter_block::program(f, chip, instance, plan),
            None => filter_block::program(&self.regs, chip, instance, plan),
        };
        r.map_err(|_| Error::InvalidArgument)?;
        self.fmi = fmi;
        Ok(())
    }
}

/// The instance must exist on the part ([`Config::chip`]), and the start bank rules
/// hold, before any register is written: CAN2's configured start bank must agree with
/// the block's `CAN2SB`; CAN1 may move `CAN2SB` only when no bank it would affect is
/// active ([`filter_block::check_can2sb`]).
fn check_start_bank<R: Registers, F: Registers>(
    regs: &R,
    filter_regs: Option<&F>,
    instance: Instance,
    config: &Config,
) -> Result<(), Error> {
    // The part must have the instance (`Config::chip`).
    if !config.get_chip().has(instance) {
        return Err(Error::InvalidArgument);
    }
    let Some(start) = config.get_can2_start_bank() else {
        return Ok(());
    };
    match instance {
        Instance::Can2 => {
            let current = match filter_regs {
                Some(r) => filter_block::can2sb(r),
                None => filter_block::can2sb(regs),
            };
            let first = |sb| config.get_chip().bank_range(Instance::Can2, sb).0;
            if first(current) == first(start as u32) {
                Ok(())
            } else {
                Err(Error::InvalidArgument)
            }
        }
        Instance::Can1 => {
            let r = match filter_regs {
                Some(f) => filter_block::check_can2sb(f, start),
                None => filter_block::check_can2sb(regs, start),
            };
            r.map_err(|_| Error::WrongMode)
        }
        Instance::Can3 => Ok(()),
    }
}

/// Puts `instance` in initialization mode with `config` (RM0410 §40.4.1): the start
/// bank rules checked first, then INRQ requested (leaving sleep) and INAK waited for
/// (bounded), `CAN_MCR` options, `CAN_BTR`, `CAN_IER` and, for CAN1 with a start bank,
/// `CAN_FMR.CAN2SB`. The one sequence of [`Can::can1`] (and the other entry points) and
/// of the in-place constructors ([`crate::BxCan::can1_in`]).
pub(crate) fn enter_configuration<R: Registers, F: Registers>(
    regs: &R,
    filter_regs: Option<&F>,
    instance: Instance,
    config: &Config,
) -> Result<(), Error> {
    check_start_bank(regs, filter_regs, instance, config)?;
    write_configuration(regs, filter_regs, instance, config)
}

/// [`enter_configuration`] after its start bank check.
fn write_configuration<R: Registers, F: Registers>(
    regs: &R,
    filter_regs: Option<&F>,
    instance: Instance,
    config: &Config,
) -> Result<(), Error> {
    mode::request(regs, Mode::Stopped, config.get_wait_iterations())?;
    regs.write32(MCR, mcr::INRQ | config.mcr_options());
    regs.write32(BTR, config.btr_value());
    regs.write32(IER, config.get_interrupts());
    if let (Instance::Can1, Some(start)) = (instance, config.get_can2_start_bank()) {
        // Checked again inside the critical section: CAN2's driver may have activated
        // a bank since `check_start_bank`.
        let r = match filter_regs {
            Some(f) => filter_block::set_can2sb(f, start),
            None => filter_block::set_can2sb(regs, start),
        };
        r.map_err(|_| Error::WrongMode)?;
    }
    Ok(())
}

/// `CAN_ESR.LEC` as a last-error code (notes "Error management": 0 none, 1 stuff, 2 form,
/// 3 acknowledgment, 4 bit recessive, 5 bit dominant, 6 CRC, 7 set by software).
pub fn lec(code: u32) -> LastErrorCode {
    match code {
        esr::LEC_STUFF => LastErrorCode::Stuff,
        esr::LEC_FORM => LastErrorCode::Form,
        esr::LEC_ACK => LastErrorCode::Acknowledge,
        esr::LEC_BIT_RECESSIVE => LastErrorCode::BitRecessive,
        esr::LEC_BIT_DOMINANT => LastErrorCode::BitDominant,
        esr::LEC_CRC => LastErrorCode::Crc,
        _ => LastErrorCode::None,
    }
}

#[allow(clippy::result_large_err)]
impl<R: Registers, F: Registers, const K: usize, const M: usize> Init<R, F, K, M> {
    /// The same controller with room for `K2` identifiers in its merged-filter lookup
    /// ([`FmiMap`]; `K` = [`LOOKUP_KEYS`] unless chosen): call before
    /// [`Init::set_filters`] (the map starts empty again). Plans whose merged or
    /// superset slots need more are refused with [`Error::FilterSpace`].
    pub fn with_lookup_capacity<const K2: usize>(self) -> Init<R, F, K2, M> {
        self.with_map_capacity::<K2, M>()
    }

    /// [`Init::with_lookup_capacity`] with room for `M2` match indices per FIFO too
    /// ([`FmiMap`]; [`MAX_FMI`] unless chosen: a `const` plan's
    /// [`crate::filters::PlanRef::match_indices`] is the least). Plans that number more
    /// are refused with [`Error::FilterSpace`].
    pub fn with_map_capacity<const K2: usize, const M2: usize>(self) -> Init<R, F, K2, M2> {
        let c = self.can;
        Init {
            can: Can {
                regs: c.regs,
                filter_regs: c.filter_regs,
                instance: c.instance,
                config: c.config,
                fmi: FmiMap::empty(),
            },
        }
    }

    /// Installs filters before going on the bus (the receive half's `set_filters` installs later lists):
    /// a run-time plan (`&FilterPlan<K>`) or a `const` one (`&SizedPlan`,
    /// [`crate::const_plan!`]), read in place.
    ///
    /// Errors: [`Error::FilterSpace`] when the plan needs more lookup keys than this
    /// controller keeps (`K`), [`Error::InvalidArgument`] with more banks than it owns.
    pub fn set_filters<'p>(&mut self, plan: impl Into<PlanRef<'p>>) -> Result<(), Error> {
        self.can.write_filters(plan.into())
    }

    /// The controller, still in initialization mode (to plan filters for its banks).
    pub fn can(&self) -> &Can<R, F, K, M> {
        &self.can
    }

    /// The controller, still in initialization mode, mutably.
    pub fn can_mut(&mut self) -> &mut Can<R, F, K, M> {
        &mut self.can
    }

    /// Leaves initialization mode: clears INRQ and waits (bounded) for INAK = 0, which the
    /// hardware gives after 11 recessive bits on CANRX (RM0410 §40.4.2).
    ///
    /// Errors: [`Error::Timeout`], with this value handed back in [`Failed::value`].
    pub fn enable(self) -> Result<Can<R, F, K, M>, Failed<Init<R, F, K, M>>> {
        let bound = self.can.bound();
        match mode::request(&self.can.regs, Mode::Normal, bound) {
            Ok(()) => Ok(self.can),
            Err(error) => Err(Failed { error, value: self }),
        }
    }

    /// Gives the register handles back, leaving the peripheral in initialization mode.
    pub fn release(self) -> (R, Option<F>) {
        self.can.release()
    }
}

/// Interrupt enable bits that the driver needs serviced for a FIFO (for firmware that
/// builds its own `CAN_IER` value).
pub const fn fifo_interrupts(fifo: Fifo) -> u32 {
    ier::fmpie(fifo.index()) | ier::fovie(fifo.index())
}
