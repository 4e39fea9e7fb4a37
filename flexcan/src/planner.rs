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

use twocan_core::filter_set::{
    exact_cover, keys_of, merge_step, min_cover, narrow, overlaps, Cube, CubeList, KeyTable,
};
use twocan_core::{Filter, FilterError, Format};

use crate::configuration::{Configuration, MAX_PRIMARY_FILTERS, MAX_SECONDARY_FILTERS};
use crate::filters::{
    element_of, mask_of, FilterTable, Hit, ELEMENT_IDE, ELEMENT_RTR, ELEMENT_STD_SHIFT, FULL_MASK,
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
        PlanOptions {
            configuration: None,
            merge: true,
            superset: false,
        }
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
    /// Keeps the counts ([`twocan_core::Error::FilterSpace`]: primary elements needed
    /// and available, or filters given and the most taken).
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
        }
    }
}

/// Step 1: the checked, narrowed list split into general filters and keys.
struct Prepared {
    general: [Filter; MAX_FILTERS],
    general_users: [u16; MAX_FILTERS],
    n_general: usize,
    keys: KeyTable,
}

impl Prepared {
    fn new(list: &[Filter]) -> Result<Self, PlanError> {
        if list.len() > MAX_FILTERS {
            return Err(PlanError::TooManyFilters {
                given: list.len().min(u16::MAX as usize) as u16,
                max: MAX_FILTERS as u16,
            });
        }
        for (i, f) in list.iter().enumerate() {
            f.check().map_err(|error| PlanError::Filter {
                index: i as u16,
                error,
            })?;
        }
        let mut p = Prepared {
            general: [Filter::pass_all(); MAX_FILTERS],
            general_users: [0; MAX_FILTERS],
            n_general: 0,
            keys: KeyTable::new(),
        };
        if list.is_empty() {
            // No filter receives nothing (unlike ACAN §4): an empty table, format D.
            return Ok(p);
        }
        for (i, f) in list.iter().enumerate() {
            let Some(g) = narrow(*f, &list[..i]) else {
                continue;
            };
            match keys_of(&g) {
                Some((keys, n)) => {
                    for &k in &keys[..n] {
                        // At most 2 × MAX_FILTERS = MAX_KEYS keys.
                        let _ = p.keys.insert(k, i as u16);
                    }
                }
                None => {
                    p.general[p.n_general] = g;
                    p.general_users[p.n_general] = i as u16;
                    p.n_general += 1;
                }
            }
        }
        Ok(p)
    }

    fn general(&self) -> &[Filter] {
        &self.general[..self.n_general]
    }

    /// Whether a key or cube must be primary (it overlaps a general filter).
    fn must_be_primary(&self, c: &Cube) -> bool {
        let f = c.filter();
        self.general().iter().any(|g| overlaps(g, &f))
    }
}

/// Nodes of the minimum-cover search ([`min_cover`]).
pub const COVER_BUDGET: u32 = 20_000;

/// Keys up to which the minimum-cover search runs (its recursion is as deep as the
/// keys it covers one by one).
pub const COVER_SEARCH_KEYS: usize = 256;

/// Primary elements a cover needs once the secondary elements are full.
#[derive(Debug, Clone, Copy)]
struct Need {
    primary: usize,
}

fn need(prep: &Prepared, cubes: &[Cube], capacity_s: usize) -> Need {
    let mut primary = prep.n_general;
    let mut singles = 0;
    for c in cubes {
        if c.is_block() || prep.must_be_primary(c) || prep.keys.count_in(c) != c.size() {
            primary += 1;
        } else {
            singles += 1;
        }
    }
    Need {
        primary: primary + singles - singles.min(capacity_s),
    }
}

/// One primary element: (position in user order, element, mask, hit).
type Primary = (u16, u32, u32, Hit);

/// Step 3: the table of a cover that fits `configuration`.
fn place(prep: &Prepared, cubes: &[Cube], configuration: Configuration, extra: u64) -> FilterTable {
    let capacity_s = configuration.secondary_filter_capacity();
    let mut primary: [Primary; MAX_PRIMARY_FILTERS] =
        [(0, 0, FULL_MASK, Hit::Filter(0)); MAX_PRIMARY_FILTERS];
    let mut np = 0;
    let mut secondary = [(0u32, Hit::Filter(0)); MAX_SECONDARY_FILTERS];
    let mut ns = 0;
    let mut all_std = true;
    for (f, &u) in prep.general().iter().zip(prep.general_users.iter()) {
        primary[np] = (u, element_of(f), mask_of(f), Hit::Filter(u));
        np += 1;
    }
    for c in cubes {
        let exact = prep.keys.count_in(c) == c.size();
        let user = prep.keys.first_user(c).unwrap_or(0);
        let hit = match (exact, prep.keys.single_user(c)) {
            (true, Some(u)) => Hit::Filter(u),
            _ => Hit::Lookup,
        };
        let f = c.filter();
        if !c.is_block() && exact && !prep.must_be_primary(c) && ns < capacity_s {
            secondary[ns] = (element_of(&f), hit);
            all_std &= f.format == Format::Standard;
            ns += 1;
        } else {
            primary[np] = (user, element_of(&f), mask_of(&f), hit);
            np += 1;
        }
    }
    primary[..np].sort_unstable_by_key(|p| (p.0, p.1));
    let global_mask = if all_std {
        ELEMENT_RTR | ELEMENT_IDE | (0x7FF << ELEMENT_STD_SHIFT)
    } else {
        FULL_MASK
    };
    let prim: [(u32, u32, Hit); MAX_PRIMARY_FILTERS] =
        core::array::from_fn(|i| (primary[i].1, primary[i].2, primary[i].3));
    FilterTable::planned(
        configuration,
        &prim[..np],
        &secondary[..ns],
        global_mask,
        &prep.keys,
        extra,
    )
}

/// Whether a single key may take a secondary element.
fn secondary_eligible(prep: &Prepared, c: &Cube) -> bool {
    !c.is_block() && prep.keys.count_in(c) == 1 && !prep.must_be_primary(c)
}

/// `cover` with blocks split back into single keys while the secondary elements have
/// room for them, smallest blocks first: a block of `k` keys costs one primary element,
/// its keys cost none while `k` secondary elements are free.
fn tuned(prep: &Prepared, cover: &CubeList, capacity_s: usize) -> CubeList {
    let mut out = cover.clone();
    let singles = out
        .as_slice()
        .iter()
        .filter(|c| secondary_eligible(prep, c))
        .count();
    let mut free = capacity_s.saturating_sub(singles);
    loop {
        // The block whose keys covered by no other cube are fewest (and fit).
        let cubes = out.as_slice();
        let mut pick: Option<(usize, usize)> = None;
        for (i, c) in cubes.iter().enumerate() {
            if !c.is_block() || prep.keys.count_in(c) != c.size() {
                continue;
            }
            let mut own = 0;
            let mut ok = true;
            for &k in prep.keys.keys() {
                if c.contains(k)
                    && !cubes
                        .iter()
                        .enumerate()
                        .any(|(j, o)| j != i && o.contains(k))
                {
                    own += 1;
                    ok &= secondary_eligible(prep, &Cube::single(k));
                }
            }
            if ok && own <= free && pick.is_none_or(|(_, n)| own < n) {
                pick = Some((i, own));
            }
        }
        let Some((i, own)) = pick else {
            return out;
        };
        let c = out.as_slice()[i];
        let mut next = CubeList::new();
        for (j, o) in out.as_slice().iter().enumerate() {
            if j != i {
                // Room: the list only shrinks or trades a block for its own keys.
                let _ = next.push(*o);
            }
        }
        for &k in prep.keys.keys() {
            if c.contains(k) && !next.as_slice().iter().any(|o| o.contains(k)) {
                let _ = next.push(Cube::single(k));
            }
        }
        out = next;
        free -= own;
    }
}

/// The best exact cover for `configuration` (fewest primary elements needed) and its
/// need: each cover as found and with blocks split back into secondary singles.
fn best_cover(
    prep: &Prepared,
    covers: &[CubeList; 4],
    configuration: Configuration,
) -> (CubeList, Need) {
    let capacity_s = configuration.secondary_filter_capacity();
    let mut best = (
        covers[0].clone(),
        need(prep, covers[0].as_slice(), capacity_s),
    );
    for c in covers.iter() {
        for candidate in [c.clone(), tuned(prep, c, capacity_s)] {
            let n = need(prep, candidate.as_slice(), capacity_s);
            if n.primary < best.1.primary {
                best = (candidate, n);
            }
        }
    }
    best
}

/// Plans one configuration: the table, or the primary elements needed.
fn plan_for(
    prep: &Prepared,
    covers: &[CubeList; 4],
    configuration: Configuration,
    superset: bool,
) -> Result<FilterTable, PlanError> {
    let capacity_p = configuration.primary_filter_capacity();
    let capacity_s = configuration.secondary_filter_capacity();
    let (cover, n) = best_cover(prep, covers, configuration);
    if n.primary <= capacity_p {
        return Ok(place(prep, cover.as_slice(), configuration, 0));
    }
    let refused = PlanError::TooManyPrimary {
        needed: n.primary.min(u16::MAX as usize) as u16,
        available: capacity_p as u8,
        secondary: capacity_s as u8,
    };
    if !superset || prep.n_general > capacity_p {
        return Err(refused);
    }
    let mut grown = cover;
    let allowed = |c: &Cube| !prep.must_be_primary(c);
    while need(prep, grown.as_slice(), capacity_s).primary > capacity_p {
        if !merge_step(&mut grown, allowed) {
            return Err(refused);
        }
    }
    let extra = grown.extra(&prep.keys);
    Ok(place(prep, grown.as_slice(), configuration, extra))
}

/// Compiles `filters` into an ID filter table (see the module documentation). An empty
/// list receives every frame (ACAN §4).
///
/// Errors: [`PlanError::TooManyFilters`], [`PlanError::Filter`], and
/// [`PlanError::TooManyPrimary`] when no placement fits and the superset fallback is
/// off (or general filters alone are too many).
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
pub fn plan(filters: &[Filter], options: PlanOptions) -> Result<FilterTable, PlanError> {
    let prep = Prepared::new(filters)?;
    let mut covers = [
        CubeList::new(),
        CubeList::new(),
        CubeList::new(),
        CubeList::new(),
    ];
    for &k in prep.keys.keys() {
        // MAX_KEYS = MAX_CUBES: room for every key.
        let _ = covers[0].push(Cube::single(k));
    }
    if options.merge {
        let _ = exact_cover(&prep.keys, 2, &mut covers[1]);
        let _ = exact_cover(&prep.keys, 3, &mut covers[2]);
        // The fewest cubes (every element costs one): exact search when small.
        if prep.keys.len() <= COVER_SEARCH_KEYS {
            let (head, tail) = covers.split_at_mut(3);
            min_cover(&prep.keys, 1, 1, &head[1], COVER_BUDGET, &mut tail[0]);
        }
        if covers[3].is_empty() {
            covers[3] = covers[1].clone();
        }
    } else {
        let singles = covers[0].clone();
        for c in covers.iter_mut().skip(1) {
            *c = singles.clone();
        }
    }
    if let Some(c) = options.configuration {
        return plan_for(&prep, &covers, c, options.superset);
    }
    for c in Configuration::ALL {
        if let Ok(t) = plan_for(&prep, &covers, c, false) {
            return Ok(t);
        }
    }
    let largest = Configuration::Filters14_18;
    if !options.superset {
        return plan_for(&prep, &covers, largest, false);
    }
    let mut best: Option<FilterTable> = None;
    for c in Configuration::ALL {
        if let Ok(t) = plan_for(&prep, &covers, c, true) {
            if best
                .as_ref()
                .is_none_or(|b| t.superset_extra() < b.superset_extra())
            {
                best = Some(t);
            }
        }
    }
    best.map_or_else(|| plan_for(&prep, &covers, largest, false), Ok)
}

#[cfg(test)]
mod tests {
    use super::*;
    use twocan_core::{Frame, FrameKind};

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

    #[test]
    fn primary_need_matches_exhaustive_search_on_small_sets() {
        let mut s = 0x2545_F491_u64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
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
            let prep = Prepared::new(&f).unwrap();
            let blocks = all_blocks(&prep.keys);
            assert!(blocks.len() <= 16);
            let mut covers = [
                CubeList::new(),
                CubeList::new(),
                CubeList::new(),
                CubeList::new(),
            ];
            for &k in prep.keys.keys() {
                covers[0].push(Cube::single(k)).unwrap();
            }
            exact_cover(&prep.keys, 2, &mut covers[1]).unwrap();
            exact_cover(&prep.keys, 3, &mut covers[2]).unwrap();
            let (head, tail) = covers.split_at_mut(3);
            min_cover(&prep.keys, 1, 1, &head[1], COVER_BUDGET, &mut tail[0]);
            if covers[3].is_empty() {
                covers[3] = covers[1].clone();
            }
            for c in [Configuration::Filters8_0, Configuration::Filters10_6] {
                let cap = c.secondary_filter_capacity();
                let mut best = usize::MAX;
                for set in 0u32..(1 << blocks.len()) {
                    let mut cubes: Vec<Cube> = (0..blocks.len())
                        .filter(|b| set & (1 << b) != 0)
                        .map(|b| blocks[b])
                        .collect();
                    for &k in prep.keys.keys() {
                        if !cubes.iter().any(|x| x.contains(k)) {
                            cubes.push(Cube::single(k));
                        }
                    }
                    best = best.min(need(&prep, &cubes, cap).primary);
                }
                let (_, got) = best_cover(&prep, &covers, c);
                assert_eq!(got.primary, best, "{c:?} {f:?}");
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
