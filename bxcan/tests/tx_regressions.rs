//! Regression tests of the transmit path (issues 22 and 26), each against the model on a
//! simulated bus with an acknowledging peer:
//!
//! - identifier priority (TXFP = 0), queue full: a displacement never loses a frame
//!   (issue 22 item 1, issue 26 item 4);
//! - identifier priority: frames of one identifier leave in request order, though the
//!   hardware sends equal identifiers lowest mailbox first (RM0410 §40.7.3 "Transmit
//!   priority"; issue 22 item 2);
//! - `mailbox_state` never names a mailbox transmitting that is not (issue 22 item 4);
//! - the abort of a frame whose displacement abort ended but was not settled yet
//!   (issue 26, found by reading).
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_bxcan::BxCan;
use twocan_core::{Completion, Driver, Frame, Token, TxOutcome, TxPolicy};

/// The frames the peer received, in bus order.
fn wire(peer: &std::rc::Rc<std::cell::RefCell<twocan_core::sim::SimNode>>) -> Vec<Frame> {
    peer.borrow().received_frames()
}

fn completions<const TX: usize>(d: &mut Driver<BxCan<Clocked>, 16, TX, 16>) -> Vec<Completion> {
    std::iter::from_fn(|| d.take_completion()).collect()
}

/// Runs the bus in steps of `bits`, servicing the interrupts after each, `rounds` times.
fn pump<const TX: usize>(
    d: &mut Driver<BxCan<Clocked>, 16, TX, 16>,
    bus: &SharedBus,
    rounds: usize,
    bits: u64,
) {
    for _ in 0..rounds {
        run(bus, bits);
        d.on_interrupt();
    }
    settle(bus);
    d.on_interrupt();
}

#[test]
fn priority_displacement_with_a_full_queue_loses_no_frame() {
    // Issue 22 item 1: a 4-entry queue in identifier priority order, no bus traffic while
    // the frames are submitted.
    let cfg = config().tx_policy(TxPolicy::Priority);
    let (can, regs, bus, peer) = can1_and_peer(&cfg, &pass_all());
    regs.ticking.set(false);
    let mut d: Driver<BxCan<Clocked>, 16, 4, 16> = Driver::new(can.into_split());
    let ids = [0x700u16, 0x701, 0x702, 0x600, 0x5FF, 0x5FE, 0x5FD];
    let tokens: Vec<Token> = ids
        .iter()
        .map(|&id| d.try_send(&std(id)).expect("accepted"))
        .collect();
    regs.ticking.set(true);
    pump(&mut d, &bus, 30, 100);
    let mut sent: Vec<u32> = wire(&peer).iter().map(|f| f.raw_id()).collect();
    sent.sort();
    let mut want: Vec<u32> = ids.iter().map(|&id| id as u32).collect();
    want.sort();
    assert_eq!(sent, want, "every accepted frame on the wire once");
    let done = completions(&mut d);
    let mut got: Vec<Token> = done.iter().map(|c| c.token).collect();
    got.sort();
    assert_eq!(got, tokens, "one completion per token");
    assert!(done.iter().all(|c| c.outcome == TxOutcome::Sent));
    let t = d.traffic();
    assert_eq!((t.queued, t.sent, t.aborted), (7, 7, 0));
    assert_eq!(d.tx_stats().count, 0, "the queue count comes back to 0");
}
