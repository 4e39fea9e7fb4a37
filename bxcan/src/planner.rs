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
//! 1. **Check** every filter ([`Filter::check`]): typed error with its index.
//! 2. **Narrow** by first-match semantics: a frame that an earlier filter accepts is
//!    always reported with that earlier index, so a later filter may drop it. Filter `j`
//!    loses a frame kind (data / remote) or, when format-free, a format, whose part is
//!    contained in one earlier filter; a filter contained entirely is dropped (it can
//!    never be reported).
//! 3. **Options**: for each remaining filter, how many entries of each class represent
//!    it exactly (a filter of kind "any" takes two list entries; a mask with a few
//!    don't-care bits may be listed in full, up to one bank's worth: 2 × 32-bit or 4 ×
//!    16-bit list entries).
//! 4. **Order constraint**: when two remaining filters `i < j` overlap (some frame
//!    matches both), the hardware must prefer `i`'s entries: class(i) ≤ class(j), and
//!    within one class the entries are laid out in user order so `i` gets the lower
//!    numbers. Overlapping filters are also kept in one FIFO.
//! 5. **Search**: each filter takes one class; the cost is
//!    `⌈n₀/2⌉ + n₁ + ⌈n₂/4⌉ + ⌈n₃/2⌉` banks. Because the cost of adding entries depends
//!    only on the residues `(n₀ mod 2, n₂ mod 4, n₃ mod 2)`, a dynamic programme over
//!    16 residue states gives the exact optimum **without** the order constraint; it is
//!    used as an admissible lower bound in a depth-first branch-and-bound that enforces
//!    the constraint. The search stops when it meets the bound (proven optimal) or after
//!    [`SEARCH_BUDGET`] nodes (then [`FilterPlan::is_proven_optimal`] is `false`; the plan
//!    is still exact). An all-32-bit-mask plan (always valid) seeds the search. Among
//!    plans with equally few banks the narrowest entries win (16-bit list, 16-bit mask,
//!    32-bit list, 32-bit mask): nine standard ids make three 16-bit list banks.
//! 6. **Layout**: per class, entries in user order, filling banks; the last bank of a
//!    list class is padded by repeating its last entry (same user index). Banks are
//!    assigned to FIFOs ([`FifoPolicy`]) and the FMI → user-index map is computed from
//!    the final layout.
//!
//! # Guarantees
//!
//! *Exact acceptance*: every entry accepts a subset of its (narrowed) filter, and the
//! entries of a filter together accept all of it, so the plan accepts exactly the union
//! of the user's filters. *Reported index*: for a frame whose first matching user filter
//! is `i`, an entry of `i` matches (narrowing only removed frames of earlier filters),
//! and any other matching entry belongs to a later filter overlapping `i`, which by 4.
//! is of a later class or of the same class with a higher number: the hardware reports
//! `i`. *Fewest banks*: among plans that give each filter entries of a single class with
//! the expansions of 3. (proof: exhaustive search with an admissible bound). Plans that
//! split one filter over several classes, or list a mask wider than one bank, are not
//! searched.

use twocan_core::{Filter, FilterError, Format, FrameKind};

use crate::filters::{
    frame_word16, list16_of, list32_of, mask16_of, mask32_of, Bank, BankKind, Fifo, FilterPlan,
    PlanError, EXT_BITS_IN_16BIT, NO_FILTER,
};
use crate::regs::FILTER_BANKS;

/// The largest user filter list the planner takes.
pub const MAX_FILTERS: usize = 128;

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

/// Planner options.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlanOptions {
    /// Banks available to the instance (CAN1: `CAN2SB`, CAN2: `28 − CAN2SB`, CAN3: 14).
    pub banks: u8,
    /// FIFO assignment.
    pub fifo: FifoPolicy,
}

impl PlanOptions {
    /// `banks` banks available, every bank to FIFO 0.
    pub const fn new(banks: u8) -> Self {
        PlanOptions {
            banks,
            fifo: FifoPolicy::Fifo0,
        }
    }

    /// The same options with another FIFO policy.
    pub const fn fifo(self, fifo: FifoPolicy) -> Self {
        PlanOptions { fifo, ..self }
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

fn kind_contains(outer: FrameKind, inner: FrameKind) -> bool {
    outer == FrameKind::Any || outer == inner
}

fn format_contains(outer: Format, inner: Format) -> bool {
    outer == Format::Any || outer == inner
}

/// Whether every frame `inner` accepts is accepted by `outer` (both conforming).
pub fn contains(outer: &Filter, inner: &Filter) -> bool {
    kind_contains(outer.kind, inner.kind)
        && format_contains(outer.format, inner.format)
        && outer.mask & !inner.mask == 0
        && inner.id & outer.mask == outer.id
}

/// Whether some frame is accepted by both (both conforming).
pub fn overlaps(a: &Filter, b: &Filter) -> bool {
    let kinds = a.kind == FrameKind::Any || b.kind == FrameKind::Any || a.kind == b.kind;
    let formats = a.format == Format::Any || b.format == Format::Any || a.format == b.format;
    kinds && formats && (a.id ^ b.id) & a.mask & b.mask == 0
}

/// Step 2: the part of `f` that no earlier filter takes, or `None` if nothing is left.
fn narrow(f: Filter, earlier: &[Filter]) -> Option<Filter> {
    let covered = |g: &Filter| earlier.iter().any(|e| contains(e, g));
    let mut f = f;
    for _ in 0..2 {
        if covered(&f) {
            return None;
        }
        if f.kind == FrameKind::Any {
            let data = Filter {
                kind: FrameKind::Data,
                ..f
            };
            let remote = Filter {
                kind: FrameKind::Remote,
                ..f
            };
            f = keep_uncovered_half(f, data, remote, &covered);
        }
        if f.format == Format::Any {
            let std = Filter {
                format: Format::Standard,
                ..f
            };
            let ext = Filter {
                format: Format::Extended,
                ..f
            };
            f = keep_uncovered_half(f, std, ext, &covered);
        }
    }
    if covered(&f) {
        None
    } else {
        Some(f)
    }
}

/// `f` split into halves `a` and `b` (by kind or by format): if earlier filters take one
/// half, only the other is left; otherwise `f` stays whole.
fn keep_uncovered_half(
    f: Filter,
    a: Filter,
    b: Filter,
    covered: &impl Fn(&Filter) -> bool,
) -> Filter {
    if covered(&a) {
        b
    } else if covered(&b) {
        a
    } else {
        f
    }
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

/// Step 3: number of entries of each class that represent `f` exactly (0 = impossible).
fn options(f: &Filter) -> [u8; CLASSES] {
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

/// Calls `out` with the entries of class `class` for `f` (consistent with [`options`]).
fn entries(f: &Filter, class: usize, user: u16, mut out: impl FnMut(Entry)) {
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
                            user,
                        });
                    }
                });
            }
        }
    }
}

/// Filters after narrowing, with their user indices, options and earlier overlaps.
struct Problem {
    n: usize,
    filters: [Filter; MAX_FILTERS],
    users: [u16; MAX_FILTERS],
    options: [[u8; CLASSES]; MAX_FILTERS],
    /// Bit i of `earlier[j]`: filter i < j overlaps j.
    earlier: [u128; MAX_FILTERS],
}

impl Problem {
    fn new(list: &[Filter]) -> Result<Self, PlanError> {
        if list.len() > MAX_FILTERS {
            return Err(PlanError::TooManyFilters);
        }
        for (i, f) in list.iter().enumerate() {
            f.check().map_err(|error: FilterError| PlanError::Filter {
                index: i as u16,
                error,
            })?;
        }
        let mut p = Problem {
            n: 0,
            filters: [Filter::pass_all(); MAX_FILTERS],
            users: [0; MAX_FILTERS],
            options: [[0; CLASSES]; MAX_FILTERS],
            earlier: [0; MAX_FILTERS],
        };
        for (i, f) in list.iter().enumerate() {
            if let Some(g) = narrow(*f, &list[..i]) {
                let j = p.n;
                p.filters[j] = g;
                p.users[j] = i as u16;
                p.options[j] = options(&g);
                let mut bits = 0u128;
                for k in 0..j {
                    if overlaps(&p.filters[k], &g) {
                        bits |= 1 << k;
                    }
                }
                p.earlier[j] = bits;
                p.n += 1;
            }
        }
        Ok(p)
    }

    /// Step 5: the class of each filter in a plan with the fewest banks, the bank count,
    /// and whether the search proved it optimal.
    ///
    /// Costs are `banks × SCALE + tie-break`, so that among plans with the fewest banks
    /// the one with the smallest tie-break weight ([`WEIGHT`]) is chosen.
    fn solve(&self) -> ([u8; MAX_FILTERS], u16, bool) {
        let n = self.n;
        let add = |s: u8, c: usize, count: u8| -> (u32, u8) {
            let (open, next) = step(s, c, count);
            (open as u32 * SCALE + count as u32 * WEIGHT[c], next)
        };
        // relax[j][s]: cheapest plan for filters j.. from state s, order constraint ignored.
        let mut relax = [[0u32; STATES]; MAX_FILTERS + 1];
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
        let mut best_classes = [M32 as u8; MAX_FILTERS];
        let mut best_cost = n as u32 * (SCALE + WEIGHT[M32]);
        let banks = |cost: u32| (cost / SCALE) as u16;
        if best_cost == bound {
            return (best_classes, banks(best_cost), true);
        }

        let mut classes = [0u8; MAX_FILTERS];
        let mut tried = [0u8; MAX_FILTERS + 1];
        let mut state = [0u8; MAX_FILTERS + 1];
        let mut cost = [0u32; MAX_FILTERS + 1];
        let mut j = 0usize;
        let mut nodes = 0u32;
        let mut proven = true;
        loop {
            if j == n {
                if cost[n] < best_cost {
                    best_cost = cost[n];
                    best_classes = classes;
                    if best_cost == bound {
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
    parent: [u16; MAX_FILTERS + FILTER_BANKS],
}

impl Groups {
    fn new() -> Self {
        let mut parent = [0u16; MAX_FILTERS + FILTER_BANKS];
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
/// Errors: [`PlanError::TooManyFilters`] beyond [`MAX_FILTERS`], [`PlanError::Filter`] for
/// a non-conforming filter, [`PlanError::TooManyBanks`] when the smallest exact plan
/// needs more than `options.banks` banks (or more than 28).
pub fn plan(filters: &[Filter], options: PlanOptions) -> Result<FilterPlan, PlanError> {
    let p = Problem::new(filters)?;
    let (classes, cost, proven) = p.solve();
    let available = options.banks.min(FILTER_BANKS as u8);
    if cost > available as u16 {
        return Err(PlanError::TooManyBanks {
            needed: cost.min(255) as u8,
            available,
        });
    }

    // Step 6: layout, class by class, entries in user order.
    let mut out = FilterPlan::manual();
    let mut bank_of = [[0u8; 4]; MAX_FILTERS]; // banks holding each filter's entries (≤ 4)
    let mut bank_count_of = [0u8; MAX_FILTERS];
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
            entries(&p.filters[j], c, p.users[j], |e| {
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
    debug_assert_eq!(out.bank_count(), cost as usize);
    out.set_optimal(proven);

    match options.fifo {
        FifoPolicy::Fifo0 => {}
        FifoPolicy::Fifo1 => {
            for b in 0..out.bank_count() {
                out.set_fifo(b, Fifo::Fifo1);
            }
        }
        FifoPolicy::Balanced => balance(&p, &bank_of, &bank_count_of, &mut out),
    }
    Ok(out)
}

/// Assigns tied groups of banks to FIFOs, largest first, to the FIFO with fewer filters.
fn balance(
    p: &Problem,
    bank_of: &[[u8; 4]; MAX_FILTERS],
    counts: &[u8; MAX_FILTERS],
    out: &mut FilterPlan,
) {
    let mut g = Groups::new();
    for j in 0..p.n {
        for &bank in bank_of[j].iter().take(counts[j] as usize) {
            g.union(j, MAX_FILTERS + bank as usize);
        }
        let mut bits = p.earlier[j];
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            g.union(i, j);
            bits &= bits - 1;
        }
    }
    // Weight of each group root: number of user filters.
    let mut weight = [0u16; MAX_FILTERS + FILTER_BANKS];
    for j in 0..p.n {
        let r = g.find(j);
        weight[r] += 1;
    }
    let mut load = [0u16; 2];
    let mut fifo_of_root = [None::<Fifo>; MAX_FILTERS + FILTER_BANKS];
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
        let r = g.find(MAX_FILTERS + b);
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
            let p = Problem::new(&list[..n]).unwrap();
            let (_, cost, proven) = p.solve();
            assert!(proven);
            assert_eq!(cost, brute_force(&p), "{:?}", &list[..n]);
        }
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
