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
//!    entries (so merging never costs a bank).
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
    exact_cover, key, keys_of, merge_step, min_cover, narrow, Cube, CubeList, KeyTable,
};
use twocan_core::{Filter, FilterError, Format, FrameKind};

pub use twocan_core::filter_set::{contains, overlaps};

use crate::filters::{
    frame_word16, list16_of, list32_of, mask16_of, mask32_of, Bank, BankKind, Fifo, FilterPlan,
    PlanError, EXT_BITS_IN_16BIT, LOOKUP, NO_FILTER,
};
use crate::regs::FILTER_BANKS;

/// The largest user filter list the planner takes.
pub const MAX_FILTERS: usize = 512;

/// Items (general filters and cubes) the bank search holds: every item takes at least a
/// quarter bank, so more than `4 × 28 = 112` never fit.
const ITEMS: usize = 128;

/// Nodes of the minimum-weight cover search ([`min_cover`]).
pub const COVER_BUDGET: u32 = 20_000;

/// Keys up to which the minimum-weight cover search runs (its recursion is as deep as
/// the keys it covers one by one).
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlanOptions {
    /// Banks available to the instance (CAN1: `CAN2SB`, CAN2: `28 − CAN2SB`, CAN3: 14).
    pub banks: u8,
    /// FIFO assignment.
    pub fifo: FifoPolicy,
    /// Merge identifiers into exact mask entries (default `false` until the driver
    /// resolves merged entries with [`crate::filters::FmiMap::resolve`]: a merged slot's
    /// [`crate::filters::FmiMap::get`] is [`LOOKUP`], not a user index).
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

fn residue(s: u8, class: usize) -> u8 {
    match class {
        L32 => s & 1,
        L16 => (s >> 1) & 3,
        M16 => (s >> 3) & 1,
        _ => 0,
    }
}

fn with_residue(s: u8, class: usize, r: u8) -> u8 {
    match class {
        L32 => (s & !1) | r,
        L16 => (s & !0b110) | (r << 1),
        M16 => (s & !0b1000) | (r << 3),
        _ => s,
    }
}

/// Banks opened and the next state when `count` entries of `class` are added in state `s`.
fn step(s: u8, class: usize, count: u8) -> (u16, u8) {
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
fn dont_care(mask: u32, range: u32) -> u32 {
    !mask & range
}

/// The identifiers of the cells (values of the `care` bits) `f` covers, spread over the
/// don't-care bits `dc`: calls `out` with each identifier.
fn spread(id: u32, dc: u32, mut out: impl FnMut(u32)) {
    // Enumerate every subset of dc (Gosper-free: the standard sub-mask walk).
    let mut sub: u32 = 0;
    loop {
        out(id | sub);
        if sub == dc {
            break;
        }
        sub = (sub.wrapping_sub(dc)) & dc;
    }
}

fn kinds_of(kind: FrameKind) -> &'static [bool] {
    match kind {
        FrameKind::Data => &[false],
        FrameKind::Remote => &[true],
        FrameKind::Any => &[false, true],
    }
}

/// Step 5: number of entries of each class that represent `item` exactly (0 =
/// impossible).
fn options(item: &Item) -> [u8; CLASSES] {
    let f = &item.filter;
    let mut o = [0u8; CLASSES];
    o[M32] = 1;
    if mask16_of(f).is_some() {
        o[M16] = 1;
    }
    let kinds = kinds_of(f.kind).len() as u32;
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
    if item.user == LOOKUP && f.format == Format::Extended {
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

/// Calls `out` with the entries of class `class` for `item` (consistent with
/// [`options`]); a list entry of a cube of several users reports its key's user.
fn entries(item: &Item, class: usize, keys: &KeyTable, mut out: impl FnMut(Entry)) {
    let f = &item.filter;
    let user = item.user;
    let user_of = |id: u32, ext: bool, remote: bool| {
        if user == LOOKUP {
            keys.lookup(key(id, ext, remote)).unwrap_or(NO_FILTER)
        } else {
            user
        }
    };
    match class {
        M32 => {
            let (v, m) = mask32_of(f);
            out(Entry { v, m, user });
        }
        M16 => {
            if let Some((v, m)) = mask16_of(f) {
                out(Entry {
                    v: v as u32,
                    m: m as u32,
                    user,
                });
            }
        }
        L32 => {
            let range = f.format.id_mask();
            for &remote in kinds_of(f.kind) {
                spread(f.id, dont_care(f.mask, range), |id| {
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
                    if let Some(w) = list32_of(&single) {
                        let user = user_of(id, f.format == Format::Extended, remote);
                        out(Entry { v: w, m: 0, user });
                    }
                });
            }
        }
        _ => {
            let (range, ext) = match f.format {
                Format::Extended => (EXT_BITS_IN_16BIT, true),
                _ => (0x7FF, false),
            };
            for &remote in kinds_of(f.kind) {
                spread(f.id, dont_care(f.mask, range), |id| {
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
                    if let Some(w) = list16_of(&single) {
                        debug_assert_eq!(w, frame_word16(id, ext, remote));
                        out(Entry {
                            v: w as u32,
                            m: 0,
                            user: user_of(id, ext, remote),
                        });
                    }
                });
            }
        }
    }
}

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
    const NONE: Item = Item {
        filter: Filter::pass_all(),
        user: NO_FILTER,
        pos: 0,
        cube: false,
        list: false,
    };
}

/// Steps 1–3: the checked, narrowed list split into general filters and keys.
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
            f.check().map_err(|error: FilterError| PlanError::Filter {
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
        for (i, f) in list.iter().enumerate() {
            let Some(g) = narrow(*f, &list[..i]) else {
                continue;
            };
            if let Some((keys, n)) = keys_of(&g) {
                for &k in &keys[..n] {
                    // 2 × MAX_FILTERS keys at most: the table holds them all.
                    p.keys
                        .insert(k, i as u16)
                        .map_err(|_| PlanError::BankOutOfRange)?;
                }
            } else {
                p.general[p.n_general] = g;
                p.general_users[p.n_general] = i as u16;
                p.n_general += 1;
            }
        }
        Ok(p)
    }

    fn general(&self) -> &[Filter] {
        &self.general[..self.n_general]
    }

    /// The items of a cover: general filters, then cubes (unsorted).
    fn items<'a>(&'a self, cubes: &'a [Cube]) -> impl Iterator<Item = Item> + 'a {
        let general = self
            .general()
            .iter()
            .zip(self.general_users.iter())
            .map(|(f, &u)| Item {
                filter: *f,
                user: u,
                pos: u,
                cube: false,
                list: true,
            });
        let cubes = cubes.iter().map(move |c| {
            let exact = self.keys.count_in(c) == c.size();
            let user = if exact {
                self.keys.single_user(c).unwrap_or(LOOKUP)
            } else {
                LOOKUP
            };
            Item {
                filter: c.filter(),
                user,
                pos: self.keys.first_user(c).unwrap_or(u16::MAX),
                cube: true,
                list: exact,
            }
        });
        general.chain(cubes)
    }
}

/// The bank count of the best class choice for `items` with the order constraint
/// ignored (a lower bound; exact when no item overlaps a later general filter).
fn relaxed_banks(items: impl Iterator<Item = Item>) -> u16 {
    let mut cost = [u16::MAX; STATES];
    cost[0] = 0;
    for item in items {
        let o = options(&item);
        let mut next = [u16::MAX; STATES];
        for s in 0..STATES as u8 {
            if cost[s as usize] == u16::MAX {
                continue;
            }
            for (c, &count) in o.iter().enumerate() {
                if count == 0 {
                    continue;
                }
                let (open, n) = step(s, c, count);
                let v = cost[s as usize].saturating_add(open);
                if v < next[n as usize] {
                    next[n as usize] = v;
                }
            }
        }
        cost = next;
    }
    cost.iter().copied().min().unwrap_or(0)
}

/// Quarter banks a cube needs at least (std single 1, std block 2, ext single 2, ext
/// block 4): the trigger of the superset loop.
fn quarters(c: &Cube) -> u32 {
    let ext = twocan_core::filter_set::key_parts(c.base).1;
    match (ext, c.is_block()) {
        (false, false) => 1,
        (false, true) => 2,
        (true, false) => 2,
        (true, true) => 4,
    }
}

/// Items placed by the search, with their classes.
struct Attempt {
    problem: Problem,
    classes: [u8; ITEMS],
    banks: u16,
    proven: bool,
}

/// Steps 5–7 for one cover: the solved attempt, or the banks needed when there are too
/// many items to search (more than fit 28 banks anyway).
fn attempt(prep: &Prepared, cubes: &[Cube]) -> Result<Attempt, u16> {
    let problem = problem(prep, cubes)?;
    let (classes, banks, proven) = problem.solve();
    Ok(Attempt {
        problem,
        classes,
        banks,
        proven,
    })
}

/// The search problem of a cover: items sorted by their place in the order
/// constraint; `Err(banks needed)` when there are too many items to search.
fn problem(prep: &Prepared, cubes: &[Cube]) -> Result<Problem, u16> {
    let n = prep.n_general + cubes.len();
    if n > ITEMS {
        return Err(relaxed_banks(prep.items(cubes)));
    }
    let mut items = [Item::NONE; ITEMS];
    for (slot, item) in items.iter_mut().zip(prep.items(cubes)) {
        *slot = item;
    }
    items[..n].sort_unstable_by_key(|i| (i.pos, i.cube, i.filter.id, i.filter.mask));
    Ok(Problem::new(&items[..n]))
}

fn banks_of(a: &Result<Attempt, u16>) -> u16 {
    match a {
        Ok(a) => a.banks,
        Err(needed) => *needed,
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

impl Problem {
    fn new(items: &[Item]) -> Self {
        let mut p = Problem {
            n: items.len(),
            items: [Item::NONE; ITEMS],
            options: [[0; CLASSES]; ITEMS],
            earlier: [0; ITEMS],
        };
        for (j, item) in items.iter().enumerate() {
            p.items[j] = *item;
            p.options[j] = options(item);
            let mut bits = 0u128;
            for (k, other) in items[..j].iter().enumerate() {
                if !(other.cube && item.cube) && overlaps(&other.filter, &item.filter) {
                    bits |= 1 << k;
                }
            }
            p.earlier[j] = bits;
        }
        p
    }
    /// Step 5: the class of each filter in a plan with the fewest banks, the bank count,
    /// and whether the search proved it optimal.
    ///
    /// Costs are `banks × SCALE + tie-break`, so that among plans with the fewest banks
    /// the one with the smallest tie-break weight ([`WEIGHT`]) is chosen.
    fn solve(&self) -> ([u8; ITEMS], u16, bool) {
        let n = self.n;
        let add = |s: u8, c: usize, count: u8| -> (u32, u8) {
            let (open, next) = step(s, c, count);
            (open as u32 * SCALE + count as u32 * WEIGHT[c], next)
        };
        // relax[j][s]: cheapest plan for filters j.. from state s, order constraint ignored.
        let mut relax = [[0u32; STATES]; ITEMS + 1];
        for j in (0..n).rev() {
            for s in 0..STATES as u8 {
                let mut best = u32::MAX;
                for c in 0..CLASSES {
                    let count = self.options[j][c];
                    if count == 0 {
                        continue;
                    }
                    let (cost, next) = add(s, c, count);
                    best = best.min(cost + relax[j + 1][next as usize]);
                }
                relax[j][s as usize] = best;
            }
        }
        let bound = relax[0][0];

        // Seed: every filter in a 32-bit mask bank (always valid).
        let mut best_classes = [M32 as u8; ITEMS];
        let mut best_cost = n as u32 * (SCALE + WEIGHT[M32]);
        let banks = |cost: u32| (cost / SCALE) as u16;
        if best_cost == bound {
            return (best_classes, banks(best_cost), true);
        }

        let mut classes = [0u8; ITEMS];
        let mut tried = [0u8; ITEMS + 1];
        let mut state = [0u8; ITEMS + 1];
        let mut cost = [0u32; ITEMS + 1];
        let mut j = 0usize;
        let mut nodes = 0u32;
        let mut proven = true;
        loop {
            if j == n {
                if cost[n] < best_cost {
                    best_cost = cost[n];
                    best_classes = classes;
                    // Fewest banks reached: stop (the tie-break is best effort, the
                    // depth-first order tries the cheapest classes first).
                    if banks(best_cost) == banks(bound) {
                        break;
                    }
                }
                j -= 1;
                continue;
            }
            let floor = {
                let mut f = 0u8;
                let mut bits = self.earlier[j];
                while bits != 0 {
                    let i = bits.trailing_zeros() as usize;
                    f = f.max(classes[i]);
                    bits &= bits - 1;
                }
                f
            };
            let mut pick: Option<(u32, usize, u32, u8)> = None;
            for c in (floor as usize)..CLASSES {
                let count = self.options[j][c];
                if count == 0 || tried[j] & (1 << c) != 0 {
                    continue;
                }
                let (inc, next) = add(state[j], c, count);
                let estimate = cost[j] + inc + relax[j + 1][next as usize];
                if estimate >= best_cost {
                    continue;
                }
                if pick.is_none_or(|p| estimate < p.0) {
                    pick = Some((estimate, c, inc, next));
                }
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
                    tried[j] |= 1 << c;
                    classes[j] = c as u8;
                    state[j + 1] = next;
                    cost[j + 1] = cost[j] + inc;
                    j += 1;
                    tried[j] = 0;
                }
            }
        }
        // Fewest banks is proven when the search ran to its end, or when the bank count
        // met the bound's (the tie-break alone may be unproven).
        let proven = proven || banks(best_cost) == banks(bound);
        (best_classes, banks(best_cost), proven)
    }
}

/// Union-find over filters and banks, for FIFO balancing.
struct Groups {
    parent: [u16; ITEMS + FILTER_BANKS],
}

impl Groups {
    fn new() -> Self {
        let mut parent = [0u16; ITEMS + FILTER_BANKS];
        for (i, p) in parent.iter_mut().enumerate() {
            *p = i as u16;
        }
        Groups { parent }
    }
    fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] as usize != x {
            let up = self.parent[self.parent[x] as usize];
            self.parent[x] = up;
            x = up as usize;
        }
        x
    }
    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[ra.max(rb)] = ra.min(rb) as u16;
        }
    }
}

/// Compiles `filters` into the fewest banks (see the module documentation).
///
/// Errors: [`PlanError::TooManyFilters`] beyond [`MAX_FILTERS`] (given and maximum),
/// [`PlanError::Filter`] for a non-conforming filter, [`PlanError::TooManyBanks`] (banks
/// needed after merging and available) when the plan needs more than `options.banks`
/// banks (or more than 28) and the superset fallback is off or cannot help (general
/// filters alone too many).
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
pub fn plan(filters: &[Filter], options: PlanOptions) -> Result<FilterPlan, PlanError> {
    let prep = Prepared::new(filters)?;
    let available = options.banks.min(FILTER_BANKS as u8);
    let mut singles = CubeList::new();
    for &k in prep.keys.keys() {
        // No more keys than the cube list holds (MAX_KEYS = MAX_CUBES).
        singles
            .push(Cube::single(k))
            .map_err(|_| PlanError::BankOutOfRange)?;
    }
    let list_only = attempt(&prep, singles.as_slice());
    let list_only_banks = banks_of(&list_only);
    let mut covers = [CubeList::new(), CubeList::new(), CubeList::new()];
    let (mut best, mut cubes) = (list_only, &singles);
    if options.merge {
        // Blocks of three or more keys save entries; blocks of two save none but can
        // fill a half-used 16-bit mask bank: both covers are tried.
        for (cover, min_gain) in covers.iter_mut().zip([3, 2]) {
            exact_cover(&prep.keys, min_gain, cover).map_err(|_| PlanError::BankOutOfRange)?;
        }
        // The lightest cover (a block weighs two single entries), by branch and bound.
        if prep.keys.len() <= COVER_SEARCH_KEYS {
            let (head, tail) = covers.split_at_mut(2);
            min_cover(&prep.keys, 2, 1, &head[0], COVER_BUDGET, &mut tail[0]);
        }
        if covers[2].is_empty() {
            // Not lighter than the greedy cover (or not searched): no new candidate.
            covers[2] = covers[0].clone();
        }
        for cover in covers.iter() {
            let merged = attempt(&prep, cover.as_slice());
            if banks_of(&merged) < banks_of(&best) {
                best = merged;
                cubes = cover;
            }
        }
    }
    let needed = banks_of(&best);
    if let Ok(a) = best {
        if a.banks <= available as u16 {
            return layout(&prep, a, 0, list_only_banks, options);
        }
    }
    if !options.superset {
        return Err(PlanError::TooManyBanks { needed, available });
    }
    // Step 9: merge cubes into supersets until the plan fits.
    let mut grown = cubes.clone();
    let general_quarters: u32 = prep
        .items(&[])
        .map(|item| {
            let o = options_quarters(&self::options(&item));
            o as u32
        })
        .sum();
    let allowed = |c: &Cube| {
        let f = c.filter();
        !prep.general().iter().any(|g| overlaps(g, &f))
    };
    loop {
        let q: u32 = general_quarters + grown.as_slice().iter().map(quarters).sum::<u32>();
        if q <= 4 * available as u32
            && relaxed_banks(prep.items(grown.as_slice())) <= available as u16
        {
            if let Ok(a) = attempt(&prep, grown.as_slice()) {
                if a.banks <= available as u16 {
                    let extra = grown.extra(&prep.keys);
                    return layout(&prep, a, extra, list_only_banks, options);
                }
            }
        }
        if !merge_step(&mut grown, allowed) {
            return Err(PlanError::TooManyBanks { needed, available });
        }
    }
}

/// The fewest quarter banks one item's options take.
fn options_quarters(o: &[u8; CLASSES]) -> u8 {
    // Quarter banks per entry of each class: 32-bit list 2, 32-bit mask 4, 16-bit list
    // 1, 16-bit mask 2.
    const Q: [u8; CLASSES] = [2, 4, 1, 2];
    (0..CLASSES)
        .filter(|&c| o[c] != 0)
        .map(|c| o[c] * Q[c])
        .min()
        .unwrap_or(4)
}

/// Step 10: the banks of an attempt, in class order, entries in item order.
fn layout(
    prep: &Prepared,
    a: Attempt,
    extra: u64,
    list_only_banks: u16,
    options: PlanOptions,
) -> Result<FilterPlan, PlanError> {
    let p = &a.problem;
    let classes = &a.classes;
    let mut out = FilterPlan::manual();
    let mut bank_of = [[0u8; 4]; ITEMS]; // banks holding each item's entries (≤ 4)
    let mut bank_count_of = [0u8; ITEMS];
    for c in 0..CLASSES {
        let cap = CAP[c] as usize;
        let mut pending: [Option<Entry>; 4] = [None; 4];
        let mut fill = 0usize;
        let flush = |pending: &mut [Option<Entry>; 4], fill: &mut usize, out: &mut FilterPlan| {
            if *fill == 0 {
                return Ok(());
            }
            // Pad by repeating the last entry (same user index).
            let last = pending[*fill - 1];
            for slot in pending.iter_mut().take(cap).skip(*fill) {
                *slot = last;
            }
            let e: [Entry; 4] = core::array::from_fn(|i| {
                pending[i].unwrap_or(Entry {
                    v: 0,
                    m: 0,
                    user: NO_FILTER,
                })
            });
            let (fr1, fr2) = match c {
                M32 => (e[0].v, e[0].m),
                L32 => (e[0].v, e[1].v),
                L16 => (e[0].v | (e[1].v << 16), e[2].v | (e[3].v << 16)),
                _ => (e[0].v | (e[0].m << 16), e[1].v | (e[1].m << 16)),
            };
            let mut users = [NO_FILTER; 4];
            for (u, x) in users.iter_mut().zip(e.iter()).take(cap) {
                *u = x.user;
            }
            out.push(Bank::raw(KINDS[c], Fifo::Fifo0, fr1, fr2), users)?;
            *pending = [None; 4];
            *fill = 0;
            Ok::<(), PlanError>(())
        };
        for j in 0..p.n {
            if classes[j] as usize != c {
                continue;
            }
            let mut result = Ok(());
            entries(&p.items[j], c, &prep.keys, |e| {
                if result.is_err() {
                    return;
                }
                pending[fill] = Some(e);
                fill += 1;
                let bank = out.bank_count();
                let k = bank_count_of[j] as usize;
                if k < 4 && (k == 0 || bank_of[j][k - 1] as usize != bank) {
                    bank_of[j][k] = bank as u8;
                    bank_count_of[j] += 1;
                }
                if fill == cap {
                    result = flush(&mut pending, &mut fill, &mut out);
                }
            });
            result?;
        }
        flush(&mut pending, &mut fill, &mut out)?;
    }
    debug_assert_eq!(out.bank_count(), a.banks as usize);
    out.set_optimal(a.proven);
    out.set_resolution(&prep.keys, extra, list_only_banks)?;

    match options.fifo {
        FifoPolicy::Fifo0 => {}
        FifoPolicy::Fifo1 => {
            for b in 0..out.bank_count() {
                out.set_fifo(b, Fifo::Fifo1);
            }
        }
        FifoPolicy::Balanced => balance(p, &bank_of, &bank_count_of, &mut out),
    }
    Ok(out)
}

/// Plans of a two-bus application sharing the CAN1/CAN2 filter block, and the
/// `CAN2SB` that gives each instance the banks it needs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DualPlan {
    /// The first bank of CAN2 (`CAN_FMR.CAN2SB`): CAN1 owns banks `0..can2sb`.
    pub can2sb: u8,
    /// CAN1's plan (banks `0..can2sb`).
    pub can1: FilterPlan,
    /// CAN2's plan (banks `can2sb..28`).
    pub can2: FilterPlan,
}

/// Plans CAN1's and CAN2's lists together and chooses `CAN2SB` so that both fit the 28
/// banks of the shared block: CAN1 gets the banks its plan needs, CAN2 the rest (with
/// the spare banks left to CAN2). `options.banks` is ignored; the other options apply
/// to both lists.
///
/// Errors: [`PlanError::DualTooManyBanks`] with each list's need when together they
/// need more than 28 banks (a list that alone needs more than 28 shows as such), or the
/// first list's [`PlanError::Filter`] / [`PlanError::TooManyFilters`].
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
pub fn plan_dual(
    can1: &[Filter],
    can2: &[Filter],
    options: PlanOptions,
) -> Result<DualPlan, PlanError> {
    let exact = PlanOptions {
        banks: FILTER_BANKS as u8,
        superset: false,
        ..options
    };
    let need = |list: &[Filter]| -> Result<u16, PlanError> {
        match plan(list, exact) {
            Ok(p) => Ok(p.bank_count() as u16),
            Err(PlanError::TooManyBanks { needed, .. }) => Ok(needed),
            Err(e) => Err(e),
        }
    };
    let (n1, n2) = (need(can1)?, need(can2)?);
    let total = FILTER_BANKS as u16;
    let can2sb = if n1 + n2 <= total {
        n1 as u8
    } else if options.superset {
        // Share the block in proportion to the needs; each list is merged down.
        let share = ((n1 as u32 * total as u32) / (n1 as u32 + n2 as u32)).clamp(1, 27);
        share as u8
    } else {
        return Err(PlanError::DualTooManyBanks {
            can1_needed: n1,
            can2_needed: n2,
            available: FILTER_BANKS as u8,
        });
    };
    let one = plan(
        can1,
        PlanOptions {
            banks: can2sb,
            ..options
        },
    )?;
    let two = plan(
        can2,
        PlanOptions {
            banks: FILTER_BANKS as u8 - can2sb,
            ..options
        },
    )?;
    Ok(DualPlan {
        can2sb,
        can1: one,
        can2: two,
    })
}

/// Assigns tied groups of banks to FIFOs, largest first, to the FIFO with fewer filters.
fn balance(p: &Problem, bank_of: &[[u8; 4]; ITEMS], counts: &[u8; ITEMS], out: &mut FilterPlan) {
    let mut g = Groups::new();
    for j in 0..p.n {
        for &bank in bank_of[j].iter().take(counts[j] as usize) {
            g.union(j, ITEMS + bank as usize);
        }
        let mut bits = p.earlier[j];
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            g.union(i, j);
            bits &= bits - 1;
        }
        // Overlapping cubes do not constrain each other's class, but share a FIFO too:
        // a frame they both accept must have one FIFO whichever entry wins.
        for i in 0..j {
            if p.items[i].cube
                && p.items[j].cube
                && overlaps(&p.items[i].filter, &p.items[j].filter)
            {
                g.union(i, j);
            }
        }
    }
    // Weight of each group root: number of user filters.
    let mut weight = [0u16; ITEMS + FILTER_BANKS];
    for j in 0..p.n {
        let r = g.find(j);
        weight[r] += 1;
    }
    let mut load = [0u16; 2];
    let mut fifo_of_root = [None::<Fifo>; ITEMS + FILTER_BANKS];
    loop {
        // Heaviest unassigned group.
        let mut heaviest: Option<usize> = None;
        for r in 0..p.n {
            if g.find(r) == r
                && fifo_of_root[r].is_none()
                && weight[r] > 0
                && heaviest.is_none_or(|h| weight[r] > weight[h])
            {
                heaviest = Some(r);
            }
        }
        let Some(r) = heaviest else { break };
        let fifo = if load[1] < load[0] {
            Fifo::Fifo1
        } else {
            Fifo::Fifo0
        };
        load[fifo.index()] += weight[r];
        fifo_of_root[r] = Some(fifo);
    }
    for b in 0..out.bank_count() {
        let r = g.find(ITEMS + b);
        out.set_fifo(b, fifo_of_root[r].unwrap_or(Fifo::Fifo0));
    }
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

    #[test]
    fn branch_and_bound_matches_exhaustive_search() {
        let mut r = Lcg(7);
        for _ in 0..400 {
            let n = 1 + (r.next() % 7) as usize;
            let list: [Filter; 7] = core::array::from_fn(|_| random_filter(&mut r));
            let p = list_only_problem(&list[..n]);
            let (_, cost, proven) = p.solve();
            assert!(proven);
            assert_eq!(cost, brute_force(&p), "{:?}", &list[..n]);
        }
    }

    fn list_only_problem(list: &[Filter]) -> Problem {
        let prep = Prepared::new(list).unwrap();
        let singles: Vec<Cube> = prep.keys.keys().iter().map(|&k| Cube::single(k)).collect();
        problem(&prep, &singles).unwrap()
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
        let prep = Prepared::new(list).unwrap();
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
            best = best.min(banks_of(&attempt(&prep, &cubes)));
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
    fn spread_enumerates_subsets() {
        let mut v = [0u32; 8];
        let mut n = 0;
        spread(0x100, 0b101, |x| {
            v[n] = x;
            n += 1;
        });
        assert_eq!(&v[..n], &[0x100, 0x101, 0x104, 0x105]);
    }
}
