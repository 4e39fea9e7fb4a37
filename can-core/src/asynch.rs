//! `async` counterparts of the split halves' operations (feature `async`), woken from
//! the interrupt handlers. No executor is assumed: the futures work with
//! embassy-executor, RTIC v2 async tasks or any host executor.
//!
//! Each wait has one waker cell ([`atomic_waker::AtomicWaker`], from the smol-rs
//! project: a lock-free single-slot waker register, `no_std`, `const`-constructible, so
//! it sits in the `static` state like the rings). The handler that makes progress wakes
//! it once per interrupt, not per frame: the receive handler after draining its FIFO,
//! the transmit handler when completions came, the status handler on a state change.
//!
//! Cancellation: every future takes nothing out of a ring until it completes (the
//! frame, completion or state change is taken in the same poll that returns it), so
//! dropping a pending future loses nothing. A dropped future also takes its waker back
//! out of the cell, so no stale waker remains to wake a task that no longer waits (each
//! cell belongs to one half, and a half runs one future at a time: it is borrowed
//! `&mut`).
//!
//! ```
//! use twocan_core::mock::MockHardware;
//! use twocan_core::split::State;
//! use twocan_core::{FifoQueue, Frame, TxOutcome};
//!
//! let state: State<MockHardware, 8, FifoQueue<4>> = State::new();
//! let mut p = state.split(MockHardware::new(1).with_loopback(true)).ok().unwrap();
//! let hw = state.hardware().unwrap();
//! let frame = Frame::standard(0x42, &[1])?;
//! // A tiny executor: poll once, play the bus and the interrupts, poll again.
//! let token = futures_lite_block_on(p.tx.send(&frame))?;
//! hw.complete_all();
//! p.tx_irq.on_interrupt();
//! p.rx0_irq.on_interrupt();
//! assert_eq!(futures_lite_block_on(p.rx.recv())?.frame, frame);
//! assert_eq!(futures_lite_block_on(p.tx.completion()).token, token);
//! # fn futures_lite_block_on<F: core::future::Future>(f: F) -> F::Output {
//! #     let mut f = core::pin::pin!(f);
//! #     let w = std::task::Waker::noop();
//! #     let mut cx = core::task::Context::from_waker(w);
//! #     loop { if let core::task::Poll::Ready(v) = f.as_mut().poll(&mut cx) { return v } }
//! # }
//! # Ok::<(), twocan_core::Error>(())
//! ```

use core::future::{poll_fn, Future};
use core::task::Poll;

use atomic_waker::AtomicWaker;

use crate::error::Error;
use crate::frame::{Frame, RxFrame};
use crate::hardware::{Completion, Hardware, Token};
use crate::split::{Rx, StateChange, Tx};
use crate::txqueue::TxQueue;

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

/// Takes the waker back out of its cell when a waiting future is dropped.
struct Unregister<'a>(&'a AtomicWaker);

impl Drop for Unregister<'_> {
    fn drop(&mut self) {
        drop(self.0.take());
    }
}

impl<'a, H: Hardware, const RX: usize, Q: TxQueue, const RX1: usize, const DONE: usize>
    Tx<'a, H, RX, Q, RX1, DONE>
{
    /// Waits for room in the transmit queue, then accepts `frame` (see
    /// [`Tx::try_send`]); its token. Fails at once with the error of `try_send`, and
    /// with [`Error::WrongMode`] when the queue is full while the controller is off the
    /// bus (nothing would free it).
    ///
    /// Cancel-safe: a dropped future has not accepted the frame.
    pub async fn send(&mut self, frame: &Frame) -> Result<Token, Error> {
        let s = self.s;
        let _unregister = Unregister(&s.wakers.tx_room);
        poll_fn(|cx| {
            for attempt in 0..2 {
                match self.try_send(frame) {
                    Ok(t) => return Poll::Ready(Ok(t)),
                    Err(nb::Error::Other(e)) => return Poll::Ready(Err(e)),
                    Err(nb::Error::WouldBlock) => {
                        if !s.hardware().is_some_and(|h| h.on_bus()) {
                            return Poll::Ready(Err(Error::WrongMode));
                        }
                        if attempt == 0 {
                            // Register, then try again: room freed in between is seen.
                            s.wakers.tx_room.register(cx.waker());
                        }
                    }
                }
            }
            Poll::Pending
        })
        .await
    }

    /// Waits for the next completion, in the order the controller reported them.
    ///
    /// Cancel-safe: a completion is taken only by the poll that returns it.
    pub async fn completion(&mut self) -> Completion {
        let s = self.s;
        let _unregister = Unregister(&s.wakers.tx_done);
        poll_fn(|cx| {
            if let Some(c) = self.take_completion() {
                return Poll::Ready(c);
            }
            s.wakers.tx_done.register(cx.waker());
            match self.take_completion() {
                Some(c) => Poll::Ready(c),
                None => Poll::Pending,
            }
        })
        .await
    }

    /// Waits for the completion of `token`. Completions of other frames that come
    /// before it are taken and dropped (they stay counted in the traffic statistics):
    /// use [`Tx::completion`] to see every one.
    ///
    /// Cancel-safe as [`Tx::completion`]: completions taken before the drop are gone,
    /// the one of `token` is still in the ring if it had not come.
    pub async fn completed(&mut self, token: Token) -> Completion {
        loop {
            let c = self.completion().await;
            if c.token == token {
                return c;
            }
        }
    }
}

impl<'a, H: Hardware, const RX: usize, Q: TxQueue, const RX1: usize, const DONE: usize>
    Rx<'a, H, RX, Q, RX1, DONE>
{
    /// Waits for a received frame; returns it with the index of the user's filter that
    /// accepted it and its time stamp (see [`Rx::receive`]).
    ///
    /// Cancel-safe: a frame is taken from the ring only by the poll that returns it.
    pub async fn recv(&mut self) -> Result<RxFrame, Error> {
        let s = self.s;
        let _unregister = Unregister(&s.wakers.rx);
        poll_fn(|cx| {
            match self.receive() {
                Ok(f) => return Poll::Ready(Ok(f)),
                Err(nb::Error::Other(e)) => return Poll::Ready(Err(e)),
                Err(nb::Error::WouldBlock) => {}
            }
            s.wakers.rx.register(cx.waker());
            match self.receive() {
                Ok(f) => Poll::Ready(Ok(f)),
                Err(nb::Error::Other(e)) => Poll::Ready(Err(e)),
                Err(nb::Error::WouldBlock) => Poll::Pending,
            }
        })
        .await
    }

    /// Waits for the next error-state change (in order, with the counters at the
    /// change).
    ///
    /// Cancel-safe: a change is taken only by the poll that returns it.
    pub async fn state_change(&mut self) -> StateChange {
        let s = self.s;
        let _unregister = Unregister(&s.wakers.state);
        poll_fn(|cx| {
            if let Some(c) = self.take_state_change() {
                return Poll::Ready(c);
            }
            s.wakers.state.register(cx.waker());
            match self.take_state_change() {
                Some(c) => Poll::Ready(c),
                None => Poll::Pending,
            }
        })
        .await
    }
}

impl<H: Hardware, const RX: usize, Q: TxQueue, const RX1: usize, const DONE: usize>
    crate::io::AsyncCanTx for Tx<'_, H, RX, Q, RX1, DONE>
{
    fn send(&mut self, frame: &Frame) -> impl Future<Output = Result<Token, Error>> {
        Tx::send(self, frame)
    }
}

impl<H: Hardware, const RX: usize, Q: TxQueue, const RX1: usize, const DONE: usize>
    crate::io::AsyncCanRx for Rx<'_, H, RX, Q, RX1, DONE>
{
    fn recv(&mut self) -> impl Future<Output = Result<RxFrame, Error>> {
        Rx::recv(self)
    }
}
