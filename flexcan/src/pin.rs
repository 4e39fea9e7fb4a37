//! Typed pin choice for the board the cargo feature selects (ACAN §7 table 3): one type
//! per Teensy pin that carries a CAN signal on that board, implementing [`TxPin`] or
//! [`RxPin`] for the instance it belongs to. A pin the board does not have, or that
//! belongs to another instance or signal, does not compile.
//!
//! | board feature | FlexCAN0 Tx | FlexCAN0 Rx | FlexCAN1 Tx | FlexCAN1 Rx |
//! |---|---|---|---|---|
//! | `teensy32` | [`Pin3`], `Pin32` (alternate) | [`Pin4`], `Pin25` (alternate) | — | — |
//! | `teensy35` | [`Pin3`], `Pin29` (alternate) | [`Pin4`], `Pin30` (alternate) | — | — |
//! | `teensy36` | [`Pin3`], `Pin29` (alternate) | [`Pin4`], `Pin30` (alternate) | `Pin33` | `Pin34` |
//!
//! The port pins behind the types come from the runtime table [`Board::pins`] of
//! [`Board::DEFAULT`] (one source of truth); a constant check per type makes the build
//! fail if a type's name and the table's Teensy pin number ever disagree.
//!
//! ```ignore
//! use twocan_flexcan::pin::{Pin29, Pin4};
//! // Teensy 3.5/3.6: alternate Tx (pin 29), default Rx (pin 4).
//! let can = Can0::take().unwrap().begin_on(Pin29, Pin4, &settings, &[], &[])?;
//! ```
//!
//! Or, for [`crate::FlexCan::begin`] with a [`crate::Target`] (host, model):
//! [`settings_for`] turns the typed choice into the settings' `use_alternate_tx_pin`
//! and `use_alternate_rx_pin`.
#![cfg_attr(
    feature = "teensy36",
    doc = "\nOn the Teensy 3.6, the Teensy 3.2's alternate pin is not a choice:\n\n\
           ```compile_fail,E0432\n\
           use twocan_flexcan::pin::{settings_for, Pin32, Pin4};\n\
           use twocan_flexcan::{Can0, Settings};\n\
           let _ = settings_for::<Can0, _, _>(&Settings::new(500_000), Pin32, Pin4);\n\
           ```\n\n\
           nor are FlexCAN0's pins for FlexCAN1 (which has no alternate):\n\n\
           ```compile_fail,E0277\n\
           use twocan_flexcan::pin::{settings_for, Pin29, Pin34};\n\
           use twocan_flexcan::{Can1, Settings};\n\
           let _ = settings_for::<Can1, _, _>(&Settings::new(500_000), Pin29, Pin34);\n\
           ```\n\n\
           nor a Tx pin as the Rx pin:\n\n\
           ```compile_fail,E0277\n\
           use twocan_flexcan::pin::{settings_for, Pin3};\n\
           use twocan_flexcan::{Can0, Settings};\n\
           let _ = settings_for::<Can0, _, _>(&Settings::new(500_000), Pin3, Pin3);\n\
           ```\n\n\
           while these build:\n\n\
           ```\n\
           use twocan_flexcan::pin::{settings_for, Pin29, Pin33, Pin34, Pin4};\n\
           use twocan_flexcan::{Can0, Can1, Settings};\n\
           let s = settings_for::<Can0, _, _>(&Settings::new(500_000), Pin29, Pin4);\n\
           assert!(s.use_alternate_tx_pin && !s.use_alternate_rx_pin);\n\
           let s = settings_for::<Can1, _, _>(&Settings::new(500_000), Pin33, Pin34);\n\
           assert!(!s.use_alternate_tx_pin && !s.use_alternate_rx_pin);\n\
           ```\n"
)]
#![cfg_attr(
    all(
        feature = "teensy32",
        not(any(feature = "teensy35", feature = "teensy36"))
    ),
    doc = "\nOn the Teensy 3.2, the Teensy 3.5/3.6 alternate pin is not a choice, and\n\
           there is no FlexCAN1:\n\n\
           ```compile_fail,E0432\n\
           use twocan_flexcan::pin::{settings_for, Pin29, Pin4};\n\
           use twocan_flexcan::{Can0, Settings};\n\
           let _ = settings_for::<Can0, _, _>(&Settings::new(500_000), Pin29, Pin4);\n\
           ```\n\n\
           ```compile_fail,E0432\n\
           use twocan_flexcan::pin::{settings_for, Pin33, Pin34};\n\
           use twocan_flexcan::{Can1, Settings};\n\
           let _ = settings_for::<Can1, _, _>(&Settings::new(500_000), Pin33, Pin34);\n\
           ```\n\n\
           while this builds:\n\n\
           ```\n\
           use twocan_flexcan::pin::{settings_for, Pin25, Pin32};\n\
           use twocan_flexcan::{Can0, Settings};\n\
           let s = settings_for::<Can0, _, _>(&Settings::new(500_000), Pin32, Pin25);\n\
           assert!(s.use_alternate_tx_pin && s.use_alternate_rx_pin);\n\
           ```\n"
)]
#![cfg_attr(
    all(feature = "teensy35", not(feature = "teensy36")),
    doc = "\nOn the Teensy 3.5, the Teensy 3.2's alternate pin is not a choice, and\n\
           there is no FlexCAN1:\n\n\
           ```compile_fail,E0432\n\
           use twocan_flexcan::pin::{settings_for, Pin32, Pin4};\n\
           use twocan_flexcan::{Can0, Settings};\n\
           let _ = settings_for::<Can0, _, _>(&Settings::new(500_000), Pin32, Pin4);\n\
           ```\n\n\
           ```compile_fail,E0432\n\
           use twocan_flexcan::pin::{settings_for, Pin33, Pin34};\n\
           use twocan_flexcan::{Can1, Settings};\n\
           let _ = settings_for::<Can1, _, _>(&Settings::new(500_000), Pin33, Pin34);\n\
           ```\n\n\
           while this builds:\n\n\
           ```\n\
           use twocan_flexcan::pin::{settings_for, Pin29, Pin30};\n\
           use twocan_flexcan::{Can0, Settings};\n\
           let s = settings_for::<Can0, _, _>(&Settings::new(500_000), Pin29, Pin30);\n\
           assert!(s.use_alternate_tx_pin && s.use_alternate_rx_pin);\n\
           ```\n"
)]

use crate::board::{Board, InstancePins};
#[cfg(feature = "teensy36")]
use crate::instance::Can1;
use crate::instance::{Can0, Instance};
use crate::regs::pins::CanPin;
use crate::settings::Settings;

mod sealed {
    pub trait Sealed {}
}

/// A Teensy pin that carries the Tx signal of instance `I` (`Can0`, `Can1`) on this
/// board. Sealed: only this module's pin types implement it.
pub trait TxPin<I>: sealed::Sealed {
    /// The port pin and its mux alternative.
    const PIN: CanPin;
    /// Whether it is the alternate pin (ACAN `mUseAlternateTxPin`).
    const ALTERNATE: bool;
}

/// A Teensy pin that carries the Rx signal of instance `I` on this board. Sealed.
pub trait RxPin<I>: sealed::Sealed {
    /// The port pin and its mux alternative.
    const PIN: CanPin;
    /// Whether it is the alternate pin (ACAN `mUseAlternateRxPin`).
    const ALTERNATE: bool;
}

/// The table row of `instance` on the selected board.
const fn row(instance: Instance) -> InstancePins {
    match Board::DEFAULT.pins(instance) {
        Some(p) => p,
        None => panic!("the board has no such instance"),
    }
}

const fn some(pin: Option<CanPin>) -> CanPin {
    match pin {
        Some(p) => p,
        None => panic!("the board has no such alternate pin"),
    }
}

macro_rules! can_pin {
    ($(#[$m:meta])* $name:ident = $n:literal, $role:ident<$inst:ident> = $pin:expr, $alt:literal) => {
        $(#[$m])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
        pub struct $name;
        impl sealed::Sealed for $name {}
        impl $role<$inst> for $name {
            const PIN: CanPin = $pin;
            const ALTERNATE: bool = $alt;
        }
        const _: () = assert!(<$name as $role<$inst>>::PIN.teensy_pin == $n);
    };
}

can_pin!(
    /// Teensy pin 3: FlexCAN0 Tx, default (PTA12, ALT2).
    Pin3 = 3, TxPin<Can0> = row(Instance::Can0).tx, false
);
can_pin!(
    /// Teensy pin 4: FlexCAN0 Rx, default (PTA13, ALT2).
    Pin4 = 4, RxPin<Can0> = row(Instance::Can0).rx, false
);
#[cfg(all(
    feature = "teensy32",
    not(any(feature = "teensy35", feature = "teensy36"))
))]
can_pin!(
    /// Teensy 3.1/3.2 pin 32: FlexCAN0 Tx, alternate (PTB18, ALT2).
    Pin32 = 32, TxPin<Can0> = some(row(Instance::Can0).alternate_tx), true
);
#[cfg(all(
    feature = "teensy32",
    not(any(feature = "teensy35", feature = "teensy36"))
))]
can_pin!(
    /// Teensy 3.1/3.2 pin 25: FlexCAN0 Rx, alternate (PTB19, ALT2).
    Pin25 = 25, RxPin<Can0> = some(row(Instance::Can0).alternate_rx), true
);
#[cfg(any(feature = "teensy35", feature = "teensy36"))]
can_pin!(
    /// Teensy 3.5/3.6 pin 29: FlexCAN0 Tx, alternate (PTB18, ALT2).
    Pin29 = 29, TxPin<Can0> = some(row(Instance::Can0).alternate_tx), true
);
#[cfg(any(feature = "teensy35", feature = "teensy36"))]
can_pin!(
    /// Teensy 3.5/3.6 pin 30: FlexCAN0 Rx, alternate (PTB19, ALT2).
    Pin30 = 30, RxPin<Can0> = some(row(Instance::Can0).alternate_rx), true
);
#[cfg(feature = "teensy36")]
can_pin!(
    /// Teensy 3.6 pin 33: FlexCAN1 Tx (PTE24, ALT2; no alternate).
    Pin33 = 33, TxPin<Can1> = row(Instance::Can1).tx, false
);
#[cfg(feature = "teensy36")]
can_pin!(
    /// Teensy 3.6 pin 34: FlexCAN1 Rx (PTE25, ALT2; no alternate).
    Pin34 = 34, RxPin<Can1> = row(Instance::Can1).rx, false
);

/// `settings` with the pin choice of `tx` and `rx` (ACAN `mUseAlternateTxPin`,
/// `mUseAlternateRxPin`, §7): `begin` then muxes exactly those pins.
/// A `const fn`, so that a firmware's `const` settings carry the pin choice and no
/// copy of the settings is made at run time (`const { settings_for(&S, Pin3, Pin4) }`).
pub const fn settings_for<I, T: TxPin<I>, X: RxPin<I>>(
    settings: &Settings,
    tx: T,
    rx: X,
) -> Settings {
    // The pins are zero-sized markers: nothing to drop.
    core::mem::forget(tx);
    core::mem::forget(rx);
    let mut s = *settings;
    s.use_alternate_tx_pin = T::ALTERNATE;
    s.use_alternate_rx_pin = X::ALTERNATE;
    s
}

#[cfg(target_os = "none")]
mod firmware {
    use twocan_core::Filter;

    use super::*;
    use crate::begin_error::BeginError;
    use crate::controller::FlexCan;
    use crate::regs::FlexCanRegs;

    impl Can0 {
        /// [`Can0::begin`] on the typed pins `tx` and `rx` (their choice replaces the
        /// settings' `use_alternate_tx_pin` / `use_alternate_rx_pin`).
        pub fn begin_on<T: TxPin<Can0>, X: RxPin<Can0>>(
            self,
            tx: T,
            rx: X,
            settings: &Settings,
            primary: &[Filter],
            secondary: &[Filter],
        ) -> Result<FlexCan<FlexCanRegs>, (Self, BeginError)> {
            self.begin(&settings_for(settings, tx, rx), primary, secondary)
        }
    }

    #[cfg(feature = "teensy36")]
    impl Can1 {
        /// [`Can1::begin`] on the typed pins (FlexCAN1 has [`Pin33`] and [`Pin34`]
        /// only).
        pub fn begin_on<T: TxPin<Can1>, X: RxPin<Can1>>(
            self,
            tx: T,
            rx: X,
            settings: &Settings,
            primary: &[Filter],
            secondary: &[Filter],
        ) -> Result<FlexCan<FlexCanRegs>, (Self, BeginError)> {
            self.begin(&settings_for(settings, tx, rx), primary, secondary)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::system::choose_pins;

    /// The typed choice picks the same port pin as the runtime table and `begin`.
    fn picks<T: TxPin<Can0>, X: RxPin<Can0>>(tx: T, rx: X) -> (u8, u8) {
        let s = settings_for(&Settings::new(500_000), tx, rx);
        let (t, r) = choose_pins(
            row(Instance::Can0),
            s.use_alternate_tx_pin,
            s.use_alternate_rx_pin,
        )
        .unwrap();
        assert_eq!((t, r), (T::PIN, X::PIN));
        (t.teensy_pin, r.teensy_pin)
    }

    #[test]
    fn typed_pins_follow_the_table() {
        assert_eq!(picks(Pin3, Pin4), (3, 4));
        #[cfg(all(
            feature = "teensy32",
            not(any(feature = "teensy35", feature = "teensy36"))
        ))]
        assert_eq!(picks(Pin32, Pin25), (32, 25));
        #[cfg(any(feature = "teensy35", feature = "teensy36"))]
        {
            assert_eq!(picks(Pin29, Pin4), (29, 4));
            assert_eq!(picks(Pin3, Pin30), (3, 30));
        }
        #[cfg(feature = "teensy36")]
        {
            let s = settings_for::<Can1, _, _>(&Settings::new(500_000), Pin33, Pin34);
            let (t, r) = choose_pins(
                row(Instance::Can1),
                s.use_alternate_tx_pin,
                s.use_alternate_rx_pin,
            )
            .unwrap();
            assert_eq!((t.teensy_pin, r.teensy_pin), (33, 34));
        }
    }
}
