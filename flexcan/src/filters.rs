//! Primary and secondary receive filters compiled into the Rx FIFO ID filter table
//! (ACAN §12, §13; Kinetis reference manuals, FlexCAN "Rx FIFO structure").
//!
//! Filters are twocan-core's portable [`Filter`]s. ACAN's two kinds differ by where
//! they land in the hardware:
//!
//! - **primary filters** use the table elements matched with an individual mask
//!   (`RXIMRn`): kind, format, identifier, or mask + acceptance, or pass-all
//!   (§12.1–12.3). Their conformance is [`Filter::check`] (§12.4); a filter of
//!   kind [`FrameKind::Any`] (not in ACAN) works too.
//! - **secondary filters** share the one global mask `RXFGMASK`: each names a single
//!   identifier with a data or remote kind and a standard or extended format, or is
//!   the pass-all filter (§13, §13.4). Anything else is a secondary conformance error.
//!
//! Numbering (§13.5): primary filters are 0, 1, …, then secondary filters continue.
//! That number is [`twocan_core::RxFrame::filter`] and the dispatcher's index.
//!
//! # Table format A
//!
//! `MCR.IDAM = 0`: each element holds one identifier, bit 31 RTR, bit 30 IDE, an
//! extended identifier in bits 29–1, a standard one in bits 29–19. A mask has the
//! same layout: a set bit is compared, a clear bit is not. Elements are examined in
//! order and the first match wins, reported by `RXFIR.IDHIT` — so a duplicate filter,
//! or one after a pass-all filter, never matches (§12.1, §12.2, §13.2, §13.3).
//!
//! # Unused elements
//!
//! A configuration has a fixed number of elements; those the user's lists do not fill
//! must not accept any extra frame. An unused primary element repeats the last
//! primary filter (it sits after it, so it is never hit); an unused secondary element
//! repeats the last secondary filter, or, with no secondary filter, the last primary
//! filter's element under the global mask (a subset of what that filter accepts,
//! after it). With no primary filter, the primary elements repeat the first secondary
//! filter: they come before it but accept exactly what it accepts, and report its
//! index.
//!
//! # No filter at all
//!
//! An empty pair of lists accepts no frame, as on every twocan backend: the table is
//! switched to format D (`MCR.IDAM` = 0b11, Kinetis RM "Rx FIFO filter: possible
//! structures": "all frames rejected"), the elements and masks are left as they are.
//! **ACAN differs** (§4, §15.1: with no filter, every frame is received with index 0);
//! to receive everything, pass [`Filter::pass_all`] (see `docs/differences.md`).
//!
//! # Secondary pass-all
//!
//! One global mask cannot compare identifiers for some secondary elements and ignore
//! them for the pass-all one. When a secondary list holds a pass-all filter, the
//! global mask is 0: every frame no primary filter takes is accepted (the pass-all
//! filter would have accepted it), and the driver finds the secondary filter that
//! matches first in software ([`Filter::matches`], the reference semantics), so the
//! reported index is still the one §13.3 describes.

use twocan_core::filter_set::{key, key_parts, lower_bound, Key, KeyTable};
use twocan_core::{Filter, Format, Frame, FrameKind};

use crate::begin_error::ConfigErrors;
use crate::configuration::{
    Configuration, MAX_PRIMARY_FILTERS, MAX_SECONDARY_FILTERS, MAX_TABLE_ELEMENTS,
};
use crate::planner::PlanError;

/// Format A element / mask bit 31: remote frame.
pub const ELEMENT_RTR: u32 = 1 << 31;
/// Format A element / mask bit 30: extended frame.
pub const ELEMENT_IDE: u32 = 1 << 30;
/// Position of an extended identifier in a format A element (bits 29–1).
pub const ELEMENT_EXT_SHIFT: u32 = 1;
/// Position of a standard identifier in a format A element (bits 29–19).
pub const ELEMENT_STD_SHIFT: u32 = 19;
/// The mask that compares kind, format and the whole identifier.
pub const FULL_MASK: u32 = ELEMENT_RTR | ELEMENT_IDE | (0x1FFF_FFFF << ELEMENT_EXT_SHIFT);

/// What a table element's hit means.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Hit {
    /// The frame was accepted by the user's filter of this index.
    Filter(u16),
    /// Accepted under a zero global mask: the first matching secondary filter (found
    /// in software) gives the index.
    ScanSecondary,
    /// A planned element standing for several user filters (merged identifiers) or for
    /// a superset ([`crate::planner`]): the frame's identifier gives the index, by
    /// binary search in the table's key table; an identifier no user filter accepts
    /// gives none (the driver drops the frame and counts it).
    Lookup,
}

/// A filter list compiled for one [`Configuration`]: the ID filter table, the masks
/// and the map from `RXFIR.IDHIT` back to the user's filter index, with room for `K`
/// lookup keys (the identifiers of merged or superset elements, [`LOOKUP_KEYS`] by
/// default).
///
/// This is the FlexCAN [`twocan_core::Hardware::Filters`] type (with the default `K`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FilterTable<
    const K: usize = LOOKUP_KEYS,
    const ELEMS: usize = MAX_TABLE_ELEMENTS,
    const PRIM: usize = MAX_PRIMARY_FILTERS,
    const SEC: usize = MAX_SECONDARY_FILTERS,
> {
    configuration: Configuration,
    elements: [u32; ELEMS],
    individual_masks: [u32; PRIM],
    global_mask: u32,
    hits: [Hit; ELEMS],
    secondary: [Filter; SEC],
    primary_count: u8,
    secondary_count: u8,
    keys: KeyTable<K>,
    extra: u64,
    reject_all: bool,
}

/// How many identifiers a [`FilterTable`] keeps by default for the thread-side lookup
/// of merged or superset elements ([`Hit::Lookup`]): the keys (identifier, format,
/// kind) the hardware routes to such an element. Elements of one user filter need no
/// key. The table lives in the driver's state (6 bytes a key); the planner plans within
/// the capacity of the table it fills ([`crate::planner`]), and a `const` plan
/// ([`crate::const_plan!`]) carries exactly the keys it needs.
pub const LOOKUP_KEYS: usize = 64;

/// The most lookup keys any plan needs: the capacity a `const` plan is computed with
/// before it is cut to its size ([`SizedTable`]).
pub const MAX_LOOKUP_KEYS: usize = twocan_core::filter_set::MAX_KEYS;

/// A filter with every field zero: the content of a fresh planner scratch.
const ZERO_FILTER: Filter = Filter {
    kind: FrameKind::Data,
    format: Format::Standard,
    id: 0,
    mask: 0,
};

/// Whether `f` conforms as a secondary filter (ACAN §13.4).
pub fn secondary_conforms(f: &Filter) -> bool {
    f.check().is_ok() && (f.is_pass_all() || (f.is_exact() && !matches!(f.kind, FrameKind::Any)))
}

/// The format A element of a filter.
pub const fn element_of(f: &Filter) -> u32 {
    let rtr = if matches!(f.kind, FrameKind::Remote) {
        ELEMENT_RTR
    } else {
        0
    };
    let (ide, id) = match f.format {
        Format::Standard => (0, f.id << ELEMENT_STD_SHIFT),
        Format::Extended => (ELEMENT_IDE, f.id << ELEMENT_EXT_SHIFT),
        Format::Any => (0, 0),
    };
    rtr | ide | id
}

/// The format A individual mask of a primary filter.
pub const fn mask_of(f: &Filter) -> u32 {
    let rtr = if matches!(f.kind, FrameKind::Any) {
        0
    } else {
        ELEMENT_RTR
    };
    let (ide, id) = match f.format {
        Format::Standard => (ELEMENT_IDE, f.mask << ELEMENT_STD_SHIFT),
        Format::Extended => (ELEMENT_IDE, f.mask << ELEMENT_EXT_SHIFT),
        Format::Any => (0, 0),
    };
    rtr | ide | id
}

impl FilterTable {
    /// Checks and compiles the lists (ACAN §12–§13) into a table of ACAN's sizes (at
    /// most 32 elements: RFFN 0–3). Every problem is reported at once (ACAN table 5
    /// bits 2–5). [`FilterTable::compile_for`] compiles into a table of any size (the
    /// RT1062's [`crate::LargeFilterTable`]).
    pub fn compile(
        configuration: Configuration,
        primary: &[Filter],
        secondary: &[Filter],
    ) -> Result<Self, ConfigErrors> {
        Self::compile_for(configuration, primary, secondary)
    }
}

impl<const K: usize, const ELEMS: usize, const PRIM: usize, const SEC: usize>
    FilterTable<K, ELEMS, PRIM, SEC>
{
    /// Checks and compiles the lists (ACAN §12–§13) into a table of this type's
    /// capacity. Every problem is reported at once (ACAN table 5 bits 2–5); a
    /// configuration whose table does not fit the type is
    /// [`ConfigErrors::CONFIGURATION_NOT_ON_CHIP`].
    pub fn compile_for(
        configuration: Configuration,
        primary: &[Filter],
        secondary: &[Filter],
    ) -> Result<Self, ConfigErrors> {
        let errors = Self::check_for(configuration, primary, secondary);
        if !errors.is_empty() {
            return Err(errors);
        }
        Ok(Self::build(configuration, primary, secondary))
    }

    /// The largest `CTRL2[RFFN]` whose table fits this type (its elements, individual
    /// masks and secondary elements; each grows with RFFN): 3 for ACAN's sizes, 0xF for
    /// [`crate::LargeFilterTable`].
    pub const MAX_RFFN: u8 = {
        let mut r = 15;
        while r > 0 {
            let c = Configuration::EVERY[r];
            if c.table_elements() <= ELEMS
                && c.primary_filter_capacity() <= PRIM
                && c.secondary_filter_capacity() <= SEC
            {
                break;
            }
            r -= 1;
        }
        r as u8
    };

    /// Whether a table of `configuration` fits this type ([`FilterTable::MAX_RFFN`]).
    pub const fn holds(configuration: Configuration) -> bool {
        configuration.rffn() <= Self::MAX_RFFN
    }

    /// The RFFN of a configuration this type holds (every table's: checked on the way
    /// in), in a form the compiler sees is at most [`FilterTable::MAX_RFFN`], so that
    /// the arrays sized to it need no bounds check ([`Configuration::rffn_at_most`]).
    #[inline(always)]
    const fn rffn_of(configuration: Configuration) -> usize {
        configuration.rffn_at_most(Self::MAX_RFFN) as usize
    }

    /// [`Configuration::table_elements`] for a configuration this type holds.
    #[inline(always)]
    pub(crate) const fn elements_of(configuration: Configuration) -> usize {
        8 * (Self::rffn_of(configuration) + 1)
    }

    /// [`Configuration::primary_filter_capacity`] for a configuration this type holds:
    /// below 32 individual masks, the FIFO's message buffers (no cap to apply).
    #[inline(always)]
    pub(crate) const fn primary_of(configuration: Configuration) -> usize {
        let occupied = 8 + 2 * Self::rffn_of(configuration);
        if PRIM >= 32 && occupied > 32 {
            32
        } else {
            occupied
        }
    }

    /// [`Configuration::secondary_filter_capacity`] for a configuration this type holds.
    #[inline(always)]
    pub(crate) const fn secondary_of(configuration: Configuration) -> usize {
        Self::elements_of(configuration) - Self::primary_of(configuration)
    }

    /// The errors [`FilterTable::compile_for`] reports for these lists (none: it
    /// compiles), without building the table.
    pub(crate) fn check_for(
        configuration: Configuration,
        primary: &[Filter],
        secondary: &[Filter],
    ) -> ConfigErrors {
        let mut errors = ConfigErrors::NONE;
        // The counts against the configuration's own capacities (ACAN table 5), also
        // for a configuration this table cannot hold.
        let (capacity_p, capacity_s) = if Self::holds(configuration) {
            (
                Self::primary_of(configuration),
                Self::secondary_of(configuration),
            )
        } else {
            errors |= ConfigErrors::CONFIGURATION_NOT_ON_CHIP;
            (
                configuration.primary_filter_capacity(),
                configuration.secondary_filter_capacity(),
            )
        };
        if primary.len() > capacity_p {
            errors |= ConfigErrors::TOO_MANY_PRIMARY_FILTERS;
        }
        if primary.iter().any(|f| f.check().is_err()) {
            errors |= ConfigErrors::PRIMARY_FILTER_NOT_CONFORM;
        }
        if secondary.len() > capacity_s {
            errors |= ConfigErrors::TOO_MANY_SECONDARY_FILTERS;
        }
        if !secondary.iter().all(secondary_conforms) {
            errors |= ConfigErrors::SECONDARY_FILTER_NOT_CONFORM;
        }
        errors
    }

    /// Builds a table from lists already checked ([`FilterTable::check_for`]).
    pub(crate) fn build(
        configuration: Configuration,
        primary: &[Filter],
        secondary: &[Filter],
    ) -> Self {
        let mut t = Self::zeroed();
        t.fill(configuration, primary, secondary);
        t
    }

    /// [`FilterTable::build`] in place, field by field: no table-sized value on the
    /// stack (a table in a `static`, [`TableSlot`]).
    pub(crate) fn fill(
        &mut self,
        configuration: Configuration,
        primary: &[Filter],
        secondary: &[Filter],
    ) {
        let t = self;
        let p = primary.len();
        let s = secondary.len();
        let capacity_p = Self::primary_of(configuration);
        let capacity_s = Self::secondary_of(configuration);
        let scan = secondary.iter().any(Filter::is_pass_all);
        let global_mask = if scan {
            0
        } else if secondary
            .iter()
            .any(|f| matches!(f.format, Format::Extended))
            || s == 0
        {
            FULL_MASK
        } else {
            // Only standard identifiers: the extended bits need no comparison.
            ELEMENT_RTR | ELEMENT_IDE | (0x7FF << ELEMENT_STD_SHIFT)
        };
        let secondary_hit = |j: usize| {
            if scan {
                Hit::ScanSecondary
            } else {
                Hit::Filter((p + j) as u16)
            }
        };

        t.configuration = configuration;
        t.elements = [0; ELEMS];
        t.individual_masks = [FULL_MASK; PRIM];
        t.global_mask = global_mask;
        t.hits = [Hit::Filter(0); ELEMS];
        t.secondary = [Filter::pass_all(); SEC];
        t.primary_count = p as u8;
        t.secondary_count = s as u8;
        t.keys.clear();
        t.extra = 0;
        t.reject_all = primary.is_empty() && secondary.is_empty();
        t.secondary[..s].copy_from_slice(secondary);

        for i in 0..capacity_p {
            let (element, mask, hit) = match (primary.get(i), primary.last(), secondary.first()) {
                (Some(f), _, _) => (element_of(f), mask_of(f), Hit::Filter(i as u16)),
                (None, Some(last), _) => {
                    (element_of(last), mask_of(last), Hit::Filter((p - 1) as u16))
                }
                (None, None, Some(first)) => (element_of(first), global_mask, secondary_hit(0)),
                // An empty pair of lists: format D rejects every frame, the element
                // is never compared.
                (None, None, None) => (0, FULL_MASK, Hit::Filter(0)),
            };
            t.elements[i] = element;
            t.individual_masks[i] = mask;
            t.hits[i] = hit;
        }
        for j in 0..capacity_s {
            let (element, hit) = match (secondary.get(j), secondary.last(), primary.last()) {
                (Some(f), _, _) => (element_of(f), secondary_hit(j)),
                (None, Some(last), _) => (element_of(last), secondary_hit(s - 1)),
                (None, None, Some(last)) => (element_of(last), Hit::Filter((p - 1) as u16)),
                (None, None, None) => (0, Hit::Filter(0)),
            };
            t.elements[capacity_p + j] = element;
            t.hits[capacity_p + j] = hit;
        }
    }
}

/// A filter table the driver compiles and keeps (a [`FilterTable`] of any size): what
/// `begin`, the split controller and `set_filters` need of the table of a layout
/// ([`crate::layout::Layout::Table`]).
pub trait OwnedTable: Clone + Send + Sync + 'static {
    /// Whether a table of `configuration` fits ([`FilterTable::holds`]).
    fn holds(configuration: Configuration) -> bool;
    /// The errors compiling the lists gives ([`FilterTable::compile_for`]).
    fn check_lists(
        configuration: Configuration,
        primary: &[Filter],
        secondary: &[Filter],
    ) -> ConfigErrors;
    /// Lists already checked, compiled in place.
    fn fill_lists(
        &mut self,
        configuration: Configuration,
        primary: &[Filter],
        secondary: &[Filter],
    );
    /// Lists already checked, compiled.
    fn build_lists(configuration: Configuration, primary: &[Filter], secondary: &[Filter]) -> Self;
    /// The configuration the table was compiled for.
    fn table_configuration(&self) -> Configuration;
    /// Whether the table accepts no frame (format D).
    fn table_rejects_all(&self) -> bool;
    /// The ID table elements.
    fn table_elements(&self) -> &[u32];
    /// The individual masks.
    fn table_individual_masks(&self) -> &[u32];
    /// `RXFGMASK`.
    fn table_global_mask(&self) -> u32;
    /// What a hit on `element` means.
    fn table_hit(&self, element: usize) -> Option<Hit>;
    /// The user's filter for a hit ([`FilterTable::filter_index`]).
    fn table_filter_index(&self, element: usize, frame: &Frame) -> Option<u16>;
}

impl<const K: usize, const ELEMS: usize, const PRIM: usize, const SEC: usize> OwnedTable
    for FilterTable<K, ELEMS, PRIM, SEC>
{
    #[inline(always)]
    fn holds(configuration: Configuration) -> bool {
        Self::holds(configuration)
    }
    fn check_lists(
        configuration: Configuration,
        primary: &[Filter],
        secondary: &[Filter],
    ) -> ConfigErrors {
        Self::check_for(configuration, primary, secondary)
    }
    fn fill_lists(
        &mut self,
        configuration: Configuration,
        primary: &[Filter],
        secondary: &[Filter],
    ) {
        self.fill(configuration, primary, secondary)
    }
    fn build_lists(configuration: Configuration, primary: &[Filter], secondary: &[Filter]) -> Self {
        Self::build(configuration, primary, secondary)
    }
    #[inline(always)]
    fn table_configuration(&self) -> Configuration {
        self.configuration
    }
    fn table_rejects_all(&self) -> bool {
        self.reject_all
    }
    fn table_elements(&self) -> &[u32] {
        self.elements()
    }
    fn table_individual_masks(&self) -> &[u32] {
        self.individual_masks()
    }
    fn table_global_mask(&self) -> u32 {
        self.global_mask
    }
    #[inline]
    fn table_hit(&self, element: usize) -> Option<Hit> {
        self.hit(element)
    }
    #[inline]
    fn table_filter_index(&self, element: usize, frame: &Frame) -> Option<u16> {
        self.filter_index(element, frame)
    }
}

/// Room for one [`FilterTable`] in a `static`, handed out once as `&'static mut`
/// ([`TableSlot::take`]): `begin` compiles the lists straight into it
/// ([`crate::FlexCan::begin_in`]) and the split controller keeps the reference
/// ([`crate::options::FullInSlot`]), so that no table-sized value moves through the
/// configuration. `T` is the table (ACAN's sizes by default; the RT1062's
/// [`crate::layout::LargeFilterTable`] with [`crate::layout::Imxrt1062`]:
/// `TableSlot::<LargeFilterTable>::new_sized()`).
///
/// ```
/// use twocan_flexcan::filters::TableSlot;
/// static TABLE: TableSlot = TableSlot::new();
/// assert!(TABLE.take().is_some());
/// assert!(TABLE.take().is_none()); // once
/// ```
pub struct TableSlot<T = FilterTable> {
    table: core::cell::UnsafeCell<T>,
    taken: core::sync::atomic::AtomicBool,
}

// SAFETY: the table is reached only through the one `&'static mut` that `take` hands
// out (the atomic flag makes it once), so no two contexts share it through the slot.
unsafe impl<T: Send> Sync for TableSlot<T> {}

impl TableSlot {
    /// An empty slot (all zeros: it lives in `.bss`).
    pub const fn new() -> Self {
        TableSlot {
            table: core::cell::UnsafeCell::new(FilterTable::zeroed()),
            taken: core::sync::atomic::AtomicBool::new(false),
        }
    }
}

impl<const K: usize, const ELEMS: usize, const PRIM: usize, const SEC: usize>
    TableSlot<FilterTable<K, ELEMS, PRIM, SEC>>
{
    /// An empty slot for a table of any size (all zeros: it lives in `.bss`).
    pub const fn new_sized() -> Self {
        TableSlot {
            table: core::cell::UnsafeCell::new(FilterTable::zeroed()),
            taken: core::sync::atomic::AtomicBool::new(false),
        }
    }
}

impl<T> TableSlot<T> {
    /// The table, the first time only.
    // The one `&mut` comes from the cell, handed out once (the flag).
    #[allow(clippy::mut_from_ref)]
    pub fn take(&'static self) -> Option<&'static mut T> {
        if self.taken.swap(true, core::sync::atomic::Ordering::AcqRel) {
            return None;
        }
        // SAFETY: the flag was clear, so this is the only reference ever handed out.
        Some(unsafe { &mut *self.table.get() })
    }
}

impl Default for TableSlot {
    fn default() -> Self {
        Self::new()
    }
}

impl<const K: usize, const ELEMS: usize, const PRIM: usize, const SEC: usize>
    FilterTable<K, ELEMS, PRIM, SEC>
{
    /// The configuration the table was compiled for.
    pub const fn configuration(&self) -> Configuration {
        self.configuration
    }

    /// Whether the table accepts no frame at all (an empty pair of lists: `MCR.IDAM`
    /// format D).
    pub const fn rejects_all(&self) -> bool {
        self.reject_all
    }

    /// Number of primary filters.
    pub const fn primary_count(&self) -> usize {
        self.primary_count as usize
    }

    /// Number of secondary filters.
    pub const fn secondary_count(&self) -> usize {
        self.secondary_count as usize
    }

    /// The user index of secondary filter `j` (ACAN §13.5: after the primary ones).
    pub const fn secondary_index(&self, j: usize) -> usize {
        self.primary_count as usize + j
    }

    /// The table elements, in hardware order (`8 × (RFFN + 1)` of them).
    pub const fn elements(&self) -> &[u32] {
        self.elements
            .split_at(Self::elements_of(self.configuration))
            .0
    }

    /// The individual masks `RXIMR0…`, one per primary element.
    pub const fn individual_masks(&self) -> &[u32] {
        self.individual_masks
            .split_at(Self::primary_of(self.configuration))
            .0
    }

    /// What each table element's hit means, in hardware order.
    pub const fn hits(&self) -> &[Hit] {
        self.hits.split_at(Self::elements_of(self.configuration)).0
    }

    /// The keys (identifier, format, kind) the hardware routes to a merged or
    /// superset element ([`Hit::Lookup`]), with their user indices: the table
    /// [`FilterTable::filter_index`] searches (never more than `K`).
    pub const fn key_table(&self) -> &KeyTable<K> {
        &self.keys
    }

    /// The global mask `RXFGMASK` of the secondary elements.
    pub const fn global_mask(&self) -> u32 {
        self.global_mask
    }

    /// What a hit on table element `element` means (`None` beyond the table).
    pub fn hit(&self, element: usize) -> Option<Hit> {
        self.elements().get(element).map(|_| self.hits[element])
    }

    /// The user's filter index for a frame the hardware accepted with `RXFIR.IDHIT`
    /// = `element` (ACAN §12.5, §13.5).
    ///
    /// `None` when `element` is beyond the table, or is a zero-mask hit that no
    /// secondary filter matches: neither is produced by the hardware for this table
    /// (a frame read with a stale or corrupted `IDHIT`), and no filter index can be
    /// told — the controller reports such a frame with [`UNKNOWN_FILTER`].
    ///
    /// For a planned table ([`crate::planner::plan`]) this is the thread-side resolver:
    /// a table lookup for an element of one user filter; for a merged or superset
    /// element ([`Hit::Lookup`]) a binary search of the frame's identifier, `None` for
    /// an identifier no user filter accepts (a superset frame: drop and count it).
    pub fn filter_index(&self, element: usize, frame: &Frame) -> Option<u16> {
        match self.hit(element)? {
            Hit::Filter(i) => Some(i),
            Hit::Lookup => {
                self.keys
                    .lookup(key(frame.raw_id(), frame.is_extended(), frame.is_remote()))
            }
            Hit::ScanSecondary => self.secondary[..self.secondary_count()]
                .iter()
                .position(|f| f.matches(frame))
                .map(|j| self.secondary_index(j) as u16),
        }
    }
}

/// The format A word a frame is compared as (identifier, IDE, RTR in element layout).
pub const fn frame_word(raw_id: u32, extended: bool, remote: bool) -> u32 {
    (if extended {
        ELEMENT_IDE | raw_id << ELEMENT_EXT_SHIFT
    } else {
        raw_id << ELEMENT_STD_SHIFT
    }) | if remote { ELEMENT_RTR } else { 0 }
}

/// One planned primary element: (element, individual mask, hit).
pub(crate) type PlannedPrimary = (u32, u32, Hit);

impl<const K: usize, const ELEMS: usize, const PRIM: usize, const SEC: usize>
    FilterTable<K, ELEMS, PRIM, SEC>
{
    /// All zeros: a planner scratch's table before its first plan.
    pub(crate) const fn zeroed() -> Self {
        FilterTable {
            configuration: Configuration::Filters8_0,
            elements: [0; ELEMS],
            individual_masks: [0; PRIM],
            global_mask: 0,
            hits: [Hit::Filter(0); ELEMS],
            secondary: [ZERO_FILTER; SEC],
            primary_count: 0,
            secondary_count: 0,
            keys: KeyTable::new(),
            extra: 0,
            reject_all: false,
        }
    }

    /// A table from planned elements (crate-internal: [`crate::planner`]), in place.
    ///
    /// `primary`: (element, individual mask, hit) for the first `primary.len()` primary
    /// elements; `secondary`: (element, hit) under `global_mask`. Unused elements repeat
    /// the last used one of their part (after it, so never hit first); with no primary
    /// element the primaries repeat the first secondary element under the global mask,
    /// with no secondary element the secondaries repeat the last primary element under
    /// the global mask (which then compares everything: a subset of that element).
    /// Of `keys`, those the table routes to a [`Hit::Lookup`] element are kept.
    ///
    /// Errors: [`PlanError::TooManyLookupKeys`] when those are more than `K`.
    pub(crate) const fn set_planned<const N: usize>(
        &mut self,
        configuration: Configuration,
        primary: &[PlannedPrimary],
        secondary: &[(u32, Hit)],
        global_mask: u32,
        keys: &KeyTable<N>,
        extra: u64,
    ) -> Result<(), PlanError> {
        let capacity_p = Self::primary_of(configuration);
        let capacity_s = Self::secondary_of(configuration);
        let (np, ns) = (primary.len(), secondary.len());
        let global_mask = if ns == 0 { FULL_MASK } else { global_mask };
        // Field by field: no table-sized value on the stack.
        self.configuration = configuration;
        self.global_mask = global_mask;
        self.primary_count = np as u8;
        self.secondary_count = 0;
        self.keys.clear();
        self.extra = extra;
        self.reject_all = np == 0 && ns == 0;
        let mut i = 0;
        while i < ELEMS {
            self.elements[i] = 0;
            self.hits[i] = Hit::Filter(0);
            i += 1;
        }
        let mut i = 0;
        while i < PRIM {
            self.individual_masks[i] = FULL_MASK;
            i += 1;
        }
        let mut i = 0;
        while i < SEC {
            self.secondary[i] = Filter::pass_all();
            i += 1;
        }
        let mut i = 0;
        while i < capacity_p {
            let (e, m, h) = if i < np {
                primary[i]
            } else if np > 0 {
                primary[np - 1]
            } else if ns > 0 {
                (secondary[0].0, global_mask, secondary[0].1)
            } else {
                (0, FULL_MASK, Hit::Filter(0))
            };
            self.elements[i] = e;
            self.individual_masks[i] = m;
            self.hits[i] = h;
            i += 1;
        }
        let mut j = 0;
        while j < capacity_s {
            let (e, h) = if j < ns {
                secondary[j]
            } else if ns > 0 {
                secondary[ns - 1]
            } else if np > 0 {
                (primary[np - 1].0, primary[np - 1].2)
            } else {
                (0, Hit::Filter(0))
            };
            self.elements[capacity_p + j] = e;
            self.hits[capacity_p + j] = h;
            j += 1;
        }
        // The keys a lookup element receives.
        let k = keys.keys();
        let u = keys.users();
        let mut needed = 0;
        let mut pass = 0;
        while pass < 2 {
            let mut x = 0;
            while x < k.len() {
                let (id, ext, rtr) = key_parts(k[x]);
                if let Some(e) = self.first_hit(frame_word(id, ext, rtr)) {
                    if matches!(self.hits[e], Hit::Lookup) {
                        if pass == 0 {
                            needed += 1;
                        } else {
                            // Counted in the first pass: room for each.
                            let _ = self.keys.insert(k[x], u[x]);
                        }
                    }
                }
                x += 1;
            }
            if pass == 0 && needed > K {
                return Err(PlanError::TooManyLookupKeys {
                    needed: needed as u16,
                    max: if K > u16::MAX as usize {
                        u16::MAX
                    } else {
                        K as u16
                    },
                });
            }
            pass += 1;
        }
        Ok(())
    }

    /// The element the hardware hits for a frame compared as `word` (format A, the
    /// first element whose masked bits agree; Kinetis RM "Rx FIFO structure"), `None`
    /// when it is rejected.
    pub const fn first_hit(&self, word: u32) -> Option<usize> {
        if self.reject_all {
            return None;
        }
        let p = Self::primary_of(self.configuration);
        let n = Self::elements_of(self.configuration);
        let mut i = 0;
        while i < n {
            let m = if i < p {
                self.individual_masks[i]
            } else {
                self.global_mask
            };
            if (word ^ self.elements[i]) & m == 0 {
                return Some(i);
            }
            i += 1;
        }
        None
    }

    /// Identifiers the hardware accepts beyond the user's filters (0 unless the table
    /// was planned in superset mode); the driver drops those frames
    /// ([`FilterTable::filter_index`] gives `None`).
    pub const fn superset_extra(&self) -> u64 {
        self.extra
    }

    /// Of `traffic` (frames with a weight each, e.g. their rate on the bus), the weight
    /// the hardware accepts and the weight the driver then drops (accepted by a superset
    /// element only): `(accepted, dropped)`; the expected software drop rate is their
    /// ratio.
    pub fn drop_weight<'a>(
        &self,
        traffic: impl IntoIterator<Item = (&'a Frame, u64)>,
    ) -> (u64, u64) {
        let (mut accepted, mut dropped) = (0, 0);
        for (frame, w) in traffic {
            if let Some((_, index)) = self.evaluate(frame) {
                accepted += w;
                if index.is_none() {
                    dropped += w;
                }
            }
        }
        (accepted, dropped)
    }

    /// The hardware's decision for a frame (format A, first element whose masked bits
    /// agree; Kinetis RM "Rx FIFO structure") and the resolved user index:
    /// `Some((IDHIT, index))`, index `None` for a frame a superset table accepts that no
    /// user filter does. `None`: the frame is rejected.
    pub fn evaluate(&self, frame: &Frame) -> Option<(usize, Option<u16>)> {
        let word = frame_word(frame.raw_id(), frame.is_extended(), frame.is_remote());
        let hit = self.first_hit(word)?;
        Some((hit, self.filter_index(hit, frame)))
    }

    /// The lookup keys it needs and its table's size: the sizes of its
    /// [`SizedTable`].
    pub const fn sizes(&self) -> TableSizes {
        TableSizes {
            elements: Self::elements_of(self.configuration),
            primary: Self::primary_of(self.configuration),
            keys: self.keys.len(),
        }
    }

    /// The same planned table in a [`SizedTable`] of exactly its elements and lookup
    /// keys (sizes from [`FilterTable::sizes`]; other sizes, or a table with secondary
    /// filters found in software ([`Hit::ScanSecondary`], a compiled ACAN list), panic
    /// — in `const` code, a compile-time error). See [`crate::const_plan!`].
    pub const fn sized<const E: usize, const P: usize, const KEYS: usize>(
        &self,
    ) -> SizedTable<E, P, KEYS> {
        let s = self.sizes();
        if s.elements != E || s.primary != P || s.keys != KEYS {
            panic!("SizedTable sizes differ from the table's (use FilterTable::sizes)");
        }
        if self.secondary_count != 0 {
            panic!("a table with ACAN secondary filters has no SizedTable");
        }
        let mut out = SizedTable {
            configuration: self.configuration,
            elements: [0; E],
            individual_masks: [0; P],
            global_mask: self.global_mask,
            hits: [Hit::Filter(0); E],
            keys: [0; KEYS],
            key_users: [0; KEYS],
            extra: self.extra,
            reject_all: self.reject_all,
        };
        let mut i = 0;
        while i < E {
            out.elements[i] = self.elements[i];
            out.hits[i] = self.hits[i];
            i += 1;
        }
        let mut i = 0;
        while i < P {
            out.individual_masks[i] = self.individual_masks[i];
            i += 1;
        }
        let (k, u) = (self.keys.keys(), self.keys.users());
        let mut i = 0;
        while i < KEYS {
            out.keys[i] = k[i];
            out.key_users[i] = u[i];
            i += 1;
        }
        out
    }

    /// The driver's table for a `const` [`SizedTable`] (for the split driver's
    /// `set_filters`; about 1 KB by value).
    ///
    /// Errors: [`PlanError::TooManyLookupKeys`] when it needs more lookup keys than `K`,
    /// [`PlanError::ConfigurationTooLarge`] when its table is larger than this type holds.
    pub const fn from_sized<const E: usize, const P: usize, const K2: usize>(
        t: &SizedTable<E, P, K2>,
    ) -> Result<Self, PlanError> {
        if !Self::holds(t.configuration) {
            return Err(PlanError::ConfigurationTooLarge {
                rffn: t.configuration.rffn(),
                max_rffn: Self::MAX_RFFN,
            });
        }
        let mut out = Self::zeroed();
        out.configuration = t.configuration;
        out.individual_masks = [FULL_MASK; PRIM];
        out.secondary = [Filter::pass_all(); SEC];
        out.global_mask = t.global_mask;
        out.extra = t.extra;
        out.reject_all = t.reject_all;
        let mut i = 0;
        while i < E {
            out.elements[i] = t.elements[i];
            out.hits[i] = t.hits[i];
            i += 1;
        }
        let mut i = 0;
        while i < P {
            out.individual_masks[i] = t.individual_masks[i];
            i += 1;
        }
        // The primary filters' count is not kept by a sized table (only ACAN's
        // secondary numbering uses it, which a planned table has none of).
        out.primary_count = P as u8;
        if out.keys.copy_from(&t.keys, &t.key_users).is_err() {
            return Err(PlanError::TooManyLookupKeys {
                needed: K2 as u16,
                max: K as u16,
            });
        }
        Ok(out)
    }
}

/// The sizes of a planned table: its elements, its primary (individual-mask) elements
/// and the lookup keys it needs (the const parameters of its [`SizedTable`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TableSizes {
    /// Table elements (`8 × (RFFN + 1)`).
    pub elements: usize,
    /// Primary elements (individual masks).
    pub primary: usize,
    /// Lookup keys needed.
    pub keys: usize,
}

/// A planned table sized to itself: the `E` elements and `P` individual masks of its
/// configuration, the global mask, what a hit on each element means (the map from
/// `RXFIR.IDHIT` back to the user's filter) and exactly the `K` lookup keys its merged
/// or superset elements need — what [`crate::const_plan!`] gives for a `const` filter
/// list. The split driver's `set_filters` takes a [`FilterTable`]
/// ([`FilterTable::from_sized`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SizedTable<const E: usize, const P: usize, const K: usize> {
    configuration: Configuration,
    elements: [u32; E],
    individual_masks: [u32; P],
    global_mask: u32,
    hits: [Hit; E],
    keys: [Key; K],
    key_users: [u16; K],
    extra: u64,
    reject_all: bool,
}

impl<const E: usize, const P: usize, const K: usize> SizedTable<E, P, K> {
    /// The configuration the table is planned for.
    pub const fn configuration(&self) -> Configuration {
        self.configuration
    }

    /// The table elements, in hardware order.
    pub const fn elements(&self) -> &[u32; E] {
        &self.elements
    }

    /// The individual masks `RXIMR0…`.
    pub const fn individual_masks(&self) -> &[u32; P] {
        &self.individual_masks
    }

    /// The global mask `RXFGMASK`.
    pub const fn global_mask(&self) -> u32 {
        self.global_mask
    }

    /// What a hit on each element means.
    pub const fn hits(&self) -> &[Hit; E] {
        &self.hits
    }

    /// Whether the table accepts no frame (format D).
    pub const fn rejects_all(&self) -> bool {
        self.reject_all
    }

    /// The lookup keys (ascending) and their user indices.
    pub const fn lookup_keys(&self) -> (&[Key; K], &[u16; K]) {
        (&self.keys, &self.key_users)
    }

    /// See [`FilterTable::superset_extra`].
    pub const fn superset_extra(&self) -> u64 {
        self.extra
    }

    /// The user's filter index for a frame the hardware accepted with `RXFIR.IDHIT` =
    /// `element` (see [`FilterTable::filter_index`]).
    pub const fn filter_index(&self, element: usize, frame: &Frame) -> Option<u16> {
        if element >= E {
            return None;
        }
        match self.hits[element] {
            Hit::Filter(i) => Some(i),
            Hit::Lookup => {
                let k = key(frame.raw_id(), frame.is_extended(), frame.is_remote());
                let at = lower_bound(&self.keys, k);
                if at < K && self.keys[at] == k {
                    Some(self.key_users[at])
                } else {
                    None
                }
            }
            // Never planned.
            Hit::ScanSecondary => None,
        }
    }

    /// See [`FilterTable::evaluate`].
    pub const fn evaluate(&self, frame: &Frame) -> Option<(usize, Option<u16>)> {
        if self.reject_all {
            return None;
        }
        let word = frame_word(frame.raw_id(), frame.is_extended(), frame.is_remote());
        let mut i = 0;
        while i < E {
            let m = if i < P {
                self.individual_masks[i]
            } else {
                self.global_mask
            };
            if (word ^ self.elements[i]) & m == 0 {
                return Some((i, self.filter_index(i, frame)));
            }
            i += 1;
        }
        None
    }
}

/// The filter index of a received frame whose `RXFIR.IDHIT` does not map back to any
/// of the user's filters ([`FilterTable::filter_index`] gives `None`): distinct from
/// every real index (a list has at most a few hundred filters). The controller counts
/// such frames ([`crate::FlexCanHw::unresolved_filter_hits`]); a
/// [`twocan_core::Dispatcher`] counts them as unhandled.
pub const UNKNOWN_FILTER: u16 = u16::MAX;

#[cfg(test)]
mod tests {
    use super::*;
    use twocan_core::frame::standard_id;

    fn d_ext(id: u32) -> Filter {
        Filter::exact(FrameKind::Data, Format::Extended, id)
    }
    fn d_std(id: u32) -> Filter {
        Filter::exact(FrameKind::Data, Format::Standard, id)
    }
    fn r_std(id: u32) -> Filter {
        Filter::exact(FrameKind::Remote, Format::Standard, id)
    }

    /// The hardware's rule on a compiled table: first element whose masked bits agree.
    fn hw_match(t: &FilterTable, frame: &Frame) -> Option<usize> {
        if t.rejects_all() {
            return None; // format D
        }
        let word = if frame.is_extended() {
            ELEMENT_IDE | frame.raw_id() << ELEMENT_EXT_SHIFT
        } else {
            frame.raw_id() << ELEMENT_STD_SHIFT
        } | if frame.is_remote() { ELEMENT_RTR } else { 0 };
        let p = t.configuration().primary_filter_capacity();
        t.elements().iter().enumerate().position(|(i, e)| {
            let m = if i < p {
                t.individual_masks()[i]
            } else {
                t.global_mask()
            };
            (word ^ e) & m == 0
        })
    }

    fn reference(primary: &[Filter], secondary: &[Filter], frame: &Frame) -> Option<u16> {
        primary
            .iter()
            .chain(secondary)
            .position(|f| f.matches(frame))
            .map(|i| i as u16)
    }

    fn frames() -> impl Iterator<Item = Frame> {
        let ids = [0u32, 1, 0x234, 0x540, 0x541, 0x542, 0x543, 0x544, 0x7FF];
        let ext = [
            0u32,
            0x234,
            0x542,
            0x123456,
            0x123457,
            0x1FFF_FFFF,
            0x234 << 18,
        ];
        let std_frames = ids.into_iter().flat_map(|id| {
            [
                Frame::standard(id as u16, &[1]).unwrap(),
                Frame::remote(id, false, 0).unwrap(),
            ]
        });
        let ext_frames = ext.into_iter().flat_map(|id| {
            [
                Frame::extended(id, &[1]).unwrap(),
                Frame::remote(id, true, 0).unwrap(),
            ]
        });
        std_frames.chain(ext_frames)
    }

    fn agrees(c: Configuration, primary: &[Filter], secondary: &[Filter]) {
        let t = FilterTable::compile(c, primary, secondary).unwrap();
        for frame in frames() {
            let want = reference(primary, secondary, &frame);
            let got = hw_match(&t, &frame).and_then(|e| t.filter_index(e, &frame));
            assert_eq!(got, want, "{c:?} {frame:?}");
        }
    }

    #[test]
    fn compiled_tables_agree_with_reference_semantics() {
        let lists: [(&[Filter], &[Filter]); 9] = [
            (&[], &[]),
            (&[d_ext(0x123456), d_std(0x234), r_std(0x542)], &[]),
            (
                &[d_ext(0x123456), d_std(0x234), r_std(0x542), d_std(0x234)],
                &[],
            ),
            (
                &[
                    d_ext(0x123456),
                    d_std(0x234),
                    Filter::pass_all(),
                    r_std(0x542),
                ],
                &[],
            ),
            (&[], &[d_ext(0x123456), d_std(0x234), r_std(0x542)]),
            (&[d_ext(0x123456)], &[d_std(0x234), r_std(0x542)]),
            (
                &[],
                &[
                    d_ext(0x123456),
                    d_std(0x234),
                    r_std(0x542),
                    Filter::pass_all(),
                ],
            ),
            (
                &[d_std(0x234)],
                &[d_std(0x234), Filter::pass_all(), r_std(0x542)],
            ),
            (
                &[Filter::masked(
                    FrameKind::Data,
                    Format::Standard,
                    0x7FC,
                    0x540,
                )],
                &[d_std(0x540), r_std(0x7FF), Filter::extended(0x234 << 18)],
            ),
        ];
        for c in Configuration::ALL {
            for (p, s) in lists {
                if s.len() <= c.secondary_filter_capacity() {
                    agrees(c, p, s);
                }
            }
        }
    }

    #[test]
    fn every_error_at_once() {
        let bad_primary = Filter::masked(FrameKind::Data, Format::Standard, 0x7FC, 0x541);
        let bad_secondary = Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, 0x540);
        let primary = [bad_primary; 9];
        let secondary = [bad_secondary];
        let e = FilterTable::compile(Configuration::Filters8_0, &primary, &secondary).unwrap_err();
        assert_eq!(
            e,
            ConfigErrors::TOO_MANY_PRIMARY_FILTERS
                | ConfigErrors::PRIMARY_FILTER_NOT_CONFORM
                | ConfigErrors::TOO_MANY_SECONDARY_FILTERS
                | ConfigErrors::SECONDARY_FILTER_NOT_CONFORM
        );
        // A kind-any exact filter is no secondary filter, but is a fine primary one.
        let any = Filter::exact(FrameKind::Any, Format::Standard, 5);
        assert!(!secondary_conforms(&any));
        assert!(FilterTable::compile(Configuration::Filters12_12, &[any], &[]).is_ok());
    }

    #[test]
    fn numbering_and_masks() {
        let t = FilterTable::compile(
            Configuration::Filters12_12,
            &[d_ext(0x123456)],
            &[d_std(0x234)],
        )
        .unwrap();
        assert_eq!(t.elements().len(), 24);
        assert_eq!(t.individual_masks().len(), 12);
        assert_eq!(t.elements()[0], ELEMENT_IDE | 0x123456 << 1);
        assert_eq!(t.individual_masks()[0], FULL_MASK);
        assert_eq!(t.elements()[12], 0x234 << 19);
        assert_eq!(t.hit(12), Some(Hit::Filter(1)));
        assert_eq!(t.hit(24), None);
        let remote = Frame::new_remote(standard_id(0x234).unwrap(), 0).unwrap();
        // An IDHIT beyond the table is no filter 0: no index at all.
        assert_eq!(t.filter_index(99, &remote), None);
        assert_eq!(t.filter_index(24, &remote), None);
        let data = Frame::new_data(standard_id(0x234).unwrap(), &[]).unwrap();
        assert_eq!(t.filter_index(12, &data), Some(1));
    }
}
