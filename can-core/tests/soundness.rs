//! Regression tests of issue 26 ("Soundness first"): what the split driver's safe API
//! must never allow, tried from several threads. Small enough for Miri (`.ci/run` runs
//! this file under it, with several scheduler seeds), which reports a data race where a
//! native run may only see wrong values.

use std::sync::Barrier;

use twocan_core::mock::MockHardware;
use twocan_core::split::State;
use twocan_core::{AnyQueue, FifoQueue, Frame, Hardware, TxPolicy};

/// Rounds of each race: many natively, a few under Miri (each is slow there).
const ROUNDS: usize = if cfg!(miri) { 4 } else { 300 };

/// Item 1: a context that polls `State::hardware()` while another splits never reads a
/// controller that is not written yet (`split` claims, writes, then publishes).
#[test]
fn hardware_is_never_seen_before_it_is_written() {
    for _ in 0..ROUNDS {
        let state: State<MockHardware, 4, FifoQueue<2>> = State::new();
        std::thread::scope(|s| {
            let reader = s.spawn(|| loop {
                if let Some(hw) = state.hardware() {
                    return hw.mailbox_count();
                }
                std::hint::spin_loop();
            });
            let timer = s.spawn(|| {
                // Any context may refresh the time stamps: never before the controller.
                for _ in 0..50 {
                    state.refresh_timestamps();
                    let _ = state.error_status();
                }
            });
            let parts = state.split(MockHardware::new(3)).ok().unwrap();
            assert_eq!(reader.join().unwrap(), 3, "a controller read before it was written");
            timer.join().unwrap();
            drop(parts);
        });
    }
}

/// Found by reading (issue 26): `split` ran `AnyQueue::adopt` before claiming the state,
/// so a losing concurrent `split` could switch the winner's queue to its own order.
#[test]
fn a_losing_split_leaves_the_winners_queue_order_alone() {
    let frame = |id| Frame::standard(id, &[]).unwrap();
    for _ in 0..ROUNDS {
        let state: State<MockHardware, 4, AnyQueue<4>> = State::new();
        let start = Barrier::new(2);
        let both_tried = Barrier::new(2);
        let orders = std::thread::scope(|s| {
            let contender = |policy: TxPolicy| {
                let (state, start, both_tried) = (&state, &start, &both_tried);
                s.spawn(move || {
                    let hw = MockHardware::new(1).with_policy(policy);
                    start.wait();
                    let parts = state.split(hw);
                    both_tried.wait();
                    let mut p = parts.ok()?;
                    // One mailbox: the first frame takes it, the two others queue.
                    for id in [0x300, 0x200, 0x100] {
                        p.tx.try_send(&frame(id)).unwrap();
                    }
                    let hw = state.hardware().unwrap();
                    for _ in 0..4 {
                        hw.complete();
                        p.tx_irq.on_interrupt();
                    }
                    let sent: Vec<u32> = hw.sent().iter().map(|f| f.raw_id()).collect();
                    Some((policy, sent))
                })
            };
            let a = contender(TxPolicy::Fifo);
            let b = contender(TxPolicy::Priority);
            [a.join().unwrap(), b.join().unwrap()]
        });
        let (policy, sent) = orders.into_iter().flatten().next().expect("one split wins");
        let b = sent.iter().position(|&id| id == 0x200).unwrap();
        let c = sent.iter().position(|&id| id == 0x100).unwrap();
        match policy {
            TxPolicy::Fifo => assert!(b < c, "request order lost: {sent:x?}"),
            TxPolicy::Priority => assert!(c < b, "identifier order lost: {sent:x?}"),
        }
    }
}
