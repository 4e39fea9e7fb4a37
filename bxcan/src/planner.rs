//! The automatic filter planner: portable [`Filter`]s → the fewest filter banks, exactly.
//!
//! Hardware facts used (lecture notes after RM0410 §40.7.4 "Identifier filtering"; see
//! [`crate::filters`]): four kinds of hardware filter ("entries"), each with a capacity per
//! bank and a hardware priority class:
//!
//! | entry          | per bank | class | holds exactly                                              |
//! |----------------|---------:|------:|------------------------------------------------------------|
//! | 32-bit list    | 2        | 0     | one identifier of one format and one kind                  |
//! | 32-bit mask    | 1        | 1     | any conforming filter                                      |
//! | 16-bit list    | 4        | 2     | one standard id, or one 14-bit prefix of extended ids; one kind |
//! | 16-bit mask    | 2        | 3     | standard or format-free filters, extended filters masking no bit below `EXID[15]` |
//!
//! See `docs/filters.md` for the numbering example and worked plans.
//!
//! # Algorithm
//!
//! 1. **Check** every filter ([`Filter::check`]): typed error with its index; a list
//!    longer than [`MAX_FILTERS`] is refused with both numbers.
//! 2. **Narrow** by first-match semantics ([`twocan_core::filter_set::narrow`]): a frame
//!    an earlier filter accepts is always reported with that earlier index, so a later
//!    filter may drop it; a filter contained entirely is dropped.
//! 3. **Split** the narrowed list: filters that accept whole identifiers (one format, one
//!    or both kinds) become *keys* (identifier, format, kind), each remembering its user
//!    index; the others stay *general* filters.
//! 4. **Merge** ([`PlanOptions::merge`]): the keys are covered by exact *cubes* (a base
//!    identifier and some ignored bits, every identifier of the cube a key of the same
//!    format and kind: what one mask entry accepts exactly), greedily, taking a block
//!    while it replaces at least three single entries
//!    ([`twocan_core::filter_set::exact_cover`]); a greedy cover taking blocks of two,
//!    and the lightest cover found by branch and bound over the maximal exact cubes
//!    ([`twocan_core::filter_set::min_cover`], up to [`COVER_SEARCH_KEYS`] keys and
//!    [`COVER_BUDGET`] nodes) are tried too. A cube whose keys belong to several
//!    user filters is resolved on the thread side ([`crate::filters::FmiMap::resolve`]:
//!    one binary search in the plan's key table); listed in a list bank, its
//!    identifiers report their own user indices directly.
//! 5. **Options**: for each item (general filter or cube), how many entries of each
//!    class represent it exactly (a filter of kind "any" takes two list entries; a mask
//!    with a few don't-care bits may be listed in full, up to one bank's worth).
//! 6. **Order constraint**: when a general filter `j` overlaps an earlier item `i`, the
//!    hardware must prefer `i`'s entries: class(i) ≤ class(j), and within one class the
//!    entries are laid out in item order. Cubes are placed at their first key's user
//!    index; two cubes never constrain each other (any entry of either reports the
//!    right index through the key table). Overlapping items are kept in one FIFO.
//! 7. **Search**: each item takes one class; the cost is
//!    `⌈n₀/2⌉ + n₁ + ⌈n₂/4⌉ + ⌈n₃/2⌉` banks. A dynamic programme over the 16 residue
//!    states `(n₀ mod 2, n₂ mod 4, n₃ mod 2)` gives the exact optimum without the order
//!    constraint, the admissible bound of a depth-first branch-and-bound that enforces
//!    it (stopping at the bound, or after [`SEARCH_BUDGET`] nodes: then
//!    [`FilterPlan::is_proven_optimal`] is `false`; the plan is still exact). Among
//!    plans with equally few banks the narrowest entries win.
//! 8. The merged plan is kept only if it needs fewer banks than the plan of single
//!    entries (so merging never costs a bank). **Lookup capacity**: the plan may leave
//!    at most `K` keys to the thread-side lookup (`K` of the [`FilterPlan<K>`] filled,
//!    the driver's). When the fewest-banks plan needs more, the covers are tried again
//!    with their multi-user blocks split
//!    ([`twocan_core::filter_set::split_multi_user_blocks`]) and the list-only plan
//!    (no key); the one with the fewest banks is kept, or the list is refused with
//!    [`PlanError::TooManyLookupKeys`] (the keys needed and `K`).
//! 9. **Superset** ([`PlanOptions::superset`]): when the exact plan needs more banks
//!    than available, cubes are merged pairwise, each time the pair whose join adds
//!    the fewest identifiers outside the set ([`twocan_core::filter_set::merge_step`];
//!    never a join that meets a general filter), until the plan fits. The hardware then
//!    accepts a superset; [`crate::filters::FmiMap::resolve`] gives `None` for the
//!    extra identifiers, which the driver drops and counts.
//! 10. **Layout**: per class, entries in item order, filling banks; the last bank of a
//!     list class is padded by repeating its last entry. Banks are assigned to FIFOs
//!     ([`FifoPolicy`]) and the FMI → user-index map is computed from the layout.
//!
//! # At compile time and at run time
//!
//! Every step is a `const fn` (loops, explicit indices, hand-written searches and
//! insertion sorts), with its working memory in a [`Scratch`] passed by `&mut`: one
//! implementation for [`crate::const_plan!`] (a `const` list planned during constant
//! evaluation, the result cut to its size), [`plan_in`] (a list known at run time, the
//! scratch in a `static`: the planning call's stack stays small) and [`plan`] /
//! [`plan_for`] (the scratch on the stack: host and `const` code).
//!
//! # Guarantees
//!
//! *Exact acceptance* (superset mode aside): every entry accepts a subset of its item,
//! items together accept exactly the union of the user's filters. *Reported index*: for
//! a frame whose first matching user filter is `i`: if `i` is a key, every entry that
//! can match the frame is a key's entry (general filters after `i` lose by 6.) and the
//! key table gives `i`; if `i` is general, an entry of `i` matches, and any other
//! matching entry is of a later general filter overlapping `i` (a key inside `i` is
//! narrowed away) which loses by 6. *Fewest banks*: for the chosen items, among plans
//! that give each item entries of a single class (exhaustive search with an admissible
//! bound); the cube cover itself is greedy (see `docs/filters.md` for its measured
//! distance to the exact lower bound).

use twocan_core::filter_set::{
    exact_cover, key, key_parts, keys_of, merge_step, min_cover, narrow, split_multi_user_blocks,
    CoverScratch, Cube, CubeList, KeyTable,
};
use twocan_core::{Filter, Format, FrameKind};

pub use twocan_core::filter_set::{contains, overlaps};

use crate::filters::{
    list16_of, list32_of, mask16_of, mask32_of, Bank, BankKind, Fifo, FilterPlan, PlanError,
    PlanSizes, EXT_BITS_IN_16BIT, LOOKUP, LOOKUP_KEYS, MAX_LOOKUP_KEYS, NO_FILTER,
};
use crate::regs::FILTER_BANKS;

/// The largest user filter list the planner takes.
pub const MAX_FILTERS: usize = 512;

/// Items (general filters and cubes) the bank search holds: every item takes at least a
/// quarter bank, so more than `4 × 28 = 112` never fit.
const ITEMS: usize = 128;

/// Nodes of the minimum-weight cover search ([`min_cover`]).
pub const COVER_BUDGET: u32 = 20_000;

/// Keys up to which the minimum-weight cover search runs (its search stack is as deep
/// as the keys it covers one by one).
pub const COVER_SEARCH_KEYS: usize = 256;

/// Branch-and-bound nodes explored before the planner settles for the best plan found.
pub const SEARCH_BUDGET: u32 = 200_000;

/// How the planner assigns banks to the two receive FIFOs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FifoPolicy {
    /// Every bank to FIFO 0.
    #[default]
    Fifo0,
    /// Every bank to FIFO 1.
    Fifo1,
    /// Spread the banks over both FIFOs to balance the number of user filters each
    /// receives, never costing a bank and never separating overlapping filters (a frame
    /// always has one FIFO). Frames of different FIFOs lose their relative order.
    Balanced,
}

/// Planner options: `PlanOptions::new(banks)` and the builder methods, or
/// `PlanOptions { banks: 14, ..Default::default() }`.
///
/// The lookup capacity is not an option: it is the `K` of the plan filled
/// ([`FilterPlan<K>`], the controller's, [`LOOKUP_KEYS`] by default), so a plan always
/// fits the driver it is made for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlanOptions {
    /// Banks available to the instance (CAN1: `CAN2SB`, CAN2: `28 − CAN2SB`, CAN3: 14).
    pub banks: u8,
    /// FIFO assignment.
    pub fifo: FifoPolicy,
    /// Merge identifiers into exact mask entries (default `true`): a merged entry
    /// standing for several user filters reports [`LOOKUP`] in
    /// [`crate::filters::FmiMap::get`], and the driver resolves its frames' user indices
    /// with [`crate::filters::FmiMap::resolve`] (one binary search in the plan's lookup
    /// keys, at most `K` of them). `false`: one list or mask entry per user filter, each
    /// slot naming its user filter.
    pub merge: bool,
    /// When the exact plan does not fit, accept a superset in hardware and let the
    /// driver drop the extra frames (default `false`: refuse with the bank counts).
    pub superset: bool,
}

impl Default for PlanOptions {
    /// All 28 banks, FIFO 0, exact merging on, no superset.
    fn default() -> Self {
        Self::new(FILTER_BANKS as u8)
    }
}

impl PlanOptions {
    /// `banks` banks available, every bank to FIFO 0, exact merging on (a merged entry's
    /// frames get their user index from `FmiMap::resolve`, which the driver calls),
    /// superset off. `.merge(false)` gives plans whose every slot names its user filter
    /// (`FmiMap::get`).
    pub const fn new(banks: u8) -> Self {
        PlanOptions {
            banks,
            fifo: FifoPolicy::Fifo0,
            merge: true,
            superset: false,
        }
    }

    /// The same options with another FIFO policy.
    pub const fn fifo(self, fifo: FifoPolicy) -> Self {
        PlanOptions { fifo, ..self }
    }

    /// The same options with merging on or off (off: one list or mask entry per user
    /// filter, the v1 plans).
    pub const fn merge(self, merge: bool) -> Self {
        PlanOptions { merge, ..self }
    }

    /// The same options with the superset fallback on or off.
    pub const fn superset(self, superset: bool) -> Self {
        PlanOptions { superset, ..self }
    }
}

const CLASSES: usize = 4;
const L32: usize = 0;
const M32: usize = 1;
const L16: usize = 2;
const M16: usize = 3;
/// Entries per bank of each class.
const CAP: [u8; CLASSES] = [2, 1, 4, 2];
const KINDS: [BankKind; CLASSES] = [
    BankKind::List32,
    BankKind::Mask32,
    BankKind::List16,
    BankKind::Mask16,
];

/// Cost of one bank in the search's combined cost (above any tie-break weight sum:
/// 128 filters × 4 entries × weight 4 < 4096).
const SCALE: u32 = 4096;
/// Tie-break weight per entry, for plans with equally few banks: prefer 16-bit lists,
/// then 16-bit masks, 32-bit lists, 32-bit masks (the narrowest hardware filter that
/// holds the filter, leaving the wider banks' kinds free for what needs them).
const WEIGHT: [u32; CLASSES] = [3, 4, 1, 2];

/// Residue state: n₀ mod 2 (bit 0), n₂ mod 4 (bits 1..2), n₃ mod 2 (bit 3).
const STATES: usize = 16;

const fn residue(s: u8, class: usize) -> u8 {
    match class {
        L32 => s & 1,
        L16 => (s >> 1) & 3,
        M16 => (s >> 3) & 1,
        _ => 0,
    }
}

const fn with_residue(s: u8, class: usize, r: u8) -> u8 {
    match class {
        L32 => (s & !1) | r,
        L16 => (s & !0b110) | (r << 1),
        M16 => (s & !0b1000) | (r << 3),
        _ => s,
    }
}

/// Banks opened and the next state when `count` entries of `class` are added in state `s`.
const fn step(s: u8, class: usize, count: u8) -> (u16, u8) {
    let cap = CAP[class];
    if class == M32 {
        return (count as u16, s);
    }
    let r = residue(s, class);
    let total = r + count;
    let opened = total.div_ceil(cap) - r.div_ceil(cap);
    (opened as u16, with_residue(s, class, total % cap))
}

/// Don't-care bit positions of `mask` within `range`.
const fn dont_care(mask: u32, range: u32) -> u32 {
    !mask & range
}

/// How many frame kinds (data, remote) `kind` accepts.
const fn kinds_len(kind: FrameKind) -> u32 {
    match kind {
        FrameKind::Any => 2,
        _ => 1,
    }
}

/// Whether the `i`-th kind `kind` accepts is remote (data first).
const fn kind_remote(kind: FrameKind, i: u32) -> bool {
    match kind {
        FrameKind::Data => false,
        FrameKind::Remote => true,
        FrameKind::Any => i == 1,
    }
}

/// Step 5: number of entries of each class that represent `item` exactly (0 =
/// impossible).
const fn options(item: &Item) -> [u8; CLASSES] {
    let f = &item.filter;
    let mut o = [0u8; CLASSES];
    o[M32] = 1;
    if mask16_of(f).is_some() {
        o[M16] = 1;
    }
    let kinds = kinds_len(f.kind);
    match f.format {
        Format::Standard => {
            let n = (1u32 << dont_care(f.mask, 0x7FF).count_ones()) * kinds;
            if n <= CAP[L32] as u32 {
                o[L32] = n as u8;
            }
            if n <= CAP[L16] as u32 {
                o[L16] = n as u8;
            }
        }
        Format::Extended => {
            let dc = dont_care(f.mask, 0x1FFF_FFFF).count_ones();
            if dc <= 1 {
                let n = (1u32 << dc) * kinds;
                if n <= CAP[L32] as u32 {
                    o[L32] = n as u8;
                }
            }
            if f.mask & !EXT_BITS_IN_16BIT == 0 {
                let dc16 = dont_care(f.mask, EXT_BITS_IN_16BIT).count_ones();
                if dc16 <= 2 {
                    let n = (1u32 << dc16) * kinds;
                    if n <= CAP[L16] as u32 {
                        o[L16] = n as u8;
                    }
                }
            }
        }
        Format::Any => {}
    }
    if !item.list {
        o[L32] = 0;
        o[L16] = 0;
    }
    if item.user == LOOKUP && matches!(f.format, Format::Extended) {
        // A 16-bit list entry of extended identifiers holds a 14-bit prefix: the keys
        // behind it cannot be told apart by entry.
        o[L16] = 0;
    }
    o
}

/// One hardware entry: a list word (`m` unused) or a mask pair; 16-bit values in the low
/// half-word.
#[derive(Debug, Clone, Copy)]
struct Entry {
    v: u32,
    m: u32,
    user: u16,
}

impl Entry {
    /// An unused slot.
    const NONE: Entry = Entry {
        v: 0,
        m: 0,
        user: NO_FILTER,
    };
}

/// The entries of class `class` for `item` (consistent with [`options`]: at most four);
/// a list entry of a cube of several users reports its key's user.
const fn entries<const N: usize>(
    item: &Item,
    class: usize,
    keys: &KeyTable<N>,
) -> ([Entry; 4], usize) {
    let f = &item.filter;
    let user = item.user;
    let mut out = [Entry::NONE; 4];
    let mut n = 0;
    match class {
        M32 => {
            let (v, m) = mask32_of(f);
            out[0] = Entry { v, m, user };
            n = 1;
        }
        M16 => {
            if let Some((v, m)) = mask16_of(f) {
                out[0] = Entry {
                    v: v as u32,
                    m: m as u32,
                    user,
                };
                n = 1;
            }
        }
        _ => {
            let ext = matches!(f.format, Format::Extended);
            let range = if class == L32 {
                f.format.id_mask()
            } else if ext {
                EXT_BITS_IN_16BIT
            } else {
                0x7FF
            };
            let dc = dont_care(f.mask, range);
            let mut r = 0;
            while r < kinds_len(f.kind) {
                let remote = kind_remote(f.kind, r);
                r += 1;
                // Every identifier of the cell: the sub-masks of the don't-care bits.
                let mut sub: u32 = 0;
                loop {
                    let id = f.id | sub;
                    let single = Filter {
                        kind: if remote {
                            FrameKind::Remote
                        } else {
                            FrameKind::Data
                        },
                        format: f.format,
                        id,
                        mask: range,
                    };
                    let word = if class == L32 {
                        list32_of(&single)
                    } else {
                        match list16_of(&single) {
                            Some(w) => Some(w as u32),
                            None => None,
                        }
                    };
                    if let Some(w) = word {
                        let u = if user == LOOKUP {
                            match keys.lookup(key(id, ext, remote)) {
                                Some(u) => u,
                                None => NO_FILTER,
                            }
                        } else {
                            user
                        };
                        if n < 4 {
                            out[n] = Entry {
                                v: w,
                                m: 0,
                                user: u,
                            };
                            n += 1;
                        }
                    }
                    if sub == dc {
                        break;
                    }
                    sub = sub.wrapping_sub(dc) & dc;
                }
            }
        }
    }
    (out, n)
}

/// A filter with every field zero (standard data, identifier and mask 0): the content
/// of a fresh scratch.
const ZERO_FILTER: Filter = Filter {
    kind: FrameKind::Data,
    format: Format::Standard,
    id: 0,
    mask: 0,
};

/// One thing the bank search places: a general filter or a cube of keys.
#[derive(Debug, Clone, Copy)]
struct Item {
    /// What it accepts (a cube as its mask filter).
    filter: Filter,
    /// The user index its entries report, or [`LOOKUP`] (resolved by key).
    user: u16,
    /// Its place in the order constraint (user index of its first key).
    pos: u16,
    /// A cube of keys (never constrained against another cube).
    cube: bool,
    /// List entries allowed (not for superset cubes).
    list: bool,
}

impl Item {
    const ZERO: Item = Item {
        filter: ZERO_FILTER,
        user: 0,
        pos: 0,
        cube: false,
        list: false,
    };

    /// The search order: by place in the order constraint, general filters before
    /// cubes, then identifier and mask.
    const fn before(&self, other: &Item) -> bool {
        if self.pos != other.pos {
            return self.pos < other.pos;
        }
        if self.cube != other.cube {
            return !self.cube;
        }
        if self.filter.id != other.filter.id {
            return self.filter.id < other.filter.id;
        }
        self.filter.mask < other.filter.mask
    }
}

/// Steps 1–3: the checked, narrowed list split into general filters and keys.
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
        let mut i = 0;
        while i < list.len() {
            let g = match narrow(list[i], list.split_at(i).0) {
                Some(g) => g,
                None => {
                    i += 1;
                    continue;
                }
            };
            match keys_of(&g) {
                Some((keys, n)) => {
                    let mut j = 0;
                    while j < n {
                        // 2 × MAX_FILTERS keys at most: the table holds them all.
                        if self.keys.insert(keys[j], i as u16).is_err() {
                            return Err(PlanError::BankOutOfRange);
                        }
                        j += 1;
                    }
                }
                None => {
                    self.general[self.n_general] = g;
                    self.general_users[self.n_general] = i as u16;
                    self.n_general += 1;
                }
            }
            i += 1;
        }
        Ok(())
    }

    const fn general(&self) -> &[Filter] {
        self.general.split_at(self.n_general).0
    }

    /// Item `idx` of a cover: general filters, then cubes (unsorted).
    const fn item(&self, cubes: &CubeList, idx: usize) -> Item {
        if idx < self.n_general {
            let u = self.general_users[idx];
            return Item {
                filter: self.general[idx],
                user: u,
                pos: u,
                cube: false,
                list: true,
            };
        }
        let c = cubes.get(idx - self.n_general);
        let exact = self.keys.count_in(&c) == c.size();
        let user = if exact {
            match self.keys.single_user(&c) {
                Some(u) => u,
                None => LOOKUP,
            }
        } else {
            LOOKUP
        };
        Item {
            filter: c.filter(),
            user,
            pos: match self.keys.first_user(&c) {
                Some(u) => u,
                None => u16::MAX,
            },
            cube: true,
            list: exact,
        }
    }
}

/// The bank count of the best class choice for the items of `cubes` with the order
/// constraint ignored (a lower bound; exact when no item overlaps a later general
/// filter).
const fn relaxed_banks(prep: &Prepared, cubes: &CubeList) -> u16 {
    let mut cost = [u16::MAX; STATES];
    cost[0] = 0;
    let n = prep.n_general + cubes.len();
    let mut idx = 0;
    while idx < n {
        let o = options(&prep.item(cubes, idx));
        idx += 1;
        let mut next = [u16::MAX; STATES];
        let mut s = 0;
        while s < STATES {
            if cost[s] != u16::MAX {
                let mut c = 0;
                while c < CLASSES {
                    if o[c] != 0 {
                        let (open, to) = step(s as u8, c, o[c]);
                        let v = cost[s].saturating_add(open);
                        if v < next[to as usize] {
                            next[to as usize] = v;
                        }
                    }
                    c += 1;
                }
            }
            s += 1;
        }
        cost = next;
    }
    let mut best = cost[0];
    let mut s = 1;
    while s < STATES {
        if cost[s] < best {
            best = cost[s];
        }
        s += 1;
    }
    best
}

/// Quarter banks a cube needs at least (std single 1, std block 2, ext single 2, ext
/// block 4): the trigger of the superset loop.
const fn quarters(c: &Cube) -> u32 {
    let ext = key_parts(c.base).1;
    match (ext, c.is_block()) {
        (false, false) => 1,
        (false, true) => 2,
        (true, false) => 2,
        (true, true) => 4,
    }
}

/// The fewest quarter banks one item's options take.
const fn options_quarters(o: &[u8; CLASSES]) -> u8 {
    // Quarter banks per entry of each class: 32-bit list 2, 32-bit mask 4, 16-bit list
    // 1, 16-bit mask 2.
    const Q: [u8; CLASSES] = [2, 4, 1, 2];
    let mut best = u8::MAX;
    let mut c = 0;
    while c < CLASSES {
        if o[c] != 0 && o[c] * Q[c] < best {
            best = o[c] * Q[c];
        }
        c += 1;
    }
    if best == u8::MAX {
        4
    } else {
        best
    }
}

/// Items in search order, with their options and earlier overlaps.
struct Problem {
    n: usize,
    items: [Item; ITEMS],
    options: [[u8; CLASSES]; ITEMS],
    /// Bit i of `earlier[j]`: item i < j overlaps j and constrains it.
    earlier: [u128; ITEMS],
}

/// Items placed by the search, with their classes (or, when there are too many items
/// to search, the banks they need at least).
struct Attempt {
    /// Searched (`false`: more items than fit 28 banks anyway; `banks` is a bound).
    ok: bool,
    banks: u16,
    proven: bool,
    problem: Problem,
    classes: [u8; ITEMS],
}

impl Attempt {
    const ZERO: Attempt = Attempt {
        ok: false,
        banks: 0,
        proven: false,
        problem: Problem {
            n: 0,
            items: [Item::ZERO; ITEMS],
            options: [[0; CLASSES]; ITEMS],
            earlier: [0; ITEMS],
        },
        classes: [0; ITEMS],
    };
}

/// Working memory of the bank search.
struct SolveScratch {
    /// `relax[j][s]`: cheapest plan for items `j..` from state `s`, order constraint
    /// ignored.
    relax: [[u32; STATES]; ITEMS + 1],
    classes: [u8; ITEMS],
    tried: [u8; ITEMS + 1],
    state: [u8; ITEMS + 1],
    cost: [u32; ITEMS + 1],
}

impl SolveScratch {
    const ZERO: SolveScratch = SolveScratch {
        relax: [[0; STATES]; ITEMS + 1],
        classes: [0; ITEMS],
        tried: [0; ITEMS + 1],
        state: [0; ITEMS + 1],
        cost: [0; ITEMS + 1],
    };
}

/// Steps 5–7 for one cover, into `a`.
const fn attempt(prep: &Prepared, cubes: &CubeList, a: &mut Attempt, s: &mut SolveScratch) {
    let n = prep.n_general + cubes.len();
    if n > ITEMS {
        a.ok = false;
        a.banks = relaxed_banks(prep, cubes);
        a.proven = false;
        a.problem.n = 0;
        return;
    }
    let p = &mut a.problem;
    p.n = n;
    let mut idx = 0;
    while idx < n {
        p.items[idx] = prep.item(cubes, idx);
        idx += 1;
    }
    // Sorted by their place in the order constraint (insertion sort: stable).
    let mut i = 1;
    while i < n {
        let x = p.items[i];
        let mut j = i;
        while j > 0 && x.before(&p.items[j - 1]) {
            p.items[j] = p.items[j - 1];
            j -= 1;
        }
        p.items[j] = x;
        i += 1;
    }
    let mut j = 0;
    while j < n {
        let item = p.items[j];
        p.options[j] = options(&item);
        let mut bits = 0u128;
        let mut k = 0;
        while k < j {
            let other = p.items[k];
            if !(other.cube && item.cube) && overlaps(&other.filter, &item.filter) {
                bits |= 1 << k;
            }
            k += 1;
        }
        p.earlier[j] = bits;
        j += 1;
    }
    let (banks, proven) = solve(&a.problem, s, &mut a.classes);
    a.ok = true;
    a.banks = banks;
    a.proven = proven;
}

/// The combined cost and next state of `count` entries of class `c` in state `s`.
const fn add(s: u8, c: usize, count: u8) -> (u32, u8) {
    let (open, next) = step(s, c, count);
    (open as u32 * SCALE + count as u32 * WEIGHT[c], next)
}

/// Step 7: the class of each item in a plan with the fewest banks (into `best_classes`),
/// the bank count, and whether the search proved it optimal.
///
/// Costs are `banks × SCALE + tie-break`, so that among plans with the fewest banks
/// the one with the smallest tie-break weight ([`WEIGHT`]) is chosen.
const fn solve(p: &Problem, s: &mut SolveScratch, best_classes: &mut [u8; ITEMS]) -> (u16, bool) {
    let n = p.n;
    let mut st = 0;
    while st < STATES {
        s.relax[n][st] = 0;
        st += 1;
    }
    let mut j = n;
    while j > 0 {
        j -= 1;
        let mut st = 0;
        while st < STATES {
            let mut best = u32::MAX;
            let mut c = 0;
            while c < CLASSES {
                let count = p.options[j][c];
                if count != 0 {
                    let (cost, next) = add(st as u8, c, count);
                    let v = cost + s.relax[j + 1][next as usize];
                    if v < best {
                        best = v;
                    }
                }
                c += 1;
            }
            s.relax[j][st] = best;
            st += 1;
        }
    }
    let bound = s.relax[0][0];
    const fn banks(cost: u32) -> u16 {
        (cost / SCALE) as u16
    }

    // Seed: every filter in a 32-bit mask bank (always valid).
    let mut i = 0;
    while i < ITEMS {
        best_classes[i] = M32 as u8;
        s.classes[i] = 0;
        i += 1;
    }
    let mut best_cost = n as u32 * (SCALE + WEIGHT[M32]);
    if best_cost == bound {
        return (banks(best_cost), true);
    }

    s.tried[0] = 0;
    s.state[0] = 0;
    s.cost[0] = 0;
    let mut j = 0usize;
    let mut nodes = 0u32;
    let mut proven = true;
    loop {
        if j == n {
            if s.cost[n] < best_cost {
                best_cost = s.cost[n];
                *best_classes = s.classes;
                // Fewest banks reached: stop (the tie-break is best effort, the
                // depth-first order tries the cheapest classes first).
                if banks(best_cost) == banks(bound) {
                    break;
                }
            }
            j -= 1;
            continue;
        }
        let mut floor = 0u8;
        let mut bits = p.earlier[j];
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            if s.classes[i] > floor {
                floor = s.classes[i];
            }
            bits &= bits - 1;
        }
        // (estimate, class, increment, next state)
        let mut pick: Option<(u32, usize, u32, u8)> = None;
        let mut c = floor as usize;
        while c < CLASSES {
            let count = p.options[j][c];
            if count != 0 && s.tried[j] & (1 << c) == 0 {
                let (inc, next) = add(s.state[j], c, count);
                let estimate = s.cost[j] + inc + s.relax[j + 1][next as usize];
                if estimate < best_cost {
                    let better = match pick {
                        None => true,
                        Some(q) => estimate < q.0,
                    };
                    if better {
                        pick = Some((estimate, c, inc, next));
                    }
                }
            }
            c += 1;
        }
        match pick {
            None => {
                if j == 0 {
                    break;
                }
                j -= 1;
            }
            Some((_, c, inc, next)) => {
                nodes += 1;
                if nodes > SEARCH_BUDGET {
                    proven = false;
                    break;
                }
                s.tried[j] |= 1 << c;
                s.classes[j] = c as u8;
                s.state[j + 1] = next;
                s.cost[j + 1] = s.cost[j] + inc;
                j += 1;
                s.tried[j] = 0;
            }
        }
    }
    // Fewest banks is proven when the search ran to its end, or when the bank count
    // met the bound's (the tie-break alone may be unproven).
    let proven = proven || banks(best_cost) == banks(bound);
    (banks(best_cost), proven)
}

/// Working memory of the layout: the banks each item's entries went to, and the
/// union-find of FIFO balancing.
struct LayoutScratch {
    bank_of: [[u8; 4]; ITEMS],
    bank_count_of: [u8; ITEMS],
    parent: [u16; ITEMS + FILTER_BANKS],
    weight: [u16; ITEMS + FILTER_BANKS],
    /// 0: no FIFO yet; 1 + the FIFO's index.
    fifo_of_root: [u8; ITEMS + FILTER_BANKS],
}

impl LayoutScratch {
    const ZERO: LayoutScratch = LayoutScratch {
        bank_of: [[0; 4]; ITEMS],
        bank_count_of: [0; ITEMS],
        parent: [0; ITEMS + FILTER_BANKS],
        weight: [0; ITEMS + FILTER_BANKS],
        fifo_of_root: [0; ITEMS + FILTER_BANKS],
    };
}

/// Completes the bank of class `c` with the `fill` pending entries (the last repeated
/// to its capacity) and appends it to `out`.
const fn flush<const K: usize>(
    c: usize,
    pending: &mut [Entry; 4],
    fill: &mut usize,
    out: &mut FilterPlan<K>,
) -> Result<(), PlanError> {
    if *fill == 0 {
        return Ok(());
    }
    let cap = CAP[c] as usize;
    // Pad by repeating the last entry (same user index).
    let last = pending[*fill - 1];
    let mut i = *fill;
    while i < cap {
        pending[i] = last;
        i += 1;
    }
    let e = *pending;
    let (fr1, fr2) = match c {
        M32 => (e[0].v, e[0].m),
        L32 => (e[0].v, e[1].v),
        L16 => (e[0].v | (e[1].v << 16), e[2].v | (e[3].v << 16)),
        _ => (e[0].v | (e[0].m << 16), e[1].v | (e[1].m << 16)),
    };
    let mut users = [NO_FILTER; 4];
    let mut i = 0;
    while i < cap {
        users[i] = e[i].user;
        i += 1;
    }
    if let Err(err) = out.push(Bank::raw(KINDS[c], Fifo::Fifo0, fr1, fr2), users) {
        return Err(err);
    }
    *pending = [Entry::NONE; 4];
    *fill = 0;
    Ok(())
}

/// Step 10: the banks of an attempt, in class order, entries in item order, into `out`;
/// then the lookup keys (refused with the counts when more than `K`) and the FIFOs.
const fn layout<const K: usize>(
    prep: &Prepared,
    a: &Attempt,
    extra: u64,
    list_only_banks: u16,
    options: PlanOptions,
    lay: &mut LayoutScratch,
    out: &mut FilterPlan<K>,
) -> Result<(), PlanError> {
    let p = &a.problem;
    out.reset();
    let mut j = 0;
    while j < ITEMS {
        lay.bank_of[j] = [0; 4];
        lay.bank_count_of[j] = 0;
        j += 1;
    }
    let mut c = 0;
    while c < CLASSES {
        let cap = CAP[c] as usize;
        let mut pending = [Entry::NONE; 4];
        let mut fill = 0usize;
        let mut j = 0;
        while j < p.n {
            if a.classes[j] as usize == c {
                let (es, ne) = entries(&p.items[j], c, &prep.keys);
                let mut x = 0;
                while x < ne {
                    pending[fill] = es[x];
                    fill += 1;
                    x += 1;
                    let bank = out.bank_count();
                    let k = lay.bank_count_of[j] as usize;
                    if k < 4 && (k == 0 || lay.bank_of[j][k - 1] as usize != bank) {
                        lay.bank_of[j][k] = bank as u8;
                        lay.bank_count_of[j] += 1;
                    }
                    if fill == cap {
                        if let Err(e) = flush(c, &mut pending, &mut fill, out) {
                            return Err(e);
                        }
                    }
                }
            }
            j += 1;
        }
        if let Err(e) = flush(c, &mut pending, &mut fill, out) {
            return Err(e);
        }
        c += 1;
    }
    out.set_optimal(a.proven);
    if let Err(e) = out.set_resolution(&prep.keys, extra, list_only_banks) {
        return Err(e);
    }
    match options.fifo {
        FifoPolicy::Fifo0 => {}
        FifoPolicy::Fifo1 => {
            let mut b = 0;
            while b < out.bank_count() {
                out.set_fifo(b, Fifo::Fifo1);
                b += 1;
            }
        }
        FifoPolicy::Balanced => balance(p, lay, out),
    }
    Ok(())
}

/// Union-find root of `x`, with path halving.
const fn find(parent: &mut [u16; ITEMS + FILTER_BANKS], mut x: usize) -> usize {
    while parent[x] as usize != x {
        let up = parent[parent[x] as usize];
        parent[x] = up;
        x = up as usize;
    }
    x
}

const fn union(parent: &mut [u16; ITEMS + FILTER_BANKS], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        if ra < rb {
            parent[rb] = ra as u16;
        } else {
            parent[ra] = rb as u16;
        }
    }
}

/// Assigns tied groups of banks to FIFOs, largest first, to the FIFO with fewer filters.
const fn balance<const K: usize>(p: &Problem, lay: &mut LayoutScratch, out: &mut FilterPlan<K>) {
    let mut i = 0;
    while i < ITEMS + FILTER_BANKS {
        lay.parent[i] = i as u16;
        lay.weight[i] = 0;
        lay.fifo_of_root[i] = 0;
        i += 1;
    }
    let mut j = 0;
    while j < p.n {
        let mut k = 0;
        while k < lay.bank_count_of[j] as usize {
            union(&mut lay.parent, j, ITEMS + lay.bank_of[j][k] as usize);
            k += 1;
        }
        let mut bits = p.earlier[j];
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            union(&mut lay.parent, i, j);
            bits &= bits - 1;
        }
        // Overlapping cubes do not constrain each other's class, but share a FIFO too:
        // a frame they both accept must have one FIFO whichever entry wins.
        let mut i = 0;
        while i < j {
            if p.items[i].cube
                && p.items[j].cube
                && overlaps(&p.items[i].filter, &p.items[j].filter)
            {
                union(&mut lay.parent, i, j);
            }
            i += 1;
        }
        j += 1;
    }
    // Weight of each group root: number of user filters.
    let mut j = 0;
    while j < p.n {
        let r = find(&mut lay.parent, j);
        lay.weight[r] += 1;
        j += 1;
    }
    let mut load = [0u16; 2];
    loop {
        // Heaviest unassigned group.
        let mut heaviest: Option<usize> = None;
        let mut r = 0;
        while r < p.n {
            if find(&mut lay.parent, r) == r && lay.fifo_of_root[r] == 0 && lay.weight[r] > 0 {
                let heavier = match heaviest {
                    None => true,
                    Some(h) => lay.weight[r] > lay.weight[h],
                };
                if heavier {
                    heaviest = Some(r);
                }
            }
            r += 1;
        }
        let r = match heaviest {
            Some(r) => r,
            None => break,
        };
        let fifo = if load[1] < load[0] { 1 } else { 0 };
        load[fifo] += lay.weight[r];
        lay.fifo_of_root[r] = 1 + fifo as u8;
    }
    let mut b = 0;
    while b < out.bank_count() {
        let r = find(&mut lay.parent, ITEMS + b);
        let fifo = if lay.fifo_of_root[r] == 2 {
            Fifo::Fifo1
        } else {
            Fifo::Fifo0
        };
        out.set_fifo(b, fifo);
        b += 1;
    }
}

/// The working memory of [`plan_in`] (about 90 KB, every field zero when new: a `static`
/// of it takes RAM but no flash) and its result, a [`FilterPlan<K>`].
///
/// A firmware that plans at run time keeps it in a `static` place it owns: an RTIC
/// `#[local]` resource, a `cortex_m::singleton!` (`&'static mut`), or any static cell
/// that lends `&mut` to one context at a time. The planning call itself then needs a
/// small stack frame (a few hundred bytes, see `bxcan/tests/planner_stack.rs`).
pub struct Scratch<const K: usize = LOOKUP_KEYS> {
    prep: Prepared,
    /// The best cover so far and the cover being tried (roles swap by index).
    cubes: [CubeList; 2],
    cover: CoverScratch,
    /// The best attempt so far and the attempt being tried (roles swap by index).
    attempts: [Attempt; 2],
    search: SolveScratch,
    layout: LayoutScratch,
    out: FilterPlan<K>,
}

impl<const K: usize> Default for Scratch<K> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const K: usize> Scratch<K> {
    /// Fresh working memory (all zeros).
    pub const fn new() -> Self {
        Scratch {
            prep: Prepared::ZERO,
            cubes: [CubeList::new(), CubeList::new()],
            cover: CoverScratch::new(),
            attempts: [Attempt::ZERO, Attempt::ZERO],
            search: SolveScratch::ZERO,
            layout: LayoutScratch::ZERO,
            out: FilterPlan::zeroed(),
        }
    }

    /// The plan of the last successful [`plan_in`] call.
    pub const fn plan(&self) -> &FilterPlan<K> {
        &self.out
    }
}

/// The cover `which` (0: greedy, blocks of three or more keys; 1: greedy, blocks of
/// two or more; 2: the lightest, by branch and bound) into `out`; `false` when there is
/// none new (the search skipped or no lighter than the first).
const fn cover_of(
    prep: &Prepared,
    which: usize,
    seed_weight: u32,
    out: &mut CubeList,
    scratch: &mut CoverScratch,
) -> Result<bool, PlanError> {
    match which {
        0 | 1 => {
            let min_gain = if which == 0 { 3 } else { 2 };
            if exact_cover(&prep.keys, min_gain, out, scratch).is_err() {
                return Err(PlanError::BankOutOfRange);
            }
            Ok(true)
        }
        _ => {
            if prep.keys.len() > COVER_SEARCH_KEYS {
                return Ok(false);
            }
            min_cover(&prep.keys, 2, 1, seed_weight, COVER_BUDGET, out, scratch);
            // Empty: not lighter than the greedy cover, whose attempt was made.
            Ok(!out.is_empty())
        }
    }
}

/// The steps of the module documentation, into `s.out`.
const fn plan_into<const K: usize>(
    filters: &[Filter],
    options: PlanOptions,
    s: &mut Scratch<K>,
) -> Result<(), PlanError> {
    let Scratch {
        prep,
        cubes,
        cover,
        attempts,
        search,
        layout: lay,
        out,
    } = s;
    out.reset();
    if let Err(e) = prep.fill(filters) {
        return Err(e);
    }
    let available = if options.banks < FILTER_BANKS as u8 {
        options.banks
    } else {
        FILTER_BANKS as u8
    };
    if cubes[0].set_singles(prep.keys.keys()).is_err() {
        return Err(PlanError::BankOutOfRange);
    }
    attempt(prep, &cubes[0], &mut attempts[0], search);
    let list_only_banks = attempts[0].banks;
    // Indices of the best attempt and of its cover.
    let (mut best, mut best_cubes) = (0usize, 0usize);
    let mut seed_weight = 0;
    if options.merge {
        // Blocks of three or more keys save entries; blocks of two save none but can
        // fill a half-used 16-bit mask bank; the lightest cover (a block weighs two
        // single entries): each is tried.
        let mut which = 0;
        while which < 3 {
            let t = 1 - best_cubes;
            let fresh = match cover_of(prep, which, seed_weight, &mut cubes[t], cover) {
                Ok(f) => f,
                Err(e) => return Err(e),
            };
            if which == 0 {
                seed_weight = cubes[t].weight(2, 1);
            }
            if fresh {
                let ta = 1 - best;
                attempt(prep, &cubes[t], &mut attempts[ta], search);
                if attempts[ta].banks < attempts[best].banks {
                    best = ta;
                    best_cubes = t;
                }
            }
            which += 1;
        }
    }
    let needed = attempts[best].banks;
    if attempts[best].ok && needed <= available as u16 {
        return match layout(prep, &attempts[best], 0, list_only_banks, options, lay, out) {
            Err(PlanError::TooManyLookupKeys { needed: keys, .. }) => within_capacity(
                prep,
                cubes,
                cover,
                attempts,
                search,
                lay,
                out,
                options,
                available,
                list_only_banks,
                seed_weight,
                keys,
            ),
            other => other,
        };
    }
    if !options.superset {
        return Err(PlanError::TooManyBanks { needed, available });
    }
    // Step 9: merge cubes into supersets until the plan fits.
    let grown = &mut cubes[best_cubes];
    let mut general_quarters = 0u32;
    let mut g = 0;
    while g < prep.n_general {
        general_quarters += options_quarters(&self::options(&prep.item(grown, g))) as u32;
        g += 1;
    }
    loop {
        let mut q = general_quarters;
        let mut i = 0;
        while i < grown.len() {
            q += quarters(&grown.get(i));
            i += 1;
        }
        if q <= 4 * available as u32 && relaxed_banks(prep, grown) <= available as u16 {
            attempt(prep, grown, &mut attempts[0], search);
            if attempts[0].ok && attempts[0].banks <= available as u16 {
                let extra = grown.extra(&prep.keys, cover);
                return layout(
                    prep,
                    &attempts[0],
                    extra,
                    list_only_banks,
                    options,
                    lay,
                    out,
                );
            }
        }
        if !merge_step(grown, prep.general()) {
            return Err(PlanError::TooManyBanks { needed, available });
        }
    }
}

/// Step 8 within the lookup capacity: the plan with the fewest banks needed more than
/// `K` lookup keys (`keys_needed`). Tried instead: the list-only plan (no key), and each
/// merged cover with its multi-user blocks split until they hold at most `K` keys
/// ([`split_multi_user_blocks`]); the one with the fewest banks is laid out, or the list is refused with
/// [`PlanError::TooManyLookupKeys`] (the keys the best plan needs, and `K`).
#[allow(clippy::too_many_arguments)]
const fn within_capacity<const K: usize>(
    prep: &Prepared,
    cubes: &mut [CubeList; 2],
    cover: &mut CoverScratch,
    attempts: &mut [Attempt; 2],
    search: &mut SolveScratch,
    lay: &mut LayoutScratch,
    out: &mut FilterPlan<K>,
    options: PlanOptions,
    available: u8,
    list_only_banks: u16,
    seed_weight: u32,
    keys_needed: u16,
) -> Result<(), PlanError> {
    if cubes[0].set_singles(prep.keys.keys()).is_err() {
        return Err(PlanError::BankOutOfRange);
    }
    attempt(prep, &cubes[0], &mut attempts[0], search);
    let (mut best, mut best_cubes) = (0usize, 0usize);
    let mut which = 0;
    while which < 3 {
        let t = 1 - best_cubes;
        let fresh = match cover_of(prep, which, seed_weight, &mut cubes[t], cover) {
            Ok(f) => f,
            Err(e) => return Err(e),
        };
        if fresh {
            split_multi_user_blocks(&prep.keys, &mut cubes[t], K);
            let ta = 1 - best;
            attempt(prep, &cubes[t], &mut attempts[ta], search);
            if attempts[ta].banks < attempts[best].banks {
                best = ta;
                best_cubes = t;
            }
        }
        which += 1;
    }
    if attempts[best].ok && attempts[best].banks <= available as u16 {
        layout(prep, &attempts[best], 0, list_only_banks, options, lay, out)
    } else {
        out.reset();
        Err(PlanError::TooManyLookupKeys {
            needed: keys_needed,
            max: if K > u16::MAX as usize {
                u16::MAX
            } else {
                K as u16
            },
        })
    }
}

/// Compiles `filters` into the fewest banks (see the module documentation), with the
/// working memory in `scratch` and the plan left there: the run-time planner of a
/// firmware, whose `scratch` lives in a `static` (see [`Scratch`]). The plan needs at
/// most `K` lookup keys (the capacity of the driver it is for).
///
/// The same `const fn` as [`plan`] and [`crate::const_plan!`]: one implementation, at
/// compile time and at run time.
///
/// Errors: as [`plan`].
///
/// ```
/// use twocan_bxcan::planner::{plan_in, PlanOptions, Scratch};
/// use twocan_core::Filter;
///
/// // In firmware: `let scratch: &'static mut Scratch = cortex_m::singleton!(: Scratch =
/// // Scratch::new()).unwrap();` or an RTIC local resource; a box on the host.
/// let mut scratch: Box<Scratch> = Box::default();
/// let filters = [Filter::standard(0x100), Filter::standard(0x101)];
/// let plan = plan_in(&filters, PlanOptions::new(14), &mut scratch)?;
/// assert_eq!(plan.bank_count(), 1);
/// # Ok::<(), twocan_bxcan::PlanError>(())
/// ```
pub const fn plan_in<'s, const K: usize>(
    filters: &[Filter],
    options: PlanOptions,
    scratch: &'s mut Scratch<K>,
) -> Result<&'s FilterPlan<K>, PlanError> {
    match plan_into(filters, options, scratch) {
        Ok(()) => Ok(&scratch.out),
        Err(e) => Err(e),
    }
}

/// [`plan`] for a driver with room for `K` lookup keys ([`crate::Init::with_lookup_capacity`]):
/// the plan needs at most `K`. Builds its own [`Scratch`] (on the stack at run time:
/// for `const` code and the host; firmware uses [`plan_in`]).
pub const fn plan_for<const K: usize>(
    filters: &[Filter],
    options: PlanOptions,
) -> Result<FilterPlan<K>, PlanError> {
    let mut s = Scratch::<K>::new();
    match plan_into(filters, options, &mut s) {
        Ok(()) => Ok(s.out),
        Err(e) => Err(e),
    }
}

/// Compiles `filters` into the fewest banks (see the module documentation), for the
/// default driver ([`LOOKUP_KEYS`] lookup keys: a merged plan that would need more
/// gives way to one that needs fewer, or the list is refused with both counts).
///
/// A `const fn`: with a `const` list, [`crate::const_plan!`] plans it at compile time
/// and keeps only what the plan needs. At run time it builds its working memory
/// ([`Scratch`], about 90 KB) on the stack: fine on a host; firmware plans with
/// [`plan_in`] and the scratch in a `static`.
///
/// Errors: [`PlanError::TooManyFilters`] beyond [`MAX_FILTERS`] (given and maximum),
/// [`PlanError::Filter`] for a non-conforming filter, [`PlanError::TooManyBanks`] (banks
/// needed after merging and available) when the plan needs more than `options.banks`
/// banks (or more than 28) and the superset fallback is off or cannot help (general
/// filters alone too many), [`PlanError::TooManyLookupKeys`] when every plan that fits
/// the banks needs more lookup keys than the driver keeps.
///
/// ```
/// use twocan_bxcan::{plan, Fifo, PlanError, PlanOptions};
/// use twocan_core::{Filter, FilterError, Format, Frame, FrameKind};
///
/// let filters = [
///     Filter::standard(0x100),                                              // user 0
///     Filter::standard(0x101),                                              // user 1
///     Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_FF00, 0x0001_2300), // user 2
/// ];
/// let p = plan(&filters, PlanOptions::new(14))?;
/// assert!(p.bank_count() <= 2 && p.is_proven_optimal());
/// // What the hardware will accept, and the user index the driver reports.
/// let hit = p.evaluate(&Frame::standard(0x101, &[])?).unwrap();
/// assert_eq!((hit.fifo, hit.filter), (Fifo::Fifo0, 1));
/// assert_eq!(p.evaluate(&Frame::extended(0x0001_23AB, &[])?).unwrap().filter, 2);
/// assert_eq!(p.evaluate(&Frame::standard(0x102, &[])?), None); // rejected in hardware
///
/// // Bad input: the failing filter's index, or the banks needed and available.
/// let bad = [Filter::standard(0x100), Filter::standard(0x800)];
/// assert_eq!(
///     plan(&bad, PlanOptions::new(14)).unwrap_err(),
///     PlanError::Filter { index: 1, error: FilterError::IdOutOfRange }
/// );
/// let many: Vec<Filter> = (0..9).map(|i| Filter::extended(i * 0x1357)).collect();
/// assert!(matches!(
///     plan(&many, PlanOptions::new(4)),
///     Err(PlanError::TooManyBanks { needed: 5, available: 4 })
/// ));
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
pub const fn plan(filters: &[Filter], options: PlanOptions) -> Result<FilterPlan, PlanError> {
    plan_for::<LOOKUP_KEYS>(filters, options)
}

/// [`plan_for`] with room for every key ([`MAX_LOOKUP_KEYS`]), or a compile-time error
/// with a readable message: the first step of [`crate::const_plan!`].
#[doc(hidden)]
pub const fn plan_or_panic(
    filters: &[Filter],
    options: PlanOptions,
) -> FilterPlan<MAX_LOOKUP_KEYS> {
    match plan_for::<MAX_LOOKUP_KEYS>(filters, options) {
        Ok(p) => p,
        Err(e) => e.panic(),
    }
}

/// Plans of a two-bus application sharing the CAN1/CAN2 filter block, and the
/// `CAN2SB` that gives each instance the banks it needs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DualPlan<const K: usize = LOOKUP_KEYS> {
    /// The first bank of CAN2 (`CAN_FMR.CAN2SB`): CAN1 owns banks `0..can2sb`.
    pub can2sb: u8,
    /// CAN1's plan (banks `0..can2sb`).
    pub can1: FilterPlan<K>,
    /// CAN2's plan (banks `can2sb..28`).
    pub can2: FilterPlan<K>,
}

/// The working memory of [`plan_dual_in`] and its result.
pub struct DualScratch<const K: usize = LOOKUP_KEYS> {
    scratch: Scratch<K>,
    plan: DualPlan<K>,
}

impl<const K: usize> Default for DualScratch<K> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const K: usize> DualScratch<K> {
    /// Fresh working memory (all zeros).
    pub const fn new() -> Self {
        DualScratch {
            scratch: Scratch::new(),
            plan: DualPlan {
                can2sb: 0,
                can1: FilterPlan::zeroed(),
                can2: FilterPlan::zeroed(),
            },
        }
    }
}

/// Banks `list` needs with the whole block and no superset.
const fn need<const K: usize>(
    list: &[Filter],
    exact: PlanOptions,
    s: &mut Scratch<K>,
) -> Result<u16, PlanError> {
    match plan_into(list, exact, s) {
        Ok(()) => Ok(s.out.bank_count() as u16),
        Err(PlanError::TooManyBanks { needed, .. }) => Ok(needed),
        Err(e) => Err(e),
    }
}

const fn plan_dual_into<const K: usize>(
    can1: &[Filter],
    can2: &[Filter],
    options: PlanOptions,
    d: &mut DualScratch<K>,
) -> Result<(), PlanError> {
    let exact = PlanOptions {
        banks: FILTER_BANKS as u8,
        superset: false,
        ..options
    };
    let n1 = match need(can1, exact, &mut d.scratch) {
        Ok(n) => n,
        Err(e) => return Err(e),
    };
    let n2 = match need(can2, exact, &mut d.scratch) {
        Ok(n) => n,
        Err(e) => return Err(e),
    };
    let total = FILTER_BANKS as u16;
    let can2sb = if n1 + n2 <= total {
        n1 as u8
    } else if options.superset {
        // Share the block in proportion to the needs; each list is merged down.
        let share = (n1 as u32 * total as u32) / (n1 as u32 + n2 as u32);
        if share < 1 {
            1
        } else if share > 27 {
            27
        } else {
            share as u8
        }
    } else {
        return Err(PlanError::DualTooManyBanks {
            can1_needed: n1,
            can2_needed: n2,
            available: FILTER_BANKS as u8,
        });
    };
    let one = PlanOptions {
        banks: can2sb,
        ..options
    };
    if let Err(e) = plan_into(can1, one, &mut d.scratch) {
        return Err(e);
    }
    if let Err(e) = d.plan.can1.copy_from(d.scratch.out.as_ref()) {
        return Err(e);
    }
    let two = PlanOptions {
        banks: FILTER_BANKS as u8 - can2sb,
        ..options
    };
    if let Err(e) = plan_into(can2, two, &mut d.scratch) {
        return Err(e);
    }
    if let Err(e) = d.plan.can2.copy_from(d.scratch.out.as_ref()) {
        return Err(e);
    }
    d.plan.can2sb = can2sb;
    Ok(())
}

/// [`plan_dual`] with the working memory and the result in `scratch` (see [`plan_in`]).
pub const fn plan_dual_in<'s, const K: usize>(
    can1: &[Filter],
    can2: &[Filter],
    options: PlanOptions,
    scratch: &'s mut DualScratch<K>,
) -> Result<&'s DualPlan<K>, PlanError> {
    match plan_dual_into(can1, can2, options, scratch) {
        Ok(()) => Ok(&scratch.plan),
        Err(e) => Err(e),
    }
}

/// [`plan_dual`] for drivers with room for `K` lookup keys (see [`plan_for`]).
pub const fn plan_dual_for<const K: usize>(
    can1: &[Filter],
    can2: &[Filter],
    options: PlanOptions,
) -> Result<DualPlan<K>, PlanError> {
    let mut d = DualScratch::<K>::new();
    match plan_dual_into(can1, can2, options, &mut d) {
        Ok(()) => Ok(d.plan),
        Err(e) => Err(e),
    }
}

/// Plans CAN1's and CAN2's lists together and chooses `CAN2SB` so that both fit the 28
/// banks of the shared block: CAN1 gets the banks its plan needs, CAN2 the rest (with
/// the spare banks left to CAN2). `options.banks` is ignored; the other options apply
/// to both lists. A `const fn`, as [`plan`].
///
/// Errors: [`PlanError::DualTooManyBanks`] with each list's need when together they
/// need more than 28 banks (a list that alone needs more than 28 shows as such), or the
/// first list's [`PlanError::Filter`] / [`PlanError::TooManyFilters`] /
/// [`PlanError::TooManyLookupKeys`].
///
/// ```
/// use twocan_bxcan::{plan_dual, PlanError, PlanOptions};
/// use twocan_core::Filter;
///
/// // CAN1: 6 extended identifiers (3 banks of two 32-bit list entries);
/// // CAN2: 4 standard identifiers (one bank of four 16-bit list entries).
/// let can1: Vec<Filter> = (0..6).map(|i| Filter::extended(0x1000 + i * 0x1357)).collect();
/// let can2: Vec<Filter> = (0..4).map(|i| Filter::standard(0x100 + i * 0x13)).collect();
/// let dual = plan_dual(&can1, &can2, PlanOptions::default().merge(false))?;
/// assert_eq!(dual.can2sb, 3); // CAN1 gets banks 0..3, CAN2 the other 25
/// assert_eq!((dual.can1.bank_count(), dual.can2.bank_count()), (3, 1));
///
/// // Together more than the block's 28 banks: each list's need is reported.
/// let big: Vec<Filter> = (0..40).map(|i| Filter::extended(i * 0x1357)).collect();
/// assert_eq!(
///     plan_dual(&big, &big, PlanOptions::default().merge(false)).unwrap_err(),
///     PlanError::DualTooManyBanks { can1_needed: 20, can2_needed: 20, available: 28 }
/// );
/// # Ok::<(), PlanError>(())
/// ```
pub const fn plan_dual(
    can1: &[Filter],
    can2: &[Filter],
    options: PlanOptions,
) -> Result<DualPlan, PlanError> {
    plan_dual_for::<LOOKUP_KEYS>(can1, can2, options)
}

/// The sizes a `const` plan of `filters` needs ([`crate::filters::SizedPlan`]): its
/// banks and its lookup keys (a compile-time error for a list that does not fit).
pub const fn plan_sizes(filters: &[Filter], options: PlanOptions) -> PlanSizes {
    plan_or_panic(filters, options).sizes()
}

/// Plans a `const` filter list at compile time: `const_plan!(FILTERS, options)` gives a
/// `&'static` [`SizedPlan`](crate::filters::SizedPlan) of exactly the banks and lookup
/// keys the plan needs, computed by the same `const fn` as the run-time planner
/// ([`planner::plan_in`](crate::planner::plan_in)). `FILTERS` is a `const` (or any
/// constant expression) of type `[Filter; N]` or `&[Filter]`; `options` a constant
/// [`PlanOptions`](crate::PlanOptions). Install it with
/// [`Init::set_filters`](crate::Init::set_filters).
///
/// A list that does not fit is a compile-time error naming the counts, e.g. "the
/// filters need 5 banks, 4 are available".
///
/// ```
/// use twocan_bxcan::{const_plan, Fifo, PlanOptions};
/// use twocan_core::{Filter, Format, Frame, FrameKind};
///
/// const FILTERS: [Filter; 3] = [
///     Filter::standard(0x100),
///     Filter::standard(0x101),
///     Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_FF00, 0x0001_2300),
/// ];
/// let plan = const_plan!(FILTERS, PlanOptions::new(14));
/// assert_eq!(plan.bank_count(), 2); // one 16-bit list bank, one 32-bit mask bank
/// assert_eq!(plan.lookup_keys().0.len(), 0); // no merged slot: no lookup key
/// let hit = plan.evaluate(&Frame::standard(0x101, &[]).unwrap()).unwrap();
/// assert_eq!((hit.fifo, hit.filter), (Fifo::Fifo0, 1));
/// // Sized to the plan: two banks and their slot users, nothing else.
/// assert!(core::mem::size_of_val(plan) < 100);
/// ```
///
/// A list that needs more banks than given does not compile:
///
/// ```compile_fail
/// use twocan_bxcan::{const_plan, PlanOptions};
/// use twocan_core::Filter;
///
/// const MANY: [Filter; 9] = {
///     let mut f = [Filter::extended(0); 9];
///     let mut i = 0;
///     while i < 9 {
///         f[i] = Filter::extended(i as u32 * 0x1357);
///         i += 1;
///     }
///     f
/// };
/// // error: evaluation panicked: twocan_bxcan::const_plan!: the filters need 5 banks,
/// // 4 are available
/// let plan = const_plan!(MANY, PlanOptions::new(4));
/// ```
#[macro_export]
macro_rules! const_plan {
    ($filters:expr, $options:expr $(,)?) => {{
        #[allow(long_running_const_eval)]
        const FULL: $crate::FilterPlan<{ $crate::filters::MAX_LOOKUP_KEYS }> =
            $crate::planner::plan_or_panic(&$filters, $options);
        const SIZES: $crate::filters::PlanSizes = FULL.sizes();
        const PLAN: $crate::filters::SizedPlan<{ SIZES.banks }, { SIZES.keys }> = FULL.sized();
        &PLAN
    }};
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_counts_banks_by_residue() {
        let mut s = 0;
        let mut total = 0;
        for _ in 0..9 {
            let (o, n) = step(s, L16, 1);
            total += o;
            s = n;
        }
        assert_eq!(total, 3);
        assert_eq!(step(0, M32, 2).0, 2);
        assert_eq!(step(0, L32, 2), (1, 0));
    }

    /// Exhaustive search over every class assignment that satisfies the order
    /// constraint: the branch-and-bound must find the same bank count.
    fn brute_force(p: &Problem) -> u16 {
        let n = p.n;
        let mut best = u16::MAX;
        let mut classes = [0u8; MAX_FILTERS];
        let total = 4usize.pow(n as u32);
        'next: for code in 0..total {
            let mut c = code;
            for cl in classes.iter_mut().take(n) {
                *cl = (c % 4) as u8;
                c /= 4;
            }
            let mut counts = [0u16; CLASSES];
            for j in 0..n {
                let k = classes[j] as usize;
                if p.options[j][k] == 0 {
                    continue 'next;
                }
                for i in 0..j {
                    if p.earlier[j] & (1 << i) != 0 && classes[i] > classes[j] {
                        continue 'next;
                    }
                }
                counts[k] += p.options[j][k] as u16;
            }
            let cost = counts[L32].div_ceil(2)
                + counts[M32]
                + counts[L16].div_ceil(4)
                + counts[M16].div_ceil(2);
            best = best.min(cost);
        }
        best
    }

    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> u32 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 33) as u32
        }
    }

    fn random_filter(r: &mut Lcg) -> Filter {
        let kind = [FrameKind::Data, FrameKind::Remote, FrameKind::Any][(r.next() % 3) as usize];
        match r.next() % 6 {
            0 => Filter::exact(kind, Format::Standard, 0x100 + r.next() % 8),
            1 => Filter::exact(kind, Format::Extended, 0x100 + r.next() % 8),
            2 => {
                let mask = 0x7FF & !(r.next() % 8);
                Filter::masked(kind, Format::Standard, mask, (0x100 + r.next() % 8) & mask)
            }
            3 => {
                let mask = 0x1FFF_FFFF & !(r.next() % 4);
                Filter::masked(kind, Format::Extended, mask, (0x100 + r.next() % 8) & mask)
            }
            4 => {
                let mask = EXT_BITS_IN_16BIT & !((r.next() % 4) << 15);
                Filter::masked(kind, Format::Extended, mask, ((r.next() % 4) << 15) & mask)
            }
            _ => Filter::kind_format(
                kind,
                [Format::Standard, Format::Extended, Format::Any][(r.next() % 3) as usize],
            ),
        }
    }

    fn prepared(list: &[Filter]) -> Box<Prepared> {
        let mut p = Box::new(Prepared::ZERO);
        p.fill(list).unwrap();
        p
    }

    /// The solved attempt of `cubes` (a list of the cubes).
    fn attempt_of(prep: &Prepared, cubes: &[Cube]) -> Box<Attempt> {
        let mut list = Box::new(CubeList::new());
        for &c in cubes {
            list.push(c).unwrap();
        }
        let mut a = Box::new(Attempt::ZERO);
        let mut s = Box::new(SolveScratch::ZERO);
        attempt(prep, &list, &mut a, &mut s);
        a
    }

    #[test]
    fn branch_and_bound_matches_exhaustive_search() {
        let mut r = Lcg(7);
        for _ in 0..400 {
            let n = 1 + (r.next() % 7) as usize;
            let list: [Filter; 7] = core::array::from_fn(|_| random_filter(&mut r));
            let prep = prepared(&list[..n]);
            let singles: Vec<Cube> = prep.keys.keys().iter().map(|&k| Cube::single(k)).collect();
            let a = attempt_of(&prep, &singles);
            assert!(a.ok && a.proven);
            assert_eq!(a.banks, brute_force(&a.problem), "{:?}", &list[..n]);
        }
    }

    /// Every exact cube of two or more keys of `keys`.
    fn all_blocks(keys: &KeyTable) -> Vec<Cube> {
        let mut out: Vec<Cube> = Vec::new();
        for &k in keys.keys() {
            let bits = twocan_core::filter_set::id_bits(k);
            // Sub-masks of the low 4 identifier bits and bit 11/12 (the test sets' range).
            let span = bits & 0b1_1000_0000_1111;
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

    /// Exhaustive search over every cover (any set of exact blocks, singles for the
    /// rest): the fewest banks any of them takes.
    fn exhaustive_banks(list: &[Filter]) -> u16 {
        let prep = prepared(list);
        let blocks = all_blocks(&prep.keys);
        assert!(blocks.len() <= 14, "{}", blocks.len());
        let mut best = u16::MAX;
        for set in 0u32..(1 << blocks.len()) {
            let mut cubes: Vec<Cube> = (0..blocks.len())
                .filter(|b| set & (1 << b) != 0)
                .map(|b| blocks[b])
                .collect();
            for &k in prep.keys.keys() {
                if !cubes.iter().any(|c| c.contains(k)) {
                    cubes.push(Cube::single(k));
                }
            }
            best = best.min(attempt_of(&prep, &cubes).banks);
        }
        best
    }

    #[test]
    fn merged_plans_match_exhaustive_search_on_small_sets() {
        let mut r = Lcg(11);
        let mut merged_somewhere = false;
        for _ in 0..150 {
            let mut list = Vec::new();
            for _ in 0..(3 + r.next() % 8) {
                let id = r.next() % 16;
                let f = match r.next() % 4 {
                    0 => Filter::extended(0x1000 | id),
                    1 => Filter::exact(FrameKind::Remote, Format::Standard, 0x100 | id),
                    _ => Filter::standard(0x100 | id as u16),
                };
                list.push(f);
            }
            let got = plan(&list, PlanOptions::new(28).merge(true)).unwrap();
            let want = exhaustive_banks(&list);
            assert_eq!(got.bank_count() as u16, want, "{list:?}");
            merged_somewhere |= (got.bank_count() as u16) < got.list_only_banks();
        }
        assert!(merged_somewhere);
    }

    #[test]
    fn list_entries_enumerate_the_cell() {
        // A standard mask ignoring bits 0 and 2: four identifiers, ascending.
        let f = Filter::masked(FrameKind::Data, Format::Standard, 0x7FA, 0x100);
        let item = Item {
            filter: f,
            user: 7,
            pos: 7,
            cube: false,
            list: true,
        };
        assert_eq!(options(&item)[L16], 4);
        let (e, n) = entries(&item, L16, &KeyTable::<4>::new());
        let words: Vec<u32> = e[..n].iter().map(|e| e.v).collect();
        let want: Vec<u32> = [0x100, 0x101, 0x104, 0x105]
            .iter()
            .map(|&id| crate::filters::frame_word16(id, false, false) as u32)
            .collect();
        assert_eq!(words, want);
        assert!(e[..n].iter().all(|e| e.user == 7));
    }
}

/// The run-time planner's stack: every value [`plan_in`] and the functions it calls
/// hold by value is small (the tables are in the [`Scratch`]).
#[cfg(test)]
mod stack {
    use super::*;
    use core::mem::size_of;
    use twocan_core::filter_set::Key;

    #[test]
    fn by_value_types_on_the_run_time_path_are_small() {
        let sizes: [(&str, usize); 22] = [
            ("&[Filter]", size_of::<&[Filter]>()),
            ("PlanOptions", size_of::<PlanOptions>()),
            ("PlanError", size_of::<PlanError>()),
            (
                "Result<&FilterPlan, PlanError>",
                size_of::<Result<&FilterPlan, PlanError>>(),
            ),
            ("Filter", size_of::<Filter>()),
            ("Item", size_of::<Item>()),
            ("Entry", size_of::<Entry>()),
            ("([Entry; 4], usize)", size_of::<([Entry; 4], usize)>()),
            ("[Entry; 4] (pending)", size_of::<[Entry; 4]>()),
            ("Cube", size_of::<Cube>()),
            ("Option<Cube>", size_of::<Option<Cube>>()),
            ("Option<(u64, Cube)>", size_of::<Option<(u64, Cube)>>()),
            ("Bank", size_of::<Bank>()),
            ("[u16; STATES] (relaxed)", size_of::<[u16; STATES]>()),
            ("[u8; CLASSES]", size_of::<[u8; CLASSES]>()),
            (
                "Option<(u32, usize, u32, u8)> (search pick)",
                size_of::<Option<(u32, usize, u32, u8)>>(),
            ),
            (
                "Option<(Fifo, u8, u16)>",
                size_of::<Option<(Fifo, u8, u16)>>(),
            ),
            ("PlanRef", size_of::<crate::filters::PlanRef<'static>>()),
            ("([Key; 2], usize)", size_of::<([Key; 2], usize)>()),
            ("[u16; 4] (users)", size_of::<[u16; 4]>()),
            ("[usize; 2] (fmi counters)", size_of::<[usize; 2]>()),
            (
                "Result<u16, PlanError>",
                size_of::<Result<u16, PlanError>>(),
            ),
        ];
        for (name, size) in sizes {
            println!("{name}: {size} B");
            assert!(size <= 128, "{name}: {size} B");
        }
        // What is not by value: the scratch (in a `static`) and the plan (in it).
        println!("Scratch<64>: {} B", size_of::<Scratch>());
        println!("FilterPlan<64>: {} B", size_of::<FilterPlan>());
        assert!(size_of::<FilterPlan>() < 1024);
        // A `const` plan: its banks, their slot users and its keys.
        use crate::filters::SizedPlan;
        println!("SizedPlan<1, 0>: {} B", size_of::<SizedPlan<1, 0>>());
        println!("SizedPlan<2, 8>: {} B", size_of::<SizedPlan<2, 8>>());
        println!("SizedPlan<28, 64>: {} B", size_of::<SizedPlan<28, 64>>());
        assert_eq!(size_of::<SizedPlan<1, 0>>(), 32);
    }

    /// The largest list of the DBC corpus (367 identifiers, 365 extended) in superset
    /// mode, the scratch boxed, on a thread with a 64 KiB stack (debug builds' frames
    /// included): the planning call's stack does not grow with the list.
    #[test]
    fn plan_in_runs_on_a_small_stack() {
        let list: Vec<Filter> = (0..367u32)
            .map(|i| Filter::extended(0x0C00_0000 + i * 0x1_0203))
            .collect();
        // Made here (a `static` in firmware): `Box::default` builds it on this stack.
        // Room for every key: the superset plan looks all of them up.
        let mut scratch: Box<Scratch<MAX_LOOKUP_KEYS>> = Box::default();
        let t = std::thread::Builder::new()
            .stack_size(64 * 1024)
            .spawn(move || {
                let p = plan_in(&list, PlanOptions::new(28).superset(true), &mut scratch);
                p.map(|p| p.bank_count())
            })
            .unwrap();
        let r = t.join().unwrap();
        assert!(matches!(r, Ok(b) if b <= 28), "{r:?}");
        // With the default capacity the same list is refused, naming the keys.
        let list: Vec<Filter> = (0..367u32)
            .map(|i| Filter::extended(0x0C00_0000 + i * 0x1_0203))
            .collect();
        let mut small: Box<Scratch> = Box::default();
        assert!(matches!(
            plan_in(&list, PlanOptions::new(28).superset(true), &mut small),
            Err(PlanError::TooManyLookupKeys { max: 64, .. })
        ));
    }
}
