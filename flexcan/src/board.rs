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

use crate::imxrt::pads::{self, ImxPins};
use crate::instance::Instance;
use crate::regs::pins::{self, CanPin};

/// A Teensy board with FlexCAN.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Board {
    /// Teensy 3.1 or 3.2 (MK20DX256).
    Teensy32,
    /// Teensy 3.5 (MK64FX512).
    Teensy35,
    /// Teensy 3.6 (MK66FX1M0).
    Teensy36,
    /// Teensy 4.0 (i.MX RT1062): CAN1, CAN2, CAN3 (pins 30/31 on the underside).
    Teensy40,
    /// Teensy 4.1 (i.MX RT1062): CAN1, CAN2, CAN3.
    Teensy41,
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
    /// i.MX RT1062 (Cortex-M7, 600 MHz): three FlexCAN modules of 64 message buffers,
    /// one interrupt line each, clocked by the CCM's CAN clock root.
    Imxrt1062,
}

impl Chip {
    /// Whether the chip is an i.MX RT (CCM, IOMUXC) rather than a Kinetis (SIM, PORT).
    pub const fn is_imxrt(self) -> bool {
        matches!(self, Chip::Imxrt1062)
    }

    /// Message buffers per FlexCAN module (Kinetis: 16; IMXRT1060RM: 64).
    pub const fn message_buffers(self) -> usize {
        match self {
            Chip::Mk20dx256 | Chip::Mk64fx512 | Chip::Mk66fx1m0 => crate::regs::NUM_MB,
            Chip::Imxrt1062 => crate::imxrt::MESSAGE_BUFFERS,
        }
    }

    /// The largest `CTRL2[RFFN]` whose Rx FIFO and ID filter table (MB0 to
    /// MB`5 + 2 × (RFFN + 1)`, reference manuals' table "Rx FIFO filter: possible
    /// structures") leave the chip's message buffers room for a data mailbox and a
    /// remote-frame mailbox: 3 on the Kinetis parts (ACAN's 14/18: MB14 remote, MB15
    /// data), 0xF on the RT1062 (IMXRT1060RM, FlexCAN chapter, CTRL2 field RFFN: the
    /// table up to MB37, MB38–MB63 left; the RT1062 layout's ERR005829 reserved mailbox is
    /// MB38 and its transmit mailboxes MB39–MB46, [`crate::Configuration::data_mailbox_in`]).
    pub const fn max_rffn(self) -> u8 {
        let mut r: u8 = 15;
        while r > 0 && crate::regs::rx_fifo_occupied_mbs(r as u32) + 2 > self.message_buffers() {
            r -= 1;
        }
        r
    }

    /// The ID filter table elements at [`Chip::max_rffn`]: 8 × (RFFN + 1), 32 or 128.
    pub const fn max_table_elements(self) -> usize {
        crate::regs::rx_fifo_filter_count(self.max_rffn() as u32)
    }

    /// The table elements under individual masks (`RXIMRn`: ACAN's primary filters) at
    /// [`Chip::max_rffn`]: one per message buffer the FIFO and its table occupy, at most
    /// 32 (the manuals' table: "elements 0–31" from RFFN = 0xC on): 14 or 32.
    pub const fn max_primary_filters(self) -> usize {
        let occupied = crate::regs::rx_fifo_occupied_mbs(self.max_rffn() as u32);
        if occupied < 32 {
            occupied
        } else {
            32
        }
    }

    /// The table elements under the global mask `RXFGMASK` (ACAN's secondary filters)
    /// at [`Chip::max_rffn`]: 18 or 96.
    pub const fn max_secondary_filters(self) -> usize {
        self.max_table_elements() - self.max_primary_filters()
    }

    /// The largest `CTRL2[RFFN]` the driver accepts on this chip: [`Chip::max_rffn`],
    /// 3 on the Kinetis parts (ACAN's four configurations, [`crate::Configuration::ALL`],
    /// in MB0–MB15) and 0xF on the RT1062 (IMXRT1060RM, FlexCAN chapter, CTRL2 field
    /// RFFN, table "Rx FIFO filter: possible structures": the table up to MB37, the
    /// transmit mailboxes after it up to MB46, served through `IMASK2`/`IFLAG2` above
    /// MB31, `MCR[MAXMB]` = the data mailbox). A controller accepts the smaller of this
    /// and its layout's limit ([`crate::layout::Layout::max_rffn`]: 3 with the default
    /// [`crate::layout::Kinetis`], 0xF with [`crate::layout::Imxrt1062`]); `begin`,
    /// `check`, the planner and the capabilities apply that one rule.
    pub const fn accepted_max_rffn(self) -> u8 {
        self.max_rffn()
    }
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
    pub const ALL: [Board; 5] = [
        Board::Teensy32,
        Board::Teensy35,
        Board::Teensy36,
        Board::Teensy40,
        Board::Teensy41,
    ];
    /// The Teensy 3.x boards (Kinetis).
    pub const KINETIS: [Board; 3] = [Board::Teensy32, Board::Teensy35, Board::Teensy36];
    /// The Teensy 4.x boards (i.MX RT1062).
    pub const IMXRT: [Board; 2] = [Board::Teensy40, Board::Teensy41];

    /// The board the cargo features select. Precedence when several are enabled:
    /// `teensy41`, `teensy40`, `teensy36`, `teensy35`, then `teensy32` (not an error).
    #[cfg(feature = "teensy41")]
    pub const DEFAULT: Board = Board::Teensy41;
    /// The board the cargo features select.
    #[cfg(all(feature = "teensy40", not(feature = "teensy41")))]
    pub const DEFAULT: Board = Board::Teensy40;
    /// The board the cargo features select.
    #[cfg(all(
        feature = "teensy36",
        not(any(feature = "teensy40", feature = "teensy41"))
    ))]
    pub const DEFAULT: Board = Board::Teensy36;
    /// The board the cargo features select.
    #[cfg(all(
        feature = "teensy35",
        not(any(feature = "teensy36", feature = "teensy40", feature = "teensy41"))
    ))]
    pub const DEFAULT: Board = Board::Teensy35;
    /// The board the cargo features select.
    #[cfg(all(
        feature = "teensy32",
        not(any(
            feature = "teensy35",
            feature = "teensy36",
            feature = "teensy40",
            feature = "teensy41"
        ))
    ))]
    pub const DEFAULT: Board = Board::Teensy32;

    /// The board's microcontroller.
    pub const fn chip(self) -> Chip {
        match self {
            Board::Teensy32 => Chip::Mk20dx256,
            Board::Teensy35 => Chip::Mk64fx512,
            Board::Teensy36 => Chip::Mk66fx1m0,
            Board::Teensy40 | Board::Teensy41 => Chip::Imxrt1062,
        }
    }

    /// Whether the board has `instance` (ACAN §6 table 2: `can1` on the Teensy 3.6 only
    /// among the 3.x; the Teensy 4.x have CAN1, CAN2 and CAN3, no `Can0`).
    pub const fn has(self, instance: Instance) -> bool {
        match (self, instance) {
            (Board::Teensy40 | Board::Teensy41, Instance::Can0) => false,
            (Board::Teensy40 | Board::Teensy41, _) => true,
            (_, Instance::Can0) => true,
            (Board::Teensy36, Instance::Can1) => true,
            _ => false,
        }
    }

    /// The pins of `instance` on a Teensy 4.x ([`crate::imxrt::pads`]); `None` on the
    /// other boards and for `Can0`.
    pub const fn imx_pins(self, instance: Instance) -> Option<ImxPins> {
        match (self, instance) {
            (Board::Teensy40 | Board::Teensy41, Instance::Can1) => Some(pads::CAN1),
            (Board::Teensy40 | Board::Teensy41, Instance::Can2) => Some(pads::CAN2),
            (Board::Teensy40 | Board::Teensy41, Instance::Can3) => Some(pads::CAN3),
            _ => None,
        }
    }

    /// The pins of `instance` on a Teensy 3.x (ACAN §7 table 3); `None` if the board
    /// does not have it, and on the Teensy 4.x (see [`Board::imx_pins`]).
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
            _ => None,
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
        for b in Board::KINETIS {
            assert_eq!(b.has(Instance::Can1), b.pins(Instance::Can1).is_some());
        }
        for b in Board::ALL {
            for i in Instance::ALL {
                let pins = b.pins(i).is_some() || b.imx_pins(i).is_some();
                assert_eq!(b.has(i), pins, "{b:?} {i:?}");
            }
        }
        let t41 = |i| {
            let p = Board::Teensy41.imx_pins(i).unwrap();
            (p.tx.teensy_pin, p.rx.teensy_pin)
        };
        assert_eq!(
            [
                t41(Instance::Can1),
                t41(Instance::Can2),
                t41(Instance::Can3)
            ],
            [(22, 23), (1, 0), (31, 30)]
        );
        assert_eq!(Board::Teensy40.chip(), Chip::Imxrt1062);
        assert_eq!(Chip::Imxrt1062.message_buffers(), 64);
        assert_eq!(Chip::Mk66fx1m0.message_buffers(), 16);
    }

    #[test]
    fn rx_fifo_sizes_per_chip() {
        // (max RFFN, elements, primary, secondary, accepted RFFN)
        assert_eq!(
            (
                Chip::Mk66fx1m0.max_rffn(),
                Chip::Mk66fx1m0.max_table_elements(),
                Chip::Mk66fx1m0.max_primary_filters(),
                Chip::Mk66fx1m0.max_secondary_filters(),
                Chip::Mk66fx1m0.accepted_max_rffn()
            ),
            (3, 32, 14, 18, 3)
        );
        assert_eq!(
            (
                Chip::Imxrt1062.max_rffn(),
                Chip::Imxrt1062.max_table_elements(),
                Chip::Imxrt1062.max_primary_filters(),
                Chip::Imxrt1062.max_secondary_filters(),
                Chip::Imxrt1062.accepted_max_rffn()
            ),
            (15, 128, 32, 96, 15)
        );
        for chip in [
            Chip::Mk20dx256,
            Chip::Mk64fx512,
            Chip::Mk66fx1m0,
            Chip::Imxrt1062,
        ] {
            // What is accepted is what the chip's message buffers allow, and the
            // largest configuration accepted has the chip's largest table.
            assert_eq!(chip.accepted_max_rffn(), chip.max_rffn());
            let c = crate::Configuration::from_rffn(chip.accepted_max_rffn()).unwrap();
            assert_eq!(c.table_elements(), chip.max_table_elements());
            assert_eq!(c.primary_filter_capacity(), chip.max_primary_filters());
            assert!(c.message_buffers_used() <= chip.message_buffers());
        }
    }
}
