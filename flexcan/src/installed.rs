//! The filter table a split controller keeps for the receive half
//! ([`crate::options::Options::Table`]): an owned [`FilterTable`] (replaceable while
//! running, [`crate::options::Full`]) or a [`PlannedTable`], a few words pointing into a
//! `static` plan made at compile time ([`crate::const_plan!`],
//! [`crate::options::Lean`]).
//!
//! Either way the receive half maps `RXFIR.IDHIT` back to the user's filter
//! ([`InstalledTable::resolve`], ACAN §12.5, §13.5) and `begin` writes the same ID
//! table, masks and `MCR.IDAM` (Kinetis RM, "Rx FIFO structure").

use twocan_core::filter_set::{key, lower_bound, Key};
use twocan_core::{Error, Frame};

use crate::configuration::Configuration;
use crate::filters::{FilterTable, Hit, OwnedTable, SizedTable};

/// Why a hit gives no user filter ([`InstalledTable::resolve`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unresolved {
    /// A merged or superset element's identifier that no user filter accepts: the
    /// driver drops the frame and counts it.
    Superset,
    /// An `IDHIT` the table does not produce (stale, corrupted): the frame is kept with
    /// [`crate::UNKNOWN_FILTER`] and counted.
    Unknown,
}

/// What the split controller needs of its filter table; `T` is the table
/// `set_filters` takes (the layout's, [`crate::layout::Layout::Table`]).
pub trait InstalledTable<T = FilterTable>: Send + 'static {
    /// Whether [`InstalledTable::replace`] can take a new table (checked before any
    /// register is written).
    const REPLACEABLE: bool;

    /// The message-buffer configuration the table is planned for.
    fn configuration(&self) -> Configuration;

    /// The user's filter for a frame the hardware accepted with `RXFIR.IDHIT` = `hit`.
    fn resolve(&self, hit: usize, frame: &Frame) -> Result<u16, Unresolved>;

    /// Replaces the table with `table` (the receive half's `set_filters`, after the
    /// registers were written). [`Error::Unsupported`] for a table that cannot change.
    fn replace(&mut self, table: &T) -> Result<(), Error>;
}

impl<T: OwnedTable> InstalledTable<T> for T {
    const REPLACEABLE: bool = true;

    #[inline(always)]
    fn configuration(&self) -> Configuration {
        self.table_configuration()
    }

    #[inline]
    fn resolve(&self, hit: usize, frame: &Frame) -> Result<u16, Unresolved> {
        match self.table_filter_index(hit, frame) {
            Some(i) => Ok(i),
            None if self.table_hit(hit) == Some(Hit::Lookup) => Err(Unresolved::Superset),
            None => Err(Unresolved::Unknown),
        }
    }

    fn replace(&mut self, table: &T) -> Result<(), Error> {
        self.clone_from(table);
        Ok(())
    }
}

impl<T: OwnedTable> InstalledTable<T> for &'static mut T {
    const REPLACEABLE: bool = true;

    #[inline(always)]
    fn configuration(&self) -> Configuration {
        self.table_configuration()
    }

    #[inline]
    fn resolve(&self, hit: usize, frame: &Frame) -> Result<u16, Unresolved> {
        <T as InstalledTable<T>>::resolve(self, hit, frame)
    }

    fn replace(&mut self, table: &T) -> Result<(), Error> {
        self.clone_from(table);
        Ok(())
    }
}

/// A filter table planned at compile time, read in place from its `static`
/// ([`SizedTable::planned`]): the ID table elements, the individual masks, the global
/// mask, what a hit on each element means and the lookup keys, as slices of the plan —
/// a few words in the driver's state instead of a table-sized copy. It cannot be
/// replaced while running.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlannedTable {
    configuration: Configuration,
    reject_all: bool,
    global_mask: u32,
    elements: &'static [u32],
    individual_masks: &'static [u32],
    hits: &'static [Hit],
    keys: &'static [Key],
    key_users: &'static [u16],
}

impl<const E: usize, const P: usize, const K: usize> SizedTable<E, P, K> {
    /// The plan as the split controller keeps it ([`PlannedTable`]), for
    /// [`crate::FlexCan::begin_planned`].
    pub const fn planned(&'static self) -> PlannedTable {
        let (keys, key_users) = self.lookup_keys();
        PlannedTable {
            configuration: self.configuration(),
            reject_all: self.rejects_all(),
            global_mask: self.global_mask(),
            elements: self.elements(),
            individual_masks: self.individual_masks(),
            hits: self.hits(),
            keys,
            key_users,
        }
    }
}

impl PlannedTable {
    /// The configuration the table is planned for.
    pub const fn configuration(&self) -> Configuration {
        self.configuration
    }

    /// Whether the table accepts no frame (format D).
    pub const fn rejects_all(&self) -> bool {
        self.reject_all
    }

    /// The ID table elements, in hardware order.
    pub const fn elements(&self) -> &'static [u32] {
        self.elements
    }

    /// The individual masks `RXIMR0…`.
    pub const fn individual_masks(&self) -> &'static [u32] {
        self.individual_masks
    }

    /// The global mask `RXFGMASK`.
    pub const fn global_mask(&self) -> u32 {
        self.global_mask
    }
}

impl<T> InstalledTable<T> for PlannedTable {
    const REPLACEABLE: bool = false;

    fn configuration(&self) -> Configuration {
        self.configuration
    }

    #[inline]
    fn resolve(&self, hit: usize, frame: &Frame) -> Result<u16, Unresolved> {
        match self.hits.get(hit) {
            Some(Hit::Filter(i)) => Ok(*i),
            Some(Hit::Lookup) => {
                let k = key(frame.raw_id(), frame.is_extended(), frame.is_remote());
                let at = lower_bound(self.keys, k);
                match (self.keys.get(at), self.key_users.get(at)) {
                    (Some(found), Some(user)) if *found == k => Ok(*user),
                    _ => Err(Unresolved::Superset),
                }
            }
            // A planned table has no ACAN secondary filters found in software.
            Some(Hit::ScanSecondary) | None => Err(Unresolved::Unknown),
        }
    }

    fn replace(&mut self, _: &T) -> Result<(), Error> {
        Err(Error::Unsupported)
    }
}
