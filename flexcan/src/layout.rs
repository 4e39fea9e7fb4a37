//! The message-buffer layout a controller is built for: a compile-time choice (a type
//! parameter of the options, [`crate::options::Full`]`<L>`, [`crate::options::Lean`]`<L>`,
//! and of [`crate::FlexCan`]), so that what differs between the Kinetis and the i.MX
//! RT1062 FlexCAN — the number of message buffers, the `IFLAG2`/`IMASK2` pair, the
//! largest Rx FIFO filter table — is data the compiler folds, not a run-time look-up.
//!
//! | layout | message buffers | `CTRL2[RFFN]` | ID filter table | transmit mailboxes | owned table |
//! |---|---|---|---|---|---|
//! | [`Kinetis`] (the default) | MB0–MB15 (`MCR[MAXMB]` = 15) | 0–3 (ACAN's four [`Configuration`]s) | up to 32 elements: 14 primary, 18 secondary | MB8–MB15, flags in `IFLAG1` | [`FilterTable`] |
//! | [`Imxrt1062`] | up to MB45 (`MCR[MAXMB]` = the data mailbox) | 0–0xF | up to 128 elements: 32 primary, 96 secondary | after the table, up to MB45, flags in `IFLAG1` or `IFLAG2` | [`LargeFilterTable`] |
//!
//! The [`Kinetis`] layout runs on every chip (the RT1062's modules too, in their first
//! 16 message buffers); [`Imxrt1062`] needs the RT1062's 64 message buffers for the
//! tables above RFFN 3 (IMXRT1060RM, FlexCAN chapter: CTRL2 field RFFN, table "Rx FIFO
//! filter: possible structures", `IMASK2`/`IFLAG2` for MB32–MB63, `MCR[MAXMB]`); on a
//! Kinetis part it accepts what [`Kinetis`] accepts ([`Chip::accepted_max_rffn`]).
//! With [`Kinetis`] every `IFLAG2` path of the driver is behind a `const` condition
//! that is false ([`Layout::IFLAG2`]), so a Teensy 3.x firmware carries none of it.
//!
//! ```
//! use twocan_flexcan::layout::{Imxrt1062, Kinetis, Layout};
//! use twocan_flexcan::{Chip, Configuration};
//! assert_eq!((Kinetis::MAX_RFFN, Kinetis::IFLAG2), (3, false));
//! assert_eq!((Imxrt1062::MAX_RFFN, Imxrt1062::IFLAG2), (0xF, true));
//! assert_eq!(Imxrt1062::MAX_RFFN, Chip::Imxrt1062.accepted_max_rffn());
//! assert!(Imxrt1062::accepts(Chip::Imxrt1062, Configuration::Filters32_96));
//! assert!(!Kinetis::accepts(Chip::Imxrt1062, Configuration::Filters32_96));
//! assert!(!Imxrt1062::accepts(Chip::Mk66fx1m0, Configuration::Filters16_24));
//! ```

use crate::board::Chip;
use crate::configuration::Configuration;
use crate::filters::{FilterTable, OwnedTable, LOOKUP_KEYS};

/// The owned filter table of the [`Imxrt1062`] layout: room for RFFN 0xF (128 elements,
/// 32 under individual masks, 96 under the global mask).
pub type LargeFilterTable = FilterTable<LOOKUP_KEYS, 128, 32, 96>;

/// What a controller's message-buffer layout fixes at compile time.
pub trait Layout: Send + Sync + 'static {
    /// The message buffers the layout may use (16 or 64).
    const MESSAGE_BUFFERS: usize;
    /// The largest `CTRL2[RFFN]` the driver accepts with this layout (on a chip that has
    /// the message buffers: [`Layout::max_rffn`]).
    const MAX_RFFN: u8;
    /// Whether transmit mailboxes may lie above MB31, served through `IFLAG2`/`IMASK2`
    /// (IMXRT1060RM, "Interrupt Masks 2 register (IMASK2)", "Interrupt Flags 2 register
    /// (IFLAG2)"). `false`: every `IFLAG2` path is dead code.
    const IFLAG2: bool;
    /// The table [`crate::options::Full`] keeps and `begin` compiles into.
    type Table: OwnedTable;

    /// The largest `CTRL2[RFFN]` accepted on `chip`: this layout's and the chip's
    /// ([`Chip::max_rffn`]), whichever is smaller — one rule for `begin`, `check`, the
    /// planner and the capabilities.
    #[inline(always)]
    fn max_rffn(chip: Chip) -> u8 {
        accepted_rffn(Self::MAX_RFFN, chip)
    }

    /// Whether `configuration` is accepted on `chip` with this layout.
    #[inline(always)]
    fn accepts(chip: Chip, configuration: Configuration) -> bool {
        configuration.rffn() <= Self::max_rffn(chip)
    }
}

/// The largest `CTRL2[RFFN]` a layout whose own largest is `layout_max` accepts on
/// `chip` ([`Layout::max_rffn`], usable in `const` code).
pub const fn accepted_rffn(layout_max: u8, chip: Chip) -> u8 {
    let chip_max = chip.accepted_max_rffn();
    if layout_max < chip_max {
        layout_max
    } else {
        chip_max
    }
}

/// ACAN's layout, MB0–MB15 (the default): every chip.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kinetis {}

impl Layout for Kinetis {
    const MESSAGE_BUFFERS: usize = crate::regs::NUM_MB;
    const MAX_RFFN: u8 = Configuration::Filters14_18.rffn();
    const IFLAG2: bool = false;
    type Table = FilterTable;
}

/// The i.MX RT1062's 64 message buffers: Rx FIFO tables up to RFFN 0xF, the transmit
/// mailboxes after them ([`Configuration::data_mailbox`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Imxrt1062 {}

impl Layout for Imxrt1062 {
    const MESSAGE_BUFFERS: usize = crate::imxrt::MESSAGE_BUFFERS;
    const MAX_RFFN: u8 = 0xF;
    const IFLAG2: bool = true;
    type Table = LargeFilterTable;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_hold_their_largest_table() {
        let largest = |max: u8| Configuration::from_rffn(max).unwrap();
        assert!(FilterTable::<LOOKUP_KEYS>::holds(largest(
            Kinetis::MAX_RFFN
        )));
        assert!(!FilterTable::<LOOKUP_KEYS>::holds(largest(
            Kinetis::MAX_RFFN + 1
        )));
        assert!(LargeFilterTable::holds(largest(Imxrt1062::MAX_RFFN)));
        for c in Configuration::EVERY {
            assert!(c.message_buffers_used() <= Imxrt1062::MESSAGE_BUFFERS);
            assert_eq!(
                Kinetis::accepts(Chip::Imxrt1062, c),
                Configuration::ALL.contains(&c)
            );
            assert!(Imxrt1062::accepts(Chip::Imxrt1062, c));
            assert_eq!(
                Imxrt1062::accepts(Chip::Mk66fx1m0, c),
                Configuration::ALL.contains(&c)
            );
        }
    }
}
