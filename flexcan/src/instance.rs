//! FlexCAN instances and their one-time ownership tokens (ACAN §6).
//!
//! ACAN's `ACAN::can0` and `ACAN::can1` are global objects whose constructor is
//! private, so a sketch cannot make a second driver for the same module. Here the
//! same guarantee is a token taken at most once: `Can0::take` (every board) and
//! `Can1::take` (Teensy 3.6) return `Some` the first time only, and `begin`
//! consumes the token. The tokens need no `unsafe`: an atomic flag records the take.
//!
//! On the host, a controller is built over any [`twocan_core::Registers`] (the
//! behavioural model) with [`crate::FlexCan::begin`], naming the instance and the
//! board as a [`Target`].

use crate::board::{Board, Chip};
use crate::imxrt;
use crate::regs;

/// A FlexCAN module, by the name its chip's reference manual gives it: FlexCAN0 and
/// FlexCAN1 on the Kinetis parts (ACAN §6 table 2), CAN1, CAN2 and CAN3 on the i.MX
/// RT1062 (IMXRT1060RM, "System Memory Map"). `Can1` names a module of either family;
/// its base, gate and interrupts depend on the chip ([`Instance::base`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Instance {
    /// FlexCAN0 (`ACAN::can0`): every Teensy 3.x.
    Can0,
    /// FlexCAN1 (`ACAN::can1`): Teensy 3.6; CAN1 of the RT1062 (Teensy 4.x).
    Can1,
    /// CAN2 of the RT1062 (Teensy 4.x).
    Can2,
    /// CAN3 of the RT1062 (Teensy 4.x), the CAN FD capable module (driven in classic
    /// CAN).
    Can3,
}

/// The interrupt numbers (NVIC IRQ numbers, vector number − 16) of one instance,
/// from the chips' vector tables (K20 and K66 reference manuals, "Interrupt channel
/// assignments"; the K64 shares the K66 numbering for FlexCAN0).
///
/// ACAN services everything from the message interrupt; the firmware enables
/// [`Irqs::message`] with [`crate::Settings::message_irq_priority`] and calls the
/// driver's `on_interrupt` from its handler. With
/// [`crate::Settings::error_interrupts`] (the default), it routes
/// [`Irqs::bus_off`], [`Irqs::error`], [`Irqs::tx_warning`] and [`Irqs::rx_warning`]
/// to the same handler.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Irqs {
    /// ORed message buffer interrupt (Rx FIFO and mailboxes).
    pub message: u16,
    /// Bus-off interrupt.
    pub bus_off: u16,
    /// Error interrupt.
    pub error: u16,
    /// Transmit warning interrupt.
    pub tx_warning: u16,
    /// Receive warning interrupt.
    pub rx_warning: u16,
    /// Wake-up interrupt.
    pub wake_up: u16,
}

impl Irqs {
    /// The RT1062's one line per module: every source on `line`.
    const fn single(line: u16) -> Self {
        Irqs {
            message: line,
            bus_off: line,
            error: line,
            tx_warning: line,
            rx_warning: line,
            wake_up: line,
        }
    }

    /// Whether every source shares one line (the RT1062).
    pub const fn is_single_line(&self) -> bool {
        self.message == self.bus_off
            && self.message == self.error
            && self.message == self.tx_warning
            && self.message == self.rx_warning
    }

    const fn from(first: u16) -> Self {
        Irqs {
            message: first,
            bus_off: first + 1,
            error: first + 2,
            tx_warning: first + 3,
            rx_warning: first + 4,
            wake_up: first + 5,
        }
    }
}

impl Instance {
    /// Every instance name.
    pub const ALL: [Instance; 4] = [
        Instance::Can0,
        Instance::Can1,
        Instance::Can2,
        Instance::Can3,
    ];

    /// Base address of the module's registers on `chip` (K20/K64/K66 memory maps,
    /// IMXRT1060RM "System Memory Map"); `None` if the chip lacks it.
    pub const fn base(self, chip: Chip) -> Option<usize> {
        match (self, chip.is_imxrt()) {
            (Instance::Can0, false) => Some(regs::CAN0_BASE),
            (Instance::Can1, false) => Some(regs::CAN1_BASE),
            (Instance::Can1, true) => Some(imxrt::CAN1_BASE),
            (Instance::Can2, true) => Some(imxrt::CAN2_BASE),
            (Instance::Can3, true) => Some(imxrt::CAN3_BASE),
            _ => None,
        }
    }

    /// The clock-gate register and bits of the module on `chip`: SIM_SCGC6.FLEXCAN0,
    /// SIM_SCGC3.FLEXCAN1 (Kinetis "SIM"); on the RT1062 both 2-bit gates of the
    /// module, its clock and its serial clock (`CCM_CCGR0[CG7, CG8]` for CAN1,
    /// `CCGR0[CG9, CG10]` for CAN2, `CCGR7[CG3, CG4]` for CAN3, IMXRT1060RM "CCM Clock
    /// Gating Register"). `None` if the chip lacks it.
    pub const fn clock_gate(self, chip: Chip) -> Option<(usize, u32)> {
        use crate::imxrt::ccm::{cg_on, CCM_CCGR0, CCM_CCGR7};
        match (self, chip.is_imxrt()) {
            (Instance::Can0, false) => Some((regs::sim::SIM_SCGC6, regs::sim::SCGC6_FLEXCAN0)),
            (Instance::Can1, false) => Some((regs::sim::SIM_SCGC3, regs::sim::SCGC3_FLEXCAN1)),
            (Instance::Can1, true) => Some((CCM_CCGR0, cg_on(7) | cg_on(8))),
            (Instance::Can2, true) => Some((CCM_CCGR0, cg_on(9) | cg_on(10))),
            (Instance::Can3, true) => Some((CCM_CCGR7, cg_on(3) | cg_on(4))),
            _ => None,
        }
    }

    /// The interrupt numbers of the module on `chip` (`None` if the chip lacks it). On
    /// the RT1062 every field is the module's one line ([`Irqs::is_single_line`]).
    pub const fn irqs(self, chip: Chip) -> Option<Irqs> {
        match (self, chip) {
            (Instance::Can0, Chip::Mk20dx256) => Some(Irqs::from(29)),
            (Instance::Can0, Chip::Mk64fx512 | Chip::Mk66fx1m0) => Some(Irqs::from(75)),
            (Instance::Can1, Chip::Mk66fx1m0) => Some(Irqs::from(94)),
            (Instance::Can1, Chip::Imxrt1062) => Some(Irqs::single(imxrt::CAN1_IRQ)),
            (Instance::Can2, Chip::Imxrt1062) => Some(Irqs::single(imxrt::CAN2_IRQ)),
            (Instance::Can3, Chip::Imxrt1062) => Some(Irqs::single(imxrt::CAN3_IRQ)),
            _ => None,
        }
    }
}

/// Which module on which board a controller drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Target {
    /// The board (pins, chip).
    pub board: Board,
    /// The FlexCAN module.
    pub instance: Instance,
}

impl Target {
    /// `instance` on `board`.
    pub const fn new(board: Board, instance: Instance) -> Self {
        Target { board, instance }
    }

    /// The interrupt numbers of this module (`None` if the board lacks it).
    pub const fn irqs(self) -> Option<Irqs> {
        if self.board.has(self.instance) {
            self.instance.irqs(self.board.chip())
        } else {
            None
        }
    }

    /// The module's register base (`None` if the board lacks it).
    pub const fn base(self) -> Option<usize> {
        if self.board.has(self.instance) {
            self.instance.base(self.board.chip())
        } else {
            None
        }
    }

    /// The module's clock gate (`None` if the board lacks it).
    pub const fn clock_gate(self) -> Option<(usize, u32)> {
        if self.board.has(self.instance) {
            self.instance.clock_gate(self.board.chip())
        } else {
            None
        }
    }
}

#[cfg(feature = "model")]
impl Target {
    /// The behavioural model's chip for this module (feature `model`): the board's
    /// chip, and on the RT1062 the instance (CAN3 differs from CAN1/CAN2). `Can0` on a
    /// Teensy 4.x, which has none, gives CAN1's.
    pub const fn model_chip(self) -> crate::model::Chip {
        use crate::model::{Chip as M, Rt1062Can};
        match (self.board.chip(), self.instance) {
            (Chip::Mk20dx256, _) => M::Mk20dx256,
            (Chip::Mk64fx512, _) => M::Mk64fx512,
            (Chip::Mk66fx1m0, _) => M::Mk66fx1m0,
            (Chip::Imxrt1062, Instance::Can2) => M::Imxrt1062(Rt1062Can::Can2),
            (Chip::Imxrt1062, Instance::Can3) => M::Imxrt1062(Rt1062Can::Can3),
            (Chip::Imxrt1062, _) => M::Imxrt1062(Rt1062Can::Can1),
        }
    }
}

#[cfg(any(
    feature = "teensy32",
    feature = "teensy35",
    feature = "teensy36",
    feature = "teensy40",
    feature = "teensy41"
))]
pub use tokens::*;

#[cfg(any(
    feature = "teensy32",
    feature = "teensy35",
    feature = "teensy36",
    feature = "teensy40",
    feature = "teensy41"
))]
mod tokens {
    use core::sync::atomic::{AtomicBool, Ordering};

    use super::{Instance, Target};
    use crate::board::Board;
    use crate::regs::FlexCanRegs;

    /// The register handles a token `T`'s `begin_in_place` and `begin_planned_in_place`
    /// can give its module, and its `end_split` takes back: [`FlexCanRegs`] (the base
    /// read at run time) for every token, and the module's fixed-base handle
    /// ([`crate::regs::FlexCanAt`], issue 21) for its own token only — `Can0At` for
    /// `Can0`, `Can1At` for the Teensy 3.6's `Can1` ([`crate::regs`]), and
    /// [`crate::imxrt::Can1At`], `Can2At`, `Can3At` for the Teensy 4.x tokens. The
    /// state's register type picks the handle, so a firmware names it once; another
    /// module's fixed base does not compile with a token. Sealed: the crate pairs each
    /// token with its module.
    ///
    /// The handle is made from the token's window ([`FlexCanRegs`] at the module's
    /// base, [`Target::base`]: the K20/K64/K66 memory maps, IMXRT1060RM "System Memory
    /// Map") by [`twocan_core::Mmio::into_fixed`],
    /// the one rule for a fixed base: the window's base must be the handle's, or the
    /// window comes back (and the token's `begin` gives
    /// [`twocan_core::Error::InvalidArgument`] with the token).
    #[cfg_attr(
        not(any(feature = "teensy40", feature = "teensy41")),
        doc = r#"
```
# fn main() {}
use twocan_flexcan::{regs::Can0At, Can0, TokenRegisters};
fn fixed<R: TokenRegisters<Can0>>() {}
const _: fn() = fixed::<Can0At>; // FlexCAN0's own base
```
FlexCAN1's base does not compile with FlexCAN0's token:
```compile_fail,E0277
# fn main() {}
use twocan_flexcan::{regs::Can1At, Can0, TokenRegisters};
fn fixed<R: TokenRegisters<Can0>>() {}
const _: fn() = fixed::<Can1At>;
```"#
    )]
    #[cfg_attr(
        any(feature = "teensy40", feature = "teensy41"),
        doc = r#"
```
# fn main() {}
use twocan_flexcan::{imxrt::Can1At, Can1, TokenRegisters};
fn fixed<R: TokenRegisters<Can1>>() {}
const _: fn() = fixed::<Can1At>; // CAN1's own base
```
CAN2's base does not compile with CAN1's token, nor the Kinetis FlexCAN1's:
```compile_fail,E0277
# fn main() {}
use twocan_flexcan::{imxrt::Can2At, Can1, TokenRegisters};
fn fixed<R: TokenRegisters<Can1>>() {}
const _: fn() = fixed::<Can2At>;
```
```compile_fail,E0277
# fn main() {}
use twocan_flexcan::{regs::Can1At, Can1, TokenRegisters};
fn fixed<R: TokenRegisters<Can1>>() {}
const _: fn() = fixed::<Can1At>;
```"#
    )]
    pub trait TokenRegisters<T>: twocan_core::Registers + Sized + sealed::Sealed<T> {
        /// `window`, the registers of `T`'s module at its reference-manual base, as this
        /// handle: the window itself, or its fixed-base form when the window's base is
        /// the handle's ([`twocan_core::Mmio::into_fixed`]); otherwise the window back.
        fn from_window(window: FlexCanRegs) -> Result<Self, FlexCanRegs>;
    }

    mod sealed {
        /// Only the crate pairs a token with its register handles.
        pub trait Sealed<T> {}
    }

    /// The Kinetis FlexCAN1 (Teensy 3.6) or the RT1062's CAN1 (Teensy 4.x) at its fixed
    /// base: the handle of the one `Can1` token of the board.
    #[cfg(any(feature = "teensy40", feature = "teensy41"))]
    #[allow(dead_code)] // a type of `Can1`'s `TokenRegisters` impl only
    type Can1Fixed = crate::imxrt::Can1At;
    #[cfg(not(any(feature = "teensy40", feature = "teensy41")))]
    #[allow(dead_code)] // a type of `Can1`'s `TokenRegisters` impl only
    type Can1Fixed = crate::regs::Can1At;

    /// One ownership token per module: `take` gives it the first time only (an atomic
    /// flag records the take), `returned` makes it again for `end`; its register
    /// handles ([`TokenRegisters`]): the run-time window and `$at`, its module's fixed
    /// base.
    macro_rules! token {
        ($(#[$m:meta])* $name:ident, $flag:ident, $instance:expr, $at:ty) => {
            impl sealed::Sealed<$name> for FlexCanRegs {}
            impl TokenRegisters<$name> for FlexCanRegs {
                #[inline(always)]
                fn from_window(window: FlexCanRegs) -> Result<Self, FlexCanRegs> {
                    Ok(window)
                }
            }
            impl sealed::Sealed<$name> for $at {}
            impl TokenRegisters<$name> for $at {
                #[inline(always)]
                fn from_window(window: FlexCanRegs) -> Result<Self, FlexCanRegs> {
                    window.into_fixed()
                }
            }

            static $flag: AtomicBool = AtomicBool::new(false);

            $(#[$m])*
            #[derive(Debug)]
            pub struct $name {
                _private: (),
            }

            impl $name {
                /// The token, the first time only.
                pub fn take() -> Option<Self> {
                    (!$flag.swap(true, Ordering::AcqRel)).then_some($name { _private: () })
                }

                /// The module this token owns (as a constant: [`Self::TARGET`]).
                pub const fn target(&self) -> Target {
                    Self::TARGET
                }

                /// The module this token owns, for `const` items (a `BeginPlan` made
                /// at compile time).
                pub const TARGET: Target = Target::new(Board::DEFAULT, $instance);

                /// The token again, for `end`: the controller it comes from was made
                /// from the one taken token (the flag stays set, so `take` still gives
                /// `None`).
                #[allow(dead_code)] // used by `end` on the target only
                pub(crate) const fn returned() -> Self {
                    $name { _private: () }
                }
            }
        };
    }

    #[cfg(all(
        any(feature = "teensy32", feature = "teensy35", feature = "teensy36"),
        not(any(feature = "teensy40", feature = "teensy41"))
    ))]
    token!(
        /// Ownership of FlexCAN0 on [`Board::DEFAULT`] (ACAN `ACAN::can0`, §6).
        Can0,
        CAN0_TAKEN,
        Instance::Can0,
        crate::regs::Can0At
    );

    #[cfg(any(feature = "teensy36", feature = "teensy40", feature = "teensy41"))]
    token!(
        /// Ownership of FlexCAN1 on the Teensy 3.6 (ACAN `ACAN::can1`, §6), or of CAN1
        /// on a Teensy 4.x (pins 22/23).
        Can1,
        CAN1_TAKEN,
        Instance::Can1,
        Can1Fixed
    );

    #[cfg(any(feature = "teensy40", feature = "teensy41"))]
    token!(
        /// Ownership of CAN2 on a Teensy 4.x (pins 1/0).
        Can2,
        CAN2_TAKEN,
        Instance::Can2,
        crate::imxrt::Can2At
    );

    #[cfg(any(feature = "teensy40", feature = "teensy41"))]
    token!(
        /// Ownership of CAN3 on a Teensy 4.x (pins 31/30), driven in classic CAN.
        Can3,
        CAN3_TAKEN,
        Instance::Can3,
        crate::imxrt::Can3At
    );

    #[cfg(test)]
    mod tests {
        #[allow(unused_imports)]
        use super::*;

        #[cfg(not(any(feature = "teensy40", feature = "teensy41")))]
        #[test]
        fn taken_once() {
            let first = Can0::take();
            assert!(first.is_some());
            assert!(Can0::take().is_none());
            assert_eq!(first.unwrap().target().instance, Instance::Can0);
        }

        /// The token's window (at its module's base) and one at `base`.
        fn windows(token: Target, base: usize) -> (FlexCanRegs, FlexCanRegs) {
            // SAFETY: never read or written here (device addresses on the host); the
            // handles only go through the base check.
            unsafe {
                (
                    FlexCanRegs::new(token.base().expect("the board's module")),
                    FlexCanRegs::new(base),
                )
            }
        }

        /// Every token's fixed handle is made from its own window only (the check of
        /// `Mmio::into_fixed`), and the run-time window passes as it is.
        fn fixed_only_from_its_own_window<T, R>(token: Target, other: usize)
        where
            R: TokenRegisters<T>,
            FlexCanRegs: TokenRegisters<T>,
        {
            let (own, foreign) = windows(token, other);
            let fixed = R::from_window(own).map_err(|w| w.base());
            assert!(fixed.is_ok(), "{token:?}: its own base");
            assert_eq!(core::mem::size_of::<R>(), 0);
            let back = R::from_window(foreign).map(|_| ()).unwrap_err();
            assert_eq!(back.base(), other, "another base: the window comes back");
            let (own, _) = windows(token, other);
            let window = <FlexCanRegs as TokenRegisters<T>>::from_window(own).unwrap();
            assert_eq!(Some(window.base()), token.base());
        }

        #[cfg(not(any(feature = "teensy40", feature = "teensy41")))]
        #[test]
        fn each_token_s_fixed_handle_is_at_its_module_s_base() {
            use crate::regs::{self, Can0At};
            fixed_only_from_its_own_window::<Can0, Can0At>(Can0::TARGET, regs::CAN1_BASE);
            #[cfg(feature = "teensy36")]
            fixed_only_from_its_own_window::<Can1, regs::Can1At>(Can1::TARGET, regs::CAN0_BASE);
        }

        #[cfg(any(feature = "teensy40", feature = "teensy41"))]
        #[test]
        fn each_token_s_fixed_handle_is_at_its_module_s_base() {
            use crate::imxrt::{Can1At, Can2At, Can3At, CAN1_BASE, CAN2_BASE, CAN3_BASE};
            fixed_only_from_its_own_window::<Can1, Can1At>(Can1::TARGET, CAN2_BASE);
            fixed_only_from_its_own_window::<Can2, Can2At>(Can2::TARGET, CAN3_BASE);
            fixed_only_from_its_own_window::<Can3, Can3At>(Can3::TARGET, CAN1_BASE);
            // The Kinetis FlexCAN1's base is no RT1062 module's.
            fixed_only_from_its_own_window::<Can1, Can1At>(Can1::TARGET, crate::regs::CAN1_BASE);
        }

        #[cfg(any(feature = "teensy40", feature = "teensy41"))]
        #[test]
        fn taken_once() {
            let first = Can3::take();
            assert!(first.is_some());
            assert!(Can3::take().is_none());
            let target = first.unwrap().target();
            assert_eq!(target.instance, Instance::Can3);
            assert_eq!(target.base(), Some(crate::imxrt::CAN3_BASE));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn irq_numbers() {
        assert_eq!(
            Target::new(Board::Teensy32, Instance::Can0)
                .irqs()
                .unwrap()
                .message,
            29
        );
        assert_eq!(
            Target::new(Board::Teensy35, Instance::Can0)
                .irqs()
                .unwrap()
                .message,
            75
        );
        let can1 = Target::new(Board::Teensy36, Instance::Can1).irqs().unwrap();
        assert_eq!((can1.message, can1.wake_up), (94, 99));
        assert!(Target::new(Board::Teensy35, Instance::Can1)
            .irqs()
            .is_none());
        let t41 = |i| Target::new(Board::Teensy41, i);
        assert_eq!(t41(Instance::Can1).irqs().unwrap().message, 36);
        assert_eq!(t41(Instance::Can2).irqs().unwrap().error, 37);
        let can3 = t41(Instance::Can3).irqs().unwrap();
        assert!(can3.is_single_line() && can3.bus_off == 154);
        assert!(!can1.is_single_line());
        assert!(t41(Instance::Can0).irqs().is_none());
        assert_eq!(t41(Instance::Can1).base(), Some(0x401D_0000));
        assert_eq!(t41(Instance::Can3).base(), Some(0x401D_8000));
        assert_eq!(
            Target::new(Board::Teensy36, Instance::Can1).base(),
            Some(0x400A_4000)
        );
        assert_eq!(
            t41(Instance::Can2).clock_gate(),
            Some((0x400F_C068, 0xF << 18))
        );
        assert_eq!(
            t41(Instance::Can3).clock_gate(),
            Some((0x400F_C084, 0xF << 6))
        );
    }
}
