//! Transmission against the model: both policies (request order vs arbitration priority),
//! displacement of the lowest-priority mailbox without priority inversion, abort,
//! mailbox states, one-shot failures.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_core::sim::Fault;
use twocan_core::{Controller, Driver, Frame, MailboxId, MailboxState, TxPolicy};

/// The identifiers the peer received, in bus order.
fn order(peer: &std::rc::Rc<std::cell::RefCell<twocan_core::sim::SimNode>>) -> Vec<u32> {
    peer.borrow()
        .received_frames()
        .iter()
        .map(|f| f.raw_id())
        .collect()
}

#[test]
fn request_order_policy_sends_in_submission_order() {
    let cfg = config().tx_policy(TxPolicy::Fifo);
    let (can, regs, bus, peer) = can1_and_peer(&cfg, &pass_all());
    regs.ticking.set(false);
    let mut d: Driver<_, 8, 8> = Driver::new(can);
    assert_eq!(d.tx_policy(), TxPolicy::Fifo);
    for id in [0x500, 0x100, 0x300, 0x050, 0x700] {
        d.try_send(&std(id)).unwrap();
    }
    for _ in 0..20 {
        run(&bus, 100);
        d.on_interrupt();
    }
    assert_eq!(order(&peer), [0x500, 0x100, 0x300, 0x050, 0x700]);
    assert_eq!(d.traffic().sent, 5);
}

#[test]
fn priority_policy_has_no_priority_inversion() {
    let cfg = config().tx_policy(TxPolicy::Priority);
    let (can, regs, bus, peer) = can1_and_peer(&cfg, &pass_all());
    regs.ticking.set(false); // no bus time while we load the mailboxes
    let mut d: Driver<_, 8, 8> = Driver::new(can);
    assert_eq!(d.tx_policy(), TxPolicy::Priority);
    for id in [0x502, 0x500, 0x501] {
        d.try_send(&std(id)).unwrap();
    }
    for m in 0..3 {
        assert_ne!(d.mailbox_state(MailboxId(m)), MailboxState::Empty);
    }
    // All three pending: the high-priority frame displaces the lowest (0x502).
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
}

#[test]
fn displacement_returns_the_frame_read_back_from_the_mailbox() {
    let cfg = config().tx_policy(TxPolicy::Priority);
    let (mut can, regs, _bus, _peer) = can1_and_peer(&cfg, &pass_all());
    regs.ticking.set(false);
    let low = Frame::extended(0x1FFF_FFFF, &[1, 2, 3, 4, 5, 6, 7, 8]).unwrap();
    assert_eq!(can.transmit(&std(0x300)), Ok(None));
    assert_eq!(can.transmit(&low), Ok(None));
    assert_eq!(can.transmit(&std(0x301)), Ok(None));
    // The same identifier as a remote frame loses arbitration to the data frame.
    let remote = Frame::remote(0x1FFF_FFFF, true, 0).unwrap();
    assert_eq!(can.transmit(&remote), Err(nb::Error::WouldBlock));
    assert_eq!(can.transmit(&std(0x001)), Ok(Some(low)));
    // Not counted as an abort: the frame is handed back, not lost.
    assert_eq!(can.take_events().aborted, 0);
}

#[test]
fn request_order_policy_never_displaces() {
    let cfg = config().tx_policy(TxPolicy::Fifo);
    let (mut can, regs, _bus, _peer) = can1_and_peer(&cfg, &pass_all());
    regs.ticking.set(false);
    for id in [0x500, 0x501, 0x502] {
        assert_eq!(can.transmit(&std(id)), Ok(None));
    }
    assert_eq!(can.transmit(&std(0x001)), Err(nb::Error::WouldBlock));
}

#[test]
fn abort_and_mailbox_states() {
    let cfg = config().tx_policy(TxPolicy::Priority);
    let (mut can, regs, bus, peer) = can1_and_peer(&cfg, &pass_all());
    regs.ticking.set(false);
    assert_eq!(can.mailbox_state(MailboxId(0)), MailboxState::Empty);
    can.transmit(&std(0x200)).unwrap(); // mailbox 0
    can.transmit(&std(0x100)).unwrap(); // mailbox 1, first in identifier order
    assert_eq!(can.mailbox_state(MailboxId(1)), MailboxState::Scheduled);
    assert_eq!(can.mailbox_state(MailboxId(0)), MailboxState::Pending);
    assert_eq!(can.mailbox_state(MailboxId(7)), MailboxState::Empty);
    assert!(can.abort(MailboxId(0)));
    assert!(!can.abort(MailboxId(0)), "already empty");
    assert!(!can.abort(MailboxId(9)), "no such mailbox");
    assert_eq!(can.mailbox_state(MailboxId(0)), MailboxState::Empty);
    settle(&bus);
    let ev = can.take_events();
    assert_eq!((ev.sent, ev.aborted), (1, 1));
    assert_eq!(order(&peer), [0x100]);
}

#[test]
fn one_shot_failure_is_reported() {
    let cfg = config().one_shot(true);
    let (mut can, _regs, bus, peer) = can1_and_peer(&cfg, &pass_all());
    bus.borrow_mut().inject_next(Fault::Bit { at: None });
    can.transmit(&std(0x123)).unwrap();
    settle(&bus);
    let ev = can.take_events();
    assert_eq!((ev.sent, ev.failed), (0, 1));
    assert!(ev.bus_error.is_some());
    assert!(order(&peer).is_empty(), "not retransmitted");
    assert_eq!(can.mailbox_state(MailboxId(0)), MailboxState::Empty);
}

/// Puts the scheduled mailbox of `regs` in transmit state, as the bus does when it
/// offers the frame (the abort of a mailbox in transmit state must wait for the bus).
fn offer(regs: &Clocked, bus: &SharedBus) {
    use twocan_core::sim::BusNode;
    let now = bus.borrow().now();
    let mut model = regs.model.clone();
    assert!(model.poll_tx(now).is_some(), "a frame is offered");
}

#[test]
fn abort_all_drops_an_in_flight_displacement() {
    let cfg = config().tx_policy(TxPolicy::Priority); // TMEIE on (default interrupts)
    let (can, regs, bus, peer) = can1_and_peer(&cfg, &pass_all());
    regs.ticking.set(false);
    let mut d: Driver<_, 8, 8> = Driver::new(can);
    d.try_send(&std(0x700)).unwrap(); // mailbox 0
    offer(&regs, &bus); // 0x700 in transmit state: its abort must wait for the bus
    d.try_send(&std(0x600)).unwrap();
    d.try_send(&std(0x650)).unwrap();
    // 0x100 displaces the lowest (0x700, on the bus): the abort is in flight.
    d.try_send(&std(0x100)).unwrap();
    assert_eq!(d.tx_stats().count, 1, "0x100 waits for the displacement");
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
    assert_eq!(d.tx_stats().count, 0);
    assert!(!regs.model.irq_lines().tx);
}

#[test]
fn a_parked_displacement_does_not_hold_the_transmit_line() {
    // The displacement ends while no transmit is waiting for it: RQCPx is acknowledged
    // at once, the frame read back stays parked and comes back from the next transmit.
    let cfg = config().tx_policy(TxPolicy::Priority);
    let (mut can, regs, bus, _peer) = can1_and_peer(&cfg, &pass_all());
    regs.ticking.set(false);
    can.transmit(&std(0x700)).unwrap();
    offer(&regs, &bus);
    can.transmit(&std(0x600)).unwrap();
    can.transmit(&std(0x650)).unwrap();
    assert_eq!(can.transmit(&std(0x100)), Err(nb::Error::WouldBlock));
    // The next bus poll finds the offered frame not started: the abort takes effect.
    {
        use twocan_core::sim::BusNode;
        let mut model = regs.model.clone();
        let now = bus.borrow().now();
        let _ = model.poll_tx(now);
    }
    assert_eq!(can.mailbox_state(MailboxId(0)), MailboxState::Empty);
    let ev = can.take_events();
    assert_eq!((ev.sent, ev.aborted, ev.failed), (0, 0, 0));
    assert!(!regs.model.irq_lines().tx);
    // Handed back, not lost, not counted as aborted.
    assert_eq!(can.transmit(&std(0x100)), Ok(Some(std(0x700))));
    assert_eq!(can.take_events().aborted, 0);
}
