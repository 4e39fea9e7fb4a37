//! Identifier sets for the filter planners: first-match narrowing of a filter list,
//! frame keys, identifier cubes (what one mask filter accepts), exact cube covers of an
//! identifier set, superset merging, and the thread-side key table that maps an
//! identifier back to the user's filter index.
//!
//! Both backends' planners (bxCAN banks, FlexCAN ID table) build on this module; it knows
//! nothing of either hardware. Everything is fixed-capacity (no allocation).
//!
//! # Cubes
//!
//! A mask filter compares some identifier bits and ignores the others, so the
//! identifiers it accepts form a *cube*: a base identifier with every combination of the
//! ignored bits. A cube is *exact* for a set when every identifier of the cube is in the
//! set; a block like `0x500..=0x53F` is one exact cube (6 ignored bits). Identifiers of
//! different formats or frame kinds never share a cube (a [`Key`] puts format and kind
//! above the identifier bits, which cubes never ignore).

use crate::filter::{Filter, Format, FrameKind};

/// The most frame keys a [`KeyTable`] holds.
pub const MAX_KEYS: usize = 1024;

/// The most cubes a [`CubeList`] holds.
pub const MAX_CUBES: usize = 1024;

/// One (identifier, format, kind): bit 30 extended, bit 29 remote, bits 28..0 the raw
/// identifier.
pub type Key = u32;

const KEY_EXT: u32 = 1 << 30;
const KEY_RTR: u32 = 1 << 29;
const KEY_ID: u32 = 0x1FFF_FFFF;

/// The key of a frame.
pub const fn key(raw_id: u32, extended: bool, remote: bool) -> Key {
    (raw_id & KEY_ID) | if extended { KEY_EXT } else { 0 } | if remote { KEY_RTR } else { 0 }
}

/// The raw identifier, format (extended?) and kind (remote?) of a key.
pub const fn key_parts(k: Key) -> (u32, bool, bool) {
    (k & KEY_ID, k & KEY_EXT != 0, k & KEY_RTR != 0)
}

/// The identifier bits of a key's format (11 or 29).
pub const fn id_bits(k: Key) -> u32 {
    if k & KEY_EXT != 0 {
        0x1FFF_FFFF
    } else {
        0x7FF
    }
}

/// The cube of keys `k` with `k & !dc == base`: one format, one kind, the identifier
/// bits `dc` ignored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Cube {
    /// The key with every ignored bit cleared.
    pub base: Key,
    /// The ignored identifier bits (a subset of the format's identifier bits).
    pub dc: u32,
}

impl Cube {
    /// The cube of one key.
    pub const fn single(k: Key) -> Cube {
        Cube { base: k, dc: 0 }
    }

    /// Number of keys (`2^ignored bits`).
    pub const fn size(&self) -> u64 {
        1u64 << self.dc.count_ones()
    }

    /// Whether the cube has more than one key.
    pub const fn is_block(&self) -> bool {
        self.dc != 0
    }

    /// Whether `k` is in the cube.
    pub const fn contains(&self, k: Key) -> bool {
        k & !self.dc == self.base
    }

    /// Whether every key of `inner` is in `self`.
    pub const fn covers(&self, inner: &Cube) -> bool {
        self.dc & inner.dc == inner.dc && inner.base & !self.dc == self.base
    }

    /// Whether some key is in both.
    pub const fn meets(&self, other: &Cube) -> bool {
        (self.base ^ other.base) & !(self.dc | other.dc) == 0
    }

    /// The smallest cube holding both, if they share format and kind.
    pub const fn join(&self, other: &Cube) -> Option<Cube> {
        if (self.base ^ other.base) & (KEY_EXT | KEY_RTR) != 0 {
            return None;
        }
        let dc = self.dc | other.dc | (self.base ^ other.base);
        Some(Cube {
            base: self.base & !dc,
            dc,
        })
    }

    /// The portable filter accepting exactly the cube.
    pub const fn filter(&self) -> Filter {
        let (id, ext, rtr) = key_parts(self.base);
        let format = if ext {
            Format::Extended
        } else {
            Format::Standard
        };
        let kind = if rtr {
            FrameKind::Remote
        } else {
            FrameKind::Data
        };
        Filter::masked(kind, format, format.id_mask() & !self.dc, id)
    }

    /// Calls `out` with every key of the cube, in ascending order.
    pub fn for_each(&self, mut out: impl FnMut(Key)) {
        let mut sub: u32 = 0;
        loop {
            out(self.base | sub);
            if sub == self.dc {
                break;
            }
            sub = sub.wrapping_sub(self.dc) & self.dc;
        }
    }
}

/// Error: more keys or cubes than the fixed capacity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Full;

/// A sorted set of at most `N` keys, each with the user filter index it belongs to.
///
/// The planners work on the full-size table ([`MAX_KEYS`], 6 KiB: a transient on the
/// planning call's stack); a driver keeps only the keys its merged filters need to
/// resolve, in a table sized for that (e.g. `twocan_bxcan::filters::LOOKUP_KEYS`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct KeyTable<const N: usize = MAX_KEYS> {
    keys: [Key; N],
    users: [u16; N],
    len: u16,
}

impl<const N: usize> Default for KeyTable<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> KeyTable<N> {
    /// The capacity.
    pub const CAPACITY: usize = N;

    /// An empty table.
    pub const fn new() -> Self {
        KeyTable {
            keys: [0; N],
            users: [0; N],
            len: 0,
        }
    }

    /// The user index of each key, in key order.
    pub fn users(&self) -> &[u16] {
        &self.users[..self.len()]
    }

    /// Number of keys.
    pub const fn len(&self) -> usize {
        self.len as usize
    }

    /// Whether the table is empty.
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The keys, ascending.
    pub fn keys(&self) -> &[Key] {
        &self.keys[..self.len()]
    }

    /// Adds `k` for `user`; a key already present keeps its first user.
    pub fn insert(&mut self, k: Key, user: u16) -> Result<(), Full> {
        let n = self.len();
        match self.keys[..n].binary_search(&k) {
            Ok(_) => Ok(()),
            Err(at) => {
                if n == N {
                    return Err(Full);
                }
                self.keys.copy_within(at..n, at + 1);
                self.users.copy_within(at..n, at + 1);
                self.keys[at] = k;
                self.users[at] = user;
                self.len += 1;
                Ok(())
            }
        }
    }

    /// The user index of `k` (binary search, at most 10 steps), `None` if absent.
    pub fn lookup(&self, k: Key) -> Option<u16> {
        self.keys[..self.len()]
            .binary_search(&k)
            .ok()
            .map(|i| self.users[i])
    }

    /// Whether `k` is in the table.
    pub fn contains(&self, k: Key) -> bool {
        self.keys[..self.len()].binary_search(&k).is_ok()
    }

    /// How many keys of the table `c` holds (a scan of the keys between the cube's
    /// lowest and highest key: at most the table's length, whatever the cube's size).
    pub fn count_in(&self, c: &Cube) -> u64 {
        let lo = c.base;
        let hi = c.base | c.dc;
        let keys = self.keys();
        let start = keys.partition_point(|&k| k < lo);
        let end = keys.partition_point(|&k| k <= hi);
        keys[start..end].iter().filter(|&&k| c.contains(k)).count() as u64
    }

    /// Whether every key of `c` is in the table.
    pub fn holds(&self, c: &Cube) -> bool {
        c.size() <= self.len() as u64 && self.count_in(c) == c.size()
    }

    /// Whether the users of `c`'s keys in the table are all one user (returned).
    pub fn single_user(&self, c: &Cube) -> Option<u16> {
        let mut user = None;
        let mut mixed = false;
        for (i, &k) in self.keys().iter().enumerate() {
            if c.contains(k) {
                match user {
                    None => user = Some(self.users[i]),
                    Some(u) if u != self.users[i] => mixed = true,
                    _ => {}
                }
            }
        }
        if mixed {
            None
        } else {
            user
        }
    }

    /// The smallest user index among `c`'s keys in the table.
    pub fn first_user(&self, c: &Cube) -> Option<u16> {
        self.keys()
            .iter()
            .zip(self.users.iter())
            .filter(|(k, _)| c.contains(**k))
            .map(|(_, u)| *u)
            .min()
    }
}

/// A list of cubes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CubeList {
    cubes: [Cube; MAX_CUBES],
    len: u16,
}

impl Default for CubeList {
    fn default() -> Self {
        Self::new()
    }
}

impl CubeList {
    /// An empty list.
    pub const fn new() -> Self {
        CubeList {
            cubes: [Cube { base: 0, dc: 0 }; MAX_CUBES],
            len: 0,
        }
    }

    /// The cubes.
    pub fn as_slice(&self) -> &[Cube] {
        &self.cubes[..self.len as usize]
    }

    /// Number of cubes.
    pub const fn len(&self) -> usize {
        self.len as usize
    }

    /// Whether the list is empty.
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Appends a cube.
    pub fn push(&mut self, c: Cube) -> Result<(), Full> {
        if self.len() == MAX_CUBES {
            return Err(Full);
        }
        self.cubes[self.len()] = c;
        self.len += 1;
        Ok(())
    }

    fn remove(&mut self, i: usize) {
        let n = self.len();
        self.cubes.copy_within(i + 1..n, i);
        self.len -= 1;
    }

    /// Identifiers the cubes accept beyond `keys`: the size of the cubes' union minus
    /// the keys it holds (exact, overlaps counted once).
    pub fn extra(&self, keys: &KeyTable) -> u64 {
        let cubes = self.as_slice();
        let union: u64 = (0..cubes.len())
            .map(|i| count_outside(cubes[i], &cubes[..i]))
            .sum();
        let inside = keys
            .keys()
            .iter()
            .filter(|&&k| cubes.iter().any(|c| c.contains(k)))
            .count() as u64;
        union - inside
    }
}

/// Keys of `c` in none of `others`: `c` is split on a bit one of them fixes until each
/// piece is inside or outside it.
fn count_outside(c: Cube, others: &[Cube]) -> u64 {
    let Some((d, rest)) = others.split_first() else {
        return c.size();
    };
    if !c.meets(d) {
        return count_outside(c, rest);
    }
    if d.covers(&c) {
        return 0;
    }
    // `c` meets `d` without being inside it: some bit is free in `c` and fixed in `d`.
    let free = c.dc & !d.dc;
    let bit = free & free.wrapping_neg();
    let toward = Cube {
        base: c.base | (d.base & bit),
        dc: c.dc & !bit,
    };
    let away = Cube {
        base: c.base | (!d.base & bit),
        dc: c.dc & !bit,
    };
    count_outside(away, rest) + count_outside(toward, others)
}

/// Grows the cube of `seed` one ignored bit at a time while it stays inside `keys`,
/// trying the identifier bits in ascending (`up`) or descending order; the result is a
/// maximal exact cube holding `seed`.
fn grow(keys: &KeyTable, seed: Key, up: bool) -> Cube {
    let bits = id_bits(seed);
    let mut c = Cube::single(seed);
    loop {
        let mut grown = false;
        for i in 0..29 {
            let b = if up { i } else { 28 - i };
            let bit = 1u32 << b;
            if bits & bit == 0 || c.dc & bit != 0 {
                continue;
            }
            let wider = Cube {
                base: c.base & !bit,
                dc: c.dc | bit,
            };
            if keys.holds(&wider) {
                c = wider;
                grown = true;
            }
        }
        if !grown {
            return c;
        }
    }
}

/// A cover of `keys` by exact cubes that aims at the fewest *weighted* entries: a block
/// (a cube of two or more keys) is worth taking when it covers at least `min_gain`
/// keys not yet covered (with a block costing twice a single entry, as in bxCAN's
/// quarter-bank weights, `min_gain = 3`: two keys cost as much as singles; with a block
/// costing one single entry, as FlexCAN's table elements, `min_gain = 2`).
///
/// Greedy set cover over candidate cubes: for each key the maximal exact cube grown
/// from it with the low bits first and with the high bits first; the candidate covering
/// the most uncovered keys is taken while it covers `min_gain` or more; the keys left
/// are single cubes. Cubes may overlap (a key in two blocks); every cube is exact.
pub fn exact_cover(keys: &KeyTable, min_gain: u64, out: &mut CubeList) -> Result<(), Full> {
    let n = keys.len();
    let mut candidates = CubeList::new();
    if min_gain > 0 {
        for &k in keys.keys() {
            for up in [true, false] {
                let c = grow(keys, k, up);
                if c.is_block() && !candidates.as_slice().contains(&c) {
                    // Full candidate list: keep the ones found so far.
                    let _ = candidates.push(c);
                }
            }
        }
    }
    let mut covered = [0u64; MAX_KEYS / 64];
    let is_covered = |cov: &[u64; MAX_KEYS / 64], i: usize| cov[i / 64] & (1 << (i % 64)) != 0;
    loop {
        let mut best: Option<(u64, usize)> = None;
        for (ci, c) in candidates.as_slice().iter().enumerate() {
            let gain = keys
                .keys()
                .iter()
                .enumerate()
                .filter(|(i, k)| c.contains(**k) && !is_covered(&covered, *i))
                .count() as u64;
            if gain >= min_gain && best.is_none_or(|(g, _)| gain > g) {
                best = Some((gain, ci));
            }
        }
        let Some((_, ci)) = best else { break };
        let c = candidates.as_slice()[ci];
        candidates.remove(ci);
        out.push(c)?;
        for (i, k) in keys.keys().iter().enumerate() {
            if c.contains(*k) {
                covered[i / 64] |= 1 << (i % 64);
            }
        }
    }
    for i in 0..n {
        if !is_covered(&covered, i) {
            out.push(Cube::single(keys.keys()[i]))?;
        }
    }
    Ok(())
}

/// Every maximal exact cube holding `seed` (no exact cube of `keys` contains it and is
/// larger), pushed to `out` if not there yet; sub-cubes are explored bit by bit in
/// ascending order, at most `limit` of them.
fn maximal_cubes_of(keys: &KeyTable, seed: Key, out: &mut CubeList, limit: &mut u32) {
    let bits = id_bits(seed);
    // Depth-first over the exact cubes holding `seed`, adding bits in ascending order.
    fn walk(keys: &KeyTable, c: Cube, from: u32, bits: u32, out: &mut CubeList, limit: &mut u32) {
        if *limit == 0 {
            return;
        }
        *limit -= 1;
        let mut maximal = true;
        for b in 0..29 {
            let bit = 1u32 << b;
            if bits & bit == 0 || c.dc & bit != 0 {
                continue;
            }
            let wider = Cube {
                base: c.base & !bit,
                dc: c.dc | bit,
            };
            if keys.holds(&wider) {
                maximal = false;
                if b >= from {
                    walk(keys, wider, b + 1, bits, out, limit);
                }
            }
        }
        if maximal && c.is_block() && !out.as_slice().contains(&c) {
            // A full list keeps the cubes found so far.
            let _ = out.push(c);
        }
    }
    walk(keys, Cube::single(seed), 0, bits, out, limit);
}

/// A minimum-weight cover of `keys` by exact cubes — a block costs `block`, a single
/// key `single` — by branch and bound over the maximal exact cubes, started from the
/// weight of `seed` (a cover already known, e.g. [`exact_cover`]'s). Writes the cover to
/// `out` only if it is lighter than `seed`. Returns whether the search finished within
/// `budget` nodes (then the result, or `seed`, is a minimum over covers by maximal
/// cubes and singles, which is the minimum over all exact covers: a block can always
/// be enlarged to a maximal one at the same weight).
pub fn min_cover(
    keys: &KeyTable,
    block: u32,
    single: u32,
    seed: &CubeList,
    budget: u32,
    out: &mut CubeList,
) -> bool {
    let n = keys.len();
    let mut cands = CubeList::new();
    let mut limit = 64 * n as u32 + 1024;
    for &k in keys.keys() {
        maximal_cubes_of(keys, k, &mut cands, &mut limit);
    }
    let complete = limit > 0 && cands.len() < MAX_CUBES;
    let weight = |c: &Cube| if c.is_block() { block } else { single };
    let seed_weight: u32 = seed.as_slice().iter().map(weight).sum();
    // Each key's least possible share of the weight, scaled by 1024.
    let mut share = [0u32; MAX_KEYS];
    for (i, &k) in keys.keys().iter().enumerate() {
        let mut s = single * 1024;
        for c in cands.as_slice() {
            if c.contains(k) {
                let per = (block * 1024) / keys.count_in(c).max(1) as u32;
                s = s.min(per);
            }
        }
        share[i] = s;
    }
    struct Search<'a> {
        keys: &'a KeyTable,
        cands: &'a [Cube],
        share: &'a [u32; MAX_KEYS],
        count: [u16; MAX_KEYS],
        chosen: [u16; MAX_KEYS],
        depth: usize,
        best: u32,
        best_set: [u16; MAX_KEYS],
        best_len: usize,
        nodes: u32,
        budget: u32,
        block: u32,
        single: u32,
    }
    /// Marker in `chosen` for "this key alone" (a single), as `SINGLE_BASE + key index`.
    const SINGLE_BASE: u16 = 0x8000;
    impl Search<'_> {
        fn mark(&mut self, c: &Cube, add: bool) {
            let keys = self.keys.keys();
            let start = keys.partition_point(|&k| k < c.base);
            let end = keys.partition_point(|&k| k <= c.base | c.dc);
            for (k, count) in keys[start..end].iter().zip(&mut self.count[start..end]) {
                if c.contains(*k) {
                    if add {
                        *count += 1;
                    } else {
                        *count -= 1;
                    }
                }
            }
        }
        fn go(&mut self, cost: u32) {
            self.nodes += 1;
            if self.nodes > self.budget {
                return;
            }
            let n = self.keys.len();
            let mut bound = 0u32;
            let mut pick: Option<(usize, usize)> = None;
            for i in 0..n {
                if self.count[i] == 0 {
                    bound += self.share[i];
                    let k = self.keys.keys()[i];
                    let options = self.cands.iter().filter(|c| c.contains(k)).count();
                    if pick.is_none_or(|(_, o)| options < o) {
                        pick = Some((i, options));
                    }
                }
            }
            if cost * 1024 + bound >= self.best * 1024 {
                return;
            }
            let Some((i, _)) = pick else {
                self.best = cost;
                self.best_set[..self.depth].copy_from_slice(&self.chosen[..self.depth]);
                self.best_len = self.depth;
                return;
            };
            let k = self.keys.keys()[i];
            for ci in 0..self.cands.len() {
                let c = self.cands[ci];
                if !c.contains(k) {
                    continue;
                }
                self.mark(&c, true);
                self.chosen[self.depth] = ci as u16;
                self.depth += 1;
                self.go(cost + self.block);
                self.depth -= 1;
                self.mark(&c, false);
            }
            self.count[i] += 1;
            self.chosen[self.depth] = SINGLE_BASE + i as u16;
            self.depth += 1;
            self.go(cost + self.single);
            self.depth -= 1;
            self.count[i] -= 1;
        }
    }
    let mut s = Search {
        keys,
        cands: cands.as_slice(),
        share: &share,
        count: [0; MAX_KEYS],
        chosen: [0; MAX_KEYS],
        depth: 0,
        best: seed_weight,
        best_set: [0; MAX_KEYS],
        best_len: 0,
        nodes: 0,
        budget,
        block,
        single,
    };
    s.go(0);
    let finished = s.nodes <= budget && complete;
    if s.best < seed_weight {
        for &c in &s.best_set[..s.best_len] {
            let cube = if c >= SINGLE_BASE {
                Cube::single(keys.keys()[(c - SINGLE_BASE) as usize])
            } else {
                cands.as_slice()[c as usize]
            };
            // No more cubes than keys: room in the list.
            let _ = out.push(cube);
        }
    }
    finished
}

/// One superset merge: replaces the pair of cubes (of one format and kind, the join
/// allowed by `allowed`) whose join adds the fewest identifiers beyond what the two
/// held, by their join, and drops every other cube the join covers. Ties go to the
/// join that removes more cubes. Returns `false` when no pair can merge.
pub fn merge_step(cubes: &mut CubeList, allowed: impl Fn(&Cube) -> bool) -> bool {
    let n = cubes.len();
    // (added identifiers, -(cubes removed), i, j, join)
    let mut best: Option<(u64, usize, usize, Cube)> = None;
    for i in 0..n {
        let a = cubes.as_slice()[i];
        for j in i + 1..n {
            let b = cubes.as_slice()[j];
            let Some(join) = a.join(&b) else { continue };
            let overlap = if a.meets(&b) {
                Cube {
                    base: (a.base | b.base) & !(a.dc & b.dc),
                    dc: a.dc & b.dc,
                }
                .size()
            } else {
                0
            };
            let added = join.size() - (a.size() + b.size() - overlap);
            if best.is_some_and(|(x, _, _, _)| added >= x) {
                continue;
            }
            if !allowed(&join) {
                continue;
            }
            best = Some((added, i, j, join));
        }
    }
    let Some((_, _, _, join)) = best else {
        return false;
    };
    let mut i = 0;
    while i < cubes.len() {
        if join.covers(&cubes.as_slice()[i]) {
            cubes.remove(i);
        } else {
            i += 1;
        }
    }
    // Room was made: at least two cubes were removed.
    let _ = cubes.push(join);
    true
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

/// The part of `f` that no filter of `earlier` takes, or `None` if nothing is left.
///
/// By first-match semantics a frame an earlier filter accepts is always reported with
/// that earlier index, so `f` may drop it: `f` loses a frame kind (data / remote) or,
/// when format-free, a format, whose part lies inside one earlier filter; a filter
/// inside an earlier one is dropped.
pub fn narrow(f: Filter, earlier: &[Filter]) -> Option<Filter> {
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

/// The keys of a filter that accepts whole identifiers of one format (mask = every
/// identifier bit): one per frame kind it accepts. `None` for any other filter.
pub fn keys_of(f: &Filter) -> Option<([Key; 2], usize)> {
    if !f.is_exact() {
        return None;
    }
    let ext = f.format == Format::Extended;
    Some(match f.kind {
        FrameKind::Data => ([key(f.id, ext, false), 0], 1),
        FrameKind::Remote => ([key(f.id, ext, true), 0], 1),
        FrameKind::Any => ([key(f.id, ext, false), key(f.id, ext, true)], 2),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(ids: &[u32]) -> KeyTable {
        let mut t = KeyTable::new();
        for (i, &id) in ids.iter().enumerate() {
            t.insert(key(id, false, false), i as u16).unwrap();
        }
        t
    }

    #[test]
    fn a_block_is_one_cube() {
        let ids: [u32; 64] = core::array::from_fn(|i| 0x500 + i as u32);
        let t = table(&ids);
        let mut out = CubeList::new();
        exact_cover(&t, 3, &mut out).unwrap();
        assert_eq!(
            out.as_slice(),
            &[Cube {
                base: 0x500,
                dc: 0x3F
            }]
        );
        assert_eq!(out.extra(&t), 0);
        assert_eq!(t.lookup(key(0x523, false, false)), Some(0x23));
        assert_eq!(t.lookup(key(0x523, false, true)), None);
    }

    #[test]
    fn covers_are_exact_and_complete() {
        let ids = [0x100, 0x101, 0x102, 0x103, 0x104, 0x106, 0x200, 0x7FF];
        let t = table(&ids);
        let mut out = CubeList::new();
        exact_cover(&t, 3, &mut out).unwrap();
        for c in out.as_slice() {
            assert!(t.holds(c), "{c:?}");
        }
        for &id in &ids {
            assert!(out
                .as_slice()
                .iter()
                .any(|c| c.contains(key(id, false, false))));
        }
        // 0x100..=0x103 is a block; the second 4-block 0x100|0x102|0x104|0x106 would add
        // two keys only (a tie with two single entries): not taken.
        assert_eq!(out.as_slice().iter().filter(|c| c.is_block()).count(), 1);
        assert_eq!(out.len(), 5);
    }

    #[test]
    fn merging_adds_the_fewest_identifiers() {
        let mut cubes = CubeList::new();
        for id in [0x100u32, 0x101, 0x103, 0x400] {
            cubes.push(Cube::single(key(id, false, false))).unwrap();
        }
        assert!(merge_step(&mut cubes, |_| true));
        // 0x100 + 0x101: a 2-cube, nothing added.
        assert!(cubes.as_slice().contains(&Cube { base: 0x100, dc: 1 }));
        assert!(merge_step(&mut cubes, |_| true));
        // then 0x100..=0x103 (one identifier added, 0x102).
        assert!(cubes.as_slice().contains(&Cube { base: 0x100, dc: 3 }));
        let t = table(&[0x100, 0x101, 0x103, 0x400]);
        assert_eq!(cubes.extra(&t), 1);
        // Overlapping cubes: counted once.
        let mut o = CubeList::new();
        o.push(Cube {
            base: 0x100,
            dc: 0xF,
        })
        .unwrap();
        o.push(Cube {
            base: 0x100,
            dc: 0x33,
        })
        .unwrap();
        assert_eq!(o.extra(&table(&[0x100])), 16 + 16 - 4 - 1);
        // A remote and a data key never merge.
        let mut two = CubeList::new();
        two.push(Cube::single(key(5, false, false))).unwrap();
        two.push(Cube::single(key(5, false, true))).unwrap();
        assert!(!merge_step(&mut two, |_| true));
    }

    proptest::proptest! {
        /// Covers are exact (every cube inside the set) and complete; merging keeps
        /// every key and `extra` counts the union exactly (checked by enumeration of
        /// the 2048 standard identifiers).
        #[test]
        fn covers_and_merges(ids in proptest::collection::btree_set(0u32..0x800, 1..120),
                             remote in proptest::collection::btree_set(0u32..0x800, 0..20),
                             steps in 0usize..40) {
            let mut t = KeyTable::new();
            for (i, &id) in ids.iter().enumerate() {
                t.insert(key(id, false, false), i as u16).unwrap();
            }
            for (i, &id) in remote.iter().enumerate() {
                t.insert(key(id, false, true), (1000 + i) as u16).unwrap();
            }
            for min_gain in [2, 3] {
                let mut out = CubeList::new();
                exact_cover(&t, min_gain, &mut out).unwrap();
                for c in out.as_slice() {
                    proptest::prop_assert!(t.holds(c));
                }
                for &k in t.keys() {
                    proptest::prop_assert!(out.as_slice().iter().any(|c| c.contains(k)));
                }
                proptest::prop_assert_eq!(out.extra(&t), 0);
                let mut merged = out.clone();
                for _ in 0..steps {
                    if !merge_step(&mut merged, |_| true) {
                        break;
                    }
                }
                let mut union = 0u64;
                for id in 0..0x800 {
                    for rtr in [false, true] {
                        let k = key(id, false, rtr);
                        if merged.as_slice().iter().any(|c| c.contains(k)) {
                            union += 1;
                            continue;
                        }
                        proptest::prop_assert!(!t.contains(k), "key {:#x} lost", k);
                    }
                }
                proptest::prop_assert_eq!(merged.extra(&t), union - t.len() as u64);
            }
        }
    }

    #[test]
    fn cube_filter_accepts_the_cube() {
        let c = Cube {
            base: key(0x1234_5600, true, true),
            dc: 0xFF,
        };
        let f = c.filter();
        assert_eq!(f.check(), Ok(()));
        assert_eq!(f.kind, FrameKind::Remote);
        assert_eq!(f.mask, 0x1FFF_FF00);
    }
}
