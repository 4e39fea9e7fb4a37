//! A bounded single-producer/single-consumer ring with ACAN-style statistics, shared
//! between one writer context and one reader context without a lock.
//!
//! [`SpscRing`] is what a `static` holds: it is built by a `const fn` from zeros, so it
//! lives in `.bss` and costs no flash image. Its two ends are used through
//! [`SpscRing::push`] and [`SpscRing::pop`], which are `unsafe` because the ring cannot
//! know who calls them: the split driver ([`crate::split`]) hands out each end once, to
//! one context, and calls them for that context only.
//!
//! Why not `heapless::spsc::Queue`: splitting it needs `&'static mut` to the queue (a
//! `static mut` or a cell crate in every firmware), one slot of every ring is left
//! unused, and the size, count, peak and overflow figures this driver reports would sit
//! beside it in extra atomics anyway. The ring here is those figures plus two indices.
//!
//! Indices count modulo `2 × N`, so a full ring and an empty one differ without a
//! spare slot and `N` need not be a power of two (when it is, the index arithmetic is
//! masks: a few instructions less per push and pop). The producer publishes a slot with a
//! `Release` store of `tail` after writing it; the consumer reads `tail` with `Acquire`
//! before reading the slot, and frees it with a `Release` store of `head` (the producer
//! reads `head` with `Acquire` before reusing a slot).

use core::mem::MaybeUninit;
use core::sync::atomic::Ordering;

use crate::sync::{AtomicU32, UnsafeCell};

/// Figures of a ring or queue (ACAN `…BufferSize`, `…BufferCount`, `…PeakCount`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BufferStats {
    /// Capacity.
    pub size: usize,
    /// Entries held now.
    pub count: usize,
    /// Highest count seen; `size + 1` once an entry was refused because the buffer was
    /// full (ACAN's convention).
    pub peak: usize,
    /// Entries refused because the buffer was full.
    pub overflows: u32,
}

/// A counter with one writer context (the others only read it): an increment is a
/// relaxed load and store, no read-modify-write loop. Saturates at `u32::MAX`.
#[derive(Debug, Default)]
pub struct Counter(core::sync::atomic::AtomicU32);

impl Counter {
    /// Zero.
    pub const fn new() -> Self {
        Counter(core::sync::atomic::AtomicU32::new(0))
    }

    /// Adds `n` (from the counter's one writer context), wrapping: readers compare
    /// readings with wrapping differences (no saturation test on the per-frame path).
    #[inline(always)]
    pub fn add(&self, n: u32) {
        let v = self.0.load(Ordering::Relaxed);
        self.0.store(v.wrapping_add(n), Ordering::Relaxed);
    }

    /// Adds one (from the counter's one writer context).
    #[inline(always)]
    pub fn inc(&self) {
        self.add(1)
    }

    /// The value.
    #[inline(always)]
    pub fn get(&self) -> u32 {
        self.0.load(Ordering::Relaxed)
    }
}

/// A bounded SPSC ring of `N` entries of `T` (see the [module docs](self)).
pub struct SpscRing<T: Copy, const N: usize> {
    /// Consumer index, modulo `2 × N` (written by the consumer only).
    head: AtomicU32,
    /// Producer index, modulo `2 × N` (written by the producer only).
    tail: AtomicU32,
    /// Highest count seen (written by the producer; reset by the consumer).
    peak: AtomicU32,
    /// Entries refused because the ring was full (written by the producer).
    overflows: Counter,
    slots: [UnsafeCell<MaybeUninit<T>>; N],
}

// SAFETY: the slots are accessed by one producer and one consumer at a time (the
// contract of `push` and `pop`, upheld by their callers: the split driver's unique
// handles), with the acquire/release protocol of the module docs ordering each slot's
// write before its read; `T: Send` because values move from the producer's context to
// the consumer's (`T: Copy`, so no slot is ever dropped). The indices and figures are
// atomics. (`Send` is automatic: `T: Send` makes the slots `Send`.)
unsafe impl<T: Copy + Send, const N: usize> Sync for SpscRing<T, N> {}

impl<T: Copy, const N: usize> Default for SpscRing<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Copy, const N: usize> SpscRing<T, N> {
    const WRAP: u32 = 2 * N as u32;

    /// An empty ring, all zeros (a `static` of it goes to `.bss`).
    #[cfg(not(all(test, twocan_loom)))]
    pub const fn new() -> Self {
        const { assert!(N < (u32::MAX / 2) as usize, "ring too large") };
        SpscRing {
            head: AtomicU32::new(0),
            tail: AtomicU32::new(0),
            peak: AtomicU32::new(0),
            overflows: Counter::new(),
            slots: [const { UnsafeCell::new(MaybeUninit::uninit()) }; N],
        }
    }

    /// An empty ring, with loom's atomics and cells (the loom models).
    #[cfg(all(test, twocan_loom))]
    pub fn new() -> Self {
        SpscRing {
            head: AtomicU32::new(0),
            tail: AtomicU32::new(0),
            peak: AtomicU32::new(0),
            overflows: Counter::new(),
            slots: core::array::from_fn(|_| UnsafeCell::new(MaybeUninit::uninit())),
        }
    }

    /// Whether `N` is a power of two: the index arithmetic is then masks (the compiler
    /// folds the test away).
    const POW2: bool = N.is_power_of_two();

    #[inline(always)]
    fn slot(index: u32) -> usize {
        let i = index as usize;
        if Self::POW2 {
            i & (N - 1)
        } else if i >= N {
            i - N
        } else {
            i
        }
    }

    #[inline(always)]
    fn advance(index: u32) -> u32 {
        if Self::POW2 {
            return index.wrapping_add(1) & (Self::WRAP - 1);
        }
        let next = index + 1;
        if next == Self::WRAP {
            0
        } else {
            next
        }
    }

    #[inline(always)]
    fn distance(head: u32, tail: u32) -> u32 {
        if Self::POW2 {
            return tail.wrapping_sub(head) & (Self::WRAP - 1);
        }
        if tail >= head {
            tail - head
        } else {
            tail + Self::WRAP - head
        }
    }

    /// The slot of `index` (an index modulo `2 × N`, as `head` and `tail` always are:
    /// only [`Self::advance`] moves them).
    #[inline(always)]
    fn cell(&self, index: u32) -> &UnsafeCell<MaybeUninit<T>> {
        let i = Self::slot(index);
        debug_assert!(i < N);
        // SAFETY: `index < 2 × N`, so `slot` maps it below `N`.
        unsafe { self.slots.get_unchecked(i) }
    }

    /// Appends `item`; gives it back, counted as an overflow (and the peak set to
    /// `N + 1`), when the ring is full.
    ///
    /// # Safety
    /// Only one context may be the producer of this ring: no two `push` calls may run at
    /// the same time (the split driver calls it from the one context that owns the
    /// ring's producer end, or inside a critical section that all its producers take).
    #[inline(always)]
    pub unsafe fn push(&self, item: T) -> Result<(), T> {
        let tail = self.tail.load(Ordering::Relaxed);
        let head = self.head.load(Ordering::Acquire);
        let count = Self::distance(head, tail);
        if count as usize >= N {
            self.overflows.inc();
            self.peak.store(N as u32 + 1, Ordering::Relaxed);
            return Err(item);
        }
        // SAFETY: the slot at `tail` is outside `head..tail`, so the consumer does not
        // read it; the caller guarantees no other producer writes it.
        self.cell(tail).with_mut(|p| unsafe { (*p).write(item) });
        self.tail.store(Self::advance(tail), Ordering::Release);
        let count = count + 1;
        if count > self.peak.load(Ordering::Relaxed) {
            self.peak.store(count, Ordering::Relaxed);
        }
        Ok(())
    }

    /// Takes the oldest entry.
    ///
    /// # Safety
    /// Only one context may be the consumer of this ring (as for [`SpscRing::push`]).
    #[inline(always)]
    pub unsafe fn pop(&self) -> Option<T> {
        let head = self.head.load(Ordering::Relaxed);
        let tail = self.tail.load(Ordering::Acquire);
        if head == tail {
            return None;
        }
        // SAFETY: the slot at `head` was written before `tail` was published past it
        // (acquire above); the producer does not rewrite it until `head` moves on.
        let item = self.cell(head).with(|p| unsafe { (*p).assume_init() });
        self.head.store(Self::advance(head), Ordering::Release);
        Some(item)
    }

    /// The oldest entry, left in the ring.
    ///
    /// # Safety
    /// As for [`SpscRing::pop`]: called from the consumer context.
    #[inline(always)]
    pub unsafe fn peek(&self) -> Option<T> {
        let head = self.head.load(Ordering::Relaxed);
        let tail = self.tail.load(Ordering::Acquire);
        if head == tail {
            return None;
        }
        // SAFETY: as in `pop`, without freeing the slot.
        Some(self.cell(head).with(|p| unsafe { (*p).assume_init() }))
    }

    /// Entries held now (exact from either end; a snapshot from anywhere else).
    pub fn len(&self) -> usize {
        let head = self.head.load(Ordering::Acquire);
        let tail = self.tail.load(Ordering::Acquire);
        Self::distance(head, tail) as usize
    }

    /// Whether the ring is empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The capacity `N`.
    pub const fn capacity(&self) -> usize {
        N
    }

    /// Size, count, peak and overflows.
    pub fn stats(&self) -> BufferStats {
        BufferStats {
            size: N,
            count: self.len(),
            peak: self.peak.load(Ordering::Relaxed) as usize,
            overflows: self.overflows.get(),
        }
    }

    /// Sets the peak back to the current count (ACAN has no equivalent; useful between
    /// measurement periods). A push racing with it may leave its own count instead.
    pub fn reset_peak(&self) {
        self.peak.store(self.len() as u32, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fills_wraps_and_counts() {
        let r: SpscRing<u32, 3> = SpscRing::new();
        // SAFETY: one test thread is both producer and consumer.
        unsafe {
            for round in 0..10u32 {
                for i in 0..3 {
                    assert_eq!(r.push(round * 10 + i), Ok(()));
                }
                assert_eq!(r.push(99), Err(99));
                assert_eq!(r.len(), 3);
                assert_eq!(r.peek(), Some(round * 10));
                for i in 0..3 {
                    assert_eq!(r.pop(), Some(round * 10 + i));
                }
                assert_eq!(r.pop(), None);
            }
        }
        let s = r.stats();
        assert_eq!((s.size, s.count, s.peak, s.overflows), (3, 0, 4, 10));
        r.reset_peak();
        assert_eq!(r.stats().peak, 0);
    }

    #[test]
    fn power_of_two_sizes_wrap_with_masks() {
        let r: SpscRing<u32, 4> = SpscRing::new();
        // SAFETY: one test thread is both producer and consumer.
        unsafe {
            // Uneven fills and drains walk the indices through every value modulo 8.
            let mut next_in = 0u32;
            let mut next_out = 0u32;
            for round in 0..50u32 {
                let fill = round % 5; // 0..=4, 4 fills the ring
                for _ in 0..fill {
                    assert_eq!(r.push(next_in), Ok(()));
                    next_in += 1;
                }
                if fill == 4 {
                    assert_eq!(r.push(999), Err(999), "full at 4");
                }
                assert_eq!(r.len(), fill as usize);
                for _ in 0..fill {
                    assert_eq!(r.peek(), Some(next_out));
                    assert_eq!(r.pop(), Some(next_out));
                    next_out += 1;
                }
                assert_eq!(r.pop(), None);
                assert!(r.is_empty());
            }
            assert_eq!(next_in, next_out);
        }
        assert_eq!(r.stats().overflows, 10);
    }

    #[test]
    fn two_threads_move_a_million_values_in_order() {
        let r: SpscRing<u64, 7> = SpscRing::new();
        // Fewer under Miri, which runs this with several scheduler seeds (.ci/run).
        const COUNT: u64 = if cfg!(miri) { 300 } else { 1_000_000 };
        std::thread::scope(|s| {
            s.spawn(|| {
                let mut next = 0;
                while next < COUNT {
                    // SAFETY: this thread is the only producer.
                    if unsafe { r.push(next) }.is_ok() {
                        next += 1;
                    }
                }
            });
            let mut expect = 0;
            while expect < COUNT {
                // SAFETY: this thread is the only consumer.
                if let Some(v) = unsafe { r.pop() } {
                    assert_eq!(v, expect);
                    expect += 1;
                }
            }
        });
        assert!(r.is_empty());
    }
}
