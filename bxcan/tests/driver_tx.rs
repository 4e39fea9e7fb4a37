//! Transmission against the model: both policies (request order vs arbitration priority),
//! displacement of the lowest-priority mailbox without priority inversion, abort,
//! mailbox states, one-shot failures with their cause, tokens and completions.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_core::{
    AbortRequest, Completion, MailboxId, MailboxState, TxFailure, TxOutcome, TxPolicy,
};
use twocan_sim::Fault;

/// The identifiers the peer received, in bus order.
fn order(peer: &std::rc::Rc<std::cell::RefCell<twocan_sim::SimNode>>) -> Vec<u32> {
    peer.borrow()
        .received_frames()
        .iter()
        .map(|f| f.raw_id())
        .collect()
}

fn completions(d: &mut Drv) -> Vec<Completion> {
    std::iter::from_fn(|| d.take_completion()).collect()
}

#[test]
fn request_order_policy_sends_in_submission_order() {
    let cfg = config().tx_policy(TxPolicy::Fifo);
    let (can, regs, bus, peer) = can1_and_peer(&cfg, &pass_all());
    regs.ticking.set(false);
    let mut d = driver(can);
    assert_eq!(d.tx_policy(), TxPolicy::Fifo);
    let mut tokens = Vec::new();
    for id in [0x500, 0x100, 0x300, 0x050, 0x700] {
        tokens.push(d.try_send(&std(id)).unwrap());
    }
    for _ in 0..20 {
        run(&bus, 100);
        d.on_interrupt();
    }
    assert_eq!(order(&peer), [0x500, 0x100, 0x300, 0x050, 0x700]);
    assert_eq!(d.traffic().sent, 5);
    let done = completions(&mut d);
    assert_eq!(done.iter().map(|c| c.token).collect::<Vec<_>>(), tokens);
    assert!(done.iter().all(|c| c.outcome == TxOutcome::Sent));
}

#[test]
fn priority_policy_has_no_priority_inversion() {
    let cfg = config().tx_policy(TxPolicy::Priority);
    let (can, regs, bus, peer) = can1_and_peer(&cfg, &pass_all());
    regs.ticking.set(false); // no bus time while we load the mailboxes
    let mut d = driver(can);
    assert_eq!(d.tx_policy(), TxPolicy::Priority);
    for id in [0x502, 0x500, 0x501] {
        d.try_send(&std(id)).unwrap();
    }
    for m in 0..3 {
        assert_ne!(d.mailbox_state(MailboxId(m)), MailboxState::Empty);
    }
    // All three pending: the high-priority frame displaces the lowest (0x502): the
    // abort of a pending mailbox ends at once, 0x100 takes it, 0x502 waits.
    d.try_send(&std(0x100)).unwrap();
    assert_eq!(
        d.tx_stats().count,
        1,
        "the displaced frame waits in the queue"
    );
    // A frame lower than all three pending waits in the queue.
    d.try_send(&std(0x600)).unwrap();
    for _ in 0..30 {
        run(&bus, 100);
        d.on_interrupt();
    }
    assert_eq!(order(&peer), [0x100, 0x500, 0x501, 0x502, 0x600]);
    let t = d.traffic();
    assert_eq!((t.sent, t.aborted, t.failed), (5, 0, 0));
    assert_eq!(
        completions(&mut d).len(),
        5,
        "the displaced frame completes once"
    );
}

#[test]
fn request_order_policy_never_displaces() {
    let cfg = config().tx_policy(TxPolicy::Fifo);
    let (can, regs, _bus, _peer) = can1_and_peer(&cfg, &pass_all());
    regs.ticking.set(false);
    let mut d = driver(can);
    for id in [0x500, 0x501, 0x502] {
        d.try_send(&std(id)).unwrap();
    }
    d.try_send(&std(0x001)).unwrap();
    assert_eq!(d.tx_stats().count, 1, "queued behind the three");
    for m in 0..3 {
        assert_ne!(d.mailbox_state(MailboxId(m)), MailboxState::Empty);
    }
}

#[test]
fn abort_and_mailbox_states() {
    let cfg = config().tx_policy(TxPolicy::Priority);
    let (can, regs, bus, peer) = can1_and_peer(&cfg, &pass_all());
    regs.ticking.set(false);
    let mut d = driver(can);
    assert_eq!(d.mailbox_state(MailboxId(0)), MailboxState::Empty);
    let t200 = d.try_send(&std(0x200)).unwrap(); // mailbox 0
    let t100 = d.try_send(&std(0x100)).unwrap(); // mailbox 1, first in identifier order
    assert_eq!(d.mailbox_state(MailboxId(1)), MailboxState::Scheduled);
    assert_eq!(d.mailbox_state(MailboxId(0)), MailboxState::Pending);
    assert_eq!(d.mailbox_state(MailboxId(7)), MailboxState::Empty);
    assert_eq!(d.abort(t200), AbortRequest::Requested);
    assert_eq!(d.mailbox_state(MailboxId(0)), MailboxState::Empty);
    settle(&bus);
    d.on_interrupt();
    let done = completions(&mut d);
    assert_eq!(done.len(), 2);
    let of = |t| done.iter().find(|c| c.token == t).unwrap().outcome;
    assert_eq!((of(t100), of(t200)), (TxOutcome::Sent, TxOutcome::Aborted));
    assert_eq!(d.abort(t200), AbortRequest::NotFound, "already ended");
    assert_eq!(order(&peer), [0x100]);
}

#[test]
fn one_shot_failure_is_reported_with_its_cause() {
    let cfg = config().one_shot(true);
    let (can, _regs, bus, peer) = can1_and_peer(&cfg, &pass_all());
    let mut d = driver(can);
    bus.borrow_mut().inject_next(Fault::Bit { at: None });
    let t = d.try_send(&std(0x123)).unwrap();
    settle(&bus);
    d.on_interrupt();
    let done = completions(&mut d);
    assert_eq!(done.len(), 1);
    assert_eq!((done[0].token, done[0].outcome), (t, TxOutcome::Failed));
    assert_eq!(done[0].cause, Some(TxFailure::Error), "TERR0, not ALST0");
    assert_eq!((d.traffic().sent, d.traffic().failed), (0, 1));
    assert_eq!(d.error_stats().bit, 1);
    assert!(order(&peer).is_empty(), "not retransmitted");
    assert_eq!(d.mailbox_state(MailboxId(0)), MailboxState::Empty);
}

/// Puts the scheduled mailbox of `regs` in transmit state, as the bus does when it
/// offers the frame (the abort of a mailbox in transmit state must wait for the bus).
fn offer(regs: &Clocked, bus: &SharedBus) {
    use twocan_sim::BusNode;
    let now = bus.borrow().now();
    let mut model = regs.model.clone();
    assert!(model.poll_tx(now).is_some(), "a frame is offered");
}

#[test]
fn abort_all_drops_an_in_flight_displacement() {
    let cfg = config().tx_policy(TxPolicy::Priority); // TMEIE on (default interrupts)
    let (can, regs, bus, peer) = can1_and_peer(&cfg, &pass_all());
    regs.ticking.set(false);
    let mut d = driver(can);
    d.try_send(&std(0x700)).unwrap(); // mailbox 0
    offer(&regs, &bus); // 0x700 in transmit state: its abort must wait for the bus
    d.try_send(&std(0x600)).unwrap();
    d.try_send(&std(0x650)).unwrap();
    // 0x100 displaces the lowest (0x700, on the bus): the abort is in flight.
    d.try_send(&std(0x100)).unwrap();
    assert_eq!(d.abort_all(), 1, "0x100 dropped from the queue");
    // The bus resolves the abort of the offered mailbox (not started: aborted).
    regs.ticking.set(true);
    for _ in 0..5 {
        run(&bus, 100);
        d.on_interrupt();
    }
    assert!(
        !regs.model.irq_lines().tx,
        "the transmit line is not left asserted"
    );
    for m in 0..3 {
        assert_eq!(d.mailbox_state(MailboxId(m)), MailboxState::Empty);
    }
    // A new frame goes alone: nothing aborted comes back.
    d.try_send(&std(0x050)).unwrap();
    for _ in 0..10 {
        run(&bus, 100);
        d.on_interrupt();
    }
    settle(&bus);
    d.on_interrupt();
    assert_eq!(order(&peer), [0x050]);
    let t = d.traffic();
    assert_eq!((t.sent, t.aborted, t.failed), (1, 4, 0));
    assert_eq!(t.sent + t.aborted + t.failed, t.queued);
    assert_eq!(d.tx_stats().count, 0);
    assert!(!regs.model.irq_lines().tx);
}

#[test]
fn a_displaced_frame_goes_back_to_the_queue_not_lost() {
    let cfg = config().tx_policy(TxPolicy::Priority);
    let (can, regs, bus, peer) = can1_and_peer(&cfg, &pass_all());
    regs.ticking.set(false);
    let mut d = driver(can);
    let low = twocan_core::Frame::extended(0x1FFF_FFFF, &[1, 2, 3, 4, 5, 6, 7, 8]).unwrap();
    d.try_send(&std(0x300)).unwrap();
    let t_low = d.try_send(&low).unwrap();
    d.try_send(&std(0x301)).unwrap();
    // The same identifier as a remote frame loses arbitration to the data frame: it
    // waits, displacing nothing.
    d.try_send(&twocan_core::Frame::remote(0x1FFF_FFFF, true, 0).unwrap())
        .unwrap();
    d.on_interrupt();
    assert_eq!(d.traffic().aborted, 0);
    d.try_send(&std(0x001)).unwrap();
    regs.ticking.set(true);
    for _ in 0..40 {
        run(&bus, 100);
        d.on_interrupt();
    }
    let got: Vec<_> = peer.borrow().received_frames().to_vec();
    assert_eq!(got.iter().filter(|f| **f == low).count(), 1, "sent once");
    let at = |id: u32, remote: bool| {
        got.iter()
            .position(|f| f.raw_id() == id && f.is_remote() == remote)
            .unwrap()
    };
    // The displacement is immediate (the lowest mailbox was pending): 0x001 goes first.
    assert_eq!(at(0x001, false), 0, "{got:?}");
    assert!(at(0x1FFF_FFFF, false) < at(0x1FFF_FFFF, true), "{got:?}");
    let done = completions(&mut d);
    assert_eq!(done.len(), 5);
    assert!(done.iter().all(|c| c.outcome == TxOutcome::Sent));
    assert!(done.iter().any(|c| c.token == t_low));
    assert_eq!(d.traffic().aborted, 0, "displacement is not an abort");
}
