//! Full load: minimum-length frames back to back from a plain node into one controller,
//! whose interrupt is serviced after a random latency.
//!
//! # How the interrupt latency is simulated
//!
//! The node under test is attached to the bus behind a [`Hooked`] wrapper that sees every
//! frame the bus hands to the model. When a frame makes the model raise its receive
//! interrupt, a latency is drawn (seeded [`XorShift64`], uniform in `0..=max_latency`):
//! the interrupt handler (`Driver::on_interrupt`) "runs" at `due = arrival + latency`.
//! The wrapper runs it just before the first later frame reaches the model (frames reach
//! it at the end of their EOF, so a handler due at that very bit time goes first), or at
//! the end of the run: the handler sees exactly the frames a handler running at `due`
//! would see, as if it took no time.
//!
//! # What is checked, independently of the drivers
//!
//! Between two runs of the handler the model is offered `n` frames; the hardware keeps
//! `min(n, depth)` of them and loses the rest, which ones by the FIFO's overrun rule
//! ([`OverrunPolicy`]). The runner predicts from that alone which frames the driver must
//! deliver, in which order, how many the model must count as lost, and in how many
//! handler runs the driver must see an overrun (the hardware flags an overrun, it does
//! not count lost frames). Budget: a FIFO of `depth` frames absorbs a latency of
//! `depth` minimum frame times (the `depth + 1`-th frame cannot arrive earlier).

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use twocan_core::{Frame, LastErrorCode};
use twocan_host::Harness;
use twocan_sim::{BusNode, BusTime, SimNode, TxRequest, TxResult};

use crate::backend::{Backend, Dut, NodeOptions, OverrunPolicy};
use crate::rng::XorShift64;

/// Bit times of the shortest classical CAN frame with its intermission: standard
/// identifier, DLC 0, no stuff bit. SOF 1 + identifier 11 + RTR 1 + IDE 1 + r0 1 + DLC 4
/// + CRC 15 + CRC delimiter 1 + ACK slot 1 + ACK delimiter 1 + EOF 7 + intermission 3
///   (ISO 11898-1).
pub const MIN_FRAME_BITS: u64 = 47;

/// The full-load bit rate.
pub const FULL_LOAD_BIT_RATE: u32 = 1_000_000;

/// The `k`-th frame of the load: standard identifier `k mod 2048`, DLC 0.
pub fn load_frame(k: u64) -> Frame {
    Frame::standard((k % 0x800) as u16, &[]).expect("11-bit identifier")
}

/// The latency budget of a FIFO of `depth` frames, in bit times.
pub const fn budget_bits(depth: usize) -> u64 {
    depth as u64 * MIN_FRAME_BITS
}

/// What a full-load run gave.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LoadReport {
    /// Frames the sender got acknowledged (the bus's count).
    pub sent: u64,
    /// Frames the bus handed to the model.
    pub arrived: u64,
    /// Frames the driver delivered through `receive`.
    pub received: u64,
    /// Frames the model counts as lost in its FIFOs.
    pub hw_lost: u64,
    /// Frames lost according to the FIFO depth and the handler times.
    pub predicted_lost: u64,
    /// Overruns the driver counted (`ErrorStatistics::hardware_overruns`).
    pub overrun_events: u64,
    /// Handler runs that had to find an overrun.
    pub predicted_overrun_events: u64,
    /// Frames lost in the driver's receive ring.
    pub ring_overflows: u64,
    /// Handler runs.
    pub isr_runs: u64,
    /// Largest latency drawn, bit times.
    pub max_latency_drawn: u64,
    /// Most frames offered to the model between two handler runs.
    pub max_interval_arrivals: u64,
    /// Frames delivered that differ from the prediction (identity or order), and frames
    /// that reached the model out of send order.
    pub mismatches: u64,
    /// The first mismatch, described.
    pub first_mismatch: Option<String>,
    /// Bus time of the run, bit times.
    pub bus_bits: u64,
    /// Wall-clock time of the run.
    pub wall: Duration,
}

struct Ctx<N> {
    node: Option<N>,
    rng: XorShift64,
    max_latency: u64,
    depth: usize,
    policy: OverrunPolicy,
    due: Option<u64>,
    interval: Vec<Frame>,
    next_seq: u64,
    report: LoadReport,
}

impl<N: Dut> Ctx<N> {
    fn mismatch(&mut self, what: String) {
        self.report.mismatches += 1;
        if self.report.first_mismatch.is_none() {
            self.report.first_mismatch = Some(what);
        }
    }

    /// A frame is about to reach the model at bit time `now`: a handler due by then runs.
    fn before_arrival(&mut self, now: u64) {
        if self.due.is_some_and(|d| d <= now) {
            self.isr();
        }
    }

    fn after_arrival(&mut self, frame: &Frame, now: u64) {
        self.report.arrived += 1;
        let expected = load_frame(self.next_seq);
        if *frame != expected {
            self.mismatch(format!(
                "arrival {}: {frame:?}, sent {expected:?}",
                self.next_seq
            ));
        }
        self.next_seq += 1;
        self.interval.push(*frame);
        let pending = self.node.as_ref().is_some_and(|n| n.irq_pending());
        if self.due.is_none() && pending {
            let latency = self.rng.up_to(self.max_latency);
            self.report.max_latency_drawn = self.report.max_latency_drawn.max(latency);
            self.due = Some(now + latency);
        }
    }

    /// The interrupt handler, then the application draining the receive ring; checked
    /// against the prediction for the frames offered since the last run.
    fn isr(&mut self) {
        self.due = None;
        self.report.isr_runs += 1;
        let Some(node) = self.node.as_mut() else {
            return;
        };
        node.driver().on_interrupt();
        let got: Vec<Frame> = std::iter::from_fn(|| node.driver().receive().ok())
            .map(|rx| rx.frame)
            .collect();
        let n = self.interval.len();
        let d = self.depth;
        let kept: Vec<Frame> = if n <= d {
            self.interval.clone()
        } else {
            match self.policy {
                OverrunPolicy::DiscardNew => self.interval[..d].to_vec(),
                OverrunPolicy::OverwriteNewest => {
                    let mut v = self.interval[..d - 1].to_vec();
                    v.push(self.interval[n - 1]);
                    v
                }
            }
        };
        let lost = n.saturating_sub(d) as u64;
        self.report.predicted_lost += lost;
        if lost > 0 {
            self.report.predicted_overrun_events += 1;
        }
        self.report.max_interval_arrivals = self.report.max_interval_arrivals.max(n as u64);
        self.report.received += got.len() as u64;
        if got != kept {
            let at = self.report.isr_runs;
            self.mismatch(format!("handler run {at}: got {got:?}, expected {kept:?}"));
        }
        self.interval.clear();
    }
}

/// The model of the node under test, behind a wrapper that runs the interrupt handler at
/// its due time (see the [module docs](self)).
pub struct Hooked<N> {
    inner: Box<dyn BusNode>,
    ctx: Rc<RefCell<Ctx<N>>>,
}

impl<N: Dut> BusNode for Hooked<N> {
    fn poll_tx(&mut self, now: u64) -> Option<TxRequest> {
        self.inner.poll_tx(now)
    }
    fn acknowledges(&self) -> bool {
        self.inner.acknowledges()
    }
    fn listens(&self) -> bool {
        self.inner.listens()
    }
    fn error_active(&self) -> bool {
        self.inner.error_active()
    }
    fn tx_result(&mut self, frame: &Frame, result: TxResult, time: BusTime) {
        self.inner.tx_result(frame, result, time)
    }
    fn rx(&mut self, frame: &Frame, own: bool, time: BusTime) {
        if own {
            return self.inner.rx(frame, own, time);
        }
        self.ctx.borrow_mut().before_arrival(time.now);
        self.inner.rx(frame, own, time);
        self.ctx.borrow_mut().after_arrival(frame, time.now);
    }
    fn rx_error(&mut self, code: LastErrorCode, dominant_after_flag: bool, time: BusTime) {
        self.inner.rx_error(code, dominant_after_flag, time)
    }
    fn advance(&mut self, bits: u64, idle: bool, now: u64) {
        self.inner.advance(bits, idle, now)
    }
    fn next_wakeup(&self, now: u64) -> Option<u64> {
        self.inner.next_wakeup(now)
    }
}

/// Sends `frames` minimum-length frames back to back at 1 Mbit/s from a plain node into a
/// pass-all node of backend `B`, its interrupt serviced after a latency uniform in
/// `0..=max_latency` bit times (seeded by `seed`).
pub fn full_load<B: Backend>(frames: u64, max_latency: u64, seed: u64) -> LoadReport {
    let start = Instant::now();
    let mut h = Harness::new(FULL_LOAD_BIT_RATE).expect("bus");
    h.bus().borrow_mut().set_tracing(false);
    let ctx = Rc::new(RefCell::new(Ctx::<B::Node> {
        node: None,
        rng: XorShift64::new(seed),
        max_latency,
        depth: B::RX_FIFO_DEPTH,
        policy: B::OVERRUN,
        due: None,
        interval: Vec::new(),
        next_seq: 0,
        report: LoadReport::default(),
    }));
    let hook = ctx.clone();
    let node = B::attach_via(&mut h, &NodeOptions::pass_all(), move |bus, name, inner| {
        bus.attach(name, Hooked { inner, ctx: hook })
    })
    .expect("node");
    ctx.borrow_mut().node = Some(node);
    let sender = SimNode::new().shared();
    let sender_id = h.bus().borrow_mut().attach("sender", sender.clone());
    h.bus().borrow_mut().run_for(100);

    let mut queued = 0u64;
    loop {
        {
            let mut s = sender.borrow_mut();
            while s.pending() < 16 && queued < frames {
                s.send(load_frame(queued));
                queued += 1;
            }
        }
        if h.bus().borrow_mut().step().is_none() {
            break;
        }
    }
    // Let every due handler run.
    h.bus().borrow_mut().run_for(max_latency + 100);
    let mut c = ctx.borrow_mut();
    if c.due.is_some() {
        c.isr();
    }
    let bus = h.bus().borrow();
    let node = c.node.take().expect("node");
    let mut report = std::mem::take(&mut c.report);
    report.sent = bus.node_stats(sender_id).map_or(0, |s| s.sent);
    report.hw_lost = node.hw_lost();
    report.overrun_events = u64::from(node.driver_ref().error_stats().hardware_overruns);
    report.ring_overflows = u64::from(node.driver_ref().traffic().rx_ring_overflows);
    report.bus_bits = bus.now();
    report.wall = start.elapsed();
    report
}

impl LoadReport {
    /// Asserts the accounting rules every run must meet, with or without losses: every
    /// frame sent reached the model, and was either delivered in the predicted order or
    /// counted lost by the model, exactly as predicted; the driver saw an overrun in
    /// exactly the handler runs that followed one.
    pub fn assert_accounted(&self, what: &str) {
        assert_eq!(self.mismatches, 0, "{what}: {:?}", self.first_mismatch);
        assert_eq!(self.arrived, self.sent, "{what}: frames reaching the model");
        assert_eq!(
            self.sent,
            self.received + self.hw_lost + self.ring_overflows,
            "{what}: sent = received + lost"
        );
        assert_eq!(
            self.hw_lost, self.predicted_lost,
            "{what}: model's lost count"
        );
        assert_eq!(self.ring_overflows, 0, "{what}: receive ring");
        assert_eq!(
            self.overrun_events, self.predicted_overrun_events,
            "{what}: overruns the driver saw"
        );
    }
}
