//! Error management of the bxCAN model (RM0410 40.7.6 "Error management", 40.9.2 "CAN
//! error status register"; notes "The bxCAN Error Management", "Bus-Off Recovery"),
//! through registers.

#[path = "model_bus.rs"]
mod bus;

use bus::*;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{self, esr, ier, mcr, msr, tsr};
use twocan_core::{LastErrorCode, Registers};
use twocan_sim::BusNode;

fn esr_of(m: &BxCanModel) -> u32 {
    m.read32(regs::ESR)
}

/// One transmission attempt of the pending mailbox that ends in a bit error.
fn failed_attempt(bus: &mut TinyBus) {
    bus.inject_error = Some(LastErrorCode::BitDominant);
    assert!(bus.step().frame.is_some());
    bus.idle(3);
}

#[test]
fn transmit_errors_raise_warning_passive_and_bus_off() {
    let (mut m, mut bus) = started(BxCanModel::can1());
    load(&mut m, 0, &std_frame(0x10, &[1]));
    for n in 1..=31u32 {
        failed_attempt(&mut bus);
        let e = esr_of(&m);
        assert_eq!(esr::TEC.get(e), 8 * n);
        assert_eq!(esr::LEC.get(e), esr::LEC_BIT_DOMINANT);
        assert_eq!(e & esr::EWGF != 0, 8 * n >= 96, "EWGF at {n} errors");
        assert_eq!(e & esr::EPVF != 0, 8 * n > 127, "EPVF at {n} errors");
        assert_eq!(e & esr::BOFF, 0);
        assert_eq!(m.error_active(), 8 * n < 128);
    }
    failed_attempt(&mut bus);
    let e = esr_of(&m);
    assert_ne!(e & esr::BOFF, 0, "TEC > 255");
    assert_eq!(
        esr::TEC.get(e),
        0,
        "TEC shows the low byte of the 9-bit counter (256)"
    );
    assert_eq!(m.state().counters.tec, 256);
    assert!(!m.listens() && !m.acknowledges());
    assert_eq!(bus.step().frame, None, "bus-off: no transmission");
    assert_eq!(
        m.read32(regs::TSR) & tsr::TME0,
        0,
        "the request stays pending"
    );
}

#[test]
fn error_passive_transmitter_acknowledge_errors_do_not_count() {
    // Alone on the bus: every attempt fails with an acknowledge error.
    let (mut m, mut bus) = started(BxCanModel::can1());
    load(&mut m, 0, &std_frame(0x10, &[1]));
    for _ in 0..40 {
        bus.step();
        bus.idle(3);
    }
    let e = esr_of(&m);
    assert_eq!(
        esr::TEC.get(e),
        128,
        "ISO 11898-1 exception 1 stops at error passive"
    );
    assert_eq!(esr::LEC.get(e), esr::LEC_ACK);
    assert_eq!(e & (esr::EPVF | esr::BOFF), esr::EPVF);
}

#[test]
fn receive_errors_and_last_error_code() {
    let (m, mut bus) = started(BxCanModel::can1());
    m.write32(regs::ESR, esr::LEC.val(esr::LEC_SOFTWARE));
    assert_eq!(esr::LEC.get(esr_of(&m)), 7, "software may set LEC to 7");
    // ISO 11898-1 rules 1 and 2 together: +1 for the error, +8 for the dominant bit
    // after the error flag.
    for _ in 0..15 {
        bus.inject_rx_error(LastErrorCode::Stuff, true);
    }
    let e = esr_of(&m);
    assert_eq!(esr::REC.get(e), 135);
    assert_eq!(esr::LEC.get(e), esr::LEC_STUFF);
    assert_eq!(e & (esr::EWGF | esr::EPVF), esr::EWGF | esr::EPVF);
    bus.inject(&std_frame(0x1, &[]));
    let e = esr_of(&m);
    assert_eq!(esr::LEC.get(e), 0);
    assert!(
        esr::REC.get(e) <= 127,
        "back in 119..=127 after a good reception"
    );
    assert_eq!(e & esr::EPVF, 0);
    for code in [
        (LastErrorCode::Form, esr::LEC_FORM),
        (LastErrorCode::Crc, esr::LEC_CRC),
        (LastErrorCode::BitRecessive, esr::LEC_BIT_RECESSIVE),
    ] {
        bus.inject_rx_error(code.0, false);
        assert_eq!(esr::LEC.get(esr_of(&m)), code.1);
    }
}

#[test]
fn erri_needs_an_enabled_error_flag_and_sce_needs_errie() {
    let (m, mut bus) = started(BxCanModel::can1());
    bus.inject_rx_error(LastErrorCode::Crc, false);
    assert_eq!(m.read32(regs::MSR) & msr::ERRI, 0, "LECIE = 0: no ERRI");
    m.write32(regs::IER, ier::LECIE);
    bus.inject_rx_error(LastErrorCode::Crc, false);
    assert_ne!(m.read32(regs::MSR) & msr::ERRI, 0);
    assert!(!m.irq_lines().sce, "ERRIE = 0: no interrupt");
    m.write32(regs::IER, ier::LECIE | ier::ERRIE);
    assert!(m.irq_lines().sce);
    m.write32(regs::MSR, msr::ERRI);
    assert_eq!(m.read32(regs::MSR) & msr::ERRI, 0);
    assert!(!m.irq_lines().sce);
    // Warning flag with EWGIE.
    m.write32(regs::IER, ier::EWGIE | ier::ERRIE);
    for _ in 0..12 {
        bus.inject_rx_error(LastErrorCode::Crc, true);
    }
    assert_ne!(esr_of(&m) & esr::EWGF, 0);
    assert!(m.irq_lines().sce);
}

fn drive_bus_off(m: &mut BxCanModel, bus: &mut TinyBus) {
    load(m, 0, &std_frame(0x10, &[1]));
    for _ in 0..32 {
        failed_attempt(bus);
    }
    assert_ne!(esr_of(m) & esr::BOFF, 0);
}

#[test]
fn automatic_bus_off_recovery() {
    let (mut m, mut b, mut bus) = started_pair(BxCanModel::can1(), BxCanModel::can3());
    m.modify32(regs::MCR, |v| v | mcr::ABOM);
    m.write32(regs::IER, ier::BOFIE | ier::ERRIE);
    drive_bus_off(&mut m, &mut bus);
    assert!(m.irq_lines().sce);
    assert_ne!(m.read32(regs::MSR) & msr::ERRI, 0);
    // 128 × 11 recessive bits; a dominant bit restarts the current run of 11. (The last
    // failed attempt was followed by 3 idle bits: 3 + 1105 = 100 runs of 11 and 8 bits.)
    bus.idle(11 * 100 + 5);
    bus.inject(&std_frame(0x7FF, &[]));
    bus.idle(11 * 28 - 1);
    assert_ne!(esr_of(&m) & esr::BOFF, 0);
    bus.idle(1);
    let e = esr_of(&m);
    assert_eq!(
        e & (esr::BOFF | esr::EPVF | esr::EWGF),
        0,
        "error-active again"
    );
    assert_eq!((esr::TEC.get(e), esr::REC.get(e)), (0, 0));
    // The pending request goes out now (automatic retransmission).
    assert_eq!(bus.run(3).len(), 1);
    assert!(receive(&mut b, 0).is_some());
    assert_ne!(m.read32(regs::TSR) & tsr::TXOK0, 0);
}

#[test]
fn manual_bus_off_recovery_needs_inrq_set_and_cleared() {
    let (mut m, mut bus) = started(BxCanModel::can1());
    drive_bus_off(&mut m, &mut bus);
    bus.idle(11 * 300);
    assert_ne!(
        esr_of(&m) & esr::BOFF,
        0,
        "ABOM = 0: no recovery without software"
    );
    m.modify32(regs::MCR, |v| v | mcr::INRQ);
    assert_ne!(
        m.read32(regs::MSR) & msr::INAK,
        0,
        "initialization mode can be entered"
    );
    bus.idle(11 * 300);
    assert_ne!(
        esr_of(&m) & esr::BOFF,
        0,
        "CANRX is not monitored in initialization mode"
    );
    m.modify32(regs::MCR, |v| v & !mcr::INRQ);
    bus.idle(11);
    assert_eq!(m.read32(regs::MSR) & msr::INAK, 0, "normal mode after SYNC");
    assert_ne!(
        esr_of(&m) & esr::BOFF,
        0,
        "still bus-off: the recovery sequence starts now"
    );
    bus.idle(128 * 11 - 1);
    assert_ne!(esr_of(&m) & esr::BOFF, 0);
    bus.idle(1);
    assert_eq!(esr_of(&m) & esr::BOFF, 0);
    assert_eq!(m.state().counters.tec, 0);
}

#[test]
fn automatic_recovery_does_not_progress_in_initialization_mode() {
    let (mut m, mut bus) = started(BxCanModel::can1());
    m.modify32(regs::MCR, |v| v | mcr::ABOM);
    drive_bus_off(&mut m, &mut bus);
    m.modify32(regs::MCR, |v| v | mcr::INRQ);
    bus.idle(11 * 200);
    assert!(m.state().bus_off);
    m.modify32(regs::MCR, |v| v & !mcr::INRQ);
    bus.idle(11 + 128 * 11);
    assert!(!m.state().bus_off);
}
