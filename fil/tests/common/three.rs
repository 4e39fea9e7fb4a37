//! Three `app` firmwares on one bus against the host demo's code path (issue 23's and
//! issue 24's "How it is checked"): the same scenario run once with the three ELFs under
//! the harness and once with `twocan_host` (the real drivers over the models on the
//! simulated bus, the portable `twocan_app::App` stepped by the host as `can-demo` does),
//! and the counters compared for equality ([`Outcome`]).
//!
//! The scenario: 500 kbit/s, 1.5 s, the three nodes and a plain fourth node
//! ("other-ecu") sending the demo's unrequested traffic every 5 ms from node 1's first
//! step. Each host node steps at its firmware's step times, read from a first run of the
//! three boards alone (docs/fil.md, "The app firmware against the host demo").

use twocan_app::App;
use twocan_bxcan::{chip, Config, FifoPolicy, Recovery};
use twocan_core::Frame;
use twocan_fil::can::Model;
use twocan_fil::world::World;
use twocan_flexcan::{Board, CanClock, Instance, Settings, Target};
use twocan_host::{BxNode, FlexNode, Harness, Rt1062Node, Serviced};
use twocan_sim::{NodeStats, SimNode};

use super::{app_stats, assert_clean, world, Stats};

pub const BIT_RATE: u32 = 500_000;
/// The firmware's application period (`Every::new(time::millis(), 10)` in every `app`).
pub const PERIOD_US: u64 = 10_000;
/// The other node's period, as in `can-demo`.
pub const OTHER_PERIOD_US: u64 = 5_000;
/// The harness's co-simulation step (its default).
pub const QUANTUM_US: u64 = 20;
pub const RUN_US: u64 = 1_500_000;

/// The three boards of a run: per board its profile name, its `app` ELF and its
/// application's (node, peer).
#[derive(Debug, Clone, Copy)]
pub struct Three {
    pub boards: [(&'static str, &'static str); 3],
    pub nodes: [(u8, u8); 3],
}

impl Three {
    /// The board that is node 1: the other node's traffic starts with its first step.
    fn lead(&self) -> usize {
        self.nodes
            .iter()
            .position(|(n, _)| *n == 1)
            .expect("a node 1")
    }
}

/// `can-demo`'s other node: frame `k` (standard `0x300 + k % 16` for even `k`, extended
/// `0x0CF0_0400 | k % 8` for odd `k`).
pub fn other_frame(k: u32) -> Frame {
    if k.is_multiple_of(2) {
        Frame::standard(0x300 + (k % 16) as u16, &k.to_le_bytes()).unwrap()
    } else {
        Frame::extended(0x0CF0_0400 | (k % 8), &k.to_be_bytes()).unwrap()
    }
}

/// What is compared: the application counters of the three nodes, the wire statistics of
/// the three controllers and the other node, the frames each board's filters refused and
/// its hardware lost, the frames the other node received, the bus totals.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Outcome {
    pub apps: [Stats; 3],
    pub wire: [NodeStats; 4],
    pub filtered: [u64; 3],
    pub lost: [u64; 3],
    pub other_received: usize,
    pub bus: (u64, u64),
}

/// Whether board `b`'s application has stepped (its `STATS` is `Some`), and its `sent`.
fn sent_so_far(w: &World<'_>, b: usize) -> Option<u32> {
    let bytes = w.machines[b].read_static("STATS")?;
    let word = |i: usize| u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
    (word(1) == 1).then(|| word(2))
}

/// Whether board `b`'s first controller holds a frame to send (loaded in a transmit
/// mailbox, waiting or on the bus): a FlexCAN message buffer above the Rx FIFO area up
/// to `MCR[MAXMB]` with code DATA or TANSWER (0b1100, 0b1110: "Message buffer
/// structure", Tx codes), a bxCAN mailbox not empty.
fn tx_loaded(w: &World<'_>, b: usize) -> bool {
    use twocan_flexcan::regs::{self, cs, ctrl2, mcr};
    let Some(a) = w.attached.iter().find(|a| a.board == b && a.port == 0) else {
        return false;
    };
    match &w.machines[b].board().cans[a.port].model {
        Model::FlexCan(m) => {
            let mcr_v = m.peek32(regs::MCR);
            let first = if mcr_v & mcr::RFEN != 0 {
                regs::rx_fifo_occupied_mbs(ctrl2::RFFN.get(m.peek32(regs::CTRL2)))
            } else {
                0
            };
            let last = (mcr::MAXMB.get(mcr_v) as usize).min(m.message_buffers() - 1);
            (first..=last)
                .any(|n| matches!(cs::CODE.get(m.peek32(regs::mb_cs(n))), 0b1100 | 0b1110))
        }
        Model::BxCan(m) => m
            .state()
            .mailboxes
            .iter()
            .any(|s| *s != twocan_core::MailboxState::Empty),
    }
}

/// How far before its `STATS` write a step's first frame may have been queued.
const STEP_WINDOW_US: u64 = 10 * QUANTUM_US;

/// Follows each board's application steps, one harness step at a time: a step ends with
/// its `STATS.sent` grown (every step publishes a heartbeat), and it began in
/// the harness step in which its first frame was loaded into a transmit mailbox (the
/// first one within [`STEP_WINDOW_US`] before that write in which the controller went
/// from nothing to send to a frame to send; the write's own harness step when none).
/// Handling what arrived and publishing can take a firmware longer than a harness step,
/// and a frame it queues during a harness step starts on the wire at the start of that
/// step, so the host steps its node there.
#[derive(Default)]
struct StepWatch {
    steps: [Vec<u64>; 3],
    last: [u32; 3],
    loaded: [bool; 3],
    sent: [u64; 3],
    rises: [Vec<u64>; 3],
}

impl StepWatch {
    /// After the harness step that started at `t` µs. The bus runs a frame whole once it
    /// started, so a frame loaded and sent within one harness step shows only in the
    /// controller's count of frames sent.
    fn look(&mut self, w: &World<'_>, t: u64) {
        for b in 0..3 {
            let loaded = tx_loaded(w, b);
            let sent = w
                .attached
                .iter()
                .find(|a| a.board == b && a.port == 0)
                .and_then(|a| w.bus.node_stats(a.node))
                .map_or(0, |s| s.sent);
            if (loaded || sent > self.sent[b]) && !self.loaded[b] {
                self.rises[b].push(t);
            }
            self.loaded[b] = loaded;
            self.sent[b] = sent;
            // `STATS` may be published before the step's first frame counts (`sent` 0).
            let now = sent_so_far(w, b).unwrap_or(0);
            if now > self.last[b] {
                let first = self.rises[b]
                    .iter()
                    .copied()
                    .find(|r| *r + STEP_WINDOW_US > t && *r <= t);
                self.steps[b].push(first.unwrap_or(t));
                self.last[b] = now;
            }
        }
    }
}

/// The other node's frames from `first_us` every 5 ms until the end of the run.
fn other_traffic(first_us: u64) -> Vec<(u64, Frame)> {
    (0..)
        .map(|k| first_us + k * OTHER_PERIOD_US)
        .take_while(|t| *t < RUN_US)
        .zip(1..)
        .map(|(t, k)| (t, other_frame(k)))
        .collect()
}

/// Node 1's first step, from the boards alone (before it nothing but the boards is on the
/// bus, so the run with the other node is the same up to there).
fn first_step(three: &Three) -> Option<u64> {
    let mut w = world(BIT_RATE, &three.boards)?;
    let mut watch = StepWatch::default();
    let mut t = 0;
    while watch.steps[three.lead()].is_empty() {
        assert!(t < RUN_US, "node 1 never stepped");
        w.run_for(u128::from(QUANTUM_US) * 1_000_000);
        watch.look(&w, t);
        t += QUANTUM_US;
    }
    Some(watch.steps[three.lead()][0])
}

/// The three firmwares under the harness with the other node from node 1's first step,
/// one harness step at a time: the outcome, the world, and each board's step times.
pub fn run_firmware(three: &Three) -> Option<(Outcome, World<'static>, [Vec<u64>; 3])> {
    let first = first_step(three)?;
    let mut w = world(BIT_RATE, &three.boards)?;
    let traffic = other_traffic(first);
    let frames: Vec<Frame> = traffic.iter().map(|(_, f)| *f).collect();
    let other = w.add_node_from(
        "other-ecu",
        SimNode::new(),
        BIT_RATE,
        frames,
        u128::from(OTHER_PERIOD_US) * 1_000_000,
        u128::from(first + QUANTUM_US) * 1_000_000,
    );
    let mut watch = StepWatch::default();
    let mut t = 0;
    while t < RUN_US {
        w.run_for(u128::from(QUANTUM_US) * 1_000_000);
        watch.look(&w, t);
        t += QUANTUM_US;
    }
    assert_clean(&w);
    assert_eq!(
        watch.steps[three.lead()].first(),
        Some(&first),
        "node 1's first step as without the other node"
    );
    // Each board's first controller: the Teensy 3.x's CAN0, the Teensy 4's CAN1, the
    // STM32s' CAN1 (the F103's CAN).
    let port = |b: usize| {
        w.attached
            .iter()
            .find(|a| a.board == b && a.port == 0)
            .unwrap_or_else(|| panic!("board {b} is not on the bus"))
            .clone()
    };
    let ports = [port(0), port(1), port(2)];
    let stats = |node| w.bus.node_stats(node).unwrap();
    let hw = |a: &twocan_fil::world::Attached| match &w.machines[a.board].board().cans[a.port].model
    {
        Model::FlexCan(m) => (m.frames_discarded(), m.frames_lost()),
        Model::BxCan(m) => {
            let st = m.state();
            (st.dropped, st.overruns[0] + st.overruns[1])
        }
    };
    let outcome = Outcome {
        apps: [0, 1, 2].map(|b| app_stats(&w, b, 1)[0]),
        wire: [
            stats(ports[0].node),
            stats(ports[1].node),
            stats(ports[2].node),
            stats(w.nodes[0].node),
        ],
        filtered: ports.each_ref().map(|p| hw(p).0),
        lost: ports.each_ref().map(|p| hw(p).1),
        other_received: other.borrow().received().len(),
        bus: (
            w.bus.stats().frames_started,
            w.bus.stats().frames_error_free,
        ),
    };
    Some((outcome, w, watch.steps))
}

fn stats_of(app: &App) -> Stats {
    let s = app.stats();
    Stats {
        sent: s.sent,
        tx_full: s.tx_full,
        heartbeats: s.heartbeats,
        heartbeat_gaps: s.heartbeat_gaps,
        heartbeat_duplicates: s.heartbeat_duplicates,
        measurements: s.measurements,
        requests: s.requests,
        answers: s.answers,
        unhandled: s.unhandled,
    }
}

/// A board's node on the host demo's code path.
enum HostNode {
    Flex(FlexNode),
    /// A Teensy 4 module, in the RT1062 layout as its firmware begins it.
    Rt(Box<Rt1062Node>),
    Bx(BxNode),
}

/// The bxCAN node of the host demo for a board's part: its `app` configuration
/// (`Config::from_bitrate` from the board's APB1 clock, for its chip, automatic bus-off
/// recovery, the filters planned into FIFO 0) over the model of a CAN1 with 14 banks at
/// reset, as the firmware's.
fn bx_node(
    h: &mut Harness,
    apb1_hz: u32,
    part: &'static twocan_bxcan::Chip,
    app: &App,
) -> HostNode {
    let config = Config::from_bitrate(apb1_hz, BIT_RATE)
        .unwrap()
        .chip(part)
        .unwrap()
        .recovery(Recovery::Automatic);
    HostNode::Bx(BxNode::with_config(h, &config, &app.filters(), FifoPolicy::Fifo0).unwrap())
}

impl HostNode {
    /// The node of `board` with its `app` firmware's configuration: the Teensy 3.6 can0
    /// with `Settings::new(500_000)` (`twocan_teensy::configs::BUS`), the Teensy 4.1 CAN1
    /// with the 24 MHz clock root (`twocan_teensy4::configs::BUS`), both with the
    /// application's filters as primary filters; the STM32 boards' CAN1 from their APB1
    /// clock (`examples/stm32`'s and `examples/stm32f7`'s boards).
    fn new(h: &mut Harness, board: &str, app: &App) -> HostNode {
        match board {
            "teensy36" => HostNode::Flex(FlexNode::teensy36_can0(h, &app.filters()).unwrap()),
            "teensy41" => HostNode::Rt(Box::new(
                Rt1062Node::begin(
                    h,
                    Target::new(Board::Teensy41, Instance::Can1),
                    &Settings::with_clock(BIT_RATE, CanClock::IMXRT_24MHZ),
                    &app.filters(),
                    &[],
                )
                .unwrap(),
            )),
            "nucleo-f767zi" => bx_node(h, 54_000_000, &chip::STM32F76X_F77X, app),
            "nucleo-f446re" => bx_node(h, 45_000_000, &chip::STM32F446, app),
            "bluepill" => bx_node(h, 36_000_000, &chip::STM32F103, app),
            other => panic!("no host node for {other}"),
        }
    }

    /// One application step, as the firmware's: `handle` then `publish`.
    fn step(&mut self, app: &mut App) {
        match self {
            HostNode::Flex(n) => {
                app.handle(&mut n.driver);
                app.publish(&mut n.driver);
            }
            HostNode::Rt(n) => {
                app.handle(&mut n.driver);
                app.publish(&mut n.driver);
            }
            HostNode::Bx(n) => {
                app.handle(&mut n.driver);
                app.publish(&mut n.driver);
            }
        }
    }

    fn id(&self) -> twocan_sim::NodeId {
        match self {
            HostNode::Flex(n) => n.id,
            HostNode::Rt(n) => n.id,
            HostNode::Bx(n) => n.id,
        }
    }

    fn filtered_out(&self) -> u64 {
        match self {
            HostNode::Flex(n) => n.filtered_out(),
            HostNode::Rt(n) => n.filtered_out(),
            HostNode::Bx(n) => n.filtered_out(),
        }
    }

    /// Frames the hardware lost (as the harness reads them from the firmware's model).
    fn lost(&self) -> u64 {
        match self {
            HostNode::Flex(n) => n.model.frames_lost(),
            HostNode::Rt(n) => n.model.frames_lost(),
            HostNode::Bx(n) => {
                let s = n.model.state();
                s.overruns[0] + s.overruns[1]
            }
        }
    }
}

impl Serviced for HostNode {
    fn service(&mut self) -> bool {
        match self {
            HostNode::Flex(n) => n.service(),
            HostNode::Rt(n) => n.service(),
            HostNode::Bx(n) => n.service(),
        }
    }
}

/// The same scenario on the host demo's code path, each `App` stepped with `handle` then
/// `publish` at its firmware's step times.
pub fn run_host(three: &Three, steps: &[Vec<u64>; 3]) -> Outcome {
    let mut h = Harness::new(BIT_RATE).unwrap();
    let mut apps = three.nodes.map(|(n, p)| App::new(n, p));
    let mut nodes: Vec<HostNode> = (0..3)
        .map(|b| HostNode::new(&mut h, three.boards[b].0, &apps[b]))
        .collect();
    let other = SimNode::new().shared();
    let other_id = {
        let mut bus = h.bus().borrow_mut();
        bus.attach("other-ecu", other.clone())
    };
    let bits = |us: u64| us * u64::from(BIT_RATE) / 1_000_000;
    let first = steps.iter().map(|s| s[0]).min().unwrap();
    assert!(h.now() < bits(first));
    // (time, 0 = other node first, then board index + 1)
    let mut actions: Vec<(u64, usize, Option<Frame>)> = Vec::new();
    for (n, times) in steps.iter().enumerate() {
        actions.extend(times.iter().map(|t| (*t, n + 1, None)));
    }
    for (t, f) in other_traffic(steps[three.lead()][0]) {
        actions.push((t, 0, Some(f)));
    }
    actions.sort_by_key(|(t, k, _)| (*t, *k));
    let mut now = None;
    for (t, who, frame) in actions {
        if now != Some(t) {
            let mut all: Vec<&mut dyn Serviced> =
                nodes.iter_mut().map(|n| n as &mut dyn Serviced).collect();
            h.run_until(bits(t), &mut all);
            now = Some(t);
        }
        match (who, frame) {
            (0, Some(f)) => other.borrow_mut().send(f),
            (b, _) => nodes[b - 1].step(&mut apps[b - 1]),
        }
    }
    {
        let mut all: Vec<&mut dyn Serviced> =
            nodes.iter_mut().map(|n| n as &mut dyn Serviced).collect();
        h.run_until(bits(RUN_US), &mut all);
    }
    let bus = h.bus().borrow();
    let outcome = Outcome {
        apps: [0, 1, 2].map(|b| stats_of(&apps[b])),
        wire: [
            bus.node_stats(nodes[0].id()).unwrap(),
            bus.node_stats(nodes[1].id()).unwrap(),
            bus.node_stats(nodes[2].id()).unwrap(),
            bus.node_stats(other_id).unwrap(),
        ],
        filtered: [0, 1, 2].map(|b| nodes[b].filtered_out()),
        lost: [0, 1, 2].map(|b| nodes[b].lost()),
        other_received: other.borrow().received().len(),
        bus: (bus.stats().frames_started, bus.stats().frames_error_free),
    };
    outcome
}

/// The whole comparison: the firmwares' step times (each on its 10 ms period, within a
/// few harness steps), the firmware run, the host run, and the two outcomes equal.
/// Returns the firmware's outcome and world for the caller's own checks; `None` when an
/// ELF is missing.
pub fn firmware_counts_what_the_host_counts(three: &Three) -> Option<(Outcome, World<'static>)> {
    let (fil, w, steps) = run_firmware(three)?;
    for (b, s) in steps.iter().enumerate() {
        let name = three.boards[b].0;
        assert!(s.len() >= 145, "{name}: {} steps", s.len());
        // The firmware's 10 ms period: a step begins within a few harness steps of its
        // due time (interrupts delay the thread).
        let late: Vec<_> = s
            .iter()
            .enumerate()
            .map(|(k, t)| t.abs_diff(s[0] + k as u64 * PERIOD_US))
            .collect();
        eprintln!("{name}: step lateness (us) max {:?}", late.iter().max());
        assert!(
            late.iter().all(|l| *l <= 10 * QUANTUM_US),
            "{name}: {late:?}"
        );
    }
    eprintln!("first steps (us): {:?}", steps.each_ref().map(|s| s[0]));
    eprintln!("firmware: {fil:#?}");
    let host = run_host(three, &steps);
    assert_eq!(fil, host, "the firmware and the host count differently");
    Some((fil, w))
}
