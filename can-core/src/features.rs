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
//! | receive and transmit time stamps ([`crate::RxFrame::timestamp`], `Completion::timestamp`) | widened and reported | not read, `None`; no widening reference and no wraps per receive ring slot kept ([`Features::Clock`] = [`NoClock`]) |
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
use crate::timestamp::{Extender, Timestamp};

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

/// What widening the hardware's 16-bit time stamps keeps in a split driver's state:
/// an [`Extender`] (the reference each stamp is widened against, and the wraps of
/// each frame waiting in a receive ring, a `u32` per ring slot) or [`NoClock`]
/// (nothing: a feature set without time stamps pays no byte for them).
///
/// [`Features::TIMESTAMPS`] follows the clock; a feature set that sets it otherwise is
/// refused when its `State` is built:
///
/// ```compile_fail
/// use twocan_core::features::{Features, NoClock, NoTally};
/// use twocan_core::mock::MockHardware;
/// use twocan_core::split::State;
/// use twocan_core::FifoQueue;
///
/// enum StampsWithoutClock {}
/// impl Features for StampsWithoutClock {
///     const TIMESTAMPS: bool = true;
///     const COUNTS: bool = false;
///     type Counter = NoTally;
///     type Clock = NoClock; // time stamps need the `Extender`
/// }
/// static CAN: State<MockHardware, 8, FifoQueue<4>, 0, 0, StampsWithoutClock> = State::new();
/// ```
///
/// ```
/// use twocan_core::features::{Features, NoTally};
/// use twocan_core::mock::MockHardware;
/// use twocan_core::split::State;
/// use twocan_core::timestamp::Extender;
/// use twocan_core::FifoQueue;
///
/// enum StampsOnly {}
/// impl Features for StampsOnly {
///     const COUNTS: bool = false;
///     type Counter = NoTally;
///     type Clock = Extender;
/// }
/// static CAN: State<MockHardware, 8, FifoQueue<4>, 0, 0, StampsOnly> = State::new();
/// # let _ = &CAN;
/// ```
pub trait StampClock: Copy + Send + Sync + 'static {
    /// Whether stamps are widened (must equal the feature set's
    /// [`Features::TIMESTAMPS`]; `State::new` refuses to build otherwise).
    const WIDENS: bool;
    /// At the origin (all zeros: a `static` of it is `.bss`).
    const NEW: Self;
    /// The wraps of a received frame's stamp as a receive ring slot keeps them (`u32`,
    /// or zero-sized).
    type Wraps: Copy + Send + Sync + 'static;
    /// `wraps` as a ring slot keeps them.
    fn keep(wraps: u32) -> Self::Wraps;
    /// The wraps a ring slot kept (0 when nothing is kept).
    fn wraps(kept: Self::Wraps) -> u32;
    /// A reading of the free-running counter ([`Extender::observe`]).
    fn observe(&mut self, counter: u16);
    /// A stamp taken at or before the latest reading ([`Extender::extend_before`]).
    fn extend_before(&self, stamp: u16) -> Timestamp;
    /// A completed transmission's stamp ([`Extender::extend_sent`]).
    fn extend_sent(&mut self, stamp: u16, pending: impl Fn(usize) -> bool) -> Timestamp;
    /// A received frame's stamp ([`Extender::extend_received`]).
    fn extend_received(
        &mut self,
        queue: usize,
        stamp: u16,
        pending: impl Fn(usize) -> bool,
    ) -> Timestamp;
}

impl StampClock for Extender {
    const WIDENS: bool = true;
    const NEW: Self = Extender::new();
    type Wraps = u32;
    #[inline(always)]
    fn keep(wraps: u32) -> u32 {
        wraps
    }
    #[inline(always)]
    fn wraps(kept: u32) -> u32 {
        kept
    }
    #[inline(always)]
    fn observe(&mut self, counter: u16) {
        Extender::observe(self, counter);
    }
    #[inline(always)]
    fn extend_before(&self, stamp: u16) -> Timestamp {
        Extender::extend_before(self, stamp)
    }
    #[inline(always)]
    fn extend_sent(&mut self, stamp: u16, pending: impl Fn(usize) -> bool) -> Timestamp {
        Extender::extend_sent(self, stamp, pending)
    }
    #[inline(always)]
    fn extend_received(
        &mut self,
        queue: usize,
        stamp: u16,
        pending: impl Fn(usize) -> bool,
    ) -> Timestamp {
        Extender::extend_received(self, queue, stamp, pending)
    }
}

/// No time stamps widened: zero-sized, and so are the wraps kept per receive ring slot.
/// Its extensions place a stamp in the first period (never called by a split driver
/// whose feature set reads no stamp).
#[derive(Debug, Clone, Copy, Default)]
pub struct NoClock;

impl StampClock for NoClock {
    const WIDENS: bool = false;
    const NEW: Self = NoClock;
    type Wraps = ();
    #[inline(always)]
    fn keep(_: u32) {}
    #[inline(always)]
    fn wraps(_: ()) -> u32 {
        0
    }
    #[inline(always)]
    fn observe(&mut self, _: u16) {}
    #[inline(always)]
    fn extend_before(&self, stamp: u16) -> Timestamp {
        Timestamp::from_parts(0, stamp)
    }
    #[inline(always)]
    fn extend_sent(&mut self, stamp: u16, _: impl Fn(usize) -> bool) -> Timestamp {
        Timestamp::from_parts(0, stamp)
    }
    #[inline(always)]
    fn extend_received(&mut self, _: usize, stamp: u16, _: impl Fn(usize) -> bool) -> Timestamp {
        Timestamp::from_parts(0, stamp)
    }
}

/// A compile-time feature set of the split driver (see the [module docs](self)).
pub trait Features: 'static {
    /// Receive and transmit time stamps are read from the hardware and widened: what
    /// the clock says ([`StampClock::WIDENS`]; a feature set that sets it otherwise is
    /// refused when its `State` is built).
    const TIMESTAMPS: bool = <Self::Clock as StampClock>::WIDENS;
    /// Whether the traffic statistics count ([`Features::Counter`] is a [`Counter`]).
    const COUNTS: bool;
    /// How the traffic counters are stored.
    type Counter: Tally;
    /// What widening time stamps keeps: [`Extender`] with [`Features::TIMESTAMPS`],
    /// [`NoClock`] without (20 B of state and 4 B per receive ring slot saved).
    type Clock: StampClock;
}

/// Every feature (the default): statistics, time stamps.
#[derive(Debug, Clone, Copy)]
pub enum Full {}

impl Features for Full {
    const COUNTS: bool = true;
    type Counter = Counter;
    type Clock = Extender;
}

/// No traffic statistics, no time stamps: the per-frame path does only the frame's work.
#[derive(Debug, Clone, Copy)]
pub enum Lean {}

impl Features for Lean {
    const COUNTS: bool = false;
    type Counter = NoTally;
    type Clock = NoClock;
}
