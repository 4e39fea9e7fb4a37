//! Issue 27: the example `app` firmware under receive backlog and with a CAN interrupt
//! pending before its interrupt start-up, with exact expectations.
//!
//! - Backlog: the harness holds the board's CAN lines low at the NVIC
//!   (`Board::hold_can_lines`: the receive interrupt delayed) while a plain node sends a
//!   burst of the peer's heartbeats (consecutive counters): exactly as many as the
//!   hardware FIFO holds (6 in the FlexCAN Rx FIFO, 3 in a bxCAN FIFO), then three more.
//!   The burst that fits is delivered whole (the application counts every heartbeat, no
//!   gap); the one that does not loses exactly the three the FIFO had no room for (one
//!   gap), the model counts 3 frames lost; the FIFO flags (FlexCAN `IFLAG1.BUF6I` warning
//!   and `BUF7I` overflow, bxCAN `FULL0`/`FOVR0`) were raised and are acknowledged
//!   afterwards; the run stays clean (no livelock: a flag never acknowledged keeps its
//!   line asserted).
//! - Start-up: the core stalls 1.5 ms as its controller joins the bus
//!   (`Board::stall_on_join_ps`) while two heartbeats arrive, so their receive interrupt
//!   is pending when the firmware unmasks its lines; every board's `app` must take it
//!   through its installed handler and count every heartbeat of the run.

mod common;

use common::*;
use twocan_core::Frame;
use twocan_fil::can::Model;
use twocan_fil::world::World;
use twocan_sim::SimNode;

/// The heartbeat the `app` firmware of `board` expects from its peer: the Teensy
/// examples are node 1 (peer 2), the Blue Pill node 3 (peer 2), the other STM32 ones
/// node 2 (peer 1).
fn peer_heartbeat(board: &str) -> u16 {
    if board.starts_with("teensy") || board == "bluepill" {
        0x102
    } else {
        0x101
    }
}

/// The driver's (overruns, FIFO warnings) as the `app` firmware of board 0 published them
/// (`OVERRUNS`, `FIFO_WARNINGS`: `ErrorStatistics` after its last step).
fn driver_fifo_counts(w: &World<'_>) -> (u32, u32) {
    let read = |name: &str| {
        w.machines[0]
            .read_u32_static(name)
            .unwrap_or_else(|| panic!("{name} symbol"))
    };
    (read("OVERRUNS"), read("FIFO_WARNINGS"))
}

fn heartbeat(id: u16, n: u32) -> Frame {
    Frame::standard(id, &n.to_le_bytes()).expect("heartbeat")
}

/// Runs in steps of 20 µs until a controller of board 0 is on the bus (bounded).
fn run_until_joined(w: &mut World<'_>, what: &str) {
    for _ in 0..25_000 {
        if w.attached
            .iter()
            .any(|a| a.board == 0 && a.bit_rate.is_some())
        {
            return;
        }
        w.run_for(20_000_000);
    }
    panic!("{what}: no controller joined the bus within 0.5 s");
}

/// Runs until the plain node has sent everything it holds (bounded by `max_s`).
fn run_until_sent(w: &mut World<'_>, peer: &std::rc::Rc<std::cell::RefCell<SimNode>>, what: &str) {
    for _ in 0..500 {
        if peer.borrow().pending() == 0 {
            return;
        }
        w.run_for(secs(0.0002));
    }
    panic!("{what}: the plain node still had frames to send after 0.1 s");
}

/// The (pending-or-warning, overrun) flags of the receive FIFO of the board's first
/// controller on the bus.
fn fifo_flags(w: &World<'_>) -> (bool, bool, u64) {
    let a = w
        .attached
        .iter()
        .find(|a| a.board == 0 && a.bit_rate.is_some())
        .expect("a controller on the bus");
    let m = &w.machines[0].board().cans[a.port].model;
    let (warn, over) = match m {
        // IFLAG1 (offset 0x30): BUF6I warning, BUF7I overflow.
        Model::FlexCan(f) => {
            let v = f.peek32(0x30);
            (v & (1 << 6) != 0, v & (1 << 7) != 0)
        }
        // CAN_RF0R (0x0C): FULL0 bit 3, FOVR0 bit 4 (reads have no side effect).
        Model::BxCan(_) => {
            let v = m.read32(0x0C);
            (v & (1 << 3) != 0, v & (1 << 4) != 0)
        }
    };
    (warn, over, m.frames_lost())
}

fn backlog(board: &str, bin: &str, depth: usize) {
    let what = format!("{board} {bin}");
    let Some(mut w) = world(500_000, &[(board, bin)]) else {
        return;
    };
    let peer = w.add_node("peer", SimNode::new(), 500_000, Vec::new(), 1);
    let id = peer_heartbeat(board);
    run_until_joined(&mut w, &what);
    w.run_for(secs(0.03));
    let mut n = 0u32;
    // Serviced: a few heartbeats, one at a time.
    for _ in 0..3 {
        peer.borrow_mut().send(heartbeat(id, n));
        n += 1;
        w.run_for(secs(0.002));
    }
    // 1. A burst that fits the FIFO while the lines are held.
    w.machines[0].board_mut().hold_can_lines = true;
    for _ in 0..depth {
        peer.borrow_mut().send(heartbeat(id, n));
        n += 1;
    }
    run_until_sent(&mut w, &peer, &what);
    let (warn, over, lost) = fifo_flags(&w);
    assert!(
        warn,
        "{what}: {depth} frames raise the FIFO warning/full flag"
    );
    assert!(!over, "{what}: {depth} frames fit");
    assert_eq!(lost, 0, "{what}");
    w.machines[0].board_mut().hold_can_lines = false;
    w.run_for(secs(0.03));
    assert_eq!(
        fifo_flags(&w),
        (false, false, 0),
        "{what}: flags acknowledged"
    );
    let s = app_stats(&w, 0, 1)[0];
    assert_eq!(
        (s.heartbeats, s.heartbeat_gaps, s.heartbeat_duplicates),
        (n, 0, 0),
        "{what}: every heartbeat of the burst that fit, in order: {s:?}"
    );
    assert_eq!(
        driver_fifo_counts(&w),
        (0, 1),
        "{what}: the driver counted the warning/full flag once, no overrun"
    );
    // 2. Three more than the FIFO holds.
    w.machines[0].board_mut().hold_can_lines = true;
    for _ in 0..depth + 3 {
        peer.borrow_mut().send(heartbeat(id, n));
        n += 1;
    }
    run_until_sent(&mut w, &peer, &what);
    let (_, over, lost) = fifo_flags(&w);
    assert!(over, "{what}: the overflow flag raised");
    assert_eq!(lost, 3, "{what}: three frames found no room");
    w.machines[0].board_mut().hold_can_lines = false;
    w.run_for(secs(0.03));
    assert_eq!(
        fifo_flags(&w),
        (false, false, 3),
        "{what}: flags acknowledged after the overflow"
    );
    // 3. Serviced again: two more heartbeats.
    for _ in 0..2 {
        peer.borrow_mut().send(heartbeat(id, n));
        n += 1;
        w.run_for(secs(0.002));
    }
    w.run_for(secs(0.03));
    let s = app_stats(&w, 0, 1)[0];
    assert_eq!(
        (s.heartbeats, s.heartbeat_gaps, s.heartbeat_duplicates),
        (n - 3, 1, 0),
        "{what}: all but the three lost, one gap where they were lost: {s:?}"
    );
    assert_eq!(s.unhandled, 0, "{what}");
    assert_eq!(
        driver_fifo_counts(&w),
        (1, 2),
        "{what}: the driver counted one overrun and a second warning/full flag"
    );
    // The plain node's frames were all acknowledged (the board received them on the
    // wire), and the board's run is clean: no fault, no stuck line, no livelock.
    assert_eq!(
        wire_count(&w, |f| raw_id(f) == (u32::from(id), false)),
        n,
        "{what}"
    );
    assert_clean(&w);
}

#[test]
fn flexcan_rx_fifo_backlog_in_the_teensy_app() {
    backlog("teensy36", "teensy-app", 6);
}

#[test]
fn flexcan_rx_fifo_backlog_in_the_teensy41_app() {
    backlog("teensy41", "teensy4-app", 6);
}

#[test]
fn bxcan_fifo_backlog_in_the_stm32_app() {
    backlog("nucleo-f767zi", "stm32f7-app", 3);
}

#[test]
fn bxcan_fifo_backlog_in_the_blue_pill_app() {
    backlog("bluepill", "stm32-app", 3);
}

/// A CAN interrupt pending before `split`/`start` on every board's `app`: one test a
/// family (Teensy 3.x, Teensy 4.1, STM32F7, STM32 F1/F4), so that a start-up bug of one
/// backend fails as many tests as it has families.
#[test]
fn a_receive_interrupt_pending_at_start_up_is_handled_on_the_teensy3_boards() {
    pending_at_start_up(&[
        ("teensy32", "teensy-app"),
        ("teensy35", "teensy-app"),
        ("teensy36", "teensy-app"),
    ]);
}

#[test]
fn a_receive_interrupt_pending_at_start_up_is_handled_on_the_teensy41() {
    pending_at_start_up(&[("teensy41", "teensy4-app")]);
}

#[test]
fn a_receive_interrupt_pending_at_start_up_is_handled_on_the_stm32f7_boards() {
    pending_at_start_up(&[
        ("nucleo-f767zi", "stm32f7-app"),
        ("disco-f746g", "stm32f7-app"),
    ]);
}

#[test]
fn a_receive_interrupt_pending_at_start_up_is_handled_on_the_stm32_f1_f4_boards() {
    pending_at_start_up(&[("bluepill", "stm32-app"), ("nucleo-f446re", "stm32-app")]);
}

/// The start-up scenario on each `(board, app)`.
fn pending_at_start_up(boards: &[(&str, &str)]) {
    for &(board, bin) in boards {
        let what = format!("{board} {bin}");
        let Some(mut w) = world(500_000, &[(board, bin)]) else {
            return;
        };
        w.machines[0].board_mut().stall_on_join_ps = Some(secs(0.0015));
        let peer = w.add_node("peer", SimNode::new(), 500_000, Vec::new(), 1);
        let id = peer_heartbeat(board);
        run_until_joined(&mut w, &what);
        // Two frames during the stall (about 0.25 ms each): the receive line is
        // asserted before the firmware unmasks it.
        peer.borrow_mut().send(heartbeat(id, 0));
        peer.borrow_mut().send(heartbeat(id, 1));
        w.run_for(secs(0.0012));
        let b = w.machines[0].board();
        let lines: Vec<u32> = b
            .cans
            .iter()
            .flat_map(|p| p.instance.irqs.iter().map(|(_, irq)| *irq))
            .collect();
        assert!(
            lines.iter().any(|irq| b.nvic.level(*irq)),
            "{what}: a CAN line asserted during the stall"
        );
        let mut n = 2u32;
        for _ in 0..40 {
            peer.borrow_mut().send(heartbeat(id, n));
            n += 1;
            w.run_for(secs(0.002));
        }
        w.run_for(secs(0.03));
        assert_clean(&w);
        let s = app_stats(&w, 0, 1)[0];
        assert_eq!(
            (
                s.heartbeats,
                s.heartbeat_gaps,
                s.heartbeat_duplicates,
                s.unhandled
            ),
            (n, 0, 0, 0),
            "{what}: {s:?}"
        );
        assert_eq!(
            wire_count(&w, |f| raw_id(f) == (u32::from(id), false)),
            n,
            "{what}"
        );
    }
}
