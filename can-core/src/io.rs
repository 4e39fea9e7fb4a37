//! The portable traits an application or a protocol stack is generic over: [`CanTx`] to
//! send and follow what was sent, [`CanRx`] to receive and follow the error state, both
//! with the statistics of [`CanStatus`]; with the `async` feature `AsyncCanTx` and
//! `AsyncCanRx` add the waits.
//!
//! The split driver's halves implement one each ([`Tx`], [`Rx`]), the one-struct
//! [`Driver`] both, so the same code runs in firmware (halves in different contexts) and
//! in polling code or host tests (one driver). A generic adapter — an ISO-TP segmenter, a
//! CANopen bridge — needs nothing more than these traits: the token of each accepted
//! frame and the completion stream that settles it, how many frames wait, the ring and
//! traffic figures, the error state. This module holds the traits and their
//! implementations for the driver's types, so that it sits above them: the driver's
//! modules never name it.
//!
//! ```
//! use twocan_core::io::{CanRx, CanTx};
//! use twocan_core::mock::{block, MockHardware};
//! use twocan_core::{Driver, Frame, TxOutcome};
//!
//! /// Sends `frame` and waits (polling `service`, at most `rounds` times) for its completion.
//! fn send_and_confirm<C: CanTx + CanRx>(
//!     can: &mut C,
//!     frame: &Frame,
//!     rounds: u32,
//!     service: impl Fn(&mut C),
//! ) -> Option<TxOutcome> {
//!     let token = block("room to send", || can.try_send(frame)).expect("accepted");
//!     for _ in 0..rounds {
//!         service(can);
//!         if let Some(done) = can.take_completion() {
//!             if done.token == token {
//!                 return Some(done.outcome);
//!             }
//!         }
//!     }
//!     None
//! }
//!
//! let mut can: Driver<MockHardware, 8, 4> = Driver::new(MockHardware::new(3).with_loopback(true));
//! let frame = Frame::standard(0x7E0, &[2, 0x10, 0x03])?;
//! let outcome = send_and_confirm(&mut can, &frame, 100, |c| {
//!     c.hardware().complete_all();
//!     c.on_interrupt();
//! });
//! assert_eq!(outcome, Some(TxOutcome::Sent));
//! assert_eq!((CanRx::available(&can), can.traffic().sent), (1, 1));
//! assert_eq!(block("the frame back", || can.receive())?.frame, frame);
//! # Ok::<(), twocan_core::Error>(())
//! ```

use crate::capabilities::Capabilities;
use crate::controller::ErrorStatus;
use crate::driver::Driver;
use crate::error::{Error, ErrorStatistics};
use crate::features::Features;
use crate::frame::{Frame, RxFrame};
use crate::hardware::{Completion, Hardware, Token};
use crate::split::{AbortRequest, Rx, StateChange, TrafficStats, Tx};
use crate::spsc::BufferStats;
use crate::txqueue::TxQueue;

/// What every handle of a driver reports: traffic and error statistics, the controller's
/// error status and capabilities. Reads only; any context may make them.
pub trait CanStatus {
    /// Traffic counters (frames queued, sent, failed, aborted, received, dropped, lost).
    fn traffic(&self) -> TrafficStats;
    /// Bus errors by kind, bus-off entries, wake-ups (a lower bound, see
    /// [`ErrorStatistics`]).
    fn error_stats(&self) -> ErrorStatistics;
    /// The controller's error state, counters and last error code, read now.
    fn error_status(&self) -> ErrorStatus;
    /// What the controller can do, as configured now.
    fn capabilities(&self) -> Capabilities;
}

/// Sends frames, and reports what became of them.
///
/// Every frame [`CanTx::try_send`] accepts gets a [`Token`], and exactly one
/// [`Completion`] with that token follows through [`CanTx::take_completion`] (sent,
/// failed in one-shot mode, or aborted), in the order the controller reported them.
pub trait CanTx: CanStatus {
    /// Accepts `frame` for transmission: its token, `WouldBlock` when the queue is
    /// full; an error means the frame was not accepted.
    fn try_send(&mut self, frame: &Frame) -> nb::Result<Token, Error>;
    /// The next completion (the completion stream); `None` when none is waiting.
    fn take_completion(&mut self) -> Option<Completion>;
    /// Aborts the frame of `token`, queued or in a mailbox; its completion follows
    /// (see [`AbortRequest`]).
    fn abort(&mut self, token: Token) -> AbortRequest;
    /// The token the next accepted frame will get.
    fn next_token(&self) -> Token;
    /// Transmit queue figures: capacity, frames queued now, peak, refusals.
    fn tx_stats(&self) -> BufferStats;
}

/// Receives frames with their user filter index, and follows the error state.
pub trait CanRx: CanStatus {
    /// The oldest received frame; `WouldBlock` when none is waiting.
    fn receive(&mut self) -> nb::Result<RxFrame, Error>;
    /// Frames waiting to be received (ACAN `available()`).
    fn available(&self) -> usize;
    /// The next error-state change, in order, with the counters at the change.
    fn take_state_change(&mut self) -> Option<StateChange>;
    /// Receive ring figures: capacity, frames waiting, peak, frames lost to a full ring.
    fn rx_stats(&self) -> BufferStats;
}

/// Sends frames, waiting for room, and waits for their completions (feature `async`).
///
/// The portable async trait: an application generic over it runs on both backends.
/// Frames are this crate's [`Frame`], an [`embedded_can::Frame`]: build them with
/// `embedded_can::Frame::new` as well as with the inherent constructors.
#[cfg(feature = "async")]
pub trait AsyncCanTx: CanTx {
    /// Waits for room, then accepts `frame`; its token.
    fn send(&mut self, frame: &Frame) -> impl core::future::Future<Output = Result<Token, Error>>;
    /// Waits for the next completion, in the order the controller reported them.
    fn completion(&mut self) -> impl core::future::Future<Output = Completion>;
    /// Waits for the completion of `token`, dropping the completions of other frames
    /// that come before it ([`Tx::completed`] has the errors).
    fn completed(
        &mut self,
        token: Token,
    ) -> impl core::future::Future<Output = Result<Completion, Error>>;
}

/// Receives frames, waiting for one, and waits for error-state changes (feature
/// `async`).
#[cfg(feature = "async")]
pub trait AsyncCanRx: CanRx {
    /// Waits for the next frame, with its user filter index and time stamp.
    fn recv(&mut self) -> impl core::future::Future<Output = Result<RxFrame, Error>>;
    /// Waits for the next error-state change.
    fn state_change(&mut self) -> impl core::future::Future<Output = StateChange>;
    /// Waits for a frame or an error-state change, whichever comes first.
    fn event(&mut self) -> impl core::future::Future<Output = Result<crate::RxEvent, Error>>;
}

/// `CanStatus` of a half: the shared state's statistics, the controller's status.
macro_rules! status_of_a_half {
    ($half:ident) => {
        impl<
                H: Hardware,
                const RX: usize,
                Q: TxQueue,
                const RX1: usize,
                const DONE: usize,
                Fe: Features,
            > CanStatus for $half<'_, H, RX, Q, RX1, DONE, Fe>
        {
            fn traffic(&self) -> TrafficStats {
                self.state().traffic()
            }
            fn error_stats(&self) -> ErrorStatistics {
                self.state().error_stats()
            }
            fn error_status(&self) -> ErrorStatus {
                self.hardware().error_status()
            }
            fn capabilities(&self) -> Capabilities {
                self.hardware().capabilities()
            }
        }
    };
}

status_of_a_half!(Tx);
status_of_a_half!(Rx);

impl<
        H: Hardware,
        const RX: usize,
        Q: TxQueue,
        const RX1: usize,
        const DONE: usize,
        Fe: Features,
    > CanTx for Tx<'_, H, RX, Q, RX1, DONE, Fe>
{
    fn try_send(&mut self, frame: &Frame) -> nb::Result<Token, Error> {
        Tx::try_send(self, frame)
    }
    fn take_completion(&mut self) -> Option<Completion> {
        Tx::take_completion(self)
    }
    fn abort(&mut self, token: Token) -> AbortRequest {
        Tx::abort(self, token)
    }
    fn next_token(&self) -> Token {
        Tx::next_token(self)
    }
    fn tx_stats(&self) -> BufferStats {
        Tx::stats(self)
    }
}

impl<
        H: Hardware,
        const RX: usize,
        Q: TxQueue,
        const RX1: usize,
        const DONE: usize,
        Fe: Features,
    > CanRx for Rx<'_, H, RX, Q, RX1, DONE, Fe>
{
    fn receive(&mut self) -> nb::Result<RxFrame, Error> {
        Rx::receive(self)
    }
    fn available(&self) -> usize {
        Rx::available(self)
    }
    fn take_state_change(&mut self) -> Option<StateChange> {
        Rx::take_state_change(self)
    }
    fn rx_stats(&self) -> BufferStats {
        Rx::stats(self)
    }
}

impl<H: Hardware, const RX: usize, const TX: usize, const RX1: usize> CanStatus
    for Driver<H, RX, TX, RX1>
{
    fn traffic(&self) -> TrafficStats {
        Driver::traffic(self)
    }
    fn error_stats(&self) -> ErrorStatistics {
        Driver::error_stats(self)
    }
    fn error_status(&self) -> ErrorStatus {
        Driver::error_status(self)
    }
    fn capabilities(&self) -> Capabilities {
        Driver::capabilities(self)
    }
}

impl<H: Hardware, const RX: usize, const TX: usize, const RX1: usize> CanTx
    for Driver<H, RX, TX, RX1>
{
    fn try_send(&mut self, frame: &Frame) -> nb::Result<Token, Error> {
        Driver::try_send(self, frame)
    }
    fn take_completion(&mut self) -> Option<Completion> {
        Driver::take_completion(self)
    }
    fn abort(&mut self, token: Token) -> AbortRequest {
        Driver::abort(self, token)
    }
    fn next_token(&self) -> Token {
        Driver::next_token(self)
    }
    fn tx_stats(&self) -> BufferStats {
        Driver::tx_stats(self)
    }
}

impl<H: Hardware, const RX: usize, const TX: usize, const RX1: usize> CanRx
    for Driver<H, RX, TX, RX1>
{
    fn receive(&mut self) -> nb::Result<RxFrame, Error> {
        Driver::receive(self)
    }
    fn available(&self) -> usize {
        Driver::available(self)
    }
    fn take_state_change(&mut self) -> Option<StateChange> {
        Driver::take_state_change(self)
    }
    fn rx_stats(&self) -> BufferStats {
        Driver::rx_stats(self)
    }
}

#[cfg(feature = "async")]
impl<H: Hardware, const RX: usize, Q: TxQueue, const RX1: usize, const DONE: usize> AsyncCanTx
    for Tx<'_, H, RX, Q, RX1, DONE>
{
    fn send(&mut self, frame: &Frame) -> impl core::future::Future<Output = Result<Token, Error>> {
        Tx::send(self, frame)
    }
    fn completion(&mut self) -> impl core::future::Future<Output = Completion> {
        Tx::completion(self)
    }
    fn completed(
        &mut self,
        token: Token,
    ) -> impl core::future::Future<Output = Result<Completion, Error>> {
        Tx::completed(self, token)
    }
}

#[cfg(feature = "async")]
impl<H: Hardware, const RX: usize, Q: TxQueue, const RX1: usize, const DONE: usize> AsyncCanRx
    for Rx<'_, H, RX, Q, RX1, DONE>
{
    fn recv(&mut self) -> impl core::future::Future<Output = Result<RxFrame, Error>> {
        Rx::recv(self)
    }
    fn state_change(&mut self) -> impl core::future::Future<Output = StateChange> {
        Rx::state_change(self)
    }
    fn event(&mut self) -> impl core::future::Future<Output = Result<crate::RxEvent, Error>> {
        Rx::event(self)
    }
}

#[cfg(all(test, feature = "mock"))]
mod tests {
    use super::{CanRx, CanStatus, CanTx};
    use crate::mock::MockHardware;
    use crate::split::State;
    use crate::{AbortRequest, Driver, ErrorState, FifoQueue, Frame, LastErrorCode, TxOutcome};

    /// Sends `n` frames through any `CanTx`, then takes every completion: what a generic
    /// adapter does, against the trait alone.
    fn send_n<T: CanTx>(tx: &mut T, n: u16) -> u32 {
        let first = tx.next_token();
        for i in 0..n {
            let f = Frame::standard(0x100 + i, &[]).unwrap();
            let t = crate::mock::block("room to send", || tx.try_send(&f)).unwrap();
            assert_eq!(t.0, first.0 + u32::from(i));
        }
        tx.traffic().queued
    }

    #[test]
    fn the_halves_answer_through_the_traits_as_through_their_own_methods() {
        let state: State<MockHardware, 8, FifoQueue<4>> = State::new();
        let mut p = state
            .split(MockHardware::new(1).with_loopback(true))
            .ok()
            .unwrap();
        assert_eq!(send_n(&mut p.tx, 3), 3);
        // One mailbox: two frames wait in the queue.
        assert_eq!(CanTx::tx_stats(&p.tx), p.tx.stats());
        assert_eq!(p.tx.tx_stats().count, 2);
        let last = p.tx.next_token();
        assert_eq!(
            CanTx::abort(&mut p.tx, crate::Token(last.0 - 1)),
            AbortRequest::Dequeued
        );
        let hw = state.hardware().unwrap();
        hw.complete();
        p.tx_irq.on_interrupt();
        p.rx0_irq.on_interrupt();
        let mut outcomes = Vec::new();
        while let Some(c) = CanTx::take_completion(&mut p.tx) {
            outcomes.push((c.token.0, c.outcome));
        }
        assert_eq!(
            outcomes,
            [(2, TxOutcome::Aborted), (0, TxOutcome::Sent)],
            "the dequeued frame's completion was recorded first"
        );
        assert_eq!(CanRx::available(&p.rx), 1);
        assert_eq!(p.rx.rx_stats(), p.rx.stats());
        assert_eq!(CanRx::receive(&mut p.rx).unwrap().frame.raw_id(), 0x100);
        assert_eq!(CanStatus::traffic(&p.rx), state.traffic());

        hw.set_status(ErrorState::Warning, 97, 3, LastErrorCode::Stuff);
        p.status_irq.on_interrupt();
        let change = CanRx::take_state_change(&mut p.rx).unwrap();
        assert_eq!(
            (change.state, change.counters.tec),
            (ErrorState::Warning, 97)
        );
        assert_eq!(CanStatus::error_status(&p.tx).counters.rec, 3);
        assert_eq!(CanStatus::error_stats(&p.rx).stuff, 1);
        assert_eq!(
            CanStatus::capabilities(&p.tx),
            crate::Hardware::capabilities(&*hw)
        );
    }

    #[test]
    fn the_one_struct_driver_answers_through_both_traits() {
        let mut d: Driver<MockHardware, 8, 4> =
            Driver::new(MockHardware::new(3).with_loopback(true));
        assert_eq!(send_n(&mut d, 2), 2);
        d.hardware().complete_all();
        d.on_interrupt();
        assert_eq!(CanRx::available(&d), 2);
        assert_eq!(
            CanTx::take_completion(&mut d).unwrap().outcome,
            TxOutcome::Sent
        );
        assert_eq!(CanRx::rx_stats(&d).count, 2);
        assert_eq!(CanTx::tx_stats(&d).count, 0);
        assert_eq!(CanTx::next_token(&d).0, 2);
    }
}
