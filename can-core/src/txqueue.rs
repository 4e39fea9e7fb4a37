//! The software transmit queue in front of the mailboxes, one type per transmit order.
//!
//! The queue is the one structure that two contexts modify (the transmit half pushes,
//! the transmit interrupt pops), so the split driver keeps it inside a critical section
//! and only ever touches it on the slow path (mailboxes busy or frames already
//! waiting). The order is a type parameter of the driver's state, so a firmware that
//! sends in request order links no priority ordering code.

use core::mem::MaybeUninit;

use crate::frame::Frame;
use crate::hardware::Token;
use crate::mailbox::TxPolicy;
use crate::priority::Priority;

/// A frame waiting for a mailbox, with its token.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Queued {
    /// The frame's token.
    pub token: Token,
    /// The frame.
    pub frame: Frame,
}

/// A transmit queue of fixed capacity.
pub trait TxQueue {
    /// The order it keeps, which must be the controller's ([`crate::Hardware::tx_policy`]).
    fn policy(&self) -> TxPolicy;
    /// Takes `policy` as its order if it can (only while empty); whether it keeps it now.
    fn adopt(&mut self, policy: TxPolicy) -> bool {
        policy == self.policy()
    }
    /// Whether the queue keeps the request order whatever it is asked to adopt (so
    /// that the transmit interrupt never displaces a mailbox for it).
    const ALWAYS_FIFO: bool = false;
    /// Capacity.
    const CAPACITY: usize;
    /// An empty queue (for `const` construction of the driver state).
    const EMPTY: Self;
    /// Entries held.
    fn len(&self) -> usize;
    /// Whether empty.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Adds an entry; gives it back when full.
    fn push(&mut self, entry: Queued) -> Result<(), Queued>;
    /// The next entry to go.
    fn peek(&self) -> Option<&Queued>;
    /// Takes the next entry to go.
    fn pop(&mut self) -> Option<Queued>;
    /// Removes the entry with `token`; whether there was one.
    fn remove(&mut self, token: Token) -> bool;
}

/// Request order (ACAN's "sequentiality"; bxCAN `TXFP = 1`): a circular buffer.
pub struct FifoQueue<const N: usize> {
    head: usize,
    len: usize,
    slots: [MaybeUninit<Queued>; N],
}

impl<const N: usize> FifoQueue<N> {
    fn at(&self, i: usize) -> usize {
        let j = self.head + i;
        if j >= N {
            j - N
        } else {
            j
        }
    }

    fn get(&self, i: usize) -> &Queued {
        // SAFETY: callers pass `i < len`; slots `head..head+len` (circular) are written.
        unsafe { self.slots[self.at(i)].assume_init_ref() }
    }
}

impl<const N: usize> TxQueue for FifoQueue<N> {
    fn policy(&self) -> TxPolicy {
        TxPolicy::Fifo
    }
    const ALWAYS_FIFO: bool = true;
    const CAPACITY: usize = N;
    const EMPTY: Self = FifoQueue {
        head: 0,
        len: 0,
        slots: [const { MaybeUninit::uninit() }; N],
    };

    fn len(&self) -> usize {
        self.len
    }

    fn push(&mut self, entry: Queued) -> Result<(), Queued> {
        if self.len == N {
            return Err(entry);
        }
        let at = self.at(self.len);
        self.slots[at].write(entry);
        self.len += 1;
        Ok(())
    }

    fn peek(&self) -> Option<&Queued> {
        (self.len > 0).then(|| self.get(0))
    }

    fn pop(&mut self) -> Option<Queued> {
        if self.len == 0 {
            return None;
        }
        let e = *self.get(0);
        self.head = self.at(1);
        self.len -= 1;
        Some(e)
    }

    fn remove(&mut self, token: Token) -> bool {
        let Some(found) = (0..self.len).find(|&i| self.get(i).token == token) else {
            return false;
        };
        for i in found..self.len - 1 {
            let next = *self.get(i + 1);
            let at = self.at(i);
            self.slots[at].write(next);
        }
        self.len -= 1;
        true
    }
}

/// Identifier priority ([`Priority`]; bxCAN `TXFP = 0`), request order among equals:
/// kept sorted, the next frame last, so taking it costs nothing and an insertion moves
/// at most `N` entries.
pub struct PriorityQueue<const N: usize> {
    len: usize,
    slots: [MaybeUninit<Queued>; N],
}

impl<const N: usize> PriorityQueue<N> {
    fn get(&self, i: usize) -> &Queued {
        // SAFETY: callers pass `i < len`; slots `0..len` are written.
        unsafe { self.slots[i].assume_init_ref() }
    }

    /// Whether `a` goes before `b`: higher priority, or equal priority and requested
    /// first (tokens compared across their wrap).
    fn goes_before(a: &Queued, b: &Queued) -> bool {
        let (pa, pb) = (Priority::of(&a.frame), Priority::of(&b.frame));
        pa.beats(pb) || (pa == pb && (a.token.0.wrapping_sub(b.token.0) as i32) < 0)
    }
}

impl<const N: usize> TxQueue for PriorityQueue<N> {
    fn policy(&self) -> TxPolicy {
        TxPolicy::Priority
    }
    const CAPACITY: usize = N;
    const EMPTY: Self = PriorityQueue {
        len: 0,
        slots: [const { MaybeUninit::uninit() }; N],
    };

    fn len(&self) -> usize {
        self.len
    }

    fn push(&mut self, entry: Queued) -> Result<(), Queued> {
        if self.len == N {
            return Err(entry);
        }
        // Entries are sorted with the next to go last: find the first that goes
        // before `entry` and slide it and those above up by one.
        let mut i = self.len;
        while i > 0 && Self::goes_before(self.get(i - 1), &entry) {
            let moved = *self.get(i - 1);
            self.slots[i].write(moved);
            i -= 1;
        }
        self.slots[i].write(entry);
        self.len += 1;
        Ok(())
    }

    fn peek(&self) -> Option<&Queued> {
        (self.len > 0).then(|| self.get(self.len - 1))
    }

    fn pop(&mut self) -> Option<Queued> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        Some(*self.get(self.len))
    }

    fn remove(&mut self, token: Token) -> bool {
        let Some(found) = (0..self.len).find(|&i| self.get(i).token == token) else {
            return false;
        };
        for i in found..self.len - 1 {
            let next = *self.get(i + 1);
            self.slots[i].write(next);
        }
        self.len -= 1;
        true
    }
}

/// Either order, taken from the controller at run time (for the one-struct
/// [`crate::Driver`] and code that does not fix the order at compile time; it links
/// both orders' code).
pub enum AnyQueue<const N: usize> {
    /// Request order.
    Fifo(FifoQueue<N>),
    /// Identifier priority.
    Priority(PriorityQueue<N>),
}

impl<const N: usize> TxQueue for AnyQueue<N> {
    fn policy(&self) -> TxPolicy {
        match self {
            AnyQueue::Fifo(_) => TxPolicy::Fifo,
            AnyQueue::Priority(_) => TxPolicy::Priority,
        }
    }

    fn adopt(&mut self, policy: TxPolicy) -> bool {
        if policy == self.policy() {
            return true;
        }
        if !self.is_empty() {
            return false;
        }
        *self = match policy {
            TxPolicy::Fifo => AnyQueue::Fifo(FifoQueue::EMPTY),
            TxPolicy::Priority => AnyQueue::Priority(PriorityQueue::EMPTY),
        };
        true
    }

    const CAPACITY: usize = N;
    const EMPTY: Self = AnyQueue::Fifo(FifoQueue::EMPTY);

    fn len(&self) -> usize {
        match self {
            AnyQueue::Fifo(q) => q.len(),
            AnyQueue::Priority(q) => q.len(),
        }
    }

    fn push(&mut self, entry: Queued) -> Result<(), Queued> {
        match self {
            AnyQueue::Fifo(q) => q.push(entry),
            AnyQueue::Priority(q) => q.push(entry),
        }
    }

    fn peek(&self) -> Option<&Queued> {
        match self {
            AnyQueue::Fifo(q) => q.peek(),
            AnyQueue::Priority(q) => q.peek(),
        }
    }

    fn pop(&mut self) -> Option<Queued> {
        match self {
            AnyQueue::Fifo(q) => q.pop(),
            AnyQueue::Priority(q) => q.pop(),
        }
    }

    fn remove(&mut self, token: Token) -> bool {
        match self {
            AnyQueue::Fifo(q) => q.remove(token),
            AnyQueue::Priority(q) => q.remove(token),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(token: u32, id: u16) -> Queued {
        Queued {
            token: Token(token),
            frame: Frame::standard(id, &[]).unwrap(),
        }
    }

    #[test]
    fn fifo_keeps_request_order_and_removes() {
        let mut f = FifoQueue::<3>::EMPTY;
        for t in 0..3 {
            assert!(f.push(q(t, 0x700 - t as u16)).is_ok());
        }
        assert!(f.push(q(9, 1)).is_err());
        assert_eq!(f.pop().unwrap().token, Token(0));
        assert!(f.push(q(3, 5)).is_ok());
        assert!(f.remove(Token(2)));
        assert!(!f.remove(Token(2)));
        let order: Vec<u32> = core::iter::from_fn(|| f.pop().map(|e| e.token.0)).collect();
        assert_eq!(order, [1, 3]);
    }

    #[test]
    fn priority_orders_by_identifier_then_request() {
        let mut p = PriorityQueue::<5>::EMPTY;
        for (t, id) in [(0, 0x300), (1, 0x100), (2, 0x300), (3, 0x050), (4, 0x100)] {
            assert!(p.push(q(t, id)).is_ok());
        }
        assert!(p.push(q(5, 0)).is_err());
        assert!(p.remove(Token(4)));
        assert_eq!(p.peek().unwrap().token, Token(3));
        let order: Vec<u32> = core::iter::from_fn(|| p.pop().map(|e| e.token.0)).collect();
        assert_eq!(order, [3, 1, 0, 2]);
    }
}
