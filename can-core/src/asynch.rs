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
//! | method | waits for | dropped while pending |
//! | --- | --- | --- |
//! | [`Tx::send`] | room in the transmit queue | the frame was not accepted (no token) |
//! | [`Tx::completion`] | the next completion | no completion taken |
//! | [`Tx::completed`] | the completion of one token | completions of other tokens taken before the drop are gone; the token's own stays in the ring |
//! | [`Rx::recv`] | a frame | no frame taken |
//! | [`Rx::state_change`] | an error-state change | no change taken |
//! | [`Rx::event`] | a frame or a state change | neither taken |
//!
//! Every future takes nothing out of a ring until it completes (the frame, completion
//! or state change is taken in the same poll that returns it), so dropping a pending
//! future loses nothing. A dropped future also takes its waker back out of its cell(s),
//! so no stale waker remains to wake a task that no longer waits (each cell belongs to
//! one half, and a half runs one future at a time: it is borrowed `&mut`). Hence one
//! task per half: the task that sends also takes the completions (between sends, with
//! [`Tx::take_completion`], or by waiting); a task that follows both frames and state
//! changes waits with [`Rx::event`].
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
//! let token = block_on(p.tx.send(&frame))?;
//! hw.complete_all();
//! p.tx_irq.on_interrupt();
//! p.rx0_irq.on_interrupt();
//! assert_eq!(block_on(p.rx.recv())?.frame, frame);
//! assert_eq!(block_on(p.tx.completion()).token, token);
//! # fn block_on<F: core::future::Future>(f: F) -> F::Output {
//! #     let mut f = core::pin::pin!(f);
//! #     let w = std::task::Waker::noop();
//! #     let mut cx = core::task::Context::from_waker(w);
//! #     for _ in 0..10_000 { if let core::task::Poll::Ready(v) = f.as_mut().poll(&mut cx) { return v } }
//! #     panic!("the future is still pending after 10,000 polls")
//! # }
//! # Ok::<(), twocan_core::Error>(())
//! ```

use core::future::poll_fn;
use core::task::Poll;

use atomic_waker::AtomicWaker;

use crate::error::Error;
use crate::frame::{Frame, RxFrame};
use crate::hardware::{Completion, Hardware, Token};
use crate::split::{Rx, StateChange, Tx};
use crate::txqueue::TxQueue;

/// Takes the waker back out of its cell when a waiting future is dropped.
struct Unregister<'a>(&'a AtomicWaker);

impl Drop for Unregister<'_> {
    fn drop(&mut self) {
        drop(self.0.take());
    }
}

/// The one wait of this module: `take` what is there; if nothing, register the task's
/// waker in `cell` and `take` again, so that what came in between is seen and no wake-up
/// is missed. Only the poll that returns a value takes it (cancel-safe when `take` takes
/// nothing it does not return), and a dropped future takes its waker back out.
async fn take_or_wait<T>(cell: &AtomicWaker, mut take: impl FnMut() -> Option<T>) -> T {
    let _unregister = Unregister(cell);
    poll_fn(|cx| {
        if let Some(v) = take() {
            return Poll::Ready(v);
        }
        cell.register(cx.waker());
        match take() {
            Some(v) => Poll::Ready(v),
            None => Poll::Pending,
        }
    })
    .await
}

/// What `take_or_wait` takes from an `nb` call: the value or the error, nothing on
/// `WouldBlock`.
fn ready<T>(r: nb::Result<T, Error>) -> Option<Result<T, Error>> {
    match r {
        Ok(v) => Some(Ok(v)),
        Err(nb::Error::Other(e)) => Some(Err(e)),
        Err(nb::Error::WouldBlock) => None,
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
        take_or_wait(&s.wakers.tx_room, || {
            ready(self.try_send(frame)).or_else(|| {
                // Queue full: nothing would free it while the controller is off the bus.
                (!s.hardware().is_some_and(|h| h.on_bus())).then_some(Err(Error::WrongMode))
            })
        })
        .await
    }

    /// Waits for the next completion, in the order the controller reported them.
    ///
    /// Cancel-safe: a completion is taken only by the poll that returns it. A call on
    /// a state without a completion ring (`DONE` = 0) does not compile: nothing would
    /// ever come.
    pub async fn completion(&mut self) -> Completion {
        const {
            assert!(
                DONE != 0,
                "completions are off (DONE = 0): none to wait for"
            );
        }
        let s = self.s;
        take_or_wait(&s.wakers.tx_done, || self.take_completion()).await
    }

    /// Waits for the completion of `token`. Completions of other frames that come
    /// before it are taken and dropped (they stay counted in the traffic statistics):
    /// use [`Tx::completion`] to see every one.
    ///
    /// Fails at once with [`Error::InvalidArgument`] for a token this half has not handed
    /// out (at or after [`Tx::next_token`], within half the token space), and with
    /// [`Error::Overrun`] when the completion ring overflowed during the wait and holds
    /// no more completions: the one of `token` may have been lost. A completion lost
    /// before the call is not detected (the wait would not end): a ring of `DONE`
    /// completions at least as large as the queue plus the mailboxes, drained, never
    /// overflows; [`crate::TrafficStats::completion_overflows`] counts the losses.
    ///
    /// Cancel-safe as [`Tx::completion`]: completions taken before the drop are gone,
    /// the one of `token` is still in the ring if it had not come. As for
    /// [`Tx::completion`], a call without a completion ring does not compile.
    pub async fn completed(&mut self, token: Token) -> Result<Completion, Error> {
        if token.0.wrapping_sub(self.next) < 0x8000_0000 {
            return Err(Error::InvalidArgument);
        }
        const {
            assert!(
                DONE != 0,
                "completions are off (DONE = 0): none to wait for"
            );
        }
        let s = self.s;
        let overflows = s.traffic().completion_overflows;
        let _unregister = Unregister(&s.wakers.tx_done);
        poll_fn(|cx| {
            for attempt in 0..2 {
                while let Some(c) = self.take_completion() {
                    if c.token == token {
                        return Poll::Ready(Ok(c));
                    }
                }
                if s.traffic().completion_overflows != overflows {
                    return Poll::Ready(Err(Error::Overrun));
                }
                if attempt == 0 {
                    // Register, then look again: a completion recorded in between is seen.
                    s.wakers.tx_done.register(cx.waker());
                }
            }
            Poll::Pending
        })
        .await
    }
}

/// What [`Rx::event`] waited for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RxEvent {
    /// A received frame, as [`Rx::recv`] returns it.
    Frame(RxFrame),
    /// An error-state change, as [`Rx::state_change`] returns it.
    StateChange(StateChange),
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
        take_or_wait(&s.wakers.rx, || ready(self.receive())).await
    }

    /// Waits for the next error-state change (in order, with the counters at the
    /// change).
    ///
    /// Cancel-safe: a change is taken only by the poll that returns it.
    pub async fn state_change(&mut self) -> StateChange {
        let s = self.s;
        take_or_wait(&s.wakers.state, || self.take_state_change()).await
    }

    /// Waits for a frame or an error-state change, whichever comes first (a waiting
    /// state change is returned before waiting frames). One task can so follow both
    /// with the one receive half, which [`Rx::recv`] and [`Rx::state_change`] each
    /// borrow `&mut`.
    ///
    /// Cancel-safe as both: a frame or change is taken only by the poll that returns
    /// it; a dropped future takes its waker out of both cells.
    pub async fn event(&mut self) -> Result<RxEvent, Error> {
        let s = self.s;
        let _frames = Unregister(&s.wakers.rx);
        let _changes = Unregister(&s.wakers.state);
        poll_fn(|cx| {
            for attempt in 0..2 {
                if let Some(c) = self.take_state_change() {
                    return Poll::Ready(Ok(RxEvent::StateChange(c)));
                }
                match self.receive() {
                    Ok(f) => return Poll::Ready(Ok(RxEvent::Frame(f))),
                    Err(nb::Error::Other(e)) => return Poll::Ready(Err(e)),
                    Err(nb::Error::WouldBlock) => {}
                }
                if attempt == 0 {
                    s.wakers.rx.register(cx.waker());
                    s.wakers.state.register(cx.waker());
                }
            }
            Poll::Pending
        })
        .await
    }
}

#[cfg(all(test, feature = "mock"))]
mod tests {
    use core::future::Future;
    use core::pin::pin;
    use core::task::{Context, Poll};

    use super::RxEvent;
    use crate::mock::MockHardware;
    use crate::split::State;
    use crate::{Error, ErrorState, FifoQueue, Frame, LastErrorCode, Token, TxOutcome};

    fn poll_once<F: Future>(f: core::pin::Pin<&mut F>) -> Poll<F::Output> {
        f.poll(&mut Context::from_waker(core::task::Waker::noop()))
    }

    #[test]
    fn completed_refuses_a_token_not_handed_out() {
        let state: State<MockHardware, 8, FifoQueue<4>> = State::new();
        let mut p = state.split(MockHardware::new(3)).ok().unwrap();
        let next = p.tx.next_token();
        assert_eq!(
            poll_once(pin!(p.tx.completed(next))),
            Poll::Ready(Err(Error::InvalidArgument))
        );
        assert_eq!(
            poll_once(pin!(p.tx.completed(Token(next.0 + 1000)))),
            Poll::Ready(Err(Error::InvalidArgument))
        );
    }

    #[test]
    fn completed_reports_a_completion_lost_to_a_full_ring_during_the_wait() {
        // A completion ring of one.
        let state: State<MockHardware, 8, FifoQueue<4>, 0, 1> = State::new();
        let mut p = state.split(MockHardware::new(3)).ok().unwrap();
        let f = Frame::standard(0x10, &[]).unwrap();
        let _t0 = p.tx.try_send(&f).unwrap();
        let t1 = p.tx.try_send(&f).unwrap();
        let mut wait = pin!(p.tx.completed(t1));
        assert!(poll_once(wait.as_mut()).is_pending());
        state.hardware().unwrap().complete_all();
        p.tx_irq.on_interrupt();
        assert_eq!(state.traffic().completion_overflows, 1);
        assert_eq!(poll_once(wait.as_mut()), Poll::Ready(Err(Error::Overrun)));
    }

    #[test]
    fn completed_skips_other_completions() {
        let state: State<MockHardware, 8, FifoQueue<4>> = State::new();
        let mut p = state.split(MockHardware::new(3)).ok().unwrap();
        let f = Frame::standard(0x10, &[]).unwrap();
        let _t0 = p.tx.try_send(&f).unwrap();
        let t1 = p.tx.try_send(&f).unwrap();
        state.hardware().unwrap().complete_all();
        p.tx_irq.on_interrupt();
        let wait = pin!(p.tx.completed(t1));
        match poll_once(wait) {
            Poll::Ready(Ok(c)) => assert_eq!((c.token, c.outcome), (t1, TxOutcome::Sent)),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn event_gives_state_changes_first_then_frames() {
        let state: State<MockHardware, 8, FifoQueue<4>> = State::new();
        let mut p = state
            .split(MockHardware::new(3).with_loopback(true))
            .ok()
            .unwrap();
        let hw = state.hardware().unwrap();
        {
            let mut ev = pin!(p.rx.event());
            assert!(poll_once(ev.as_mut()).is_pending());
        }
        let f = Frame::standard(0x42, &[7]).unwrap();
        p.tx.try_send(&f).unwrap();
        hw.complete_all();
        p.rx0_irq.on_interrupt();
        hw.set_status(ErrorState::Passive, 128, 0, LastErrorCode::Acknowledge);
        p.status_irq.on_interrupt();
        let first = poll_once(pin!(p.rx.event()));
        match first {
            Poll::Ready(Ok(RxEvent::StateChange(c))) => assert_eq!(c.state, ErrorState::Passive),
            other => panic!("{other:?}"),
        }
        match poll_once(pin!(p.rx.event())) {
            Poll::Ready(Ok(RxEvent::Frame(r))) => assert_eq!(r.frame, f),
            other => panic!("{other:?}"),
        }
        assert!(poll_once(pin!(p.rx.event())).is_pending());
    }
}
