//! Test modes of the bxCAN model: silent, loop back, loop back combined with silent
//! (RM0410 40.5 "Test mode"), through registers and a tiny bus.

#[path = "model_bus.rs"]
mod bus;

use bus::*;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{self, btr, esr, fa1r, fmr, tsr};
use twocan_core::Registers;
use twocan_sim::BusNode;

/// Two started models; `a` gets the BTR test bits `bits` (set in initialization mode).
fn pair_with(bits: u32) -> (BxCanModel, BxCanModel, TinyBus) {
    let (mut a, b, mut bus) = started_pair(BxCanModel::can1(), BxCanModel::can3());
    enter_init(&mut a);
    a.modify32(regs::BTR, |v| v | bits);
    leave_init(&mut a, &mut bus);
    (a, b, bus)
}

#[test]
fn loop_back_receives_its_own_frames_and_sends_them_on_the_bus() {
    let (mut a, mut b, mut bus) = pair_with(btr::LBKM);
    let f = std_frame(0x321, &[7, 7]);
    load(&mut a, 0, &f);
    let req = a.poll_tx(bus.now).unwrap();
    assert!(req.self_ack && !req.internal);
    bus.run(2);
    assert_ne!(a.read32(regs::TSR) & tsr::TXOK0, 0);
    assert_eq!(
        receive(&mut a, 0).unwrap().frame,
        f,
        "own frame through the filters"
    );
    assert_eq!(
        receive(&mut b, 0).unwrap().frame,
        f,
        "the frame is on the wire"
    );
    // CANRX is disregarded: frames of other nodes are not received.
    load(&mut b, 0, &std_frame(0x10, &[]));
    bus.run(2);
    assert_eq!(receive(&mut a, 0), None);
}

#[test]
fn loop_back_ignores_the_acknowledge_slot() {
    let (mut a, mut bus) = started(BxCanModel::can1());
    enter_init(&mut a);
    a.modify32(regs::BTR, |v| v | btr::LBKM);
    leave_init(&mut a, &mut bus);
    load(&mut a, 1, &std_frame(0x5, &[]));
    assert!(bus.step().acked, "no other node, yet no acknowledge error");
    assert_eq!(esr::LEC.get(a.read32(regs::ESR)), 0);
    assert_eq!(esr::TEC.get(a.read32(regs::ESR)), 0);
    assert!(receive(&mut a, 0).is_some());
}

#[test]
fn loop_back_frames_still_pass_through_the_filters() {
    let (mut a, _b, mut bus) = pair_with(btr::LBKM);
    a.modify32(regs::FMR, |v| v | fmr::FINIT);
    a.write32(regs::FA1R, 0);
    a.modify32(regs::FMR, |v| v & !fmr::FINIT);
    load(&mut a, 0, &std_frame(0x321, &[]));
    bus.run(2);
    assert_ne!(a.read32(regs::TSR) & tsr::TXOK0, 0);
    assert_eq!(receive(&mut a, 0), None, "no active filter: dropped");
    assert_eq!(a.read32(regs::FA1R) & fa1r::fact(0), 0);
}

#[test]
fn silent_mode_receives_but_neither_transmits_nor_acknowledges() {
    let (mut a, mut b, mut bus) = pair_with(btr::SILM);
    assert!(a.listens() && !a.acknowledges());
    // With only the silent node listening nobody acknowledges: the frame fails.
    load(&mut b, 0, &std_frame(0x100, &[1]));
    let slot = bus.step();
    assert!(!slot.acked, "the only other node is silent");
    assert_eq!(esr::LEC.get(b.read32(regs::ESR)), esr::LEC_ACK);
    assert_eq!(
        receive(&mut a, 0),
        None,
        "an unacknowledged frame is not valid"
    );
    b.write32(regs::TSR, tsr::ABRQ0);
    bus.idle(3);
    // Another node acknowledges: the silent node receives the frame.
    let mut c = BxCanModel::can1();
    bus.nodes.push(c.clone());
    start(&mut c, &mut bus);
    let f = std_frame(0x101, &[2]);
    load(&mut b, 1, &f);
    assert!(bus.step().acked);
    assert_eq!(
        receive(&mut a, 0).unwrap().frame,
        f,
        "the silent node still receives"
    );
    // A silent node cannot start a transmission: the request stays pending.
    load(&mut a, 0, &std_frame(0x200, &[]));
    assert!(a.poll_tx(bus.now).is_none());
    bus.idle(3);
    assert!(bus.run(3).is_empty());
    assert_eq!(a.read32(regs::TSR) & tsr::TME0, 0);
}

#[test]
fn loop_back_combined_with_silent_is_internal() {
    let (mut a, mut b, mut bus) = pair_with(btr::LBKM | btr::SILM);
    let f = std_frame(0x321, &[1, 2, 3]);
    load(&mut a, 0, &f);
    let req = a.poll_tx(bus.now).unwrap();
    assert!(req.self_ack && req.internal);
    bus.run(2);
    assert_ne!(a.read32(regs::TSR) & tsr::TXOK0, 0);
    assert_eq!(receive(&mut a, 0).unwrap().frame, f);
    assert_eq!(receive(&mut b, 0), None, "nothing on the wire");
    load(&mut b, 0, &std_frame(0x10, &[]));
    bus.run(2);
    assert_eq!(receive(&mut a, 0), None, "CANRX disconnected");
}
