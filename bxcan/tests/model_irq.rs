//! The four interrupt lines of the bxCAN model (RM0410 40.8 "bxCAN interrupts", figure
//! "Event flags and interrupt generation"), from register flags and enables.

#[path = "model_bus.rs"]
mod bus;

use bus::*;
use twocan_bxcan::model::{BxCanModel, IrqLines};
use twocan_bxcan::regs::{self, ier, mcr, msr, rfxr, tsr};
use twocan_core::{LastErrorCode, Registers};

const NONE: IrqLines = IrqLines {
    tx: false,
    rx0: false,
    rx1: false,
    sce: false,
};

#[test]
fn transmit_line_follows_rqcp_and_tmeie() {
    let (mut a, _b, mut bus) = started_pair(BxCanModel::can1(), BxCanModel::can3());
    for x in 0..3 {
        load(&mut a, x, &std_frame(0x10 + x as u16, &[]));
    }
    bus.run(5);
    assert_eq!(a.irq_lines(), NONE, "TMEIE = 0");
    a.write32(regs::IER, ier::TMEIE);
    assert_eq!(a.irq_lines(), IrqLines { tx: true, ..NONE });
    a.write32(regs::TSR, tsr::RQCP0 | tsr::RQCP1);
    assert!(a.irq_lines().tx, "RQCP2 still set");
    a.write32(regs::TSR, tsr::RQCP2);
    assert_eq!(a.irq_lines(), NONE);
}

#[test]
fn fifo_lines_follow_fmp_full_and_fovr() {
    let mut m = BxCanModel::can1();
    let mut bus = TinyBus::new(&[&m]);
    enter_init(&mut m);
    accept_all(&mut m, 0, 0);
    leave_init(&mut m, &mut bus);

    m.write32(regs::IER, ier::FFIE0);
    bus.inject(&std_frame(1, &[]));
    bus.inject(&std_frame(2, &[]));
    assert_eq!(m.irq_lines(), NONE, "pending but not full");
    bus.inject(&std_frame(3, &[]));
    assert_eq!(m.irq_lines(), IrqLines { rx0: true, ..NONE });
    m.write32(regs::RF0R, rfxr::FULL);
    assert_eq!(m.irq_lines(), NONE);

    m.write32(regs::IER, ier::FOVIE0);
    bus.inject(&std_frame(4, &[]));
    assert_eq!(m.irq_lines(), IrqLines { rx0: true, ..NONE });
    m.write32(regs::RF0R, rfxr::FOVR);
    assert_eq!(m.irq_lines(), NONE);

    m.write32(regs::IER, ier::FMPIE0);
    assert!(m.irq_lines().rx0, "messages pending");
    for _ in 0..3 {
        m.write32(regs::RF0R, rfxr::RFOM);
    }
    assert_eq!(m.irq_lines(), NONE, "FIFO empty");

    // FIFO 1 drives the RX1 line only.
    enter_init(&mut m);
    accept_all(&mut m, 0, 1);
    leave_init(&mut m, &mut bus);
    m.write32(regs::IER, ier::FMPIE0 | ier::FMPIE1);
    bus.inject(&std_frame(5, &[]));
    assert_eq!(m.irq_lines(), IrqLines { rx1: true, ..NONE });
    m.write32(regs::IER, ier::FMPIE0);
    assert_eq!(
        m.irq_lines(),
        NONE,
        "the line is a level: disabling drops it"
    );
}

#[test]
fn status_change_line_follows_erri_wkui_slaki() {
    let (m, mut bus) = started(BxCanModel::can1());
    m.write32(regs::IER, ier::LECIE);
    bus.inject_rx_error(LastErrorCode::Form, false);
    assert_eq!(m.irq_lines(), NONE, "ERRI set, ERRIE = 0");
    m.write32(regs::IER, ier::LECIE | ier::ERRIE);
    assert_eq!(m.irq_lines(), IrqLines { sce: true, ..NONE });
    m.write32(regs::MSR, msr::ERRI);
    assert_eq!(m.irq_lines(), NONE);

    m.write32(regs::IER, ier::SLKIE);
    m.write32(regs::MCR, mcr::SLEEP);
    assert_eq!(m.irq_lines(), IrqLines { sce: true, ..NONE });
    m.write32(regs::MSR, msr::SLAKI);
    assert_eq!(m.irq_lines(), NONE);

    bus.inject(&std_frame(0x1, &[]));
    assert_ne!(m.read32(regs::MSR) & msr::WKUI, 0);
    assert_eq!(m.irq_lines(), NONE, "WKUIE = 0");
    m.write32(regs::IER, ier::WKUIE);
    assert_eq!(m.irq_lines(), IrqLines { sce: true, ..NONE });
    assert!(m.irq_lines().any());
}
