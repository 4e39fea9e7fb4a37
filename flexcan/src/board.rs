//! Board facts: which FlexCAN instances a Teensy has, on which pins, on which chip
//! (ACAN §6 table 2, §7 table 3).
//!
//! The board is a runtime value ([`Board`]), so the host tests check every board in
//! one build; the cargo features `teensy32` (Teensy 3.1 and 3.2), `teensy35` and
//! `teensy36` choose `Board::DEFAULT` for firmware. With several board features at
//! once (as in an `--all-features` build, or by feature unification) the last in that
//! list wins, silently: `teensy36` over `teensy35` over `teensy32` (see the crate
//! documentation, "Board features"). This is deliberately not a compile error, so that
//! `--all-features` builds keep working.
//!
//! Pin numbers and port pins come from [`crate::regs::pins`]. With a board feature,
//! `crate::pin` gives each pin of the selected board's row a type (ACAN's alternate-pin
//! choice checked at compile time), derived from [`Board::pins`].

use crate::instance::Instance;
use crate::regs::pins::{self, CanPin};

/// A Teensy 3.x board.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Board {
    /// Teensy 3.1 or 3.2 (MK20DX256).
    Teensy32,
    /// Teensy 3.5 (MK64FX512).
    Teensy35,
    /// Teensy 3.6 (MK66FX1M0).
    Teensy36,
}

/// The microcontroller of a board.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Chip {
    /// Kinetis K20, MK20DX256VLH7 (72 MHz).
    Mk20dx256,
    /// Kinetis K64, MK64FX512VMD12 (120 MHz).
    Mk64fx512,
    /// Kinetis K66, MK66FX1M0VMD18 (180 MHz).
    Mk66fx1m0,
}

/// The Tx and Rx pins of one instance, default and alternate (ACAN §7 table 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct InstancePins {
    /// Default Tx pin.
    pub tx: CanPin,
    /// Default Rx pin.
    pub rx: CanPin,
    /// Alternate Tx pin, if the board has one.
    pub alternate_tx: Option<CanPin>,
    /// Alternate Rx pin, if the board has one.
    pub alternate_rx: Option<CanPin>,
}

impl Board {
    /// Every board.
    pub const ALL: [Board; 3] = [Board::Teensy32, Board::Teensy35, Board::Teensy36];

    /// The board the cargo features select. Precedence when several are enabled:
    /// `teensy36`, then `teensy35`, then `teensy32` (not an error).
    #[cfg(feature = "teensy36")]
    pub const DEFAULT: Board = Board::Teensy36;
    /// The board the cargo features select.
    #[cfg(all(feature = "teensy35", not(feature = "teensy36")))]
    pub const DEFAULT: Board = Board::Teensy35;
    /// The board the cargo features select.
    #[cfg(all(
        feature = "teensy32",
        not(any(feature = "teensy35", feature = "teensy36"))
    ))]
    pub const DEFAULT: Board = Board::Teensy32;

    /// The board's microcontroller.
    pub const fn chip(self) -> Chip {
        match self {
            Board::Teensy32 => Chip::Mk20dx256,
            Board::Teensy35 => Chip::Mk64fx512,
            Board::Teensy36 => Chip::Mk66fx1m0,
        }
    }

    /// Whether the board has `instance` (ACAN §6 table 2: `can1` on the Teensy 3.6 only).
    pub const fn has(self, instance: Instance) -> bool {
        match instance {
            Instance::Can0 => true,
            Instance::Can1 => matches!(self, Board::Teensy36),
        }
    }

    /// The pins of `instance` on this board (ACAN §7 table 3); `None` if the board
    /// does not have it.
    pub const fn pins(self, instance: Instance) -> Option<InstancePins> {
        match (self, instance) {
            (Board::Teensy32, Instance::Can0) => Some(InstancePins {
                tx: pins::TEENSY31_CAN0_TX,
                rx: pins::TEENSY31_CAN0_RX,
                alternate_tx: Some(pins::TEENSY31_CAN0_TX_ALT),
                alternate_rx: Some(pins::TEENSY31_CAN0_RX_ALT),
            }),
            (Board::Teensy35 | Board::Teensy36, Instance::Can0) => Some(InstancePins {
                tx: pins::TEENSY35_CAN0_TX,
                rx: pins::TEENSY35_CAN0_RX,
                alternate_tx: Some(pins::TEENSY35_CAN0_TX_ALT),
                alternate_rx: Some(pins::TEENSY35_CAN0_RX_ALT),
            }),
            (Board::Teensy36, Instance::Can1) => Some(InstancePins {
                tx: pins::TEENSY36_CAN1_TX,
                rx: pins::TEENSY36_CAN1_RX,
                alternate_tx: None,
                alternate_rx: None,
            }),
            (Board::Teensy32 | Board::Teensy35, Instance::Can1) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn acan_table_3() {
        let teensy = |b: Board, i| {
            let p = b.pins(i).unwrap();
            (
                p.tx.teensy_pin,
                p.alternate_tx.map(|p| p.teensy_pin),
                p.rx.teensy_pin,
                p.alternate_rx.map(|p| p.teensy_pin),
            )
        };
        assert_eq!(
            teensy(Board::Teensy32, Instance::Can0),
            (3, Some(32), 4, Some(25))
        );
        assert_eq!(
            teensy(Board::Teensy35, Instance::Can0),
            (3, Some(29), 4, Some(30))
        );
        assert_eq!(
            teensy(Board::Teensy36, Instance::Can0),
            (3, Some(29), 4, Some(30))
        );
        assert_eq!(
            teensy(Board::Teensy36, Instance::Can1),
            (33, None, 34, None)
        );
        assert!(Board::Teensy32.pins(Instance::Can1).is_none());
        assert!(Board::Teensy35.pins(Instance::Can1).is_none());
        for b in Board::ALL {
            assert_eq!(b.has(Instance::Can1), b.pins(Instance::Can1).is_some());
        }
    }
}
