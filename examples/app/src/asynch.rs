//! The async form of the portable application (feature `async`), generic over the
//! portable async traits [`AsyncCanTx`] / [`AsyncCanRx`], so that it runs on both
//! controllers' split halves under any executor (embassy-executor in the firmware, a
//! host executor in the demo and the tests).
//!
//! - [`App::publish_async`]: one period of [`App::publish`], waiting for room in the
//!   transmit queue instead of keeping a refused frame for the next period;
//! - [`App::receive_async`]: waits for one frame and dispatches it by filter index;
//! - [`echo`] / [`echo_frame`]: the echo node of the `async_echo` firmware examples.
//!
//! ```
//! use twocan_app::asynch::echo_frame;
//! use twocan_core::Frame;
//! let f = Frame::standard(0x7FF, &[1, 2]).unwrap();
//! assert_eq!(echo_frame(&f), Frame::standard(0x000, &[1, 2]).unwrap());
//! ```

use twocan_core::{AsyncCanRx, AsyncCanTx, Error, Frame};

use crate::App;

/// The frame the echo node sends back for `frame`: the same format, kind and data, the
/// identifier plus one (wrapping within 11 or 29 bits).
pub fn echo_frame(frame: &Frame) -> Frame {
    let (mask, extended) = if frame.is_extended() {
        (0x1FFF_FFFF, true)
    } else {
        (0x7FF, false)
    };
    let id = frame.raw_id().wrapping_add(1) & mask;
    // The same kind, DLC code (9..=15 kept as written) and data bytes.
    let echoed = Frame::from_registers(
        id,
        extended,
        frame.is_remote(),
        frame.dlc(),
        frame.data_padded(),
    );
    // The identifier is masked to its format and the DLC is the received frame's: the
    // constructor accepts both.
    echoed.unwrap_or(*frame)
}

/// What the echo node did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EchoStats {
    /// Frames received.
    pub received: u32,
    /// Echoes accepted by the transmit queue.
    pub echoed: u32,
    /// Echoes the driver refused (bus-off, wrong mode): counted, not retried.
    pub refused: u32,
}

/// Waits for one frame on `rx` and sends its [`echo_frame`] through `tx` (waiting for
/// room). A receive error is returned; a refused echo is counted in `stats`.
///
/// Cancel-safe at every await: dropped while waiting for a frame, nothing was taken;
/// dropped while waiting for room, the received frame is counted but not echoed.
pub async fn echo<T: AsyncCanTx, R: AsyncCanRx>(
    tx: &mut T,
    rx: &mut R,
    stats: &mut EchoStats,
) -> Result<(), Error> {
    let got = rx.recv().await?;
    stats.received = stats.received.wrapping_add(1);
    match tx.send(&echo_frame(&got.frame)).await {
        Ok(_) => stats.echoed = stats.echoed.wrapping_add(1),
        Err(_) => stats.refused = stats.refused.wrapping_add(1),
    }
    Ok(())
}

impl App {
    /// Waits for one frame on `rx` and hands it to its filter's call-back; a receive
    /// error is returned. Cancel-safe: a dropped call took no frame.
    pub async fn receive_async<R: AsyncCanRx>(&mut self, rx: &mut R) -> Result<(), Error> {
        let frame = rx.recv().await?;
        self.dispatcher.dispatch(&mut self.state, &frame);
        self.state.stats.unhandled = self.dispatcher.unhandled();
        Ok(())
    }

    /// One period of [`App::publish`] through an async transmit half: the answers owed,
    /// the heartbeat, and every 4th period a measurement, every 10th a status request,
    /// each waiting for room in the transmit queue (so `tx_full` counts only refusals).
    /// A frame the driver refuses (bus-off, wrong mode) is counted in `tx_full` and kept
    /// for the next period, which it starts, as [`App::publish`] does.
    ///
    /// Dropped while waiting for room, the frame it waited with is kept and goes first
    /// in the next period (as a frame refused by [`App::publish`] does).
    pub async fn publish_async<T: AsyncCanTx>(&mut self, tx: &mut T) {
        self.tick = self.tick.wrapping_add(1);
        if let Some(f) = self.pending.take() {
            if !self.send_async(tx, f).await {
                return;
            }
        }
        while self.state.pending_answers > 0 {
            self.state.pending_answers -= 1;
            if let Some(f) = self.answer() {
                if !self.send_async(tx, f).await {
                    return;
                }
            }
        }
        if let Some(f) = self.heartbeat() {
            if !self.send_async(tx, f).await {
                return;
            }
        }
        if self.tick.is_multiple_of(4) {
            if let Some(f) = self.measurement() {
                if !self.send_async(tx, f).await {
                    return;
                }
            }
        }
        if self.tick.is_multiple_of(10) {
            if let Some(f) = self.status_request() {
                self.send_async(tx, f).await;
            }
        }
    }

    /// Sends `frame`, waiting for room. The frame sits in `pending` until it is
    /// accepted, so a dropped future or a refusal leaves it for the next period.
    async fn send_async<T: AsyncCanTx>(&mut self, tx: &mut T, frame: Frame) -> bool {
        self.pending = Some(frame);
        match tx.send(&frame).await {
            Ok(_) => {
                self.pending = None;
                self.state.stats.sent += 1;
                true
            }
            Err(_) => {
                self.state.stats.tx_full += 1;
                false
            }
        }
    }
}
