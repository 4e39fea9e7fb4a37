//! Receive FIFOs of the bxCAN model (RM0410 40.7.3 "Reception handling", 40.7.5
//! "Message storage"; notes "FIFO Management", "FIFO Overrun"), through registers.

#[path = "model_bus.rs"]
mod bus;

use bus::*;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{self, ier, mcr, rdtxr, rfxr, rixr};
use twocan_core::{Frame, Registers};

fn fmp(m: &BxCanModel, x: usize) -> u32 {
    rfxr::FMP.get(m.read32(regs::rfxr(x)))
}

fn frames(n: u16) -> Vec<Frame> {
    (0..n).map(|i| std_frame(0x100 + i, &[i as u8])).collect()
}

#[test]
fn fifo_pending_states_and_release() {
    let (mut m, mut bus) = started(BxCanModel::can1());
    let f = frames(3);
    assert_eq!(m.read32(regs::RF0R), 0);
    bus.inject(&f[0]);
    assert_eq!(fmp(&m, 0), 1, "pending_1");
    bus.inject(&f[1]);
    assert_eq!(fmp(&m, 0), 2, "pending_2");
    assert_eq!(m.read32(regs::RF0R) & rfxr::FULL, 0);
    bus.inject(&f[2]);
    assert_eq!(
        m.read32(regs::RF0R),
        rfxr::FMP.val(3) | rfxr::FULL,
        "pending_3, FULL"
    );
    // The output mailbox shows the oldest message; RFOM releases it.
    assert_eq!(receive(&mut m, 0).unwrap().frame, f[0]);
    assert_eq!(fmp(&m, 0), 2);
    assert_ne!(
        m.read32(regs::RF0R) & rfxr::FULL,
        0,
        "FULL is cleared by software only"
    );
    m.write32(regs::RF0R, rfxr::FULL);
    assert_eq!(m.read32(regs::RF0R), rfxr::FMP.val(2));
    assert_eq!(receive(&mut m, 0).unwrap().frame, f[1]);
    assert_eq!(receive(&mut m, 0).unwrap().frame, f[2]);
    assert_eq!(m.read32(regs::RF0R), 0);
    // Releasing an empty FIFO has no effect.
    m.write32(regs::RF0R, rfxr::RFOM);
    assert_eq!(m.read32(regs::RF0R), 0);
    assert_eq!(
        m.read32(regs::rixr(0)),
        0,
        "empty output mailbox reads 0 in the model"
    );
    assert_eq!(m.read32(regs::RF1R), 0, "FIFO 1 untouched");
}

#[test]
fn overrun_with_fifo_unlocked_overwrites_the_newest() {
    let (m, mut bus) = started(BxCanModel::can1());
    m.write32(regs::IER, ier::FOVIE0);
    let f = frames(5);
    for x in &f {
        bus.inject(x);
    }
    let r = m.read32(regs::RF0R);
    assert_eq!(r, rfxr::FMP.val(3) | rfxr::FULL | rfxr::FOVR);
    assert!(m.irq_lines().rx0);
    let got: Vec<Frame> = m.fifo_contents(0).iter().map(|e| e.frame).collect();
    assert_eq!(
        got,
        [f[0], f[1], f[4]],
        "the latest message is always available"
    );
    assert_eq!(m.state().overruns[0], 2);
    m.write32(regs::RF0R, rfxr::FOVR);
    assert_eq!(m.read32(regs::RF0R) & rfxr::FOVR, 0);
    assert!(!m.irq_lines().rx0);
}

#[test]
fn overrun_with_fifo_locked_discards_the_new_message() {
    let (mut m, mut bus) = started(BxCanModel::can1());
    m.modify32(regs::MCR, |v| v | mcr::RFLM);
    let f = frames(5);
    for x in &f {
        bus.inject(x);
    }
    assert_ne!(m.read32(regs::RF0R) & rfxr::FOVR, 0);
    let got: Vec<Frame> = (0..3).map(|_| receive(&mut m, 0).unwrap().frame).collect();
    assert_eq!(
        got,
        [f[0], f[1], f[2]],
        "the three oldest messages are kept"
    );
    assert_eq!(receive(&mut m, 0), None);
}

#[test]
fn output_mailbox_register_layout() {
    let (mut m, mut bus) = started(BxCanModel::can1());
    let e = Frame::remote(0x1234_5678, true, 5).unwrap();
    bus.inject(&e);
    let rir = m.read32(regs::rixr(0));
    assert_eq!(rixr::STID.get(rir), 0x1234_5678 >> 18);
    assert_eq!(rixr::EXID.get(rir), 0x1234_5678 & 0x3_FFFF);
    assert_eq!(rir & (rixr::IDE | rixr::RTR | 1), rixr::IDE | rixr::RTR);
    assert_eq!(rdtxr::DLC.get(m.read32(regs::rdtxr(0))), 5);
    assert_eq!(m.read32(regs::rdlxr(0)), 0);
    m.write32(regs::RF0R, rfxr::RFOM);

    let s = std_frame(0x7FF, &[1, 2, 3, 4, 5, 6, 7, 8]);
    bus.inject(&s);
    assert_eq!(m.read32(regs::rixr(0)), 0x7FF << 21);
    assert_eq!(m.read32(regs::rdtxr(0)) & 0xFFFF, 8, "DLC 8, FMI 0");
    assert_eq!(m.read32(regs::rdlxr(0)), 0x0403_0201);
    assert_eq!(m.read32(regs::rdhxr(0)), 0x0807_0605);
    // Read-only: writes to the output mailbox are ignored.
    m.write32(regs::rixr(0), 0);
    m.write32(regs::rdlxr(0), 0);
    assert_eq!(m.read32(regs::rdlxr(0)), 0x0403_0201);
    assert_eq!(receive(&mut m, 0).unwrap().frame, s);
}

#[test]
fn fifo_1_assignment() {
    let mut m = BxCanModel::can1();
    let mut bus = TinyBus::new(&[&m]);
    enter_init(&mut m);
    accept_all(&mut m, 3, 1);
    leave_init(&mut m, &mut bus);
    bus.inject(&std_frame(0x1, &[]));
    assert_eq!(fmp(&m, 0), 0);
    assert_eq!(fmp(&m, 1), 1);
    let r = receive(&mut m, 1).unwrap();
    assert_eq!(
        r.fmi, 0,
        "bank 3 is the first bank of FIFO 1: filter number 0"
    );
}

#[test]
fn received_frames_count_down_rec() {
    let (mut m, mut bus) = started(BxCanModel::can1());
    bus.inject_rx_error(twocan_core::LastErrorCode::Crc, false);
    bus.inject_rx_error(twocan_core::LastErrorCode::Crc, true);
    // +1, then +1 and +8 (ISO 11898-1 rules 1 and 2)
    assert_eq!(twocan_bxcan::regs::esr::REC.get(m.read32(regs::ESR)), 10);
    bus.inject(&std_frame(0x1, &[]));
    let e = m.read32(regs::ESR);
    assert_eq!(twocan_bxcan::regs::esr::REC.get(e), 9);
    assert_eq!(
        twocan_bxcan::regs::esr::LEC.get(e),
        0,
        "a correct transfer clears LEC"
    );
    assert!(receive(&mut m, 0).is_some());
}
