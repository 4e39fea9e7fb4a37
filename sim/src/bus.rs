//! The simulated bus: attached nodes, bus time, arbitration, frame attempts, faults, trace.
//!
//! # Time
//!
//! Time is counted in bit times from 0 and only moves when the caller runs the bus. One
//! *event* is either a frame attempt on the wire (SOF to the end of the intermission), an
//! internal frame (no time), or a stretch of idle time. [`Bus::step`] runs one frame event if
//! some node wants to send; [`Bus::step_until`] also lets idle time pass; [`Bus::run_until`],
//! [`Bus::run_for`] and [`Bus::run_until_idle`] loop over them. A test harness services its
//! controllers' interrupts between events:
//!
//! ```ignore
//! while let Some(event) = bus.step_until(deadline) {
//!     driver_a.on_interrupt();
//!     driver_b.on_interrupt();
//! }
//! ```
//!
//! Every node gets [`BusNode::advance`] for every bit time that passes, frames included,
//! in chunks between the moments when the bus tells some node something. What `idle` says
//! depends on the node:
//!
//! - a node taking part in the frame attempt — a transmitter, or a node that
//!   [`BusNode::listens`] at SOF — gets `idle = false` for every bit of the attempt until the
//!   bus has told it the outcome (so `idle = true` never comes between its `poll_tx` and its
//!   `tx_result`);
//! - any other node (bus-off, synchronising, asleep, in initialization) and every node
//!   after it has been told the outcome gets the wire's levels: a chunk with `idle = false`
//!   contains dominant bits and ends on one, a chunk with `idle = true` is all recessive.
//!   So a bus-off node counts the recessive tail of every frame (ACK delimiter and EOF, or
//!   the error delimiter, with the intermission: 11 bits) as one recovery sequence, as
//!   ISO 11898-1 wants, and a transmitter that has just gone bus-off counts its own error
//!   delimiter;
//! - the intermission and idle stretches are `idle = true` for everyone.
//!
//! Within a frame attempt the nodes are told, with [`BusTime`] `{ sof, now }`:
//!
//! - losers of arbitration: [`TxResult::ArbitrationLost`] at the end of the arbitration field;
//! - a transmitter that detects an error: [`TxResult::Error`] right after the bit where it
//!   detected it (its error counter moves then, so a node that goes bus-off counts the
//!   recessive bits of its own error delimiter);
//! - a receiver that detects an error: [`BusNode::rx_error`] after the bit that follows its
//!   error flag (when ISO rule 2, `dominant_after_flag`, is known);
//! - success: [`TxResult::Acked`] then `rx(frame, own = true)` for the transmitter, and
//!   `rx(frame, own = false)` for each receiver, at the end of EOF;
//! - then the 3 intermission bits pass and the event ends.
//!
//! An idle stretch ends at the time the caller asked for, at the earliest
//! [`BusNode::next_wakeup`] of any node, or after [`Bus::set_idle_quantum`] bits.
//!
//! # Arbitration and outcome
//!
//! When the bus is idle every node's [`BusNode::poll_tx`] is asked (in attach order). The
//! smallest [`Priority`](twocan_core::priority::Priority) wins; the other requesters lose
//! arbitration and receive the frame like every node that [`BusNode::listens`]. Nodes with the
//! very same arbitration field all "win" and send together: the wire is the wired-AND of their
//! bits, so the first one to send recessive where another sends dominant detects a bit error
//! (`BitRecessive`); if it is error-active its error flag destroys the frame for all (the
//! others then see a bit error too), if it is error-passive the other frame goes on. Identical
//! frames simply succeed for every sender.
//!
//! The attempt is then played bit by bit (by `sim/src/engine.rs`, whose module comment lists
//! the rules and what is not modelled): each receiver acknowledges if it [`BusNode::acknowledges`] and
//! its CRC matched; a transmitter that sees no acknowledgement (and did not ask for
//! `self_ack`) detects an acknowledge error; a node detecting an error sends an active error
//! flag if it is [`BusNode::error_active`] (and, for a receiver, able to drive the bus, i.e.
//! it acknowledges), which the others see as a bit, stuff or form error; error-passive nodes
//! send passive flags that do not disturb the others. Consequences worth knowing:
//!
//! - a lone error-active transmitter gets `Error(Acknowledge)`; listen-only receivers see its
//!   error flag as a form error in the ACK delimiter and get `rx_error(Form)`, not `rx`;
//! - a lone error-passive transmitter also gets `Error(Acknowledge)`, but its passive flag is
//!   recessive, so listen-only receivers accept the frame (`rx`) — as a listen-only sniffer on
//!   a real bus with no acknowledging node shows the same frame over and over;
//! - the successful transmitter gets `tx_result(Acked)` *and* `rx(frame, own = true)`: a
//!   model that does not receive its own frames (FlexCAN with SRXDIS, bxCAN outside
//!   loop-back) ignores the latter;
//! - a frame whose last EOF bit is hit by another node's error flag is valid for the
//!   receivers but not for the transmitter, which sends it again (the known double reception).
//!
//! # Internal frames
//!
//! A request with `internal: true` (FlexCAN loop-back, bxCAN loop-back + silent) never reaches
//! the wire: it is served before any wire request, the node gets `tx_result(Acked)` and
//! `rx(frame, own = true)` at once, no bus time passes and no other node sees anything. A
//! real controller would take a frame time for it; this simplification keeps the shared
//! time of the other nodes untouched. At most [`MAX_INSTANT_EVENTS`] internal frames are
//! served in a row without time passing; after that they wait until time moves.

use std::boxed::Box;
use std::string::String;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::vec::Vec;

use super::bits::{wire_bits, FrameBits, INTERMISSION_BITS};
use super::engine::{self, PartOutcome, RxSpec, TxSpec};
use super::fast;
use super::inject::{Fault, FaultError, Injector, RandomFaults, Sees};
use super::node::{BusNode, BusTime, ConfinementEvent, TxRequest, TxResult};
use super::stats::{BusStats, NodeStats};
use super::trace::{bits_to_micros, ErrorInfo, NodeOutcome, NodeReport, Trace, TraceRecord};

/// At most this many internal frames are served in a row without bus time passing.
pub const MAX_INSTANT_EVENTS: u32 = 4096;

/// A node's handle on a [`Bus`]: its index in attach order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(usize);

impl NodeId {
    /// The index of the node in attach order (0 for the first node attached).
    pub const fn index(self) -> usize {
        self.0
    }

    #[cfg(test)]
    pub(crate) const fn from_index(index: usize) -> Self {
        NodeId(index)
    }
}

/// One bus event (see the [module docs](self)).
#[derive(Debug, Clone, PartialEq)]
pub enum BusEvent {
    /// Idle time passed, `from..to` in bit times.
    Idle {
        /// Start of the stretch.
        from: u64,
        /// End of the stretch (the current time).
        to: u64,
    },
    /// A frame attempt on the wire, from SOF to the end of its intermission.
    Frame(Box<TraceRecord>),
    /// An internal frame of one node (no time passed).
    Internal(Box<TraceRecord>),
}

impl BusEvent {
    /// The trace record of a frame or internal event.
    pub fn record(&self) -> Option<&TraceRecord> {
        match self {
            BusEvent::Frame(r) | BusEvent::Internal(r) => Some(r),
            BusEvent::Idle { .. } => None,
        }
    }
}

/// Why a bus could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimError {
    /// A bit rate of 0 bit/s.
    ZeroBitRate,
}

impl core::fmt::Display for SimError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SimError::ZeroBitRate => f.write_str("bit rate must be above 0 bit/s"),
        }
    }
}

impl std::error::Error for SimError {}

/// [`Bus::run_until_idle`] reached its bit budget while some node still had work.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StillBusy {
    /// The bus time when it gave up.
    pub now: u64,
}

impl core::fmt::Display for StillBusy {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "the simulated bus was still busy at bit time {} when its budget ran out",
            self.now
        )
    }
}

impl std::error::Error for StillBusy {}

/// A node's transmit request, with the node's index.
type Request = (usize, TxRequest);

/// What the bus tells a node at the end of (or during) a frame attempt.
#[derive(Debug, Clone, Copy)]
enum Notice {
    Lost(twocan_core::frame::Frame),
    Tx(twocan_core::frame::Frame, TxResult),
    Rx,
    RxError(twocan_core::error::LastErrorCode, bool),
    /// The end of the attempt for a transmitter; whether it read a dominant bit during its
    /// passive error flag.
    TxEnd(bool),
    /// A fault-confinement event the outcome does not carry.
    Confinement(ConfinementEvent),
}

/// A wire frame attempt that has started and is not over yet (see [`Bus::run_bits`]).
struct InFlight {
    sof: u64,
    /// Offset from SOF of the end of the last EOF or error delimiter.
    end: u64,
    schedule: Vec<(u64, u8, usize, Notice)>,
    /// The next schedule entry to deliver.
    next: usize,
    /// Offset from SOF up to which every node has been advanced.
    done: u64,
    in_frame: Vec<bool>,
    wire: Vec<bool>,
    record: TraceRecord,
    receivers: Vec<usize>,
    frame: twocan_core::frame::Frame,
}

struct Slot {
    name: String,
    node: Box<dyn BusNode>,
    stats: NodeStats,
}

/// The time of a [`Bus`], readable while the bus is borrowed ([`Bus::clock`]).
#[derive(Clone, Debug, Default)]
pub struct BusClock(Arc<AtomicU64>);

impl BusClock {
    /// The bus time, in bit times (as [`Bus::now`]).
    pub fn now(&self) -> u64 {
        self.0.load(Ordering::Relaxed)
    }
}

/// A deterministic simulated CAN bus (see the [module docs](self)).
pub struct Bus {
    bit_rate: u32,
    now: u64,
    /// [`Bus::now`] for readers that cannot borrow the bus ([`Bus::clock`]).
    clock: BusClock,
    slots: Vec<Slot>,
    trace: Trace,
    tracing: bool,
    injector: Injector,
    stats: BusStats,
    instant_streak: u32,
    idle_quantum: u64,
    in_flight: Option<InFlight>,
    fast_path: bool,
    stats_fast_attempts: u64,
    refused: Vec<(Fault, FaultError)>,
}

impl core::fmt::Debug for Bus {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Bus")
            .field("bit_rate", &self.bit_rate)
            .field("now", &self.now)
            .field(
                "nodes",
                &self
                    .slots
                    .iter()
                    .map(|s| s.name.as_str())
                    .collect::<Vec<_>>(),
            )
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

impl Bus {
    /// An empty bus at `bit_rate` bit/s (used only to convert bit times to microseconds).
    pub fn new(bit_rate: u32) -> Result<Self, SimError> {
        if bit_rate == 0 {
            return Err(SimError::ZeroBitRate);
        }
        Ok(Bus {
            bit_rate,
            now: 0,
            clock: BusClock::default(),
            slots: Vec::new(),
            trace: Trace::new(bit_rate),
            tracing: true,
            injector: Injector::default(),
            stats: BusStats::default(),
            instant_streak: 0,
            idle_quantum: u64::MAX,
            in_flight: None,
            fast_path: true,
            stats_fast_attempts: 0,
            refused: Vec::new(),
        })
    }

    /// Attaches a node. To keep a handle on it, attach a clone of an `Rc<RefCell<_>>`
    /// (which implements [`BusNode`]) or a model type that is itself a shared handle.
    pub fn attach<N: BusNode + 'static>(&mut self, name: &str, node: N) -> NodeId {
        self.attach_boxed(name, Box::new(node))
    }

    /// Attaches an already boxed node.
    pub fn attach_boxed(&mut self, name: &str, node: Box<dyn BusNode>) -> NodeId {
        self.slots.push(Slot {
            name: name.into(),
            node,
            stats: NodeStats::default(),
        });
        NodeId(self.slots.len() - 1)
    }

    /// Number of attached nodes.
    pub fn node_count(&self) -> usize {
        self.slots.len()
    }

    /// The name a node was attached with.
    pub fn node_name(&self, id: NodeId) -> Option<&str> {
        self.slots.get(id.0).map(|s| s.name.as_str())
    }

    /// The bit rate in bit/s.
    pub fn bit_rate(&self) -> u32 {
        self.bit_rate
    }

    /// The current bus time in bit times.
    pub fn now(&self) -> u64 {
        self.now
    }

    /// A handle on [`Bus::now`] that reads it without borrowing the bus: for register
    /// wrappers whose accesses come from inside a bus step (a node's hook), where the
    /// bus is borrowed ([`crate::PollClock`]'s watchdog).
    pub fn clock(&self) -> BusClock {
        self.clock.clone()
    }

    fn set_now(&mut self, now: u64) {
        self.now = now;
        self.clock.0.store(now, Ordering::Relaxed);
    }

    /// The current bus time in microseconds (rounded down).
    pub fn now_micros(&self) -> u64 {
        self.bits_to_micros(self.now)
    }

    /// Microseconds for `bits` bit times (rounded down).
    pub fn bits_to_micros(&self, bits: u64) -> u64 {
        bits_to_micros(bits, self.bit_rate)
    }

    /// Bit times for `micros` microseconds (rounded up, so that waiting that long is enough).
    pub fn micros_to_bits(&self, micros: u64) -> u64 {
        let bits = (u128::from(micros) * u128::from(self.bit_rate)).div_ceil(1_000_000);
        u64::try_from(bits).unwrap_or(u64::MAX)
    }

    /// The trace so far.
    pub fn trace(&self) -> &Trace {
        &self.trace
    }

    /// The trace, to clear it.
    pub fn trace_mut(&mut self) -> &mut Trace {
        &mut self.trace
    }

    /// Turns recording into the trace on or off (on by default). Events are still returned.
    pub fn set_tracing(&mut self, on: bool) {
        self.tracing = on;
    }

    /// Bus totals.
    pub fn stats(&self) -> BusStats {
        BusStats {
            elapsed_bits: self.now,
            ..self.stats
        }
    }

    /// Bus load so far: busy bit times over elapsed bit times.
    pub fn load(&self) -> f64 {
        self.stats().load()
    }

    /// A node's counters.
    pub fn node_stats(&self, id: NodeId) -> Option<NodeStats> {
        self.slots.get(id.0).map(|s| s.stats)
    }

    /// Frame attempts started on the wire so far; the next one gets this number.
    pub fn frames_started(&self) -> u64 {
        self.stats.frames_started
    }

    /// Injects `fault` into wire frame attempt number `seq` (0 = the first SOF on the bus;
    /// retransmissions count as new attempts). A fault that cannot happen is refused:
    /// [`Bus::try_inject`] says so at once; here it is recorded in
    /// [`Bus::refused_faults`] (and, when the frame decides it, in the attempt's
    /// [`TraceRecord::refused`]).
    pub fn inject(&mut self, seq: u64, fault: Fault) {
        if let Err(e) = self.try_inject(seq, fault) {
            self.refused.push((fault, e));
        }
    }

    /// [`Bus::inject`], refusing at once a fault that cannot happen in any frame.
    pub fn try_inject(&mut self, seq: u64, fault: Fault) -> Result<(), FaultError> {
        fault.validate()?;
        self.injector.at_frame(seq, fault);
        Ok(())
    }

    /// Injects `fault` into the next frame attempt on the wire (see [`Bus::inject`]).
    pub fn inject_next(&mut self, fault: Fault) {
        self.inject(self.stats.frames_started, fault);
    }

    /// [`Bus::inject_next`], refusing at once a fault that cannot happen in any frame.
    pub fn try_inject_next(&mut self, fault: Fault) -> Result<(), FaultError> {
        self.try_inject(self.stats.frames_started, fault)
    }

    /// Injects `fault` into the next `count` frame attempts that `node` transmits (see
    /// [`Bus::inject`]).
    pub fn inject_from(&mut self, node: NodeId, count: u32, fault: Fault) {
        if let Err(e) = self.try_inject_from(node, count, fault) {
            self.refused.push((fault, e));
        }
    }

    /// [`Bus::inject_from`], refusing at once a fault that cannot happen in any frame.
    pub fn try_inject_from(
        &mut self,
        node: NodeId,
        count: u32,
        fault: Fault,
    ) -> Result<(), FaultError> {
        fault.validate()?;
        self.injector.on_node(node, count, fault);
        Ok(())
    }

    /// Every fault refused so far, at injection or when its frame showed it cannot happen.
    pub fn refused_faults(&self) -> &[(Fault, FaultError)] {
        &self.refused
    }

    /// Random injection (`None` turns it off). Same seed and same traffic give the same faults.
    pub fn set_random_faults(&mut self, random: Option<RandomFaults>) {
        self.injector.set_random(random.as_ref());
    }

    /// Removes every scheduled and random fault.
    pub fn clear_faults(&mut self) {
        self.injector.clear();
    }

    /// Uses the fast path for attempts that cannot fail (one transmitter, no injected fault,
    /// an acknowledgement: `sim/src/fast.rs`) instead of playing their bits (on by default).
    /// The results are the same either way; turning it off measures the bit-level path.
    pub fn set_fast_path(&mut self, on: bool) {
        self.fast_path = on;
    }

    /// Frame attempts resolved by the fast path so far.
    pub fn fast_path_attempts(&self) -> u64 {
        self.stats_fast_attempts
    }

    /// The longest idle stretch one event may cover (default: unlimited). Setting 1 makes
    /// the bus poll every node after each idle bit, for models that cannot give a
    /// [`BusNode::next_wakeup`] hint.
    pub fn set_idle_quantum(&mut self, bits: u64) {
        self.idle_quantum = bits.max(1);
    }

    /// Runs one frame attempt or internal frame if some node wants to send now; `None` (and
    /// no time passes) if none does. A frame attempt left in flight by [`Bus::run_bits`] is
    /// finished first (that is the event returned).
    pub fn step(&mut self) -> Option<BusEvent> {
        if self.in_flight.is_some() {
            return self.continue_attempt(u64::MAX);
        }
        match self.begin()? {
            Some(event) => Some(event),
            None => self.continue_attempt(u64::MAX),
        }
    }

    /// Starts the next event if some node wants to send: `Some(Some(event))` for an
    /// internal frame (already over), `Some(None)` for a wire attempt now in flight.
    fn begin(&mut self) -> Option<Option<BusEvent>> {
        let (internal, wire) = self.poll();
        if let Some((k, req)) = internal {
            if self.instant_streak < MAX_INSTANT_EVENTS {
                self.instant_streak += 1;
                return Some(Some(self.internal_frame(k, req)));
            }
        }
        if wire.is_empty() {
            return None;
        }
        self.instant_streak = 0;
        self.start_attempt(wire);
        Some(None)
    }

    /// Whether a frame attempt is in flight: [`Bus::run_bits`] stopped inside it.
    pub fn in_frame(&self) -> bool {
        self.in_flight.is_some()
    }

    /// The bit offset from SOF of the attempt in flight (the number of its bits that have
    /// passed), if one is.
    pub fn frame_offset(&self) -> Option<u64> {
        self.in_flight.as_ref().map(|f| self.now - f.sof)
    }

    /// Runs the bus for exactly `bits` bit times, stopping inside a frame attempt if the
    /// time falls there (the other run methods never cut a frame). Software can then
    /// access its controllers' registers while the frame is on the wire — between the
    /// transmit request and the end of the frame, or between a read and a write-back — and
    /// continue with another `run_bits` or any other run method. Every node has been
    /// advanced to [`Bus::now`] and told [`BusNode::paused_in_frame`] the wire's level.
    /// Returns the events that ended in the span (a frame cut by the end of the span is
    /// returned by the call that finishes it).
    pub fn run_bits(&mut self, bits: u64) -> Vec<BusEvent> {
        let until = self.now.saturating_add(bits);
        let mut events = Vec::new();
        loop {
            if self.in_flight.is_some() {
                match self.continue_attempt(until) {
                    Some(event) => events.push(event),
                    None => break,
                }
                continue;
            }
            if self.now >= until {
                break;
            }
            match self.begin() {
                Some(Some(event)) => events.push(event),
                Some(None) => {}
                None => {
                    let mut to = until.min(self.now.saturating_add(self.idle_quantum));
                    if let Some(w) = self.next_wakeup() {
                        to = to.min(w);
                    }
                    events.push(self.idle_to(to));
                }
            }
        }
        events
    }

    /// Runs one event if the bus time is before `until`: a frame if some node wants to send
    /// (it may end after `until`: frames are never cut), otherwise idle time up to `until`,
    /// the next node wake-up or the idle quantum, whichever comes first. `None` once
    /// `now() >= until`.
    pub fn step_until(&mut self, until: u64) -> Option<BusEvent> {
        if self.now >= until {
            return None;
        }
        if let Some(event) = self.step() {
            return Some(event);
        }
        let mut to = until.min(self.now.saturating_add(self.idle_quantum));
        if let Some(w) = self.next_wakeup() {
            to = to.min(w);
        }
        Some(self.idle_to(to))
    }

    /// Runs events until the bus time reaches `until` (or passes it by the end of a frame).
    pub fn run_until(&mut self, until: u64) -> Vec<BusEvent> {
        let mut events = Vec::new();
        while let Some(event) = self.step_until(until) {
            events.push(event);
        }
        events
    }

    /// Runs events for `bits` bit times from now (see [`Bus::run_until`]).
    pub fn run_for(&mut self, bits: u64) -> Vec<BusEvent> {
        self.run_until(self.now.saturating_add(bits))
    }

    /// Runs until no node wants to send and none has a pending [`BusNode::next_wakeup`],
    /// letting idle time pass only up to such wake-ups. Gives up with [`StillBusy`] when that
    /// would take more than `max_bits` bit times (a lone transmitter nobody acknowledges
    /// retries forever). Returns the bus time when it became idle.
    pub fn run_until_idle(&mut self, max_bits: u64) -> Result<u64, StillBusy> {
        let deadline = self.now.saturating_add(max_bits);
        loop {
            if self.step().is_some() {
                if self.now > deadline {
                    return Err(StillBusy { now: self.now });
                }
                continue;
            }
            match self.next_wakeup() {
                None => return Ok(self.now),
                Some(w) if w <= deadline => {
                    self.idle_to(w);
                }
                Some(_) => return Err(StillBusy { now: self.now }),
            }
        }
    }

    fn next_wakeup(&self) -> Option<u64> {
        let now = self.now;
        self.slots
            .iter()
            .filter_map(|s| s.node.next_wakeup(now))
            .filter(|&w| w > now)
            .min()
    }

    fn poll(&mut self) -> (Option<Request>, Vec<Request>) {
        let now = self.now;
        let mut internal = None;
        let mut wire = Vec::new();
        for (k, slot) in self.slots.iter_mut().enumerate() {
            if let Some(req) = slot.node.poll_tx(now) {
                if req.internal {
                    if internal.is_none() {
                        internal = Some((k, req));
                    }
                } else {
                    wire.push((k, req));
                }
            }
        }
        (internal, wire)
    }

    fn advance_all(&mut self, bits: u64, idle: bool) {
        if bits == 0 {
            return;
        }
        self.set_now(self.now.saturating_add(bits));
        let now = self.now;
        for slot in &mut self.slots {
            slot.node.advance(bits, idle, now);
        }
    }

    /// Advances every node over wire bits `from..to` of the attempt that started at `sof`
    /// (offsets from SOF). A node still taking part in the frame (`in_frame`) gets one chunk
    /// with `idle = false`; any other node gets the wire's levels: the part up to the last
    /// dominant bit with `idle = false`, the recessive rest with `idle = true`.
    fn advance_span(&mut self, wire: &[bool], sof: u64, from: u64, to: u64, in_frame: &[bool]) {
        if to <= from {
            return;
        }
        let last_dominant = (from..to)
            .rev()
            .find(|&i| !wire.get(i as usize).copied().unwrap_or(true));
        for (k, slot) in self.slots.iter_mut().enumerate() {
            let node = &mut slot.node;
            match last_dominant {
                _ if in_frame.get(k).copied().unwrap_or(false) => {
                    node.advance(to - from, false, sof + to)
                }
                Some(d) => {
                    node.advance(d + 1 - from, false, sof + d + 1);
                    if to > d + 1 {
                        node.advance(to - (d + 1), true, sof + to);
                    }
                }
                None => node.advance(to - from, true, sof + to),
            }
        }
        self.set_now(sof + to);
    }

    fn idle_to(&mut self, to: u64) -> BusEvent {
        let from = self.now;
        self.advance_all(to.saturating_sub(from), true);
        self.instant_streak = 0;
        BusEvent::Idle { from, to: self.now }
    }

    fn record(&mut self, record: TraceRecord) -> Box<TraceRecord> {
        if self.tracing {
            self.trace.push(record.clone());
        }
        Box::new(record)
    }

    fn internal_frame(&mut self, k: usize, req: TxRequest) -> BusEvent {
        let time = BusTime {
            sof: self.now,
            now: self.now,
        };
        let slot = &mut self.slots[k];
        slot.node.tx_result(&req.frame, TxResult::Acked, time);
        slot.node.rx(&req.frame, true, time);
        slot.stats.sent_internal += 1;
        self.stats.internal_frames += 1;
        let id = NodeId(k);
        let record = TraceRecord {
            seq: self.stats.frames_started,
            internal: true,
            sof: self.now,
            end: self.now,
            frame: req.frame,
            bits: super::bits::frame_bits(&req.frame),
            transmitters: vec![id],
            arbitration_losers: Vec::new(),
            faults: Vec::new(),
            refused: Vec::new(),
            first_error: None,
            acked: true,
            delivered: false,
            reports: vec![NodeReport {
                node: id,
                outcome: NodeOutcome::Transmitted(TxResult::Acked),
                error_bit: None,
            }],
        };
        BusEvent::Internal(self.record(record))
    }

    /// Starts a wire frame attempt: arbitration, the attempt played bit by bit, and the
    /// schedule of what each node is told when. Nothing is delivered yet: the attempt is
    /// in flight until [`Bus::continue_attempt`] has reached its end.
    fn start_attempt(&mut self, requests: Vec<Request>) {
        let sof = self.now;
        let seq = self.stats.frames_started;
        self.stats.frames_started += 1;

        // Arbitration: the smallest key wins; equal keys send together.
        let best = requests.iter().map(|(_, r)| r.frame.priority()).min();
        let (contenders, losers): (Vec<_>, Vec<_>) = requests
            .into_iter()
            .partition(|(_, r)| Some(r.frame.priority()) == best);
        let receivers: Vec<usize> = (0..self.slots.len())
            .filter(|k| !contenders.iter().any(|(c, _)| c == k))
            .filter(|&k| self.slots[k].node.listens())
            .collect();
        let mut streams: Vec<(Vec<bool>, FrameBits)> = contenders
            .iter()
            .map(|(_, r)| wire_bits(&r.frame))
            .collect();
        let reference = (0..streams.len())
            .min_by(|&a, &b| streams[a].0.cmp(&streams[b].0))
            .unwrap_or(0);
        let ref_bits = streams[reference].1;

        let tx_ids: Vec<NodeId> = contenders.iter().map(|(k, _)| NodeId(*k)).collect();
        let mut faults = if self.injector.is_idle() {
            Vec::new()
        } else {
            let rx_ids: Vec<NodeId> = receivers.iter().map(|&k| NodeId(k)).collect();
            self.injector.faults_for(seq, &tx_ids, &rx_ids, &ref_bits)
        };
        let mut refused = Vec::new();
        faults.retain(|f| match f.check_layout(&ref_bits, &streams[reference].0) {
            Ok(()) => true,
            Err(e) => {
                refused.push((*f, e));
                false
            }
        });
        self.refused.extend_from_slice(&refused);
        let wire_faults = engine::WireFaults {
            stuck: faults.iter().find_map(Fault::stuck_range),
            delimiter: faults.iter().find_map(Fault::bus_delimiter),
            intermission: faults.iter().find_map(Fault::bus_intermission),
        };

        // The fast path needs only whether someone acknowledges: no per-node specs.
        let fast = if self.fast_path && faults.is_empty() && contenders.len() == 1 {
            let any_ack = receivers.iter().any(|&k| self.slots[k].node.acknowledges());
            fast::decide(contenders[0].1.self_ack, any_ack)
        } else {
            None
        };
        let res = match fast {
            Some(acked) => {
                self.stats_fast_attempts += 1;
                let stream = core::mem::take(&mut streams[0].0);
                fast::resolve(streams[0].1, acked, receivers.len(), stream)
            }
            None => {
                let txs: Vec<TxSpec<'_>> = contenders
                    .iter()
                    .zip(&streams)
                    .map(|((k, r), (stream, bits))| TxSpec {
                        stream,
                        bits: *bits,
                        self_ack: r.self_ack,
                        active: self.slots[*k].node.error_active(),
                        faults: faults
                            .iter()
                            .filter_map(|f| f.tx_part(NodeId(*k), bits))
                            .collect(),
                    })
                    .collect();
                let rxs: Vec<RxSpec> = receivers
                    .iter()
                    .map(|&k| {
                        let node = &self.slots[k].node;
                        let acks = node.acknowledges();
                        RxSpec {
                            acks,
                            active: acks && node.error_active(),
                            faults: faults
                                .iter()
                                .filter_map(|f| f.rx_part(NodeId(k), &ref_bits))
                                .collect(),
                        }
                    })
                    .collect();
                engine::resolve_with(&txs, &rxs, wire_faults)
            }
        };

        let frame = contenders[res.reference].1.frame;
        let bits = streams[res.reference].1;
        let end = u64::from(res.end).max(u64::from(bits.arbitration_end));

        // Who is told what, when (bit offsets from SOF): losers at the end of arbitration;
        // a transmitter's error when it detects it (its counters change then, so a node that
        // goes bus-off counts the recessive bits of its error delimiter); a receiver's error
        // after the bit that follows its error flag (when rule 2 is known); successes at the
        // end of the node's EOF; the end of the attempt to each transmitter.
        let mut schedule: Vec<(u64, u8, usize, Notice)> = Vec::new();
        let arb = u64::from(bits.arbitration_end);
        for (k, r) in &losers {
            schedule.push((arb, 0, *k, Notice::Lost(r.frame)));
        }
        for (n, ((k, r), outcome)) in contenders.iter().zip(&res.tx).enumerate() {
            let (at, result) = match *outcome {
                PartOutcome::Ok { done } => (u64::from(done), TxResult::Acked),
                PartOutcome::Error { code, at, .. } => (u64::from(at) + 1, TxResult::Error(code)),
            };
            schedule.push((at.min(end), 1, *k, Notice::Tx(r.frame, result)));
            let mut flag = false;
            if let PartOutcome::Error {
                dominant_in_passive_flag,
                arbitration_stuff_exception,
                ..
            } = *outcome
            {
                flag = dominant_in_passive_flag;
                if arbitration_stuff_exception {
                    let event = ConfinementEvent::ArbitrationStuffException;
                    schedule.push((at.min(end), 0, *k, Notice::Confinement(event)));
                }
            }
            let penalties = res.tx_penalties.get(n).copied().unwrap_or(0);
            if penalties > 0 {
                let event = ConfinementEvent::FlagPenalties {
                    transmitter: true,
                    count: penalties,
                };
                schedule.push((end, 3, *k, Notice::Confinement(event)));
            }
            schedule.push((end, 3, *k, Notice::TxEnd(flag)));
        }
        for (n, (&k, outcome)) in receivers.iter().zip(&res.rx).enumerate() {
            let (at, notice) = match *outcome {
                PartOutcome::Ok { done } => (u64::from(done), Notice::Rx),
                PartOutcome::Error {
                    code,
                    at,
                    dominant_after_flag,
                    ..
                } => (
                    u64::from(at) + 8,
                    Notice::RxError(code, dominant_after_flag),
                ),
            };
            schedule.push((at.min(end), 2, k, notice));
            // Errors after its first one (a form error in a delimiter): each counts as a
            // receive error (rule 1, rule 2 for its own flag), told after its flag.
            for &(code, at, dominant_after_flag) in res.rx_more_errors.get(n).into_iter().flatten()
            {
                let when = (u64::from(at) + 8).min(end);
                schedule.push((when, 2, k, Notice::RxError(code, dominant_after_flag)));
            }
            let penalties = res.rx_penalties.get(n).copied().unwrap_or(0);
            if penalties > 0 {
                let event = ConfinementEvent::FlagPenalties {
                    transmitter: false,
                    count: penalties,
                };
                schedule.push((end, 3, k, Notice::Confinement(event)));
            }
        }
        schedule.sort_by_key(|&(at, order, k, _)| (at, order, k));

        // Transmitters and receivers take part in the frame until they are told its outcome.
        let mut in_frame = vec![false; self.slots.len()];
        for &k in contenders.iter().map(|(k, _)| k).chain(&receivers) {
            in_frame[k] = true;
        }

        let mut reports = Vec::with_capacity(contenders.len() + receivers.len());
        let mut first_error: Option<ErrorInfo> = None;
        let mut note_error = |node: NodeId, transmitter: bool, code, bit: u32| {
            if first_error.is_none_or(|e| bit < e.bit) {
                first_error = Some(ErrorInfo {
                    node,
                    transmitter,
                    code,
                    bit,
                });
            }
        };
        for ((k, _), outcome) in contenders.iter().zip(&res.tx) {
            let (outcome, error_bit) = match *outcome {
                PartOutcome::Ok { .. } => (NodeOutcome::Transmitted(TxResult::Acked), None),
                PartOutcome::Error { code, at, .. } => {
                    note_error(NodeId(*k), true, code, at);
                    (NodeOutcome::Transmitted(TxResult::Error(code)), Some(at))
                }
            };
            reports.push(NodeReport {
                node: NodeId(*k),
                outcome,
                error_bit,
            });
        }
        for (&k, outcome) in receivers.iter().zip(&res.rx) {
            let (outcome, error_bit) = match *outcome {
                PartOutcome::Ok { .. } => (NodeOutcome::Received, None),
                PartOutcome::Error {
                    code,
                    at,
                    dominant_after_flag,
                    ..
                } => {
                    note_error(NodeId(k), false, code, at);
                    (
                        NodeOutcome::ReceiveError {
                            code,
                            dominant_after_flag,
                        },
                        Some(at),
                    )
                }
            };
            reports.push(NodeReport {
                node: NodeId(k),
                outcome,
                error_bit,
            });
        }

        // A delimiter or intermission fault whose bit never came is refused, not moved.
        for m in &res.missed {
            let (who, aim) = match *m {
                engine::Missed::Tx(n, a) => (Sees::Node(NodeId(contenders[n].0)), a),
                engine::Missed::Rx(n, a) => (Sees::Node(NodeId(receivers[n])), a),
                engine::Missed::Bus(a) => (Sees::Bus, a),
            };
            let (fault, error) = match aim {
                engine::Aim::Delimiter(bit) => (
                    Fault::DelimiterBit { who, bit },
                    FaultError::DelimiterNotReached(bit),
                ),
                engine::Aim::Intermission(bit) => (
                    Fault::IntermissionBit { who, bit },
                    FaultError::IntermissionNotReached(bit),
                ),
            };
            if let Some(pos) = faults.iter().position(|f| *f == fault) {
                faults.remove(pos);
                refused.push((fault, error));
                self.refused.push((fault, error));
            }
        }

        let record = TraceRecord {
            seq,
            internal: false,
            sof,
            end: sof + end + u64::from(INTERMISSION_BITS),
            frame,
            bits,
            transmitters: tx_ids,
            arbitration_losers: losers.iter().map(|(k, _)| NodeId(*k)).collect(),
            faults,
            refused,
            first_error,
            acked: res.acked,
            delivered: res.observer_ok,
            reports,
        };

        // Start of frame: every requester starts as a transmitter, every other listening
        // node as a receiver.
        let time = BusTime { sof, now: sof };
        for (k, _) in contenders.iter().chain(&losers) {
            self.slots[*k].node.attempt_started(true, time);
        }
        for &k in &receivers {
            if !losers.iter().any(|(l, _)| *l == k) {
                self.slots[k].node.attempt_started(false, time);
            }
        }

        self.in_flight = Some(InFlight {
            sof,
            end,
            schedule,
            next: 0,
            done: 0,
            in_frame,
            wire: res.wire,
            record,
            receivers,
            frame,
        });
    }

    /// Plays the attempt in flight up to bus time `until` (at most to the end of its
    /// intermission), delivering what is due. Returns its event once it is over; `None`
    /// while it is still in flight (or if there is none).
    fn continue_attempt(&mut self, until: u64) -> Option<BusEvent> {
        let mut f = self.in_flight.take()?;
        let limit = until.saturating_sub(f.sof);
        while let Some(&(at, _, k, notice)) = f.schedule.get(f.next) {
            if at > limit {
                break;
            }
            f.next += 1;
            self.advance_span(&f.wire, f.sof, f.done, at, &f.in_frame);
            f.done = f.done.max(at);
            self.set_now(f.sof + f.done);
            let time = BusTime {
                sof: f.sof,
                now: self.now,
            };
            let slot = &mut self.slots[k];
            // A loser is told again as a receiver (unless it does not listen).
            f.in_frame[k] = matches!(notice, Notice::Lost(_)) && f.receivers.contains(&k);
            match notice {
                Notice::Lost(fr) => {
                    slot.node.tx_result(&fr, TxResult::ArbitrationLost, time);
                    slot.stats.arbitration_lost += 1;
                }
                Notice::Tx(fr, result) => {
                    slot.node.tx_result(&fr, result, time);
                    if result == TxResult::Acked {
                        slot.node.rx(&fr, true, time);
                        slot.stats.sent += 1;
                    } else {
                        slot.stats.tx_errors += 1;
                    }
                }
                Notice::Rx => {
                    slot.node.rx(&f.frame, false, time);
                    slot.stats.received += 1;
                }
                Notice::RxError(code, dominant_after_flag) => {
                    slot.node.rx_error(code, dominant_after_flag, time);
                    slot.stats.rx_errors += 1;
                }
                Notice::TxEnd(flag) => slot.node.tx_attempt_end(flag, time),
                Notice::Confinement(event) => slot.node.confinement_event(event, time),
            }
        }
        if limit < f.end {
            self.advance_span(&f.wire, f.sof, f.done, limit, &f.in_frame);
            f.done = f.done.max(limit);
            self.set_now(f.sof + f.done);
            let recessive = f
                .done
                .checked_sub(1)
                .and_then(|i| f.wire.get(i as usize).copied())
                .unwrap_or(true);
            let now = self.now;
            for slot in &mut self.slots {
                slot.node.paused_in_frame(recessive, now);
            }
            self.in_flight = Some(f);
            return None;
        }
        self.advance_span(&f.wire, f.sof, f.done, f.end, &f.in_frame);
        f.done = f.done.max(f.end);
        self.set_now(f.sof + f.done);
        let total = f.end + u64::from(INTERMISSION_BITS);
        let to = limit.min(total);
        if to > f.done {
            self.advance_all(to - f.done, true);
            f.done = to;
        }
        if f.done < total {
            self.in_flight = Some(f);
            return None;
        }
        self.stats.busy_bits += self.now - f.sof;
        if f.record.first_error.is_some() {
            self.stats.frames_with_errors += 1;
        } else {
            self.stats.frames_error_free += 1;
        }
        Some(BusEvent::Frame(self.record(f.record)))
    }
}
