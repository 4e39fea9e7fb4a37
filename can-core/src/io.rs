//! The two portable traits an application is generic over: [`CanTx`] to send,
//! [`CanRx`] to receive. The split driver's halves implement one each, the one-struct
//! [`crate::Driver`] both, so the same application code runs in firmware (halves in
//! different contexts) and in polling code or host tests (one driver).

use crate::error::Error;
use crate::frame::{Frame, RxFrame};
use crate::hardware::Token;

/// Sends frames.
pub trait CanTx {
    /// Accepts `frame` for transmission: its token, `WouldBlock` when the queue is
    /// full; an error means the frame was not accepted.
    fn try_send(&mut self, frame: &Frame) -> nb::Result<Token, Error>;
}

/// Receives frames with their user filter index.
pub trait CanRx {
    /// The oldest received frame; `WouldBlock` when none is waiting.
    fn receive(&mut self) -> nb::Result<RxFrame, Error>;
}

/// Sends frames, waiting for room (feature `async`).
///
/// The portable async trait: an application generic over it runs on both backends.
/// Frames are this crate's [`Frame`], an [`embedded_can::Frame`]: build them with
/// `embedded_can::Frame::new` as well as with the inherent constructors.
#[cfg(feature = "async")]
pub trait AsyncCanTx {
    /// Waits for room, then accepts `frame`; its token.
    fn send(&mut self, frame: &Frame) -> impl core::future::Future<Output = Result<Token, Error>>;
}

/// Receives frames, waiting for one (feature `async`).
#[cfg(feature = "async")]
pub trait AsyncCanRx {
    /// Waits for the next frame, with its user filter index and time stamp.
    fn recv(&mut self) -> impl core::future::Future<Output = Result<RxFrame, Error>>;
}
