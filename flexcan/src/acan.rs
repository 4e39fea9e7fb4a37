//! One call per module, as an ACAN sketch's `ACAN::can0.begin (settings)` or an ACAN_T4
//! sketch's `ACAN_T4::can1.begin (settings)` (feature `rt` and a board feature): the
//! module's one call takes its token, begins with the board's defaults on the board's
//! default pins receiving every frame (ACAN's `begin` with no filter; see below), splits
//! the controller **in place** into the library's `static` state of the module (ACAN's
//! buffer sizes, [`OneCallState`], its filter table in a `static` [`TableSlot`]: nothing
//! table-sized moves through the call), wires the interrupts
//! ([`IrqState::start_in_place`]: handlers, then `mMessageIRQPriority`, then the lines
//! unmasked) and returns the transmit and receive halves. The `*_checked` forms take
//! the settings checked beforehand (a `const` [`BeginPlan`]). Its `end_*` is ACAN's `end`: the way back, after which the one call runs
//! again.
//!
//! | board | one call | way back | default settings | layout ([`crate::layout`]) |
//! |---|---|---|---|---|
//! | Teensy 3.x | `can0`, and `can1` on the Teensy 3.6 | `end_can0`, `end_can1` | [`Settings::new`] (ACAN table 7: the 16 MHz oscillator), pins of [`crate::Board::pins`] | [`Kinetis`]: MB0–MB15, ACAN's |
//! | Teensy 4.0 / 4.1 | `can1`, `can2`, `can3` | `end_can1`, `end_can2`, `end_can3` | [`Settings::with_clock`] at [`CanClock::default_for`] the RT1062 (the 24 MHz oscillator root; ACAN_T4's is 60 MHz from PLL3, see `docs/differences.md`), pins 22/23, 0/1 (CAN2: TX 1, RX 0), 30/31 (CAN3: TX 31, RX 30) | [`Imxrt1062`]: the ERR005829 workaround ([`Layout::E5829`]: the first mailbox after the Rx FIFO area kept INACTIVE, two INACTIVE writes after each transmit activation; i.MX RT1060 chip errata) and tables up to RFFN 0xF (a `*_with` or `*_checked` call may give `Filters16_24` … `Filters32_96`); the filter table is the 128-element [`crate::layout::LargeFilterTable`] |
//!
//! The five steps stay available for programs that want control (their own state sizes,
//! filters, pins, priorities, or their own vectors): `Can0::take` (`Can1::take` ...),
//! `begin_in` into a `static` [`TableSlot`] (or `begin` / `begin_on`, whose controller
//! carries its table), a `static` `rt::AcanState` (or another [`IrqState`]),
//! [`IrqState::start`] (or `start_in_place`) with the NVIC, and the halves.
//!
//! **Filters:** the one call installs [`Filter::pass_all`], so that every frame is
//! received as with ACAN's `begin` without filters (`FlexCan::begin` with an empty list
//! receives nothing, see `docs/differences.md`); give filters with the `*_with` form.
//!
//! **How it runs:** every one call is [`start`] (and every way back [`end`]) over the
//! module's [`Module`] token, its [`Spare`] slot, its [`TableSlot`] and its
//! [`OneCallState`]. Those two are
//! generic over the registers, so host tests run them over the behavioural model with
//! a token of their own.
//!
//! **On the host** (no `target_os = "none"`) the board's one calls touch nothing and
//! return [`OneCallError::NotOnTarget`]: the registers they reach are the chip's.

use core::cell::Cell;
use core::fmt;
use core::mem::MaybeUninit;

use critical_section::Mutex;
use twocan_core::{Error, FifoQueue, Filter, Leftovers, Registers};

use crate::begin_error::BeginError;
#[allow(unused_imports)] // doc links
use crate::can_clock::CanClock;
use crate::filters::TableSlot;
#[allow(unused_imports)] // used by the board's one calls
use crate::layout::{BoardLayout, Imxrt1062, Kinetis, Layout};
use crate::options::FullInSlot;
use crate::regs::FlexCanRegs;
use crate::rt::{Halves, InPlaceError, IrqState, Nvic, StartError, StopError};
use crate::settings::{Settings, RECEIVE_BUFFER_SIZE, TRANSMIT_BUFFER_SIZE};
use crate::{BeginPlan, FlexCanHw, Target};

/// The state of a module started by the one call: ACAN's buffer sizes (receive 32,
/// transmit 16, table 7), 8 completions, every feature, the filter table compiled by
/// `begin` straight into the module's `static` [`TableSlot`] ([`FullInSlot`]: no
/// table-sized value moves through the one call, so it configures within a few hundred
/// bytes of stack, issue 21), in the message-buffer layout `L` ([`crate::layout`]: the
/// board's, [`BoardLayout`], by default — [`Imxrt1062`] on a Teensy 4, with the
/// ERR005829 workaround; [`Kinetis`] on a Teensy 3.x).
pub type OneCallState<R = FlexCanRegs, L = BoardLayout> =
    IrqState<R, RECEIVE_BUFFER_SIZE, FifoQueue<TRANSMIT_BUFFER_SIZE>, 8, FullInSlot<L>>;

/// The transmit and receive halves of a module started by the one call (layout `L` as
/// [`OneCallState`]).
pub type AcanHalves<R = FlexCanRegs, L = BoardLayout> =
    Halves<R, RECEIVE_BUFFER_SIZE, FifoQueue<TRANSMIT_BUFFER_SIZE>, 8, FullInSlot<L>>;

/// The filter table of a one call's module in the layout `L` (ACAN's 32 elements with
/// [`Kinetis`], 128 with [`Imxrt1062`]).
pub type OneCallTable<L = BoardLayout> = <L as Layout>::Table;

/// A module's ownership token as the one call uses it: taken once, begun in place, and
/// ended back into a token (`Can0`..`Can3` on the target; a host test's own over the
/// model).
pub trait Module: Sized {
    /// The module's registers.
    type Regs: Registers + 'static;

    /// The message-buffer layout the one call begins the module in ([`crate::layout`]):
    /// [`Imxrt1062`] for the Teensy 4 modules (the RT1062's tables and the ERR005829
    /// workaround), [`Kinetis`] for the Teensy 3.x ones.
    type Layout: Layout;

    /// The module this token owns (what a [`BeginPlan`] for it names).
    const TARGET: Target;

    /// The token the first time (`Can1::take` ...).
    fn take() -> Option<Self>;

    /// ACAN's `begin` on the board's default pins, with the settings checked
    /// beforehand, written in place into `hw` with its lists compiled into `slot` (the
    /// token and the slot come back with the error; nothing is written then).
    #[allow(clippy::type_complexity)]
    fn begin_in_place<'h>(
        self,
        hw: &'h mut MaybeUninit<FlexCanHw<Self::Regs, FullInSlot<Self::Layout>>>,
        checked: &BeginPlan<Self::Layout>,
        primary: &[Filter],
        secondary: &[Filter],
        slot: &'static mut OneCallTable<Self::Layout>,
    ) -> Result<
        &'h mut FlexCanHw<Self::Regs, FullInSlot<Self::Layout>>,
        (Self, BeginError, &'static mut OneCallTable<Self::Layout>),
    >;

    /// ACAN's `end`: the module stopped, its pins and clock gates released, the token
    /// and the table back (the controller comes back with the error).
    #[allow(clippy::result_large_err, clippy::type_complexity)]
    fn end_split(
        hw: FlexCanHw<Self::Regs, FullInSlot<Self::Layout>>,
    ) -> Result<
        (Self, &'static mut OneCallTable<Self::Layout>),
        (FlexCanHw<Self::Regs, FullInSlot<Self::Layout>>, Error),
    >;
}

/// What a [`Spare`] keeps: the token and its module's filter table.
type Kept<M> = (M, &'static mut OneCallTable<<M as Module>::Layout>);

/// Where a module's token and filter table wait between one calls: given back by the
/// way back or by a failed one call (both are taken once: [`Module::take`],
/// [`TableSlot::take`]).
pub struct Spare<M: Module>(Mutex<Cell<Option<Kept<M>>>>);

impl<M: Module> Spare<M> {
    /// Empty.
    pub const fn new() -> Self {
        Spare(Mutex::new(Cell::new(None)))
    }

    fn put(&self, kept: Kept<M>) {
        critical_section::with(|cs| self.0.borrow(cs).set(Some(kept)));
    }

    fn take(&self) -> Option<Kept<M>> {
        critical_section::with(|cs| self.0.borrow(cs).take())
    }

    /// Whether a token waits here.
    pub fn holds(&self) -> bool {
        critical_section::with(|cs| {
            let cell = self.0.borrow(cs);
            let kept = cell.take();
            let held = kept.is_some();
            cell.set(kept);
            held
        })
    }
}

impl<M: Module> Default for Spare<M> {
    fn default() -> Self {
        Self::new()
    }
}

/// The one call: the spare token and table or the first ones, `begin` in place into
/// `state` with the settings `checked` beforehand and the filter lists, then `state`
/// started (handlers in place, then the lines unmasked; `IrqState::start_in_place`);
/// the halves. Neither the controller nor its table moves through the call. A refused
/// `begin` or start keeps the token and the table in `spare`.
#[allow(clippy::result_large_err, clippy::type_complexity)]
// Called once per module, with `checked` usually a `const`: inlined, its checks fold.
#[inline]
pub fn start<M: Module>(
    spare: &Spare<M>,
    table: &'static TableSlot<OneCallTable<M::Layout>>,
    state: &'static OneCallState<M::Regs, M::Layout>,
    checked: &BeginPlan<M::Layout>,
    primary: &[Filter],
    secondary: &[Filter],
    nvic: &mut impl Nvic,
) -> Result<AcanHalves<M::Regs, M::Layout>, OneCallError>
where
    OneCallState<M::Regs, M::Layout>: Sync,
{
    let mut kept = spare.take().or_else(|| Some((M::take()?, table.take()?)));
    if kept.is_none() {
        return Err(OneCallError::Taken);
    }
    let started = state.start_in_place(
        M::TARGET,
        |hw| {
            let (token, slot) = kept.take().ok_or(None)?;
            token
                .begin_in_place(hw, checked, primary, secondary, slot)
                .map_err(|(token, e, slot)| {
                    kept = Some((token, slot));
                    Some(e)
                })
        },
        nvic,
    );
    // Not started: the token and the table wait for the next call.
    if let Some(k) = kept {
        spare.put(k);
    }
    started.map_err(|e| match e {
        InPlaceError::Init(Some(e)) => OneCallError::Begin(e),
        InPlaceError::Init(None) => OneCallError::Taken,
        InPlaceError::Start(e) => OneCallError::Start(e),
    })
}

/// The way back from [`start`]: the lines masked, the handlers and the halves taken back
/// ([`IrqState::stop`]), the module stopped and its pins and clock gates released
/// ([`Module::end_split`]), its token and table in `spare` for the next one call.
/// Returns what was left in the rings and the queue (discarded); on error the halves
/// come back when the driver still runs (`None`: the module was stopped but did not
/// acknowledge in time).
#[allow(clippy::result_large_err, clippy::type_complexity)]
pub fn end<M: Module>(
    spare: &Spare<M>,
    state: &'static OneCallState<M::Regs, M::Layout>,
    halves: AcanHalves<M::Regs, M::Layout>,
    nvic: &mut impl Nvic,
) -> Result<Leftovers, (OneCallError, Option<AcanHalves<M::Regs, M::Layout>>)>
where
    OneCallState<M::Regs, M::Layout>: Sync,
{
    let (hw, left) = state
        .stop(halves.0, halves.1, nvic)
        .map_err(|(e, h)| (OneCallError::Stop(e), Some(h)))?;
    let kept = M::end_split(hw).map_err(|(_, e)| (OneCallError::End(e), None))?;
    spare.put(kept);
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

/// The target's tokens as [`Module`]s: `begin_in_place` and `end_split` at the module's
/// base address.
#[cfg(target_os = "none")]
macro_rules! module {
    ($token:ty, $layout:ty) => {
        impl Module for $token {
            type Regs = FlexCanRegs;
            type Layout = $layout;
            const TARGET: Target = <$token>::TARGET;

            fn take() -> Option<Self> {
                <$token>::take()
            }

            fn begin_in_place<'h>(
                self,
                hw: &'h mut MaybeUninit<FlexCanHw<FlexCanRegs, FullInSlot<$layout>>>,
                checked: &BeginPlan<$layout>,
                primary: &[Filter],
                secondary: &[Filter],
                slot: &'static mut OneCallTable<$layout>,
            ) -> Result<
                &'h mut FlexCanHw<FlexCanRegs, FullInSlot<$layout>>,
                (Self, BeginError, &'static mut OneCallTable<$layout>),
            > {
                <$token>::begin_in_place(self, hw, checked, primary, secondary, slot)
            }

            fn end_split(
                hw: FlexCanHw<FlexCanRegs, FullInSlot<$layout>>,
            ) -> Result<
                (Self, &'static mut OneCallTable<$layout>),
                (FlexCanHw<FlexCanRegs, FullInSlot<$layout>>, Error),
            > {
                <$token>::end_split(hw)
            }
        }
    };
}

#[cfg(all(
    target_os = "none",
    not(any(feature = "teensy40", feature = "teensy41"))
))]
module!(crate::Can0, Kinetis);
#[cfg(all(
    target_os = "none",
    feature = "teensy36",
    not(any(feature = "teensy40", feature = "teensy41"))
))]
module!(crate::Can1, Kinetis);
// The RT1062's modules: the RT1062 layout (its tables, the ERR005829 workaround).
#[cfg(all(target_os = "none", any(feature = "teensy40", feature = "teensy41")))]
module!(crate::Can1, Imxrt1062);
#[cfg(all(target_os = "none", any(feature = "teensy40", feature = "teensy41")))]
module!(crate::Can2, Imxrt1062);
#[cfg(all(target_os = "none", any(feature = "teensy40", feature = "teensy41")))]
module!(crate::Can3, Imxrt1062);

/// Defines the one call and its way back for one module.
macro_rules! one_call {
    ($(#[$m:meta])* $token:ident, $layout:ty, $state:ident, $table:ident, $spare:ident, $start:ident, $start_with:ident, $start_checked:ident, $end:ident, $name:literal) => {
        $(#[$m])*
        #[doc = concat!("The module's state and interrupt handlers (ACAN's buffer sizes, the layout `", stringify!($layout), "`), used by [`", stringify!($start), "`].")]
        pub static $state: OneCallState<FlexCanRegs, $layout> = OneCallState::new();

        $(#[$m])*
        #[cfg(target_os = "none")]
        static $table: TableSlot<OneCallTable<$layout>> = TableSlot::new_sized();

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
        ) -> Result<AcanHalves<FlexCanRegs, $layout>, OneCallError> {
            $start_with(&default_settings(bit_rate), &[Filter::pass_all()], &[], nvic)
        }

        $(#[$m])*
        #[doc = concat!("[`", stringify!($start), "`] with `settings` and ACAN's primary and secondary filter lists.")]
        pub fn $start_with(
            settings: &Settings,
            primary: &[Filter],
            secondary: &[Filter],
            nvic: &mut impl Nvic,
        ) -> Result<AcanHalves<FlexCanRegs, $layout>, OneCallError> {
            #[cfg(not(target_os = "none"))]
            {
                let _ = (settings, primary, secondary, nvic);
                Err(OneCallError::NotOnTarget)
            }
            #[cfg(target_os = "none")]
            {
                // The settings checked first (ACAN table 5), before the state lends its
                // storage.
                let checked = BeginPlan::<$layout>::new_with_layout(
                    crate::$token::TARGET,
                    settings,
                    settings.configuration,
                )
                .map_err(OneCallError::Begin)?;
                $start_checked(&checked, primary, secondary, nvic)
            }
        }

        $(#[$m])*
        #[doc = concat!("[`", stringify!($start_with), "`] with the settings checked beforehand: a `BeginPlan<", stringify!($layout), ">` for `", stringify!($token), "::TARGET` (`BeginPlan::new_with_layout`), `const` for `const` settings (no check of the settings runs then, and the configuration's stack is the smallest). A plan for another module is `Begin(Hardware(InvalidArgument))`.")]
        pub fn $start_checked(
            checked: &BeginPlan<$layout>,
            primary: &[Filter],
            secondary: &[Filter],
            nvic: &mut impl Nvic,
        ) -> Result<AcanHalves<FlexCanRegs, $layout>, OneCallError> {
            #[cfg(not(target_os = "none"))]
            {
                let _ = (checked, primary, secondary, nvic);
                Err(OneCallError::NotOnTarget)
            }
            #[cfg(target_os = "none")]
            {
                start(&$spare, &$table, &$state, checked, primary, secondary, nvic)
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
            halves: AcanHalves<FlexCanRegs, $layout>,
            nvic: &mut impl Nvic,
        ) -> Result<Leftovers, (OneCallError, Option<AcanHalves<FlexCanRegs, $layout>>)> {
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
    Kinetis,
    CAN0,
    TABLE0,
    SPARE0,
    can0,
    can0_with,
    can0_checked,
    end_can0,
    "can0"
);
// A Teensy 3.6's can1 (Kinetis layout) or a Teensy 4's CAN1 (RT1062 layout): the
// board's layout either way.
one_call!(
    #[cfg(any(feature = "teensy36", feature = "teensy40", feature = "teensy41"))]
    Can1,
    crate::layout::BoardLayout,
    CAN1,
    TABLE1,
    SPARE1,
    can1,
    can1_with,
    can1_checked,
    end_can1,
    "can1"
);
one_call!(
    #[cfg(any(feature = "teensy40", feature = "teensy41"))]
    Can2,
    Imxrt1062,
    CAN2,
    TABLE2,
    SPARE2,
    can2,
    can2_with,
    can2_checked,
    end_can2,
    "can2"
);
one_call!(
    #[cfg(any(feature = "teensy40", feature = "teensy41"))]
    Can3,
    Imxrt1062,
    CAN3,
    TABLE3,
    SPARE3,
    can3,
    can3_with,
    can3_checked,
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
