//! The bxCAN examples of the Blue Pill (STM32F103C8, Cortex-M3) and the NUCLEO-F446RE
//! (STM32F446RE, Cortex-M4F), one source (`examples/stm32`), on their board profiles:
//! each example does what its documentation says; the `app`s of a Blue Pill, a
//! NUCLEO-F446RE and a Teensy 3.6 share one bus (issue 23's "How it is checked") and
//! count what the host demo's code path counts for the same scenario; the negative cases
//! (a board at the wrong bit rate; no stuck interrupt on the real firmware) run on the new
//! profiles. The clock-gate and stuck-interrupt firmwares of these profiles are in
//! `tests/profiles.rs`.

mod common;

use common::three::{self, Three};
use common::*;
use twocan_core::Frame;
use twocan_fil::nvic::exc;
use twocan_fil::world::World;
use twocan_sim::SimNode;

const BOARDS: [&str; 2] = ["bluepill", "nucleo-f446re"];

/// The receive FIFO 0 line of the board's CAN1 (the F103's `USB_LP_CAN_RX0`, the F446's
/// `CAN1_RX0`): 20 on both.
fn rx0_taken(w: &World<'_>) -> u64 {
    let b = w.machines[0].board();
    let line = b.cans[0].instance.irqs[1].1;
    b.irq_taken(line)
}

#[test]
fn loopback_frames_come_back() {
    for board in BOARDS {
        let Some(mut w) = world(500_000, &[(board, "stm32-loopback")]) else {
            return;
        };
        w.run_for(secs(3.2));
        assert_clean(&w);
        let m = &w.machines[0];
        assert_eq!(m.read_u32_static("SENT"), Some(3), "{board}");
        assert_eq!(m.read_u32_static("RECEIVED"), Some(3), "{board}");
        // Each frame's withdrawn follower was aborted, and none came back.
        assert_eq!(m.read_u32_static("WITHDRAWN"), Some(3), "{board}");
        assert_eq!(m.read_u32_static("STRAY"), Some(0), "{board}");
        let ticks = m.board().taken.get(&exc::SYSTICK).copied().unwrap_or(0);
        assert!(
            (3_100..=3_200).contains(&ticks),
            "{board}: {ticks} SysTicks"
        );
        assert!(rx0_taken(&w) >= 3, "{board}: {:?}", m.board().taken);
        // The part's line names, from the chip table the profile reads.
        let names: Vec<_> = m.board().cans[0]
            .instance
            .irqs
            .iter()
            .map(|i| i.0)
            .collect();
        let want = if board == "bluepill" {
            "USB_LP_CAN_RX0"
        } else {
            "CAN1_RX0"
        };
        assert_eq!(names[1], want, "{board}");
    }
}

/// `stm32-loopback-lean` (issue 21: fire-and-forget transmit, no statistics, no time
/// stamps, the filter planned at compile time and fixed, CAN1 at its fixed address): the
/// same frames come back as with the default choice, through the same receive line; the
/// transmit line is never taken (the quiet transmit mode: no completion to report, and a
/// frame every second always finds an empty mailbox, so nothing waits in the queue).
#[test]
fn lean_loopback_frames_come_back() {
    for board in BOARDS {
        let Some(mut w) = world(500_000, &[(board, "stm32-loopback-lean")]) else {
            return;
        };
        w.run_for(secs(3.2));
        assert_clean(&w);
        let m = &w.machines[0];
        assert_eq!(m.read_u32_static("SENT"), Some(3), "{board}");
        assert_eq!(m.read_u32_static("RECEIVED"), Some(3), "{board}");
        let ticks = m.board().taken.get(&exc::SYSTICK).copied().unwrap_or(0);
        assert!(
            (3_100..=3_200).contains(&ticks),
            "{board}: {ticks} SysTicks"
        );
        assert!(rx0_taken(&w) >= 3, "{board}: {:?}", m.board().taken);
        let tx_line = m.board().cans[0].instance.irqs[0].1;
        assert_eq!(
            m.board().irq_taken(tx_line),
            0,
            "{board}: {:?}",
            m.board().taken
        );
    }
}

/// `filters`: each frame reaches the call-back of its filter, 0x777 none; on the F103
/// the plan fits its 14 banks.
#[test]
fn filters_deliver_exactly_the_expected_identifiers() {
    for board in BOARDS {
        let Some(mut w) = world(500_000, &[(board, "stm32-filters")]) else {
            return;
        };
        w.run_for(secs(2.05));
        assert_clean(&w);
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
        assert!(count(&|id, ext, _| !ext && id == 0x777) >= 2, "{board}");
        let m = &w.machines[0];
        let hits = m.read_static("HITS").expect("HITS");
        for (i, want) in expected.iter().enumerate() {
            let got = u32::from_le_bytes(hits[4 * i..4 * i + 4].try_into().unwrap());
            assert!(*want >= 2, "{board}: filter {i} frames sent: {want}");
            assert!(
                got == *want || got + 1 == *want,
                "{board}: filter {i}: {got} of {want}"
            );
        }
        assert_eq!(m.read_u32_static("ERRORS"), Some(0), "{board}");
        let banks = m.read_static("BANKS").expect("BANKS");
        let word = |i: usize| u32::from_le_bytes(banks[4 * i..4 * i + 4].try_into().unwrap());
        // Balanced over both FIFOs, within the 14 banks CAN1 owns at reset.
        assert!(word(0) > 0 && word(1) > 0, "{board}: {banks:?}");
        assert!(word(0) + word(1) <= 14, "{board}: {banks:?}");
    }
}

#[test]
fn async_echo_answers_every_frame_with_its_identifier_plus_one() {
    for board in BOARDS {
        let Some(mut w) = world(500_000, &[(board, "stm32-async-echo")]) else {
            return;
        };
        let sent = [
            Frame::standard(0x123, &[1]).unwrap(),
            Frame::extended(0x1234_5678, &[1, 2, 3, 4, 5, 6, 7, 8]).unwrap(),
            Frame::standard(0x7FE, &[]).unwrap(),
        ];
        let tester = w.add_node_from(
            "tester",
            SimNode::new(),
            500_000,
            sent.to_vec(),
            5_000_000_000,
            50_000_000_000,
        );
        w.run_for(secs(0.498));
        assert_clean(&w);
        let records = w.bus.trace().records();
        assert!(records.iter().all(|r| r.is_error_free()), "{board}");
        let (tester_node, board_node) = (w.nodes[0].node, w.attached[0].node);
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
        assert!(rx0_taken(&w) >= 90, "{board}");
    }
}

/// NUCLEO-F446RE `can1-can2`: CAN1 and CAN2 of one chip exchange the application's
/// frames; CAN2's filters live in CAN1's block from bank 14.
#[test]
fn can1_and_can2_of_the_f446_exchange_frames() {
    let Some(mut w) = world(500_000, &[("nucleo-f446re", "stm32-can1-can2")]) else {
        return;
    };
    w.run_for(secs(1.2));
    assert_clean(&w);
    let stats = app_stats(&w, 0, 2);
    let hb = |id: u32| wire_count(&w, |f| raw_id(f) == (id, false) && !is_remote(f));
    assert!(hb(0x101) >= 100 && hb(0x102) >= 100);
    for (a, b, peer_hb) in [(0, 1, hb(0x102)), (1, 0, hb(0x101))] {
        let (a, b) = (stats[a], stats[b]);
        assert_eq!(
            a.heartbeat_gaps + a.heartbeat_duplicates + a.unhandled,
            0,
            "{a:?}"
        );
        assert!(
            a.heartbeats + 1 >= peer_hb && a.heartbeats <= peer_hb,
            "{a:?}"
        );
        assert!(
            a.requests >= 1 && a.answers >= 1 && a.measurements >= 1,
            "{a:?}"
        );
        assert!(b.sent > 0);
    }
    // Both controllers on the wire, CAN2's lines (63..=66) taken.
    assert_eq!(w.attached.len(), 2);
    for a in &w.attached {
        let s = w.bus.node_stats(a.node).unwrap();
        assert!(s.sent >= 100 && s.received >= 100, "{}: {s:?}", a.name);
    }
    let b = w.machines[0].board();
    let can2_lines: u64 = (63..=66).map(|l| b.irq_taken(l)).sum();
    assert!(can2_lines >= 100, "{:?}", b.taken);
}

/// The real `app` firmware alone on the bus (no acknowledgement: error interrupts,
/// retransmissions) is not flagged by the stuck-interrupt detector.
#[test]
fn the_apps_do_not_have_a_stuck_interrupt() {
    for board in BOARDS {
        let Some(mut w) = world(500_000, &[(board, "stm32-app")]) else {
            return;
        };
        w.run_for(secs(0.3));
        assert!(w.machines[0].board().stuck.is_empty(), "{board}");
        assert_clean(&w);
        let stats = app_stats(&w, 0, 1)[0];
        assert!(stats.sent > 0, "{board}: {stats:?}");
    }
}

/// A plain node at 250 kbit/s on the board's 500 kbit/s bus: error frames, the board's
/// controller leaves error active, nothing it sends gets through; at the right rate
/// (control) no error once both are on the bus.
#[test]
fn a_node_at_the_wrong_bit_rate_gives_error_frames_and_error_state_changes() {
    let mismatch = |board: &str, rate: u32| {
        let mut w = world(500_000, &[(board, "stm32-app")])?;
        let traffic = vec![Frame::standard(0x300, &[1, 2, 3, 4]).unwrap()];
        w.add_node("peer", SimNode::new(), rate, traffic, 2_000_000_000);
        w.run_for(secs(0.4));
        Some(w)
    };
    let late = |w: &World<'_>| {
        w.bus
            .trace()
            .records()
            .iter()
            .filter(|r| !r.is_error_free() && r.sof > 25_000)
            .count()
    };
    for board in BOARDS {
        let Some(ok) = mismatch(board, 500_000) else {
            return;
        };
        assert_eq!(late(&ok), 0, "{board}: no errors at the right rate");
        let bad = mismatch(board, 250_000).unwrap();
        assert!(bad.nodes[0].misclocked);
        assert!(late(&bad) > 100, "{board}: error frames");
        let name = &bad.attached[0].name;
        assert!(
            bad.changes
                .iter()
                .any(|c| &c.node == name && c.to != "error-active"),
            "{board}: {:?}",
            bad.changes
        );
        let s = bad.bus.node_stats(bad.attached[0].node).unwrap();
        assert_eq!(s.sent, 0, "{board}: {s:?}");
        assert!(s.tx_errors > 0 && s.rx_errors > 0, "{board}: {s:?}");
        assert!(bad.machines[0].board().faults.is_empty());
        // The firmware's driver reported it too.
        let changes = bad.machines[0].read_u32_static("STATE_CHANGES").unwrap();
        assert!(changes >= 1, "{board}");
    }
}

/// The Blue Pill `app` built for 250 kbit/s (`bus-250k`) with the NUCLEO-F446RE `app` at
/// 500 kbit/s: the harness decodes each board's rate from its `CAN_BTR`, the bus carries
/// error frames and both firmwares' drivers report error passive at least.
#[test]
fn two_stm32_boards_at_different_bit_rates() {
    let Some(mut w) = world(
        500_000,
        &[
            ("nucleo-f446re", "stm32-app"),
            ("bluepill", "stm32-app-250k"),
        ],
    ) else {
        return;
    };
    w.run_for(secs(0.4));
    assert!(w.clean(), "no fault: the firmwares cope with a bad bus");
    let port = |b: usize| w.attached.iter().find(|a| a.board == b).unwrap().clone();
    let (nucleo, bluepill) = (port(0), port(1));
    assert_eq!(nucleo.bit_rate, Some(500_000));
    assert_eq!(bluepill.bit_rate, Some(250_000));
    assert!(bluepill.misclocked && !nucleo.misclocked);
    for (i, a) in [&nucleo, &bluepill].into_iter().enumerate() {
        let s = w.bus.node_stats(a.node).unwrap();
        assert_eq!(s.sent, 0, "{}: {s:?}", a.name);
        assert!(
            w.machines[i].read_u32_static("WORST_STATE").unwrap() >= 2,
            "{}",
            a.name
        );
    }
}

// ---------------------------------------------------------------------------------------
// Three boards on one bus, against the host demo's code path
// ---------------------------------------------------------------------------------------

/// The three boards: the Teensy 3.6 (node 1, peer 2), the NUCLEO-F446RE (node 2, peer 1)
/// and the Blue Pill (node 3, peer 2), as `examples/stm32`'s `Board::app` and the Teensy
/// `app` number them.
const THREE: Three = Three {
    boards: [
        ("teensy36", "teensy-app"),
        ("nucleo-f446re", "stm32-app"),
        ("bluepill", "stm32-app"),
    ],
    nodes: [(1, 2), (2, 1), (3, 2)],
};

/// Issue 23, "How it is checked": the `app` of a Blue Pill, a NUCLEO-F446RE and a Teensy
/// 3.6 on one bus with the demo's other node; every node hears its peer's heartbeats,
/// and the counters equal those of the host demo's code path for the same scenario. The
/// candump trace goes to `FIL_THREE_BOARD_TRACE` when set.
#[test]
fn three_boards_count_what_the_host_demo_counts() {
    let Some((fil, w)) = three::firmware_counts_what_the_host_counts(&THREE) else {
        return;
    };
    if let Some(path) = std::env::var_os("FIL_THREE_BOARD_TRACE") {
        std::fs::write(path, w.candump()).unwrap();
    }
    // Not vacuous: each node counted its peer's heartbeats and got answers to its
    // requests; node 1 is asked by node 2, node 2 by nodes 1 and 3, node 3 by nobody.
    for (b, a) in fil.apps.iter().enumerate() {
        assert!(a.heartbeats >= 140, "board {b}: {a:?}");
        assert!(a.answers >= 10, "board {b}: {a:?}");
        assert_eq!(
            a.heartbeat_gaps + a.heartbeat_duplicates,
            0,
            "board {b}: {a:?}"
        );
    }
    assert!(fil.apps[0].requests >= 10, "{fil:?}");
    assert!(fil.apps[1].requests >= 2 * 10, "{fil:?}");
    assert_eq!(fil.apps[2].requests, 0, "{fil:?}");
    assert!(fil.wire[3].sent >= 290, "{fil:?}");
}
