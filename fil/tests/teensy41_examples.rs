//! The Teensy 4.1 examples (`examples/teensy4`, i.MX RT1062, issue 24) under the
//! `teensy41` profile: each does what its documentation says, observed through the bus,
//! the interrupts taken and the counters the examples export; the three-board run
//! (Teensy 4.1 + Teensy 3.6 + NUCLEO-F767ZI `app`s on one bus); and the negative checks on
//! the real firmware (no stuck interrupt, a peer at the wrong bit rate). The profile's
//! own negative firmwares (clock gate off, stuck interrupt, no clock root) are in
//! `teensy41.rs`.

mod common;

use common::three::{self, Three};
use common::*;
use twocan_core::Frame;
use twocan_fil::nvic::exc;
use twocan_sim::SimNode;

const BOARD: &str = "teensy41";
/// CAN1's interrupt line (IMXRT1060RM: 36), CAN2's (37).
const CAN1_IRQ: u32 = 36;
const CAN2_IRQ: u32 = 37;

fn taken(w: &twocan_fil::world::World<'_>, board: usize, irq: u32) -> u64 {
    w.machines[board].board().irq_taken(irq)
}

#[test]
fn loopback_frames_come_back() {
    let Some(mut w) = world(500_000, &[(BOARD, "teensy4-loopback")]) else {
        return;
    };
    w.run_for(secs(3.2));
    assert_clean(&w);
    let m = &w.machines[0];
    assert_eq!(m.read_u32_static("SENT"), Some(3));
    assert_eq!(m.read_u32_static("RECEIVED"), Some(3));
    assert_eq!(m.read_u32_static("HALT"), Some(0));
    let ticks = m.board().taken.get(&exc::SYSTICK).copied().unwrap_or(0);
    assert!((3_100..=3_200).contains(&ticks), "{ticks} SysTicks");
    assert!(taken(&w, 0, CAN1_IRQ) >= 3, "{:?}", m.board().taken);
    // Loop-back: the frames never reach the wire.
    assert_eq!(wire_count(&w, |_| true), 0);
}

/// `teensy4-loopback-lean` (issue 21: fire-and-forget transmit, no statistics, no time
/// stamps, the filter table planned at compile time for the RT1062 layout): the same
/// frames come back as with the default choice, through the same line.
#[test]
fn lean_loopback_frames_come_back() {
    let Some(mut w) = world(500_000, &[(BOARD, "teensy4-loopback-lean")]) else {
        return;
    };
    w.run_for(secs(3.2));
    assert_clean(&w);
    let m = &w.machines[0];
    assert_eq!(m.read_u32_static("SENT"), Some(3));
    assert_eq!(m.read_u32_static("RECEIVED"), Some(3));
    assert_eq!(m.read_u32_static("HALT"), Some(0));
    let ticks = m.board().taken.get(&exc::SYSTICK).copied().unwrap_or(0);
    assert!((3_100..=3_200).contains(&ticks), "{ticks} SysTicks");
    assert!(taken(&w, 0, CAN1_IRQ) >= 3, "{:?}", m.board().taken);
    // Loop-back: the frames never reach the wire.
    assert_eq!(wire_count(&w, |_| true), 0);
}

#[test]
fn filters_deliver_exactly_the_expected_identifiers() {
    let Some(mut w) = world(500_000, &[(BOARD, "teensy4-filters")]) else {
        return;
    };
    w.run_for(secs(1.25));
    assert_clean(&w);
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
    let expected = [
        count(&|id, ext, r| !ext && !r && (0x300..=0x30F).contains(&id)),
        count(&|id, ext, r| ext && !r && id & 0x1FFF_00FF == 0x18FF_0000),
        count(&|id, ext, _| !ext && id == 0x234),
        count(&|id, ext, _| ext && id == 0x12_3456),
        count(&|id, ext, r| !ext && r && id == 0x542),
    ];
    assert!(
        count(&|id, ext, _| !ext && id == 0x777) >= 1,
        "0x777 was sent"
    );
    let m = &w.machines[0];
    let hits = m.read_static("HITS").expect("HITS");
    for (i, want) in expected.iter().enumerate() {
        let got = u32::from_le_bytes(hits[4 * i..4 * i + 4].try_into().unwrap());
        assert!(*want >= 2, "filter {i}: {want} frames sent");
        assert!(
            got == *want || got + 1 == *want,
            "filter {i}: {got} of {want}"
        );
    }
    assert_eq!(m.read_u32_static("ERRORS"), Some(0));
}

#[test]
fn can1_and_can2_of_one_board_talk() {
    let Some(mut w) = world(500_000, &[(BOARD, "teensy4-can1-can2")]) else {
        return;
    };
    w.run_for(secs(1.0));
    assert_clean(&w);
    let [n1, n2] = app_stats(&w, 0, 2)[..] else {
        unreachable!()
    };
    // 10 ms steps over about a second: each node hears most of the other's heartbeats.
    for (name, s) in [("CAN1", n1), ("CAN2", n2)] {
        assert!(s.sent > 100, "{name}: {s:?}");
        assert!(s.heartbeats > 80, "{name}: {s:?}");
        assert_eq!(s.heartbeat_gaps, 0, "{name}: {s:?}");
        assert!(s.answers > 0 && s.measurements > 0, "{name}: {s:?}");
    }
    assert!(taken(&w, 0, CAN1_IRQ) > 0 && taken(&w, 0, CAN2_IRQ) > 0);
    assert_eq!(
        w.bus
            .trace()
            .records()
            .iter()
            .filter(|r| !r.is_error_free())
            .count(),
        0
    );
}

#[test]
fn async_echo_answers_with_the_identifier_plus_one() {
    let Some(mut w) = world(500_000, &[(BOARD, "teensy4-async-echo")]) else {
        return;
    };
    // The tester's frames, 0x10 apart so that no echo (identifier + 1) is one of them,
    // one every 20 ms in turn.
    let traffic = (0..5u8)
        .map(|i| Frame::standard(0x120 + 0x10 * u16::from(i), &[i]).unwrap())
        .collect();
    w.add_node("tester", SimNode::new(), 500_000, traffic, 20_000_000_000);
    w.run_for(secs(0.5));
    assert_clean(&w);
    let mut total = 0;
    for i in 0..5u32 {
        let id = 0x120 + 0x10 * i;
        let sent = wire_count(&w, |f| raw_id(f) == (id, false));
        let echoed = wire_count(&w, |f| raw_id(f) == (id + 1, false));
        assert!(sent >= 4, "0x{id:X} sent {sent} times");
        assert!(
            echoed == sent || echoed + 1 == sent,
            "0x{id:X}: {echoed} echoes of {sent}"
        );
        total += echoed;
    }
    let counted = w.machines[0].read_u32_static("ECHOED").unwrap();
    assert!(
        counted == total || counted + 1 == total,
        "ECHOED {counted}, {total} on the wire"
    );
}

/// The three `app`s on one bus: the Teensy 4.1 (node 3, listening to node 1), the Teensy
/// 3.6 (node 1, peer 2) and the NUCLEO-F767ZI (node 2, peer 1), with the demo's other
/// node; every node's counters, wire statistics, filtered and lost frames equal those of
/// the host demo's code path for the same scenario (`common::three`), and each board's
/// counters agree with the frames the bus carried.
const THREE: Three = Three {
    boards: [
        (BOARD, "teensy4-app-node3"),
        ("teensy36", "teensy-app"),
        ("nucleo-f767zi", "stm32f7-app"),
    ],
    nodes: [(3, 1), (1, 2), (2, 1)],
};

#[test]
fn three_boards_count_what_the_host_demo_counts() {
    let Some((fil, w)) = three::firmware_counts_what_the_host_counts(&THREE) else {
        return;
    };
    assert_eq!(
        w.bus
            .trace()
            .records()
            .iter()
            .filter(|r| !r.is_error_free())
            .count(),
        0,
        "no error frame"
    );
    let [t41, t36, stm] = fil.apps;
    let heartbeats =
        |node: u32| wire_count(&w, |f| raw_id(f) == (0x100 + node, false) && !is_remote(f));
    // Each node counts the heartbeats of its peer that the bus carried (the last one may
    // arrive after the node's last step).
    for (name, s, peer) in [
        ("teensy41", t41, 1),
        ("teensy36", t36, 2),
        ("nucleo", stm, 1),
    ] {
        let on_wire = heartbeats(peer);
        assert!(on_wire > 140, "{name}: {on_wire} heartbeats of node {peer}");
        assert!(
            s.heartbeats == on_wire || s.heartbeats + 1 == on_wire,
            "{name}: {s:?}, {on_wire} on the wire"
        );
        assert_eq!(
            s.heartbeat_gaps + s.heartbeat_duplicates,
            0,
            "{name}: {s:?}"
        );
        assert_eq!(s.unhandled, 0, "{name}: {s:?}");
        assert!(s.answers >= 10, "{name}: {s:?}");
    }
    // Node 1 is asked by nodes 2 and 3, node 2 by node 1, node 3 by nobody.
    assert!(t36.requests >= 2 * 10, "{fil:?}");
    assert!(stm.requests >= 10, "{fil:?}");
    assert_eq!(t41.requests, 0, "{fil:?}");
    assert!(fil.wire[3].sent >= 290, "{fil:?}");
    // The Teensy 4.1 sent its own heartbeats (0x103) and measurements, all acknowledged.
    let own = wire_count(&w, |f| {
        let (id, ext) = raw_id(f);
        (!ext && id == 0x103) || (ext && id == 0x18FF_0300)
    });
    assert!(heartbeats(3) > 140);
    assert!(
        t41.sent >= own && own > 0,
        "{t41:?}: {own} of its frames on the wire"
    );
}

#[test]
fn the_app_alone_has_no_stuck_interrupt() {
    let Some(mut w) = world(500_000, &[(BOARD, "teensy4-app")]) else {
        return;
    };
    w.run_for(secs(0.3));
    assert!(w.machines[0].board().stuck.is_empty());
    assert_clean(&w);
    assert!(app_stats(&w, 0, 1)[0].sent > 0);
    assert!(taken(&w, 0, CAN1_IRQ) > 0);
}

#[test]
fn a_peer_at_the_wrong_bit_rate_gives_error_frames_and_error_states() {
    let run = |rate: u32| {
        let mut w = world(500_000, &[(BOARD, "teensy4-app")])?;
        let traffic = vec![Frame::standard(0x300, &[1, 2, 3, 4]).unwrap()];
        w.add_node("peer", SimNode::new(), rate, traffic, 2_000_000_000);
        w.run_for(secs(0.4));
        Some(w)
    };
    let Some(ok) = run(500_000) else {
        return;
    };
    assert!(
        ok.changes.iter().all(|c| c.at_us < 50_000),
        "{:?}",
        ok.changes
    );
    let bad = run(250_000).unwrap();
    assert!(bad.nodes[0].misclocked);
    let errors = bad
        .bus
        .trace()
        .records()
        .iter()
        .filter(|r| !r.is_error_free())
        .count();
    assert!(errors > 100, "{errors} error frames");
    let name = &bad.attached[0].name;
    assert!(
        bad.changes
            .iter()
            .any(|c| &c.node == name && c.to != "error-active"),
        "{:?}",
        bad.changes
    );
    assert!(bad.machines[0].read_u32_static("STATE_CHANGES").unwrap() > 0);
    assert!(bad.machines[0].board().faults.is_empty());
}
