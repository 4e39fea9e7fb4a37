//! The `app` firmware of a Teensy 3.6 and of a NUCLEO-F767ZI against the host demo's code
//! path: the same scenario run once with `twocan-host` (the real drivers over the models
//! on the simulated bus, the portable `twocan_app::App` stepped by the host, as
//! `can-demo` does) and once with the two firmware ELFs under the harness, and the
//! counters compared for equality: the nine application counters of each node (read from
//! the firmware's `STATS`), each node's frames sent and received on the wire, with its
//! errors and lost arbitrations, the frames its filters refused and the frames its
//! hardware lost, and the bus totals.
//!
//! The scenario: 500 kbit/s, 1.5 s, the Teensy as node 1 and the STM32 as node 2, a third
//! plain node ("other-ecu") sending the demo's unrequested traffic every 5 ms; without
//! faults, and with the demo's random faults (`--error-rate 0.02 --seed 7`: the bus draws
//! them per frame attempt from the seed, the same in both runs).
//!
//! Aligned, for stated reasons (docs/fil.md, "The app firmware against the host demo"):
//! - the application period is the firmware's, 10 ms (the demo steps every 1 ms);
//! - each node steps at its firmware's times, read from a first run under the harness:
//!   boot and clock set-up take the firmware 13–16 ms, which the host does not have, and
//!   the step that SysTick starts falls in one 20 µs harness step or the next; a frame the
//!   firmware queues during a harness step starts on the wire at the start of that step,
//!   so the host steps its node at that start;
//! - the other node's traffic starts with node 1's first step.

mod common;

use common::*;
use twocan_app::App;
use twocan_bxcan::{Config, FifoPolicy, Recovery};
use twocan_core::Frame;
use twocan_fil::can::Model;
use twocan_fil::world::World;
use twocan_host::{BxNode, FlexNode, Harness, Serviced, STM32F767_APB1_HZ};
use twocan_sim::{NodeStats, RandomFaults, SimNode};

const BIT_RATE: u32 = 500_000;
/// The firmware's application period (`Every::new(time::millis(), 10)` in both `app`s).
const PERIOD_US: u64 = 10_000;
/// The other node's period, as in `can-demo`.
const OTHER_PERIOD_US: u64 = 5_000;
/// The harness's co-simulation step (its default).
const QUANTUM_US: u64 = 20;
const RUN_US: u64 = 1_500_000;
const TEENSY: &str = "teensy36";
const STM32: &str = "nucleo-f767zi";

/// `can-demo`'s `--seed` and `--error-rate`: random faults on the bus, or none.
type Faults = Option<(u64, f64)>;

/// `can-demo`'s other node: frame `k` (standard `0x300 + k % 16` for even `k`, extended
/// `0x0CF0_0400 | k % 8` for odd `k`).
fn other_frame(k: u32) -> Frame {
    if k.is_multiple_of(2) {
        Frame::standard(0x300 + (k % 16) as u16, &k.to_le_bytes()).unwrap()
    } else {
        Frame::extended(0x0CF0_0400 | (k % 8), &k.to_be_bytes()).unwrap()
    }
}

/// What is compared.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Outcome {
    /// Application counters of node 1 (Teensy) and node 2 (STM32).
    apps: [Stats; 2],
    /// Wire statistics of the Teensy's CAN0, the STM32's CAN1 and the other node.
    wire: [NodeStats; 3],
    /// Frames each board's hardware filters refused.
    filtered: [u64; 2],
    /// Frames each board's hardware lost (FlexCAN Rx FIFO / bxCAN FIFO overruns).
    lost: [u64; 2],
    /// Frames the other node received.
    other_received: usize,
    /// Bus: frame attempts, error-free ones.
    bus: (u64, u64),
}

/// The `STATS` of board `b`, `None` before its application's first step.
fn try_stats(w: &World<'_>, b: usize) -> Option<Stats> {
    let bytes = w.machines[b].read_static("STATS")?;
    let word = |i: usize| u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
    (word(1) == 1).then(|| app_stats(w, b, 1)[0])
}

/// Each firmware's application steps: the start of the harness step in which step `n`
/// queued its first frame, in µs, for every step before the end of the run. Read from a
/// run without the other node: each step sends heartbeat `n` (its counter), preceded by
/// the answers to the requests it received, and the bus is idle when it does (the two
/// nodes step 2.4 ms apart), so the first frame of the step starts on the wire at the
/// start of the harness step in which the firmware queued it.
fn step_times() -> Option<[Vec<u64>; 2]> {
    let mut w = fil_world()?;
    w.run_for(u128::from(RUN_US + 2 * PERIOD_US) * 1_000_000);
    assert_clean(&w);
    let wire: Vec<_> = w
        .bus
        .trace()
        .records()
        .iter()
        .filter(|r| !r.internal && r.is_error_free())
        .collect();
    let us = |bits: u64| bits * 1_000_000 / u64::from(BIT_RATE);
    let mut steps = [Vec::new(), Vec::new()];
    for (node, out) in [1u32, 2].into_iter().zip(&mut steps) {
        for (i, r) in wire.iter().enumerate() {
            if raw_id(&r.frame) != (0x100 + node, false) || is_remote(&r.frame) {
                continue;
            }
            let n = r.frame.data_u32(0).unwrap() as usize;
            assert_eq!(n, out.len(), "node {node}: heartbeats in order");
            // The answers this step sent before its heartbeat.
            let mut first = i;
            while first > 0
                && raw_id(&wire[first - 1].frame) == (0x200 + node, false)
                && !is_remote(&wire[first - 1].frame)
            {
                first -= 1;
            }
            out.push(us(wire[first].sof));
        }
        assert!(
            out.iter().all(|t| t % QUANTUM_US == 0),
            "node {node}: steps start harness steps: {out:?}"
        );
        out.retain(|t| *t < RUN_US);
    }
    Some(steps)
}

fn fil_world() -> Option<World<'static>> {
    world(BIT_RATE, &[(TEENSY, "teensy-app"), (STM32, "stm32f7-app")])
}

/// The other node's frames: `other_frame(1)`, `other_frame(2)`, ... from `first_us` every
/// 5 ms until the end of the run.
fn other_traffic(first_us: u64) -> Vec<(u64, Frame)> {
    (0..)
        .map(|k| first_us + k * OTHER_PERIOD_US)
        .take_while(|t| *t < RUN_US)
        .zip(1..)
        .map(|(t, k)| (t, other_frame(k)))
        .collect()
}

/// The firmware pair under the harness.
fn run_firmware(first: [u64; 2], faults: Faults) -> Option<(Outcome, World<'static>)> {
    let mut w = fil_world()?;
    if let Some((seed, rate)) = faults {
        w.bus.set_random_faults(Some(RandomFaults::new(seed, rate)));
    }
    let traffic = other_traffic(first[0]);
    let frames: Vec<Frame> = traffic.iter().map(|(_, f)| *f).collect();
    let other = w.add_node_from(
        "other-ecu",
        SimNode::new(),
        BIT_RATE,
        frames,
        u128::from(OTHER_PERIOD_US) * 1_000_000,
        // Due at the end of the step before `first[0]`'s: on the wire at its start.
        u128::from(first[0] + QUANTUM_US) * 1_000_000,
    );
    w.run_for(u128::from(RUN_US) * 1_000_000);
    assert_clean(&w);
    // The boards' controllers on the bus: the Teensy 3.6's CAN0 (CAN1 is never enabled)
    // and the STM32's CAN1 (CAN2 idem).
    let port = |b: usize, name: &str| {
        w.attached
            .iter()
            .find(|a| a.board == b && a.name.ends_with(name))
            .unwrap_or_else(|| panic!("board {b} has no {name}"))
    };
    let (t, s) = (port(0, "/CAN0"), port(1, "/CAN1"));
    let stats = |node| w.bus.node_stats(node).unwrap();
    let (filtered, lost): (Vec<u64>, Vec<u64>) = [t, s]
        .iter()
        .map(|a| match &w.machines[a.board].board().cans[a.port].model {
            Model::FlexCan(m) => (m.frames_discarded(), m.frames_lost()),
            Model::BxCan(m) => {
                let st = m.state();
                (st.dropped, st.overruns[0] + st.overruns[1])
            }
        })
        .unzip();
    let outcome = Outcome {
        apps: [try_stats(&w, 0).unwrap(), try_stats(&w, 1).unwrap()],
        wire: [stats(t.node), stats(s.node), stats(w.nodes[0].node)],
        filtered: [filtered[0], filtered[1]],
        lost: [lost[0], lost[1]],
        other_received: other.borrow().received().len(),
        bus: (
            w.bus.stats().frames_started,
            w.bus.stats().frames_error_free,
        ),
    };
    Some((outcome, w))
}

/// Copies `twocan_app::AppStats` into the tests' `Stats`.
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

/// What a host action does at its time.
#[derive(Debug, Clone, Copy)]
enum Action {
    Step(usize),
    Other(Frame),
}

/// The same scenario on the host demo's code path: `twocan_host`'s Teensy 3.6 can0 and
/// STM32F767 CAN1 over their models, with the firmware's settings (FlexCAN
/// `Settings::new(500_000)` and the application's filters as primary filters, as
/// `twocan_teensy::configs::BUS`; bxCAN `Config::from_bitrate(54 MHz, 500 kbit/s)` with
/// automatic bus-off recovery and the filters planned into FIFO 0, as `stm32f7-app`),
/// each `App` stepped with `handle` then `publish` as the firmware does.
fn run_host(steps: &[Vec<u64>; 2], faults: Faults) -> (Outcome, Vec<(u64, Frame, bool)>) {
    let first = [steps[0][0], steps[1][0]];
    let mut h = Harness::new(BIT_RATE).unwrap();
    let mut apps = [App::new(1, 2), App::new(2, 1)];
    let mut teensy = FlexNode::teensy36_can0(&mut h, &apps[0].filters()).unwrap();
    let config = Config::from_bitrate(STM32F767_APB1_HZ, BIT_RATE)
        .unwrap()
        .recovery(Recovery::Automatic);
    let mut stm32 =
        BxNode::with_config(&mut h, &config, &apps[1].filters(), FifoPolicy::Fifo0).unwrap();
    let other = SimNode::new().shared();
    let other_id = {
        let mut bus = h.bus().borrow_mut();
        bus.set_tracing(true);
        if let Some((seed, rate)) = faults {
            bus.set_random_faults(Some(RandomFaults::new(seed, rate)));
        }
        bus.attach("other-ecu", other.clone())
    };
    let bits = |us: u64| us * u64::from(BIT_RATE) / 1_000_000;
    // Both controllers are on the bus before the first step, as in the harness (the
    // firmware's first frames are acknowledged).
    assert!(h.now() < bits(first[0].min(first[1])));
    let mut actions: Vec<(u64, Action)> = Vec::new();
    for (n, times) in steps.iter().enumerate() {
        actions.extend(times.iter().map(|t| (*t, Action::Step(n))));
    }
    for (t, f) in other_traffic(first[0]) {
        actions.push((t, Action::Other(f)));
    }
    // At one time the other node queues first: a driver's register accesses may let bus
    // time pass (the host's poll clock), which must not start a node's frame before the
    // other node's is queued — in the harness all are queued before the bus moves on, and
    // arbitration decides.
    actions.sort_by_key(|(t, a)| (*t, !matches!(a, Action::Other(_))));
    let mut now = None;
    for (t, action) in actions {
        // The bus moves on once per time: the actions of one time all queue their frames
        // before it does.
        if now != Some(t) {
            h.run_until(bits(t), &mut [&mut teensy as &mut dyn Serviced, &mut stm32]);
            now = Some(t);
        }
        match action {
            Action::Step(0) => {
                apps[0].handle(&mut teensy.driver);
                apps[0].publish(&mut teensy.driver);
            }
            Action::Step(_) => {
                apps[1].handle(&mut stm32.driver);
                apps[1].publish(&mut stm32.driver);
            }
            Action::Other(f) => other.borrow_mut().send(f),
        }
    }
    h.run_until(
        bits(RUN_US),
        &mut [&mut teensy as &mut dyn Serviced, &mut stm32],
    );
    let bus = h.bus().borrow();
    let bx = stm32.model.state();
    let outcome = Outcome {
        apps: [stats_of(&apps[0]), stats_of(&apps[1])],
        wire: [
            bus.node_stats(teensy.id).unwrap(),
            bus.node_stats(stm32.id).unwrap(),
            bus.node_stats(other_id).unwrap(),
        ],
        filtered: [teensy.filtered_out(), stm32.filtered_out()],
        lost: [teensy.model.frames_lost(), bx.overruns[0] + bx.overruns[1]],
        other_received: other.borrow().received().len(),
        bus: (bus.stats().frames_started, bus.stats().frames_error_free),
    };
    // The demo's "sent" column is the driver's count: the frames on the wire.
    assert_eq!(
        u64::from(teensy.driver.traffic().sent),
        outcome.wire[0].sent
    );
    assert_eq!(u64::from(stm32.driver.traffic().sent), outcome.wire[1].sent);
    let trace = trace_of(bus.trace().records());
    (outcome, trace)
}

fn trace_of(records: &[twocan_sim::trace::TraceRecord]) -> Vec<(u64, Frame, bool)> {
    records
        .iter()
        .filter(|r| !r.internal)
        .map(|r| (r.sof, r.frame, r.is_error_free()))
        .collect()
}

/// The oracle (issue 27): each node's application counters computed from the scenario
/// alone — the two schedules of steps — with no driver code, so that a bug the
/// firmware and the host demo share (both run the same driver) still fails. Each step
/// (tick `k` = 1, 2, ...) of a node handles what arrived, then publishes the answers to
/// the requests it just handled, a heartbeat, a measurement when `k % 4 == 0` and a
/// status request when `k % 10 == 0` (`twocan_app::App::publish`). A frame published at
/// a step reaches the peer within `ARRIVAL_US` (a few frames on an otherwise idle bus);
/// the peer counts it at its first step after that. The schedules must keep every step
/// of one node at least `ARRIVAL_US` away from the other's (asserted), so that no frame
/// lands on the edge of a step. Without faults: no gap, no duplicate, nothing unhandled,
/// the transmit queue never full.
fn oracle(steps: &[Vec<u64>; 2]) -> [Stats; 2] {
    const ARRIVAL_US: u64 = 1_000;
    for (a, b) in [(0, 1), (1, 0)] {
        for t in &steps[a] {
            let near = steps[b].iter().find(|u| **u <= *t && *t < **u + ARRIVAL_US);
            assert!(
                near.is_none(),
                "node {}'s step at {t} us is within {ARRIVAL_US} us of node {}'s at {near:?} us",
                a + 1,
                b + 1
            );
        }
    }
    // What each node publishes at each of its steps: (time, heartbeat, measurement,
    // request, answers), answers depending on the peer's requests handled then.
    let mut out = [Stats::default(), Stats::default()];
    // Requests each node sent, by time.
    let requests: [Vec<u64>; 2] = [0, 1].map(|n| {
        steps[n]
            .iter()
            .enumerate()
            .filter(|(k, _)| (k + 1) % 10 == 0)
            .map(|(_, t)| *t)
            .collect()
    });
    // Answers each node sent, by time: at each step, one per peer request that arrived
    // since its previous step.
    let answers: [Vec<u64>; 2] = [0, 1].map(|n| {
        let peer = 1 - n;
        let mut sent = Vec::new();
        let mut prev = 0;
        for t in &steps[n] {
            let arrived = requests[peer]
                .iter()
                .filter(|r| prev <= **r + ARRIVAL_US && **r + ARRIVAL_US < *t)
                .count();
            sent.extend(std::iter::repeat_n(*t, arrived));
            prev = *t;
        }
        sent
    });
    for n in 0..2 {
        let peer = 1 - n;
        let last = *steps[n].last().expect("steps");
        let seen = |times: &[u64]| times.iter().filter(|t| **t + ARRIVAL_US < last).count() as u32;
        let k = steps[n].len() as u32;
        let s = &mut out[n];
        s.sent = k + k / 4 + k / 10 + answers[n].len() as u32;
        s.heartbeats = seen(&steps[peer]);
        let measurements: Vec<u64> = steps[peer]
            .iter()
            .enumerate()
            .filter(|(k, _)| (k + 1) % 4 == 0)
            .map(|(_, t)| *t)
            .collect();
        s.measurements = seen(&measurements);
        s.requests = seen(&requests[peer]);
        s.answers = seen(&answers[peer]);
    }
    out
}

/// The oracle on the wire: per identifier, the frames of each node's schedule that ended
/// before the end of the run (every step before `RUN_US - ARRIVAL`), counted in the bus
/// trace (the simulated bus's record, not a driver's count).
fn wire_matches_schedule(w: &World<'_>, steps: &[Vec<u64>; 2], apps: &[Stats; 2]) {
    for n in 0..2u32 {
        let mine = &steps[n as usize];
        let k = mine.iter().filter(|t| **t + 1_000 < RUN_US).count() as u32;
        let hb = wire_count(w, |f| raw_id(f) == (0x100 + n + 1, false) && !is_remote(f));
        let ms = wire_count(w, |f| raw_id(f) == (0x18FF_0000 | (n + 1) << 8, true));
        let rq = wire_count(w, |f| raw_id(f) == (0x200 + 2 - n, false) && is_remote(f));
        let an = wire_count(w, |f| raw_id(f) == (0x200 + n + 1, false) && !is_remote(f));
        assert_eq!(
            (hb, ms, rq),
            (k, k / 4, k / 10),
            "node {}: heartbeats, measurements, requests on the wire",
            n + 1
        );
        // The peer counted every answer this node put on the wire before its last step.
        assert!(
            an >= apps[1 - n as usize].answers,
            "node {}: answers on the wire {an}, counted by the peer {}",
            n + 1,
            apps[1 - n as usize].answers
        );
    }
}

#[test]
fn app_firmware_counts_what_the_host_demo_counts() {
    compare(None);
}

/// The same with `can-demo --error-rate 0.02 --seed 7`: the bus draws a fault for 2 % of
/// the frame attempts from the same seed in both runs.
#[test]
fn app_firmware_counts_what_the_host_demo_counts_with_errors() {
    compare(Some((7, 0.02)));
}

fn compare(faults: Faults) {
    let Some(steps) = step_times() else {
        return;
    };
    let first = [steps[0][0], steps[1][0]];
    // The firmware's 10 ms period, give or take the harness step its SysTick falls in;
    // a step's first frame may start later than the step when the bus is busy then (at
    // most one frame: 160 bit times), but the next step is back on the grid.
    const LATE_US: u64 = 160 * 1_000_000 / BIT_RATE as u64;
    for (node, s) in steps.iter().enumerate() {
        assert!(s.len() >= 148, "{} steps", s.len());
        for (k, t) in s.iter().enumerate() {
            let due = s[0] + k as u64 * PERIOD_US;
            assert!(
                *t + QUANTUM_US >= due && *t <= due + QUANTUM_US + LATE_US,
                "node {}: step {k} at {t} us, due at {due} us",
                node + 1
            );
        }
    }
    let Some((fil, w)) = run_firmware(first, faults) else {
        return;
    };
    let (host, host_trace) = run_host(&steps, faults);
    eprintln!(
        "first application steps: Teensy {} us, STM32 {} us",
        first[0], first[1]
    );
    eprintln!("firmware: {fil:#?}");
    // The comparison can fail: a scenario with traffic in it, counters that move.
    let hb = 145; // (1500 - 16) ms / 10 ms, less the last one still in flight
    assert!(fil.apps.iter().all(|s| s.heartbeats >= hb), "{fil:?}");
    assert!(fil.filtered.iter().all(|f| *f >= 250), "{fil:?}");
    assert!(fil.wire[2].sent >= 290, "{fil:?}");
    if faults.is_some() {
        // The faults hit: error frames, retransmissions, errors on every node.
        assert!(fil.bus.1 + 10 <= fil.bus.0, "{fil:?}");
        assert!(
            fil.wire.iter().all(|w| w.tx_errors + w.rx_errors > 0),
            "{fil:?}"
        );
    }
    if faults.is_none() {
        // The oracle: the counters the schedules give, for both runs.
        let expected = oracle(&steps);
        assert_eq!(fil.apps, expected, "firmware against the schedule");
        assert_eq!(host.apps, expected, "host demo against the schedule");
        wire_matches_schedule(&w, &steps, &fil.apps);
    } else {
        // Faults change what is received (retransmissions, double receptions), not
        // what each application publishes: per step a heartbeat, a measurement every
        // 4th, a request every 10th, and an answer per request it handled (all in the
        // step that handled them).
        for n in 0..2 {
            for (what, apps) in [("firmware", &fil.apps), ("host", &host.apps)] {
                let k = steps[n].len() as u32;
                assert_eq!(
                    apps[n].sent,
                    k + k / 4 + k / 10 + apps[n].requests,
                    "{what}: node {}: sent",
                    n + 1
                );
                assert_eq!(apps[n].tx_full, 0, "{what}: node {}", n + 1);
            }
        }
    }
    let fil_trace = trace_of(w.bus.trace().records());
    // Not compared: the frames' start times. The host's bxCAN register wrapper lets bus
    // time pass while the driver reads `CAN_MSR` (`twocan_host::Clocked`, for the
    // drivers' waits on the hardware), so the STM32's frames can start a bit time later
    // on the host; shown for information.
    let same = fil_trace
        .iter()
        .zip(&host_trace)
        .filter(|(a, b)| a == b)
        .count();
    eprintln!(
        "bus traces: {same} of {} records identical (start time, frame, outcome)",
        fil_trace.len()
    );
    if fil != host {
        let diverge = fil_trace
            .iter()
            .zip(&host_trace)
            .position(|(a, b)| a != b)
            .unwrap_or(fil_trace.len().min(host_trace.len()));
        let show = |t: &[(u64, Frame, bool)]| {
            t.iter()
                .skip(diverge.saturating_sub(4))
                .take(8)
                .map(|(sof, f, ok)| format!("  {sof} {f:?} {ok}"))
                .collect::<Vec<_>>()
                .join("\n")
        };
        panic!(
            "the firmware and the host count differently\nfirmware: {fil:#?}\nhost: {host:#?}\nbus traces diverge at record {diverge}:\nfirmware:\n{}\nhost:\n{}",
            show(&fil_trace),
            show(&host_trace)
        );
    }
}
