//! Every example firmware on every board it supports does what its documentation says,
//! checked through what can be observed: bus frames, interrupts taken, the application
//! counters the examples export (`SENT`, `RECEIVED`, `HITS`, `ERRORS`, `STATS`).

mod common;

use common::*;
use twocan_core::Frame;
use twocan_fil::nvic::exc;
use twocan_fil::world::World;

const TEENSY: [&str; 3] = ["teensy32", "teensy35", "teensy36"];
const STM32: [&str; 2] = ["nucleo-f767zi", "disco-f746g"];

#[test]
fn loopback_frames_come_back_on_every_board() {
    let boards = TEENSY
        .iter()
        .map(|b| (*b, "teensy-loopback"))
        .chain(STM32.iter().map(|b| (*b, "stm32f7-loopback")));
    for (board, bin) in boards {
        let Some(mut w) = world(500_000, &[(board, bin)]) else {
            return;
        };
        // One frame per second: three by 3.2 s.
        w.run_for(secs(3.2));
        assert_clean(&w);
        let m = &w.machines[0];
        assert_eq!(m.read_u32_static("SENT"), Some(3), "{board}");
        assert_eq!(m.read_u32_static("RECEIVED"), Some(3), "{board}");
        if bin.starts_with("stm32") {
            // Each frame's withdrawn follower was aborted, and none came back.
            assert_eq!(m.read_u32_static("WITHDRAWN"), Some(3), "{board}");
            assert_eq!(m.read_u32_static("STRAY"), Some(0), "{board}");
        }
        let b = m.board();
        // The 1 ms SysTick ran (3,199 ticks less the start-up time).
        let ticks = b.taken.get(&exc::SYSTICK).copied().unwrap_or(0);
        assert!(
            (3_100..=3_200).contains(&ticks),
            "{board}: {ticks} SysTicks"
        );
        // The CAN receive interrupt was taken for each frame.
        let rx_line = b.cans[0].instance.irqs[if board.starts_with("teensy") { 0 } else { 1 }].1;
        assert!(b.irq_taken(rx_line) >= 3, "{board}: {:?}", b.taken);
    }
}

/// `teensy-loopback-lean` (issue 21: fire-and-forget transmit, no statistics, no time
/// stamps, the filter table planned at compile time): the same frames come back as with
/// the default choice, through the same interrupt line.
#[test]
fn lean_loopback_frames_come_back_on_every_teensy() {
    for board in TEENSY {
        let Some(mut w) = world(500_000, &[(board, "teensy-loopback-lean")]) else {
            return;
        };
        // One frame per second: three by 3.2 s.
        w.run_for(secs(3.2));
        assert_clean(&w);
        let m = &w.machines[0];
        assert_eq!(m.read_u32_static("SENT"), Some(3), "{board}");
        assert_eq!(m.read_u32_static("RECEIVED"), Some(3), "{board}");
        let b = m.board();
        let rx_line = b.cans[0].instance.irqs[0].1;
        assert!(b.irq_taken(rx_line) >= 3, "{board}: {:?}", b.taken);
    }
}

/// `stm32f7-loopback-lean` (issue 21: fire-and-forget transmit, no statistics, no time
/// stamps, the filter planned at compile time and fixed, CAN1 at its fixed address): the
/// same frames come back as with the default choice, through the same receive line; the
/// transmit line is never taken (the quiet transmit mode: no completion to report, and a
/// frame every second always finds an empty mailbox).
#[test]
fn lean_loopback_frames_come_back_on_every_stm32f7() {
    for board in STM32 {
        let Some(mut w) = world(500_000, &[(board, "stm32f7-loopback-lean")]) else {
            return;
        };
        w.run_for(secs(3.2));
        assert_clean(&w);
        let m = &w.machines[0];
        assert_eq!(m.read_u32_static("SENT"), Some(3), "{board}");
        assert_eq!(m.read_u32_static("RECEIVED"), Some(3), "{board}");
        let b = m.board();
        let irqs = &b.cans[0].instance.irqs;
        assert!(b.irq_taken(irqs[1].1) >= 3, "{board}: {:?}", b.taken);
        assert_eq!(b.irq_taken(irqs[0].1), 0, "{board}: {:?}", b.taken);
    }
}

/// STM32F7 `filters`: each frame reaches the call-back of its filter, 0x777 none.
#[test]
fn stm32_filters_deliver_exactly_the_expected_identifiers() {
    for board in STM32 {
        let Some(mut w) = world(500_000, &[(board, "stm32f7-filters")]) else {
            return;
        };
        w.run_for(secs(2.05));
        assert_clean(&w);
        // bxCAN loop-back without silent mode: the frames are on the wire too.
        let count = |p: &dyn Fn(u32, bool, bool) -> bool| {
            wire_count(&w, |f| {
                let (id, ext) = raw_id(f);
                p(id, ext, is_remote(f))
            })
        };
        let expected = [
            count(&|id, ext, _| !ext && id == 0x100),
            count(&|id, ext, _| !ext && id == 0x101),
            count(&|id, ext, r| !ext && r && id == 0x542),
            count(&|id, ext, r| !ext && !r && (0x300..=0x30F).contains(&id)),
            count(&|id, ext, _| ext && id == 0x12_3456),
            count(&|id, ext, r| ext && !r && id & 0x1FFF_00FF == 0x18FF_0000),
        ];
        let rejected = count(&|id, ext, _| !ext && id == 0x777);
        assert!(
            rejected >= 2,
            "{board}: the frame no filter accepts was sent"
        );
        let m = &w.machines[0];
        let hits = m.read_static("HITS").expect("HITS");
        for (i, want) in expected.iter().enumerate() {
            let got = u32::from_le_bytes(hits[4 * i..4 * i + 4].try_into().unwrap());
            assert!(*want >= 2, "{board}: filter {i} frames sent: {want}");
            // The last frame may still wait in the driver's queue for the next loop.
            assert!(
                got == *want || got + 1 == *want,
                "{board}: filter {i}: {got} of {want}"
            );
        }
        assert_eq!(m.read_u32_static("ERRORS"), Some(0), "{board}");
        let banks = m.read_static("BANKS").expect("BANKS");
        assert!(
            banks.iter().any(|b| *b != 0),
            "{board}: filter banks assigned"
        );
    }
}

/// Teensy `filters`: every filter's call-back sees exactly its frames, none reaches the
/// wrong one. (It used to halt in `begin` with blink code 5: masked filters given as
/// secondary filters, which ACAN §13.4 forbids; the example now lists them as primary.)
#[test]
fn teensy_filters_deliver_exactly_the_expected_identifiers() {
    for board in TEENSY {
        let Some(mut w) = world(500_000, &[(board, "teensy-filters")]) else {
            return;
        };
        // One frame every 100 ms after start-up: twelve by 1.25 s, the last
        // one at least 30 ms before the end (dispatched by then).
        w.run_for(secs(1.25));
        assert_clean(&w);
        // FlexCAN loop-back: the frames never reach the wire; the bus records them as
        // internal frames of the controller.
        let count = |p: &dyn Fn(u32, bool, bool) -> bool| {
            w.bus
                .trace()
                .records()
                .iter()
                .filter(|r| {
                    let (id, ext) = raw_id(&r.frame);
                    r.internal && r.is_error_free() && p(id, ext, is_remote(&r.frame))
                })
                .count() as u32
        };
        // The filters of `examples/teensy/src/filters_example.rs`, by index.
        let expected = [
            count(&|id, ext, r| !ext && !r && id & 0x7F0 == 0x300),
            count(&|id, ext, r| ext && !r && id & 0x1FFF_00FF == 0x18FF_0000),
            count(&|id, ext, r| !ext && !r && id == 0x234),
            count(&|id, ext, r| ext && !r && id == 0x12_3456),
            count(&|id, ext, r| !ext && r && id == 0x542),
        ];
        let rejected = count(&|id, ext, _| !ext && id == 0x777);
        // Two rounds of the six frames: each filter's frame twice, 0x777 twice.
        assert_eq!(expected, [2; 5], "{board}: frames sent per filter");
        assert_eq!(rejected, 2, "{board}: the frame no filter accepts was sent");
        assert_eq!(w.bus.stats().internal_frames, 12, "{board}");
        assert_eq!(
            w.bus.stats().frames_started,
            0,
            "{board}: nothing on the wire"
        );
        let m = &w.machines[0];
        let hits = m.read_static("HITS").expect("HITS");
        assert_eq!(hits.len(), 4 * 5, "{board}: HITS is [AtomicU32; 5]");
        for (i, want) in expected.iter().enumerate() {
            let got = u32::from_le_bytes(hits[4 * i..4 * i + 4].try_into().unwrap());
            assert_eq!(got, *want, "{board}: filter {i}");
        }
        assert_eq!(m.read_u32_static("ERRORS"), Some(0), "{board}");
    }
}

/// `async-echo` (both families, on `embassy-executor`): a plain node sends standard
/// and extended frames; every one comes back once, with its identifier plus one and
/// the same data, in order.
#[test]
fn async_echo_answers_every_frame_with_its_identifier_plus_one() {
    let boards = TEENSY
        .iter()
        .map(|b| (*b, "teensy-async-echo"))
        .chain(STM32.iter().map(|b| (*b, "stm32f7-async-echo")));
    for (board, bin) in boards {
        let Some(mut w) = world(500_000, &[(board, bin)]) else {
            return;
        };
        let sent = [
            twocan_core::Frame::standard(0x123, &[1]).unwrap(),
            twocan_core::Frame::extended(0x1234_5678, &[1, 2, 3, 4, 5, 6, 7, 8]).unwrap(),
            twocan_core::Frame::standard(0x7FE, &[]).unwrap(),
        ];
        // Every 5 ms from 50 ms (the firmware is on the bus after about 16 ms): 90
        // frames by 0.498 s, the last at 495 ms (its echo follows within 0.5 ms).
        let tester = w.add_node_from(
            "tester",
            twocan_sim::SimNode::new(),
            500_000,
            sent.to_vec(),
            5_000_000_000,
            50_000_000_000,
        );
        w.run_for(secs(0.498));
        assert_clean(&w);
        let records = w.bus.trace().records();
        assert!(
            records.iter().all(|r| r.is_error_free()),
            "{board}: an error on the bus"
        );
        let tester_node = w.nodes[0].node;
        let board_node = w.attached[0].node;
        let from = |n| {
            records
                .iter()
                .filter(|r| r.transmitters == [n])
                .map(|r| r.frame)
                .collect::<Vec<_>>()
        };
        let (asked, echoed) = (from(tester_node), from(board_node));
        assert_eq!(asked.len(), 90, "{board}");
        assert_eq!(echoed.len(), 90, "{board}");
        assert_eq!(records.len(), 180, "{board}: nothing else on the bus");
        for (k, (a, e)) in asked.iter().zip(&echoed).enumerate() {
            assert_eq!(*a, sent[k % 3], "{board}: frame {k}");
            let (id, ext) = raw_id(a);
            assert_eq!(raw_id(e), (id + 1, ext), "{board}: echo {k}");
            assert_eq!(
                embedded_can::Frame::data(e),
                embedded_can::Frame::data(a),
                "{board}: echo {k}"
            );
        }
        assert_eq!(tester.borrow().received_frames(), echoed, "{board}");
        assert_eq!(w.machines[0].read_u32_static("ECHOED"), Some(90), "{board}");
        // The receive interrupt woke the executor for each frame.
        let b = w.machines[0].board();
        let rx_line = b.cans[0].instance.irqs[if board.starts_with("teensy") { 0 } else { 1 }].1;
        assert!(b.irq_taken(rx_line) >= 90, "{board}: {:?}", b.taken);
    }
}

fn assert_app_pair(a: Stats, b: Stats, b_sent_heartbeats: u32, label: &str) {
    assert_eq!(a.heartbeat_gaps, 0, "{label}: {a:?}");
    assert_eq!(a.heartbeat_duplicates, 0, "{label}: {a:?}");
    assert_eq!(a.unhandled, 0, "{label}: {a:?}");
    assert_eq!(a.tx_full, 0, "{label}: {a:?}");
    // Each peer heartbeat on the wire was counted (the last may await the next step).
    assert!(
        a.heartbeats + 1 >= b_sent_heartbeats && a.heartbeats <= b_sent_heartbeats,
        "{label}: {} heartbeats counted, {b_sent_heartbeats} on the wire",
        a.heartbeats
    );
    // A status request every 10 steps, answered by the peer.
    assert!(a.requests >= 1 && a.answers >= 1, "{label}: {a:?}");
    assert!(a.measurements >= 1, "{label}: {a:?}");
    assert!(b.sent > 0);
}

/// Runs `w` for `seconds` in slices of `SLICE_US`, then on until two slices pass with
/// no `STATS` change on any board (no application step: every frame of the last steps
/// is on the wire). Returns, per board, the end (µs) of the slice in which its `STATS`
/// last changed (its last step lies within the `SLICE_US` before).
const SLICE_US: u64 = 500;
fn run_tracking_steps(w: &mut World<'_>, boards: usize, count: usize, seconds: f64) -> Vec<u64> {
    let mut last = vec![0u64; boards];
    let mut seen: Vec<Option<Vec<Stats>>> = vec![None; boards];
    let mut quiet = 0;
    let mut slices = 0u64;
    let end_us = (seconds * 1e6) as u64;
    loop {
        w.run_for(u128::from(SLICE_US) * 1_000_000);
        slices += 1;
        let now = slices * SLICE_US;
        let mut changed = false;
        for b in 0..boards {
            let bytes = w.machines[b].read_static("STATS").expect("STATS");
            let now_stats = (bytes[4] == 1).then(|| app_stats(w, b, count));
            if now_stats != seen[b] {
                seen[b] = now_stats;
                last[b] = now;
                changed = true;
            }
        }
        quiet = if changed { 0 } else { quiet + 1 };
        if now >= end_us && quiet >= 2 {
            return last;
        }
        assert!(now < end_us + 50_000, "no quiet 1 ms after the run");
    }
}

/// Wire frames (error free) matching `pred` that ended before `t_us`, and before
/// `t_us - SLICE_US`: the peer's step at a time within that slice counted the second
/// number at least and the first at most.
fn wire_before(w: &World<'_>, t_us: u64, pred: impl Fn(&Frame) -> bool) -> (u32, u32) {
    let us = |bits: u64| bits * 2; // 500 kbit/s
    let records = w.bus.trace().records();
    let ok = records
        .iter()
        .filter(|r| !r.internal && r.is_error_free() && pred(&r.frame));
    let hi = ok.clone().filter(|r| us(r.end) < t_us).count() as u32;
    let lo = ok.filter(|r| us(r.end) + SLICE_US < t_us).count() as u32;
    (lo, hi)
}

/// Issue 27: each node's `AppStats` against the frames on the wire, per identifier, for
/// node `a` (its counters `sa`, its last step in the slice ending at `a_last`) and its
/// peer `b`. Everything `a` queued is on the wire: its `sent` is the sum of its
/// heartbeats, measurements, requests and answers on the wire; one request every 10
/// heartbeats and one measurement every 4; an answer per request `a` handled. What `a`
/// counted of `b`'s frames is what `b` put on the wire before `a`'s last step.
fn assert_app_wire(w: &World<'_>, a: u32, b: u32, sa: Stats, a_last: u64, label: &str) {
    let data = |id: u32| move |f: &Frame| raw_id(f) == (id, false) && !is_remote(f);
    let all = |p: &dyn Fn(&Frame) -> bool| wire_count(w, p);
    let hb = all(&data(0x100 + a));
    let meas = all(&|f: &Frame| raw_id(f) == (0x18FF_0000 | a << 8, true));
    let req = all(&|f: &Frame| raw_id(f) == (0x200 + b, false) && is_remote(f));
    let ans = all(&data(0x200 + a));
    assert_eq!(
        sa.sent,
        hb + meas + req + ans,
        "{label}: sent = heartbeats {hb} + measurements {meas} + requests {req} + answers {ans} on the wire"
    );
    assert_eq!((meas, req), (hb / 4, hb / 10), "{label}: the schedule");
    let within = |(lo, hi): (u32, u32), n: u32, what: &str| {
        assert!(
            lo <= n && n <= hi,
            "{label}: {what} counted {n}, on the wire before the last step {lo}..={hi}"
        );
    };
    within(
        wire_before(w, a_last, data(0x100 + b)),
        sa.heartbeats,
        "heartbeats",
    );
    within(
        wire_before(w, a_last, |f: &Frame| {
            raw_id(f) == (0x18FF_0000 | b << 8, true)
        }),
        sa.measurements,
        "measurements",
    );
    within(
        wire_before(w, a_last, |f: &Frame| {
            raw_id(f) == (0x200 + a, false) && is_remote(f)
        }),
        sa.requests,
        "requests",
    );
    within(
        wire_before(w, a_last, data(0x200 + b)),
        sa.answers,
        "answers",
    );
    // Every request handled was answered in the same step.
    assert_eq!(ans, sa.requests, "{label}: one answer per request handled");
}

/// The `app` of a Teensy (node 1) and of an STM32F7 board (node 2) on one bus.
#[test]
fn teensy_and_stm32_apps_talk_through_the_portable_application() {
    for (teensy, stm32) in [
        ("teensy36", "nucleo-f767zi"),
        ("teensy32", "disco-f746g"),
        ("teensy35", "nucleo-f767zi"),
    ] {
        let Some(mut w) = world(500_000, &[(teensy, "teensy-app"), (stm32, "stm32f7-app")]) else {
            return;
        };
        let last = run_tracking_steps(&mut w, 2, 1, 1.5);
        assert_clean(&w);
        let n1 = app_stats(&w, 0, 1)[0];
        let n2 = app_stats(&w, 1, 1)[0];
        assert_app_wire(&w, 1, 2, n1, last[0], teensy);
        assert_app_wire(&w, 2, 1, n2, last[1], stm32);
        let hb = |id: u32| wire_count(&w, |f| raw_id(f) == (id, false) && !is_remote(f));
        assert!(hb(0x101) >= 140, "{teensy}: {} heartbeats", hb(0x101));
        assert_app_pair(n1, n2, hb(0x102), teensy);
        assert_app_pair(n2, n1, hb(0x101), stm32);
        // Same application, same schedule: the two nodes count alike.
        assert!(n1.heartbeats.abs_diff(n2.heartbeats) <= 2, "{n1:?} {n2:?}");
        assert!(
            n1.measurements.abs_diff(n2.measurements) <= 1,
            "{n1:?} {n2:?}"
        );
        // Once both nodes are on the bus every frame is acknowledged: the only errors
        // are the acknowledge errors of the first node before its peer joined.
        let late_errors = w
            .bus
            .trace()
            .records()
            .iter()
            .filter(|r| !r.is_error_free() && r.sof > 500_000 / 20)
            .count();
        assert_eq!(late_errors, 0, "{teensy} + {stm32}: errors after 50 ms");
    }
}

/// Teensy 3.6 `can0-can1` and NUCLEO-F767ZI `can1-can2`: the two controllers of one
/// chip exchange frames.
#[test]
fn two_controllers_of_one_chip_exchange_frames() {
    for (board, bin) in [
        ("teensy36", "teensy-can0-can1"),
        ("nucleo-f767zi", "stm32f7-can1-can2"),
    ] {
        let Some(mut w) = world(500_000, &[(board, bin)]) else {
            return;
        };
        let last = run_tracking_steps(&mut w, 1, 2, 1.2);
        assert_clean(&w);
        let stats = app_stats(&w, 0, 2);
        assert_app_wire(&w, 1, 2, stats[0], last[0], board);
        assert_app_wire(&w, 2, 1, stats[1], last[0], board);
        let hb = |id: u32| wire_count(&w, |f| raw_id(f) == (id, false) && !is_remote(f));
        assert!(hb(0x101) >= 100 && hb(0x102) >= 100, "{board}");
        assert_app_pair(stats[0], stats[1], hb(0x102), board);
        assert_app_pair(stats[1], stats[0], hb(0x101), board);
        // Both controllers sent and received on the wire.
        for a in &w.attached {
            let s = w.bus.node_stats(a.node).unwrap();
            assert!(s.sent >= 100 && s.received >= 100, "{}: {s:?}", a.name);
        }
    }
}

/// The same ELF twice on one bus: two boards, each with its own CPU, memory and
/// controllers.
#[test]
fn the_same_firmware_twice_on_one_bus() {
    let Some(mut w) = world(
        500_000,
        &[
            ("teensy36", "teensy-loopback"),
            ("teensy36", "teensy-loopback"),
        ],
    ) else {
        return;
    };
    w.run_for(secs(2.1));
    assert_clean(&w);
    assert_eq!(w.machines[1].board().name, "teensy36#2");
    for m in &w.machines {
        assert_eq!(m.read_u32_static("SENT"), Some(2));
        assert_eq!(m.read_u32_static("RECEIVED"), Some(2));
    }
    // Loop-back frames stay inside each controller: nothing on the wire.
    assert_eq!(w.bus.stats().frames_started, 0);
}
