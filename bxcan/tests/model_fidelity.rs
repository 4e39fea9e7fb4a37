//! bxCAN model fidelity (issue 17 items and the races of issue 14), at register level:
//! - 32-bit filters compare bit 0 (the identifier side has "0" there);
//! - `IER.EPVIE` raises `MSR.ERRI` when error-passive is entered;
//! - `MSR.TXM` / `RXM` / `RX` / `SAMP` follow the frame on the wire;
//! - `MCR.DBF` freezes reception and transmission during a debug halt;
//! - an `ABRQx` written while the mailbox is transmitting waits for the outcome: whether the
//!   frame went out is `TXOKx` once `RQCPx` is set (RM0410 40.7.1 "Transmit abort" /
//!   "transmit mailbox states");
//! - `LEC` read, then set to 0b111 by software: a code latched in between is lost.

#[path = "model_bus.rs"]
mod tiny;

use tiny::{enter_init, load, receive, std_frame, tir_of};
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{self, esr, fa1r, fm1r, fmr, fs1r, ier, mcr, msr, tsr};
use twocan_core::{Frame, Registers};
use twocan_sim::{Bus, BusEvent, Fault, SimNode};

/// Initialization, bank 0 as a 32-bit filter (`list` or mask) with `fr1`/`fr2` into FIFO 0,
/// then normal mode with `mcr_bits`; joins `bus` and synchronises.
fn join(bus: &mut Bus, name: &str, mcr_bits: u32, list: bool, fr1: u32, fr2: u32) -> BxCanModel {
    let mut m = BxCanModel::can1();
    bus.attach(name, m.clone());
    enter_init(&mut m);
    m.modify32(regs::FMR, |v| v | fmr::FINIT);
    m.modify32(regs::FS1R, |v| v | fs1r::fsc(0));
    m.modify32(regs::FM1R, |v| {
        if list {
            v | fm1r::fbm(0)
        } else {
            v & !fm1r::fbm(0)
        }
    });
    m.write32(regs::fir1(0), fr1);
    m.write32(regs::fir2(0), fr2);
    m.modify32(regs::FA1R, |v| v | fa1r::fact(0));
    m.modify32(regs::FMR, |v| v & !fmr::FINIT);
    m.write32(regs::MCR, mcr_bits);
    bus.run_until_idle(100).unwrap();
    assert_eq!(m.read32(regs::MSR) & msr::INAK, 0);
    m
}

fn accept_all(bus: &mut Bus, name: &str, mcr_bits: u32) -> BxCanModel {
    join(bus, name, mcr_bits, false, 0, 0)
}

/// Sends `f` from a plain node and returns whether `m` stored it in FIFO 0.
fn delivered(bus: &mut Bus, m: &mut BxCanModel, f: Frame) -> bool {
    let peer = SimNode::new().with_one_shot(true).shared();
    bus.attach("peer", peer.clone());
    peer.borrow_mut().send(f);
    bus.run_until_idle(10_000).unwrap();
    receive(m, 0).is_some_and(|r| r.frame == f)
}

#[test]
fn list_filter_entry_with_bit_0_set_never_matches() {
    let f = std_frame(0x2A5, &[1]);
    let g = std_frame(0x2A6, &[2]);
    let mut bus = Bus::new(500_000).unwrap();
    let mut m = join(&mut bus, "m", 0, true, tir_of(&f) | 1, tir_of(&g));
    assert!(!delivered(&mut bus, &mut m, f), "bit 0 set: no match");
    assert!(delivered(&mut bus, &mut m, g), "the other entry matches");
}

#[test]
fn mask_filter_compares_bit_0_only_where_the_mask_says() {
    let f = std_frame(0x155, &[3]);
    // Identifier with bit 0 set, mask checking every bit: nothing can match.
    let mut bus = Bus::new(500_000).unwrap();
    let mut m = join(&mut bus, "m", 0, false, tir_of(&f) | 1, u32::MAX);
    assert!(!delivered(&mut bus, &mut m, f));
    // The same identifier with bit 0 left out of the mask matches.
    let mut bus = Bus::new(500_000).unwrap();
    let mut m = join(&mut bus, "m", 0, false, tir_of(&f) | 1, !1);
    assert!(delivered(&mut bus, &mut m, f));
}

#[test]
fn epvie_raises_erri_when_error_passive_is_entered() {
    for enabled in [true, false] {
        let mut bus = Bus::new(500_000).unwrap();
        let mut m = accept_all(&mut bus, "m", 0);
        let ie = if enabled {
            ier::EPVIE | ier::ERRIE
        } else {
            ier::ERRIE
        };
        m.write32(regs::IER, ie);
        // Alone on the bus: an acknowledge error per attempt, TEC + 8 until error-passive.
        load(&mut m, 0, &std_frame(0x10, &[]));
        for attempt in 1..=20u32 {
            // Error-passive, it waits 8 bits (suspend transmission) between attempts.
            while !matches!(bus.step_until(u64::MAX), Some(BusEvent::Frame(_))) {}
            let tec = esr::TEC.get(m.read32(regs::ESR));
            let passive = m.read32(regs::ESR) & esr::EPVF != 0;
            assert_eq!(tec, (8 * attempt).min(128), "attempt {attempt}");
            assert_eq!(passive, tec >= 128);
            let erri = m.read32(regs::MSR) & msr::ERRI != 0;
            assert_eq!(erri, enabled && passive, "attempt {attempt}");
            assert_eq!(m.irq_lines().sce, enabled && passive);
        }
    }
}

#[test]
fn msr_status_bits_follow_the_frame_on_the_wire() {
    let mut bus = Bus::new(500_000).unwrap();
    let mut a = accept_all(&mut bus, "a", 0);
    let b = accept_all(&mut bus, "b", 0);
    let idle = msr::SAMP | msr::RX;
    let status = |m: &BxCanModel| m.read32(regs::MSR) & (msr::TXM | msr::RXM | msr::SAMP | msr::RX);
    assert_eq!((status(&a), status(&b)), (idle, idle));
    let f = std_frame(0x7F0, &[0xFF]);
    load(&mut a, 0, &f);
    // After the SOF bit (dominant).
    bus.run_bits(1);
    assert_eq!(status(&a), msr::TXM);
    assert_eq!(status(&b), msr::RXM);
    // Identifier 0x7F0: bits 1..=7 are recessive; after bit 3 the wire is recessive.
    bus.run_bits(2);
    assert_eq!(status(&a), msr::TXM | idle);
    assert_eq!(status(&b), msr::RXM | idle);
    bus.run_until_idle(10_000).unwrap();
    assert_eq!((status(&a), status(&b)), (idle, idle));
}

#[test]
fn msr_txm_turns_into_rxm_when_arbitration_is_lost() {
    let mut bus = Bus::new(500_000).unwrap();
    let mut a = accept_all(&mut bus, "a", 0);
    let mut b = accept_all(&mut bus, "b", 0);
    load(&mut a, 0, &std_frame(0x100, &[]));
    load(&mut b, 0, &std_frame(0x101, &[]));
    bus.run_bits(5);
    assert_ne!(b.read32(regs::MSR) & msr::TXM, 0, "b still in arbitration");
    bus.run_bits(10); // past the arbitration field (bit 12)
    assert_eq!(b.read32(regs::MSR) & (msr::TXM | msr::RXM), msr::RXM);
    assert_eq!(a.read32(regs::MSR) & (msr::TXM | msr::RXM), msr::TXM);
}

#[test]
fn debug_freeze_only_with_dbf() {
    for dbf in [true, false] {
        let mut bus = Bus::new(500_000).unwrap();
        let mut m = accept_all(&mut bus, "m", if dbf { mcr::DBF } else { 0 });
        let listener = SimNode::new().with_listen_only(true).shared();
        let talker = SimNode::new().shared();
        bus.attach("listener", listener.clone());
        bus.attach("talker", talker.clone());
        m.set_debug_halt(true);
        let mine = std_frame(0x111, &[1]);
        let theirs = std_frame(0x222, &[2]);
        load(&mut m, 0, &mine);
        talker.borrow_mut().send(theirs);
        bus.run_for(2_000);
        let sent = listener.borrow().received_frames().contains(&mine);
        let got = receive(&mut m, 0).map(|r| r.frame);
        if dbf {
            assert!(!sent, "frozen: no transmission");
            assert_eq!(got, None, "frozen: no reception");
            assert_eq!(m.read32(regs::TSR) & tsr::TME0, 0, "still pending");
            // Nobody acknowledged the talker meanwhile (the listener is listen-only): it
            // retried until the halt ended.
            m.set_debug_halt(false);
            bus.run_for(2_000);
            assert!(listener.borrow().received_frames().contains(&mine));
            assert_eq!(receive(&mut m, 0).map(|r| r.frame), Some(theirs));
        } else {
            assert!(sent);
            assert_eq!(got, Some(theirs));
        }
    }
}

#[test]
fn abort_request_while_transmitting_waits_and_txok_tells_the_outcome() {
    for fail in [false, true] {
        let mut bus = Bus::new(500_000).unwrap();
        let mut a = accept_all(&mut bus, "a", 0);
        let peer = SimNode::new().shared();
        bus.attach("peer", peer.clone());
        let f = std_frame(0x321, &[9, 9]);
        load(&mut a, 0, &f);
        if fail {
            bus.inject_next(Fault::Bit { at: None });
        }
        bus.run_bits(8);
        assert_ne!(a.read32(regs::MSR) & msr::TXM, 0);
        // The driver sees mailbox 0 still requested and not complete, and aborts it.
        let seen = a.read32(regs::TSR);
        assert_eq!(seen & (tsr::TME0 | tsr::RQCP0), 0);
        a.write32(regs::TSR, tsr::ABRQ0);
        // Not decided yet: the mailbox is in transmit state, ABRQ0 reads 1.
        let t = a.read32(regs::TSR);
        assert_eq!(t & (tsr::ABRQ0 | tsr::RQCP0), tsr::ABRQ0);
        bus.run_until_idle(10_000).unwrap();
        let t = a.read32(regs::TSR);
        assert_eq!(t & (tsr::RQCP0 | tsr::TME0), tsr::RQCP0 | tsr::TME0);
        assert_eq!(t & tsr::ABRQ0, 0);
        if fail {
            assert_eq!(t & tsr::TXOK0, 0, "aborted after the failed attempt");
            assert!(peer.borrow().received_frames().is_empty());
            assert_eq!(bus.trace().records().len(), 1, "no retransmission");
        } else {
            assert_ne!(
                t & tsr::TXOK0,
                0,
                "sent: counting it aborted would be wrong"
            );
            assert_eq!(peer.borrow().received_frames(), vec![f]);
        }
    }
}

#[test]
fn lec_set_to_seven_by_software_loses_a_code_latched_after_the_read() {
    let mut bus = Bus::new(500_000).unwrap();
    let mut a = accept_all(&mut bus, "a", mcr::NART);
    let peer = SimNode::new().shared();
    bus.attach("peer", peer.clone());
    load(&mut a, 0, &std_frame(0x40, &[1]));
    bus.inject_next(Fault::Bit { at: None });
    bus.run_until_idle(10_000).unwrap();
    // The driver reads LEC: a bit error.
    let read = esr::LEC.get(a.read32(regs::ESR));
    assert!(read == esr::LEC_BIT_DOMINANT || read == esr::LEC_BIT_RECESSIVE);
    // Before it writes 0b111, the next frame gets an acknowledge error.
    load(&mut a, 1, &std_frame(0x41, &[2]));
    bus.inject_next(Fault::Ack);
    bus.run_until_idle(10_000).unwrap();
    assert_eq!(esr::LEC.get(a.read32(regs::ESR)), esr::LEC_ACK);
    a.write32(regs::ESR, esr::LEC.val(esr::LEC_SOFTWARE));
    // The acknowledge error was never seen through LEC; the counter did count it.
    assert_eq!(esr::LEC.get(a.read32(regs::ESR)), esr::LEC_SOFTWARE);
    assert_eq!(esr::TEC.get(a.read32(regs::ESR)), 16);
}

/// Bits until `done(m)` holds, running the bus one bit at a time (at most `max`).
fn bits_until(bus: &mut Bus, max: u64, mut done: impl FnMut() -> bool) -> u64 {
    for n in 0..max {
        if done() {
            return n;
        }
        bus.run_bits(1);
    }
    panic!("not within {max} bits");
}

#[test]
fn initialization_request_waits_for_the_frame_in_flight_at_the_lowest_bit_rate() {
    use twocan_core::timing::frame_time::{bits_to_micros, MAX_FRAME_IN_FLIGHT_BITS};
    use twocan_sim::frame_bits;
    // 2.5 kbit/s, the slowest exact ACAN rate; a long extended frame with heavy stuffing.
    let mut bus = Bus::new(2_500).unwrap();
    let mut a = accept_all(&mut bus, "a", 0);
    let mut b = accept_all(&mut bus, "b", 0);
    let f = Frame::extended(0, &[0; 8]).unwrap();
    let total = u64::from(frame_bits(&f).total);
    load(&mut a, 0, &f);
    bus.run_bits(1);
    // Both controllers are asked to enter initialization one bit into the frame.
    a.modify32(regs::MCR, |v| v | mcr::INRQ);
    b.modify32(regs::MCR, |v| v | mcr::INRQ);
    let inak = |m: &BxCanModel| m.read32(regs::MSR) & msr::INAK != 0;
    assert!(!inak(&a) && !inak(&b), "not while the frame is on the wire");
    let waited = bits_until(&mut bus, 1_000, || inak(&a) && inak(&b));
    // Transmitter and receiver acknowledge at the end of the end of frame.
    assert_eq!(waited, total - 1);
    assert!(waited <= u64::from(MAX_FRAME_IN_FLIGHT_BITS));
    // At 2.5 kbit/s that is longer than a fixed 18 ms bound, and within the computed one.
    let us = bus.bits_to_micros(waited);
    assert!(us > 18_000, "{us} µs");
    assert!(us <= bits_to_micros(MAX_FRAME_IN_FLIGHT_BITS, 2_500).unwrap());
    // The frame was completed and stored before initialization mode.
    assert_eq!(receive(&mut b, 0).map(|r| r.frame), Some(f));
    assert_ne!(a.read32(regs::TSR) & tsr::TXOK0, 0);
}
