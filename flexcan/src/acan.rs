//! One call per module, as an ACAN sketch's `ACAN::can0.begin (settings)` or an ACAN_T4
//! sketch's `ACAN_T4::can1.begin (settings)` (feature `rt` and a board feature): the
//! module's one call takes its token, begins with the board's defaults on the board's
//! default pins receiving every frame (ACAN's `begin` with no filter; see below), splits
//! the controller into the library's `static` state of the module (ACAN's buffer sizes,
//! [`AcanState`]), wires the interrupts ([`IrqState::start`]: handlers, then
//! `mMessageIRQPriority`, then the lines unmasked) and returns the transmit and receive
//! halves. Its `end_*` is ACAN's `end`: the way back, after which the one call runs
//! again.
//!
//! | board | one call | way back | default settings |
//! |---|---|---|---|
//! | Teensy 3.x | `can0`, and `can1` on the Teensy 3.6 | `end_can0`, `end_can1` | [`Settings::new`] (ACAN table 7: the 16 MHz oscillator), pins of [`crate::Board::pins`] |
//! | Teensy 4.0 / 4.1 | `can1`, `can2`, `can3` | `end_can1`, `end_can2`, `end_can3` | [`Settings::with_clock`] at [`CanClock::default_for`] the RT1062 (the 24 MHz oscillator root; ACAN_T4's is 60 MHz from PLL3, see `docs/differences.md`), pins 22/23, 0/1 (CAN2: TX 1, RX 0), 30/31 (CAN3: TX 31, RX 30) |
//!
//! The five steps stay available for programs that want control (their own state sizes,
//! filters, pins, priorities, or their own vectors): `Can0::take` (`Can1::take` ...),
//! `begin` / `begin_on` with pins, a `static` [`AcanState`] (or another [`IrqState`]),
//! [`IrqState::start`] with the NVIC, and the halves.
//!
//! **Filters:** the one call installs [`Filter::pass_all`], so that every frame is
//! received as with ACAN's `begin` without filters (`FlexCan::begin` with an empty list
//! receives nothing, see `docs/differences.md`); give filters with the `*_with` form.
//!
//! **How it runs:** every one call is [`start`] (and every way back [`end`]) over the
//! module's [`Module`] token, its [`Spare`] slot and its [`AcanState`]. Those two are
//! generic over the registers, so host tests run them over the behavioural model with
//! a token of their own.
//!
//! **On the host** (no `target_os = "none"`) the board's one calls touch nothing and
//! return [`OneCallError::NotOnTarget`]: the registers they reach are the chip's.

use core::cell::Cell;
use core::fmt;

use critical_section::Mutex;
use twocan_core::{Error, FifoQueue, Filter, Leftovers, Registers};

use crate::begin_error::BeginError;
#[allow(unused_imports)] // doc links
use crate::can_clock::CanClock;
use crate::controller::FlexCan;
use crate::regs::FlexCanRegs;
use crate::rt::{Halves, IrqState, Nvic, StartError, StopError};
use crate::settings::{Settings, RECEIVE_BUFFER_SIZE, TRANSMIT_BUFFER_SIZE};

/// The state of a module started by the one call: ACAN's buffer sizes (receive 32,
/// transmit 16, table 7), 8 completions.
pub use crate::rt::AcanState;

/// The transmit and receive halves of a module started by the one call.
pub type AcanHalves =
    Halves<FlexCanRegs, RECEIVE_BUFFER_SIZE, twocan_core::FifoQueue<TRANSMIT_BUFFER_SIZE>, 8>;

/// A module's ownership token as the one call uses it: taken once, begun, and ended
/// back into a token (`Can0`..`Can3` on the target; a host test's own over the model).
pub trait Module: Sized {
    /// The module's registers.
    type Regs: Registers + 'static;

    /// The token the first time (`Can1::take` ...).
    fn take() -> Option<Self>;

    /// ACAN's `begin` on the board's default pins ([`Settings`] says which; the
    /// token comes back with the error).
    #[allow(clippy::result_large_err)]
    fn begin(
        self,
        settings: &Settings,
        primary: &[Filter],
        secondary: &[Filter],
    ) -> Result<FlexCan<Self::Regs>, (Self, BeginError)>;

    /// ACAN's `end`: the module stopped, its pins and clock gates released, the token
    /// back (the controller comes back with the error).
    #[allow(clippy::result_large_err)]
    fn end(controller: FlexCan<Self::Regs>) -> Result<Self, (FlexCan<Self::Regs>, Error)>;
}

/// Where a token waits between one calls: given back by the way back or by a failed
/// one call (a token is taken once from [`Module::take`]).
pub struct Spare<M>(Mutex<Cell<Option<M>>>);

impl<M> Spare<M> {
    /// Empty.
    pub const fn new() -> Self {
        Spare(Mutex::new(Cell::new(None)))
    }

    fn put(&self, token: M) {
        critical_section::with(|cs| self.0.borrow(cs).set(Some(token)));
    }

    fn take(&self) -> Option<M> {
        critical_section::with(|cs| self.0.borrow(cs).take())
    }

    /// Whether a token waits here.
    pub fn holds(&self) -> bool {
        critical_section::with(|cs| {
            let cell = self.0.borrow(cs);
            let token = cell.take();
            let held = token.is_some();
            cell.set(token);
            held
        })
    }
}

impl<M> Default for Spare<M> {
    fn default() -> Self {
        Self::new()
    }
}

/// The halves the one call gives over `M`'s registers.
pub type HalvesOf<M, const RX: usize, const TX: usize, const DONE: usize> =
    Halves<<M as Module>::Regs, RX, FifoQueue<TX>, DONE>;

/// The one call: the spare token or the first one, `begin` with `settings` and the
/// filter lists, then `state` started (handlers in place, then the lines unmasked); the
/// halves. A refused `begin` keeps the token in `spare`; a refused start ends the module
/// again and keeps its token (unless the module would not stop: it keeps running
/// unwired, as after `begin`).
#[allow(clippy::result_large_err, clippy::type_complexity)]
pub fn start<M: Module, const RX: usize, const TX: usize, const DONE: usize>(
    spare: &Spare<M>,
    state: &'static IrqState<M::Regs, RX, FifoQueue<TX>, DONE>,
    settings: &Settings,
    primary: &[Filter],
    secondary: &[Filter],
    nvic: &mut impl Nvic,
) -> Result<HalvesOf<M, RX, TX, DONE>, OneCallError>
where
    IrqState<M::Regs, RX, FifoQueue<TX>, DONE>: Sync,
{
    let Some(token) = spare.take().or_else(M::take) else {
        return Err(OneCallError::Taken);
    };
    let controller = match token.begin(settings, primary, secondary) {
        Ok(c) => c,
        Err((token, e)) => {
            spare.put(token);
            return Err(OneCallError::Begin(e));
        }
    };
    match state.start(controller.into_split(), nvic) {
        Ok(halves) => Ok(halves),
        Err((e, hw)) => {
            if let Ok(token) = M::end(hw.into_controller()) {
                spare.put(token);
            }
            Err(OneCallError::Start(e))
        }
    }
}

/// The way back from [`start`]: the lines masked, the handlers and the halves taken back
/// ([`IrqState::stop`]), the module stopped and its pins and clock gates released
/// ([`Module::end`]), its token in `spare` for the next one call. Returns what was left
/// in the rings and the queue (discarded); on error the halves come back when the
/// driver still runs (`None`: the module was stopped but did not acknowledge in time).
#[allow(clippy::result_large_err, clippy::type_complexity)]
pub fn end<M: Module, const RX: usize, const TX: usize, const DONE: usize>(
    spare: &Spare<M>,
    state: &'static IrqState<M::Regs, RX, FifoQueue<TX>, DONE>,
    halves: HalvesOf<M, RX, TX, DONE>,
    nvic: &mut impl Nvic,
) -> Result<Leftovers, (OneCallError, Option<HalvesOf<M, RX, TX, DONE>>)>
where
    IrqState<M::Regs, RX, FifoQueue<TX>, DONE>: Sync,
{
    let (hw, left) = state
        .stop(halves.0, halves.1, nvic)
        .map_err(|(e, h)| (OneCallError::Stop(e), Some(h)))?;
    let token = M::end(hw.into_controller()).map_err(|(_, e)| (OneCallError::End(e), None))?;
    spare.put(token);
    Ok(left)
}

/// Why a one call did not start or end the module.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum OneCallError {
    /// Not built for the target: nothing was touched.
    NotOnTarget,
    /// The module's token is held elsewhere (the five steps took it, or the module
    /// runs already).
    Taken,
    /// `begin` refused (ACAN §15): the module was left as `begin` left it; the token
    /// is kept for the next call.
    Begin(BeginError),
    /// The interrupts could not be wired (the module's entry points run a state of
    /// the five steps): the module was ended again; the token is kept.
    Start(StartError),
    /// The way back refused (the halves come back with it).
    Stop(StopError),
    /// The module did not stop within its handshake bound (`FlexCan::end`).
    End(twocan_core::Error),
}

impl fmt::Display for OneCallError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            OneCallError::NotOnTarget => f.write_str("the one call runs on the target only"),
            OneCallError::Taken => f.write_str("the module's token is held elsewhere"),
            OneCallError::Begin(e) => write!(f, "begin: {e}"),
            OneCallError::Start(e) => write!(f, "start: {e}"),
            OneCallError::Stop(e) => write!(f, "stop: {e}"),
            OneCallError::End(e) => write!(f, "end: {e}"),
        }
    }
}

impl core::error::Error for OneCallError {}

/// The board's default settings of a one call at `bit_rate`: ACAN's (Kinetis) or, on
/// the RT1062, the same at the chip's default clock root ([`CanClock::default_for`]).
pub const fn default_settings(bit_rate: u32) -> Settings {
    #[cfg(any(feature = "teensy40", feature = "teensy41"))]
    {
        Settings::with_clock(
            bit_rate,
            CanClock::default_for(crate::board::Chip::Imxrt1062),
        )
    }
    #[cfg(not(any(feature = "teensy40", feature = "teensy41")))]
    {
        Settings::new(bit_rate)
    }
}

/// The target's tokens as [`Module`]s: `begin` and `end` at the module's base address.
#[cfg(target_os = "none")]
macro_rules! module {
    ($token:ty) => {
        impl Module for $token {
            type Regs = FlexCanRegs;

            fn take() -> Option<Self> {
                <$token>::take()
            }

            fn begin(
                self,
                settings: &Settings,
                primary: &[Filter],
                secondary: &[Filter],
            ) -> Result<FlexCan<FlexCanRegs>, (Self, BeginError)> {
                <$token>::begin(self, settings, primary, secondary)
            }

            fn end(
                controller: FlexCan<FlexCanRegs>,
            ) -> Result<Self, (FlexCan<FlexCanRegs>, Error)> {
                <$token>::end(controller)
            }
        }
    };
}

#[cfg(all(
    target_os = "none",
    not(any(feature = "teensy40", feature = "teensy41"))
))]
module!(crate::Can0);
#[cfg(all(
    target_os = "none",
    any(feature = "teensy36", feature = "teensy40", feature = "teensy41")
))]
module!(crate::Can1);
#[cfg(all(target_os = "none", any(feature = "teensy40", feature = "teensy41")))]
module!(crate::Can2);
#[cfg(all(target_os = "none", any(feature = "teensy40", feature = "teensy41")))]
module!(crate::Can3);

/// Defines the one call and its way back for one module.
macro_rules! one_call {
    ($(#[$m:meta])* $token:ident, $state:ident, $spare:ident, $start:ident, $start_with:ident, $end:ident, $name:literal) => {
        $(#[$m])*
        #[doc = concat!("The module's state and interrupt handlers (ACAN's buffer sizes), used by [`", stringify!($start), "`].")]
        pub static $state: AcanState = AcanState::new();

        $(#[$m])*
        #[cfg(target_os = "none")]
        static $spare: Spare<crate::$token> = Spare::new();

        $(#[$m])*
        #[doc = concat!("ACAN `ACAN::", $name, ".begin (ACANSettings (bit_rate))` (ACAN_T4 `ACAN_T4::", $name, ".begin`): ")]
        /// the module begun with the board's default settings ([`default_settings`]) at
        /// `bit_rate` on the board's default pins, receiving every frame, its interrupts
        /// wired at the default priority; the halves. See the [module
        /// documentation](self).
        pub fn $start(
            bit_rate: u32,
            nvic: &mut impl Nvic,
        ) -> Result<AcanHalves, OneCallError> {
            $start_with(&default_settings(bit_rate), &[Filter::pass_all()], &[], nvic)
        }

        $(#[$m])*
        #[doc = concat!("[`", stringify!($start), "`] with `settings` and ACAN's primary and secondary filter lists.")]
        pub fn $start_with(
            settings: &Settings,
            primary: &[Filter],
            secondary: &[Filter],
            nvic: &mut impl Nvic,
        ) -> Result<AcanHalves, OneCallError> {
            #[cfg(not(target_os = "none"))]
            {
                let _ = (settings, primary, secondary, nvic);
                Err(OneCallError::NotOnTarget)
            }
            #[cfg(target_os = "none")]
            {
                start(&$spare, &$state, settings, primary, secondary, nvic)
            }
        }

        $(#[$m])*
        #[doc = concat!("ACAN `ACAN::", $name, ".end ()`: the way back from [`", stringify!($start), "`] ([`end`]): ")]
        /// the lines masked, the handlers and the halves taken back, the module
        /// stopped and its pins and clock gates released. The one call runs again
        /// afterwards. Returns what was left in the rings and the queue (discarded); on
        /// error the halves come back when the driver still runs.
        #[allow(clippy::result_large_err)]
        pub fn $end(
            halves: AcanHalves,
            nvic: &mut impl Nvic,
        ) -> Result<Leftovers, (OneCallError, Option<AcanHalves>)> {
            #[cfg(not(target_os = "none"))]
            {
                let _ = nvic;
                Err((OneCallError::NotOnTarget, Some(halves)))
            }
            #[cfg(target_os = "none")]
            {
                end(&$spare, &$state, halves, nvic)
            }
        }
    };
}

one_call!(
    #[cfg(not(any(feature = "teensy40", feature = "teensy41")))]
    Can0,
    CAN0,
    SPARE0,
    can0,
    can0_with,
    end_can0,
    "can0"
);
one_call!(
    #[cfg(any(feature = "teensy36", feature = "teensy40", feature = "teensy41"))]
    Can1,
    CAN1,
    SPARE1,
    can1,
    can1_with,
    end_can1,
    "can1"
);
one_call!(
    #[cfg(any(feature = "teensy40", feature = "teensy41"))]
    Can2,
    CAN2,
    SPARE2,
    can2,
    can2_with,
    end_can2,
    "can2"
);
one_call!(
    #[cfg(any(feature = "teensy40", feature = "teensy41"))]
    Can3,
    CAN3,
    SPARE3,
    can3,
    can3_with,
    end_can3,
    "can3"
);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rt::IrqNumber;

    struct NoNvic;
    impl Nvic for NoNvic {
        fn set_priority(&mut self, _: IrqNumber, _: u8) {
            unreachable!("nothing wired on the host")
        }
        fn unmask(&mut self, _: IrqNumber) {
            unreachable!("nothing wired on the host")
        }
        fn mask(&mut self, _: IrqNumber) {
            unreachable!("nothing wired on the host")
        }
    }

    #[cfg(not(any(feature = "teensy40", feature = "teensy41")))]
    #[test]
    fn on_the_host_the_one_call_touches_nothing() {
        assert_eq!(
            can0(500_000, &mut NoNvic).map(|_| ()),
            Err(OneCallError::NotOnTarget)
        );
        assert!(CAN0.state().hardware().is_none());
        assert!(!crate::rt::is_wired(crate::Instance::Can0));
        assert_eq!(default_settings(500_000), Settings::new(500_000));
    }

    #[cfg(any(feature = "teensy40", feature = "teensy41"))]
    #[test]
    fn on_the_host_the_one_call_touches_nothing() {
        for (result, state, instance) in [
            (
                can1(500_000, &mut NoNvic).map(|_| ()),
                &CAN1,
                crate::Instance::Can1,
            ),
            (
                can2(500_000, &mut NoNvic).map(|_| ()),
                &CAN2,
                crate::Instance::Can2,
            ),
            (
                can3(500_000, &mut NoNvic).map(|_| ()),
                &CAN3,
                crate::Instance::Can3,
            ),
        ] {
            assert_eq!(result, Err(OneCallError::NotOnTarget));
            assert!(state.state().hardware().is_none());
            assert!(!crate::rt::is_wired(instance));
        }
        let s = default_settings(500_000);
        assert_eq!(s.can_clock.hz(), 24_000_000);
        assert_eq!(s.actual_bit_rate(), 500_000);
    }
}
