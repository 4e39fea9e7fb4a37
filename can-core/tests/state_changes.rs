//! Error-state changes are never lost silently: past the ring's [`STATE_CHANGES`]
//! entries, each further change the thread side has not taken is counted in
//! `TrafficStats::state_change_overflows`, through the split halves and the driver.
#![cfg(feature = "mock")]

use twocan_core::mock::MockHardware;
use twocan_core::split::STATE_CHANGES;
use twocan_core::{Driver, ErrorState, FifoQueue, LastErrorCode, State};

/// Alternates warning and active `n` times (2 n changes), one status interrupt each.
fn alternate(hw: &MockHardware, mut irq: impl FnMut(), n: usize) {
    for _ in 0..n {
        hw.set_status(ErrorState::Warning, 96, 0, LastErrorCode::None);
        irq();
        hw.set_status(ErrorState::Active, 95, 0, LastErrorCode::None);
        irq();
    }
}

#[test]
fn split_halves_count_the_changes_the_ring_cannot_hold() {
    static CAN: State<MockHardware, 8, FifoQueue<4>> = State::new();
    let mut p = CAN.split(MockHardware::new(3)).map_err(|(e, _)| e).unwrap();
    let hw = CAN.hardware().unwrap();
    // 12 changes, none taken: the first 8 stay, 4 are counted as lost.
    alternate(&hw, || p.status_irq.on_interrupt(), 6);
    let t = CAN.traffic();
    assert_eq!(STATE_CHANGES, 8);
    assert_eq!(t.state_changes, 12);
    assert_eq!(t.state_change_overflows, 4);
    let kept: Vec<ErrorState> = core::iter::from_fn(|| p.rx.take_state_change())
        .map(|c| c.state)
        .collect();
    assert_eq!(kept.len(), STATE_CHANGES);
    // The oldest eight, in order.
    for (i, s) in kept.iter().enumerate() {
        let want = if i % 2 == 0 {
            ErrorState::Warning
        } else {
            ErrorState::Active
        };
        assert_eq!(*s, want, "{i}");
    }
    // Taken in time, nothing more is lost.
    hw.set_status(ErrorState::Warning, 100, 0, LastErrorCode::None);
    p.status_irq.on_interrupt();
    assert_eq!(
        p.rx.take_state_change().map(|c| (c.state, c.counters.tec)),
        Some((ErrorState::Warning, 100))
    );
    assert_eq!(CAN.traffic().state_change_overflows, 4);
    assert_eq!(CAN.traffic().state_changes, 13);
}

#[test]
fn the_driver_reports_the_same_count() {
    let mut can: Driver<MockHardware, 8, 4> = Driver::new(MockHardware::new(3));
    for _ in 0..5 {
        can.hardware()
            .set_status(ErrorState::Warning, 96, 0, LastErrorCode::None);
        can.on_status();
        can.hardware()
            .set_status(ErrorState::Active, 95, 0, LastErrorCode::None);
        can.on_status();
    }
    assert_eq!(can.traffic().state_changes, 10);
    assert_eq!(can.traffic().state_change_overflows, 2);
    let n = core::iter::from_fn(|| can.take_state_change()).count();
    assert_eq!(n, STATE_CHANGES);
}
