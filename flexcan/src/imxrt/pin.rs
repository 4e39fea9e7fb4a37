//! Typed pins of the Teensy 4.0 / 4.1 (features `teensy40`, `teensy41`): one type per
//! Teensy pin that carries a FlexCAN signal, implementing [`TxPin`] or [`RxPin`] for
//! its module. A pin of another module or signal does not compile. The boards have no
//! alternate pins, so the types only check the wiring the firmware states.
//!
//! | module | Tx | Rx |
//! |---|---|---|
//! | `Can1` | [`Pin22`] | [`Pin23`] |
//! | `Can2` | [`Pin1`] | [`Pin0`] |
//! | `Can3` | [`Pin31`] | [`Pin30`] |
//!
//! The pads behind the types come from [`Board::imx_pins`] of [`Board::DEFAULT`]; a
//! constant check per type makes the build fail if a type's name and the table's
//! Teensy pin number disagree.
//!
//! ```
//! use twocan_flexcan::pin::{settings_for, Pin22, Pin23};
//! use twocan_flexcan::{Can1, CanClock, Settings};
//! let s = settings_for::<Can1, _, _>(&Settings::with_clock(500_000, CanClock::IMXRT_24MHZ), Pin22, Pin23);
//! assert!(!s.use_alternate_tx_pin);
//! ```
//!
//! ```compile_fail,E0277
//! use twocan_flexcan::pin::{settings_for, Pin22, Pin0};
//! use twocan_flexcan::{Can1, Settings};
//! let _ = settings_for::<Can1, _, _>(&Settings::default(), Pin22, Pin0);
//! ```

use crate::board::Board;
use crate::imxrt::pads::ImxPin;
use crate::imxrt::ImxPins;
use crate::instance::{Can1, Can2, Can3, Instance};
use crate::settings::Settings;

mod sealed {
    pub trait Sealed {}
}

/// A Teensy 4 pin that carries the Tx signal of module `I`. Sealed.
pub trait TxPin<I>: sealed::Sealed {
    /// The pad and its IOMUXC registers.
    const PIN: ImxPin;
}

/// A Teensy 4 pin that carries the Rx signal of module `I`. Sealed.
pub trait RxPin<I>: sealed::Sealed {
    /// The pad and its IOMUXC registers.
    const PIN: ImxPin;
}

const fn row(instance: Instance) -> ImxPins {
    match Board::DEFAULT.imx_pins(instance) {
        Some(p) => p,
        None => panic!("the board has no such module"),
    }
}

macro_rules! can_pin {
    ($(#[$m:meta])* $name:ident = $n:literal, $role:ident<$inst:ident> = $pin:expr) => {
        $(#[$m])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
        pub struct $name;
        impl sealed::Sealed for $name {}
        impl $role<$inst> for $name {
            const PIN: ImxPin = $pin;
        }
        const _: () = assert!(<$name as $role<$inst>>::PIN.teensy_pin == $n);
    };
}

can_pin!(
    /// Pin 22: CAN1 Tx (`GPIO_AD_B1_08`).
    Pin22 = 22, TxPin<Can1> = row(Instance::Can1).tx
);
can_pin!(
    /// Pin 23: CAN1 Rx (`GPIO_AD_B1_09`).
    Pin23 = 23, RxPin<Can1> = row(Instance::Can1).rx
);
can_pin!(
    /// Pin 1: CAN2 Tx (`GPIO_AD_B0_02`).
    Pin1 = 1, TxPin<Can2> = row(Instance::Can2).tx
);
can_pin!(
    /// Pin 0: CAN2 Rx (`GPIO_AD_B0_03`).
    Pin0 = 0, RxPin<Can2> = row(Instance::Can2).rx
);
can_pin!(
    /// Pin 31: CAN3 Tx (`GPIO_EMC_36`).
    Pin31 = 31, TxPin<Can3> = row(Instance::Can3).tx
);
can_pin!(
    /// Pin 30: CAN3 Rx (`GPIO_EMC_37`).
    Pin30 = 30, RxPin<Can3> = row(Instance::Can3).rx
);

/// The settings with the typed pin choice applied: on the Teensy 4.x the default pins
/// (no alternates), so the settings come back with both alternate flags cleared.
/// A `const fn`, as the Kinetis one.
pub const fn settings_for<I, T: TxPin<I>, X: RxPin<I>>(
    settings: &Settings,
    tx: T,
    rx: X,
) -> Settings {
    // The pins are zero-sized markers: nothing to drop.
    core::mem::forget(tx);
    core::mem::forget(rx);
    let mut s = *settings;
    s.use_alternate_tx_pin = false;
    s.use_alternate_rx_pin = false;
    s
}

#[cfg(target_os = "none")]
mod firmware {
    use twocan_core::Filter;

    use super::*;
    use crate::begin_error::BeginError;
    use crate::controller::FlexCan;
    use crate::regs::FlexCanRegs;

    macro_rules! begin_on {
        ($token:ident) => {
            impl $token {
                /// `begin` with the typed pins of this module (the RT1062 layout,
                /// [`crate::layout::Imxrt1062`], as `begin`).
                pub fn begin_on<T: TxPin<$token>, X: RxPin<$token>>(
                    self,
                    tx: T,
                    rx: X,
                    settings: &Settings,
                    primary: &[Filter],
                    secondary: &[Filter],
                ) -> Result<FlexCan<FlexCanRegs, crate::layout::Imxrt1062>, (Self, BeginError)>
                {
                    self.begin(&settings_for(settings, tx, rx), primary, secondary)
                }
            }
        };
    }

    begin_on!(Can1);
    begin_on!(Can2);
    begin_on!(Can3);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typed_pins_follow_the_table() {
        assert_eq!(<Pin22 as TxPin<Can1>>::PIN.pad, "GPIO_AD_B1_08");
        assert_eq!(<Pin0 as RxPin<Can2>>::PIN.daisy.unwrap().1, 1);
        assert_eq!(<Pin30 as RxPin<Can3>>::PIN.alt, 9);
        let s = Settings {
            use_alternate_rx_pin: true,
            ..Settings::default()
        };
        assert!(!settings_for::<Can3, _, _>(&s, Pin31, Pin30).use_alternate_rx_pin);
    }
}
