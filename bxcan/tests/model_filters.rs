//! Identifier filtering of the bxCAN model (RM0410 40.7.4 "Identifier filtering"; notes
//! "The bxCAN Identifier Filtering": filter numbering example, priority rules, the
//! identifier #4 example), through registers.

#[path = "model_bus.rs"]
mod bus;

use bus::*;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{self, fa1r, ffa1r, fm1r, fmr, fs1r};
use twocan_core::{Frame, Registers};

/// One filter bank's configuration.
#[derive(Debug, Clone, Copy)]
struct Bank {
    bank: usize,
    fifo: usize,
    scale32: bool,
    list: bool,
    active: bool,
    r1: u32,
    r2: u32,
}

/// 32-bit layout of a standard identifier (data frame).
fn s32(id: u32) -> u32 {
    id << 21
}
/// 16-bit layout of a standard identifier (data frame).
fn s16(id: u32) -> u32 {
    id << 5
}
/// 32-bit mask: STID, IDE and RTR must match.
const MASK32_EXACT: u32 = 0xFFE0_0006;
/// 16-bit mask: every bit must match.
const MASK16_EXACT: u32 = 0xFFFF;

fn list32(bank: usize, fifo: usize, active: bool, ids: [u32; 2]) -> Bank {
    Bank {
        bank,
        fifo,
        scale32: true,
        list: true,
        active,
        r1: s32(ids[0]),
        r2: s32(ids[1]),
    }
}
fn mask32(bank: usize, fifo: usize, active: bool, id: u32, mask: u32) -> Bank {
    Bank {
        bank,
        fifo,
        scale32: true,
        list: false,
        active,
        r1: s32(id),
        r2: mask,
    }
}
fn list16(bank: usize, fifo: usize, active: bool, ids: [u32; 4]) -> Bank {
    let r1 = s16(ids[0]) | (s16(ids[1]) << 16);
    let r2 = s16(ids[2]) | (s16(ids[3]) << 16);
    Bank {
        bank,
        fifo,
        scale32: false,
        list: true,
        active,
        r1,
        r2,
    }
}
fn mask16(bank: usize, fifo: usize, active: bool, ids: [u32; 2]) -> Bank {
    let r1 = s16(ids[0]) | (MASK16_EXACT << 16);
    let r2 = s16(ids[1]) | (MASK16_EXACT << 16);
    Bank {
        bank,
        fifo,
        scale32: false,
        list: false,
        active,
        r1,
        r2,
    }
}

/// Programs the banks as a driver would: FINIT = 1, deactivate, configure, activate,
/// FINIT = 0.
fn configure(m: &mut BxCanModel, banks: &[Bank]) {
    m.modify32(regs::FMR, |v| v | fmr::FINIT);
    for b in banks {
        let i = b.bank;
        m.modify32(regs::FA1R, |v| v & !fa1r::fact(i));
        let set = |v: u32, bit: u32, on: bool| if on { v | bit } else { v & !bit };
        m.modify32(regs::FS1R, |v| set(v, fs1r::fsc(i), b.scale32));
        m.modify32(regs::FM1R, |v| set(v, fm1r::fbm(i), b.list));
        m.modify32(regs::FFA1R, |v| set(v, ffa1r::ffa(i), b.fifo == 1));
        m.write32(regs::fir1(i), b.r1);
        m.write32(regs::fir2(i), b.r2);
        m.modify32(regs::FA1R, |v| set(v, fa1r::fact(i), b.active));
    }
    m.modify32(regs::FMR, |v| v & !fmr::FINIT);
}

/// A model in normal mode with `banks` configured (nothing else).
fn with_banks(mut m: BxCanModel, banks: &[Bank]) -> (BxCanModel, TinyBus) {
    let mut bus = TinyBus::new(&[&m]);
    enter_init(&mut m);
    configure(&mut m, banks);
    leave_init(&mut m, &mut bus);
    (m, bus)
}

/// Sends `f` from outside and returns `(fifo, fmi)` of where it landed.
fn land(m: &mut BxCanModel, bus: &mut TinyBus, f: &Frame) -> Option<(usize, u32)> {
    bus.inject(f);
    for fifo in 0..2 {
        if let Some(r) = receive(m, fifo) {
            assert_eq!(r.frame, *f);
            return Some((fifo, r.fmi));
        }
    }
    None
}

/// The notes' "Example of Filter Numbering" table (RM0410 figure "Example of filter
/// numbering"): banks 0..13 over FIFO 0 and FIFO 1, identifier list / mask, 16 / 32-bit,
/// some deactivated. Every filter accepts one identifier of its own: FIFO 0 filter n
/// accepts 0x100 + n, FIFO 1 filter n accepts 0x200 + n.
#[test]
fn filter_numbering_example_of_the_notes() {
    let a = |n: u32| 0x100 + n;
    let b = |n: u32| 0x200 + n;
    let banks = [
        // FIFO 0
        list32(0, 0, true, [a(0), a(1)]),
        mask32(1, 0, true, a(2), MASK32_EXACT),
        list16(3, 0, true, [a(3), a(4), a(5), a(6)]),
        list32(5, 0, false, [a(7), a(8)]),
        mask16(6, 0, true, [a(9), a(10)]),
        list32(9, 0, true, [a(11), a(12)]),
        mask32(13, 0, true, a(13), MASK32_EXACT),
        // FIFO 1
        mask16(2, 1, true, [b(0), b(1)]),
        list32(4, 1, true, [b(2), b(3)]),
        mask16(7, 1, false, [b(4), b(5)]),
        mask16(8, 1, true, [b(6), b(7)]),
        list16(10, 1, false, [b(8), b(9), b(10), b(11)]),
        list32(11, 1, true, [b(12), b(13)]),
        mask32(12, 1, true, b(14), MASK32_EXACT),
    ];
    let (mut m, mut bus) = with_banks(BxCanModel::can1(), &banks);
    let deactivated_0 = [7, 8];
    let deactivated_1 = [4, 5, 8, 9, 10, 11];
    for n in 0..=13 {
        let got = land(&mut m, &mut bus, &std_frame(a(n) as u16, &[n as u8]));
        let want = (!deactivated_0.contains(&n)).then_some((0, n));
        assert_eq!(got, want, "FIFO 0 filter number {n}");
    }
    for n in 0..=14 {
        let got = land(&mut m, &mut bus, &std_frame(b(n) as u16, &[n as u8]));
        let want = (!deactivated_1.contains(&n)).then_some((1, n));
        assert_eq!(got, want, "FIFO 1 filter number {n}");
    }
    assert_eq!(
        m.state().dropped,
        8,
        "frames for deactivated banks are dropped"
    );
    assert_eq!(
        land(&mut m, &mut bus, &std_frame(0x300, &[])),
        None,
        "no match: dropped"
    );
    assert_eq!(m.state().filter_hits[3], 4);
    assert_eq!(m.state().filter_hits[5], 0);
}

/// The notes' "Example of the Filtering Mechanism": filters 0, 1 (identifier list),
/// 2, 3 (identifier mask), 4, 5 (identifier list), all 32-bit in FIFO 0. The message
/// matches identifier #4 and the masks #2 and #3; list mode wins: FMI = 4.
#[test]
fn identifier_4_example_of_the_notes() {
    let banks = [
        list32(0, 0, true, [0x010, 0x011]),
        mask32(1, 0, true, 0x100, 0x7 << 29), // 0x100..=0x1FF
        mask32(2, 0, true, 0x000, 0),         // everything
        list32(3, 0, true, [0x123, 0x124]),
    ];
    let (mut m, mut bus) = with_banks(BxCanModel::can1(), &banks);
    assert_eq!(
        land(&mut m, &mut bus, &std_frame(0x123, &[4])),
        Some((0, 4))
    );
    // Without an identifier match the lower-numbered mask wins.
    assert_eq!(land(&mut m, &mut bus, &std_frame(0x150, &[])), Some((0, 2)));
    assert_eq!(land(&mut m, &mut bus, &std_frame(0x250, &[])), Some((0, 3)));
    assert_eq!(land(&mut m, &mut bus, &std_frame(0x011, &[])), Some((0, 1)));
}

#[test]
fn a_32_bit_filter_wins_over_a_16_bit_one() {
    let banks = [
        list16(0, 0, true, [0x55, 0x55, 0x55, 0x55]),
        mask32(1, 0, true, 0, 0),
    ];
    let (mut m, mut bus) = with_banks(BxCanModel::can1(), &banks);
    assert_eq!(land(&mut m, &mut bus, &std_frame(0x55, &[])), Some((0, 4)));
    // Across FIFOs too: the 32-bit mask in FIFO 1 wins over the 16-bit list in FIFO 0.
    let banks = [
        list16(0, 0, true, [0x55, 0x56, 0x57, 0x58]),
        mask32(1, 1, true, 0, 0),
    ];
    let (mut m, mut bus) = with_banks(BxCanModel::can1(), &banks);
    assert_eq!(land(&mut m, &mut bus, &std_frame(0x56, &[])), Some((1, 0)));
}

#[test]
fn equal_scale_and_mode_lower_filter_number_wins() {
    let banks = [
        mask32(0, 0, true, 0x100, 0x7 << 29),
        mask32(1, 0, true, 0, 0),
    ];
    let (mut m, mut bus) = with_banks(BxCanModel::can1(), &banks);
    assert_eq!(land(&mut m, &mut bus, &std_frame(0x1AA, &[])), Some((0, 0)));
    assert_eq!(land(&mut m, &mut bus, &std_frame(0x2AA, &[])), Some((0, 1)));
    let banks = [
        mask16(0, 0, true, [0x30, 0x31]),
        list16(1, 0, true, [0x31, 0x31, 0x40, 0x31]),
    ];
    let (mut m, mut bus) = with_banks(BxCanModel::can1(), &banks);
    assert_eq!(
        land(&mut m, &mut bus, &std_frame(0x31, &[])),
        Some((0, 2)),
        "list first"
    );
    assert_eq!(land(&mut m, &mut bus, &std_frame(0x30, &[])), Some((0, 0)));
}

#[test]
fn sixteen_bit_filters_see_ide_rtr_and_exid_17_15() {
    // Extended identifier whose STID part is 0x123 and EXID[17:15] = 5.
    let ext = (0x123 << 18) | (5 << 15) | 0x1234;
    let w = (0x123 << 5) | (1 << 3) | 5; // STID RTR=0 IDE=1 EXID[17:15]
    let banks = [Bank {
        bank: 0,
        fifo: 0,
        scale32: false,
        list: true,
        active: true,
        r1: w,
        r2: 0,
    }];
    let (mut m, mut bus) = with_banks(BxCanModel::can1(), &banks);
    assert_eq!(land(&mut m, &mut bus, &ext_frame(ext, &[])), Some((0, 0)));
    assert_eq!(
        land(&mut m, &mut bus, &ext_frame(ext ^ (1 << 15), &[])),
        None,
        "EXID[15] differs"
    );
    assert_eq!(
        land(&mut m, &mut bus, &std_frame(0x123, &[])),
        None,
        "IDE differs"
    );
    let remote = Frame::remote(ext, true, 0).unwrap();
    assert_eq!(land(&mut m, &mut bus, &remote), None, "RTR differs");
    // A 16-bit mask on IDE alone accepts every extended frame, no standard one.
    let banks = [Bank {
        bank: 0,
        fifo: 1,
        scale32: false,
        list: false,
        active: true,
        r1: (1 << 3) | (1 << 19),
        r2: 0xFFFF_FFFF,
    }];
    let (mut m, mut bus) = with_banks(BxCanModel::can1(), &banks);
    assert_eq!(
        land(&mut m, &mut bus, &ext_frame(0x1FFF_FFFF, &[])),
        Some((1, 0))
    );
    assert_eq!(land(&mut m, &mut bus, &std_frame(0x7FF, &[])), None);
}

#[test]
fn thirty_two_bit_filters_see_the_whole_extended_identifier() {
    let id = 0x1ABC_DEF1u32;
    let r = (id << 3) | (1 << 2); // STID/EXID[28:18] EXID[17:0] IDE RTR=0 0
    let banks = [Bank {
        bank: 0,
        fifo: 0,
        scale32: true,
        list: true,
        active: true,
        r1: r,
        r2: r | 2,
    }];
    let (mut m, mut bus) = with_banks(BxCanModel::can1(), &banks);
    assert_eq!(land(&mut m, &mut bus, &ext_frame(id, &[])), Some((0, 0)));
    assert_eq!(
        land(&mut m, &mut bus, &Frame::remote(id, true, 1).unwrap()),
        Some((0, 1))
    );
    assert_eq!(land(&mut m, &mut bus, &ext_frame(id ^ 1, &[])), None);
}

#[test]
fn reception_is_deactivated_while_finit_is_set() {
    let (mut m, mut bus) = started(BxCanModel::can1());
    m.modify32(regs::FMR, |v| v | fmr::FINIT);
    assert_eq!(land(&mut m, &mut bus, &std_frame(1, &[])), None);
    m.modify32(regs::FMR, |v| v & !fmr::FINIT);
    assert_eq!(land(&mut m, &mut bus, &std_frame(1, &[])), Some((0, 0)));
}

#[test]
fn filter_register_write_rules() {
    let mut m = BxCanModel::can1();
    enter_init(&mut m);
    // FINIT = 1 at reset: mode, scale and FIFO registers are writable; 28 bits.
    for r in [regs::FM1R, regs::FS1R, regs::FFA1R, regs::FA1R] {
        m.write32(r, u32::MAX);
        assert_eq!(m.read32(r), 0x0FFF_FFFF);
    }
    m.write32(regs::FA1R, 0b01);
    m.write32(regs::fir1(0), 0x1111_1111);
    m.write32(regs::fir1(1), 0x2222_2222);
    m.write32(regs::FMR, regs::fmr::CAN2SB.val(14)); // FINIT = 0
    assert_eq!(m.read32(regs::FMR), 0x2A1C_0E00);
    for r in [regs::FM1R, regs::FS1R, regs::FFA1R] {
        m.write32(r, 0);
        assert_eq!(m.read32(r), 0x0FFF_FFFF, "only while FINIT = 1");
    }
    // Bank values: written when FINIT = 1 or the bank is inactive.
    m.write32(regs::fir1(0), 0x3333_3333);
    assert_eq!(
        m.read32(regs::fir1(0)),
        0x1111_1111,
        "active bank, FINIT = 0"
    );
    m.write32(regs::fir1(1), 0x4444_4444);
    assert_eq!(m.read32(regs::fir1(1)), 0x4444_4444, "inactive bank");
    // FA1R at any time.
    m.write32(regs::FA1R, 0);
    assert_eq!(m.read32(regs::FA1R), 0);
    m.write32(regs::fir1(0), 0x3333_3333);
    assert_eq!(m.read32(regs::fir1(0)), 0x3333_3333);
}

#[test]
fn can3_has_14_banks_and_no_can2sb() {
    let m = BxCanModel::can3();
    m.write32(regs::FA1R, u32::MAX);
    assert_eq!(m.read32(regs::FA1R), 0x3FFF);
    m.write32(regs::FA1R, 0);
    m.write32(regs::fir1(13), 7);
    m.write32(regs::fir1(14), 7);
    assert_eq!((m.read32(regs::fir1(13)), m.read32(regs::fir1(14))), (7, 0));
    m.write32(regs::FMR, fmr::FINIT | fmr::CAN2SB.val(3));
    assert_eq!(
        m.read32(regs::FMR),
        0x2A1C_0E01,
        "CAN2SB is reserved on CAN3"
    );
    // All 14 banks belong to CAN3, whatever CAN2SB would say.
    let banks = [mask32(13, 1, true, 0, 0)];
    let (mut m, mut bus) = with_banks(BxCanModel::can3(), &banks);
    assert_eq!(land(&mut m, &mut bus, &std_frame(9, &[])), Some((1, 0)));
}
