//! Issue 6, item 1: the portable application (`twocan_app::App`, the module the Teensy and
//! STM32 firmware examples run) on a FlexCAN node and a bxCAN node on one bus. They
//! exchange standard (heartbeat, status answer), extended (measurement) and remote
//! (status request) frames through the same portable filter list and dispatch by filter
//! index. Expected counts follow from the application's schedule: per 1 ms period one
//! heartbeat, a measurement every 4th, a remote status request every 10th.

use twocan_app::AppStats;
use twocan_sim::{FaultKind, RandomFaults, TxResult};
use twocan_tests::app_bus::{run_apps, AppBus};

const RATE: u32 = 500_000;
/// Periods: the last status request (period 1000) is answered in 1001 and handled by
/// the asking node in 1002, within the run.
const PERIODS: u32 = 1003;

/// Frames the other ECU got acknowledged.
fn other_sent(b: &AppBus) -> u64 {
    b.other
        .borrow()
        .tx_reports()
        .iter()
        .filter(|r| r.result == TxResult::Acked)
        .count() as u64
}

fn exact_schedule(s: &AppStats, periods: u32, who: &str) {
    assert_eq!(s.tx_full, 0, "{who}: {s:?}");
    assert_eq!(
        s.heartbeats, periods,
        "{who}: one heartbeat per period: {s:?}"
    );
    assert_eq!(s.heartbeat_gaps, 0, "{who}: {s:?}");
    assert_eq!(s.heartbeat_duplicates, 0, "{who}: {s:?}");
    assert_eq!(s.measurements, periods / 4, "{who}: {s:?}");
    assert_eq!(s.requests, periods / 10, "{who}: {s:?}");
    assert_eq!(
        s.answers,
        periods / 10,
        "{who}: every request answered: {s:?}"
    );
    assert_eq!(s.unhandled, 0, "{who}: {s:?}");
}

#[test]
fn app_on_flexcan_and_bxcan_exchanges_every_frame_kind() {
    let b = run_apps(RATE, PERIODS, None);
    exact_schedule(&b.teensy_app.stats(), PERIODS, "Teensy (FlexCAN)");
    exact_schedule(&b.stm32_app.stats(), PERIODS, "STM32 (bxCAN)");
    // Each node queued, per period, a heartbeat, plus measurements, requests, answers;
    // every frame went out and was taken by the other node's filters.
    let per_node = PERIODS + PERIODS / 4 + 2 * (PERIODS / 10);
    assert_eq!(b.teensy_queued, per_node);
    assert_eq!(b.stm32_queued, per_node);
    let (t, s) = (b.teensy.driver.traffic(), b.stm32.driver.traffic());
    assert_eq!(t.sent, per_node, "{t:?}");
    assert_eq!(s.sent, per_node, "{s:?}");
    assert_eq!(
        t.received, s.sent,
        "every bxCAN frame reached the FlexCAN application"
    );
    assert_eq!(
        s.received, t.sent,
        "every FlexCAN frame reached the bxCAN application"
    );
    // The other ECU's frames: acknowledged on the bus, refused by both filter lists.
    let other = other_sent(&b);
    assert_eq!(other, u64::from(PERIODS.div_ceil(5)));
    assert_eq!(b.teensy.filtered_out(), other);
    assert_eq!(b.stm32.filtered_out(), other);
    assert_eq!((b.teensy.lost(), b.stm32.lost()), (0, 0));
    // The sniffer saw all three kinds on the wire, and nothing else.
    let seen = b.sniffer.borrow().received_frames();
    assert_eq!(seen.len() as u64, u64::from(t.sent + s.sent) + other);
    let remotes = seen.iter().filter(|f| f.is_remote()).count() as u32;
    let extended = seen
        .iter()
        .filter(|f| f.is_extended() && !f.is_remote())
        .count() as u32;
    assert!(remotes >= 2 * (PERIODS / 10));
    assert!(extended >= 2 * (PERIODS / 4));
    assert!(b
        .h
        .bus()
        .borrow()
        .trace()
        .records()
        .iter()
        .all(|r| r.is_error_free()));
}

#[test]
fn app_survives_random_bus_errors_without_gaps() {
    // 3 % of the frame attempts hit by a random error of any kind (seeded): frames are
    // retransmitted, so nothing is missing; a double reception (error in the last but one
    // EOF bit) is seen as a duplicate, not as a new heartbeat.
    let faults = RandomFaults::new(0x5EED_0006, 0.03).with_kinds(&[
        FaultKind::Bit,
        FaultKind::Stuff,
        FaultKind::Crc,
        FaultKind::Form,
        FaultKind::Ack,
    ]);
    let b = run_apps(RATE, PERIODS, Some(faults));
    let records = b.h.bus().borrow().trace().records().len();
    let errored =
        b.h.bus()
            .borrow()
            .trace()
            .records()
            .iter()
            .filter(|r| !r.is_error_free())
            .count();
    assert!(
        errored * 100 > records,
        "faults were injected: {errored}/{records}"
    );
    println!("{errored} of {records} attempts errored");
    for (s, who) in [
        (b.teensy_app.stats(), "Teensy (FlexCAN)"),
        (b.stm32_app.stats(), "STM32 (bxCAN)"),
    ] {
        assert_eq!(s.tx_full, 0, "{who}: {s:?}");
        assert_eq!(s.heartbeat_gaps, 0, "{who}: {s:?}");
        assert_eq!(
            s.heartbeats - s.heartbeat_duplicates,
            PERIODS,
            "{who}: {s:?}"
        );
        // Measurements carry no sequence number: a double reception counts twice.
        assert!(s.measurements >= PERIODS / 4, "{who}: {s:?}");
        println!("{who}: {s:?}");
        assert!(s.requests >= PERIODS / 10, "{who}: {s:?}");
        assert!(s.answers >= PERIODS / 10, "{who}: {s:?}");
        assert_eq!(s.unhandled, 0);
    }
    for (t, lost, who) in [
        (b.teensy.driver.traffic(), b.teensy.lost(), "FlexCAN"),
        (b.stm32.driver.traffic(), b.stm32.lost(), "bxCAN"),
    ] {
        // Every frame the application queued during the run was sent.
        assert_eq!(t.failed + t.aborted, 0, "{who}: {t:?}");
        assert_eq!(lost, 0, "{who}");
    }
    assert_eq!(b.teensy.driver.traffic().sent, b.teensy_queued);
    assert_eq!(b.stm32.driver.traffic().sent, b.stm32_queued);
    let e = b.teensy.driver.error_stats();
    let f = b.stm32.driver.error_stats();
    assert!(
        e.stuff + e.form + e.acknowledge + e.bit + e.crc > 0,
        "{e:?}"
    );
    assert!(
        f.stuff + f.form + f.acknowledge + f.bit + f.crc > 0,
        "{f:?}"
    );
    assert_eq!((e.bus_off, f.bus_off), (0, 0));
}
