//! The bxCAN model on the simulated bus (`twocan_sim::Bus`): the `BusNode`
//! contract end to end — SYNC through `next_wakeup`, arbitration, acknowledgement, error
//! frames, bus-off recovery, loop back — with the model driven through registers.

#[path = "model_bus.rs"]
mod tiny;

use tiny::{accept_all, enter_init, load, receive, std_frame};
use twocan_bxcan::model::{BxCanModel, Mode};
use twocan_bxcan::regs::{self, btr, esr, mcr, msr, tsr};
use twocan_core::Registers;
use twocan_sim::{Bus, BusEvent, Fault, SimNode};

/// Initialization, accept-all filter into FIFO 0, extra `MCR` bits, then INRQ cleared.
fn configure(m: &mut BxCanModel, mcr_bits: u32, btr_bits: u32) {
    enter_init(m);
    accept_all(m, 0, 0);
    m.modify32(regs::BTR, |v| v | btr_bits);
    m.write32(regs::MCR, mcr_bits);
}

#[test]
fn sync_and_frame_exchange() {
    let mut bus = Bus::new(500_000).unwrap();
    let (mut a, mut b) = (BxCanModel::can1(), BxCanModel::can3());
    let sniffer = SimNode::new().shared();
    bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    bus.attach("sniffer", sniffer.clone());
    configure(&mut a, 0, 0);
    configure(&mut b, mcr::TTCM, 0);
    assert_ne!(a.read32(regs::MSR) & msr::INAK, 0);
    // SYNC completes through the models' wake-up hints.
    bus.run_until_idle(1_000).unwrap();
    assert_eq!(bus.now(), 11);
    assert_eq!(
        (a.state().mode, b.state().mode),
        (Mode::Normal, Mode::Normal)
    );

    let f = std_frame(0x123, &[0xDE, 0xAD]);
    load(&mut a, 0, &f);
    bus.run_until_idle(1_000).unwrap();
    assert_ne!(a.read32(regs::TSR) & tsr::TXOK0, 0);
    let r = receive(&mut b, 0).unwrap();
    assert_eq!(r.frame, f);
    assert_eq!(
        r.time, 11,
        "b's timer runs from TTCM = 1 (bus time 0) to the SOF (11)"
    );
    assert_eq!(sniffer.borrow().received_frames(), vec![f]);
    assert_eq!(receive(&mut a, 0), None);
}

#[test]
fn arbitration_between_the_models() {
    let mut bus = Bus::new(500_000).unwrap();
    let (mut a, mut b) = (BxCanModel::can1(), BxCanModel::can3());
    bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    configure(&mut a, mcr::NART, 0);
    configure(&mut b, 0, 0);
    bus.run_until_idle(1_000).unwrap();
    load(&mut a, 0, &std_frame(0x200, &[1]));
    load(&mut b, 0, &std_frame(0x100, &[2]));
    bus.run_until_idle(10_000).unwrap();
    let t = a.read32(regs::TSR);
    assert_eq!(
        t & 0x00FF_FFFF,
        tsr::RQCP0 | tsr::ALST0,
        "one-shot: lost, not retried"
    );
    assert_eq!(receive(&mut a, 0).unwrap().frame, std_frame(0x100, &[2]));
    assert_eq!(receive(&mut b, 0), None, "a gave up");
}

#[test]
fn lone_transmitter_stops_counting_at_error_passive() {
    let mut bus = Bus::new(500_000).unwrap();
    let mut a = BxCanModel::can1();
    bus.attach("a", a.clone());
    configure(&mut a, 0, 0);
    bus.run_until_idle(100).unwrap();
    load(&mut a, 0, &std_frame(0x7, &[]));
    bus.run_for(20_000);
    let e = a.read32(regs::ESR);
    assert_eq!(esr::TEC.get(e), 128);
    assert_eq!(esr::LEC.get(e), esr::LEC_ACK);
    assert_eq!(e & (esr::EPVF | esr::BOFF), esr::EPVF);
}

#[test]
fn bus_off_and_automatic_recovery() {
    let mut bus = Bus::new(500_000).unwrap();
    let mut a = BxCanModel::can1();
    let peer = SimNode::new().shared();
    let id_a = bus.attach("a", a.clone());
    bus.attach("peer", peer.clone());
    configure(&mut a, mcr::ABOM, 0);
    bus.run_until_idle(100).unwrap();
    bus.inject_from(id_a, 32, Fault::Bit { at: None });
    let f = std_frame(0x42, &[4, 2]);
    load(&mut a, 0, &f);
    // Error-passive from the 16th error on, it waits 8 bits of suspend transmission after
    // each intermission (idle events of exactly 8 bits).
    while !a.state().bus_off {
        match bus.step_until(u64::MAX) {
            Some(BusEvent::Frame(_)) => {}
            Some(BusEvent::Idle { from, to }) => assert_eq!(to - from, 8),
            other => panic!("a retries until bus-off: {other:?}"),
        }
    }
    let off_at = bus.now();
    assert_ne!(a.read32(regs::ESR) & esr::BOFF, 0);
    // Recovery (128 × 11 recessive bits) and the retransmission, driven by the hints.
    bus.run_until_idle(10_000).unwrap();
    assert!(!a.state().bus_off);
    assert!(bus.now() >= off_at + 128 * 11);
    assert_eq!(peer.borrow().received_frames(), vec![f]);
    assert_ne!(a.read32(regs::TSR) & tsr::TXOK0, 0);
}

#[test]
fn loop_back_and_silent_loop_back() {
    let mut bus = Bus::new(500_000).unwrap();
    let (mut a, mut b) = (BxCanModel::can1(), BxCanModel::can3());
    let sniffer = SimNode::new().with_listen_only(true).shared();
    bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    bus.attach("sniffer", sniffer.clone());
    configure(&mut a, 0, btr::LBKM);
    configure(&mut b, 0, btr::LBKM | btr::SILM);
    bus.run_until_idle(100).unwrap();
    let fa = std_frame(0x10, &[1]);
    let fb = std_frame(0x20, &[2]);
    load(&mut a, 0, &fa);
    load(&mut b, 0, &fb);
    bus.run_until_idle(10_000).unwrap();
    assert_eq!(
        receive(&mut a, 0).unwrap().frame,
        fa,
        "loop back: own frame, self-acknowledged"
    );
    assert_eq!(receive(&mut b, 0).unwrap().frame, fb, "internal: own frame");
    assert_eq!(receive(&mut a, 0), None);
    assert_eq!(receive(&mut b, 0), None);
    assert_eq!(
        sniffer.borrow().received_frames(),
        vec![fa],
        "only the loop back frame is on the wire"
    );
}
