//! How the message buffers are shared out (ACAN §3 table 1, §11 table 4; on the
//! RT1062 also the larger Rx FIFO tables of IMXRT1060RM, FlexCAN chapter, CTRL2 field
//! RFFN and table "Rx FIFO filter: possible structures": [`Configuration`]).
//!
//! With the Rx FIFO enabled, MB0–MB5 are the FIFO itself and the ID filter table
//! starts at MB6; `CTRL2.RFFN` sets the table to `8 × (RFFN + 1)` elements, each MB
//! holding four (Kinetis reference manuals, FlexCAN chapter, "Rx FIFO structure").
//! The elements of the first MBs the FIFO occupies are matched with the individual
//! masks `RXIMRn` ("primary filters" in ACAN), the others with `RXFGMASK`
//! ("secondary filters"). MB15 sends data frames, the MBs between the table and MB15
//! send remote frames.
//!
//! | configuration | RFFN | table | primary | secondary | remote MBs | data MB |
//! |---|---|---|---|---|---|---|
//! | [`Configuration::Filters8_0`] | 0 | MB6–MB7 | 8 | 0 | MB8–MB14 (7) | MB15 |
//! | [`Configuration::Filters10_6`] | 1 | MB6–MB9 | 10 | 6 | MB10–MB14 (5) | MB15 |
//! | [`Configuration::Filters12_12`] | 2 | MB6–MB11 | 12 | 12 | MB12–MB14 (3) | MB15 |
//! | [`Configuration::Filters14_18`] | 3 | MB6–MB13 | 14 | 18 | MB14 (1) | MB15 |

/// The number of message buffers of the FlexCAN modules of the K20, K64 and K66.
pub const MESSAGE_BUFFERS: u8 = 16;

/// The message buffer that sends data frames (ACAN §3 table 1).
pub const DATA_MAILBOX: u8 = 15;

/// Most ID filter table elements any configuration uses (RFFN = 3).
pub const MAX_TABLE_ELEMENTS: usize = 32;

/// Most primary filters (individual-mask elements) any configuration allows.
pub const MAX_PRIMARY_FILTERS: usize = 14;

/// Most secondary filters (global-mask elements) any configuration allows.
pub const MAX_SECONDARY_FILTERS: usize = 18;

/// The message-buffer partition, ACAN `mConfiguration` (§11, table 4), and on the
/// i.MX RT1062 the larger Rx FIFO filter tables of `CTRL2[RFFN]` = 4 to 0xF
/// (IMXRT1060RM, FlexCAN chapter, CTRL2 field RFFN and table "Rx FIFO filter: possible
/// structures").
///
/// The names read "primary filters _ secondary filters", as ACAN's `k12_12_Filters`.
/// The discriminant is the `RFFN` value.
///
/// | RFFN | configuration | table | primary (`RXIMRn`) | secondary (`RXFGMASK`) | remote MBs | data MB |
/// |---|---|---|---|---|---|---|
/// | 0–3 | ACAN's four ([`Configuration::ALL`], module docs) | MB6–MB13 at most | 8–14 | 0–18 | up to MB14 | MB15 |
/// | 4 | [`Configuration::Filters16_24`] | MB6–MB15 | 16 | 24 | MB16–MB22 (7) | MB23 |
/// | 8 | [`Configuration::Filters24_48`] | MB6–MB23 | 24 | 48 | MB24–MB30 (7) | MB31 |
/// | 0xB | [`Configuration::Filters30_66`] | MB6–MB29 | 30 | 66 | MB30 (1) | MB31 |
/// | 0xC | [`Configuration::Filters32_72`] | MB6–MB31 | 32 | 72 | MB32–MB38 (7) | MB39 |
/// | 0xF | [`Configuration::Filters32_96`] | MB6–MB37 | 32 | 96 | MB38–MB44 (7) | MB45 |
///
/// Beyond ACAN's four the transmit mailboxes follow the table: up to seven remote-frame
/// mailboxes, then the data mailbox, never across MB31/MB32 (so they all answer in one
/// of `IFLAG1`/`IFLAG2`, IMXRT1060RM "Interrupt Flags 2 register (IFLAG2)") — see
/// [`Configuration::data_mailbox`]. Those configurations need 64 message buffers: the
/// controller's layout ([`crate::layout::Imxrt1062`]) and the chip
/// ([`crate::Chip::accepted_max_rffn`]) decide which are accepted.
///
/// The MB columns above are the positions without the ERR005829 reservation (the
/// [`crate::layout::Kinetis`] layout, and the RT1062 tables as the manual numbers
/// them). The [`crate::layout::Imxrt1062`] layout keeps the first valid mailbox
/// after the table INACTIVE (i.MX RT1060 chip errata, ERR005829:
/// [`Configuration::reserved_mailbox`]) and puts the same number of transmit
/// mailboxes after it ([`Configuration::first_remote_mailbox_in`],
/// [`Configuration::data_mailbox_in`]): data mailbox MB16 for ACAN's four, MB39 at
/// RFFN 8, MB40 at 0xC, MB46 at 0xF (table in [`crate::layout`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[allow(non_camel_case_types)]
#[repr(u8)]
pub enum Configuration {
    /// 8 primary, 0 secondary filters, 7 remote-frame mailboxes (`k8_0_Filters`).
    Filters8_0 = 0,
    /// 10 primary, 6 secondary filters, 5 remote-frame mailboxes (`k10_6_Filters`).
    Filters10_6 = 1,
    /// 12 primary, 12 secondary filters, 3 remote-frame mailboxes (`k12_12_Filters`,
    /// ACAN's default, §11).
    #[default]
    Filters12_12 = 2,
    /// 14 primary, 18 secondary filters, 1 remote-frame mailbox (`k14_18_Filters`).
    Filters14_18 = 3,
    /// RFFN 4 (RT1062): 40 elements, 16 primary, 24 secondary; MB16–MB22 remote, MB23 data.
    Filters16_24 = 4,
    /// RFFN 5 (RT1062): 48 elements, 18 primary, 30 secondary; MB18–MB24 remote, MB25 data.
    Filters18_30 = 5,
    /// RFFN 6 (RT1062): 56 elements, 20 primary, 36 secondary; MB20–MB26 remote, MB27 data.
    Filters20_36 = 6,
    /// RFFN 7 (RT1062): 64 elements, 22 primary, 42 secondary; MB22–MB28 remote, MB29 data.
    Filters22_42 = 7,
    /// RFFN 8 (RT1062): 72 elements, 24 primary, 48 secondary; MB24–MB30 remote, MB31 data.
    Filters24_48 = 8,
    /// RFFN 9 (RT1062): 80 elements, 26 primary, 54 secondary; MB26–MB30 remote, MB31 data.
    Filters26_54 = 9,
    /// RFFN 0xA (RT1062): 88 elements, 28 primary, 60 secondary; MB28–MB30 remote, MB31 data.
    Filters28_60 = 10,
    /// RFFN 0xB (RT1062): 96 elements, 30 primary, 66 secondary; MB30 remote, MB31 data.
    Filters30_66 = 11,
    /// RFFN 0xC (RT1062): 104 elements, 32 primary, 72 secondary; MB32–MB38 remote,
    /// MB39 data.
    Filters32_72 = 12,
    /// RFFN 0xD (RT1062): 112 elements, 32 primary, 80 secondary; MB34–MB40 remote,
    /// MB41 data.
    Filters32_80 = 13,
    /// RFFN 0xE (RT1062): 120 elements, 32 primary, 88 secondary; MB36–MB42 remote,
    /// MB43 data.
    Filters32_88 = 14,
    /// RFFN 0xF (RT1062): 128 elements, 32 primary, 96 secondary; MB38–MB44 remote,
    /// MB45 data.
    Filters32_96 = 15,
}

impl Configuration {
    /// ACAN's four configurations (every one of a 16-buffer module), in table order.
    pub const ALL: [Configuration; 4] = [
        Configuration::Filters8_0,
        Configuration::Filters10_6,
        Configuration::Filters12_12,
        Configuration::Filters14_18,
    ];

    /// Every `CTRL2[RFFN]` value, 0 to 0xF, in order (the last twelve need 64 message
    /// buffers).
    pub const EVERY: [Configuration; 16] = [
        Configuration::Filters8_0,
        Configuration::Filters10_6,
        Configuration::Filters12_12,
        Configuration::Filters14_18,
        Configuration::Filters16_24,
        Configuration::Filters18_30,
        Configuration::Filters20_36,
        Configuration::Filters22_42,
        Configuration::Filters24_48,
        Configuration::Filters26_54,
        Configuration::Filters28_60,
        Configuration::Filters30_66,
        Configuration::Filters32_72,
        Configuration::Filters32_80,
        Configuration::Filters32_88,
        Configuration::Filters32_96,
    ];

    /// The configuration of `CTRL2[RFFN]` = `rffn` (`None` above 0xF).
    pub const fn from_rffn(rffn: u8) -> Option<Configuration> {
        if rffn < 16 {
            Some(Self::EVERY[rffn as usize])
        } else {
            None
        }
    }

    /// The `CTRL2.RFFN` field value (Kinetis RM and IMXRT1060RM, CTRL2: number of Rx
    /// FIFO filters).
    pub const fn rffn(self) -> u8 {
        self as u8
    }

    /// The RFFN value of a configuration known to be at most `max` (a table, a
    /// controller or a layout that holds only those), computed so that the compiler
    /// sees the bound: a mask when `max + 1` is a power of two (3, 0xF), else a minimum.
    /// The same value as [`Configuration::rffn`] for every configuration up to `max`.
    #[inline(always)]
    pub const fn rffn_at_most(self, max: u8) -> u8 {
        let r = self as u8;
        if max & max.wrapping_add(1) == 0 {
            r & max
        } else if r > max {
            max
        } else {
            r
        }
    }

    /// Elements of the ID filter table: `8 × (RFFN + 1)`.
    pub const fn table_elements(self) -> usize {
        8 * (self.rffn() as usize + 1)
    }

    /// Message buffers taken by the Rx FIFO and its ID filter table:
    /// `6 + 2 × (RFFN + 1)`.
    pub const fn fifo_mailboxes(self) -> u8 {
        6 + 2 * (self.rffn() + 1)
    }

    /// How many primary filters fit (ACAN table 4): the table elements matched with
    /// individual masks, one per message buffer the FIFO occupies, at most 32
    /// (IMXRT1060RM "Rx FIFO filter: possible structures": elements 0–31 from RFFN = 0xC).
    pub const fn primary_filter_capacity(self) -> usize {
        let occupied = self.fifo_mailboxes() as usize;
        if occupied < 32 {
            occupied
        } else {
            32
        }
    }

    /// How many secondary filters fit (ACAN table 4): the remaining table elements,
    /// matched with `RXFGMASK`.
    pub const fn secondary_filter_capacity(self) -> usize {
        self.table_elements() - self.primary_filter_capacity()
    }

    /// The first remote-frame mailbox without the ERR005829 reservation (the
    /// [`crate::layout::Kinetis`] layout): the first message buffer after the Rx FIFO
    /// and its table. With the [`crate::layout::Imxrt1062`] layout:
    /// [`Configuration::first_remote_mailbox_in`]`(true)`.
    pub const fn first_remote_mailbox(self) -> u8 {
        self.fifo_mailboxes()
    }

    /// The message buffer the ERR005829 workaround keeps INACTIVE (i.MX RT1060 chip
    /// errata, ERR005829: "the first valid mailbox", the first message buffer after the
    /// area the Rx FIFO and its ID filter table occupy): MB`6 + 2 × (RFFN + 1)`, MB8 at
    /// RFFN 0, MB38 at RFFN 0xF. Reserved only by a layout with
    /// [`crate::layout::Layout::E5829`]; never loaded with a frame.
    pub const fn reserved_mailbox(self) -> u8 {
        self.fifo_mailboxes()
    }

    /// The first remote-frame mailbox; with `e5829` (the layout's
    /// [`crate::layout::Layout::E5829`]) the transmit mailboxes leave room for the
    /// reserved mailbox ([`Configuration::reserved_mailbox`]): they move up by one, as
    /// many as without it ([`Configuration::remote_mailbox_count`]), or start at MB32
    /// when one up would put them across MB31/MB32 (RFFN 8 to 0xB: the table ends in
    /// MB23 … MB29, the reserved mailbox MB24 … MB30; the buffers between it and MB32
    /// stay INACTIVE). Without `e5829`: [`Configuration::first_remote_mailbox`].
    pub const fn first_remote_mailbox_in(self, e5829: bool) -> u8 {
        if e5829 {
            let first = self.reserved_mailbox() + 1;
            if first / 32 == (first + self.remote_mailbox_count()) / 32 {
                first
            } else {
                (first | 31) + 1
            }
        } else {
            self.first_remote_mailbox()
        }
    }

    /// The data mailbox with or without the ERR005829 reservation (`e5829`, see
    /// [`Configuration::first_remote_mailbox_in`]): the remote-frame mailboxes and
    /// then the data mailbox, `MCR[MAXMB]`. Without `e5829`: [`Configuration::data_mailbox`].
    pub const fn data_mailbox_in(self, e5829: bool) -> u8 {
        if e5829 {
            self.first_remote_mailbox_in(true) + self.remote_mailbox_count()
        } else {
            self.data_mailbox()
        }
    }

    /// The message buffers taken into matching and arbitration with or without the
    /// ERR005829 reservation: MB0 to [`Configuration::data_mailbox_in`] (`MCR[MAXMB]` + 1).
    pub const fn message_buffers_used_in(self, e5829: bool) -> usize {
        self.data_mailbox_in(e5829) as usize + 1
    }

    /// The message buffer that sends data frames without the ERR005829 reservation
    /// (the [`crate::layout::Kinetis`] layout): MB15 in ACAN's configurations (§3
    /// table 1); beyond them the seventh after the table, or MB31 when the table ends
    /// within seven of it (the transmit mailboxes stay within one of `IFLAG1` and
    /// `IFLAG2`). Also the last message buffer the driver enables (`MCR[MAXMB]`). With
    /// the [`crate::layout::Imxrt1062`] layout: [`Configuration::data_mailbox_in`]`(true)`.
    pub const fn data_mailbox(self) -> u8 {
        let first = self.first_remote_mailbox();
        if first <= DATA_MAILBOX {
            DATA_MAILBOX
        } else if first + 7 > (first | 31) {
            first | 31
        } else {
            first + 7
        }
    }

    /// How many mailboxes send remote frames (ACAN §9: 7, 5, 3 or 1).
    pub const fn remote_mailbox_count(self) -> u8 {
        self.data_mailbox() - self.first_remote_mailbox()
    }

    /// The message buffers the configuration uses without the ERR005829 reservation,
    /// MB0 to [`Configuration::data_mailbox`] (`MCR[MAXMB]` + 1): 16 for ACAN's four.
    /// With the [`crate::layout::Imxrt1062`] layout:
    /// [`Configuration::message_buffers_used_in`]`(true)`.
    pub const fn message_buffers_used(self) -> usize {
        self.data_mailbox() as usize + 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn acan_table_4() {
        let rows: [(Configuration, usize, usize, u8); 4] = [
            (Configuration::Filters8_0, 8, 0, 7),
            (Configuration::Filters10_6, 10, 6, 5),
            (Configuration::Filters12_12, 12, 12, 3),
            (Configuration::Filters14_18, 14, 18, 1),
        ];
        for (c, p, s, r) in rows {
            assert_eq!(c.primary_filter_capacity(), p);
            assert_eq!(c.secondary_filter_capacity(), s);
            assert_eq!(c.remote_mailbox_count(), r);
            assert_eq!(
                c.first_remote_mailbox() + c.remote_mailbox_count(),
                DATA_MAILBOX
            );
            assert!(c.table_elements() <= MAX_TABLE_ELEMENTS);
            assert!(p <= MAX_PRIMARY_FILTERS && s <= MAX_SECONDARY_FILTERS);
            assert_eq!(c.data_mailbox(), DATA_MAILBOX);
            assert_eq!(c.message_buffers_used(), MESSAGE_BUFFERS as usize);
        }
        assert_eq!(Configuration::default(), Configuration::Filters12_12);
    }

    #[test]
    fn rt1062_configurations_follow_the_manual_table() {
        // (RFFN, elements, primary, secondary, first remote MB, data MB)
        let rows = [
            (4, 40, 16, 24, 16, 23),
            (7, 64, 22, 42, 22, 29),
            (8, 72, 24, 48, 24, 31),
            (0xB, 96, 30, 66, 30, 31),
            (0xC, 104, 32, 72, 32, 39),
            (0xD, 112, 32, 80, 34, 41),
            (0xF, 128, 32, 96, 38, 45),
        ];
        for (r, e, p, s, first, data) in rows {
            let c = Configuration::from_rffn(r).unwrap();
            assert_eq!(c.rffn(), r);
            assert_eq!(
                (
                    c.table_elements(),
                    c.primary_filter_capacity(),
                    c.secondary_filter_capacity(),
                    c.first_remote_mailbox(),
                    c.data_mailbox()
                ),
                (e, p, s, first, data),
                "RFFN {r}"
            );
        }
        for (r, c) in Configuration::EVERY.iter().enumerate() {
            assert_eq!(c.rffn() as usize, r);
            // The transmit mailboxes lie in one flag register and fit 8 token slots.
            assert_eq!(
                c.first_remote_mailbox() / 32,
                c.data_mailbox() / 32,
                "{c:?}"
            );
            assert!(c.remote_mailbox_count() >= 1 && c.remote_mailbox_count() <= 7);
            assert!(c.message_buffers_used() <= 64);
        }
        assert_eq!(Configuration::from_rffn(16), None);
    }

    /// The ERR005829 reservation (i.MX RT1060 chip errata, ERR005829): the first valid
    /// mailbox after the FIFO area reserved, the transmit mailboxes after it as many as
    /// without it, never across MB31/MB32, all within the RT1062's 64 buffers.
    #[test]
    fn the_e5829_reservation_keeps_every_remote_mailbox() {
        // (RFFN, reserved MB, first remote MB, data MB)
        let rows = [
            (0, 8, 9, 16),
            (1, 10, 11, 16),
            (3, 14, 15, 16),
            (4, 16, 17, 24),
            (7, 22, 23, 30),
            (8, 24, 32, 39),
            (9, 26, 32, 37),
            (0xB, 30, 32, 33),
            (0xC, 32, 33, 40),
            (0xF, 38, 39, 46),
        ];
        for (r, reserved, first, data) in rows {
            let c = Configuration::from_rffn(r).unwrap();
            assert_eq!(
                (
                    c.reserved_mailbox(),
                    c.first_remote_mailbox_in(true),
                    c.data_mailbox_in(true)
                ),
                (reserved, first, data),
                "RFFN {r}"
            );
        }
        for c in Configuration::EVERY {
            let (first, data) = (c.first_remote_mailbox_in(true), c.data_mailbox_in(true));
            // The first valid mailbox: right after the FIFO and its table.
            assert_eq!(
                usize::from(c.reserved_mailbox()),
                crate::regs::rx_fifo_occupied_mbs(u32::from(c.rffn()))
            );
            assert!(c.reserved_mailbox() < first && data < 64, "{c:?}");
            assert_eq!(first / 32, data / 32, "{c:?}");
            assert_eq!(data - first, c.remote_mailbox_count(), "{c:?}");
            assert_eq!(c.message_buffers_used_in(true), usize::from(data) + 1);
            // Without the reservation: the plain rule.
            assert_eq!(c.first_remote_mailbox_in(false), c.first_remote_mailbox());
            assert_eq!(c.data_mailbox_in(false), c.data_mailbox());
            assert_eq!(c.message_buffers_used_in(false), c.message_buffers_used());
        }
    }
}
