//! Identifier sets for the filter planners: first-match narrowing of a filter list,
//! frame keys, identifier cubes (what one mask filter accepts), exact cube covers of an
//! identifier set, superset merging, and the thread-side key table that maps an
//! identifier back to the user's filter index.
//!
//! Both backends' planners (bxCAN banks, FlexCAN ID table) build on this module; it knows
//! nothing of either hardware. Everything is fixed-capacity (no allocation).
//!
//! # One implementation, at compile time and at run time
//!
//! Every function the planners use is a `const fn` (loops, explicit indices and
//! hand-written searches: no iterator, closure or trait call), so that a filter list
//! that is a `const` is planned during constant evaluation by the very code that plans
//! a list known only at run time. The working tables are not locals: they are the
//! fields of a [`CoverScratch`] the caller passes by `&mut`, so a firmware that plans at
//! run time keeps them in a `static` and the call's stack frame stays small; the
//! searches that were recursive keep their stacks in the scratch too.
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

/// The most frame keys a [`KeyTable`] holds by default (and the planners' key table:
/// two keys per filter of [`FrameKind::Any`], 512 filters).
pub const MAX_KEYS: usize = 1024;

/// The most cubes a [`CubeList`] holds.
pub const MAX_CUBES: usize = 1024;

/// The most keys [`min_cover`] searches (its search stack holds one level per key).
pub const MIN_COVER_KEYS: usize = 256;

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

/// The first index of the ascending `keys` whose key is `>= x` (`keys.len()` if none).
pub const fn lower_bound(keys: &[Key], x: Key) -> usize {
    lower_bound_in(keys, keys.len(), x)
}

/// [`lower_bound`] over `keys[..n]` (no sub-slice made: cheaper in `const` code). `n`
/// is clamped to the slice, so the search never indexes past it: with a table of
/// capacity 0 (a lean filter map) it compiles to nothing, no bounds-check panic path.
const fn lower_bound_in(keys: &[Key], n: usize, x: Key) -> usize {
    let n = if n < keys.len() { n } else { keys.len() };
    let (mut lo, mut hi) = (0, n);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if keys[mid] < x {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The first index of the ascending `keys` whose key is `> x` (`keys.len()` if none).
pub const fn upper_bound(keys: &[Key], x: Key) -> usize {
    upper_bound_in(keys, keys.len(), x)
}

/// [`upper_bound`] over `keys[..n]`.
const fn upper_bound_in(keys: &[Key], n: usize, x: Key) -> usize {
    let n = if n < keys.len() { n } else { keys.len() };
    let (mut lo, mut hi) = (0, n);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if keys[mid] <= x {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
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
    /// The empty-list placeholder (the single key 0).
    pub const ZERO: Cube = Cube { base: 0, dc: 0 };

    /// The cube of one key.
    pub const fn single(k: Key) -> Cube {
        Cube { base: k, dc: 0 }
    }

    /// Whether both are the same cube (`==` in `const` code).
    pub const fn same(&self, other: &Cube) -> bool {
        self.base == other.base && self.dc == other.dc
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
/// The planners work on the full-size table ([`MAX_KEYS`], 6 KiB, in their scratch); a
/// plan keeps only the keys its merged filters need to resolve, in a table sized for
/// that (e.g. `twocan_bxcan::filters::LOOKUP_KEYS`, or exactly the keys of a `const`
/// plan).
#[derive(Clone)]
pub struct KeyTable<const N: usize = MAX_KEYS> {
    keys: [Key; N],
    users: [u16; N],
    len: u16,
}

/// Tables are equal when their keys and users are (whatever their capacities held
/// before).
impl<const N: usize> PartialEq for KeyTable<N> {
    fn eq(&self, other: &Self) -> bool {
        self.keys() == other.keys() && self.users() == other.users()
    }
}

impl<const N: usize> Eq for KeyTable<N> {}

impl<const N: usize> core::fmt::Debug for KeyTable<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("KeyTable")
            .field("keys", &self.keys())
            .field("users", &self.users())
            .finish()
    }
}

impl<const N: usize> Default for KeyTable<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> KeyTable<N> {
    /// The capacity.
    pub const CAPACITY: usize = N;

    /// An empty table (all zeros).
    pub const fn new() -> Self {
        KeyTable {
            keys: [0; N],
            users: [0; N],
            len: 0,
        }
    }

    /// Empties the table.
    pub const fn clear(&mut self) {
        self.len = 0;
    }

    /// The user index of each key, in key order.
    pub const fn users(&self) -> &[u16] {
        self.users.split_at(self.len as usize).0
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
    pub const fn keys(&self) -> &[Key] {
        self.keys.split_at(self.len as usize).0
    }

    /// Adds `k` for `user`; a key already present keeps its first user.
    pub const fn insert(&mut self, k: Key, user: u16) -> Result<(), Full> {
        let n = self.len();
        let at = lower_bound_in(&self.keys, n, k);
        if at < n && self.keys[at] == k {
            return Ok(());
        }
        if n == N {
            return Err(Full);
        }
        let mut i = n;
        while i > at {
            self.keys[i] = self.keys[i - 1];
            self.users[i] = self.users[i - 1];
            i -= 1;
        }
        self.keys[at] = k;
        self.users[at] = user;
        self.len += 1;
        Ok(())
    }

    /// Appends `k` for `user` after the last key, which must be smaller (a table built
    /// in key order, as [`KeyTable::copy_from`] does); `Err(Full)` when full.
    const fn push_sorted(&mut self, k: Key, user: u16) -> Result<(), Full> {
        let n = self.len();
        if n == N {
            return Err(Full);
        }
        self.keys[n] = k;
        self.users[n] = user;
        self.len += 1;
        Ok(())
    }

    /// Replaces the content with `keys` and their `users` (ascending keys, as another
    /// table's [`KeyTable::keys`] and [`KeyTable::users`]); `Err(Full)` (the table
    /// left empty) when they are more than `N`.
    pub const fn copy_from(&mut self, keys: &[Key], users: &[u16]) -> Result<(), Full> {
        self.len = 0;
        if keys.len() > N || users.len() != keys.len() {
            return Err(Full);
        }
        let mut i = 0;
        while i < keys.len() {
            if self.push_sorted(keys[i], users[i]).is_err() {
                self.len = 0;
                return Err(Full);
            }
            i += 1;
        }
        Ok(())
    }

    /// The position of `k` in [`KeyTable::keys`], `None` if absent.
    pub const fn position(&self, k: Key) -> Option<usize> {
        let n = self.len as usize;
        let at = lower_bound_in(&self.keys, n, k);
        if at < n && at < N && self.keys[at] == k {
            Some(at)
        } else {
            None
        }
    }

    /// The user index of `k` (binary search, at most 10 steps), `None` if absent.
    pub const fn lookup(&self, k: Key) -> Option<u16> {
        match self.position(k) {
            Some(i) if i < N => Some(self.users[i]),
            _ => None,
        }
    }

    /// Whether `k` is in the table.
    pub const fn contains(&self, k: Key) -> bool {
        self.position(k).is_some()
    }

    /// The range of [`KeyTable::keys`] between `c`'s lowest and highest key: every key
    /// of the table that `c` may hold is in it.
    pub const fn span(&self, c: &Cube) -> (usize, usize) {
        let n = self.len as usize;
        (
            lower_bound_in(&self.keys, n, c.base),
            upper_bound_in(&self.keys, n, c.base | c.dc),
        )
    }

    /// How many keys of the table `c` holds (a scan of the keys between the cube's
    /// lowest and highest key: at most the table's length, whatever the cube's size).
    pub const fn count_in(&self, c: &Cube) -> u64 {
        let (mut i, end) = self.span(c);
        let mut n = 0;
        while i < end {
            if self.keys[i] & !c.dc == c.base {
                n += 1;
            }
            i += 1;
        }
        n
    }

    /// Whether every key of `c` is in the table.
    pub const fn holds(&self, c: &Cube) -> bool {
        let size = c.size();
        if size > self.len() as u64 {
            return false;
        }
        let (mut i, end) = self.span(c);
        // Fewer keys between its lowest and highest than it has: not all there.
        if ((end - i) as u64) < size {
            return false;
        }
        let mut n = 0;
        while i < end {
            if self.keys[i] & !c.dc == c.base {
                n += 1;
            }
            i += 1;
        }
        n == size
    }

    /// Whether the users of `c`'s keys in the table are all one user (returned).
    pub const fn single_user(&self, c: &Cube) -> Option<u16> {
        let (mut i, end) = self.span(c);
        let mut user: Option<u16> = None;
        while i < end {
            if c.contains(self.keys[i]) {
                match user {
                    None => user = Some(self.users[i]),
                    Some(u) => {
                        if u != self.users[i] {
                            return None;
                        }
                    }
                }
            }
            i += 1;
        }
        user
    }

    /// The smallest user index among `c`'s keys in the table.
    pub const fn first_user(&self, c: &Cube) -> Option<u16> {
        let (mut i, end) = self.span(c);
        let mut user: Option<u16> = None;
        while i < end {
            if c.contains(self.keys[i]) {
                let u = self.users[i];
                user = match user {
                    Some(v) if v <= u => Some(v),
                    _ => Some(u),
                };
            }
            i += 1;
        }
        user
    }
}

/// A list of cubes.
#[derive(Clone)]
pub struct CubeList {
    cubes: [Cube; MAX_CUBES],
    len: u16,
}

/// Lists are equal when their cubes are.
impl PartialEq for CubeList {
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}

impl Eq for CubeList {}

impl core::fmt::Debug for CubeList {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_list().entries(self.as_slice()).finish()
    }
}

impl Default for CubeList {
    fn default() -> Self {
        Self::new()
    }
}

impl CubeList {
    /// An empty list (all zeros).
    pub const fn new() -> Self {
        CubeList {
            cubes: [Cube::ZERO; MAX_CUBES],
            len: 0,
        }
    }

    /// The cubes.
    pub const fn as_slice(&self) -> &[Cube] {
        self.cubes.split_at(self.len as usize).0
    }

    /// Cube `i` (`i < len`).
    pub const fn get(&self, i: usize) -> Cube {
        self.cubes[i]
    }

    /// Number of cubes.
    pub const fn len(&self) -> usize {
        self.len as usize
    }

    /// Whether the list is empty.
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Empties the list.
    pub const fn clear(&mut self) {
        self.len = 0;
    }

    /// Appends a cube.
    pub const fn push(&mut self, c: Cube) -> Result<(), Full> {
        if self.len() == MAX_CUBES {
            return Err(Full);
        }
        self.cubes[self.len()] = c;
        self.len += 1;
        Ok(())
    }

    /// Whether `c` is in the list.
    pub const fn has(&self, c: &Cube) -> bool {
        let mut i = 0;
        while i < self.len() {
            if self.cubes[i].same(c) {
                return true;
            }
            i += 1;
        }
        false
    }

    /// Replaces the content with `other`'s.
    pub const fn copy_from(&mut self, other: &CubeList) {
        let n = other.len();
        self.cubes
            .split_at_mut(n)
            .0
            .copy_from_slice(other.cubes.split_at(n).0);
        self.len = other.len;
    }

    /// Replaces the content with one single cube per key of `keys` (the cover of no
    /// merging).
    pub const fn set_singles(&mut self, keys: &[Key]) -> Result<(), Full> {
        self.len = 0;
        let mut i = 0;
        while i < keys.len() {
            if let Err(e) = self.push(Cube::single(keys[i])) {
                return Err(e);
            }
            i += 1;
        }
        Ok(())
    }

    /// Removes cube `i`, keeping the order of the others.
    pub const fn remove(&mut self, i: usize) {
        let n = self.len();
        let mut j = i;
        while j + 1 < n {
            self.cubes[j] = self.cubes[j + 1];
            j += 1;
        }
        self.len -= 1;
    }

    /// The weight of the list: `block` per cube of two or more keys, `single` per
    /// single key.
    pub const fn weight(&self, block: u32, single: u32) -> u32 {
        let mut w = 0;
        let mut i = 0;
        while i < self.len() {
            w += if self.cubes[i].is_block() {
                block
            } else {
                single
            };
            i += 1;
        }
        w
    }

    /// Identifiers the cubes accept beyond `keys`: the size of the cubes' union minus
    /// the keys it holds (exact, overlaps counted once).
    pub const fn extra<const N: usize>(
        &self,
        keys: &KeyTable<N>,
        scratch: &mut CoverScratch,
    ) -> u64 {
        let cubes = self.as_slice();
        let mut union = 0u64;
        let mut i = 0;
        while i < cubes.len() {
            union += count_outside(cubes[i], cubes.split_at(i).0, &mut scratch.split);
            i += 1;
        }
        let mut inside = 0u64;
        let k = keys.keys();
        let mut x = 0;
        while x < k.len() {
            let mut j = 0;
            while j < cubes.len() {
                if cubes[j].contains(k[x]) {
                    inside += 1;
                    break;
                }
                j += 1;
            }
            x += 1;
        }
        union - inside
    }
}

/// Depth of [`count_outside`]'s stack: each pending piece has fewer ignored bits than
/// the one below it (29 identifier bits at most).
const SPLIT_DEPTH: usize = 30;

/// Keys of `c` in none of `others`: `c` is split on a bit one of them fixes until each
/// piece is inside or outside it (the pieces still to count wait on `stack`).
const fn count_outside(c: Cube, others: &[Cube], stack: &mut [(Cube, u16); SPLIT_DEPTH]) -> u64 {
    let n = others.len();
    let mut total = 0u64;
    let mut sp = 0;
    let mut cur = c;
    let mut at = 0usize;
    loop {
        // Count `cur` from `others[at..]`.
        let mut done = false;
        while !done {
            if at == n {
                total += cur.size();
                done = true;
            } else {
                let d = others[at];
                if !cur.meets(&d) {
                    at += 1;
                } else if d.covers(&cur) {
                    done = true;
                } else {
                    // `cur` meets `d` without being inside it: a bit free in `cur` and
                    // fixed in `d`; the piece away from `d` is counted from the next
                    // cube, the piece toward it again against `d`.
                    let free = cur.dc & !d.dc;
                    let bit = free & free.wrapping_neg();
                    let away = Cube {
                        base: cur.base | (!d.base & bit),
                        dc: cur.dc & !bit,
                    };
                    stack[sp] = (away, (at + 1) as u16);
                    sp += 1;
                    cur = Cube {
                        base: cur.base | (d.base & bit),
                        dc: cur.dc & !bit,
                    };
                }
            }
        }
        if sp == 0 {
            return total;
        }
        sp -= 1;
        cur = stack[sp].0;
        at = stack[sp].1 as usize;
    }
}

/// One level of [`maximal_cubes_of`]'s depth-first walk.
#[derive(Debug, Clone, Copy)]
struct WalkFrame {
    cube: Cube,
    /// The lowest bit a wider cube may add and still be walked from here.
    from: u8,
    /// The next bit to try.
    bit: u8,
    /// No wider exact cube found so far.
    maximal: bool,
}

impl WalkFrame {
    const ZERO: WalkFrame = WalkFrame {
        cube: Cube::ZERO,
        from: 0,
        bit: 0,
        maximal: false,
    };
}

/// One level of [`min_cover`]'s branch and bound.
#[derive(Debug, Clone, Copy)]
struct SearchFrame {
    /// The uncovered key branched on (index in the key table).
    key: u16,
    /// Its position in the branching order (every key before it is covered here).
    pos: u16,
    /// The next candidate cube to try.
    next: u16,
    /// The branch in progress: a candidate, [`SINGLE_CHILD`] or [`NO_CHILD`].
    child: u16,
    /// The weight chosen above this level.
    cost: u32,
}

impl SearchFrame {
    const ZERO: SearchFrame = SearchFrame {
        key: 0,
        pos: 0,
        next: 0,
        child: 0,
        cost: 0,
    };
}

const NO_CHILD: u16 = u16::MAX;
const SINGLE_CHILD: u16 = u16::MAX - 1;

/// Marker in `chosen` for "this key alone" (a single), as `SINGLE_BASE + key index`.
const SINGLE_BASE: u16 = 0x8000;

/// Room for the (key, candidate) incidences of [`min_cover`]'s search.
const INCIDENCE: usize = 4096;

/// Working memory of [`exact_cover`], [`min_cover`] and [`CubeList::extra`]: the
/// candidate cubes, the search's per-key tables and the stacks of the (formerly
/// recursive) searches. All zeros when new: a `static` of it takes no flash.
#[derive(Debug, Clone)]
pub struct CoverScratch {
    cands: CubeList,
    covered: [u64; MAX_KEYS / 64],
    share: [u32; MIN_COVER_KEYS],
    options: [u16; MIN_COVER_KEYS],
    order: [u16; MIN_COVER_KEYS],
    count: [u16; MIN_COVER_KEYS],
    chosen: [u16; MIN_COVER_KEYS],
    best_set: [u16; MIN_COVER_KEYS],
    frames: [SearchFrame; MIN_COVER_KEYS],
    /// Each candidate's keys lie in `keys[cand_lo..cand_hi]`.
    cand_lo: [u16; MAX_CUBES],
    cand_hi: [u16; MAX_CUBES],
    /// The candidates holding key `i`, ascending: `incidence[start[i]..start[i + 1]]`
    /// (when they fit; the search scans the candidates otherwise).
    incidence_start: [u16; MIN_COVER_KEYS + 1],
    incidence: [u16; INCIDENCE],
    walk: [WalkFrame; 32],
    split: [(Cube, u16); SPLIT_DEPTH],
}

impl Default for CoverScratch {
    fn default() -> Self {
        Self::new()
    }
}

impl CoverScratch {
    /// Fresh working memory (all zeros).
    pub const fn new() -> Self {
        CoverScratch {
            cands: CubeList::new(),
            covered: [0; MAX_KEYS / 64],
            share: [0; MIN_COVER_KEYS],
            options: [0; MIN_COVER_KEYS],
            order: [0; MIN_COVER_KEYS],
            count: [0; MIN_COVER_KEYS],
            chosen: [0; MIN_COVER_KEYS],
            best_set: [0; MIN_COVER_KEYS],
            frames: [SearchFrame::ZERO; MIN_COVER_KEYS],
            cand_lo: [0; MAX_CUBES],
            cand_hi: [0; MAX_CUBES],
            incidence_start: [0; MIN_COVER_KEYS + 1],
            incidence: [0; INCIDENCE],
            walk: [WalkFrame::ZERO; 32],
            split: [(Cube::ZERO, 0); SPLIT_DEPTH],
        }
    }
}

/// Grows the cube of `seed` one ignored bit at a time while it stays inside `keys`,
/// trying the identifier bits in ascending (`up`) or descending order; the result is a
/// maximal exact cube holding `seed`.
const fn grow<const N: usize>(keys: &KeyTable<N>, seed: Key, up: bool) -> Cube {
    let bits = id_bits(seed);
    let mut c = Cube::single(seed);
    loop {
        let mut grown = false;
        let mut i = 0;
        while i < 29 {
            let b = if up { i } else { 28 - i };
            i += 1;
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

const fn is_covered(cov: &[u64; MAX_KEYS / 64], i: usize) -> bool {
    cov[i / 64] & (1 << (i % 64)) != 0
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
/// `out` is cleared first.
pub const fn exact_cover<const N: usize>(
    keys: &KeyTable<N>,
    min_gain: u64,
    out: &mut CubeList,
    scratch: &mut CoverScratch,
) -> Result<(), Full> {
    out.clear();
    let n = keys.len();
    let k = keys.keys();
    let cands = &mut scratch.cands;
    cands.clear();
    if min_gain > 0 {
        let mut i = 0;
        while i < n {
            let mut dir = 0;
            while dir < 2 {
                let c = grow(keys, k[i], dir == 0);
                if c.is_block() && !cands.has(&c) {
                    // Full candidate list: keep the ones found so far.
                    let _ = cands.push(c);
                }
                dir += 1;
            }
            i += 1;
        }
    }
    let covered = &mut scratch.covered;
    let mut w = 0;
    while w < covered.len() {
        covered[w] = 0;
        w += 1;
    }
    // Each candidate's keys lie in `k[lo..hi]`. A candidate's gain only falls as keys
    // are covered: one below `min_gain` (a taken one among them) is out for good, its
    // range emptied.
    let nc = cands.len();
    let mut ci = 0;
    while ci < nc {
        let (lo, hi) = keys.span(&cands.cubes[ci]);
        scratch.cand_lo[ci] = lo as u16;
        scratch.cand_hi[ci] = hi as u16;
        ci += 1;
    }
    loop {
        // (gain, candidate) of the first candidate covering the most uncovered keys.
        let mut best: Option<(u64, usize)> = None;
        let mut ci = 0;
        while ci < nc {
            let c = cands.cubes[ci];
            let mut i = scratch.cand_lo[ci] as usize;
            let end = scratch.cand_hi[ci] as usize;
            let mut gain = 0u64;
            while i < end {
                if k[i] & !c.dc == c.base && !is_covered(covered, i) {
                    gain += 1;
                }
                i += 1;
            }
            if gain < min_gain {
                scratch.cand_hi[ci] = scratch.cand_lo[ci];
            } else {
                let better = match best {
                    None => true,
                    Some((g, _)) => gain > g,
                };
                if better {
                    best = Some((gain, ci));
                }
            }
            ci += 1;
        }
        let ci = match best {
            Some((_, ci)) => ci,
            None => break,
        };
        let c = cands.cubes[ci];
        if let Err(e) = out.push(c) {
            return Err(e);
        }
        let mut i = scratch.cand_lo[ci] as usize;
        while i < scratch.cand_hi[ci] as usize {
            if k[i] & !c.dc == c.base {
                covered[i / 64] |= 1 << (i % 64);
            }
            i += 1;
        }
    }
    let mut i = 0;
    while i < n {
        if !is_covered(covered, i) {
            if let Err(e) = out.push(Cube::single(k[i])) {
                return Err(e);
            }
        }
        i += 1;
    }
    Ok(())
}

/// Every maximal exact cube holding `seed` (no exact cube of `keys` contains it and is
/// larger), pushed to `out` if not there yet; sub-cubes are explored bit by bit in
/// ascending order (depth first, a cube pushed after the wider ones walked from it), at
/// most `limit` of them.
const fn maximal_cubes_of<const N: usize>(
    keys: &KeyTable<N>,
    seed: Key,
    out: &mut CubeList,
    limit: &mut u32,
    walk: &mut [WalkFrame; 32],
) {
    let bits = id_bits(seed);
    if *limit == 0 {
        return;
    }
    *limit -= 1;
    walk[0] = WalkFrame {
        cube: Cube::single(seed),
        from: 0,
        bit: 0,
        maximal: true,
    };
    let mut sp = 1;
    while sp > 0 {
        let top = sp - 1;
        let b = walk[top].bit;
        if b < 29 {
            walk[top].bit = b + 1;
            let c = walk[top].cube;
            let bit = 1u32 << b;
            if bits & bit == 0 || c.dc & bit != 0 {
                continue;
            }
            let wider = Cube {
                base: c.base & !bit,
                dc: c.dc | bit,
            };
            if keys.holds(&wider) {
                walk[top].maximal = false;
                if b >= walk[top].from && *limit > 0 {
                    *limit -= 1;
                    walk[sp] = WalkFrame {
                        cube: wider,
                        from: b + 1,
                        bit: 0,
                        maximal: true,
                    };
                    sp += 1;
                }
            }
        } else {
            let f = walk[top];
            if f.maximal && f.cube.is_block() && !out.has(&f.cube) {
                // A full list keeps the cubes found so far.
                let _ = out.push(f.cube);
            }
            sp -= 1;
        }
    }
}

/// Adds (`add`) or removes one cover count of every key of `c` (whose keys lie in
/// `keys[lo..hi]`), keeping `bound` (the shares of the uncovered keys) up to date.
#[allow(clippy::too_many_arguments)]
const fn mark<const N: usize>(
    keys: &KeyTable<N>,
    c: &Cube,
    lo: usize,
    hi: usize,
    count: &mut [u16; MIN_COVER_KEYS],
    share: &[u32; MIN_COVER_KEYS],
    bound: &mut u32,
    add: bool,
) {
    let mut i = lo;
    while i < hi {
        if keys.keys[i] & !c.dc == c.base {
            if add {
                if count[i] == 0 {
                    *bound -= share[i];
                }
                count[i] += 1;
            } else {
                count[i] -= 1;
                if count[i] == 0 {
                    *bound += share[i];
                }
            }
        }
        i += 1;
    }
}

/// A minimum-weight cover of `keys` by exact cubes — a block costs `block`, a single
/// key `single` — by branch and bound over the maximal exact cubes, started from
/// `seed_weight`, the weight of a cover already known (e.g. [`exact_cover`]'s,
/// [`CubeList::weight`]). Writes the cover to `out` (cleared first) only if it is
/// lighter than the seed. Returns whether the search finished within `budget` nodes
/// (then the result, or the seed, is a minimum over covers by maximal cubes and
/// singles, which is the minimum over all exact covers: a block can always be enlarged
/// to a maximal one at the same weight). More than [`MIN_COVER_KEYS`] keys are not
/// searched (`false`, `out` empty).
pub const fn min_cover<const N: usize>(
    keys: &KeyTable<N>,
    block: u32,
    single: u32,
    seed_weight: u32,
    budget: u32,
    out: &mut CubeList,
    scratch: &mut CoverScratch,
) -> bool {
    out.clear();
    let n = keys.len();
    if n > MIN_COVER_KEYS {
        return false;
    }
    let k = keys.keys();
    let s = scratch;
    s.cands.clear();
    let mut limit = 64 * n as u32 + 1024;
    let mut i = 0;
    while i < n {
        maximal_cubes_of(keys, k[i], &mut s.cands, &mut limit, &mut s.walk);
        i += 1;
    }
    let complete = limit > 0 && s.cands.len() < MAX_CUBES;
    let nc = s.cands.len();
    // Each key's least possible share of the weight (scaled by 1024), and how many
    // candidates hold it (the search branches on the key with the fewest).
    let mut i = 0;
    while i < n {
        s.share[i] = single * 1024;
        s.options[i] = 0;
        s.count[i] = 0;
        i += 1;
    }
    let mut ci = 0;
    while ci < nc {
        let c = s.cands.cubes[ci];
        let (lo, hi) = keys.span(&c);
        s.cand_lo[ci] = lo as u16;
        s.cand_hi[ci] = hi as u16;
        let held = keys.count_in(&c);
        let per = (block * 1024) / if held == 0 { 1 } else { held as u32 };
        let mut x = lo;
        while x < hi {
            if keys.keys[x] & !c.dc == c.base {
                if per < s.share[x] {
                    s.share[x] = per;
                }
                s.options[x] += 1;
            }
            x += 1;
        }
        ci += 1;
    }
    // The candidates of each key, ascending.
    let mut total = 0usize;
    let mut i = 0;
    while i < n {
        s.incidence_start[i] = if total > u16::MAX as usize {
            u16::MAX
        } else {
            total as u16
        };
        total += s.options[i] as usize;
        i += 1;
    }
    let listed = total <= INCIDENCE;
    if listed {
        s.incidence_start[n] = total as u16;
        // `count` is the fill of each key's list here (zero again below).
        let mut ci = 0;
        while ci < nc {
            let c = s.cands.cubes[ci];
            let mut x = s.cand_lo[ci] as usize;
            while x < s.cand_hi[ci] as usize {
                if keys.keys[x] & !c.dc == c.base {
                    s.incidence[s.incidence_start[x] as usize + s.count[x] as usize] = ci as u16;
                    s.count[x] += 1;
                }
                x += 1;
            }
            ci += 1;
        }
        let mut i = 0;
        while i < n {
            s.count[i] = 0;
            i += 1;
        }
    }
    // The search branches on the uncovered key held by the fewest candidates (the
    // lowest index among equals): the first uncovered key in this order.
    let mut i = 0;
    while i < n {
        let x = i as u16;
        let mut j = i;
        while j > 0 && s.options[s.order[j - 1] as usize] > s.options[i] {
            s.order[j] = s.order[j - 1];
            j -= 1;
        }
        s.order[j] = x;
        i += 1;
    }
    // The least weight the uncovered keys can still add (scaled by 1024), kept up to
    // date as keys are covered and uncovered.
    let mut bound = 0u32;
    let mut i = 0;
    while i < n {
        bound += s.share[i];
        i += 1;
    }
    let mut best = seed_weight;
    let mut best_len = 0usize;
    let mut depth = 0usize;
    let mut nodes = 0u32;
    let mut sp = 0usize;
    // The pending call of the search (its cost, and where its scan for an uncovered
    // key starts: every key before the caller's is covered), as the recursion
    // `go(cost)` was.
    let mut call: Option<(u32, usize)> = Some((0, 0));
    loop {
        if let Some((cost, start)) = call {
            call = None;
            nodes += 1;
            if nodes > budget {
                // Every later call would return at once: nothing changes any more.
                break;
            }
            let mut p = start;
            while p < n && s.count[s.order[p] as usize] != 0 {
                p += 1;
            }
            if cost * 1024 + bound < best * 1024 {
                if p == n {
                    best = cost;
                    s.best_set
                        .split_at_mut(depth)
                        .0
                        .copy_from_slice(s.chosen.split_at(depth).0);
                    best_len = depth;
                } else {
                    s.frames[sp] = SearchFrame {
                        key: s.order[p],
                        pos: p as u16,
                        next: 0,
                        child: NO_CHILD,
                        cost,
                    };
                    sp += 1;
                }
            }
        }
        if sp == 0 {
            break;
        }
        let top = sp - 1;
        let f = s.frames[top];
        let ki = f.key as usize;
        if f.child == SINGLE_CHILD {
            // Both kinds of branch done: this level returns.
            depth -= 1;
            s.count[ki] -= 1;
            bound += s.share[ki];
            sp -= 1;
            continue;
        }
        if f.child != NO_CHILD {
            depth -= 1;
            let ci = f.child as usize;
            let c = s.cands.cubes[ci];
            let (lo, hi) = (s.cand_lo[ci] as usize, s.cand_hi[ci] as usize);
            mark(keys, &c, lo, hi, &mut s.count, &s.share, &mut bound, false);
        }
        // The next candidate holding the key: from its list, or by a scan.
        let mut next = f.next as usize;
        let found = if listed {
            if next < s.options[ki] as usize {
                let ci = s.incidence[s.incidence_start[ki] as usize + next] as usize;
                next += 1;
                Some(ci)
            } else {
                None
            }
        } else {
            let mut ci = next;
            while ci < nc && !s.cands.cubes[ci].contains(k[ki]) {
                ci += 1;
            }
            next = ci + 1;
            if ci < nc {
                Some(ci)
            } else {
                None
            }
        };
        if let Some(ci) = found {
            let c = s.cands.cubes[ci];
            let (lo, hi) = (s.cand_lo[ci] as usize, s.cand_hi[ci] as usize);
            mark(keys, &c, lo, hi, &mut s.count, &s.share, &mut bound, true);
            s.chosen[depth] = ci as u16;
            depth += 1;
            s.frames[top].next = next as u16;
            s.frames[top].child = ci as u16;
            call = Some((f.cost + block, f.pos as usize));
        } else {
            // The key was uncovered when picked, and its blocks are undone.
            s.count[ki] += 1;
            bound -= s.share[ki];
            s.chosen[depth] = SINGLE_BASE + ki as u16;
            depth += 1;
            s.frames[top].child = SINGLE_CHILD;
            call = Some((f.cost + single, f.pos as usize));
        }
    }
    let finished = nodes <= budget && complete;
    if best < seed_weight {
        let mut j = 0;
        while j < best_len {
            let c = s.best_set[j];
            let cube = if c >= SINGLE_BASE {
                Cube::single(k[(c - SINGLE_BASE) as usize])
            } else {
                s.cands.get(c as usize)
            };
            // No more cubes than keys: room in the list.
            let _ = out.push(cube);
            j += 1;
        }
    }
    finished
}

/// Keys held by the blocks of `cubes` whose keys belong to several users: an upper
/// bound of the keys a plan of `cubes` leaves to the thread-side lookup (a block of one
/// user, a single key, or a block listed key by key needs none).
pub const fn multi_user_keys<const N: usize>(keys: &KeyTable<N>, cubes: &CubeList) -> usize {
    let mut n = 0;
    let mut i = 0;
    while i < cubes.len() {
        let c = cubes.get(i);
        if c.is_block() && keys.single_user(&c).is_none() {
            n += keys.count_in(&c) as usize;
        }
        i += 1;
    }
    n
}

/// Splits the blocks of `cubes` whose keys belong to several users until they hold at
/// most `max` keys ([`multi_user_keys`]): the smallest such block first, its lower half
/// (on its highest ignored bit) kept as a block, the keys of its upper half that no
/// other cube covers as single keys. Blocks of two keys go first, which costs no entry
/// (two single entries take the room of one block); a larger block loses about one
/// entry per key freed. The cover stays exact and complete.
pub const fn split_multi_user_blocks<const N: usize>(
    keys: &KeyTable<N>,
    cubes: &mut CubeList,
    max: usize,
) {
    loop {
        let mut estimate = 0usize;
        let mut smallest: Option<(usize, u64)> = None;
        let mut i = 0;
        while i < cubes.len() {
            let c = cubes.get(i);
            if c.is_block() && keys.single_user(&c).is_none() {
                let held = keys.count_in(&c);
                estimate += held as usize;
                let smaller = match smallest {
                    None => true,
                    Some((_, h)) => held < h,
                };
                if smaller {
                    smallest = Some((i, held));
                }
            }
            i += 1;
        }
        let i = match smallest {
            Some((i, _)) if estimate > max => i,
            _ => return,
        };
        let c = cubes.get(i);
        cubes.remove(i);
        let top = 1u32 << (31 - c.dc.leading_zeros());
        let half = c.dc & !top;
        // Room: one cube out, at most as many in as it held keys (never more cubes than
        // keys, MAX_CUBES = MAX_KEYS).
        let _ = cubes.push(Cube {
            base: c.base,
            dc: half,
        });
        let upper = Cube {
            base: c.base | top,
            dc: half,
        };
        let all = keys.keys();
        let (mut x, end) = keys.span(&upper);
        while x < end {
            let k = all[x];
            if upper.contains(k) {
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
                    let _ = cubes.push(Cube::single(k));
                }
            }
            x += 1;
        }
    }
}

/// Whether some filter of `general` accepts a frame of `c` (a superset cube may not:
/// the frame would be reported with the wrong index).
pub const fn meets_any(c: &Cube, general: &[Filter]) -> bool {
    let f = c.filter();
    let mut i = 0;
    while i < general.len() {
        if overlaps(&general[i], &f) {
            return true;
        }
        i += 1;
    }
    false
}

/// One superset merge: replaces the pair of cubes (of one format and kind, the join
/// meeting no filter of `general`) whose join adds the fewest identifiers beyond what
/// the two held, by their join, and drops every other cube the join covers. Returns
/// `false` when no pair can merge.
pub const fn merge_step(cubes: &mut CubeList, general: &[Filter]) -> bool {
    let n = cubes.len();
    // (added identifiers, join)
    let mut best: Option<(u64, Cube)> = None;
    let mut i = 0;
    while i < n {
        let a = cubes.get(i);
        let mut j = i + 1;
        while j < n {
            let b = cubes.get(j);
            j += 1;
            let join = match a.join(&b) {
                Some(x) => x,
                None => continue,
            };
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
            if let Some((x, _)) = best {
                if added >= x {
                    continue;
                }
            }
            if meets_any(&join, general) {
                continue;
            }
            best = Some((added, join));
        }
        i += 1;
    }
    let join = match best {
        Some((_, join)) => join,
        None => return false,
    };
    let mut i = 0;
    while i < cubes.len() {
        if join.covers(&cubes.get(i)) {
            cubes.remove(i);
        } else {
            i += 1;
        }
    }
    // Room was made: at least two cubes were removed.
    let _ = cubes.push(join);
    true
}

const fn kind_contains(outer: FrameKind, inner: FrameKind) -> bool {
    matches!(outer, FrameKind::Any) || outer as u8 == inner as u8
}

const fn format_contains(outer: Format, inner: Format) -> bool {
    matches!(outer, Format::Any) || outer as u8 == inner as u8
}

/// Whether every frame `inner` accepts is accepted by `outer` (both conforming).
pub const fn contains(outer: &Filter, inner: &Filter) -> bool {
    kind_contains(outer.kind, inner.kind)
        && format_contains(outer.format, inner.format)
        && outer.mask & !inner.mask == 0
        && inner.id & outer.mask == outer.id
}

/// Whether some frame is accepted by both (both conforming).
pub const fn overlaps(a: &Filter, b: &Filter) -> bool {
    let kinds = matches!(a.kind, FrameKind::Any)
        || matches!(b.kind, FrameKind::Any)
        || a.kind as u8 == b.kind as u8;
    let formats = matches!(a.format, Format::Any)
        || matches!(b.format, Format::Any)
        || a.format as u8 == b.format as u8;
    kinds && formats && (a.id ^ b.id) & a.mask & b.mask == 0
}

/// Whether a filter of `earlier` contains `g`.
const fn covered(g: &Filter, earlier: &[Filter]) -> bool {
    let mut i = 0;
    while i < earlier.len() {
        if contains(&earlier[i], g) {
            return true;
        }
        i += 1;
    }
    false
}

/// `b` if `a` is covered, `a` if `b` is, else `f`.
const fn keep_uncovered_half(f: Filter, a: Filter, b: Filter, earlier: &[Filter]) -> Filter {
    if covered(&a, earlier) {
        b
    } else if covered(&b, earlier) {
        a
    } else {
        f
    }
}

/// The part of `f` that no filter of `earlier` takes, or `None` if nothing is left.
///
/// By first-match semantics a frame an earlier filter accepts is always reported with
/// that earlier index, so `f` may drop it: `f` loses a frame kind (data / remote) or,
/// when format-free, a format, whose part lies inside one earlier filter; a filter
/// inside an earlier one is dropped.
pub const fn narrow(f: Filter, earlier: &[Filter]) -> Option<Filter> {
    let mut f = f;
    let mut round = 0;
    while round < 2 {
        round += 1;
        if covered(&f, earlier) {
            return None;
        }
        if matches!(f.kind, FrameKind::Any) {
            let data = Filter {
                kind: FrameKind::Data,
                ..f
            };
            let remote = Filter {
                kind: FrameKind::Remote,
                ..f
            };
            f = keep_uncovered_half(f, data, remote, earlier);
        }
        if matches!(f.format, Format::Any) {
            let std = Filter {
                format: Format::Standard,
                ..f
            };
            let ext = Filter {
                format: Format::Extended,
                ..f
            };
            f = keep_uncovered_half(f, std, ext, earlier);
        }
    }
    if covered(&f, earlier) {
        None
    } else {
        Some(f)
    }
}

/// The keys of a filter that accepts whole identifiers of one format (mask = every
/// identifier bit): one per frame kind it accepts. `None` for any other filter.
pub const fn keys_of(f: &Filter) -> Option<([Key; 2], usize)> {
    if !f.is_exact() {
        return None;
    }
    let ext = matches!(f.format, Format::Extended);
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

    fn cover(t: &KeyTable, min_gain: u64) -> CubeList {
        let mut out = CubeList::new();
        exact_cover(t, min_gain, &mut out, &mut CoverScratch::new()).unwrap();
        out
    }

    fn extra(cubes: &CubeList, t: &KeyTable) -> u64 {
        cubes.extra(t, &mut CoverScratch::new())
    }

    #[test]
    fn a_block_is_one_cube() {
        let ids: [u32; 64] = core::array::from_fn(|i| 0x500 + i as u32);
        let t = table(&ids);
        let out = cover(&t, 3);
        assert_eq!(
            out.as_slice(),
            &[Cube {
                base: 0x500,
                dc: 0x3F
            }]
        );
        assert_eq!(extra(&out, &t), 0);
        assert_eq!(t.lookup(key(0x523, false, false)), Some(0x23));
        assert_eq!(t.lookup(key(0x523, false, true)), None);
    }

    #[test]
    fn covers_are_exact_and_complete() {
        let ids = [0x100, 0x101, 0x102, 0x103, 0x104, 0x106, 0x200, 0x7FF];
        let t = table(&ids);
        let out = cover(&t, 3);
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
        assert!(merge_step(&mut cubes, &[]));
        // 0x100 + 0x101: a 2-cube, nothing added.
        assert!(cubes.as_slice().contains(&Cube { base: 0x100, dc: 1 }));
        assert!(merge_step(&mut cubes, &[]));
        // then 0x100..=0x103 (one identifier added, 0x102).
        assert!(cubes.as_slice().contains(&Cube { base: 0x100, dc: 3 }));
        let t = table(&[0x100, 0x101, 0x103, 0x400]);
        assert_eq!(extra(&cubes, &t), 1);
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
        assert_eq!(extra(&o, &table(&[0x100])), 16 + 16 - 4 - 1);
        // A remote and a data key never merge.
        let mut two = CubeList::new();
        two.push(Cube::single(key(5, false, false))).unwrap();
        two.push(Cube::single(key(5, false, true))).unwrap();
        assert!(!merge_step(&mut two, &[]));
        // A join that meets a general filter is not taken.
        let mut near = CubeList::new();
        near.push(Cube::single(key(0x100, false, false))).unwrap();
        near.push(Cube::single(key(0x102, false, false))).unwrap();
        let general = [Filter::standard(0x101)];
        assert!(merge_step(&mut near, &[]));
        near.clear();
        near.push(Cube::single(key(0x100, false, false))).unwrap();
        near.push(Cube::single(key(0x103, false, false))).unwrap();
        assert!(!merge_step(&mut near, &general));
    }

    /// The recursive form of the minimum-cover search, kept as the reference of the
    /// iterative one in [`min_cover`].
    fn min_cover_reference(keys: &KeyTable, block: u32, single: u32, seed: u32) -> Option<u32> {
        let mut cands = CubeList::new();
        let mut limit = 64 * keys.len() as u32 + 1024;
        let mut walk = [WalkFrame::ZERO; 32];
        for &k in keys.keys() {
            maximal_cubes_of(keys, k, &mut cands, &mut limit, &mut walk);
        }
        let cands = cands.as_slice().to_vec();
        fn go(
            keys: &KeyTable,
            cands: &[Cube],
            covered: &mut Vec<u16>,
            cost: u32,
            best: &mut u32,
            block: u32,
            single: u32,
        ) {
            let Some(i) = (0..keys.len()).find(|&i| covered[i] == 0) else {
                *best = (*best).min(cost);
                return;
            };
            if cost >= *best {
                return;
            }
            let k = keys.keys()[i];
            for c in cands.iter().filter(|c| c.contains(k)) {
                let touched: Vec<usize> = (0..keys.len())
                    .filter(|&j| c.contains(keys.keys()[j]))
                    .collect();
                touched.iter().for_each(|&j| covered[j] += 1);
                go(keys, cands, covered, cost + block, best, block, single);
                touched.iter().for_each(|&j| covered[j] -= 1);
            }
            covered[i] += 1;
            go(keys, cands, covered, cost + single, best, block, single);
            covered[i] -= 1;
        }
        let mut best = seed;
        let mut covered = vec![0u16; keys.len()];
        go(keys, &cands, &mut covered, 0, &mut best, block, single);
        (best < seed).then_some(best)
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
                let out = cover(&t, min_gain);
                for c in out.as_slice() {
                    proptest::prop_assert!(t.holds(c));
                }
                for &k in t.keys() {
                    proptest::prop_assert!(out.as_slice().iter().any(|c| c.contains(k)));
                }
                proptest::prop_assert_eq!(extra(&out, &t), 0);
                let mut merged = out.clone();
                for _ in 0..steps {
                    if !merge_step(&mut merged, &[]) {
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
                proptest::prop_assert_eq!(extra(&merged, &t), union - t.len() as u64);
            }
        }

        /// The iterative minimum-cover search finds the weight of an exhaustive
        /// recursive search over the same candidates, and its cover is exact and
        /// complete.
        #[test]
        fn min_cover_is_minimal(ids in proptest::collection::btree_set(0u32..0x40, 1..24)) {
            let t = table(&ids.iter().copied().collect::<Vec<_>>());
            let seed = cover(&t, 3).weight(2, 1);
            let mut out = CubeList::new();
            let finished = min_cover(&t, 2, 1, seed, 1_000_000, &mut out, &mut CoverScratch::new());
            proptest::prop_assert!(finished);
            let want = min_cover_reference(&t, 2, 1, seed);
            if out.is_empty() {
                proptest::prop_assert_eq!(want, None);
            } else {
                proptest::prop_assert_eq!(Some(out.weight(2, 1)), want);
                for c in out.as_slice() {
                    proptest::prop_assert!(t.holds(c));
                }
                for &k in t.keys() {
                    proptest::prop_assert!(out.as_slice().iter().any(|c| c.contains(k)));
                }
            }
        }
    }

    #[test]
    fn multi_user_blocks_are_split_to_the_capacity() {
        // 0x100..=0x17F: one block of 128 users.
        let ids: Vec<u32> = (0x100..0x180).collect();
        let t = table(&ids);
        let mut c = cover(&t, 3);
        assert_eq!(multi_user_keys(&t, &c), 128);
        split_multi_user_blocks(&t, &mut c, 64);
        assert_eq!(multi_user_keys(&t, &c), 64);
        // Exact and complete, one 64-block and 64 singles.
        assert_eq!(c.len(), 65);
        for &k in t.keys() {
            assert!(c.as_slice().iter().any(|x| x.contains(k)));
        }
        assert!(c.as_slice().iter().all(|x| t.holds(x)));
        split_multi_user_blocks(&t, &mut c, 0);
        assert_eq!(multi_user_keys(&t, &c), 0);
        assert_eq!(c.len(), 128);
    }

    #[test]
    fn key_table_keeps_order_and_first_user() {
        let mut t: KeyTable<4> = KeyTable::new();
        for (k, u) in [(5, 0), (1, 1), (3, 2), (5, 3)] {
            t.insert(k, u).unwrap();
        }
        assert_eq!(t.keys(), &[1, 3, 5]);
        assert_eq!(t.users(), &[1, 2, 0]);
        t.insert(0, 9).unwrap();
        assert_eq!(t.insert(7, 9), Err(Full));
        assert_eq!(t.lookup(5), Some(0));
        assert_eq!(t.lookup(2), None);
        let mut small: KeyTable<2> = KeyTable::new();
        assert_eq!(small.copy_from(t.keys(), t.users()), Err(Full));
        assert!(small.is_empty());
        small.copy_from(&t.keys()[..2], &t.users()[..2]).unwrap();
        assert_eq!(small.keys(), &[0, 1]);
    }

    /// The whole cover machinery runs in constant evaluation.
    const CONST_COVER: (usize, u64) = {
        let mut t: KeyTable = KeyTable::new();
        let mut i = 0;
        while i < 16 {
            let _ = t.insert(key(0x300 + i, false, false), i as u16);
            i += 1;
        }
        let _ = t.insert(key(0x7FF, false, false), 16);
        let mut out = CubeList::new();
        let mut s = CoverScratch::new();
        let _ = exact_cover(&t, 3, &mut out, &mut s);
        (out.len(), out.extra(&t, &mut s))
    };
    const _: () = assert!(CONST_COVER.0 == 2 && CONST_COVER.1 == 0);

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
