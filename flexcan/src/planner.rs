//! The FlexCAN filter planner: portable [`Filter`]s → the Rx FIFO ID filter table of a
//! [`Configuration`], primary and secondary elements placed automatically, identifiers
//! merged into exact mask elements, with a superset fallback.
//!
//! Hardware facts used (Kinetis reference manuals, FlexCAN "Rx FIFO structure" and
//! `RXIMRn`/`RXFGMASK`; ACAN §11–§13): table format A, elements examined in order, the
//! first whose masked bits agree is reported (`RXFIR.IDHIT`); the first
//! `primary_filter_capacity()` elements are compared under their own mask `RXIMRn`
//! ("primary"), the others under the one global mask `RXFGMASK` ("secondary").
//!
//! # Algorithm
//!
//! 1. Check and narrow the list by first-match semantics
//!    ([`twocan_core::filter_set::narrow`]); split it into *keys* (filters of whole
//!    identifiers: one format, one or both kinds) and *general* filters.
//! 2. Cover the keys by exact cubes ([`twocan_core::filter_set::exact_cover`]; a block
//!    of two identifiers already saves an element) — covers tried: no merging, greedy
//!    with blocks of two or more, greedy with blocks of three or more, and the fewest
//!    cubes by branch and bound ([`twocan_core::filter_set::min_cover`], up to
//!    [`COVER_SEARCH_KEYS`] keys and [`COVER_BUDGET`] nodes); each also with blocks
//!    split back into single keys while secondary elements are free.
//! 3. Place: general filters and blocks take primary elements (a mask each); single
//!    keys take the secondary elements (global mask comparing everything, or only the
//!    standard identifier bits when every secondary key is standard), except keys that
//!    overlap a general filter, which must come before it and so are primary. Primary
//!    elements are laid out in user order (a block at its first key's index): a frame's
//!    first matching user filter is hit first, as ACAN §12.5 requires.
//! 4. The cover that needs the fewest primary elements is kept; if it needs more than
//!    the configuration has, superset mode ([`PlanOptions::superset`]) merges cubes
//!    pairwise ([`twocan_core::filter_set::merge_step`], the join adding the fewest
//!    identifiers, never meeting a general filter) until it fits; otherwise the plan is
//!    refused with the counts ([`PlanError::TooManyPrimary`]).
//! 5. "Choose the configuration for me" ([`PlanOptions::configuration`] = `None`): the
//!    smallest table that fits exactly (the most remote-frame mailboxes left, ACAN §9);
//!    in superset mode, if none fits, the configuration with the fewest extra
//!    identifiers.
//!
//! The thread side resolves a frame's index with [`FilterTable::filter_index`] (a
//! table lookup, or a binary search for a merged or superset element).

//!
//! # Lookup capacity
//!
//! A merged or superset element standing for several user filters ([`Hit::Lookup`])
//! leaves its frames' user indices to a binary search in the table's lookup keys, at
//! most `K` of them ([`FilterTable<K>`], [`LOOKUP_KEYS`] by default). When the cover
//! with the fewest primary elements would need more, its multi-user blocks are split
//! ([`twocan_core::filter_set::split_multi_user_blocks`]) and the covers tried again;
//! if no placement within the capacity fits, the list is refused with both counts
//! ([`PlanError::TooManyLookupKeys`]).
//!
//! # At compile time and at run time
//!
//! Every step is a `const fn` with its working memory in a [`Scratch`]: [`plan`] (and
//! [`crate::const_plan!`], which keeps only what the table needs) for `const` lists,
//! [`plan_in`] with the scratch in a `static` for lists known at run time.

use twocan_core::filter_set::{
    exact_cover, keys_of, meets_any, merge_step, min_cover, narrow, split_multi_user_blocks,
    CoverScratch, Cube, CubeList, KeyTable,
};
use twocan_core::{Filter, FilterError, Format, FrameKind};

use crate::configuration::{Configuration, MAX_PRIMARY_FILTERS, MAX_SECONDARY_FILTERS};
use crate::filters::{
    element_of, mask_of, FilterTable, Hit, PlannedPrimary, TableSizes, ELEMENT_IDE, ELEMENT_RTR,
    ELEMENT_STD_SHIFT, FULL_MASK, LOOKUP_KEYS, MAX_LOOKUP_KEYS,
};

/// The largest user filter list the planner takes.
pub const MAX_FILTERS: usize = 512;

/// Planner options.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlanOptions {
    /// The configuration to plan for, or `None`: choose it (see the module notes).
    pub configuration: Option<Configuration>,
    /// Merge identifiers into exact mask elements (default `true`).
    pub merge: bool,
    /// When the exact plan does not fit, accept a superset in hardware and drop the
    /// extra frames in the driver (default `false`).
    pub superset: bool,
}

impl Default for PlanOptions {
    /// Choose the configuration, merging, no superset.
    fn default() -> Self {
        Self::choose()
    }
}

impl PlanOptions {
    /// Plan for `configuration`, merging, no superset.
    pub const fn new(configuration: Configuration) -> Self {
        PlanOptions {
            configuration: Some(configuration),
            merge: true,
            superset: false,
        }
    }

    /// Choose the configuration (the default, usable in `const` code), merging, no
    /// superset.
    pub const fn choose() -> Self {
        PlanOptions {
            configuration: None,
            merge: true,
            superset: false,
        }
    }

    /// The same options with merging on or off.
    pub const fn merge(self, merge: bool) -> Self {
        PlanOptions { merge, ..self }
    }

    /// The same options with the superset fallback on or off.
    pub const fn superset(self, superset: bool) -> Self {
        PlanOptions { superset, ..self }
    }
}

/// Why a list could not be planned.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlanError {
    /// A user filter does not conform.
    Filter {
        /// Its index in the user's list.
        index: u16,
        /// Why.
        error: FilterError,
    },
    /// More filters than the planner takes.
    TooManyFilters {
        /// Filters given.
        given: u16,
        /// The most the planner takes ([`MAX_FILTERS`]).
        max: u16,
    },
    /// The list needs more primary (individual-mask) elements than the configuration
    /// has, with its secondary elements full (for "choose for me": of the largest
    /// configuration, 14/18).
    TooManyPrimary {
        /// Primary elements the best exact placement needs.
        needed: u16,
        /// Primary elements of the configuration.
        available: u8,
        /// Secondary elements of the configuration (all used).
        secondary: u8,
    },
    /// Every placement that fits leaves more identifiers to the thread-side lookup than
    /// the table keeps (`K` of [`FilterTable<K>`], [`LOOKUP_KEYS`] by default).
    TooManyLookupKeys {
        /// Identifiers the best placement would look up.
        needed: u16,
        /// The lookup capacity.
        max: u16,
    },
    /// The configuration asked for has a larger ID filter table than the table type
    /// holds ([`FilterTable::MAX_RFFN`]: RFFN 3 for ACAN's sizes, 0xF for
    /// [`crate::LargeFilterTable`], the RT1062 layout's).
    ConfigurationTooLarge {
        /// `CTRL2[RFFN]` of the configuration asked for.
        rffn: u8,
        /// The largest the table holds.
        max_rffn: u8,
    },
}

impl core::fmt::Display for PlanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PlanError::Filter { index, .. } => write!(f, "filter {index} does not conform"),
            PlanError::TooManyFilters { given, max } => {
                write!(f, "{given} filters given, the planner takes at most {max}")
            }
            PlanError::TooManyPrimary {
                needed,
                available,
                secondary,
            } => write!(
                f,
                "the filters need {needed} primary filter elements, the configuration has \
                 {available} (and {secondary} secondary, all used)"
            ),
            PlanError::TooManyLookupKeys { needed, max } => write!(
                f,
                "the table needs {needed} lookup keys for its merged elements, it keeps {max}"
            ),
            PlanError::ConfigurationTooLarge { rffn, max_rffn } => write!(
                f,
                "the configuration's table (RFFN {rffn}) is larger than the table holds \
                 (RFFN {max_rffn} at most)"
            ),
        }
    }
}

impl core::error::Error for PlanError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            PlanError::Filter { error, .. } => Some(error),
            _ => None,
        }
    }
}

impl From<PlanError> for twocan_core::Error {
    /// Keeps the counts ([`twocan_core::Error::FilterSpace`]: primary elements or lookup
    /// keys needed and available, or filters given and the most taken).
    fn from(e: PlanError) -> Self {
        match e {
            PlanError::Filter { error, .. } => twocan_core::Error::Filter(error),
            PlanError::TooManyFilters { given, max } => twocan_core::Error::FilterSpace {
                needed: given,
                available: max,
            },
            PlanError::TooManyPrimary {
                needed, available, ..
            } => twocan_core::Error::FilterSpace {
                needed,
                available: available as u16,
            },
            PlanError::TooManyLookupKeys { needed, max } => twocan_core::Error::FilterSpace {
                needed,
                available: max,
            },
            PlanError::ConfigurationTooLarge { .. } => twocan_core::Error::InvalidArgument,
        }
    }
}

/// A message built in `const` code (for a compile-time error that names the counts).
struct Message {
    buf: [u8; 160],
    len: usize,
}

impl Message {
    const fn new() -> Self {
        Message {
            buf: [0; 160],
            len: 0,
        }
    }

    const fn text(mut self, s: &str) -> Self {
        let b = s.as_bytes();
        let mut i = 0;
        while i < b.len() && self.len < self.buf.len() {
            self.buf[self.len] = b[i];
            self.len += 1;
            i += 1;
        }
        self
    }

    const fn number(mut self, mut n: u32) -> Self {
        let mut digits = [0u8; 10];
        let mut k = 0;
        loop {
            digits[k] = b'0' + (n % 10) as u8;
            k += 1;
            n /= 10;
            if n == 0 {
                break;
            }
        }
        while k > 0 && self.len < self.buf.len() {
            k -= 1;
            self.buf[self.len] = digits[k];
            self.len += 1;
        }
        self
    }

    const fn as_str(&self) -> &str {
        match core::str::from_utf8(self.buf.split_at(self.len).0) {
            Ok(s) => s,
            Err(_) => "twocan_flexcan::const_plan!: the filters cannot be planned",
        }
    }
}

impl PlanError {
    /// Panics with a message naming the error and its counts: in `const` code (as in
    /// [`crate::const_plan!`]) a compile-time error that says why the list cannot be
    /// planned.
    pub const fn panic(self) -> ! {
        let m = Message::new().text("twocan_flexcan::const_plan!: ");
        let m = match self {
            PlanError::Filter { index, error } => m
                .text("filter ")
                .number(index as u32)
                .text(" does not conform: ")
                .text(match error {
                    FilterError::IdOutOfRange => "the identifier is wider than its format",
                    FilterError::MaskOutOfRange => "the mask is wider than the format",
                    FilterError::AcceptanceOutsideMask => {
                        "the acceptance value has bits outside the mask"
                    }
                    FilterError::AnyFormatWithIdentifier => "Format::Any with a non-zero mask",
                }),
            PlanError::TooManyFilters { given, max } => m
                .number(given as u32)
                .text(" filters given, the planner takes at most ")
                .number(max as u32),
            PlanError::TooManyPrimary {
                needed,
                available,
                secondary,
            } => m
                .text("the filters need ")
                .number(needed as u32)
                .text(" primary filter elements, the configuration has ")
                .number(available as u32)
                .text(" (and ")
                .number(secondary as u32)
                .text(" secondary, all used)"),
            PlanError::TooManyLookupKeys { needed, max } => m
                .text("the table needs ")
                .number(needed as u32)
                .text(" lookup keys, the capacity is ")
                .number(max as u32),
            PlanError::ConfigurationTooLarge { rffn, max_rffn } => m
                .text("the configuration's table (RFFN ")
                .number(rffn as u32)
                .text(") is larger than the table holds (RFFN ")
                .number(max_rffn as u32)
                .text(" at most)"),
        };
        panic!("{}", m.as_str())
    }
}

/// A filter with every field zero: the content of a fresh scratch.
const ZERO_FILTER: Filter = Filter {
    kind: FrameKind::Data,
    format: Format::Standard,
    id: 0,
    mask: 0,
};

/// Step 1: the checked, narrowed list split into general filters and keys.
struct Prepared {
    general: [Filter; MAX_FILTERS],
    general_users: [u16; MAX_FILTERS],
    n_general: usize,
    keys: KeyTable,
}

impl Prepared {
    const ZERO: Prepared = Prepared {
        general: [ZERO_FILTER; MAX_FILTERS],
        general_users: [0; MAX_FILTERS],
        n_general: 0,
        keys: KeyTable::new(),
    };

    const fn fill(&mut self, list: &[Filter]) -> Result<(), PlanError> {
        self.n_general = 0;
        self.keys.clear();
        if list.len() > MAX_FILTERS {
            return Err(PlanError::TooManyFilters {
                given: if list.len() > u16::MAX as usize {
                    u16::MAX
                } else {
                    list.len() as u16
                },
                max: MAX_FILTERS as u16,
            });
        }
        let mut i = 0;
        while i < list.len() {
            if let Err(error) = list[i].check() {
                return Err(PlanError::Filter {
                    index: i as u16,
                    error,
                });
            }
            i += 1;
        }
        // No filter receives nothing (unlike ACAN §4): an empty table, format D.
        let mut i = 0;
        while i < list.len() {
            if let Some(g) = narrow(list[i], list.split_at(i).0) {
                match keys_of(&g) {
                    Some((keys, n)) => {
                        let mut j = 0;
                        while j < n {
                            // At most 2 × MAX_FILTERS = MAX_KEYS keys.
                            let _ = self.keys.insert(keys[j], i as u16);
                            j += 1;
                        }
                    }
                    None => {
                        self.general[self.n_general] = g;
                        self.general_users[self.n_general] = i as u16;
                        self.n_general += 1;
                    }
                }
            }
            i += 1;
        }
        Ok(())
    }

    const fn general(&self) -> &[Filter] {
        self.general.split_at(self.n_general).0
    }

    /// Whether a key or cube must be primary (it overlaps a general filter).
    const fn must_be_primary(&self, c: &Cube) -> bool {
        meets_any(c, self.general())
    }

    /// Whether a single key may take a secondary element.
    const fn secondary_eligible(&self, c: &Cube) -> bool {
        !c.is_block() && self.keys.count_in(c) == 1 && !self.must_be_primary(c)
    }
}

/// Nodes of the minimum-cover search ([`min_cover`]).
pub const COVER_BUDGET: u32 = 20_000;

/// Keys up to which the minimum-cover search runs (its search stack is as deep as the
/// keys it covers one by one).
pub const COVER_SEARCH_KEYS: usize = 256;

/// Primary elements a cover needs once the secondary elements are full.
const fn need(prep: &Prepared, cubes: &CubeList, capacity_s: usize) -> usize {
    let mut primary = prep.n_general;
    let mut singles = 0;
    let mut i = 0;
    while i < cubes.len() {
        let c = cubes.get(i);
        if c.is_block() || prep.must_be_primary(&c) || prep.keys.count_in(&c) != c.size() {
            primary += 1;
        } else {
            singles += 1;
        }
        i += 1;
    }
    primary + singles
        - if singles < capacity_s {
            singles
        } else {
            capacity_s
        }
}

/// One primary element while placing: (position in user order, element, mask, hit).
type Primary = (u16, u32, u32, Hit);

/// Working memory of [`place`], for a table of `PRIM` primary and `SEC` secondary
/// elements at most.
struct PlaceScratch<const PRIM: usize, const SEC: usize> {
    primary: [Primary; PRIM],
    planned: [PlannedPrimary; PRIM],
    secondary: [(u32, Hit); SEC],
}

impl<const PRIM: usize, const SEC: usize> PlaceScratch<PRIM, SEC> {
    const ZERO: Self = PlaceScratch {
        primary: [(0, 0, 0, Hit::Filter(0)); PRIM],
        planned: [(0, 0, Hit::Filter(0)); PRIM],
        secondary: [(0, Hit::Filter(0)); SEC],
    };
}

/// Step 3: the table of a cover that fits `configuration`, into `out`.
const fn place<const K: usize, const ELEMS: usize, const PRIM: usize, const SEC: usize>(
    prep: &Prepared,
    cubes: &CubeList,
    configuration: Configuration,
    extra: u64,
    ps: &mut PlaceScratch<PRIM, SEC>,
    out: &mut FilterTable<K, ELEMS, PRIM, SEC>,
) -> Result<(), PlanError> {
    let capacity_s = FilterTable::<K, ELEMS, PRIM, SEC>::secondary_of(configuration);
    let mut np = 0;
    let mut ns = 0;
    let mut all_std = true;
    let mut g = 0;
    while g < prep.n_general {
        let f = prep.general[g];
        let u = prep.general_users[g];
        ps.primary[np] = (u, element_of(&f), mask_of(&f), Hit::Filter(u));
        np += 1;
        g += 1;
    }
    let mut i = 0;
    while i < cubes.len() {
        let c = cubes.get(i);
        i += 1;
        let exact = prep.keys.count_in(&c) == c.size();
        let user = match prep.keys.first_user(&c) {
            Some(u) => u,
            None => 0,
        };
        let hit = match (exact, prep.keys.single_user(&c)) {
            (true, Some(u)) => Hit::Filter(u),
            _ => Hit::Lookup,
        };
        let f = c.filter();
        if !c.is_block() && exact && !prep.must_be_primary(&c) && ns < capacity_s {
            ps.secondary[ns] = (element_of(&f), hit);
            all_std &= matches!(f.format, Format::Standard);
            ns += 1;
        } else {
            ps.primary[np] = (user, element_of(&f), mask_of(&f), hit);
            np += 1;
        }
    }
    // In user order (a block at its first key's index): insertion sort, stable.
    let mut i = 1;
    while i < np {
        let x = ps.primary[i];
        let mut j = i;
        while j > 0
            && (x.0 < ps.primary[j - 1].0
                || (x.0 == ps.primary[j - 1].0 && x.1 < ps.primary[j - 1].1))
        {
            ps.primary[j] = ps.primary[j - 1];
            j -= 1;
        }
        ps.primary[j] = x;
        i += 1;
    }
    let mut i = 0;
    while i < np {
        ps.planned[i] = (ps.primary[i].1, ps.primary[i].2, ps.primary[i].3);
        i += 1;
    }
    let global_mask = if all_std {
        ELEMENT_RTR | ELEMENT_IDE | (0x7FF << ELEMENT_STD_SHIFT)
    } else {
        FULL_MASK
    };
    out.set_planned(
        configuration,
        ps.planned.split_at(np).0,
        ps.secondary.split_at(ns).0,
        global_mask,
        &prep.keys,
        extra,
    )
}

/// `cubes` with blocks split back into single keys while the secondary elements have
/// room for them, smallest blocks first: a block of `k` keys costs one primary element,
/// its keys cost none while `k` secondary elements are free. In place.
const fn tune(prep: &Prepared, cubes: &mut CubeList, capacity_s: usize) {
    let mut singles = 0;
    let mut i = 0;
    while i < cubes.len() {
        if prep.secondary_eligible(&cubes.get(i)) {
            singles += 1;
        }
        i += 1;
    }
    let mut free = capacity_s.saturating_sub(singles);
    let keys = prep.keys.keys();
    loop {
        // The block whose keys covered by no other cube are fewest (and fit).
        let mut pick: Option<(usize, usize)> = None;
        let mut i = 0;
        while i < cubes.len() {
            let c = cubes.get(i);
            if c.is_block() && prep.keys.count_in(&c) == c.size() {
                let mut own = 0;
                let mut ok = true;
                let (mut x, end) = prep.keys.span(&c);
                while x < end {
                    let k = keys[x];
                    if c.contains(k) {
                        let mut other = false;
                        let mut j = 0;
                        while j < cubes.len() {
                            if j != i && cubes.get(j).contains(k) {
                                other = true;
                                break;
                            }
                            j += 1;
                        }
                        if !other {
                            own += 1;
                            ok &= prep.secondary_eligible(&Cube::single(k));
                        }
                    }
                    x += 1;
                }
                let fewer = match pick {
                    None => true,
                    Some((_, n)) => own < n,
                };
                if ok && own <= free && fewer {
                    pick = Some((i, own));
                }
            }
            i += 1;
        }
        let (i, own) = match pick {
            Some(p) => p,
            None => return,
        };
        let c = cubes.get(i);
        cubes.remove(i);
        let (mut x, end) = prep.keys.span(&c);
        while x < end {
            let k = keys[x];
            if c.contains(k) {
                let mut other = false;
                let mut j = 0;
                while j < cubes.len() {
                    if cubes.get(j).contains(k) {
                        other = true;
                        break;
                    }
                    j += 1;
                }
                if !other {
                    // Room: the list only trades a block for its own keys.
                    let _ = cubes.push(Cube::single(k));
                }
            }
            x += 1;
        }
        free -= own;
    }
}

/// The working memory of [`plan_in`] (about 70 KB, every field zero when new: a
/// `static` of it takes RAM but no flash) and its result, a [`FilterTable<K>`].
///
/// A firmware that plans at run time keeps it in a `static` place it owns (an RTIC
/// `#[local]` resource, a `cortex_m::singleton!`, any static cell lending `&mut` to one
/// context at a time); the planning call then needs a small stack frame.
///
/// The table's sizes are those of [`FilterTable`]'s parameters (ACAN's by default;
/// `Scratch<K, 128, 32, 96>` plans for the RT1062 layout's [`crate::LargeFilterTable`]).
pub struct Scratch<
    const K: usize = LOOKUP_KEYS,
    const ELEMS: usize = { crate::configuration::MAX_TABLE_ELEMENTS },
    const PRIM: usize = MAX_PRIMARY_FILTERS,
    const SEC: usize = MAX_SECONDARY_FILTERS,
> {
    prep: Prepared,
    /// The merged covers: greedy with blocks of two or more, greedy with blocks of
    /// three or more, and the fewest cubes (the list of singles is made on demand).
    covers: [CubeList; 3],
    /// Merged covers in `covers` (0 without merging, 2 when the search found nothing
    /// lighter).
    n_covers: usize,
    best: CubeList,
    cand: CubeList,
    cover: CoverScratch,
    place: PlaceScratch<PRIM, SEC>,
    tables: [FilterTable<K, ELEMS, PRIM, SEC>; 2],
    /// The table of the last successful plan.
    result: usize,
}

impl<const K: usize, const ELEMS: usize, const PRIM: usize, const SEC: usize> Default
    for Scratch<K, ELEMS, PRIM, SEC>
{
    fn default() -> Self {
        Self::new()
    }
}

impl<const K: usize, const ELEMS: usize, const PRIM: usize, const SEC: usize>
    Scratch<K, ELEMS, PRIM, SEC>
{
    /// Fresh working memory (all zeros).
    pub const fn new() -> Self {
        Scratch {
            prep: Prepared::ZERO,
            covers: [CubeList::new(), CubeList::new(), CubeList::new()],
            n_covers: 0,
            best: CubeList::new(),
            cand: CubeList::new(),
            cover: CoverScratch::new(),
            place: PlaceScratch::ZERO,
            tables: [FilterTable::zeroed(), FilterTable::zeroed()],
            result: 0,
        }
    }

    /// The table of the last successful [`plan_in`] call.
    pub const fn table(&self) -> &FilterTable<K, ELEMS, PRIM, SEC> {
        &self.tables[self.result]
    }
}

/// Cover `idx` into `out`: 0 the single keys, then the merged covers.
const fn load_cover(prep: &Prepared, covers: &[CubeList; 3], idx: usize, out: &mut CubeList) {
    if idx == 0 {
        // No more keys than cubes fit (MAX_KEYS = MAX_CUBES).
        let _ = out.set_singles(prep.keys.keys());
    } else {
        out.copy_from(&covers[idx - 1]);
    }
}

/// The best exact cover for `capacity_s` secondary elements (fewest primary elements
/// needed) into `best`, and its need: each cover as found and with blocks split back
/// into secondary singles; with `max_keys`, each cover's multi-user blocks split first
/// so that it needs at most that many lookup keys.
const fn best_cover(
    prep: &Prepared,
    covers: &[CubeList; 3],
    n_covers: usize,
    capacity_s: usize,
    max_keys: Option<usize>,
    best: &mut CubeList,
    cand: &mut CubeList,
) -> usize {
    load_cover(prep, covers, 0, best);
    let mut best_need = need(prep, best, capacity_s);
    let mut idx = 0;
    while idx <= n_covers {
        let mut variant = 0;
        while variant < 2 {
            load_cover(prep, covers, idx, cand);
            if let Some(k) = max_keys {
                split_multi_user_blocks(&prep.keys, cand, k);
            }
            if variant == 1 {
                tune(prep, cand, capacity_s);
            }
            let n = need(prep, cand, capacity_s);
            if n < best_need {
                best.copy_from(cand);
                best_need = n;
            }
            variant += 1;
        }
        idx += 1;
    }
    best_need
}

/// Plans one configuration into `tables[t]` (a configuration the table holds).
const fn plan_for_configuration<
    const K: usize,
    const ELEMS: usize,
    const PRIM: usize,
    const SEC: usize,
>(
    s: &mut Scratch<K, ELEMS, PRIM, SEC>,
    configuration: Configuration,
    superset: bool,
    t: usize,
) -> Result<(), PlanError> {
    let Scratch {
        prep,
        covers,
        n_covers,
        best,
        cand,
        cover,
        place: ps,
        tables,
        ..
    } = s;
    let capacity_p = FilterTable::<K, ELEMS, PRIM, SEC>::primary_of(configuration);
    let capacity_s = FilterTable::<K, ELEMS, PRIM, SEC>::secondary_of(configuration);
    let n = best_cover(prep, covers, *n_covers, capacity_s, None, best, cand);
    if n <= capacity_p {
        let keys = match place(prep, best, configuration, 0, ps, &mut tables[t]) {
            Err(PlanError::TooManyLookupKeys { needed, .. }) => needed,
            other => return other,
        };
        // Within the lookup capacity: blocks split, the covers tried again.
        let n = best_cover(prep, covers, *n_covers, capacity_s, Some(K), best, cand);
        if n <= capacity_p {
            return place(prep, best, configuration, 0, ps, &mut tables[t]);
        }
        return Err(PlanError::TooManyLookupKeys {
            needed: keys,
            max: if K > u16::MAX as usize {
                u16::MAX
            } else {
                K as u16
            },
        });
    }
    let refused = PlanError::TooManyPrimary {
        needed: if n > u16::MAX as usize {
            u16::MAX
        } else {
            n as u16
        },
        available: capacity_p as u8,
        secondary: capacity_s as u8,
    };
    if !superset || prep.n_general > capacity_p {
        return Err(refused);
    }
    while need(prep, best, capacity_s) > capacity_p {
        if !merge_step(best, prep.general()) {
            return Err(refused);
        }
    }
    let extra = best.extra(&prep.keys, cover);
    place(prep, best, configuration, extra, ps, &mut tables[t])
}

/// The steps of the module documentation, into `s`.
const fn plan_into<const K: usize, const ELEMS: usize, const PRIM: usize, const SEC: usize>(
    filters: &[Filter],
    options: PlanOptions,
    s: &mut Scratch<K, ELEMS, PRIM, SEC>,
) -> Result<(), PlanError> {
    // The configurations the table holds: RFFN 0 to `max` (ACAN's four by default).
    let max = FilterTable::<K, ELEMS, PRIM, SEC>::MAX_RFFN as usize;
    if let Some(c) = options.configuration {
        if !FilterTable::<K, ELEMS, PRIM, SEC>::holds(c) {
            return Err(PlanError::ConfigurationTooLarge {
                rffn: c.rffn(),
                max_rffn: max as u8,
            });
        }
    }
    if let Err(e) = s.prep.fill(filters) {
        return Err(e);
    }
    s.n_covers = 0;
    if options.merge {
        let _ = exact_cover(&s.prep.keys, 2, &mut s.covers[0], &mut s.cover);
        let _ = exact_cover(&s.prep.keys, 3, &mut s.covers[1], &mut s.cover);
        s.n_covers = 2;
        // The fewest cubes (every element costs one): exact search when small.
        if s.prep.keys.len() <= COVER_SEARCH_KEYS {
            let seed = s.covers[0].weight(1, 1);
            let [_, _, min] = &mut s.covers;
            min_cover(&s.prep.keys, 1, 1, seed, COVER_BUDGET, min, &mut s.cover);
            if !s.covers[2].is_empty() {
                s.n_covers = 3;
            }
        }
    }
    s.result = 0;
    if let Some(c) = options.configuration {
        return plan_for_configuration(s, c, options.superset, 0);
    }
    let mut i = 0;
    while i <= max {
        if plan_for_configuration(s, Configuration::EVERY[i], false, 0).is_ok() {
            return Ok(());
        }
        i += 1;
    }
    let largest = Configuration::EVERY[max];
    if !options.superset {
        return plan_for_configuration(s, largest, false, 0);
    }
    // The configuration with the fewest extra identifiers.
    let mut best: Option<usize> = None;
    let mut keys_refused: Option<PlanError> = None;
    let mut i = 0;
    while i <= max {
        let t = match best {
            Some(b) => 1 - b,
            None => 0,
        };
        match plan_for_configuration(s, Configuration::EVERY[i], true, t) {
            Ok(()) => {
                let fewer = match best {
                    None => true,
                    Some(b) => s.tables[t].superset_extra() < s.tables[b].superset_extra(),
                };
                if fewer {
                    best = Some(t);
                }
            }
            Err(e @ PlanError::TooManyLookupKeys { .. }) => keys_refused = Some(e),
            Err(_) => {}
        }
        i += 1;
    }
    match (best, keys_refused) {
        (Some(b), _) => {
            s.result = b;
            Ok(())
        }
        // A superset fits the elements but not the lookup capacity: say so.
        (None, Some(e)) => Err(e),
        (None, None) => plan_for_configuration(s, largest, false, 0),
    }
}

/// Compiles `filters` into an ID filter table with the working memory in `scratch` and
/// the table left there: the run-time planner of a firmware, whose scratch lives in a
/// `static` (see [`Scratch`]). The table needs at most `K` lookup keys.
///
/// The same `const fn` as [`plan`] and [`crate::const_plan!`]. Errors: as [`plan`].
///
/// The scratch's sizes choose the table's: `Scratch<K, 128, 32, 96>` plans a
/// [`crate::LargeFilterTable`] (RFFN up to 0xF, the RT1062 layout's), choosing among
/// all sixteen configurations.
pub const fn plan_in<
    's,
    const K: usize,
    const ELEMS: usize,
    const PRIM: usize,
    const SEC: usize,
>(
    filters: &[Filter],
    options: PlanOptions,
    scratch: &'s mut Scratch<K, ELEMS, PRIM, SEC>,
) -> Result<&'s FilterTable<K, ELEMS, PRIM, SEC>, PlanError> {
    match plan_into(filters, options, scratch) {
        Ok(()) => Ok(&scratch.tables[scratch.result]),
        Err(e) => Err(e),
    }
}

/// [`plan`] for a table with room for `K` lookup keys. Builds its own [`Scratch`] (on
/// the stack at run time: for `const` code and the host; firmware uses [`plan_in`]).
pub const fn plan_for<const K: usize>(
    filters: &[Filter],
    options: PlanOptions,
) -> Result<FilterTable<K>, PlanError> {
    plan_sized::<
        K,
        { crate::configuration::MAX_TABLE_ELEMENTS },
        MAX_PRIMARY_FILTERS,
        MAX_SECONDARY_FILTERS,
    >(filters, options)
}

/// [`plan_for`] into a table of any size (its [`Scratch`] on the stack): with
/// `FilterTable<K, 128, 32, 96>` the RT1062 layout's tables, RFFN up to 0xF
/// ([`plan_large`]).
pub const fn plan_sized<const K: usize, const ELEMS: usize, const PRIM: usize, const SEC: usize>(
    filters: &[Filter],
    options: PlanOptions,
) -> Result<FilterTable<K, ELEMS, PRIM, SEC>, PlanError> {
    let mut s = Scratch::<K, ELEMS, PRIM, SEC>::new();
    match plan_into(filters, options, &mut s) {
        Ok(()) => {
            let [a, b] = s.tables;
            Ok(if s.result == 0 { a } else { b })
        }
        Err(e) => Err(e),
    }
}

/// Compiles `filters` into an ID filter table (see the module documentation), with the
/// default lookup capacity ([`LOOKUP_KEYS`]). An empty list receives nothing (format
/// D).
///
/// A `const fn`: with a `const` list, [`crate::const_plan!`] plans it at compile time.
/// At run time it builds its working memory ([`Scratch`], about 70 KB) on the stack:
/// fine on a host; firmware plans with [`plan_in`] and the scratch in a `static`.
///
/// Errors: [`PlanError::TooManyFilters`], [`PlanError::Filter`],
/// [`PlanError::TooManyPrimary`] when no placement fits and the superset fallback is
/// off (or general filters alone are too many), [`PlanError::TooManyLookupKeys`] when
/// every placement that fits needs more lookup keys than the table keeps.
///
/// ```
/// use twocan_core::{Filter, FilterError, Format, Frame, FrameKind};
/// use twocan_flexcan::planner::{plan, PlanError, PlanOptions};
/// use twocan_flexcan::Configuration;
///
/// let filters = [
///     Filter::standard(0x100),                                                     // user 0
///     Filter::standard(0x101),                                                     // user 1
///     Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_FF00, 0x0001_2300), // user 2
/// ];
/// // "Choose the configuration for me": the smallest table that fits (8 elements, all
/// // primary), leaving the most remote-frame mailboxes.
/// let table = plan(&filters, PlanOptions::default())?;
/// assert_eq!(table.configuration(), Configuration::Filters8_0);
/// assert!(table.primary_count() <= 3);
/// // Which element the hardware hits, and the user index the driver reports.
/// let (_element, user) = table.evaluate(&Frame::standard(0x101, &[])?).unwrap();
/// assert_eq!(user, Some(1));
/// let (_, user) = table.evaluate(&Frame::extended(0x0001_23AB, &[])?).unwrap();
/// assert_eq!(user, Some(2));
/// assert_eq!(table.evaluate(&Frame::standard(0x102, &[])?), None);
///
/// // Bad input: the failing filter's index, or the element counts.
/// assert_eq!(
///     plan(&[Filter::extended(0x2000_0000)], PlanOptions::default()).unwrap_err(),
///     PlanError::Filter { index: 0, error: FilterError::IdOutOfRange }
/// );
/// let masks: Vec<Filter> = (0..9)
///     .map(|i| Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, i << 4))
///     .collect();
/// let err = plan(&masks, PlanOptions::new(Configuration::Filters8_0).merge(false)).unwrap_err();
/// assert_eq!(err, PlanError::TooManyPrimary { needed: 9, available: 8, secondary: 0 });
/// assert!(err.to_string().starts_with("the filters need 9 primary filter elements"));
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
pub const fn plan(filters: &[Filter], options: PlanOptions) -> Result<FilterTable, PlanError> {
    plan_for::<LOOKUP_KEYS>(filters, options)
}

/// [`plan`] for the RT1062 layout ([`crate::layout::Imxrt1062`]): a
/// [`crate::LargeFilterTable`], the configuration chosen among RFFN 0 to 0xF (up to 128
/// elements: 32 primary, 96 secondary) or given. A configuration whose table is larger
/// than the chip takes is refused by `begin` ([`crate::Chip::accepted_max_rffn`]).
///
/// ```
/// use twocan_core::Filter;
/// use twocan_flexcan::planner::{plan, plan_large, PlanError, PlanOptions};
/// use twocan_flexcan::Configuration;
///
/// // 120 single identifiers: more than ACAN's 14/18 table holds; the smallest large
/// // table that does has 120 elements (RFFN 0xE).
/// let ids: Vec<Filter> = (0..120u32).map(|i| Filter::extended(0x1000 + 7 * i)).collect();
/// let options = PlanOptions::default().merge(false);
/// assert!(matches!(plan(&ids, options), Err(PlanError::TooManyPrimary { .. })));
/// let table = plan_large(&ids, options)?;
/// assert_eq!(table.configuration(), Configuration::Filters32_88);
/// // ACAN's table type does not hold RFFN 0xF: a typed error.
/// assert_eq!(
///     plan(&ids, PlanOptions::new(Configuration::Filters32_96)).unwrap_err(),
///     PlanError::ConfigurationTooLarge { rffn: 15, max_rffn: 3 }
/// );
/// # Ok::<(), PlanError>(())
/// ```
pub fn plan_large(
    filters: &[Filter],
    options: PlanOptions,
) -> Result<crate::LargeFilterTable, PlanError> {
    plan_sized(filters, options)
}

/// [`plan_for`] with room for every key ([`MAX_LOOKUP_KEYS`]), or a compile-time error
/// with a readable message: the first step of [`crate::const_plan!`].
#[doc(hidden)]
pub const fn plan_or_panic(
    filters: &[Filter],
    options: PlanOptions,
) -> FilterTable<MAX_LOOKUP_KEYS> {
    match plan_for::<MAX_LOOKUP_KEYS>(filters, options) {
        Ok(t) => t,
        Err(e) => e.panic(),
    }
}

/// The sizes a `const` table of `filters` needs ([`crate::filters::SizedTable`]).
pub const fn plan_sizes(filters: &[Filter], options: PlanOptions) -> TableSizes {
    plan_or_panic(filters, options).sizes()
}

/// Plans a `const` filter list at compile time: `const_plan!(FILTERS, options)` gives a
/// `&'static` [`SizedTable`](crate::filters::SizedTable) of exactly the table elements
/// of its configuration and the lookup keys it needs, computed by the same `const fn`
/// as the run-time planner ([`planner::plan_in`](crate::planner::plan_in)). `FILTERS`
/// is a constant expression of type `[Filter; N]` or `&[Filter]`, `options` a constant
/// [`PlanOptions`](crate::planner::PlanOptions) (`PlanOptions::choose()` or
/// `PlanOptions::new(configuration)`). The split driver installs it as a
/// [`FilterTable`](crate::FilterTable) ([`FilterTable::from_sized`](crate::FilterTable::from_sized)).
///
/// A list that does not fit is a compile-time error naming the counts.
///
/// ```
/// use twocan_core::{Filter, Frame};
/// use twocan_flexcan::planner::PlanOptions;
/// use twocan_flexcan::{const_plan, Configuration};
///
/// const FILTERS: [Filter; 3] = [
///     Filter::standard(0x100),
///     Filter::standard(0x101),
///     Filter::extended(0x18FE_F100),
/// ];
/// let table = const_plan!(FILTERS, PlanOptions::choose());
/// assert_eq!(table.configuration(), Configuration::Filters8_0);
/// let (_, user) = table.evaluate(&Frame::standard(0x101, &[]).unwrap()).unwrap();
/// assert_eq!(user, Some(1));
/// // 0x100 and 0x101 share one element (a cube of two users): their keys are looked up.
/// assert_eq!(table.lookup_keys().0.len(), 2);
/// ```
///
/// A list that needs more primary elements than the configuration has does not
/// compile:
///
/// ```compile_fail
/// use twocan_core::{Filter, Format, FrameKind};
/// use twocan_flexcan::planner::PlanOptions;
/// use twocan_flexcan::{const_plan, Configuration};
///
/// const MASKS: [Filter; 9] = {
///     let mut f = [Filter::pass_all(); 9];
///     let mut i = 0;
///     while i < 9 {
///         f[i] = Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, (i as u32) << 4);
///         i += 1;
///     }
///     f
/// };
/// // error: evaluation panicked: twocan_flexcan::const_plan!: the filters need 9
/// // primary filter elements, the configuration has 8 (and 0 secondary, all used)
/// let table = const_plan!(MASKS, PlanOptions::new(Configuration::Filters8_0));
/// ```
#[macro_export]
macro_rules! const_plan {
    ($filters:expr, $options:expr $(,)?) => {{
        #[allow(long_running_const_eval)]
        const FULL: $crate::FilterTable<{ $crate::filters::MAX_LOOKUP_KEYS }> =
            $crate::planner::plan_or_panic(&$filters, $options);
        const SIZES: $crate::filters::TableSizes = FULL.sizes();
        const TABLE: $crate::filters::SizedTable<
            { SIZES.elements },
            { SIZES.primary },
            { SIZES.keys },
        > = FULL.sized();
        &TABLE
    }};
}

/// [`plan_large`] with room for every key, or a compile-time error with a readable
/// message: the first step of [`crate::const_plan_large!`].
#[doc(hidden)]
pub const fn plan_large_or_panic(
    filters: &[Filter],
    options: PlanOptions,
) -> crate::filters::FilterTable<MAX_LOOKUP_KEYS, 128, 32, 96> {
    match plan_sized::<MAX_LOOKUP_KEYS, 128, 32, 96>(filters, options) {
        Ok(t) => t,
        Err(e) => e.panic(),
    }
}

/// [`crate::const_plan!`] for the RT1062 layout ([`crate::layout::Imxrt1062`]): the
/// configuration chosen among RFFN 0 to 0xF (tables up to 128 elements, 32 primary and
/// 96 secondary) or given, planned at compile time into a `&'static`
/// [`SizedTable`](crate::filters::SizedTable) for `begin_planned` with
/// [`crate::options::Lean`]`<Imxrt1062>` (its [`crate::BeginPlan`] made with
/// `BeginPlan::<Imxrt1062>::new_with_layout`).
///
/// ```
/// use twocan_core::{Filter, Frame};
/// use twocan_flexcan::planner::PlanOptions;
/// use twocan_flexcan::{const_plan_large, Configuration};
///
/// const IDS: [Filter; 100] = {
///     let mut f = [Filter::pass_all(); 100];
///     let mut i = 0;
///     while i < 100 {
///         f[i] = Filter::extended(0x1000 + 7 * i as u32);
///         i += 1;
///     }
///     f
/// };
/// let table = const_plan_large!(IDS, PlanOptions::choose().merge(false));
/// assert_eq!(table.configuration(), Configuration::Filters32_72);
/// let (_, user) = table.evaluate(&Frame::extended(0x1000 + 7 * 99, &[]).unwrap()).unwrap();
/// assert_eq!(user, Some(99));
/// ```
#[macro_export]
macro_rules! const_plan_large {
    ($filters:expr, $options:expr $(,)?) => {{
        #[allow(long_running_const_eval)]
        const FULL: $crate::FilterTable<{ $crate::filters::MAX_LOOKUP_KEYS }, 128, 32, 96> =
            $crate::planner::plan_large_or_panic(&$filters, $options);
        const SIZES: $crate::filters::TableSizes = FULL.sizes();
        const TABLE: $crate::filters::SizedTable<
            { SIZES.elements },
            { SIZES.primary },
            { SIZES.keys },
        > = FULL.sized();
        &TABLE
    }};
}

#[cfg(test)]
mod tests {
    use super::*;
    use twocan_core::{Format, Frame, FrameKind};

    fn first(filters: &[Filter], f: &Frame) -> Option<u16> {
        filters.iter().position(|x| x.matches(f)).map(|i| i as u16)
    }

    fn exact(filters: &[Filter], t: &FilterTable) {
        for id in 0..0x800u32 {
            for f in [
                Frame::standard(id as u16, &[]).unwrap(),
                Frame::remote(id, false, 0).unwrap(),
            ] {
                let got = t.evaluate(&f).and_then(|(_, i)| i);
                assert_eq!(got, first(filters, &f), "{f:?}");
            }
        }
    }

    /// `n` general filters (masked extended ranges, one primary element each) and `m`
    /// single extended identifiers, none mergeable with another, and a frame each accepts.
    fn mixed(n: u32, m: u32) -> (Vec<Filter>, Vec<Frame>) {
        let mut filters = Vec::new();
        let mut frames = Vec::new();
        for i in 0..n {
            filters.push(Filter::masked(
                FrameKind::Data,
                Format::Extended,
                0x1FFF_FF00,
                0x0100_0000 + (i << 8),
            ));
            frames.push(Frame::extended(0x0100_0000 + (i << 8) + 0x33, &[]).unwrap());
        }
        for j in 0..m {
            filters.push(Filter::extended(0x0002_0000 + 5 * j));
            frames.push(Frame::extended(0x0002_0000 + 5 * j, &[]).unwrap());
        }
        (filters, frames)
    }

    #[test]
    fn rt1062_tables_of_32_64_96_and_128_elements() {
        for (n, m, c) in [
            (14, 18, Configuration::Filters14_18),
            (22, 42, Configuration::Filters22_42),
            (30, 66, Configuration::Filters30_66),
            (32, 96, Configuration::Filters32_96),
        ] {
            let (filters, frames) = mixed(n, m);
            // "Choose for me" gives the smallest table that holds the list.
            let t = plan_large(&filters, PlanOptions::choose()).unwrap();
            assert_eq!(t.configuration(), c);
            assert_eq!(t.elements().len(), c.table_elements());
            for f in &frames {
                let got = t.evaluate(f).and_then(|(_, i)| i);
                assert_eq!(got, first(&filters, f), "{c:?} {f:?}");
                assert!(got.is_some());
            }
            assert_eq!(t.evaluate(&Frame::standard(0x7FF, &[]).unwrap()), None);
            // ACAN's table type holds the first only.
            let acan = plan(&filters, PlanOptions::choose());
            assert_eq!(acan.is_ok(), c == Configuration::Filters14_18, "{c:?}");
        }
        // One general filter more than the 32 individual masks: refused with the counts.
        let (filters, _) = mixed(33, 0);
        assert_eq!(
            plan_large(&filters, PlanOptions::choose()).unwrap_err(),
            PlanError::TooManyPrimary {
                needed: 33,
                available: 32,
                secondary: 96
            }
        );
        // A configuration the table type cannot hold: typed, never a panic.
        assert_eq!(
            plan(&[], PlanOptions::new(Configuration::Filters16_24)).unwrap_err(),
            PlanError::ConfigurationTooLarge {
                rffn: 4,
                max_rffn: 3
            }
        );
        // The run-time planner with the large scratch, a configuration given.
        let (filters, frames) = mixed(20, 30);
        let mut scratch: Box<Scratch<LOOKUP_KEYS, 128, 32, 96>> = Box::default();
        let t = plan_in(
            &filters,
            PlanOptions::new(Configuration::Filters32_72),
            &mut scratch,
        )
        .unwrap();
        assert_eq!(t.configuration(), Configuration::Filters32_72);
        for f in &frames {
            assert_eq!(t.evaluate(f).and_then(|(_, i)| i), first(&filters, f));
        }
    }

    #[test]
    fn a_block_takes_one_primary_element() {
        let f: Vec<Filter> = (0x500..0x540).map(Filter::standard).collect();
        let t = plan(&f, PlanOptions::new(Configuration::Filters8_0)).unwrap();
        exact(&f, &t);
        assert_eq!(t.primary_count(), 1);
        // Without merging: 64 identifiers never fit 14 + 18 elements.
        assert_eq!(
            plan(&f, PlanOptions::default().merge(false)),
            Err(PlanError::TooManyPrimary {
                needed: 46,
                available: 14,
                secondary: 18
            })
        );
    }

    #[test]
    fn configuration_is_chosen_and_singles_go_secondary() {
        // 14 identifiers, no two a block: 8/0 cannot hold them, 10/6 can (10 + 6).
        let f: Vec<Filter> = (0..14u16).map(|i| Filter::standard(i * 0x81)).collect();
        let t = plan(&f, PlanOptions::default()).unwrap();
        assert_eq!(t.configuration(), Configuration::Filters10_6);
        exact(&f, &t);
    }

    #[test]
    fn general_filters_keep_first_match_order() {
        let f = [
            Filter::standard(0x105),
            Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, 0x100),
            Filter::standard(0x106),
            Filter::exact(FrameKind::Any, Format::Standard, 0x200),
            Filter::standard(0x300),
            Filter::standard(0x301),
        ];
        for c in Configuration::ALL {
            let t = plan(&f, PlanOptions::new(c)).unwrap();
            exact(&f, &t);
        }
    }

    /// Every exact cube of two or more keys (identifier bits 0–3, the test range).
    fn all_blocks(keys: &KeyTable) -> Vec<Cube> {
        let mut out: Vec<Cube> = Vec::new();
        for &k in keys.keys() {
            let span = 0xF;
            let mut dc: u32 = 0;
            loop {
                dc = dc.wrapping_sub(span) & span;
                if dc == 0 {
                    break;
                }
                let c = Cube { base: k & !dc, dc };
                if keys.holds(&c) && !out.contains(&c) {
                    out.push(c);
                }
            }
        }
        out
    }

    fn list_of(cubes: &[Cube]) -> Box<CubeList> {
        let mut l = Box::new(CubeList::new());
        for &c in cubes {
            l.push(c).unwrap();
        }
        l
    }

    #[test]
    fn primary_need_matches_exhaustive_search_on_small_sets() {
        let mut s = 0x2545_F491_u64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let mut scratch: Box<Scratch> = Box::default();
        for _ in 0..200 {
            let n = 3 + next() % 9;
            let f: Vec<Filter> = (0..n)
                .map(|_| {
                    let id = 0x100 | (next() % 16) as u32;
                    match next() % 3 {
                        0 => Filter::exact(FrameKind::Remote, Format::Standard, id),
                        _ => Filter::standard(id as u16),
                    }
                })
                .collect();
            // The planner's covers, as `plan_in` makes them (before any configuration is
            // tried: whether 8/0 fits does not matter).
            let _ = plan_in(
                &f,
                PlanOptions::new(Configuration::Filters8_0),
                &mut scratch,
            );
            let sc = &mut *scratch;
            let blocks = all_blocks(&sc.prep.keys);
            assert!(blocks.len() <= 16);
            for c in [Configuration::Filters8_0, Configuration::Filters10_6] {
                let cap = c.secondary_filter_capacity();
                let mut best = usize::MAX;
                for set in 0u32..(1 << blocks.len()) {
                    let mut cubes: Vec<Cube> = (0..blocks.len())
                        .filter(|b| set & (1 << b) != 0)
                        .map(|b| blocks[b])
                        .collect();
                    for &k in sc.prep.keys.keys() {
                        if !cubes.iter().any(|x| x.contains(k)) {
                            cubes.push(Cube::single(k));
                        }
                    }
                    best = best.min(need(&sc.prep, &list_of(&cubes), cap));
                }
                let got = best_cover(
                    &sc.prep,
                    &sc.covers,
                    sc.n_covers,
                    cap,
                    None,
                    &mut sc.best,
                    &mut sc.cand,
                );
                assert_eq!(got, best, "{c:?} {f:?}");
            }
        }
    }

    #[test]
    fn superset_fits_and_drops_the_rest() {
        let f: Vec<Filter> = (0..40u16)
            .map(|i| Filter::standard(i * 37 % 0x800))
            .collect();
        assert!(plan(&f, PlanOptions::new(Configuration::Filters12_12)).is_err());
        let t = plan(
            &f,
            PlanOptions::new(Configuration::Filters12_12).superset(true),
        )
        .unwrap();
        assert!(t.superset_extra() > 0);
        let mut dropped = 0;
        for id in 0..0x800u16 {
            let frame = Frame::standard(id, &[]).unwrap();
            match (t.evaluate(&frame), first(&f, &frame)) {
                (Some((_, got)), Some(want)) => assert_eq!(got, Some(want)),
                (Some((_, None)), None) => dropped += 1,
                (None, None) => {}
                other => panic!("{id:#x}: {other:?}"),
            }
        }
        assert_eq!(dropped, t.superset_extra());
    }
}

/// The run-time planner's stack: every value [`plan_in`] and the functions it calls
/// hold by value is small (the tables are in the [`Scratch`]).
#[cfg(test)]
mod stack {
    use super::*;
    use core::mem::size_of;

    #[test]
    fn by_value_types_on_the_run_time_path_are_small() {
        let sizes: [(&str, usize); 12] = [
            ("&[Filter]", size_of::<&[Filter]>()),
            ("PlanOptions", size_of::<PlanOptions>()),
            ("PlanError", size_of::<PlanError>()),
            (
                "Result<&FilterTable, PlanError>",
                size_of::<Result<&FilterTable, PlanError>>(),
            ),
            ("Filter", size_of::<Filter>()),
            ("Cube", size_of::<Cube>()),
            ("Primary", size_of::<Primary>()),
            ("PlannedPrimary", size_of::<PlannedPrimary>()),
            ("(u32, Hit)", size_of::<(u32, Hit)>()),
            (
                "Option<(usize, usize)> (tune pick)",
                size_of::<Option<(usize, usize)>>(),
            ),
            ("Configuration", size_of::<Configuration>()),
            ("Result<(), PlanError>", size_of::<Result<(), PlanError>>()),
        ];
        for (name, size) in sizes {
            println!("{name}: {size} B");
            assert!(size <= 128, "{name}: {size} B");
        }
        println!("Scratch<64>: {} B", size_of::<Scratch>());
        println!("FilterTable<64>: {} B", size_of::<FilterTable>());
        assert!(size_of::<FilterTable>() < 1024);
        use crate::filters::SizedTable;
        println!(
            "SizedTable<8, 8, 0>: {} B",
            size_of::<SizedTable<8, 8, 0>>()
        );
        println!(
            "SizedTable<16, 10, 4>: {} B",
            size_of::<SizedTable<16, 10, 4>>()
        );
        println!(
            "SizedTable<32, 14, 64>: {} B",
            size_of::<SizedTable<32, 14, 64>>()
        );
    }

    fn filters_367() -> Vec<Filter> {
        (0..367u32)
            .map(|i| Filter::extended(0x0C00_0000 + i * 0x1_0203))
            .collect()
    }

    /// The largest list of the DBC corpus's size (367 identifiers, 365 extended) in
    /// superset mode, the scratch boxed, on a thread with a 64 KiB stack (debug builds'
    /// frames included).
    #[test]
    fn plan_in_runs_on_a_small_stack() {
        let list = filters_367();
        // Room for every key: the superset table looks all of them up.
        let mut scratch: Box<Scratch<MAX_LOOKUP_KEYS>> = Box::default();
        let t = std::thread::Builder::new()
            .stack_size(64 * 1024)
            .spawn(move || {
                plan_in(&list, PlanOptions::choose().superset(true), &mut scratch)
                    .map(|t| (t.configuration(), t.superset_extra() > 0))
            })
            .unwrap();
        assert_eq!(t.join().unwrap(), Ok((Configuration::Filters14_18, true)));
        // With the default capacity the same list is refused, naming the keys.
        let mut small: Box<Scratch> = Box::default();
        assert!(matches!(
            plan_in(
                &filters_367(),
                PlanOptions::choose().superset(true),
                &mut small
            ),
            Err(PlanError::TooManyLookupKeys { max: 64, .. })
        ));
    }
}
