//! The waker cells of one driver state (feature `async`): the [`crate::split::State`]
//! holds them, the interrupt handlers wake them, the async halves
//! ([`crate::asynch`]) register in them. Apart from the halves, so that the state and
//! the async methods do not import each other.

use atomic_waker::AtomicWaker;

/// The waker cells of one driver state.
pub(crate) struct Wakers {
    /// Receive half waiting for a frame.
    pub(crate) rx: AtomicWaker,
    /// Receive half waiting for a state change.
    pub(crate) state: AtomicWaker,
    /// Transmit half waiting for room in the queue.
    pub(crate) tx_room: AtomicWaker,
    /// Transmit half waiting for a completion.
    pub(crate) tx_done: AtomicWaker,
}

impl Wakers {
    pub(crate) const fn new() -> Self {
        Wakers {
            rx: AtomicWaker::new(),
            state: AtomicWaker::new(),
            tx_room: AtomicWaker::new(),
            tx_done: AtomicWaker::new(),
        }
    }
}
