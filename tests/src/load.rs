//! Full load: minimum-length frames back to back from a plain node into one controller,
//! whose interrupt is serviced after a random latency.
//!
//! # How the interrupt latency is simulated
//!
//! The node under test is attached to the bus behind a [`Hooked`] wrapper that sees every
//! frame the bus hands to the model. When a frame makes the model raise its receive
//! interrupt, a latency is drawn (seeded [`XorShift64`], uniform in `0..=max_latency`):
//! the interrupt handler "runs" at `due = arrival + latency` (`Driver::on_interrupt` for
//! the unsplit driver; for a lean split one, [`crate::lean`], the handlers of the raised
//! lines as the chip's vectors run them, the receive handler `Rx0Irq::on_interrupt`
//! among them), and the application then drains the receive ring ([`Loaded`]).
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
use twocan_sim::{Bus, BusNode, BusTime, NodeId, SimNode, TxRequest, TxResult};

use crate::backend::{Backend, BxCanBackend, Dut, FlexCanBackend, NodeOptions, OverrunPolicy};
use crate::backend::{Teensy36Can0, Teensy41Can1};
use crate::lean::{
    attach_bx_lean, attach_flex_lean, FlexLeanModelHw, LeanBxNode, LeanFlexNode, LeanFlexPart,
    LeanNode,
};
use crate::rng::XorShift64;
use twocan_flexcan::layout::Layout;
use twocan_flexcan::model::FlexCanModel;

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

/// What the runner needs from the node under test: its interrupt request, its
/// interrupt side, its thread side, and the counts of what it lost.
pub trait Loaded: 'static {
    /// Whether the model raises an interrupt line the driver services.
    fn irq_pending(&self) -> bool;
    /// The interrupt side: the handlers of the raised lines (as the chip's vectors run
    /// them).
    fn service(&mut self);
    /// The thread side: the next frame of the receive ring.
    fn receive(&mut self) -> Option<Frame>;
    /// Frames lost in the hardware receive FIFOs, as the model counts them.
    fn hw_lost(&self) -> u64;
    /// Overruns the driver counted (`ErrorStatistics::hardware_overruns`).
    fn overrun_events(&self) -> u64;
    /// Frames the driver lost because its receive ring was full.
    fn ring_overflows(&self) -> u64;
    /// Frames the driver's traffic statistics count as received (0 without
    /// statistics).
    fn counted_received(&self) -> u64;
}

/// A node the full-load runner brings up: the unsplit driver of every [`Backend`]
/// (every feature), and the lean split driver of each backend ([`LeanBxCan`],
/// [`LeanFlexCan`], [`LeanRt1062`]).
pub trait LoadInstance {
    /// The node.
    type Node: Loaded;
    /// For messages.
    const NAME: &'static str;
    /// Frames its receive FIFO holds.
    const RX_FIFO_DEPTH: usize;
    /// What its receive FIFO does when full.
    const OVERRUN: OverrunPolicy;
    /// Whether its driver counts traffic (statistics on).
    const COUNTS: bool;
    /// Brings the node up on `h`'s bus (at [`FULL_LOAD_BIT_RATE`]), receiving every
    /// frame; `attach` puts the model on the bus.
    fn attach_via(
        h: &mut Harness,
        attach: impl FnOnce(&mut Bus, &str, Box<dyn BusNode>) -> NodeId,
    ) -> Self::Node;
}

/// The unsplit driver (`Driver::on_interrupt`, `Driver::receive`), every feature.
impl<N: Dut + 'static> Loaded for N {
    fn irq_pending(&self) -> bool {
        Dut::irq_pending(self)
    }
    fn service(&mut self) {
        self.driver().on_interrupt();
    }
    fn receive(&mut self) -> Option<Frame> {
        self.driver().receive().ok().map(|rx| rx.frame)
    }
    fn hw_lost(&self) -> u64 {
        Dut::hw_lost(self)
    }
    fn overrun_events(&self) -> u64 {
        u64::from(self.driver_ref().error_stats().hardware_overruns)
    }
    fn ring_overflows(&self) -> u64 {
        u64::from(self.driver_ref().traffic().rx_ring_overflows)
    }
    fn counted_received(&self) -> u64 {
        u64::from(self.driver_ref().traffic().received)
    }
}

impl<B: Backend> LoadInstance for B {
    type Node = B::Node;
    const NAME: &'static str = B::NAME;
    const RX_FIFO_DEPTH: usize = B::RX_FIFO_DEPTH;
    const OVERRUN: OverrunPolicy = B::OVERRUN;
    const COUNTS: bool = true;
    fn attach_via(
        h: &mut Harness,
        attach: impl FnOnce(&mut Bus, &str, Box<dyn BusNode>) -> NodeId,
    ) -> Self::Node {
        B::attach_via(h, &NodeOptions::pass_all(), attach).expect("node")
    }
}

/// The lean split driver on bxCAN ([`crate::lean`]): the RX0 line runs the receive
/// handler (`Rx0Irq`), the receive half drains the ring.
pub struct LeanBxCan;

impl Loaded for LeanBxNode {
    fn irq_pending(&self) -> bool {
        self.model.irq_lines().any()
    }
    fn service(&mut self) {
        // One handler per line, as the four vectors of the chip run them.
        let l = self.model.irq_lines();
        if l.tx {
            self.parts.tx_irq.on_interrupt();
        }
        if l.rx0 {
            self.parts.rx0_irq.on_interrupt();
        }
        if l.rx1 {
            self.parts.rx1_irq.on_interrupt();
        }
        if l.sce {
            self.parts.status_irq.on_interrupt();
        }
    }
    fn receive(&mut self) -> Option<Frame> {
        self.parts.rx.receive().ok().map(|rx| rx.frame)
    }
    fn hw_lost(&self) -> u64 {
        let s = self.model.state();
        s.overruns[0] + s.overruns[1]
    }
    fn overrun_events(&self) -> u64 {
        u64::from(self.state.error_stats().hardware_overruns)
    }
    fn ring_overflows(&self) -> u64 {
        u64::from(self.state.traffic().rx_ring_overflows)
    }
    fn counted_received(&self) -> u64 {
        u64::from(self.state.traffic().received)
    }
}

impl LoadInstance for LeanBxCan {
    type Node = LeanBxNode;
    const NAME: &'static str = "bxCAN (STM32F767 CAN1), lean split";
    // The same FIFO as the unsplit node: FIFO 0, 3 deep, RFLM = 0 (`bx_lean_config`).
    const RX_FIFO_DEPTH: usize = <BxCanBackend as Backend>::RX_FIFO_DEPTH;
    const OVERRUN: OverrunPolicy = <BxCanBackend as Backend>::OVERRUN;
    const COUNTS: bool = false;
    fn attach_via(
        h: &mut Harness,
        attach: impl FnOnce(&mut Bus, &str, Box<dyn BusNode>) -> NodeId,
    ) -> LeanBxNode {
        attach_bx_lean(h, attach).expect("lean bxCAN node")
    }
}

/// The lean split driver on the FlexCAN module `P` ([`crate::lean`]): the ORed
/// message-buffer line runs the transmit, receive (`Rx0Irq`) and status handlers, the
/// receive half drains the ring.
pub struct LeanFlexCanOf<P>(core::marker::PhantomData<P>);

/// The lean split driver on Teensy 3.6 can0 (ACAN's layout, the 8-filter partition).
pub type LeanFlexCan = LeanFlexCanOf<Teensy36Can0>;

/// The lean split driver on Teensy 4.1 CAN1 (the RT1062 model in the RT1062 layout,
/// the 12/12 partition): `teensy4-loopback-lean`.
pub type LeanRt1062 = LeanFlexCanOf<Teensy41Can1>;

impl<L: Layout> Loaded for LeanNode<FlexLeanModelHw<L>, FlexCanModel> {
    fn irq_pending(&self) -> bool {
        self.model.irq_pending()
    }
    fn service(&mut self) {
        self.parts.tx_irq.on_interrupt();
        self.parts.rx0_irq.on_interrupt();
        self.parts.status_irq.on_interrupt();
    }
    fn receive(&mut self) -> Option<Frame> {
        self.parts.rx.receive().ok().map(|rx| rx.frame)
    }
    fn hw_lost(&self) -> u64 {
        self.model.frames_lost()
    }
    fn overrun_events(&self) -> u64 {
        u64::from(self.state.error_stats().hardware_overruns)
    }
    fn ring_overflows(&self) -> u64 {
        u64::from(self.state.traffic().rx_ring_overflows)
    }
    fn counted_received(&self) -> u64 {
        u64::from(self.state.traffic().received)
    }
}

impl<P: LeanFlexPart> LoadInstance for LeanFlexCanOf<P> {
    type Node = LeanFlexNode<P>;
    const NAME: &'static str = P::LEAN_NAME;
    // The Rx FIFO: 6 deep whatever the filter partition and the chip, a full FIFO
    // discards the new frame (Kinetis RM and IMXRT1060RM, FlexCAN "Rx FIFO"; the
    // model's `regs::RX_FIFO_DEPTH` for every chip).
    const RX_FIFO_DEPTH: usize = <FlexCanBackend as Backend>::RX_FIFO_DEPTH;
    const OVERRUN: OverrunPolicy = <FlexCanBackend as Backend>::OVERRUN;
    const COUNTS: bool = false;
    fn attach_via(
        h: &mut Harness,
        attach: impl FnOnce(&mut Bus, &str, Box<dyn BusNode>) -> NodeId,
    ) -> LeanFlexNode<P> {
        attach_flex_lean::<P, FULL_LOAD_BIT_RATE>(h, attach).expect("lean FlexCAN node")
    }
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
    /// Frames the driver's traffic statistics count as received (0 without
    /// statistics).
    pub counted_received: u64,
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

impl<N: Loaded> Ctx<N> {
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
        node.service();
        let got: Vec<Frame> = std::iter::from_fn(|| node.receive()).collect();
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

impl<N: Loaded> BusNode for Hooked<N> {
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
/// pass-all node of `B` (a backend's unsplit driver or a lean split one), its interrupt
/// serviced after a latency uniform in `0..=max_latency` bit times (seeded by `seed`).
pub fn full_load<B: LoadInstance>(frames: u64, max_latency: u64, seed: u64) -> LoadReport {
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
    let node = B::attach_via(&mut h, move |bus, name, inner| {
        bus.attach(name, Hooked { inner, ctx: hook })
    });
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
    report.overrun_events = node.overrun_events();
    report.ring_overflows = node.ring_overflows();
    report.counted_received = node.counted_received();
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
