//! One call per module, as an ACAN sketch's `ACAN::can0.begin (settings)` (feature `rt`
//! and a board feature): [`can0`] (and [`can1`] on the Teensy 3.6) takes the module's
//! token, begins with ACAN's defaults on the board's default pins ([`Settings::new`]:
//! ACAN table 7, [`crate::Board::pins`]) receiving every frame (ACAN's `begin` with no
//! filter; see below), splits the controller into the library's `static` state of the
//! module ([`CAN0`], [`CAN1`]: ACAN's buffer sizes), wires the interrupts
//! ([`IrqState::start`]: handlers, then `mMessageIRQPriority`, then the lines unmasked)
//! and returns the transmit and receive halves. [`end_can0`] / [`end_can1`] are ACAN's
//! `end`: the way back, after which [`can0`] runs again.
//!
//! The five steps stay available for programs that want control (their own state sizes,
//! filters, pins, priorities, or their own vectors): `Can0::take`, `Can0::begin_in`
//! into a `static` `filters::TableSlot` (or `begin` / `begin_on`, whose controller carries its
//! table), a `static` [`IrqState`] ([`OneCallState`], `rt::AcanState`),
//! [`IrqState::start`] with the NVIC, and the halves.
//!
//! **Filters:** the one call installs [`Filter::pass_all`], so that every frame is
//! received as with ACAN's `begin` without filters (`FlexCan::begin` with an empty list
//! receives nothing, see `docs/differences.md`); give filters with [`can0_with`].
//!
//! **On the host** (no `target_os = "none"`) these functions touch nothing and return
//! [`OneCallError::NotOnTarget`]: the registers they reach are the chip's.

#[cfg(target_os = "none")]
use core::cell::Cell;
use core::fmt;

#[cfg(target_os = "none")]
use critical_section::Mutex;
use twocan_core::{Filter, Leftovers};

use crate::begin_error::BeginError;
#[cfg(target_os = "none")]
use crate::filters::{FilterTable, TableSlot};
use crate::options::FullInSlot;
use crate::regs::FlexCanRegs;
#[cfg(target_os = "none")]
use crate::rt::InPlaceError;
#[allow(unused_imports)] // doc links
use crate::rt::IrqState;
use crate::rt::{Halves, Nvic, StartError, StopError};
use crate::settings::{Settings, RECEIVE_BUFFER_SIZE, TRANSMIT_BUFFER_SIZE};
use crate::BeginPlan;
#[cfg(target_os = "none")]
use crate::Can0;
#[cfg(all(target_os = "none", feature = "teensy36"))]
use crate::Can1;

/// The state of a module started by the one call: ACAN's buffer sizes, every feature,
/// the filter table compiled by `begin` straight into the module's `static`
/// `TableSlot` ([`FullInSlot`]: no table-sized value moves through the one call, so
/// it configures within a few hundred bytes of stack, issue 21).
pub type OneCallState = IrqState<
    FlexCanRegs,
    RECEIVE_BUFFER_SIZE,
    twocan_core::FifoQueue<TRANSMIT_BUFFER_SIZE>,
    8,
    FullInSlot,
>;

/// The transmit and receive halves of a module started by the one call.
pub type AcanHalves = Halves<
    FlexCanRegs,
    RECEIVE_BUFFER_SIZE,
    twocan_core::FifoQueue<TRANSMIT_BUFFER_SIZE>,
    8,
    FullInSlot,
>;

/// FlexCAN0's state and interrupt handlers, used by [`can0`].
pub static CAN0: OneCallState = OneCallState::new();
/// FlexCAN1's (Teensy 3.6), used by [`can1`].
#[cfg(feature = "teensy36")]
pub static CAN1: OneCallState = OneCallState::new();

/// FlexCAN0's filter table, which the one call's `begin` compiles into.
#[cfg(target_os = "none")]
static TABLE0: TableSlot = TableSlot::new();
/// FlexCAN1's.
#[cfg(all(target_os = "none", feature = "teensy36"))]
static TABLE1: TableSlot = TableSlot::new();

/// Tokens given back by [`end_can0`] / [`end_can1`] or by a failed one call, for the
/// next one call (a token is taken once from `Can0::take`).
#[cfg(target_os = "none")]
static SPARE0: Spare<Can0> = Mutex::new(Cell::new(None));
#[cfg(all(target_os = "none", feature = "teensy36"))]
static SPARE1: Spare<Can1> = Mutex::new(Cell::new(None));

/// A module's token and filter table between one calls (both taken once from their
/// `take`).
#[cfg(target_os = "none")]
type Spare<T> = Mutex<Cell<Option<(T, &'static mut FilterTable)>>>;

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
    /// the five steps): nothing was configured; the token is kept.
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

/// Defines the one call and its way back for one module.
macro_rules! one_call {
    ($(#[$m:meta])* $token:ident, $state:ident, $table:ident, $spare:ident, $start:ident, $start_with:ident, $start_checked:ident, $end:ident, $name:literal) => {
        $(#[$m])*
        #[doc = concat!("ACAN `ACAN::", $name, ".begin (ACANSettings (bit_rate))`: ")]
        /// the module begun with ACAN's defaults at `bit_rate` on the board's default
        /// pins, receiving every frame, its interrupts wired at the default priority;
        /// the halves. See the [module documentation](self).
        pub fn $start(
            bit_rate: u32,
            nvic: &mut impl Nvic,
        ) -> Result<AcanHalves, OneCallError> {
            $start_with(&Settings::new(bit_rate), &[Filter::pass_all()], &[], nvic)
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
                // The settings checked first (ACAN table 5), before the state lends its
                // storage.
                let checked = BeginPlan::new($token::TARGET, settings, settings.configuration)
                    .map_err(OneCallError::Begin)?;
                $start_checked(&checked, primary, secondary, nvic)
            }
        }

        $(#[$m])*
        #[doc = concat!("[`", stringify!($start_with), "`] with the settings checked beforehand: a `BeginPlan` for `", stringify!($token), "::TARGET`, `const` for `const` settings (no check of the settings runs then, and the configuration's stack is the smallest). A plan for another module is `Begin(Hardware(InvalidArgument))`.")]
        pub fn $start_checked(
            checked: &BeginPlan,
            primary: &[Filter],
            secondary: &[Filter],
            nvic: &mut impl Nvic,
        ) -> Result<AcanHalves, OneCallError> {
            #[cfg(not(target_os = "none"))]
            {
                let _ = (checked, primary, secondary, nvic);
                Err(OneCallError::NotOnTarget)
            }
            #[cfg(target_os = "none")]
            {
                let mut spare = critical_section::with(|cs| $spare.borrow(cs).take())
                    .or_else(|| Some(($token::take()?, $table.take()?)));
                let Some(target) = spare.as_ref().map(|(token, _)| token.target()) else {
                    return Err(OneCallError::Taken);
                };
                // Configured in place in the state (`start_in_place`): neither the
                // controller nor its table moves through the one call.
                let started = $state.start_in_place(
                    target,
                    |hw| {
                        let (token, slot) = spare.take().ok_or(None)?;
                        token
                            .begin_in_place(hw, checked, primary, secondary, slot)
                            .map_err(|(token, e, slot)| {
                                spare = Some((token, slot));
                                Some(e)
                            })
                    },
                    nvic,
                );
                // Not started: the token and the table wait for the next call.
                if let Some(kept) = spare {
                    critical_section::with(|cs| $spare.borrow(cs).set(Some(kept)));
                }
                started.map_err(|e| match e {
                    InPlaceError::Init(Some(e)) => OneCallError::Begin(e),
                    InPlaceError::Init(None) => OneCallError::Taken,
                    InPlaceError::Start(e) => OneCallError::Start(e),
                })
            }
        }

        $(#[$m])*
        #[doc = concat!("ACAN `ACAN::", $name, ".end ()`: the way back from [`", stringify!($start), "`]: ")]
        /// the lines masked, the handlers and the halves taken back
        /// ([`IrqState::stop`]), the module stopped and its pins and clock gate
        /// released (`FlexCan::end`). The one call runs again afterwards. Returns what
        /// was left in the rings and the queue (discarded); on error the halves come
        /// back when the driver still runs (`None`: the module was stopped but did not
        /// acknowledge in time).
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
                let (hw, left) = $state
                    .stop(halves.0, halves.1, nvic)
                    .map_err(|(e, h)| (OneCallError::Stop(e), Some(h)))?;
                let spare =
                    $token::end_split(hw).map_err(|(_, e)| (OneCallError::End(e), None))?;
                critical_section::with(|cs| $spare.borrow(cs).set(Some(spare)));
                Ok(left)
            }
        }
    };
}

one_call!(
    Can0,
    CAN0,
    TABLE0,
    SPARE0,
    can0,
    can0_with,
    can0_checked,
    end_can0,
    "can0"
);
one_call!(
    #[cfg(feature = "teensy36")]
    Can1,
    CAN1,
    TABLE1,
    SPARE1,
    can1,
    can1_with,
    can1_checked,
    end_can1,
    "can1"
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

    #[test]
    fn on_the_host_the_one_call_touches_nothing() {
        assert_eq!(
            can0(500_000, &mut NoNvic).map(|_| ()),
            Err(OneCallError::NotOnTarget)
        );
        assert!(CAN0.state().hardware().is_none());
        assert!(!crate::rt::is_wired(crate::Instance::Can0));
    }
}
