//! Dual CAN: CAN1 (master) and CAN2 (slave) sharing CAN1's 28 filter banks, split at
//! `FMR.CAN2SB` (RM0410 40.2 "bxCAN main features", 40.9.4 "CAN filter master
//! register"; notes "Filter Bank Scale and Mode Configuration"), through registers.

#[path = "model_bus.rs"]
mod bus;

use bus::*;
use twocan_bxcan::model::{BxCanModel, Mode};
use twocan_bxcan::regs::{self, fa1r, ffa1r, fm1r, fmr, fs1r, Instance};
use twocan_core::Registers;

/// CAN1 and CAN2 in normal mode on one bus, no filter configured.
fn dual() -> (BxCanModel, BxCanModel, TinyBus) {
    let (mut can1, mut can2) = BxCanModel::can1_can2();
    let mut bus = TinyBus::new(&[&can1, &can2]);
    enter_init(&mut can1);
    enter_init(&mut can2);
    leave_init(&mut can1, &mut bus);
    leave_init(&mut can2, &mut bus);
    (can1, can2, bus)
}

fn set_can2sb(can1: &mut BxCanModel, sb: u32) {
    can1.modify32(regs::FMR, |v| fmr::CAN2SB.set(v, sb));
}

/// Configures `bank` through CAN1's filter registers: 32-bit, `list`, FIFO `fifo`, with
/// `r1`/`r2`, active.
fn bank32(can1: &mut BxCanModel, bank: usize, fifo: usize, list: bool, r1: u32, r2: u32) {
    can1.modify32(regs::FMR, |v| v | fmr::FINIT);
    can1.modify32(regs::FS1R, |v| v | fs1r::fsc(bank));
    can1.modify32(regs::FM1R, |v| {
        if list {
            v | fm1r::fbm(bank)
        } else {
            v & !fm1r::fbm(bank)
        }
    });
    can1.modify32(regs::FFA1R, |v| {
        if fifo == 1 {
            v | ffa1r::ffa(bank)
        } else {
            v & !ffa1r::ffa(bank)
        }
    });
    can1.write32(regs::fir1(bank), r1);
    can1.write32(regs::fir2(bank), r2);
    can1.modify32(regs::FA1R, |v| v | fa1r::fact(bank));
    can1.modify32(regs::FMR, |v| v & !fmr::FINIT);
}

fn where_is(m: &mut BxCanModel) -> Option<(usize, u32)> {
    (0..2).find_map(|x| receive(m, x).map(|r| (x, r.fmi)))
}

#[test]
fn instances_and_filter_windows() {
    let (mut can1, can2) = BxCanModel::can1_can2();
    assert_eq!(
        (can1.instance(), can2.instance()),
        (Instance::Can1, Instance::Can2)
    );
    assert!(!can1.same_controller(&can2));
    assert!(can1.same_controller(&can1.clone()));
    assert_eq!(can1.read32(regs::FMR), 0x2A1C_0E01, "CAN2SB = 14 at reset");
    // CAN2 has no filter registers: its filter window reads 0 and ignores writes.
    assert_eq!(can2.read32(regs::FMR), 0);
    can2.write32(regs::FMR, 0);
    can2.write32(regs::FA1R, u32::MAX);
    assert_eq!(can2.read32(regs::FA1R), 0);
    assert_eq!(can1.read32(regs::FMR), 0x2A1C_0E01);
    assert_eq!(can1.read32(regs::FA1R), 0);
    // The controllers are independent otherwise.
    enter_init(&mut can1);
    assert_eq!(can2.state().mode, Mode::Sleep);
}

#[test]
fn can2_uses_the_banks_from_can2sb_upward() {
    let (mut can1, mut can2, mut bus) = dual();
    let std_100_1ff = (0x100 << 21, 0x700 << 21); // 0x100..=0x1FF
    bank32(&mut can1, 0, 0, false, std_100_1ff.0, std_100_1ff.1);
    bank32(&mut can1, 14, 1, false, 0, 0); // everything
    bus.inject(&std_frame(0x150, &[]));
    assert_eq!(where_is(&mut can1), Some((0, 0)));
    assert_eq!(
        where_is(&mut can2),
        Some((1, 0)),
        "bank 14 is CAN2's first bank"
    );
    bus.inject(&std_frame(0x250, &[]));
    assert_eq!(where_is(&mut can1), None);
    assert_eq!(where_is(&mut can2), Some((1, 0)));

    // Move the split: bank 14 now belongs to CAN1; CAN2's banks 20..27 are inactive.
    set_can2sb(&mut can1, 20);
    bus.inject(&std_frame(0x250, &[]));
    // FIFO 1 numbering of CAN1: banks 0..13 are FIFO 0, bank 14 is its first FIFO 1 bank.
    assert_eq!(where_is(&mut can1), Some((1, 0)));
    assert_eq!(where_is(&mut can2), None);

    // CAN2SB = 0: every bank to CAN2; CAN1 has none.
    set_can2sb(&mut can1, 0);
    bus.inject(&std_frame(0x150, &[]));
    assert_eq!(where_is(&mut can1), None);
    assert_eq!(
        where_is(&mut can2),
        Some((0, 0)),
        "the 32-bit mask of bank 0 wins"
    );

    // CAN2SB = 28: every bank to CAN1.
    set_can2sb(&mut can1, 28);
    bus.inject(&std_frame(0x150, &[]));
    assert_eq!(where_is(&mut can1), Some((0, 0)));
    assert_eq!(where_is(&mut can2), None);
    assert!(can2.state().dropped >= 2);
}

#[test]
fn can2_numbers_its_filters_from_its_first_bank() {
    let (mut can1, mut can2, mut bus) = dual();
    set_can2sb(&mut can1, 10);
    // CAN1's bank 9 (FIFO 0, 16-bit mask by default, inactive) does not count for CAN2.
    bank32(&mut can1, 10, 0, true, 0x10 << 21, 0x11 << 21);
    bank32(&mut can1, 11, 0, false, 0, 0);
    bus.inject(&std_frame(0x11, &[]));
    assert_eq!(where_is(&mut can2), Some((0, 1)));
    bus.inject(&std_frame(0x12, &[]));
    assert_eq!(where_is(&mut can2), Some((0, 2)));
    assert_eq!(where_is(&mut can1), None);
}

#[test]
fn finit_stops_reception_of_both_controllers() {
    let (mut can1, mut can2, mut bus) = dual();
    bank32(&mut can1, 0, 0, false, 0, 0);
    bank32(&mut can1, 14, 0, false, 0, 0);
    can1.modify32(regs::FMR, |v| v | fmr::FINIT);
    bus.inject(&std_frame(0x1, &[]));
    assert_eq!((where_is(&mut can1), where_is(&mut can2)), (None, None));
    can1.modify32(regs::FMR, |v| v & !fmr::FINIT);
    bus.inject(&std_frame(0x1, &[]));
    assert_eq!(
        (where_is(&mut can1), where_is(&mut can2)),
        (Some((0, 0)), Some((0, 0)))
    );
}

#[test]
fn can1_and_can2_talk_to_each_other() {
    let (mut can1, mut can2, mut bus) = dual();
    bank32(&mut can1, 0, 0, false, 0, 0);
    bank32(&mut can1, 14, 1, false, 0, 0);
    load(&mut can1, 0, &std_frame(0x100, &[1]));
    load(&mut can2, 0, &std_frame(0x080, &[2]));
    let sent = bus.run(4);
    assert_eq!(
        sent.iter().map(|f| f.raw_id()).collect::<Vec<_>>(),
        [0x080, 0x100]
    );
    assert_eq!(receive(&mut can1, 0).unwrap().frame, std_frame(0x080, &[2]));
    assert_eq!(receive(&mut can2, 1).unwrap().frame, std_frame(0x100, &[1]));
}
