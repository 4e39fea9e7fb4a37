//! The portable application shared by the firmware examples, the host demo and the
//! cross-controller tests.
//!
//! It only speaks the `twocan-core` API, so the very same code runs on a Teensy 3.x
//! (FlexCAN), an STM32F7 board (bxCAN) and the host simulation. Each node:
//! - publishes a *heartbeat* (standard data frame `0x100 + node`, a 32-bit counter) and a
//!   *measurement* (extended data frame `0x18FF_0000 | node << 8`, 8 bytes);
//! - periodically asks its peer for a *status* with a remote frame
//!   (standard `0x200 + peer`, DLC 4) and answers the peer's remote requests with a data
//!   frame of the same identifier;
//! - receives through [`App::filters`] (the same portable filter list on every controller)
//!   and handles frames by filter index through a [`Dispatcher`].
//!
//! ```
//! use twocan_app::{App, FILTER_COUNT};
//! let app = App::new(1, 2);
//! let filters = app.filters();
//! assert_eq!(filters.len(), FILTER_COUNT);
//! assert!(filters.iter().all(|f| f.check().is_ok()));
//! ```
#![no_std]
#![deny(missing_docs)]

#[cfg(feature = "async")]
pub mod asynch;
pub mod firmware;

use twocan_core::{CanRx, CanTx, Dispatcher, Filter, Format, Frame, FrameKind, RxFrame};

/// Number of filters of the application's list.
pub const FILTER_COUNT: usize = 4;

/// The filter list of node `node` talking with `peer` ([`App::filters`]), as a `const fn`:
/// firmware with little RAM compiles it into a filter plan at build time (e.g. bxCAN's
/// `const_plan!`) instead of planning at run time.
pub const fn filters_for(node: u8, peer: u8) -> [Filter; FILTER_COUNT] {
    [
        Filter::standard(0x100 + peer as u16),
        Filter::masked(
            FrameKind::Data,
            Format::Extended,
            0x1FFF_FF00,
            0x18FF_0000 | (peer as u32) << 8,
        ),
        Filter::exact(FrameKind::Remote, Format::Standard, 0x200 + node as u32),
        Filter::exact(FrameKind::Data, Format::Standard, 0x200 + peer as u32),
    ]
}

/// Filter index: the peer's heartbeat.
pub const F_HEARTBEAT: usize = 0;
/// Filter index: the peer's measurements (extended, masked).
pub const F_MEASUREMENT: usize = 1;
/// Filter index: remote requests for our status.
pub const F_STATUS_REQUEST: usize = 2;
/// Filter index: the peer's status answers.
pub const F_STATUS: usize = 3;

/// Counters of what the application saw and did (`repr(C)`: the firmware-in-the-loop
/// tests read them from the firmware's memory in this field order).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[repr(C)]
pub struct AppStats {
    /// Frames accepted by the driver's transmit queue.
    pub sent: u32,
    /// Frames refused because the transmit queue was full (retried later).
    pub tx_full: u32,
    /// Heartbeats received from the peer.
    pub heartbeats: u32,
    /// Heartbeats whose counter skipped values (frames lost between the peers).
    pub heartbeat_gaps: u32,
    /// Heartbeats received twice (CAN's double reception: an error in the last-but-one
    /// bit of end-of-frame makes receivers keep a frame its transmitter sends again).
    pub heartbeat_duplicates: u32,
    /// Measurements received.
    pub measurements: u32,
    /// Remote status requests received.
    pub requests: u32,
    /// Status answers received.
    pub answers: u32,
    /// Frames taken by a filter without call-back (none expected).
    pub unhandled: u32,
}

/// The state the call-backs work on.
#[derive(Debug, Default)]
pub struct AppState {
    /// Counters.
    pub stats: AppStats,
    /// Next expected heartbeat counter from the peer.
    expected: Option<u32>,
    /// Status requests waiting to be answered.
    pending_answers: u32,
}

/// One node of the demo.
pub struct App {
    node: u8,
    peer: u8,
    counter: u32,
    tick: u32,
    /// What the node saw.
    pub state: AppState,
    dispatcher: Dispatcher<AppState, FILTER_COUNT>,
    pending: Option<Frame>,
}

impl App {
    /// A node `node` talking with `peer` (both `0..=255`).
    pub fn new(node: u8, peer: u8) -> Self {
        let mut dispatcher = Dispatcher::new();
        // Indices are constants below FILTER_COUNT, so `set` cannot fail.
        let _ = dispatcher.set(F_HEARTBEAT, on_heartbeat);
        let _ = dispatcher.set(F_MEASUREMENT, on_measurement);
        let _ = dispatcher.set(F_STATUS_REQUEST, on_status_request);
        let _ = dispatcher.set(F_STATUS, on_status);
        App {
            node,
            peer,
            counter: 0,
            tick: 0,
            state: AppState::default(),
            dispatcher,
            pending: None,
        }
    }

    /// The portable filter list, in the order of the `F_*` indices ([`filters_for`]).
    pub fn filters(&self) -> [Filter; FILTER_COUNT] {
        filters_for(self.node, self.peer)
    }

    /// Runs one period of the application with a one-struct driver (something that both
    /// sends and receives): [`App::handle`], then [`App::publish`]. Call it from the main
    /// loop (on the host: every simulated millisecond).
    pub fn step<C: CanTx + CanRx>(&mut self, driver: &mut C) {
        self.handle(driver);
        self.publish(driver);
    }

    /// Handles every frame waiting in `rx` through the dispatcher (by filter index).
    pub fn handle<R: CanRx>(&mut self, rx: &mut R) {
        while let Ok(frame) = rx.receive() {
            self.dispatcher.dispatch(&mut self.state, &frame);
        }
        self.state.stats.unhandled = self.dispatcher.unhandled();
    }

    /// Answers requests and publishes this period's frames through `driver`.
    pub fn publish<T: CanTx>(&mut self, driver: &mut T) {
        self.tick = self.tick.wrapping_add(1);
        // A frame refused earlier goes first, so that the heartbeat counter stays in order.
        if let Some(f) = self.pending.take() {
            if !self.send(driver, f) {
                return;
            }
        }
        while self.state.pending_answers > 0 {
            self.state.pending_answers -= 1;
            if let Some(f) = self.answer() {
                if !self.send(driver, f) {
                    return;
                }
            }
        }
        if let Some(f) = self.heartbeat() {
            if !self.send(driver, f) {
                return;
            }
        }
        if self.tick.is_multiple_of(4) {
            if let Some(f) = self.measurement() {
                if !self.send(driver, f) {
                    return;
                }
            }
        }
        if self.tick.is_multiple_of(10) {
            if let Some(f) = self.status_request() {
                self.send(driver, f);
            }
        }
    }

    /// The answer to a status request: our counter.
    fn answer(&self) -> Option<Frame> {
        Frame::standard(0x200 + self.node as u16, &self.counter.to_le_bytes()).ok()
    }

    /// This period's heartbeat. The counter moves on even if the frame waits in
    /// `pending`: it goes first next time.
    fn heartbeat(&mut self) -> Option<Frame> {
        let f = Frame::standard(0x100 + self.node as u16, &self.counter.to_le_bytes()).ok()?;
        self.counter = self.counter.wrapping_add(1);
        Some(f)
    }

    /// The measurement (every 4th period).
    fn measurement(&self) -> Option<Frame> {
        let mut m = [0u8; 8];
        m[..4].copy_from_slice(&self.tick.to_le_bytes());
        m[4..].copy_from_slice(&(self.counter ^ 0xA5A5_A5A5).to_le_bytes());
        Frame::extended(0x18FF_0000 | (self.node as u32) << 8, &m).ok()
    }

    /// The remote status request to the peer (every 10th period).
    fn status_request(&self) -> Option<Frame> {
        Frame::remote(0x200 + self.peer as u32, false, 4).ok()
    }

    /// Queues `frame`; if the queue is full keeps it for the next step and returns false.
    fn send<T: CanTx>(&mut self, driver: &mut T, frame: Frame) -> bool {
        match driver.try_send(&frame) {
            Ok(_) => {
                self.state.stats.sent += 1;
                true
            }
            Err(_) => {
                self.state.stats.tx_full += 1;
                self.pending = Some(frame);
                false
            }
        }
    }

    /// Counters.
    pub fn stats(&self) -> AppStats {
        self.state.stats
    }
}

fn on_heartbeat(s: &mut AppState, rx: &RxFrame) {
    s.stats.heartbeats += 1;
    if let Some(n) = rx.frame.data_u32(0) {
        match s.expected {
            Some(expected) if n.wrapping_add(1) == expected => {
                s.stats.heartbeat_duplicates += 1;
                return;
            }
            Some(expected) if n != expected => s.stats.heartbeat_gaps += 1,
            _ => {}
        }
        s.expected = Some(n.wrapping_add(1));
    }
}

fn on_measurement(s: &mut AppState, _rx: &RxFrame) {
    s.stats.measurements += 1;
}

fn on_status_request(s: &mut AppState, _rx: &RxFrame) {
    s.stats.requests += 1;
    s.pending_answers += 1;
}

fn on_status(s: &mut AppState, _rx: &RxFrame) {
    s.stats.answers += 1;
}
