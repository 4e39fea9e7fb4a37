//! Races through the real driver over the model (the model is not atomic:
//! `Bus::run_bits` stops inside a frame, so driver register accesses interleave with the
//! frame on the wire), and the one-shot failure causes.
//!
//! - Abort (RM0410 §40.7.3 "Transmit handling", "Abort"): `ABRQx` on a mailbox in
//!   transmit state waits for the outcome; `TXOKx` with `RQCPx` tells whether the frame
//!   was sent. The driver must take the outcome from `TXOKx`, not from having aborted.
//! - One-shot mode (`NART`): a failed attempt ends the request with `ALSTx` (arbitration
//!   lost) or `TERRx` (transmission error) (RM0410 §40.9.2 `CAN_TSR`).
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_core::{AbortRequest, Completion, TxFailure, TxOutcome};

fn completions(d: &mut Drv) -> Vec<Completion> {
    std::iter::from_fn(|| d.take_completion()).collect()
}

/// Runs bit by bit until the bus is inside a frame (bounded).
fn until_in_frame(bus: &SharedBus) {
    for _ in 0..200 {
        if bus.borrow().in_frame() {
            return;
        }
        bus.borrow_mut().run_bits(1);
    }
    panic!("no frame started");
}

#[test]
fn abort_while_the_frame_is_on_the_wire_completes_as_sent() {
    let (can, regs, bus, peer) = can1_and_peer(&config(), &pass_all());
    regs.ticking.set(false); // bus time passes only where the test says
    let mut d = driver(can);
    let f = std(0x321);
    let t = d.try_send(&f).unwrap();
    until_in_frame(&bus);
    bus.borrow_mut().run_bits(20);
    assert!(bus.borrow().in_frame(), "still on the wire");
    assert_eq!(d.abort(t), AbortRequest::Requested);
    settle(&bus);
    d.on_interrupt();
    let done = completions(&mut d);
    assert_eq!(done.len(), 1, "{done:?}");
    assert_eq!((done[0].token, done[0].outcome), (t, TxOutcome::Sent));
    let tr = d.traffic();
    assert_eq!((tr.sent, tr.aborted, tr.failed), (1, 0, 0));
    assert_eq!(peer.borrow().received_frames(), vec![f], "one copy");
    run(&bus, 1_000);
    d.on_interrupt();
    assert_eq!(peer.borrow().received_frames().len(), 1, "not sent again");
}

#[test]
fn abort_before_start_of_frame_completes_as_aborted() {
    let (can, regs, bus, peer) = can1_and_peer(&config(), &pass_all());
    regs.ticking.set(false);
    let mut d = driver(can);
    let t = d.try_send(&std(0x322)).unwrap();
    assert!(!bus.borrow().in_frame());
    assert_eq!(d.abort(t), AbortRequest::Requested);
    settle(&bus);
    d.on_interrupt();
    let done = completions(&mut d);
    assert_eq!(done.len(), 1, "{done:?}");
    assert_eq!((done[0].token, done[0].outcome), (t, TxOutcome::Aborted));
    let tr = d.traffic();
    assert_eq!((tr.sent, tr.aborted), (0, 1));
    assert!(peer.borrow().received_frames().is_empty(), "no copy");
    assert!(
        bus.borrow().trace().records().is_empty(),
        "nothing on the wire"
    );
}

#[test]
fn one_shot_arbitration_loss_is_reported_with_its_cause() {
    let (can, regs, bus, peer) = can1_and_peer(&config().one_shot(true), &pass_all());
    regs.ticking.set(false);
    let mut d = driver(can);
    // Both frames wait for the same start of frame: the peer's lower identifier wins.
    let winner = std(0x050);
    peer.borrow_mut().send(winner);
    let t = d.try_send(&std(0x300)).unwrap();
    settle(&bus);
    d.on_interrupt();
    let done = completions(&mut d);
    assert_eq!(done.len(), 1, "{done:?}");
    assert_eq!((done[0].token, done[0].outcome), (t, TxOutcome::Failed));
    assert_eq!(
        done[0].cause,
        Some(TxFailure::ArbitrationLost),
        "ALST0, not TERR0"
    );
    let tr = d.traffic();
    assert_eq!((tr.sent, tr.failed), (0, 1));
    // Losing arbitration is no error: no counter moved, no error counted.
    assert_eq!(d.counters().tec, 0);
    assert_eq!(d.error_stats().bit, 0);
    // The winner's frame was received; ours was not retried (NART).
    let got = drain(&mut d);
    assert_eq!(
        got.iter().map(|r| r.frame).collect::<Vec<_>>(),
        vec![winner]
    );
    assert_eq!(bus.borrow().trace().records().len(), 1, "only the winner");
}
