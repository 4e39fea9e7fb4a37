//! Hand-over from an STM32 HAL: the bxCAN instances built from the HAL's PAC singletons,
//! its clocks and CAN pins, with no `unsafe` in the program. One module per HAL
//! (`f7`: `stm32f7xx-hal` 0.8, feature `hal-stm32f7`, its items also re-exported here;
//! `f4`: `stm32f4xx-hal` 0.23, feature `hal-stm32f4`; `f1`: `stm32f1xx-hal` 0.11, feature
//! `hal-stm32f1`, the STM32F103's CAN; `hal-stm32f1-connectivity`: the F105/F107's CAN1 and
//! CAN2), over one generic piece (this
//! module): the handle [`HandedOver`], the shared filter block [`Can1Filters`], giving
//! the parts back ([`HandedOver::free`], [`HandedOver::park`], [`Parked::free`]), and
//! `configure`. A family module adds only what its HAL spells differently: the pins
//! (typed, [`TxPin`]/[`RxPin`] for the data sheet's table), the PAC types, the RCC and
//! clock types.
//!
//! The program owns the PAC singleton of an instance (`pac::CAN1`, …) once, from
//! `pac::Peripherals::take()`. Giving it **by value** to a family's `can1`, `can1_dual`,
//! `can2` or `can3` is the proof that nothing else reaches that instance's registers; the
//! constructor turns it into the bounded register window of [`crate::regs`] (the one
//! `unsafe` of the hand-over is here, in this crate: `whole`, `control` and `dual`). It also:
//!
//! - enables and resets the instance's clock in RCC (`RCC_APB1ENR.CANxEN`,
//!   `RCC_APB1RSTR`) through the HAL;
//! - keeps the APB1 frequency of the HAL's clocks (bxCAN's clock, RM0410 §40.7.7:
//!   tq = (BRP + 1) × tPCLK): [`HandedOver::config`] solves the bit timing from it, and
//!   [`HandedOver::configure`] refuses a [`Config`] whose timing was computed for another
//!   clock (`Error::InvalidArgument`, the handle handed back);
//! - takes the TX and RX pins, already in their CAN alternate function: the pin types
//!   carry the alternate function number (`Pin<'D', 1, Alternate<9>>`), and only the
//!   pins of the data sheets' alternate-function tables implement [`TxPin`]/[`RxPin`]
//!   for an instance — a wrong pin, or the right pin in the wrong function, does not
//!   compile (`compile_fail` examples in each family module: rustdoc runs the F7's;
//!   the F1's and F4's, whose HALs do not build on the host, are cross-built by
//!   `tools/hal-doctests/run.sh`).
//!
//! # Giving the singleton and the pins back
//!
//! `can1`, `can2` and `can3` keep the PAC singleton and the two pins in the handle
//! ([`HalParts`]), as HAL peripherals do:
//!
//! - before configuring, [`HandedOver::free`] returns `(CANx, tx, rx)`;
//! - to get them back after the driver has run, take them out first with
//!   [`HandedOver::park`] (a [`Parked`] value), configure and run the controller, and
//!   when its register handle comes back ([`Init::release`], [`Can::release`]), give
//!   that handle to [`Parked::free`]: the singleton is only returned in exchange for
//!   the one register window of that instance, so the driver can no longer reach it.
//!
//! [`HandedOver::configure`] on a handle that still holds its parts drops them (the
//! pins stay in their CAN function, the singleton is gone for good). CAN1 handed over
//! with `can1_dual` keeps nothing: CAN2 may still reach CAN1's filter block through a
//! [`Can1Filters`] copy, so CAN1's singleton must never come back.
//!
//! # CAN2 and the shared filter block
//!
//! CAN2 has no filter registers: its reception goes through CAN1's filter block
//! (RM0410 §40.3 "dual CAN", §40.9.4; RM0390 §30.3). `can1_dual` gives CAN1 its control
//! and mailbox registers and returns a [`Can1Filters`] handle to the filter block;
//! `can2` takes one. So CAN2 cannot be built without CAN1's singleton having been handed
//! over in dual mode (which also keeps CAN1 clocked, as CAN2's filters need), and no
//! register has two owners. `can1` hands the whole CAN1 block to CAN1 and gives no
//! filter handle: then CAN2 cannot be built at all. CAN1's block is at 0x4000_6400 on
//! every part with CAN2 (`twocan_bxcan::chip`).

use twocan_core::{Error, Registers};

use crate::chip::Chip;
use crate::config::{Config, ConfigError};
use crate::controller::{Can, Failed, Init};
use crate::filter_block;
use crate::instance::Instance;
use crate::planner::{FifoPolicy, PlanOptions};
use crate::regs::{CanRegs, CanRegsAt, ControlRegs, ControlRegsAt, FilterRegs};

#[cfg(feature = "hal-stm32f1")]
pub mod f1;
#[cfg(feature = "hal-stm32f4")]
pub mod f4;
#[cfg(feature = "hal-stm32f7")]
pub mod f7;
#[cfg(feature = "hal-stm32f7")]
pub use f7::*;

pub(crate) mod sealed {
    /// Keeps [`super::TxPin`] and [`super::RxPin`] to the pins listed in this module.
    pub trait Sealed {}
}

/// A pin that carries the TX signal of the bxCAN instance `CAN` (the PAC singleton's
/// type) in its current mode. Implemented for the pins of the module's table only.
pub trait TxPin<CAN>: sealed::Sealed {}

/// A pin that carries the RX signal of the bxCAN instance `CAN`. Implemented for the pins
/// of the module's table only.
pub trait RxPin<CAN>: sealed::Sealed {}

/// `Sealed` and `$role<$can>` for each pin `Pin<$port, $n, Alternate<$af>>` of the calling
/// family module (its HAL's `Pin` and `Alternate` in scope).
#[cfg_attr(
    not(any(feature = "hal-stm32f7", feature = "hal-stm32f4")),
    allow(unused_macros)
)]
macro_rules! can_pins {
    ($can:ty, $af:literal, $role:ident: $(($port:literal, $n:literal)),+ $(,)?) => {
        $(
            impl $crate::hal::sealed::Sealed for Pin<$port, $n, Alternate<$af>> {}
            impl $crate::hal::$role<$can> for Pin<$port, $n, Alternate<$af>> {}
        )+
    };
}
#[cfg_attr(
    not(any(feature = "hal-stm32f7", feature = "hal-stm32f4")),
    allow(unused_imports)
)]
pub(crate) use can_pins;

/// CAN1's filter registers (`CAN_FMR` .. `CAN_F27R2`, CAN1's block + `0x200..0x320`),
/// reached only through the [`Can1Filters`] handles that a family's `can1_dual` gives out.
#[cfg_attr(
    not(any(feature = "hal-stm32f7", feature = "hal-stm32f4")),
    allow(dead_code)
)]
// SAFETY: offsets 0x200..0x320 from CAN1's base (RM0410 §2.2.2, §40.9.5) are CAN1's
// filter registers, 32-bit accessible. A reference to this value is created only by
// `can1_dual`, which consumes the `pac::CAN1` singleton (handed out once per program by
// the PAC), and then gives CAN1 the control window below 0x200 only.
static CAN1_FILTERS: FilterRegs = unsafe { FilterRegs::new(crate::regs::CAN1_BASE) };

/// A handle to CAN1's filter block, shared by CAN1 and CAN2 in dual mode: from
/// `can1_dual` only (the proof that CAN1's singleton was handed over and its block
/// split), and required by `can2`. Copying it shares the one block; the drivers program
/// it in critical sections.
#[derive(Debug, Clone, Copy)]
pub struct Can1Filters {
    regs: &'static FilterRegs,
}

impl Registers for Can1Filters {
    #[inline(always)]
    fn read32(&self, offset: usize) -> u32 {
        self.regs.read32(offset)
    }

    #[inline(always)]
    fn write32(&self, offset: usize, value: u32) {
        self.regs.write32(offset, value)
    }
}

/// A bxCAN instance handed over by the HAL, clocked, not yet configured: its register
/// handles, the APB1 frequency and (`P`) the PAC singleton and pins it was built from
/// ([`HalParts`], or `()` when they were parked or, for `can1_dual`, not kept).
/// [`HandedOver::configure`] puts it in initialization mode ([`Init`]).
///
/// - `Can1` (from `can1`) and `Can3` (from `can3`) own a whole register block;
/// - [`DualCan`] (from `can1_dual`) and `Can2` (from `can2`) own a control block
///   and share CAN1's filter block.
#[derive(Debug)]
pub struct HandedOver<R: Registers, F: Registers = R, P = ()> {
    regs: R,
    filters: Option<F>,
    instance: Instance,
    apb1_hz: u32,
    chip: Option<&'static Chip>,
    parts: P,
}

/// The PAC singleton of a bxCAN instance and its TX and RX pins, as handed over.
#[derive(Debug)]
pub struct HalParts<CAN, TX, RX> {
    can: CAN,
    tx: TX,
    rx: RX,
}

/// The singleton and pins taken out of a [`HandedOver`] by [`HandedOver::park`]: given
/// back by [`Parked::free`] in exchange for the instance's register window.
#[derive(Debug)]
pub struct Parked<CAN, TX, RX> {
    parts: HalParts<CAN, TX, RX>,
}

/// A PAC singleton type of a bxCAN instance handed over with its parts kept: the
/// register window the hand-over made of it, and that window's address.
pub trait PacCan: sealed::Sealed {
    /// The window `can1`, `can2` or `can3` built: the whole block for CAN1 alone
    /// and CAN3, the control block for CAN2.
    type Window: Window;
    /// The PAC's address of the instance's registers.
    fn base() -> usize;
    /// Whether `window` is this instance's (its base address is the PAC's).
    fn is_window(window: &Self::Window) -> bool {
        window.base() == Self::base()
    }
}

/// A register window the hand-over makes: its base address.
pub trait Window: sealed::Sealed {
    /// The base address of the window.
    fn base(&self) -> usize;
}
impl sealed::Sealed for CanRegs {}
impl Window for CanRegs {
    fn base(&self) -> usize {
        CanRegs::base(self)
    }
}
impl sealed::Sealed for ControlRegs {}
impl Window for ControlRegs {
    fn base(&self) -> usize {
        ControlRegs::base(self)
    }
}

/// `Sealed` and [`PacCan`] for a PAC singleton type (`pac::CAN1`, …) and its window.
#[cfg_attr(
    not(any(feature = "hal-stm32f7", feature = "hal-stm32f4")),
    allow(unused_macros)
)]
macro_rules! pac_can {
    ($($can:ty => $window:ty),+ $(,)?) => {
        $(
            impl $crate::hal::sealed::Sealed for $can {}
            impl $crate::hal::PacCan for $can {
                type Window = $window;
                fn base() -> usize {
                    <$can>::ptr() as usize
                }
            }
        )+
    };
}
#[cfg_attr(
    not(any(feature = "hal-stm32f7", feature = "hal-stm32f4")),
    allow(unused_imports)
)]
pub(crate) use pac_can;

impl<CAN: PacCan, TX, RX> Parked<CAN, TX, RX> {
    /// Gives back `(CANx, tx, rx)` for the instance's register window `regs` (from
    /// [`Init::release`] or [`Can::release`]), which it consumes: the window is not
    /// `Clone`, and its type is the whole window the hand-over made (not a part split
    /// off it), so once it is here the driver reaches the instance no more.
    ///
    /// Errors: the window of another instance is refused and handed back with this
    /// value.
    #[allow(clippy::result_large_err)]
    pub fn free(self, regs: CAN::Window) -> Result<(CAN, TX, RX), (Self, CAN::Window)> {
        if !CAN::is_window(&regs) {
            return Err((self, regs));
        }
        let HalParts { can, tx, rx } = self.parts;
        Ok((can, tx, rx))
    }
}

/// CAN1 of a dual set-up: control registers, and CAN1's filter block shared (its
/// singleton and pins are not kept: see the module notes).
pub type DualCan = HandedOver<ControlRegs, Can1Filters>;

/// Hands over an instance with its own whole register block (CAN1 alone, CAN3, the
/// F103's CAN): the window at `CAN::base()`, the parts kept.
///
/// # Safety
///
/// `can` is the PAC singleton of the instance at `CAN::base()` (consumed: no other handle
/// to these registers exists), and its clock is enabled.
pub(crate) unsafe fn whole<CAN: PacCan<Window = CanRegs>, TX, RX>(
    can: CAN,
    tx: TX,
    rx: RX,
    instance: Instance,
    apb1_hz: u32,
    chip: Option<&'static Chip>,
) -> HandedOver<CanRegs, CanRegs, HalParts<CAN, TX, RX>> {
    HandedOver {
        // SAFETY: the caller's promise: `CAN::base()` is this instance's block, whose
        // singleton is in `parts` (given back only for this window).
        regs: unsafe { CanRegs::new(CAN::base()) },
        filters: None,
        instance,
        apb1_hz,
        chip,
        parts: HalParts { can, tx, rx },
    }
}

/// Hands over CAN2: its control and mailbox registers, and CAN1's filter block through
/// `filters`; the parts kept.
///
/// # Safety
///
/// As [`whole`], for CAN2's singleton (CAN2 has no filter registers of its own).
// Dual-CAN pieces: unused with the F103-only `hal-stm32f1` alone.
#[cfg_attr(
    not(any(feature = "hal-stm32f7", feature = "hal-stm32f4")),
    allow(dead_code)
)]
pub(crate) unsafe fn control<CAN: PacCan<Window = ControlRegs>, TX, RX>(
    can: CAN,
    tx: TX,
    rx: RX,
    apb1_hz: u32,
    chip: Option<&'static Chip>,
    filters: Can1Filters,
) -> HandedOver<ControlRegs, Can1Filters, HalParts<CAN, TX, RX>> {
    HandedOver {
        // SAFETY: the caller's promise: CAN2's block, whose singleton is in `parts`.
        regs: unsafe { ControlRegs::new(CAN::base()) },
        filters: Some(filters),
        instance: Instance::Can2,
        apb1_hz,
        chip,
        parts: HalParts { can, tx, rx },
    }
}

/// Hands over CAN1 as the master of a dual set-up: its control and mailbox registers,
/// and the [`Can1Filters`] handle to the block it shares with CAN2. The singleton and
/// pins are consumed (never given back: see the module notes).
///
/// # Safety
///
/// `can1` is CAN1's PAC singleton, at `CAN::base()` = CAN1's block (the `CAN1_FILTERS`
/// window's base), and its clock is enabled.
// Dual-CAN pieces: unused with the F103-only `hal-stm32f1` alone.
#[cfg_attr(
    not(any(feature = "hal-stm32f7", feature = "hal-stm32f4")),
    allow(dead_code)
)]
pub(crate) unsafe fn dual<CAN: PacCan, TX, RX>(
    can1: CAN,
    tx: TX,
    rx: RX,
    apb1_hz: u32,
    chip: Option<&'static Chip>,
) -> (DualCan, Can1Filters) {
    let _ = (can1, tx, rx);
    let filters = Can1Filters {
        regs: &CAN1_FILTERS,
    };
    let handle = HandedOver {
        // SAFETY: CAN1's control and mailbox registers (offsets below 0x200 of its
        // block), whose singleton this function consumed; the filter registers above go
        // to `CAN1_FILTERS` only.
        regs: unsafe { ControlRegs::new(CAN::base()) },
        filters: Some(filters),
        instance: Instance::Can1,
        apb1_hz,
        chip,
        parts: (),
    };
    (handle, filters)
}

impl<R: Registers, F: Registers, CAN, TX, RX> HandedOver<R, F, HalParts<CAN, TX, RX>> {
    /// Gives the PAC singleton and the pins back, before configuring (the clock stays
    /// enabled; the pins stay in their CAN function).
    pub fn free(self) -> (CAN, TX, RX) {
        let HalParts { can, tx, rx } = self.parts;
        (can, tx, rx)
    }

    /// Takes the singleton and the pins out, to be given back later by [`Parked::free`]
    /// in exchange for this instance's register window.
    pub fn park(self) -> (HandedOver<R, F>, Parked<CAN, TX, RX>) {
        let HandedOver {
            regs,
            filters,
            instance,
            apb1_hz,
            chip,
            parts,
        } = self;
        (
            HandedOver {
                regs,
                filters,
                instance,
                apb1_hz,
                chip,
                parts: (),
            },
            Parked { parts },
        )
    }
}

impl<R: Registers, F: Registers, P> HandedOver<R, F, P> {
    /// The instance.
    pub fn instance(&self) -> Instance {
        self.instance
    }

    /// The part [`HandedOver::config`] configures for (`Config::chip`): the family
    /// module sets it where its HAL builds one part; otherwise the program says which.
    pub fn with_chip(mut self, chip: &'static Chip) -> Self {
        self.chip = Some(chip);
        self
    }

    /// The APB1 clock (Hz) the HAL reported: bxCAN's clock.
    pub fn apb1_hz(&self) -> u32 {
        self.apb1_hz
    }

    /// A configuration for `bitrate` on this APB1 clock ([`Config::from_bitrate`]),
    /// for the part the family module knows (`Config::chip`; the F7 module leaves the
    /// default), to adjust with the builder before [`HandedOver::configure`].
    pub fn config(&self, bitrate: u32) -> Result<Config, ConfigError> {
        let config = Config::from_bitrate(self.apb1_hz, bitrate)?;
        match self.chip {
            Some(chip) => config.chip(chip),
            None => Ok(config),
        }
    }

    /// Whether `config`'s bit timing fits this clock: computed from this APB1 frequency,
    /// or a raw `CAN_BTR` value ([`Config::from_btr`], clock unknown: the caller's word).
    pub fn accepts(&self, config: &Config) -> bool {
        let hz = config.get_clock_hz();
        hz == 0 || hz == self.apb1_hz
    }

    fn refuse(self, error: Error) -> Failed<Self> {
        Failed { error, value: self }
    }

    fn from_can(can: Can<R, F>, apb1_hz: u32, chip: Option<&'static Chip>, parts: P) -> Self {
        let instance = can.instance();
        let (regs, filters) = can.release();
        HandedOver {
            regs,
            filters,
            instance,
            apb1_hz,
            chip,
            parts,
        }
    }
}

impl<R: Registers, F: Registers, P> HandedOver<R, F, P> {
    /// Planner options for this instance under `config`, before anything is
    /// configured: its bank count and `fifo` (as `Can::plan_options` gives them after
    /// [`HandedOver::configure`]). A dual block is split at `config`'s
    /// [`Config::can2_start_bank`] when it sets one, otherwise at the `CAN2SB` the
    /// filter registers hold now (RM0410 §40.9.4 "CAN filter master register").
    pub fn plan_options(&self, config: &Config, fifo: FifoPolicy) -> PlanOptions {
        let can2sb = match (config.get_can2_start_bank(), &self.filters) {
            (Some(bank), _) => u32::from(bank),
            (None, Some(f)) => filter_block::can2sb(f),
            (None, None) => filter_block::can2sb(&self.regs),
        };
        let (start, end) = config.get_chip().bank_range(self.instance, can2sb);
        PlanOptions::new((end - start) as u8).fifo(fifo)
    }
}

// The error values hand the whole handle back (nothing is lost).
#[allow(clippy::result_large_err)]
impl<P> HandedOver<CanRegs, CanRegs, P> {
    /// The register handle for an in-place constructor ([`crate::BxCan::can1_in`],
    /// [`crate::BxCan::can3_in`], through `State::split_with` or
    /// `rt::IrqState::start_in_place`), which configures the instance itself: nothing
    /// is written here, and no controller or filter map is built on the stack (issue
    /// 21). [`Error::InvalidArgument`] when `config` was computed for another clock
    /// ([`HandedOver::accepts`]), with this handle back.
    pub fn into_registers(self, config: &Config) -> Result<CanRegs, Failed<Self>> {
        self.into_single(config)
    }

    /// [`HandedOver::into_registers`] with the base address a constant: the registers
    /// as a zero-sized [`CanRegsAt`] (`Can1At`, `Can3At` of [`crate::regs`]), so that
    /// the per-frame code reaches each register at an address known at compile time
    /// (issue 21). The window the hand-over made from the consumed PAC singleton
    /// becomes the fixed handle (`twocan_core::Mmio::into_fixed`), so the registers
    /// still have one owner and the program needs no `unsafe`. The singleton and pins
    /// this handle may hold are dropped with it (only the window of
    /// [`HandedOver::into_registers`] buys them back from [`Parked::free`]).
    ///
    /// Errors, with this handle back: [`Error::InvalidArgument`] when `config` was
    /// computed for another clock, or when `BASE` is not this instance's base address
    /// (`let regs: Can1At = can3.into_registers_at(&config)?` is refused).
    pub fn into_registers_at<const BASE: usize>(
        self,
        config: &Config,
    ) -> Result<CanRegsAt<BASE>, Failed<Self>> {
        if !self.accepts(config) {
            return Err(self.refuse(Error::InvalidArgument));
        }
        self.convert(|regs, filters| regs.into_fixed().map_err(|regs| (regs, filters)))
    }

    /// Configures the instance ([`Can::can1`] or [`Can::can3`]): initialization mode,
    /// options, bit timing.
    ///
    /// Errors, with this handle back in [`Failed::value`]: [`Error::InvalidArgument`]
    /// when `config` was computed for another clock ([`HandedOver::accepts`]);
    /// [`Error::Timeout`] when the controller does not acknowledge initialization mode.
    pub fn configure(self, config: &Config) -> Result<Init<CanRegs>, Failed<Self>> {
        self.configure_single(config)
    }
}

#[allow(clippy::result_large_err)]
impl<P> HandedOver<ControlRegs, Can1Filters, P> {
    /// The control and filter register handles for an in-place constructor
    /// ([`crate::BxCan::can1_dual_in`], [`crate::BxCan::can2_in`]); as the whole
    /// block's [`HandedOver::into_registers`].
    pub fn into_registers(
        self,
        config: &Config,
    ) -> Result<(ControlRegs, Can1Filters), Failed<Self>> {
        self.into_dual(config)
    }

    /// [`HandedOver::into_registers`] of a dual handle with the control registers' base
    /// a constant ([`ControlRegsAt`]: `Can1ControlAt`, `Can2At` of [`crate::regs`]);
    /// as the whole block's [`HandedOver::into_registers_at`], errors included.
    pub fn into_registers_at<const BASE: usize>(
        self,
        config: &Config,
    ) -> Result<(ControlRegsAt<BASE>, Can1Filters), Failed<Self>> {
        if !self.accepts(config) {
            return Err(self.refuse(Error::InvalidArgument));
        }
        self.convert(|regs, filters| match filters {
            Some(f) => match regs.into_fixed() {
                Ok(fixed) => Ok((fixed, f)),
                Err(regs) => Err((regs, Some(f))),
            },
            // No filter handle (not built by this module).
            None => Err((regs, None)),
        })
    }

    /// Configures CAN1 ([`Can::can1_dual`]: `CAN2SB` is written when `config` sets
    /// [`Config::can2_start_bank`]) or CAN2 ([`Can::can2`]); errors as for a whole
    /// block's `configure`.
    pub fn configure(
        self,
        config: &Config,
    ) -> Result<Init<ControlRegs, Can1Filters>, Failed<Self>> {
        self.configure_dual(config)
    }
}

// The register types stay generic below, so that the host tests run the same code over
// the behavioural model.
#[allow(clippy::result_large_err)]
impl<R: Registers, P> HandedOver<R, R, P> {
    fn into_single(self, config: &Config) -> Result<R, Failed<Self>> {
        if !self.accepts(config) {
            return Err(self.refuse(Error::InvalidArgument));
        }
        Ok(self.regs)
    }

    fn configure_single(self, config: &Config) -> Result<Init<R, R>, Failed<Self>> {
        if !self.accepts(config) {
            return Err(self.refuse(Error::InvalidArgument));
        }
        let HandedOver {
            regs,
            instance,
            apb1_hz,
            chip,
            parts,
            ..
        } = self;
        let made = match instance {
            Instance::Can3 => Can::can3(regs, config),
            _ => Can::can1(regs, config),
        };
        made.map_err(|f| Failed {
            error: f.error,
            value: Self::from_can(f.value, apb1_hz, chip, parts),
        })
    }
}

#[allow(clippy::result_large_err)]
impl<R: Registers, F: Registers, P> HandedOver<R, F, P> {
    /// `f` applied to the register handles, or this handle back with
    /// [`Error::InvalidArgument`] when `f` gives them back (nothing is lost).
    fn convert<T>(
        self,
        f: impl FnOnce(R, Option<F>) -> Result<T, (R, Option<F>)>,
    ) -> Result<T, Failed<Self>> {
        let HandedOver {
            regs,
            filters,
            instance,
            apb1_hz,
            chip,
            parts,
        } = self;
        f(regs, filters).map_err(|(regs, filters)| Failed {
            error: Error::InvalidArgument,
            value: HandedOver {
                regs,
                filters,
                instance,
                apb1_hz,
                chip,
                parts,
            },
        })
    }

    fn into_dual(self, config: &Config) -> Result<(R, F), Failed<Self>> {
        if !self.accepts(config) {
            return Err(self.refuse(Error::InvalidArgument));
        }
        match self {
            HandedOver {
                regs,
                filters: Some(filters),
                ..
            } => Ok((regs, filters)),
            // Not built by this module, whose dual handles always have one.
            other => Err(Failed {
                error: Error::InvalidArgument,
                value: other,
            }),
        }
    }

    fn configure_dual(self, config: &Config) -> Result<Init<R, F>, Failed<Self>> {
        let accepted = self.accepts(config);
        let HandedOver {
            regs,
            filters,
            instance,
            apb1_hz,
            chip,
            parts,
        } = self;
        let filters = match filters {
            Some(f) if accepted => f,
            // Another clock, or no filter handle (not built by this module, whose dual
            // handles always have one).
            filters => {
                return Err(Failed {
                    error: Error::InvalidArgument,
                    value: HandedOver {
                        regs,
                        filters,
                        instance,
                        apb1_hz,
                        chip,
                        parts,
                    },
                })
            }
        };
        let made = match instance {
            Instance::Can2 => Can::can2(regs, filters, config),
            _ => Can::can1_dual(regs, filters, config),
        };
        made.map_err(|f| Failed {
            error: f.error,
            value: Self::from_can(f.value, apb1_hz, chip, parts),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // `configure` over the behavioural model (the same generic code as on target).
    use crate::model::BxCanModel;
    use crate::regs::{BTR, FMR, MCR, MSR};
    use std::{cell::RefCell, rc::Rc};
    use twocan_core::Mode;
    use twocan_sim::{Bus, PollClock};

    type Regs = PollClock<BxCanModel>;

    fn bus() -> Rc<RefCell<Bus>> {
        Rc::new(RefCell::new(Bus::new(500_000).unwrap()))
    }

    fn handed<F: Registers>(
        regs: Regs,
        filters: Option<F>,
        instance: Instance,
    ) -> HandedOver<Regs, F> {
        HandedOver {
            regs,
            filters,
            instance,
            apb1_hz: 54_000_000,
            chip: None,
            parts: (),
        }
    }

    #[test]
    fn a_config_for_another_clock_is_refused_before_any_register_is_written() {
        let bus = bus();
        let model = BxCanModel::can1();
        let regs = PollClock::new(model.clone(), &bus, MSR);
        let mcr_at_reset = model.read32(MCR);
        let h = handed::<Regs>(regs, None, Instance::Can1);
        assert_eq!(h.config(500_000).unwrap().get_clock_hz(), 54_000_000);
        let other = Config::from_bitrate(48_000_000, 500_000).unwrap();
        assert!(!h.accepts(&other));
        let back = h.configure_single(&other).unwrap_err();
        assert_eq!(back.error, Error::InvalidArgument);
        assert_eq!(
            (back.value.instance(), back.value.apb1_hz()),
            (Instance::Can1, 54_000_000)
        );
        assert_eq!(model.read32(MCR), mcr_at_reset);
        // The handle handed back configures with a config for its clock.
        let config = back.value.config(500_000).unwrap();
        let init = back
            .value
            .configure_single(&config)
            .map_err(|f| f.error)
            .unwrap();
        assert_eq!(init.can().mode(), Mode::Stopped);
        assert_eq!(
            model.read32(BTR) & 0x03FF_03FF,
            config.btr_value() & 0x03FF_03FF
        );
    }

    #[test]
    fn a_raw_btr_config_is_the_caller_s_word() {
        let bus = bus();
        let model = BxCanModel::can3();
        let h = handed::<Regs>(
            PollClock::new(model.clone(), &bus, MSR),
            None,
            Instance::Can3,
        );
        let raw = Config::from_btr(0x001C_0005).unwrap();
        assert!(h.accepts(&raw));
        let init = h.configure_single(&raw).map_err(|f| f.error).unwrap();
        assert_eq!(init.can().instance(), Instance::Can3);
        assert_eq!(init.can().bank_range(), (0, 14));
    }

    #[test]
    fn dual_handles_share_can1_s_filter_block() {
        let bus = bus();
        let (m1, m2) = BxCanModel::can1_can2();
        let can1 = handed(
            PollClock::new(m1.clone(), &bus, MSR),
            Some(m1.clone()),
            Instance::Can1,
        );
        let can2 = handed(
            PollClock::new(m2.clone(), &bus, MSR),
            Some(m1.clone()),
            Instance::Can2,
        );
        let config1 = can1.config(500_000).unwrap().can2_start_bank(10).unwrap();
        let init1 = can1.configure_dual(&config1).map_err(|f| f.error).unwrap();
        let init2 = can2
            .configure_dual(&Config::from_bitrate(54_000_000, 500_000).unwrap())
            .map_err(|f| f.error)
            .unwrap();
        assert_eq!(crate::regs::fmr::CAN2SB.get(m1.read32(FMR)), 10);
        assert_eq!(init1.can().bank_range(), (0, 10));
        assert_eq!(init2.can().bank_range(), (10, 28));
        assert_eq!(init2.can().instance(), Instance::Can2);
    }

    #[test]
    fn a_dual_handle_without_filters_or_for_another_clock_is_handed_back() {
        let bus = bus();
        let (_m1, m2) = BxCanModel::can1_can2();
        let no_filters =
            handed::<BxCanModel>(PollClock::new(m2.clone(), &bus, MSR), None, Instance::Can2);
        let config = Config::from_bitrate(54_000_000, 500_000).unwrap();
        let back = no_filters.configure_dual(&config).unwrap_err();
        assert_eq!(back.error, Error::InvalidArgument);
        assert_eq!(back.value.instance(), Instance::Can2);
        let (m1, m2) = BxCanModel::can1_can2();
        let other_clock = handed(PollClock::new(m2, &bus, MSR), Some(m1), Instance::Can2);
        let config = Config::from_bitrate(27_000_000, 500_000).unwrap();
        let back = other_clock.configure_dual(&config).unwrap_err();
        assert_eq!(back.error, Error::InvalidArgument);
        assert!(
            back.value.filters.is_some(),
            "the filter handle comes back too"
        );
    }

    #[test]
    fn into_registers_hands_the_registers_over_untouched_and_plan_options_match_configure() {
        let bus = bus();
        // Whole block (CAN1 alone): the handle, nothing written; a config for another
        // clock refused with the handle back.
        let model = BxCanModel::can1();
        let h = handed::<Regs>(
            PollClock::new(model.clone(), &bus, MSR),
            None,
            Instance::Can1,
        );
        let mcr_at_reset = model.read32(MCR);
        let config = h.config(500_000).unwrap();
        let options = h.plan_options(&config, FifoPolicy::Fifo1);
        let other = Config::from_bitrate(48_000_000, 500_000).unwrap();
        let h = h.into_single(&other).unwrap_err();
        assert_eq!(h.error, Error::InvalidArgument);
        let regs = h.value.into_single(&config).map_err(|f| f.error).unwrap();
        assert_eq!(model.read32(MCR), mcr_at_reset, "nothing configured");
        // The options are the ones `configure` would give.
        let h = HandedOver {
            regs,
            filters: None::<Regs>,
            instance: Instance::Can1,
            apb1_hz: 54_000_000,
            chip: None,
            parts: (),
        };
        let init = h.configure_single(&config).map_err(|f| f.error).unwrap();
        assert_eq!(options, init.can().plan_options(FifoPolicy::Fifo1));

        // Dual: CAN2's banks where the config splits the block (or, without a split in
        // the config, where the register splits it now).
        let (m1, m2) = BxCanModel::can1_can2();
        let can1 = handed(
            PollClock::new(m1.clone(), &bus, MSR),
            Some(m1.clone()),
            Instance::Can1,
        );
        let can2 = handed(
            PollClock::new(m2.clone(), &bus, MSR),
            Some(m1.clone()),
            Instance::Can2,
        );
        let config1 = can1.config(500_000).unwrap().can2_start_bank(10).unwrap();
        assert_eq!(
            can1.plan_options(&config1, FifoPolicy::Fifo0),
            PlanOptions::new(10)
        );
        assert_eq!(
            can2.plan_options(&config1, FifoPolicy::Fifo1),
            PlanOptions::new(18).fifo(FifoPolicy::Fifo1)
        );
        let base = Config::from_bitrate(54_000_000, 500_000).unwrap();
        let at_reset = crate::regs::fmr::CAN2SB.get(m1.read32(FMR)) as u8;
        assert_eq!(
            can2.plan_options(&base, FifoPolicy::Fifo1),
            PlanOptions::new(28 - at_reset).fifo(FifoPolicy::Fifo1)
        );
        let (_, f) = can2.into_dual(&base).map_err(|f| f.error).unwrap();
        assert_eq!(f.read32(FMR), m1.read32(FMR), "CAN1's filter block");
        let no_filters =
            handed::<BxCanModel>(PollClock::new(m2.clone(), &bus, MSR), None, Instance::Can2);
        assert_eq!(
            no_filters.into_dual(&base).unwrap_err().error,
            Error::InvalidArgument
        );
    }

    #[test]
    fn into_registers_at_gives_the_instance_s_fixed_window_only() {
        use crate::regs::{Can1At, Can1ControlAt, Can2At, Can3At, CAN1_BASE, CAN2_BASE, CAN3_BASE};
        fn whole(base: usize, instance: Instance) -> HandedOver<CanRegs> {
            HandedOver {
                // SAFETY: never read or written here (device addresses on the host).
                regs: unsafe { CanRegs::new(base) },
                filters: None,
                instance,
                apb1_hz: 54_000_000,
                chip: None,
                parts: (),
            }
        }
        fn dual(base: usize, filters: Option<Can1Filters>) -> HandedOver<ControlRegs, Can1Filters> {
            HandedOver {
                // SAFETY: as above.
                regs: unsafe { ControlRegs::new(base) },
                filters,
                instance: Instance::Can2,
                apb1_hz: 54_000_000,
                chip: None,
                parts: (),
            }
        }
        let config = Config::from_bitrate(54_000_000, 500_000).unwrap();
        let other = Config::from_bitrate(48_000_000, 500_000).unwrap();

        // Whole block: another clock, then another instance's base, refused with the
        // handle back; its own base accepted.
        let Err(back) = whole(CAN1_BASE, Instance::Can1).into_registers_at::<CAN1_BASE>(&other)
        else {
            panic!("a config for another clock was accepted");
        };
        assert_eq!(back.error, Error::InvalidArgument);
        let Err(back) = back.value.into_registers_at::<CAN3_BASE>(&config) else {
            panic!("CAN1's window became CAN3's");
        };
        assert_eq!(back.error, Error::InvalidArgument);
        assert_eq!(back.value.regs.base(), CAN1_BASE, "the window comes back");
        let can1: Result<Can1At, _> = back.value.into_registers_at(&config);
        assert!(can1.is_ok());
        let can3: Result<Can3At, _> = whole(CAN3_BASE, Instance::Can3).into_registers_at(&config);
        assert!(can3.is_ok());

        // Dual: the filter handle goes with the control registers; without one, or at
        // another base, refused with both back.
        let filters = Can1Filters {
            regs: &CAN1_FILTERS,
        };
        let Err(back) = dual(CAN2_BASE, None).into_registers_at::<CAN2_BASE>(&config) else {
            panic!("a dual handle without filters was accepted");
        };
        assert_eq!(back.error, Error::InvalidArgument);
        let Err(back) = dual(CAN2_BASE, Some(filters)).into_registers_at::<CAN1_BASE>(&config)
        else {
            panic!("CAN2's window became CAN1's");
        };
        assert_eq!(back.error, Error::InvalidArgument);
        assert!(
            back.value.filters.is_some(),
            "the filter handle comes back too"
        );
        let Err(back) = back.value.into_registers_at::<CAN2_BASE>(&other) else {
            panic!("a config for another clock was accepted");
        };
        let can2: Result<(Can2At, Can1Filters), _> = back.value.into_registers_at(&config);
        assert!(can2.is_ok_and(|(_, f)| f.regs.base() == CAN1_BASE));
        let can1: Result<(Can1ControlAt, Can1Filters), _> =
            dual(CAN1_BASE, Some(filters)).into_registers_at(&config);
        assert!(can1.is_ok());
    }
}
