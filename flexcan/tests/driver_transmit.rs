//! ACAN §3 "sequentiality", §8, §9: data frames through the transmit ring and the one
//! data mailbox leave strictly in order; remote frames use the remote-frame mailboxes
//! of the configuration; abort; mailbox states.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_core::{
    AbortRequest, Error, Frame, Hardware, MailboxId, MailboxState, TxOutcome, TxPolicy,
};
use twocan_flexcan::regs::{self, code, cs};
use twocan_flexcan::{Configuration, Settings};
use twocan_sim::SimNode;

/// Identifiers that a priority-ordered transmitter would reorder.
fn scrambled_id(i: u32) -> u16 {
    ((i.wrapping_mul(7919) + 13) % 0x800) as u16
}

#[test]
fn strict_order_across_10_000_frames() {
    const N: u32 = 10_000;
    let (model, mut can) = begin::<64, 16>(&loop_back(1_000_000), &[], &[]).unwrap();
    assert_eq!(can.tx_policy(), TxPolicy::Fifo);
    let mut bus = bus_with(1_000_000, &[&model]);
    let mut next = 0u32;
    let mut expected = 0u32;
    let mut rejected = 0u32;
    while expected < N {
        // Fill the transmit ring until it is full.
        while next < N {
            let f = if next.is_multiple_of(3) {
                ext_data(0x1000 + scrambled_id(next) as u32, &next.to_le_bytes())
            } else {
                std_data(scrambled_id(next), &next.to_le_bytes())
            };
            match can.try_send(&f) {
                Ok(_) => next += 1,
                Err(nb::Error::WouldBlock) => {
                    rejected += 1;
                    break;
                }
                Err(e) => panic!("{e:?}"),
            }
        }
        run1(&mut bus, &mut can, 200);
        for rx in drain(&mut can) {
            let seq = u32::from_le_bytes(rx.frame.data().try_into().unwrap());
            assert_eq!(seq, expected, "frame {expected} overtaken");
            expected += 1;
        }
    }
    let t = can.traffic();
    assert_eq!((t.queued, t.sent, t.received), (N, N, N));
    assert!(rejected > 0);
    assert_eq!(
        can.tx_stats().peak,
        17,
        "ACAN §8.5: size + 1 after a full buffer"
    );
    assert_eq!(can.rx_stats().overflows, 0);
}

#[test]
fn strict_order_between_two_nodes() {
    // can0 sends 500 frames to can1 of a Teensy 3.6 over the simulated bus.
    let t36 = |i| twocan_flexcan::Target::new(twocan_flexcan::Board::Teensy36, i);
    let s = Settings::new(500_000);
    let (m0, mut can0) =
        begin_on::<32, 8>(t36(twocan_flexcan::Instance::Can0), &s, &[], &[]).unwrap();
    let (m1, mut can1) =
        begin_on::<600, 8>(t36(twocan_flexcan::Instance::Can1), &s, &[], &[]).unwrap();
    let mut bus = bus_with(500_000, &[&m0, &m1]);
    let mut next = 0u32;
    while next < 500 {
        while next < 500
            && can0
                .try_send(&std_data(scrambled_id(next), &next.to_le_bytes()))
                .is_ok()
        {
            next += 1;
        }
        run(&mut bus, &mut [&mut can0, &mut can1], 400);
    }
    run(&mut bus, &mut [&mut can0, &mut can1], 20_000);
    let seqs: Vec<u32> = drain(&mut can1)
        .iter()
        .map(|rx| u32::from_le_bytes(rx.frame.data().try_into().unwrap()))
        .collect();
    assert_eq!(seqs, (0..500).collect::<Vec<u32>>());
    assert_eq!(can0.traffic().sent, 500);
    assert!(drain(&mut can0).is_empty(), "no self reception by default");
}

#[test]
fn remote_mailboxes_per_configuration_9() {
    for c in Configuration::ALL {
        let mut s = loop_back(500_000);
        s.configuration = c;
        let (model, mut can) = begin::<32, 16>(&s, &[], &[]).unwrap();
        let r = c.remote_mailbox_count();
        assert_eq!(can.hardware().mailbox_count(), 1 + r);
        // Straight to the remote-frame mailboxes (ACAN: remote frames are not queued).
        for i in 0..r {
            can.try_send_now(&remote(0x500 + i as u32, false)).unwrap();
            assert_eq!(can.mailbox_state(MailboxId(1 + i)), MailboxState::Pending);
        }
        assert!(
            matches!(
                can.try_send_now(&remote(0x5FF, false)),
                Err(nb::Error::WouldBlock)
            ),
            "{c:?}"
        );
        // The data mailbox is independent of them.
        assert_eq!(can.mailbox_state(MailboxId(0)), MailboxState::Empty);
        can.try_send_now(&std_data(0x10, &[1])).unwrap();
        assert!(matches!(
            can.try_send_now(&std_data(0x11, &[])),
            Err(nb::Error::WouldBlock)
        ));
        assert_eq!(can.tx_stats().count, 0, "nothing queued");
        let mut bus = bus_with(500_000, &[&model]);
        run1(&mut bus, &mut can, 2_000);
        let got = drain(&mut can);
        assert_eq!(got.len(), r as usize + 1, "{c:?}");
        assert_eq!(can.traffic().sent, r as u32 + 1);
        // Remote frames came back as remote frames, the data frame as data.
        assert_eq!(
            got.iter().filter(|rx| rx.frame.is_remote()).count(),
            r as usize
        );
        for i in 0..=r {
            assert_eq!(can.mailbox_state(MailboxId(i)), MailboxState::Empty);
        }
        // After its remote frame, each mailbox is left inactive (not an Rx mailbox).
        for mb in c.first_remote_mailbox()..15 {
            assert_eq!(
                cs::CODE.get(model.peek32(regs::mb_cs(mb as usize))),
                code::TX_INACTIVE,
                "MB{mb}"
            );
        }
    }
}

#[test]
fn remote_frames_through_the_driver_queue() {
    let (model, mut can) = begin::<32, 16>(&loop_back(500_000), &[], &[]).unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    let frames: Vec<Frame> = vec![
        std_data(0x300, &[0]),
        remote(0x100, false),
        std_data(0x200, &[1]),
        remote(0x050, true),
        std_data(0x100, &[2]),
    ];
    for f in &frames {
        can.try_send(f).unwrap();
    }
    run1(&mut bus, &mut can, 5_000);
    let got: Vec<Frame> = drain(&mut can).iter().map(|rx| rx.frame).collect();
    assert_eq!(got.len(), frames.len());
    // Data frames keep their order whatever the remote frames do.
    let data: Vec<Frame> = got.iter().filter(|f| !f.is_remote()).copied().collect();
    assert_eq!(data, vec![frames[0], frames[2], frames[4]]);
}

#[test]
fn remote_frames_overtake_queued_data_frames_through_their_own_mailboxes() {
    // ACAN: data frames wait for MB15 in order; a remote frame goes straight to a
    // remote-frame mailbox (`try_send_now`), never behind them.
    let (model, mut can) = begin::<32, 16>(&loop_back(500_000), &[], &[]).unwrap();
    for i in 0..4 {
        can.try_send(&std_data(0x300 + i, &[])).unwrap();
    }
    assert_eq!(can.tx_stats().count, 3);
    let t = can.try_send_now(&remote(0x100, false)).unwrap();
    assert_eq!(can.tx_stats().count, 3, "not queued");
    assert_eq!(can.mailbox_state(MailboxId(1)), MailboxState::Pending);
    let mut bus = bus_with(500_000, &[&model]);
    run1(&mut bus, &mut can, 5_000);
    let got: Vec<Frame> = drain(&mut can).iter().map(|rx| rx.frame).collect();
    assert_eq!(got.len(), 5);
    // 0x100 wins arbitration against the data frame pending in MB15.
    assert!(got[0].is_remote() || got[1].is_remote(), "{got:?}");
    let done: Vec<_> = std::iter::from_fn(|| can.take_completion()).collect();
    assert_eq!(done.len(), 5);
    assert!(done
        .iter()
        .any(|c| c.token == t && c.outcome == TxOutcome::Sent));
}

#[test]
fn abort_a_pending_data_frame() {
    // Normal mode, alone on the bus: before any bus time, nothing has left MB15.
    let (_model, mut can) = begin::<32, 16>(&Settings::new(500_000), &[], &[]).unwrap();
    let t = can.try_send(&std_data(0x123, &[1])).unwrap();
    assert_eq!(can.mailbox_state(MailboxId(0)), MailboxState::Pending);
    assert_eq!(can.abort(t), AbortRequest::Requested);
    assert_eq!(can.mailbox_state(MailboxId(0)), MailboxState::Empty);
    assert_eq!(
        can.abort(t),
        AbortRequest::NotFound,
        "nothing pending any more"
    );
    can.on_interrupt();
    assert_eq!((can.traffic().aborted, can.traffic().sent), (1, 0));
    let c = can.take_completion().unwrap();
    assert_eq!((c.token, c.outcome), (t, TxOutcome::Aborted));
    // The mailbox is usable again.
    can.try_send(&std_data(0x124, &[])).unwrap();
    assert_eq!(can.mailbox_state(MailboxId(0)), MailboxState::Pending);
}

#[test]
fn abort_all_drops_the_ring_and_the_mailboxes() {
    let (_model, mut can) = begin::<32, 16>(&Settings::new(500_000), &[], &[]).unwrap();
    for i in 0..5 {
        can.try_send(&std_data(i, &[])).unwrap();
    }
    can.try_send_now(&remote(0x42, false)).unwrap();
    assert_eq!(can.abort_all(), 4);
    can.on_interrupt();
    assert_eq!(can.traffic().aborted, 4 + 2);
    for m in 0..can.hardware().mailbox_count() {
        assert_eq!(can.mailbox_state(MailboxId(m)), MailboxState::Empty);
    }
    let done: Vec<_> = std::iter::from_fn(|| can.take_completion()).collect();
    assert_eq!(done.len(), 6, "one completion per accepted frame");
    assert!(done.iter().all(|c| c.outcome == TxOutcome::Aborted));
}

#[test]
fn frames_reach_a_plain_iso_node() {
    let (model, mut can) = begin::<32, 16>(&Settings::new(250_000), &[], &[]).unwrap();
    let other = SimNode::new().shared();
    let mut bus = bus_with(250_000, &[&model]);
    bus.attach("other", other.clone());
    let frames = [
        std_data(0x7FF, &[1, 2, 3]),
        ext_data(0x1FFF_FFFF, &[8; 8]),
        remote(0x12, false),
        remote(0x345678, true),
    ];
    for f in &frames {
        can.try_send(f).unwrap();
    }
    run1(&mut bus, &mut can, 3_000);
    let got = other.borrow().received_frames();
    assert_eq!(got.len(), 4);
    for f in &frames {
        assert!(got.contains(f), "{f:?}");
    }
}

#[test]
fn listen_only_does_not_transmit() {
    let mut s = Settings::new(500_000);
    s.listen_only = true;
    let (_model, mut can) = begin::<32, 16>(&s, &[], &[]).unwrap();
    assert_eq!(
        can.try_send(&std_data(1, &[])),
        Err(nb::Error::Other(Error::WrongMode))
    );
    assert_eq!(
        can.try_send_now(&remote(1, false)),
        Err(nb::Error::Other(Error::WrongMode))
    );
    assert_eq!(can.traffic().queued, 0, "an error means not accepted");
}

/// Issue 14: a remote-frame mailbox becomes a receive mailbox for its identifier after
/// sending (Kinetis RM "Transmit process"); a frame it catches — one the Rx FIFO's
/// filters did not take — is counted when the mailbox is made inactive again, not
/// delivered (it passed none of the user's filters) and not lost without a trace.
#[test]
fn a_frame_caught_by_a_remote_frame_mailbox_is_counted() {
    use twocan_core::{Filter, Format, FrameKind};
    let mut s = Settings::new(500_000);
    s.configuration = Configuration::Filters8_0;
    // The Rx FIFO takes data frames 0x700 only.
    let only = [Filter::exact(FrameKind::Data, Format::Standard, 0x700)];
    let (model, mut can) = begin::<32, 16>(&s, &only, &[]).unwrap();
    let other = SimNode::new().shared();
    let mut bus = bus_with(500_000, &[&model]);
    bus.attach("other", other.clone());
    run1(&mut bus, &mut can, 30);
    let request = remote(0x123, false);
    can.try_send_now(&request).unwrap();
    // The bus runs with the driver's interrupt not serviced: the remote frame leaves,
    // then the other node sends a remote frame of the same identifier, which only the
    // (now receiving) remote-frame mailbox accepts.
    run(&mut bus, &mut [], 200);
    assert_eq!(other.borrow().received_frames(), [request]);
    other.borrow_mut().send(request);
    run(&mut bus, &mut [], 200);
    let first = s.configuration.first_remote_mailbox() as usize;
    // The driver's last control-word read (finding the mailbox free) left it locked
    // (Kinetis RM "Message buffer lock mechanism"): the frame waits in the serial
    // message buffer until any other access unlocks it, here a read of the timer.
    assert_eq!(model.locked_mailbox(), Some(first));
    let _ = twocan_core::Registers::read32(&model, regs::TIMER);
    assert_eq!(
        cs::CODE.get(model.peek32(regs::mb_cs(first))),
        code::RX_FULL,
        "the mailbox caught it"
    );
    assert_eq!(can.hardware().remote_mailbox_catches(), 0);
    run1(&mut bus, &mut can, 10);
    assert_eq!(can.hardware().remote_mailbox_catches(), 1);
    assert!(
        drain(&mut can).is_empty(),
        "not delivered: no user filter takes it"
    );
    assert_eq!(can.traffic().sent, 1, "the remote frame's completion");
    assert_eq!(
        cs::CODE.get(model.peek32(regs::mb_cs(first))),
        code::TX_INACTIVE
    );
    // A data frame 0x700 still goes to the FIFO; nothing more is counted.
    other.borrow_mut().send(std_data(0x700, &[7]));
    run1(&mut bus, &mut can, 200);
    assert_eq!(drain(&mut can).len(), 1);
    assert_eq!(can.hardware().remote_mailbox_catches(), 1);
}

/// The same catch while the driver's own control-word read keeps the mailbox locked:
/// the frame waits in the serial message buffer until the next unlock. The transmit
/// handler's settle reads `TIMER` after the completion's time stamp (widening), which
/// unlocks it (Kinetis RM "Message buffer lock mechanism"): the frame moves in, raises
/// the mailbox's flag, and the handler counts it in the same pass — once, not lost and
/// not counted again when the driver later reads MB15 to load a data frame.
#[test]
fn a_frame_caught_behind_the_lock_is_counted_at_the_next_unlock() {
    use twocan_core::{Filter, Format, FrameKind};
    let mut s = Settings::new(500_000);
    s.configuration = Configuration::Filters8_0;
    let only = [Filter::exact(FrameKind::Data, Format::Standard, 0x700)];
    let (model, mut can) = begin::<32, 16>(&s, &only, &[]).unwrap();
    let other = SimNode::new().shared();
    let mut bus = bus_with(500_000, &[&model]);
    bus.attach("other", other.clone());
    run1(&mut bus, &mut can, 30);
    let request = remote(0x123, false);
    can.try_send_now(&request).unwrap();
    run(&mut bus, &mut [], 200);
    other.borrow_mut().send(request);
    run(&mut bus, &mut [], 200);
    let first = s.configuration.first_remote_mailbox() as usize;
    assert_eq!(model.locked_mailbox(), Some(first));
    // Settled; the settle's TIMER read unlocked the mailbox and the catch is counted.
    run1(&mut bus, &mut can, 10);
    assert_eq!(can.traffic().sent, 1);
    assert_eq!(can.hardware().remote_mailbox_catches(), 1);
    assert_eq!(model.locked_mailbox(), None);
    // Loading a data frame reads MB15's control word: nothing more to count.
    can.try_send(&std_data(0x10, &[1])).unwrap();
    run1(&mut bus, &mut can, 300);
    assert_eq!(can.hardware().remote_mailbox_catches(), 1);
    assert_eq!(can.traffic().sent, 2);
    assert!(drain(&mut can).is_empty());
    assert_eq!(
        cs::CODE.get(model.peek32(regs::mb_cs(first))),
        code::TX_INACTIVE
    );
}
