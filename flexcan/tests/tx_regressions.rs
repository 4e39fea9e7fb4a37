//! Issue 22 item 3: `try_send` keeps remote frames in request order with data frames
//! (`docs/differences.md`), though they go to other mailboxes (the remote-frame
//! mailboxes) and the module picks among pending mailboxes by identifier, ties lowest
//! mailbox first (Kinetis RM, "Arbitration process", `CTRL1[LBUF]` = 0).
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_core::Frame;
use twocan_flexcan::Settings;
use twocan_sim::SimNode;

/// Submits `frames` through `try_send` (waiting for room as needed) to a peer on the
/// bus and gives what the peer received, in bus order.
fn wire_order(frames: &[Frame]) -> Vec<Frame> {
    let (model, mut can) = begin::<32, 8>(&Settings::new(500_000), &[], &[]).unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    let peer = SimNode::new().shared();
    bus.attach("peer", peer.clone());
    let mut next = 0;
    while next < frames.len() {
        match can.try_send(&frames[next]) {
            Ok(_) => next += 1,
            Err(nb::Error::WouldBlock) => run1(&mut bus, &mut can, 100),
            Err(e) => panic!("{e:?}"),
        }
    }
    run1(&mut bus, &mut can, 5_000);
    let t = can.traffic();
    assert_eq!(
        (t.queued, t.sent),
        (frames.len() as u32, frames.len() as u32)
    );
    let got = peer.borrow().received_frames();
    got
}

#[test]
fn remote_frames_of_one_identifier_leave_in_request_order() {
    let frames: Vec<Frame> = (0..6)
        .map(|k| Frame::remote(0x300, false, k).unwrap())
        .collect();
    assert_eq!(wire_order(&frames), frames);
}

#[test]
fn remote_and_data_frames_leave_in_request_order() {
    let frames = [
        std_data(0x400, &[1]),
        remote(0x100, false),
        std_data(0x050, &[2]),
        remote(0x200, false),
        Frame::remote(0x1234, true, 3).unwrap(),
        std_data(0x7FF, &[3]),
        remote(0x010, false),
        remote(0x020, false),
        std_data(0x001, &[4]),
    ];
    assert_eq!(wire_order(&frames), frames);
}

#[test]
fn try_send_now_still_takes_any_free_remote_mailbox() {
    // ACAN's path is unchanged: remote frames straight to the remote-frame mailboxes
    // (three in the 12/12 configuration), several at once, data frame beside them.
    let (_model, mut can) = begin::<32, 8>(&Settings::new(500_000), &[], &[]).unwrap();
    for k in 0..3 {
        can.try_send_now(&remote(0x500 + k, false)).unwrap();
    }
    assert!(matches!(
        can.try_send_now(&remote(0x5FF, false)),
        Err(nb::Error::WouldBlock)
    ));
    can.try_send_now(&std_data(0x10, &[1])).unwrap();
    // `try_send` waits behind them instead.
    can.try_send(&std_data(0x11, &[2])).unwrap();
    assert_eq!(can.tx_stats().count, 1);
}

/// Runs bit by bit until the bus is inside a frame (bounded).
fn until_in_frame(bus: &mut twocan_sim::Bus) {
    for _ in 0..200 {
        if bus.in_frame() {
            return;
        }
        bus.run_bits(1);
    }
    panic!("no frame started");
}

#[test]
fn an_abort_requested_during_arbitration_takes_effect_after_the_loss() {
    // Issue 26 item 6: while the module transmits, the driver does not write ABORT (the
    // frame could end before the write lands, and ABORT over a sent mailbox would read
    // aborted); the abort waits for the transmission's end. Here the frame loses
    // arbitration: the message-buffer interrupt of the winner's frame applies the
    // abort, and the frame never goes.
    let (model, mut can) = begin::<32, 8>(&Settings::new(500_000), &[], &[]).unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    let peer = SimNode::new().shared();
    bus.attach("peer", peer.clone());
    let ours = std_data(0x123, &[1]);
    peer.borrow_mut().send(std_data(0x050, &[2]));
    let t = can.try_send(&ours).unwrap();
    until_in_frame(&mut bus);
    bus.run_bits(3); // both in arbitration
    let esr1 = model.peek32(twocan_flexcan::regs::ESR1);
    assert_ne!(esr1 & twocan_flexcan::regs::esr1::TX, 0, "transmitting");
    assert_eq!(can.abort(t), twocan_core::AbortRequest::Requested);
    run1(&mut bus, &mut can, 2_000);
    let c = can.take_completion().expect("one completion");
    assert_eq!((c.token, c.outcome), (t, twocan_core::TxOutcome::Aborted));
    assert!(can.take_completion().is_none());
    assert!(
        !bus.trace()
            .records()
            .iter()
            .any(|r| r.frame == ours && r.is_error_free()),
        "never sent"
    );
    let tr = can.traffic();
    assert_eq!((tr.queued, tr.sent, tr.aborted), (1, 0, 1));
}
