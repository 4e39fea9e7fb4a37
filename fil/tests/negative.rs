//! Tests that prove the harness can fail: a firmware that skips a clock gate faults
//! with its PC reported; one that enables a CAN interrupt with its cause pending and a
//! handler that does not clear it is caught as a stuck interrupt; a node or a second
//! board at the wrong bit rate produces error frames and error-state changes.

mod common;

use common::*;
use twocan_core::Frame;
use twocan_fil::nvic::exc;
use twocan_sim::SimNode;

/// The address of the single `LDR` from `base` in function `reset`: found by running
/// rather than by decoding, the test checks the reported PC lies inside `reset`.
fn reset_range(w: &twocan_fil::world::World<'_>) -> std::ops::Range<u32> {
    let s = w.machines[0].image.symbol("reset").expect("reset symbol");
    let start = s.address & !1;
    start..start + s.size as u32
}

#[test]
fn touching_can_registers_with_the_clock_gated_faults_with_the_pc() {
    for (board, bin, base) in [
        ("teensy36", "kinetis-gate", 0x4002_4000),
        ("teensy32", "kinetis-gate", 0x4002_4000),
        ("nucleo-f767zi", "stm32-gate", 0x4000_6400),
        ("disco-f746g", "stm32-gate", 0x4000_6400),
    ] {
        let Some(mut w) = world(500_000, &[(board, &format!("../negative/{bin}"))]) else {
            return;
        };
        w.run_for(secs(0.005));
        assert!(!w.clean(), "{board}");
        let b = w.machines[0].board();
        assert_eq!(b.faults.len(), 1, "{board}: {:?}", b.faults);
        let f = &b.faults[0];
        assert_eq!(f.address, Some(base), "{board}");
        assert!(
            reset_range(&w).contains(&f.pc),
            "{board}: PC 0x{:08X}",
            f.pc
        );
        // The instruction at the PC is the load (Thumb LDR immediate, 0x68xx).
        let insn = w.machines[0].read_memory(f.pc, 2).unwrap();
        assert_eq!(insn[1] & 0xF8, 0x68, "{board}: {insn:02X?}");
        assert!(f.kind.contains("clock gated"), "{}", f.kind);
        if board.starts_with("teensy") {
            // Kinetis: a bus error; BusFault is disabled out of reset, so HardFault.
            assert_eq!(f.taken_as, Some(exc::HARD_FAULT), "{board}");
            assert!(!f.silent);
            assert_eq!(b.taken.get(&exc::HARD_FAULT), Some(&1));
            assert!(
                b.console.contains("fault handler"),
                "{board}: {:?}",
                b.console
            );
            assert!(!b.console.contains("no fault"), "{board}");
        } else {
            // STM32: no bus error, the read gives 0 and the firmware goes on.
            assert_eq!(f.taken_as, None, "{board}");
            assert!(f.silent);
            assert!(b.taken.is_empty(), "{board}: {:?}", b.taken);
            assert!(
                b.console.contains("the read returned"),
                "{board}: {:?}",
                b.console
            );
        }
    }
}

#[test]
fn an_interrupt_whose_cause_is_never_cleared_is_reported_stuck() {
    for (board, bin, irq) in [
        ("teensy36", "kinetis-stuck", 75),
        ("nucleo-f767zi", "stm32-stuck", 19),
    ] {
        let Some(mut w) = world(500_000, &[(board, &format!("../negative/{bin}"))]) else {
            return;
        };
        w.run_for(secs(0.01));
        assert!(!w.clean(), "{board}");
        let b = w.machines[0].board();
        assert!(b.faults.is_empty(), "{board}: {:?}", b.faults);
        assert_eq!(b.stuck.len(), 1, "{board}");
        assert_eq!(b.stuck[0].exception, 16 + irq);
        assert!(
            b.console.contains("enabling IRQ"),
            "{board}: {:?}",
            b.console
        );
        assert!(!b.console.contains("back in thread mode"), "{board}");
    }
}

#[test]
fn the_example_apps_do_not_have_a_stuck_interrupt() {
    // The same detector on the real firmware: an `app` alone on the bus (no peer: error
    // interrupts and retransmissions) is not flagged.
    for (board, bin) in [("teensy36", "teensy-app"), ("nucleo-f767zi", "stm32f7-app")] {
        let Some(mut w) = world(500_000, &[(board, bin)]) else {
            return;
        };
        w.run_for(secs(0.3));
        assert!(w.machines[0].board().stuck.is_empty(), "{board}");
        // Not vacuous: the run is clean, the firmware reached its application steps
        // (frames sent, `STATS`) and took CAN interrupts.
        assert_clean(&w);
        let stats = app_stats(&w, 0, 1)[0];
        assert!(stats.sent > 0, "{board}: {stats:?}");
        let b = w.machines[0].board();
        let can_irqs: u64 = b.cans[0]
            .instance
            .irqs
            .iter()
            .map(|(_, line)| b.irq_taken(*line))
            .sum();
        assert!(
            can_irqs > 0,
            "{board}: no CAN interrupt taken {:?}",
            b.taken
        );
    }
}

fn mismatch(board: &str, bin: &str, node_rate: u32) -> Option<twocan_fil::world::World<'static>> {
    let mut w = world(500_000, &[(board, bin)])?;
    let traffic = vec![Frame::standard(0x300, &[1, 2, 3, 4]).unwrap()];
    w.add_node("peer", SimNode::new(), node_rate, traffic, 2_000_000_000);
    w.run_for(secs(0.4));
    Some(w)
}

#[test]
fn a_node_at_the_wrong_bit_rate_gives_error_frames_and_error_state_changes() {
    for (board, bin) in [("teensy36", "teensy-app"), ("nucleo-f767zi", "stm32f7-app")] {
        // Control: the peer at the bus rate acknowledges everything.
        let Some(ok) = mismatch(board, bin, 500_000) else {
            return;
        };
        let late = |w: &twocan_fil::world::World<'_>| {
            w.bus
                .trace()
                .records()
                .iter()
                .filter(|r| !r.is_error_free() && r.sof > 25_000)
                .count()
        };
        assert_eq!(late(&ok), 0, "{board}: no errors at the right rate");
        assert!(
            ok.changes.iter().all(|c| c.at_us < 50_000),
            "{:?}",
            ok.changes
        );

        // The peer at 250 kbit/s on a 500 kbit/s bus.
        let bad = mismatch(board, bin, 250_000).unwrap();
        assert!(bad.nodes[0].misclocked);
        assert!(late(&bad) > 100, "{board}: error frames");
        let board_node = &bad.attached[0].name;
        let change = bad
            .changes
            .iter()
            .find(|c| &c.node == board_node && c.to != "error-active");
        assert!(change.is_some(), "{board}: {:?}", bad.changes);
        let (tec, rec) = bad.machines[0].board().cans[0].model.counters();
        assert_ne!(
            twocan_fil::world::error_state(tec, rec),
            "error-active",
            "{board}: TEC {tec} REC {rec}"
        );
        // Nothing the board sent got through.
        let s = bad.bus.node_stats(bad.attached[0].node).unwrap();
        assert_eq!(s.sent, 0, "{board}: {s:?}");
        assert!(s.tx_errors > 0 && s.rx_errors > 0, "{board}: {s:?}");
        // The candump trace shows the error frames.
        assert!(
            bad.candump().contains("20000"),
            "SocketCAN error frames in the trace"
        );
        // Nothing else went wrong: no fault, no stuck line, no livelock, no unknown
        // register, no rule violation — the firmware copes with a bad bus — and the
        // control ran as clean.
        assert_clean(&bad);
        assert_clean(&ok);
    }
}

/// Two boards on one bus, one at the wrong bit rate: the Teensy 3.6 `app` at 500 kbit/s
/// and the NUCLEO-F767ZI `app` built with `bus-250k`. The bus carries error frames and
/// both firmwares' drivers report error-state changes (`STATE_CHANGES`, `WORST_STATE`);
/// the same pair at the right rate (control) stays error active after both joined.
#[test]
fn two_boards_at_different_bit_rates_give_error_frames_and_error_state_changes() {
    let teensy = ("teensy36", "teensy-app");
    let run = |stm32_bin: &str| {
        let mut w = world(500_000, &[teensy, ("nucleo-f767zi", stm32_bin)])?;
        w.run_for(secs(0.4));
        Some(w)
    };
    let Some(ok) = run("stm32f7-app") else {
        return;
    };
    let Some(bad) = run("stm32f7-app-250k") else {
        return;
    };
    // Both boards joined 16 ms into the run at the latest.
    let late = |w: &twocan_fil::world::World<'_>| {
        w.bus
            .trace()
            .records()
            .iter()
            .filter(|r| !r.is_error_free() && r.sof > 500_000 / 50)
            .count()
    };
    let worst = |w: &twocan_fil::world::World<'_>, i: usize| {
        w.machines[i]
            .read_u32_static("WORST_STATE")
            .expect("WORST_STATE")
    };
    let changes = |w: &twocan_fil::world::World<'_>, i: usize| {
        w.machines[i]
            .read_u32_static("STATE_CHANGES")
            .expect("STATE_CHANGES")
    };

    // The first controller of each board (Teensy 3.6 CAN0, NUCLEO CAN1).
    let first = |w: &twocan_fil::world::World<'_>, i: usize| {
        w.attached
            .iter()
            .find(|a| a.board == i && a.port == 0)
            .cloned()
            .expect("controller")
    };

    // Control: no error frame once both are on the bus, both stay error active.
    assert_clean(&ok);
    assert_eq!(late(&ok), 0, "errors at the right rate");
    assert_eq!(first(&ok, 0).bit_rate, Some(500_000));
    assert_eq!(first(&ok, 1).bit_rate, Some(500_000));
    assert!(ok.attached.iter().all(|a| !a.misclocked));
    for i in 0..2 {
        assert_eq!(worst(&ok, i), 0, "board {i}: error active throughout");
    }

    // The STM32 at 250 kbit/s: the harness decodes its rate from CAN_BTR.
    // Nothing else went wrong: the firmwares cope with a bad bus (no fault, stuck line,
    // livelock, unknown register or rule violation).
    assert_clean(&bad);
    let (teensy_can, stm32_can) = (first(&bad, 0), first(&bad, 1));
    assert_eq!(stm32_can.bit_rate, Some(250_000));
    assert!(stm32_can.misclocked && !teensy_can.misclocked);
    assert!(late(&bad) > 100, "error frames: {}", late(&bad));
    assert!(
        bad.candump().contains("20000"),
        "SocketCAN error frames in the trace"
    );
    // Nothing either board sent got through, and each side saw errors.
    for a in [&teensy_can, &stm32_can] {
        let s = bad.bus.node_stats(a.node).unwrap();
        assert_eq!(s.sent, 0, "{}: {s:?}", a.name);
        assert!(s.tx_errors > 0 && s.rx_errors > 0, "{}: {s:?}", a.name);
    }
    // The error-state change, as each firmware's driver reported it: error passive
    // (2) at least, seen by the harness too.
    for i in 0..2 {
        assert!(changes(&bad, i) >= 1, "board {i}");
        assert!(
            worst(&bad, i) >= 2,
            "board {i}: worst state {}",
            worst(&bad, i)
        );
        let name = &first(&bad, i).name;
        assert!(
            bad.changes
                .iter()
                .any(|c| &c.node == name && c.to != "error-active"),
            "{name}: {:?}",
            bad.changes
        );
    }
}

#[test]
fn a_kinetis_firmware_that_leaves_the_watchdog_alone_is_reset() {
    for board in ["teensy32", "teensy36"] {
        let Some(mut w) = world(500_000, &[(board, "../negative/kinetis-no-wdog")]) else {
            return;
        };
        w.run_for(secs(0.001));
        assert!(!w.clean());
        let b = w.machines[0].board();
        assert_eq!(b.faults.len(), 1, "{board}: {:?}", b.faults);
        assert!(
            b.faults[0]
                .kind
                .contains("WDOG not unlocked within the WCT"),
            "{:?}",
            b.faults
        );
        assert!(b.halted.is_some());
        // Reset at 256 bus clocks (bus = core = 20.97 MHz out of reset): 12.2 µs.
        let at = b.faults[0].at_ns;
        assert!((12_000..=13_000).contains(&at), "{board}: {at} ns");
    }
}

/// The livelock detector (issue 27): an interrupt storm interleaved with SysTick — which
/// defeats the count of consecutive entries of one exception — and a handler that never
/// returns (SysTick still entering and returning) both fail the run, with the exceptions
/// taken over the window.
#[test]
fn a_storm_interleaved_with_systick_is_a_livelock() {
    let Some(mut w) = world(500_000, &[("teensy36", "../negative/kinetis-storm")]) else {
        return;
    };
    w.run_for(secs(0.05));
    assert!(!w.clean());
    let b = w.machines[0].board();
    assert!(b.faults.is_empty(), "{:?}", b.faults);
    // The consecutive-entry detector does not see it: SysTick breaks every run.
    assert!(b.stuck.is_empty(), "{:?}", b.stuck);
    let l = b.livelock.as_ref().expect("livelock reported");
    assert!(
        b.halted
            .as_deref()
            .is_some_and(|h| h.starts_with("livelock")),
        "the board stops at the livelock: {:?}",
        b.halted
    );
    assert_eq!(l.kind, twocan_fil::machine::LivelockKind::NoThreadProgress);
    let window = l.at_ns - l.since_ns;
    assert!(
        (20_000_000..21_000_000).contains(&window),
        "found one quantum after the bound: {l}"
    );
    let count = |e: u32| l.taken.iter().find(|(x, _)| *x == e).map_or(0, |(_, n)| *n);
    let ticks = count(exc::SYSTICK);
    assert!(
        (15..=25).contains(&ticks),
        "SysTick at about 1 kHz over 20 ms: {l}"
    );
    assert!(count(exc::IRQ0 + 75) > 10 * ticks, "{l}");
    assert!(b.console.contains("pending IRQ 75"), "{:?}", b.console);
    assert!(!b.console.contains("back in thread mode"));
    let report = twocan_fil::report::render(&w);
    assert!(
        report.contains("LIVELOCK: no thread-mode progress"),
        "{report}"
    );
    assert!(report.contains("SysTick x"), "{report}");
}

#[test]
fn a_handler_that_never_returns_is_a_livelock() {
    let Some(mut w) = world(500_000, &[("teensy36", "../negative/kinetis-hang")]) else {
        return;
    };
    w.run_for(secs(0.05));
    assert!(!w.clean());
    let b = w.machines[0].board();
    assert!(b.faults.is_empty(), "{:?}", b.faults);
    assert!(b.stuck.is_empty(), "{:?}", b.stuck);
    let l = b.livelock.as_ref().expect("livelock reported");
    assert!(
        b.halted
            .as_deref()
            .is_some_and(|h| h.starts_with("livelock")),
        "the board stops at the livelock: {:?}",
        b.halted
    );
    assert_eq!(
        l.kind,
        twocan_fil::machine::LivelockKind::HandlerNeverReturns {
            exception: exc::IRQ0 + 75
        }
    );
    // SysTick kept preempting it and returning: entries over the window.
    let ticks = l
        .taken
        .iter()
        .find(|(e, _)| *e == exc::SYSTICK)
        .map_or(0, |(_, n)| *n);
    assert!((15..=25).contains(&ticks), "{l}");
    assert_eq!(b.taken.get(&(exc::IRQ0 + 75)), Some(&1), "entered once");
    assert!(b.console.contains("for good"), "{:?}", b.console);
    let report = twocan_fil::report::render(&w);
    assert!(
        report.contains("LIVELOCK: the IRQ 75 handler never returned"),
        "{report}"
    );
}

/// The control: a firmware that sleeps in thread mode between its interrupts is not a
/// livelock however long it sleeps (sleeping in thread mode is waiting, not a lack of
/// progress): the Teensy `loopback` example over 0.1 s.
#[test]
fn sleeping_in_thread_mode_is_not_a_livelock() {
    let Some(mut w) = world(500_000, &[("teensy36", "teensy-loopback")]) else {
        return;
    };
    w.run_for(secs(0.1));
    assert_clean(&w);
    let b = w.machines[0].board();
    assert!(b.idle_cycles > 0, "the firmware sleeps: {}", b.idle_cycles);
}
