//! What a split driver pays for, chosen at compile time (issue 21): the `Fe` parameter of
//! [`crate::split::State`] and its handles, [`Full`] by default, [`Lean`] one line away:
//!
//! ```
//! use twocan_core::mock::MockHardware;
//! use twocan_core::split::State;
//! use twocan_core::{FifoQueue, Lean};
//!
//! // Fire-and-forget (no completion ring: DONE = 0), no statistics, no time stamps.
//! static CAN: State<MockHardware, 8, FifoQueue<4>, 0, 0, Lean> = State::new();
//! # let _ = &CAN;
//! ```
//!
//! | | [`Full`] | [`Lean`] |
//! |---|---|---|
//! | traffic statistics ([`crate::TrafficStats`]: queued, sent, failed, aborted, received, dropped) | counted | zero-sized, read as 0 |
//! | receive and transmit time stamps ([`crate::RxFrame::timestamp`], `Completion::timestamp`) | widened and reported | not read, `None` |
//!
//! Transmit completions are the `DONE` parameter (0: no completion ring, fire and
//! forget). With `DONE` = 0, [`Lean`] and a request-order queue ([`crate::FifoQueue`]),
//! nothing is left for the transmit interrupt to report: on a controller that offers it
//! ([`crate::Hardware::QUIET_TX`], bxCAN), the driver then enables that interrupt only
//! while frames wait in its queue, and the direct path loads a mailbox whether or not
//! its last end was acknowledged — a frame sent with an empty queue costs no
//! interrupt. Rare events stay counted in both (hardware overruns, ring and queue
//! overflows, error counts, state changes): they cost nothing on the per-frame path.
//! Counters wrap (compare readings with wrapping differences).
//!
//! A backend adopts this by nothing: the choice lives in the portable state. A backend
//! that records time stamps in hardware may still want the recording off in its own
//! configuration (bxCAN `Config::timestamps(false)`, `CAN_MCR.TTCM` = 0) so that its
//! per-frame code does not read them either.

use crate::spsc::Counter;

/// A traffic counter as a feature set stores it: [`Counter`] (counted) or [`NoTally`]
/// (zero-sized, nothing counted).
pub trait Tally: Send + Sync {
    /// Zero (all zeros: a `static` of it is `.bss`).
    const NEW: Self;
    /// Adds one (from the counter's one writer context).
    fn inc(&self);
    /// Adds `n` (from the counter's one writer context).
    fn add(&self, n: u32);
    /// The value (0 when nothing is counted).
    fn get(&self) -> u32;
}

impl Tally for Counter {
    const NEW: Self = Counter::new();
    #[inline(always)]
    fn inc(&self) {
        Counter::inc(self)
    }
    #[inline(always)]
    fn add(&self, n: u32) {
        Counter::add(self, n)
    }
    #[inline(always)]
    fn get(&self) -> u32 {
        Counter::get(self)
    }
}

/// A counter that counts nothing and takes no room.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoTally;

impl Tally for NoTally {
    const NEW: Self = NoTally;
    #[inline(always)]
    fn inc(&self) {}
    #[inline(always)]
    fn add(&self, _: u32) {}
    #[inline(always)]
    fn get(&self) -> u32 {
        0
    }
}

/// A compile-time feature set of the split driver (see the [module docs](self)).
pub trait Features: 'static {
    /// Receive and transmit time stamps are read from the hardware and widened.
    const TIMESTAMPS: bool;
    /// Whether the traffic statistics count ([`Features::Counter`] is a [`Counter`]).
    const COUNTS: bool;
    /// How the traffic counters are stored.
    type Counter: Tally;
}

/// Every feature (the default): statistics, time stamps.
#[derive(Debug, Clone, Copy)]
pub enum Full {}

impl Features for Full {
    const TIMESTAMPS: bool = true;
    const COUNTS: bool = true;
    type Counter = Counter;
}

/// No traffic statistics, no time stamps: the per-frame path does only the frame's work.
#[derive(Debug, Clone, Copy)]
pub enum Lean {}

impl Features for Lean {
    const TIMESTAMPS: bool = false;
    const COUNTS: bool = false;
    type Counter = NoTally;
}
