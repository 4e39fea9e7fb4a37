//! How the 16 message buffers are shared out (ACAN §3 table 1, §11 table 4).
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

/// The message-buffer partition, ACAN `mConfiguration` (§11, table 4).
///
/// The names read "primary filters _ secondary filters", as ACAN's `k12_12_Filters`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[allow(non_camel_case_types)]
pub enum Configuration {
    /// 8 primary, 0 secondary filters, 7 remote-frame mailboxes (`k8_0_Filters`).
    Filters8_0,
    /// 10 primary, 6 secondary filters, 5 remote-frame mailboxes (`k10_6_Filters`).
    Filters10_6,
    /// 12 primary, 12 secondary filters, 3 remote-frame mailboxes (`k12_12_Filters`,
    /// ACAN's default, §11).
    #[default]
    Filters12_12,
    /// 14 primary, 18 secondary filters, 1 remote-frame mailbox (`k14_18_Filters`).
    Filters14_18,
}

impl Configuration {
    /// Every configuration, in table order.
    pub const ALL: [Configuration; 4] = [
        Configuration::Filters8_0,
        Configuration::Filters10_6,
        Configuration::Filters12_12,
        Configuration::Filters14_18,
    ];

    /// The `CTRL2.RFFN` field value (Kinetis RM, CTRL2: number of Rx FIFO filters).
    pub const fn rffn(self) -> u8 {
        match self {
            Configuration::Filters8_0 => 0,
            Configuration::Filters10_6 => 1,
            Configuration::Filters12_12 => 2,
            Configuration::Filters14_18 => 3,
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
    /// individual masks, one per message buffer the FIFO occupies.
    pub const fn primary_filter_capacity(self) -> usize {
        self.fifo_mailboxes() as usize
    }

    /// How many secondary filters fit (ACAN table 4): the remaining table elements,
    /// matched with `RXFGMASK`.
    pub const fn secondary_filter_capacity(self) -> usize {
        self.table_elements() - self.primary_filter_capacity()
    }

    /// The first remote-frame mailbox.
    pub const fn first_remote_mailbox(self) -> u8 {
        self.fifo_mailboxes()
    }

    /// How many mailboxes send remote frames (ACAN §9: 7, 5, 3 or 1).
    pub const fn remote_mailbox_count(self) -> u8 {
        DATA_MAILBOX - self.first_remote_mailbox()
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
        }
        assert_eq!(Configuration::default(), Configuration::Filters12_12);
    }
}
