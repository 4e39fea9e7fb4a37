//! The message-buffer layout a controller is built for: a compile-time choice (a type
//! parameter of the options, [`crate::options::Full`]`<L>`, [`crate::options::Lean`]`<L>`,
//! and of [`crate::FlexCan`]), so that what differs between the Kinetis and the i.MX
//! RT1062 FlexCAN — the number of message buffers, the `IFLAG2`/`IMASK2` pair, the
//! largest Rx FIFO filter table — is data the compiler folds, not a run-time look-up.
//!
//! | layout | message buffers | `CTRL2[RFFN]` | ID filter table | transmit mailboxes | owned table |
//! |---|---|---|---|---|---|
//! | [`Kinetis`] (the default) | MB0–MB15 (`MCR[MAXMB]` = 15) | 0–3 (ACAN's four [`Configuration`]s) | up to 32 elements: 14 primary, 18 secondary | MB8–MB15, flags in `IFLAG1` | [`FilterTable`] |
//! | [`Imxrt1062`] | up to MB46 (`MCR[MAXMB]` = the data mailbox) | 0–0xF | up to 128 elements: 32 primary, 96 secondary | after the table and the ERR005829 reserved mailbox, up to MB46, flags in `IFLAG1` or `IFLAG2` | [`LargeFilterTable`] |
//!
//! One layout per chip: [`Kinetis`] on the Kinetis parts only (on an RT1062 module
//! `begin` refuses it with `ConfigErrors::LAYOUT_NOT_FOR_CHIP`: it would run without the
//! ERR005829 workaround); [`Imxrt1062`] needs the RT1062's 64 message buffers
//! (IMXRT1060RM, FlexCAN chapter: CTRL2 field RFFN, table "Rx FIFO filter: possible
//! structures", `IMASK2`/`IFLAG2` for MB32–MB63, `MCR[MAXMB]`): on a 16-buffer Kinetis
//! part it takes no configuration ([`Layout::accepts`], `CONFIGURATION_NOT_ON_CHIP`),
//! since its data mailbox is MB16 at least.
//! With [`Kinetis`] every `IFLAG2` path of the driver is behind a `const` condition
//! that is false ([`Layout::IFLAG2`]), so a Teensy 3.x firmware carries none of it.
//!
//! Erratum ERR005829 (i.MX RT1060 chip errata: "FlexCAN does not transmit a message
//! that is enabled to be transmitted in a specific moment during the arbitration
//! process"; a frame activated at that moment waits for a later arbitration, which an
//! idle bus may never start) is worked around with [`Imxrt1062`] only
//! ([`Layout::E5829`]), as the errata describe: the first valid mailbox — the first
//! message buffer after the Rx FIFO and its ID filter table,
//! [`Configuration::reserved_mailbox`], MB8 at RFFN 0 — is a transmit mailbox kept
//! INACTIVE (code 0b1000), within `MCR[MAXMB]`, never loaded, its interrupt masked;
//! after each control/status write that activates a transmit mailbox the driver writes
//! INACTIVE into that mailbox's control/status word twice. The transmit mailboxes move
//! up by one and keep their number ([`Configuration::first_remote_mailbox_in`]: ACAN's
//! four configurations send data from MB16, 14/18 from RFFN 0xB … 8 from MB32 on, so
//! that they never straddle MB31/MB32). [`Kinetis`] is unchanged (the constant is
//! false: no reserved mailbox, no extra write).
//!
//! | RFFN | table | reserved | remote-frame mailboxes | data mailbox (`MAXMB`) |
//! |---|---|---|---|---|
//! | 0 | MB6–MB7 | MB8 | MB9–MB15 (7) | MB16 |
//! | 3 | MB6–MB13 | MB14 | MB15 (1) | MB16 |
//! | 4 | MB6–MB15 | MB16 | MB17–MB23 (7) | MB24 |
//! | 7 | MB6–MB21 | MB22 | MB23–MB29 (7) | MB30 |
//! | 8 | MB6–MB23 | MB24 (MB25–MB31 INACTIVE) | MB32–MB38 (7) | MB39 |
//! | 0xB | MB6–MB29 | MB30 (MB31 INACTIVE) | MB32 (1) | MB33 |
//! | 0xC | MB6–MB31 | MB32 | MB33–MB39 (7) | MB40 |
//! | 0xF | MB6–MB37 | MB38 | MB39–MB45 (7) | MB46 |
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
//! // ERR005829: the RT1062 layout reserves the first valid mailbox, Kinetis does not.
//! assert_eq!((Kinetis::E5829, Imxrt1062::E5829), (false, true));
//! let c = Configuration::Filters8_0;
//! assert_eq!(Imxrt1062::reserved_mailbox(c), Some(8));
//! assert_eq!((Imxrt1062::first_remote_mailbox(c), Imxrt1062::data_mailbox(c)), (9, 16));
//! assert_eq!(Kinetis::reserved_mailbox(c), None);
//! assert_eq!((Kinetis::first_remote_mailbox(c), Kinetis::data_mailbox(c)), (8, 15));
//! // Its data mailbox beyond MB15: no configuration on a 16-buffer module.
//! assert!(!Imxrt1062::accepts(Chip::Mk66fx1m0, c));
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
    /// Whether the layout applies the workaround of erratum ERR005829 (i.MX RT1060 chip
    /// errata, ERR005829: "FlexCAN does not transmit a message that is enabled to be
    /// transmitted in a specific moment during the arbitration process"): the first
    /// valid mailbox after the Rx FIFO area ([`Configuration::reserved_mailbox`]) is a
    /// transmit mailbox kept INACTIVE, never loaded, its interrupt masked, within
    /// `MCR[MAXMB]`; the transmit mailboxes follow it
    /// ([`Configuration::first_remote_mailbox_in`]); after each control/status write
    /// that activates a transmit mailbox the driver writes INACTIVE into the reserved
    /// mailbox's control/status word twice. `false`: none of it is compiled.
    const E5829: bool;
    /// The table [`crate::options::Full`] keeps and `begin` compiles into.
    type Table: OwnedTable;
    /// The chip-level plan a controller of this layout keeps for `end`
    /// ([`crate::system::LayoutSystem`]): [`crate::PortPlan`] for [`Kinetis`],
    /// [`crate::imxrt::ImxrtPlan`] for [`Imxrt1062`] (only its own chip family's).
    type System: crate::system::LayoutSystem;

    /// The largest `CTRL2[RFFN]` accepted on `chip`: this layout's and the chip's
    /// ([`Chip::max_rffn`]), whichever is smaller — one rule for `begin`, `check`, the
    /// planner and the capabilities.
    #[inline(always)]
    fn max_rffn(chip: Chip) -> u8 {
        accepted_rffn(Self::MAX_RFFN, chip)
    }

    /// Whether `configuration` is accepted on `chip` with this layout: its RFFN at most
    /// [`Layout::max_rffn`] and its message buffers ([`Layout::message_buffers_used`])
    /// on the chip — one rule with `begin` and `check`.
    #[inline(always)]
    fn accepts(chip: Chip, configuration: Configuration) -> bool {
        layout_accepts(
            Self::MAX_RFFN,
            Self::IFLAG2,
            Self::E5829,
            chip,
            configuration,
        )
    }

    /// The first remote-frame mailbox of `configuration` with this layout
    /// ([`Configuration::first_remote_mailbox_in`]).
    #[inline(always)]
    fn first_remote_mailbox(configuration: Configuration) -> u8 {
        configuration.first_remote_mailbox_in(Self::E5829)
    }

    /// The data mailbox of `configuration` with this layout, `MCR[MAXMB]`
    /// ([`Configuration::data_mailbox_in`]).
    #[inline(always)]
    fn data_mailbox(configuration: Configuration) -> u8 {
        configuration.data_mailbox_in(Self::E5829)
    }

    /// The mailbox the ERR005829 workaround keeps INACTIVE ([`Layout::E5829`]), `None`
    /// for a layout without it.
    #[inline(always)]
    fn reserved_mailbox(configuration: Configuration) -> Option<u8> {
        Self::E5829.then(|| configuration.reserved_mailbox())
    }

    /// The message buffers `configuration` takes into matching and arbitration with
    /// this layout (`MCR[MAXMB]` + 1, [`Configuration::message_buffers_used_in`]).
    #[inline(always)]
    fn message_buffers_used(configuration: Configuration) -> usize {
        configuration.message_buffers_used_in(Self::E5829)
    }
}

/// [`Layout::accepts`] from the layout's constants (usable in `const` code): the RFFN at
/// most the layout's and the chip's ([`accepted_rffn`]), and, for a layout of more than
/// 16 buffers, every buffer the configuration uses on the chip (the RT1062 layout's
/// ERR005829 reservation moves the data mailbox of ACAN's four configurations to MB16,
/// so that layout takes no configuration on a 16-buffer Kinetis module).
pub const fn layout_accepts(
    layout_max: u8,
    iflag2: bool,
    e5829: bool,
    chip: Chip,
    configuration: Configuration,
) -> bool {
    configuration.rffn() <= accepted_rffn(layout_max, chip)
        && (!iflag2 || configuration.message_buffers_used_in(e5829) <= chip.message_buffers())
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

/// The layout of the board the crate is built for: [`Imxrt1062`] with the feature
/// `teensy40` or `teensy41` (so that a Teensy 4 firmware gets the RT1062's tables and
/// the ERR005829 workaround, [`Layout::E5829`], without naming a layout), [`Kinetis`]
/// otherwise (the Teensy 3.x, and the host without a board feature). The precedence of
/// the board features is the crate's ("Board features"): a Teensy 4 feature wins. What
/// the one calls (`acan`, feature `rt`), `rt::AcanState` and the Teensy 4 tokens' `begin`
/// use; `Full`, `FullInSlot`, `Lean` and `FlexCan` keep [`Kinetis`] as their default.
#[cfg(any(feature = "teensy40", feature = "teensy41"))]
pub type BoardLayout = Imxrt1062;
/// The layout of the board the crate is built for: [`Imxrt1062`] with the feature
/// `teensy40` or `teensy41` (so that a Teensy 4 firmware gets the RT1062's tables and
/// the ERR005829 workaround, [`Layout::E5829`], without naming a layout), [`Kinetis`]
/// otherwise (the Teensy 3.x, and the host without a board feature). The precedence of
/// the board features is the crate's ("Board features"): a Teensy 4 feature wins. What
/// the one calls (`acan`, feature `rt`), `rt::AcanState` and the Teensy 4 tokens' `begin`
/// use; `Full`, `FullInSlot`, `Lean` and `FlexCan` keep [`Kinetis`] as their default.
#[cfg(not(any(feature = "teensy40", feature = "teensy41")))]
pub type BoardLayout = Kinetis;

/// ACAN's layout, MB0–MB15 (the default): every chip.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kinetis {}

impl Layout for Kinetis {
    const MESSAGE_BUFFERS: usize = crate::regs::NUM_MB;
    const MAX_RFFN: u8 = Configuration::Filters14_18.rffn();
    const IFLAG2: bool = false;
    const E5829: bool = false;
    type Table = FilterTable;
    type System = crate::system::PortPlan;
}

/// The i.MX RT1062's 64 message buffers: Rx FIFO tables up to RFFN 0xF, the transmit
/// mailboxes after them ([`Configuration::data_mailbox`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Imxrt1062 {}

impl Layout for Imxrt1062 {
    const MESSAGE_BUFFERS: usize = crate::imxrt::MESSAGE_BUFFERS;
    const MAX_RFFN: u8 = 0xF;
    const IFLAG2: bool = true;
    const E5829: bool = true;
    type Table = LargeFilterTable;
    type System = crate::imxrt::ImxrtPlan;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_board_layout_and_window_follow_the_board_feature() {
        let teensy4 = cfg!(any(feature = "teensy40", feature = "teensy41"));
        // The RT1062 layout (ERR005829 workaround, RFFN up to 0xF) on a Teensy 4 only.
        assert_eq!(BoardLayout::E5829, teensy4);
        assert_eq!(BoardLayout::MAX_RFFN, if teensy4 { 0xF } else { 3 });
        // Its window reaches the individual masks beyond the Kinetis block.
        let (imxrt, kinetis) = (crate::regs::IMXRT_BLOCK_END, crate::regs::BLOCK_END);
        let expected = if teensy4 { imxrt } else { kinetis };
        assert_eq!(crate::regs::BOARD_BLOCK_END, expected);
        assert_eq!(crate::regs::rximr(64), imxrt);
    }

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
            assert!(Imxrt1062::message_buffers_used(c) <= Imxrt1062::MESSAGE_BUFFERS);
            assert_eq!(
                Kinetis::accepts(Chip::Imxrt1062, c),
                Configuration::ALL.contains(&c)
            );
            assert_eq!(
                Kinetis::accepts(Chip::Mk66fx1m0, c),
                Configuration::ALL.contains(&c)
            );
            assert!(Imxrt1062::accepts(Chip::Imxrt1062, c));
            // The reservation puts the data mailbox at MB16 or above.
            assert!(!Imxrt1062::accepts(Chip::Mk66fx1m0, c));
            // Kinetis: the plain positions; RT1062: one reserved mailbox, none lost.
            assert_eq!(Kinetis::data_mailbox(c), c.data_mailbox());
            assert_eq!(Kinetis::first_remote_mailbox(c), c.first_remote_mailbox());
            assert_eq!(
                Imxrt1062::data_mailbox(c) - Imxrt1062::first_remote_mailbox(c),
                c.remote_mailbox_count()
            );
            assert_eq!(Imxrt1062::reserved_mailbox(c), Some(c.fifo_mailboxes()));
        }
    }
}
