//! Transmit mailboxes of the bxCAN model (RM0410 40.7.1 "Transmission handling"; notes
//! "Transmit Priority", "Abort", "Non Automatic Retransmission Mode", "Transmit Mailbox
//! States"), through registers and a tiny bus.

#[path = "model_bus.rs"]
mod bus;

use bus::*;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{self, esr, ier, mcr, tdtxr, tixr, tsr};
use twocan_core::{LastErrorCode, MailboxState, Registers};
use twocan_sim::{BusNode, BusTime, TxResult};

fn pair() -> (BxCanModel, BxCanModel, TinyBus) {
    started_pair(BxCanModel::can1(), BxCanModel::can3())
}

fn ids(frames: &[twocan_core::Frame]) -> Vec<u32> {
    frames.iter().map(|f| f.raw_id()).collect()
}

fn code(m: &BxCanModel) -> u32 {
    tsr::CODE.get(m.read32(regs::TSR))
}

#[test]
fn priority_by_identifier() {
    let (mut a, _b, mut bus) = pair();
    load(&mut a, 0, &std_frame(0x300, &[0]));
    load(&mut a, 1, &std_frame(0x100, &[1]));
    load(&mut a, 2, &std_frame(0x200, &[2]));
    let t = a.read32(regs::TSR);
    assert_eq!(t & (tsr::TME0 | tsr::TME1 | tsr::TME2), 0);
    assert_eq!(
        t & (tsr::LOW0 | tsr::LOW1 | tsr::LOW2),
        tsr::LOW0,
        "0x300 has the lowest priority"
    );
    assert_eq!(code(&a), 0, "all full: CODE = lowest-priority mailbox");
    assert_eq!(
        a.state().mailboxes,
        [
            MailboxState::Pending,
            MailboxState::Scheduled,
            MailboxState::Pending
        ]
    );
    assert_eq!(ids(&bus.run(10)), [0x100, 0x200, 0x300]);
}

#[test]
fn equal_identifiers_go_in_mailbox_order() {
    let (mut a, _b, mut bus) = pair();
    load(&mut a, 2, &std_frame(0x123, &[2]));
    load(&mut a, 1, &std_frame(0x123, &[1]));
    // Same base identifier: the standard frame wins over the extended one (Priority).
    load(&mut a, 0, &ext_frame(0x123 << 18, &[0]));
    let sent = bus.run(10);
    assert_eq!(
        sent,
        [
            std_frame(0x123, &[1]),
            std_frame(0x123, &[2]),
            ext_frame(0x123 << 18, &[0])
        ]
    );
}

#[test]
fn priority_by_request_order() {
    let (mut a, _b, mut bus) = pair();
    a.modify32(regs::MCR, |v| v | mcr::TXFP);
    load(&mut a, 2, &std_frame(0x100, &[]));
    load(&mut a, 0, &std_frame(0x300, &[]));
    load(&mut a, 1, &std_frame(0x050, &[]));
    let t = a.read32(regs::TSR);
    assert_eq!(
        t & (tsr::LOW0 | tsr::LOW1 | tsr::LOW2),
        tsr::LOW1,
        "the last request is the lowest"
    );
    assert_eq!(code(&a), 1);
    assert_eq!(ids(&bus.run(10)), [0x100, 0x300, 0x050]);
}

#[test]
fn code_tme_and_low_flags() {
    let (mut a, _b, mut bus) = pair();
    let t = a.read32(regs::TSR);
    assert_eq!(t, tsr::TME0 | tsr::TME1 | tsr::TME2);
    assert_eq!(code(&a), 0);
    load(&mut a, 0, &std_frame(0x10, &[]));
    assert_eq!(code(&a), 1, "the next empty mailbox");
    assert_eq!(
        a.read32(regs::TSR) & (tsr::LOW0 | tsr::LOW1 | tsr::LOW2),
        0,
        "LOW needs two pending"
    );
    load(&mut a, 1, &std_frame(0x20, &[]));
    assert_eq!(code(&a), 2);
    assert_eq!(
        a.read32(regs::TSR) & (tsr::LOW0 | tsr::LOW1 | tsr::LOW2),
        tsr::LOW1
    );
    bus.run(1);
    assert_eq!(code(&a), 0, "mailbox 0 is empty again");
    assert_eq!(
        a.read32(regs::TSR) & (tsr::TME0 | tsr::TME1 | tsr::TME2),
        tsr::TME0 | tsr::TME2
    );
}

#[test]
fn mailbox_registers_are_locked_while_not_empty() {
    let (mut a, mut b, mut bus) = pair();
    let f = std_frame(0x321, &[1, 2, 3, 4, 5]);
    load(&mut a, 0, &f);
    let before: Vec<u32> = (0..4).map(|r| a.read32(regs::tixr(0) + 4 * r)).collect();
    assert_eq!(before[0], tir_of(&f) | tixr::TXRQ);
    for r in 0..4 {
        a.write32(regs::tixr(0) + 4 * r, 0xDEAD_BEEF);
    }
    let after: Vec<u32> = (0..4).map(|r| a.read32(regs::tixr(0) + 4 * r)).collect();
    assert_eq!(before, after);
    bus.run(1);
    assert_eq!(receive(&mut b, 0).unwrap().frame, f);
    assert_eq!(
        a.read32(regs::tixr(0)) & tixr::TXRQ,
        0,
        "TXRQ cleared when empty"
    );
    a.write32(regs::tdlxr(0), 0xDEAD_BEEF);
    assert_eq!(a.read32(regs::tdlxr(0)), 0xDEAD_BEEF, "writable again");
}

#[test]
fn success_sets_rqcp_and_txok_which_are_write_1_to_clear() {
    let (mut a, _b, mut bus) = pair();
    a.write32(regs::IER, ier::TMEIE);
    load(&mut a, 1, &std_frame(0x10, &[]));
    assert!(!a.irq_lines().tx);
    bus.run(1);
    let t = a.read32(regs::TSR);
    assert_eq!(t & 0x00FF_FFFF, tsr::RQCP1 | tsr::TXOK1);
    assert!(a.irq_lines().tx);
    a.write32(regs::TSR, 0);
    assert_eq!(
        a.read32(regs::TSR) & 0x00FF_FFFF,
        tsr::RQCP1 | tsr::TXOK1,
        "writing 0 changes nothing"
    );
    a.write32(regs::TSR, tsr::TXOK1);
    assert_eq!(
        a.read32(regs::TSR) & 0x00FF_FFFF,
        tsr::RQCP1,
        "TXOK alone is rc_w1"
    );
    a.write32(regs::TSR, tsr::RQCP1);
    assert_eq!(a.read32(regs::TSR) & 0x00FF_FFFF, 0);
    assert!(!a.irq_lines().tx);

    // Clearing RQCP clears TXOK, ALST and TERR too.
    load(&mut a, 1, &std_frame(0x10, &[]));
    bus.run(1);
    a.write32(regs::TSR, tsr::RQCP1);
    assert_eq!(a.read32(regs::TSR) & 0x00FF_FFFF, 0);
}

#[test]
fn a_new_request_clears_the_previous_status() {
    let (mut a, _b, mut bus) = pair();
    load(&mut a, 0, &std_frame(0x10, &[]));
    bus.run(1);
    assert_ne!(a.read32(regs::TSR) & (tsr::RQCP0 | tsr::TXOK0), 0);
    load(&mut a, 0, &std_frame(0x11, &[]));
    assert_eq!(a.read32(regs::TSR) & (tsr::RQCP0 | tsr::TXOK0), 0);
}

#[test]
fn abort_pending_and_scheduled_mailboxes_at_once() {
    let (mut a, _b, _bus) = pair();
    load(&mut a, 0, &std_frame(0x200, &[]));
    load(&mut a, 1, &std_frame(0x100, &[]));
    assert_eq!(
        a.state().mailboxes[..2],
        [MailboxState::Pending, MailboxState::Scheduled]
    );
    // Pending.
    a.write32(regs::TSR, tsr::ABRQ0);
    let t = a.read32(regs::TSR);
    assert_eq!(
        t & (tsr::RQCP0 | tsr::TXOK0 | tsr::ABRQ0 | tsr::TME0),
        tsr::RQCP0 | tsr::TME0
    );
    // Scheduled.
    a.write32(regs::TSR, tsr::ABRQ1);
    let t = a.read32(regs::TSR);
    assert_eq!(
        t & (tsr::RQCP1 | tsr::TXOK1 | tsr::ABRQ1 | tsr::TME1),
        tsr::RQCP1 | tsr::TME1
    );
    assert_eq!(a.state().mailboxes, [MailboxState::Empty; 3]);
    // Empty: no effect.
    a.write32(regs::TSR, tsr::RQCP2 | tsr::ABRQ2);
    assert_eq!(a.read32(regs::TSR) & (tsr::RQCP2 | tsr::ABRQ2), 0);
}

#[test]
fn abort_while_transmitting_then_success_completes_with_txok() {
    let (mut a, _b, bus) = pair();
    load(&mut a, 0, &std_frame(0x100, &[9]));
    let now = bus.now;
    let req = a.poll_tx(now).unwrap();
    assert_eq!(a.state().mailboxes[0], MailboxState::Transmitting);
    a.write32(regs::TSR, tsr::ABRQ0);
    let t = a.read32(regs::TSR);
    assert_ne!(
        t & tsr::ABRQ0,
        0,
        "abort pending until the end of the transmission"
    );
    assert_eq!(t & (tsr::TME0 | tsr::RQCP0), 0);
    a.tx_result(
        &req.frame,
        TxResult::Acked,
        BusTime {
            sof: now,
            now: now + 52,
        },
    );
    let t = a.read32(regs::TSR);
    assert_eq!(
        t & (tsr::ABRQ0 | tsr::RQCP0 | tsr::TXOK0 | tsr::TME0),
        tsr::RQCP0 | tsr::TXOK0 | tsr::TME0
    );
}

#[test]
fn abort_while_transmitting_then_failure_aborts() {
    for result in [
        TxResult::Error(LastErrorCode::BitDominant),
        TxResult::ArbitrationLost,
    ] {
        let (mut a, _b, bus) = pair();
        load(&mut a, 0, &std_frame(0x100, &[9]));
        let now = bus.now;
        let req = a.poll_tx(now).unwrap();
        a.write32(regs::TSR, tsr::ABRQ0);
        a.tx_result(
            &req.frame,
            result,
            BusTime {
                sof: now,
                now: now + 30,
            },
        );
        let t = a.read32(regs::TSR);
        assert_eq!(
            t & (tsr::ABRQ0 | tsr::RQCP0 | tsr::TXOK0 | tsr::TME0),
            tsr::RQCP0 | tsr::TME0
        );
        let cause = if result == TxResult::ArbitrationLost {
            tsr::ALST0
        } else {
            tsr::TERR0
        };
        assert_eq!(t & (tsr::ALST0 | tsr::TERR0), cause);
        assert_eq!(a.state().mailboxes[0], MailboxState::Empty);
    }
}

#[test]
fn abort_of_an_offered_frame_the_bus_did_not_start() {
    let (mut a, _b, mut bus) = pair();
    load(&mut a, 0, &std_frame(0x100, &[9]));
    a.poll_tx(bus.now).unwrap();
    a.write32(regs::TSR, tsr::ABRQ0);
    assert_ne!(a.read32(regs::TSR) & tsr::ABRQ0, 0);
    bus.idle(1);
    assert_eq!(
        a.read32(regs::TSR) & (tsr::ABRQ0 | tsr::RQCP0 | tsr::TME0),
        tsr::RQCP0 | tsr::TME0
    );
    assert!(bus.run(5).is_empty());
}

#[test]
fn no_automatic_retransmission_acknowledge_error() {
    // Alone on the bus: nobody acknowledges.
    let (mut a, mut bus) = started(BxCanModel::can1());
    a.modify32(regs::MCR, |v| v | mcr::NART);
    load(&mut a, 2, &std_frame(0x100, &[1]));
    let slot = bus.step();
    assert!(!slot.acked);
    let t = a.read32(regs::TSR);
    assert_eq!(
        t & 0x00FF_FFFF,
        tsr::RQCP2 | tsr::TERR2,
        "one attempt, completed, TXOK = 0"
    );
    assert_ne!(t & tsr::TME2, 0);
    let e = a.read32(regs::ESR);
    assert_eq!(esr::LEC.get(e), esr::LEC_ACK);
    assert_eq!(esr::TEC.get(e), 8);
    assert_eq!(bus.step().frame, None, "no retry");
}

#[test]
fn no_automatic_retransmission_arbitration_lost() {
    let (mut a, mut b, mut bus) = pair();
    a.modify32(regs::MCR, |v| v | mcr::NART);
    load(&mut a, 0, &std_frame(0x200, &[1]));
    load(&mut b, 0, &std_frame(0x100, &[2]));
    let slot = bus.step();
    assert_eq!(slot.from, Some(1));
    let t = a.read32(regs::TSR);
    assert_eq!(t & 0x00FF_FFFF, tsr::RQCP0 | tsr::ALST0);
    assert_ne!(t & tsr::TME0, 0);
    assert_eq!(
        receive(&mut a, 0).unwrap().frame,
        std_frame(0x100, &[2]),
        "the loser receives the winner"
    );
    bus.idle(3);
    assert_eq!(bus.step().frame, None);
    assert_eq!(
        esr::TEC.get(a.read32(regs::ESR)),
        0,
        "arbitration loss is no error"
    );
}

#[test]
fn automatic_retransmission_after_arbitration_loss_and_error() {
    let (mut a, mut b, mut bus) = pair();
    load(&mut a, 0, &std_frame(0x200, &[1]));
    load(&mut b, 0, &std_frame(0x100, &[2]));
    bus.step();
    let t = a.read32(regs::TSR);
    assert_eq!(
        t & (tsr::RQCP0 | tsr::ALST0 | tsr::TME0),
        tsr::ALST0,
        "still pending, ALST set"
    );
    bus.idle(3);
    bus.inject_error = Some(LastErrorCode::Stuff);
    bus.step();
    let t = a.read32(regs::TSR);
    assert_eq!(
        t & (tsr::RQCP0 | tsr::ALST0 | tsr::TERR0 | tsr::TME0),
        tsr::TERR0,
        "error: retried"
    );
    assert_eq!(esr::TEC.get(a.read32(regs::ESR)), 8);
    bus.idle(3);
    bus.step();
    let t = a.read32(regs::TSR);
    assert_eq!(
        t & 0x00FF_FFFF,
        tsr::RQCP0 | tsr::TXOK0,
        "the last attempt succeeded"
    );
    assert_eq!(esr::TEC.get(a.read32(regs::ESR)), 7);
}

#[test]
fn transmission_starts_in_normal_mode_only() {
    let (mut a, mut b, mut bus) = pair();
    enter_init(&mut a);
    load(&mut a, 0, &std_frame(0x42, &[]));
    assert!(a.poll_tx(bus.now).is_none());
    assert_eq!(bus.step().frame, None);
    leave_init(&mut a, &mut bus);
    assert_eq!(ids(&bus.run(5)), [0x42]);
    assert!(receive(&mut b, 0).is_some());
}

#[test]
fn remote_and_extended_frames_and_dlc_above_8() {
    let (mut a, mut b, mut bus) = pair();
    let r = twocan_core::Frame::remote(0x1ABC_DEF0, true, 3).unwrap();
    load(&mut a, 0, &r);
    bus.run(1);
    assert_eq!(receive(&mut b, 0).unwrap().frame, r);
    load(&mut a, 1, &std_frame(0x5, &[1, 2, 3, 4, 5, 6, 7, 8]));
    bus.run(1);
    assert_eq!(receive(&mut b, 0).unwrap().frame.dlc(), 8);
    // A DLC code of 9..15 goes on the simulated bus as written, with 8 bytes, and the
    // receiver's RDTxR.DLC holds it unchanged.
    a.write32(regs::tdtxr(1), tdtxr::DLC.val(15));
    a.write32(regs::tdlxr(1), 0x0403_0201);
    a.write32(regs::tdhxr(1), 0x0807_0605);
    a.write32(regs::tixr(1), tixr::STID.val(0x6) | tixr::TXRQ);
    bus.run(1);
    let got = receive(&mut b, 0).unwrap().frame;
    assert_eq!((got.dlc(), got.data()), (15, &[1, 2, 3, 4, 5, 6, 7, 8][..]));
}
