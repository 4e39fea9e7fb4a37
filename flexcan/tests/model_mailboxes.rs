//! Mailboxes: transmit arbitration, abort, remote frames and answers, receive matching,
//! locking, overrun, time stamps ("Transmit process", "Arbitration process", "Transmission
//! abort mechanism", "Remote frames", "Receive process", "Matching process", "Mailbox lock
//! mechanism", "Time stamp", "Free Running Timer"), on every module of `support::CHIPS`.

#[path = "model_support.rs"]
mod support;

use support::*;
use twocan_core::Frame;
use twocan_flexcan::model::layout;
use twocan_flexcan::model::Chip;
use twocan_flexcan::regs::{self, code, cs, ctrl1, ctrl2, mcr};
use twocan_sim::{BusNode, BusTime, TxResult};

on_every_chip!(
    lowest_id_first_by_default,
    lowest_buffer_first_with_lbuf,
    local_priority_goes_before_the_id,
    lost_arbitration_and_errors_retry,
    abort_with_aen,
    inactivation_without_aen,
    remote_answer_mailbox,
    remote_requests_are_stored_with_rrs,
    sent_remote_frame_becomes_a_receive_mailbox_for_the_answer,
    receive_queue_overrun_and_masks,
    eacen_compares_rtr_under_the_mask,
    a_locked_mailbox_receives_after_unlock,
    time_stamps_come_from_the_free_running_timer,
    message_buffer_interrupt_line,
    maxmb_limits_the_active_mailboxes,
);

/// An enabled module in normal mode without the FIFO (every MB is a mailbox; MB0–MB15
/// take part, MCR\[MAXMB\] = 0xF out of reset on every module), self reception off.
fn rig(chip: Chip) -> Rig {
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    r.set_bits(regs::MCR, mcr::SRXDIS | mcr::IRMQ);
    for n in 0..Manual::of(chip).message_buffers {
        r.wr(regs::rximr(n), u32::MAX);
        r.wr(regs::mb_cs(n), 0);
    }
    r.start();
    r
}

fn lowest_id_first_by_default(chip: Chip) {
    let mut r = rig(chip);
    let frames = [
        (3, std(0x300, &[3])),
        (4, ext(0x100 << 18, &[4])), // same base ID as a standard 0x100: standard first
        (5, std(0x100, &[5])),
        (6, remote(0x100, false, 0)), // data before remote
        (7, std(0x0FF, &[7])),
        (9, ext(0x0FF << 18 | 1, &[])),
    ];
    for (n, f) in &frames {
        r.load_mb(*n, f, code::TX_DATA);
    }
    let sent = r.transmit_all();
    let mut expected: Vec<Frame> = frames.iter().map(|(_, f)| *f).collect();
    expected.sort_by_key(|f| f.priority());
    assert_eq!(sent, expected);
    assert_eq!(r.rd(regs::IFLAG1), 0b10_1111_1000);
    // Write 1 to clear, one flag at a time.
    r.wr(regs::IFLAG1, 1 << 3);
    assert_eq!(r.rd(regs::IFLAG1), 0b10_1111_0000);
    assert_eq!(r.code(3), code::TX_INACTIVE);
    assert_eq!(r.code(6), code::RX_EMPTY);
}

fn lowest_buffer_first_with_lbuf(chip: Chip) {
    let mut r = rig(chip);
    r.freeze();
    r.ctrl1(ctrl1::LBUF);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    r.load_mb(9, &std(0x001, &[]), code::TX_DATA);
    r.load_mb(2, &std(0x700, &[]), code::TX_DATA);
    r.load_mb(5, &std(0x010, &[]), code::TX_DATA);
    let ids: Vec<u32> = r.transmit_all().iter().map(|f| f.raw_id()).collect();
    assert_eq!(ids, vec![0x700, 0x010, 0x001]);
}

fn local_priority_goes_before_the_id(chip: Chip) {
    let mut r = rig(chip);
    r.freeze();
    r.set_bits(regs::MCR, mcr::LPRIOEN);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    r.load_mb_prio(1, &std(0x001, &[]), code::TX_DATA, 3);
    r.load_mb_prio(2, &std(0x700, &[]), code::TX_DATA, 0);
    r.load_mb_prio(3, &std(0x010, &[]), code::TX_DATA, 3);
    let ids: Vec<u32> = r.transmit_all().iter().map(|f| f.raw_id()).collect();
    assert_eq!(ids, vec![0x700, 0x001, 0x010]);
}

fn lost_arbitration_and_errors_retry(chip: Chip) {
    let mut r = rig(chip);
    r.load_mb(4, &std(0x123, &[1]), code::TX_DATA);
    assert_eq!(
        r.transmit(TxResult::ArbitrationLost),
        Some(std(0x123, &[1]))
    );
    assert_eq!(r.code(4), code::TX_DATA);
    assert_eq!(r.rd(regs::IFLAG1), 0);
    r.transmit(TxResult::Error(twocan_core::LastErrorCode::Stuff));
    assert_eq!(r.code(4), code::TX_DATA, "automatic retransmission");
    assert_eq!(r.transmit_all(), vec![std(0x123, &[1])]);
    assert_eq!(r.rd(regs::IFLAG1), 1 << 4);
}

fn abort_with_aen(chip: Chip) {
    let mut r = rig(chip);
    r.freeze();
    r.set_bits(regs::MCR, mcr::AEN);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    r.load_mb(4, &std(0x123, &[1]), code::TX_DATA);
    r.load_mb(5, &std(0x124, &[1]), code::TX_DATA);
    let c = r.rd(regs::mb_cs(4));
    r.wr(regs::mb_cs(4), cs::CODE.replace(c, code::TX_ABORT));
    assert_eq!(r.rd(regs::IFLAG1), 1 << 4, "abort done: IFLAG set");
    assert_eq!(r.code(4), code::TX_ABORT);
    // Aborting an inactive mailbox does nothing.
    r.wr(regs::mb_cs(7), code::TX_INACTIVE << 24);
    r.wr(regs::mb_cs(7), code::TX_ABORT << 24);
    assert_eq!(r.rd(regs::IFLAG1), 1 << 4);
    assert_eq!(r.transmit_all(), vec![std(0x124, &[1])]);
}

fn inactivation_without_aen(chip: Chip) {
    let mut r = rig(chip);
    r.load_mb(4, &std(0x123, &[1]), code::TX_DATA);
    r.wr(regs::mb_cs(4), code::TX_INACTIVE << 24);
    assert_eq!(r.rd(regs::IFLAG1), 0);
    // ABORT without AEN is not a transmit code: nothing is sent, no flag.
    r.load_mb(5, &std(0x124, &[1]), code::TX_DATA);
    r.wr(regs::mb_cs(5), code::TX_ABORT << 24);
    assert_eq!(r.rd(regs::IFLAG1), 0);
    assert!(r.transmit_all().is_empty());
}

fn remote_answer_mailbox(chip: Chip) {
    let mut r = rig(chip);
    let answer = std(0x300, &[0xDE, 0xAD]);
    r.load_mb(6, &answer, code::RX_RANSWER);
    // A request for another ID, even under open masks, does nothing.
    r.wr(regs::RXMGMASK, 0); // (not in freeze: ignored anyway)
    r.deliver(&remote(0x301, false, 2));
    r.deliver(&std(0x300, &[]));
    assert_eq!(r.code(6), code::RX_RANSWER);
    assert!(r.transmit_all().is_empty());
    // The matching request: TANSWER, then the answer goes out and the code returns.
    r.deliver(&remote(0x300, false, 8));
    assert_eq!(r.code(6), code::TX_TANSWER);
    assert_eq!(r.transmit_all(), vec![answer]);
    assert_eq!(r.code(6), code::RX_RANSWER);
    assert_eq!(r.rd(regs::IFLAG1), 1 << 6);
    // An extended request with the same number is another identifier.
    r.deliver(&remote(0x300, true, 2));
    assert_eq!(r.code(6), code::RX_RANSWER);
    // Software can write TANSWER itself.
    let c = r.rd(regs::mb_cs(6));
    r.wr(regs::mb_cs(6), cs::CODE.replace(c, code::TX_TANSWER));
    assert_eq!(r.transmit_all(), vec![answer]);
}

fn remote_requests_are_stored_with_rrs(chip: Chip) {
    let mut r = rig(chip);
    r.freeze();
    r.set_bits(regs::CTRL2, ctrl2::RRS);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    r.load_mb(6, &std(0x300, &[1]), code::RX_RANSWER);
    r.rx_mb(7, 0x300, false);
    r.deliver(&remote(0x300, false, 4));
    assert_eq!(r.code(6), code::RX_RANSWER, "no automatic answer");
    let (f, c, _) = r.read_mb(7);
    assert_eq!((f, c), (remote(0x300, false, 4), code::RX_FULL));
}

fn sent_remote_frame_becomes_a_receive_mailbox_for_the_answer(chip: Chip) {
    let mut r = rig(chip);
    r.load_mb(2, &remote(0x77, false, 2), code::TX_REMOTE);
    assert_eq!(r.transmit_all(), vec![remote(0x77, false, 2)]);
    assert_eq!(r.code(2), code::RX_EMPTY);
    assert_eq!(r.rd(regs::IFLAG1), 1 << 2);
    r.wr(regs::IFLAG1, 1 << 2);
    r.deliver(&std(0x77, &[5, 6]));
    assert_eq!(r.rd(regs::IFLAG1), 1 << 2);
    let (f, c, _) = r.read_mb(2);
    assert_eq!((f, c), (std(0x77, &[5, 6]), code::RX_FULL));
}

fn receive_queue_overrun_and_masks(chip: Chip) {
    let mut r = rig(chip);
    r.rx_mb(3, 0x55, false);
    r.rx_mb(9, 0x55, false);
    r.rx_mb(10, 0x55, true);
    r.deliver(&std(0x55, &[1]));
    r.deliver(&std(0x55, &[2]));
    assert_eq!((r.code(3), r.code(9)), (code::RX_FULL, code::RX_FULL));
    r.deliver(&std(0x55, &[3]));
    assert_eq!(
        r.code(9),
        code::RX_OVERRUN,
        "IRMQ: the last matching mailbox is overrun"
    );
    assert_eq!(r.read_mb(3).0, std(0x55, &[1]));
    assert_eq!(r.read_mb(9).0, std(0x55, &[3]));
    assert_eq!(r.m.mailbox_overruns(), 1);
    // Serviced: FULL again on the next frame, first free mailbox first.
    r.deliver(&std(0x55, &[4]));
    assert_eq!(
        r.read_mb(3),
        (std(0x55, &[4]), code::RX_FULL, r.read_mb(3).2)
    );
    assert_eq!(r.code(10), code::RX_EMPTY, "IDE must match");
    // Masks: individual mask of MB 10 ignores the low ID bits.
    r.freeze();
    r.wr(regs::rximr(10), 0x1FFF_FF00);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    r.deliver(&ext(0xAB, &[]));
    assert_eq!(
        r.read_mb(10).0,
        ext(0xAB, &[]),
        "received ID replaces the filter ID"
    );
    // IRMQ = 0: RXMGMASK, RX14MASK and RX15MASK.
    r.freeze();
    r.clear_bits(regs::MCR, mcr::IRMQ);
    r.wr(regs::RXMGMASK, 0);
    r.wr(regs::RX14MASK, u32::MAX);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    for n in [3, 9, 10] {
        r.wr(regs::mb_cs(n), 0);
    }
    r.rx_mb(14, 0x66, false);
    r.rx_mb(4, 0x00, false);
    r.deliver(&std(0x66, &[7]));
    assert_eq!(r.read_mb(4).0, std(0x66, &[7]), "RXMGMASK = 0 accepts all");
    r.deliver(&std(0x66, &[8]));
    assert_eq!(
        r.code(4),
        code::RX_FULL,
        "IRMQ = 0: the first match, serviced"
    );
    r.wr(regs::mb_cs(4), 0);
    r.deliver(&std(0x67, &[]));
    assert_eq!(r.code(14), code::RX_EMPTY, "RX14MASK checks every bit");
    r.deliver(&std(0x66, &[9]));
    assert_eq!(r.read_mb(14).0, std(0x66, &[9]));
}

fn eacen_compares_rtr_under_the_mask(chip: Chip) {
    let mut r = rig(chip);
    r.freeze();
    r.set_bits(regs::CTRL2, ctrl2::EACEN | ctrl2::RRS);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    r.rx_mb(5, 0x42, false); // RTR = 0 in the mailbox
    r.deliver(&remote(0x42, false, 1));
    assert_eq!(r.code(5), code::RX_EMPTY, "mask bit 31 set: RTR compared");
    r.deliver(&std(0x42, &[]));
    assert_eq!(r.code(5), code::RX_FULL);
    // EACEN = 0: RTR never compared.
    let mut r = rig(chip);
    r.freeze();
    r.set_bits(regs::CTRL2, ctrl2::RRS);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    r.rx_mb(5, 0x42, false);
    r.deliver(&remote(0x42, false, 1));
    assert_eq!(r.code(5), code::RX_FULL);
}

fn a_locked_mailbox_receives_after_unlock(chip: Chip) {
    let mut r = rig(chip);
    r.rx_mb(3, 0x10, false);
    let _ = r.rd(regs::mb_cs(3)); // lock
    assert_eq!(r.m.locked_mailbox(), Some(3));
    r.deliver(&std(0x10, &[1]));
    assert_eq!(
        r.code(3),
        code::RX_EMPTY,
        "held in the serial message buffer"
    );
    let _ = r.rd(regs::TIMER); // global unlock
    assert_eq!(r.m.locked_mailbox(), None);
    assert_eq!(r.code(3), code::RX_FULL);
    // Reading another C/S word also unlocks.
    let _ = r.rd(regs::mb_cs(3));
    r.deliver(&std(0x10, &[2]));
    let _ = r.rd(regs::mb_cs(4));
    assert_eq!(r.m.locked_mailbox(), Some(4));
    assert_eq!(r.read_mb(3).0, std(0x10, &[2]));
}

fn time_stamps_come_from_the_free_running_timer(chip: Chip) {
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    r.set_bits(regs::MCR, mcr::SRXDIS | mcr::IRMQ);
    r.wr(regs::rximr(1), u32::MAX);
    r.wr(regs::mb_cs(0), 0);
    r.idle(500); // frozen: the timer does not count
    assert_eq!(r.rd(regs::TIMER), 0);
    r.start();
    assert_eq!(r.rd(regs::TIMER), 11);
    r.idle(89);
    assert_eq!(r.rd(regs::TIMER), 100);
    r.rx_mb(1, 0x20, false);
    r.deliver(&std(0x20, &[])); // SOF at 100, identifier from 101
    assert_eq!(r.read_mb(1).2, 101);
    assert_eq!(r.rd(regs::TIMER), 100 + FRAME_BITS as u32 + 3);
    r.load_mb(2, &std(0x21, &[]), code::TX_DATA);
    let t0 = r.rd(regs::TIMER) as u16;
    r.transmit(TxResult::Acked);
    assert_eq!(r.read_mb(2).2, t0 + 1);
    // Wraps at 16 bits; software may write it.
    r.wr(regs::TIMER, 0xFFFF);
    r.idle(2);
    assert_eq!(r.rd(regs::TIMER), 1);
    assert_eq!(r.m.timer(), 1);
    // TSYN: reception in MB0 resets the timer.
    r.freeze();
    r.ctrl1(ctrl1::TSYN);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    r.wr(regs::rximr(0), u32::MAX);
    r.rx_mb(0, 0x30, false);
    r.deliver(&std(0x30, &[]));
    let after = r.rd(regs::TIMER);
    assert_eq!(
        after, 3,
        "reset at the end of the frame, then the intermission"
    );
}

/// The message buffer interrupt line from MB1 and from the last message buffer (MB15, or
/// MB63 on the RT1062, whose flag is IFLAG2 bit 31: [`mb_flag`]), MCR\[MAXMB\] raised to it.
fn message_buffer_interrupt_line(chip: Chip) {
    let mut r = rig(chip);
    let last = r.manual().message_buffers - 1;
    r.freeze();
    r.wr(regs::MCR, mcr::MAXMB.replace(r.rd(regs::MCR), last as u32));
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    for n in [1, last] {
        let (flags, imask, bit) = mb_flag(n);
        let iflag = if imask == regs::IMASK1 {
            regs::IFLAG1
        } else {
            layout::IFLAG2
        };
        r.load_mb(n, &std(n as u16, &[]), code::TX_DATA);
        r.transmit_all();
        assert_eq!((r.rd(regs::IFLAG1), r.rd(layout::IFLAG2)), flags, "MB{n}");
        assert!(!r.m.irq().message_buffer, "MB{n}: its mask bit clear");
        r.wr(imask, bit);
        assert!(r.m.irq().message_buffer && r.m.irq_pending(), "MB{n}");
        r.wr(iflag, bit);
        assert!(!r.m.irq_pending(), "MB{n}");
        assert_eq!(r.rd(imask), bit);
        r.wr(imask, 0);
    }
    // One bit per message buffer: MB0–MB15 on the Kinetis parts; MB0–MB31 in IMASK1 and
    // MB32–MB63 in IMASK2 on the RT1062 (IMXRT1060RM "Interrupt Masks 1/2 register"),
    // IMASK2 reserved on the Kinetis parts.
    r.wr(regs::IMASK1, u32::MAX);
    r.wr(layout::IMASK2, u32::MAX);
    let want = r.manual();
    assert_eq!(r.rd(regs::IMASK1), want.flags1);
    assert_eq!(r.rd(layout::IMASK2), want.flags2);
}

fn maxmb_limits_the_active_mailboxes(chip: Chip) {
    let mut r = rig(chip);
    r.freeze();
    r.wr(regs::MCR, mcr::MAXMB.replace(r.rd(regs::MCR), 3));
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    r.load_mb(5, &std(0x5, &[]), code::TX_DATA);
    r.load_mb(3, &std(0x3, &[]), code::TX_DATA);
    assert_eq!(r.transmit_all(), vec![std(0x3, &[])]);
    let t = BusTime {
        sof: r.now,
        now: r.now,
    };
    r.m.tx_result(&std(0x5, &[]), TxResult::Acked, t); // a stray report changes nothing
    assert_eq!(r.code(5), code::TX_DATA);
}
