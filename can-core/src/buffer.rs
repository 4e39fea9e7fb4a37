//! Software rings between the interrupt handler and thread code.
//!
//! Capacities are const generics. Every ring reports what ACAN's driver buffers report
//! (ACAN §9, §10): its size, the current count, the peak count — which becomes
//! `size + 1` once a push found the ring full — and, beyond ACAN, the exact number of
//! rejected pushes, so that no loss is silent.
//!
//! Each ring keeps its state in a [`critical_section::Mutex`], so a `&Ring` can be used
//! from an interrupt handler and from thread code at once. The storage is `heapless`
//! (`Deque` for first-in first-out rings, `BinaryHeap` for the priority-ordered transmit
//! queue).

use core::cell::RefCell;
use critical_section::Mutex;
use heapless::binary_heap::{BinaryHeap, Min};
use heapless::Deque;

use crate::frame::Frame;
use crate::mailbox::TxPolicy;
use crate::priority::Priority;

/// Occupancy figures of one ring.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BufferStats {
    /// Capacity.
    pub size: usize,
    /// Items held now.
    pub count: usize,
    /// Highest count reached; `size + 1` once an item was rejected (ACAN §9.3, §10.3).
    pub peak: usize,
    /// Items rejected because the ring was full.
    pub overflows: u32,
}

#[derive(Debug)]
struct Accounting {
    peak: usize,
    overflows: u32,
}

impl Accounting {
    const fn new() -> Self {
        Accounting {
            peak: 0,
            overflows: 0,
        }
    }
    fn pushed(&mut self, count: usize) {
        if count > self.peak {
            self.peak = count;
        }
    }
    fn rejected(&mut self, size: usize) {
        self.peak = size + 1;
        self.overflows = self.overflows.saturating_add(1);
    }
}

/// A first-in first-out ring of `N` items shared between interrupt and thread code.
pub struct Ring<T, const N: usize> {
    inner: Mutex<RefCell<(Deque<T, N>, Accounting)>>,
}

impl<T, const N: usize> Default for Ring<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T, const N: usize> Ring<T, N> {
    /// An empty ring (usable in a `static`).
    pub const fn new() -> Self {
        Ring {
            inner: Mutex::new(RefCell::new((Deque::new(), Accounting::new()))),
        }
    }

    /// Appends `item`; when full, counts the overflow and gives the item back.
    pub fn push(&self, item: T) -> Result<(), T> {
        critical_section::with(|cs| {
            let mut g = self.inner.borrow_ref_mut(cs);
            let (q, acc) = &mut *g;
            match q.push_back(item) {
                Ok(()) => {
                    acc.pushed(q.len());
                    Ok(())
                }
                Err(item) => {
                    acc.rejected(N);
                    Err(item)
                }
            }
        })
    }

    /// Removes the oldest item.
    pub fn pop(&self) -> Option<T> {
        critical_section::with(|cs| self.inner.borrow_ref_mut(cs).0.pop_front())
    }

    /// Puts an item back at the front (it becomes the next one popped). Fails when full;
    /// such a failure is not an overflow of new data, so it is not counted.
    pub fn push_front(&self, item: T) -> Result<(), T> {
        critical_section::with(|cs| self.inner.borrow_ref_mut(cs).0.push_front(item))
    }

    /// Items held now.
    pub fn len(&self) -> usize {
        critical_section::with(|cs| self.inner.borrow_ref(cs).0.len())
    }

    /// Whether the ring is empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the ring is full.
    pub fn is_full(&self) -> bool {
        self.len() == N
    }

    /// Capacity.
    pub const fn capacity(&self) -> usize {
        N
    }

    /// Occupancy figures.
    pub fn stats(&self) -> BufferStats {
        critical_section::with(|cs| {
            let g = self.inner.borrow_ref(cs);
            BufferStats {
                size: N,
                count: g.0.len(),
                peak: g.1.peak,
                overflows: g.1.overflows,
            }
        })
    }

    /// Resets the peak count to the current count and the overflow count to zero.
    pub fn reset_peak(&self) {
        critical_section::with(|cs| {
            let mut g = self.inner.borrow_ref_mut(cs);
            g.1.peak = g.0.len();
            g.1.overflows = 0;
        })
    }
}

/// An entry of the priority-ordered transmit queue: arbitration priority, then request order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Queued {
    priority: Priority,
    seq: u64,
    frame: Frame,
}

impl PartialOrd for Queued {
    fn partial_cmp(&self, other: &Self) -> Option<core::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Queued {
    fn cmp(&self, other: &Self) -> core::cmp::Ordering {
        (self.priority, self.seq).cmp(&(other.priority, other.seq))
    }
}

enum TxStore<const N: usize> {
    Fifo(Deque<Frame, N>),
    Priority(BinaryHeap<Queued, Min, N>),
}

struct TxInner<const N: usize> {
    store: TxStore<N>,
    acc: Accounting,
    seq: u64,
}

impl<const N: usize> TxInner<N> {
    fn len(&self) -> usize {
        match &self.store {
            TxStore::Fifo(q) => q.len(),
            TxStore::Priority(h) => h.len(),
        }
    }
}

/// The driver's transmit queue of `N` frames, ordered by the transmit policy:
/// request order ([`TxPolicy::Fifo`]) or arbitration priority then request order
/// ([`TxPolicy::Priority`]).
pub struct TxQueue<const N: usize> {
    inner: Mutex<RefCell<TxInner<N>>>,
}

impl<const N: usize> TxQueue<N> {
    /// An empty queue with the given ordering.
    pub const fn new(policy: TxPolicy) -> Self {
        let store = match policy {
            TxPolicy::Fifo => TxStore::Fifo(Deque::new()),
            TxPolicy::Priority => TxStore::Priority(BinaryHeap::new()),
        };
        TxQueue {
            inner: Mutex::new(RefCell::new(TxInner {
                store,
                acc: Accounting::new(),
                seq: 0,
            })),
        }
    }

    /// The ordering of this queue.
    pub fn policy(&self) -> TxPolicy {
        critical_section::with(|cs| match self.inner.borrow_ref(cs).store {
            TxStore::Fifo(_) => TxPolicy::Fifo,
            TxStore::Priority(_) => TxPolicy::Priority,
        })
    }

    /// Queues a new frame; when full, counts the overflow and gives it back.
    pub fn push(&self, frame: Frame) -> Result<(), Frame> {
        self.insert(frame, false)
    }

    /// Puts back a frame taken from the queue (or displaced from a mailbox) so that it
    /// is the next of its rank to go. Not counted as new traffic; fails only when full.
    pub fn requeue(&self, frame: Frame) -> Result<(), Frame> {
        self.insert(frame, true)
    }

    fn insert(&self, frame: Frame, front: bool) -> Result<(), Frame> {
        critical_section::with(|cs| {
            let mut g = self.inner.borrow_ref_mut(cs);
            let inner = &mut *g;
            let result = match &mut inner.store {
                TxStore::Fifo(q) if front => q.push_front(frame),
                TxStore::Fifo(q) => q.push_back(frame),
                TxStore::Priority(h) => {
                    // A displaced frame goes before every queued frame of equal priority:
                    // it was requested earlier than all of them.
                    let seq = if front { 0 } else { inner.seq + 1 };
                    h.push(Queued {
                        priority: frame.priority(),
                        seq,
                        frame,
                    })
                    .map_err(|q| q.frame)
                }
            };
            match result {
                Ok(()) => {
                    if !front {
                        inner.seq += 1;
                    }
                    let len = inner.len();
                    inner.acc.pushed(len);
                    Ok(())
                }
                Err(f) => {
                    if !front {
                        inner.acc.rejected(N);
                    }
                    Err(f)
                }
            }
        })
    }

    /// The frame that should go next, without removing it.
    pub fn peek(&self) -> Option<Frame> {
        critical_section::with(|cs| match &self.inner.borrow_ref(cs).store {
            TxStore::Fifo(q) => q.front().copied(),
            TxStore::Priority(h) => h.peek().map(|q| q.frame),
        })
    }

    /// Removes the frame that should go next.
    pub fn pop(&self) -> Option<Frame> {
        critical_section::with(|cs| match &mut self.inner.borrow_ref_mut(cs).store {
            TxStore::Fifo(q) => q.pop_front(),
            TxStore::Priority(h) => h.pop().map(|q| q.frame),
        })
    }

    /// Frames queued now.
    pub fn len(&self) -> usize {
        critical_section::with(|cs| self.inner.borrow_ref(cs).len())
    }

    /// Whether nothing is queued.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the queue is full.
    pub fn is_full(&self) -> bool {
        self.len() == N
    }

    /// Drops every queued frame, returning how many were dropped.
    pub fn clear(&self) -> usize {
        critical_section::with(|cs| {
            let mut g = self.inner.borrow_ref_mut(cs);
            let n = g.len();
            match &mut g.store {
                TxStore::Fifo(q) => q.clear(),
                TxStore::Priority(h) => h.clear(),
            }
            n
        })
    }

    /// Occupancy figures.
    pub fn stats(&self) -> BufferStats {
        critical_section::with(|cs| {
            let g = self.inner.borrow_ref(cs);
            BufferStats {
                size: N,
                count: g.len(),
                peak: g.acc.peak,
                overflows: g.acc.overflows,
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ring_overflow_accounting() {
        let r: Ring<u8, 4> = Ring::new();
        for i in 0..4 {
            r.push(i).unwrap();
        }
        assert_eq!(r.stats().peak, 4);
        for i in 0..3 {
            assert_eq!(r.push(10 + i), Err(10 + i));
        }
        assert_eq!(
            r.stats(),
            BufferStats {
                size: 4,
                count: 4,
                peak: 5,
                overflows: 3
            }
        );
        assert_eq!(r.pop(), Some(0));
        r.push_front(9).unwrap();
        assert_eq!(r.pop(), Some(9));
        assert_eq!(r.len(), 3);
        r.reset_peak();
        assert_eq!(r.stats().peak, 3);
    }

    #[test]
    fn priority_queue_orders_by_priority_then_request() {
        let q: TxQueue<8> = TxQueue::new(TxPolicy::Priority);
        let f = |id, b| Frame::standard(id, &[b]).unwrap();
        q.push(f(0x300, 1)).unwrap();
        q.push(f(0x100, 2)).unwrap();
        q.push(f(0x300, 3)).unwrap();
        q.push(f(0x100, 4)).unwrap();
        q.requeue(f(0x300, 0)).unwrap();
        let order: heapless::Vec<u8, 8> = core::iter::from_fn(|| q.pop())
            .map(|f| f.data()[0])
            .collect();
        assert_eq!(&order[..], &[2, 4, 0, 1, 3]);
    }

    #[test]
    fn fifo_queue_keeps_request_order() {
        let q: TxQueue<3> = TxQueue::new(TxPolicy::Fifo);
        for id in [0x300, 0x100, 0x200] {
            q.push(Frame::standard(id, &[]).unwrap()).unwrap();
        }
        assert!(q.push(Frame::standard(1, &[]).unwrap()).is_err());
        assert_eq!(q.stats().peak, 4);
        assert_eq!(q.pop().unwrap().raw_id(), 0x300);
        q.requeue(Frame::standard(0x7, &[]).unwrap()).unwrap();
        assert_eq!(q.pop().unwrap().raw_id(), 0x7);
        assert_eq!(q.pop().unwrap().raw_id(), 0x100);
        assert_eq!(q.clear(), 1);
    }
}
