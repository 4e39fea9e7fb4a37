//! The bxCAN model on each part of the family (`twocan_bxcan::model::part`), through
//! registers: what the manuals say differs — the instances, the bank count of CAN1's
//! block, `CAN_FMR.CAN2SB`, CAN3's own block — and what they say stays the same (reset
//! values, `TTCM`, `DBF`).
//!
//! Sources: RM0008 (STM32F10x) §24.2 "bxCAN main features", §24.7.4 "Identifier
//! filtering", §24.9.2 "CAN control and status registers", §24.9.4 "CAN filter
//! registers"; RM0390 (STM32F446) §30.2, §30.9; RM0090 (STM32F405/407) §32.2, §32.9;
//! RM0430 (STM32F413/423) §32.2 Table 219; RM0410 (STM32F76x) §40.2 Table 289.

#[path = "model_bus.rs"]
mod bus;

use bus::*;
use twocan_bxcan::model::part::{self, Part};
use twocan_bxcan::model::{BxCanModel, Mode};
use twocan_bxcan::regs::{self, fa1r, ffa1r, fm1r, fmr, fs1r, mcr, Instance};
use twocan_core::Registers;

/// RM0008 §24.9.2 / RM0390 §30.9.2 / RM0410 §40.9.2 reset values, common to every part.
const MCR_RESET: u32 = 0x0001_0002;
const MSR_RESET: u32 = 0x0000_0C02;
const TSR_RESET: u32 = 0x1C00_0000;
const BTR_RESET: u32 = 0x0123_0000;
/// RM0008 §24.9.4 / RM0390 §30.9.4: FINIT = 1, CAN2SB = 14 (reserved bits as shown).
const FMR_RESET: u32 = 0x2A1C_0E01;

fn banks_mask(n: usize) -> u32 {
    (1u32 << n) - 1
}

/// The model of `instance` on `part`.
fn model(part: &'static Part, instance: Instance) -> BxCanModel {
    BxCanModel::of_part(part)
        .into_iter()
        .find(|m| m.instance() == instance)
        .expect("instance of the part")
}

/// Configures `bank` through `m`'s filter registers as a 32-bit mask filter with `id`
/// and `mask` into FIFO `fifo`, active.
fn mask32(m: &mut BxCanModel, bank: usize, fifo: usize, id: u32, mask: u32) {
    m.modify32(regs::FMR, |v| v | fmr::FINIT);
    m.modify32(regs::FS1R, |v| v | fs1r::fsc(bank));
    m.modify32(regs::FM1R, |v| v & !fm1r::fbm(bank));
    m.modify32(regs::FFA1R, |v| {
        if fifo == 1 {
            v | ffa1r::ffa(bank)
        } else {
            v & !ffa1r::ffa(bank)
        }
    });
    m.write32(regs::fir1(bank), id);
    m.write32(regs::fir2(bank), mask);
    m.modify32(regs::FA1R, |v| v | fa1r::fact(bank));
    m.modify32(regs::FMR, |v| v & !fmr::FINIT);
}

fn where_is(m: &mut BxCanModel) -> Option<(usize, u32)> {
    (0..2).find_map(|x| receive(m, x).map(|r| (x, r.fmi)))
}

#[test]
fn every_part_gives_its_instances_in_order() {
    for p in Part::ALL {
        let models = BxCanModel::of_part(p);
        let got: Vec<Instance> = models.iter().map(|m| m.instance()).collect();
        let want: Vec<Instance> = p.instances.iter().map(|i| i.instance).collect();
        assert_eq!(got, want, "{}", p.name);
        assert_eq!(want[0], Instance::Can1, "{}: CAN1 first", p.name);
        assert!(models.iter().all(|m| m.part() == p));
        for (i, a) in models.iter().enumerate() {
            for b in &models[i + 1..] {
                assert!(!a.same_controller(b), "{}", p.name);
            }
        }
    }
    // The F7 constructors the other tests use describe an STM32F76x.
    assert_eq!(*BxCanModel::can1().part(), part::STM32F76X_F77X);
    assert_eq!(*BxCanModel::can3().part(), part::STM32F76X_F77X);
    assert_eq!(*BxCanModel::can1_can2().1.part(), part::STM32F76X_F77X);
}

#[test]
fn part_descriptors_are_consistent() {
    for p in Part::ALL {
        // Dual-CAN parts have 28 banks in CAN1's block, single-CAN parts 14 (RM0008
        // §24.2; RM0410 §40.2 Table 289; RM0430 §32.2 Table 219).
        assert_eq!(p.can1_banks, if p.dual() { 28 } else { 14 }, "{}", p.name);
        assert_eq!(p.banks_of(Instance::Can1), Some(p.can1_banks));
        assert_eq!(p.banks_of(Instance::Can2), p.dual().then_some(28));
        if p.instance(Instance::Can3).is_some() {
            assert_eq!(p.banks_of(Instance::Can3), Some(14), "{}", p.name);
            assert!(p.dual(), "{}: CAN3 only on dual-CAN parts", p.name);
        }
        let mut lines: Vec<u16> = p
            .instances
            .iter()
            .flat_map(|i| i.irqs.iter().map(|(_, n)| *n))
            .collect();
        let n = lines.len();
        lines.sort_unstable();
        lines.dedup();
        assert_eq!(lines.len(), n, "{}: an interrupt number used twice", p.name);
        let mut bits: Vec<u8> = p.instances.iter().map(|i| i.apb1enr_bit).collect();
        bits.sort_unstable();
        bits.dedup();
        assert_eq!(bits.len(), p.instances.len(), "{}", p.name);
        for i in p.instances {
            assert_eq!(i.base % 0x400, 0, "{} {}", p.name, i.name);
            assert!(i.apb1enr_bit < 32);
        }
        // Only the F103 shares its CAN SRAM with the USB device (RM0008 §24.2 note).
        assert_eq!(p.sram_shared_with_usb, *p == part::STM32F103, "{}", p.name);
    }
}

#[test]
fn reset_values_are_the_same_on_every_part() {
    for p in Part::ALL {
        for m in BxCanModel::of_part(p) {
            let what = format!("{} {:?}", p.name, m.instance());
            assert_eq!(m.state().mode, Mode::Sleep, "{what}");
            assert_eq!(m.read32(regs::MCR), MCR_RESET, "{what}: MCR (DBF = 1)");
            assert_eq!(m.read32(regs::MSR), MSR_RESET, "{what}: MSR");
            assert_eq!(m.read32(regs::TSR), TSR_RESET, "{what}: TSR");
            assert_eq!(m.read32(regs::BTR), BTR_RESET, "{what}: BTR");
            for r in [regs::RF0R, regs::RF1R, regs::IER, regs::ESR] {
                assert_eq!(m.read32(r), 0, "{what}: 0x{r:03X}");
            }
            if m.instance() == Instance::Can2 {
                // CAN2 has no filter registers of its own (it uses CAN1's).
                assert_eq!(m.read32(regs::FMR), 0, "{what}");
            } else {
                assert_eq!(m.read32(regs::FMR), FMR_RESET, "{what}: FMR");
                for r in [regs::FM1R, regs::FS1R, regs::FFA1R, regs::FA1R] {
                    assert_eq!(m.read32(r), 0, "{what}: 0x{r:03X}");
                }
            }
        }
    }
}

#[test]
fn filter_registers_are_as_wide_as_the_bank_count() {
    // RM0008 §24.9.4: FM1R/FS1R/FFA1R/FA1R bits 27:14 are "available in connectivity line
    // devices only and are reserved otherwise"; CAN_FiRx exists for the banks that exist.
    for p in Part::ALL {
        for m in BxCanModel::of_part(p) {
            let Some(n) = p
                .banks_of(m.instance())
                .filter(|_| m.instance() != Instance::Can2)
            else {
                continue;
            };
            let what = format!("{} {:?}", p.name, m.instance());
            m.write32(regs::FMR, FMR_RESET); // FINIT = 1
            for r in [regs::FM1R, regs::FS1R, regs::FFA1R, regs::FA1R] {
                m.write32(r, u32::MAX);
                assert_eq!(m.read32(r), banks_mask(n), "{what}: 0x{r:03X}");
                m.write32(r, 0);
            }
            for bank in 0..regs::FILTER_BANKS {
                m.write32(regs::fir1(bank), 0x1234_5678 ^ bank as u32);
                m.write32(regs::fir2(bank), 0x8765_4321 ^ bank as u32);
            }
            for bank in 0..regs::FILTER_BANKS {
                let want = |v: u32| if bank < n { v ^ bank as u32 } else { 0 };
                assert_eq!(
                    m.read32(regs::fir1(bank)),
                    want(0x1234_5678),
                    "{what}: F{bank}R1"
                );
                assert_eq!(
                    m.read32(regs::fir2(bank)),
                    want(0x8765_4321),
                    "{what}: F{bank}R2"
                );
            }
        }
    }
}

#[test]
fn can2sb_exists_only_on_dual_can_parts() {
    // RM0008 §24.9.4 CAN_FMR bits 13:8: "available in connectivity line devices only and
    // are reserved otherwise"; RM0390 §30.9.4: CAN2SB[5:0] of the dual block.
    let write = FMR_RESET & !fmr::CAN2SB.mask() | fmr::CAN2SB.val(20);
    for (p, instance, stored) in [
        (&part::STM32F103, Instance::Can1, false),
        (&part::STM32F105_F107, Instance::Can1, true),
        (&part::STM32F405_F407, Instance::Can1, true),
        (&part::STM32F446, Instance::Can1, true),
        (&part::STM32F413_F423, Instance::Can1, true),
        (&part::STM32F413_F423, Instance::Can3, false),
        (&part::STM32F76X_F77X, Instance::Can3, false),
    ] {
        let m = model(p, instance);
        m.write32(regs::FMR, write);
        let want = if stored { write } else { FMR_RESET };
        assert_eq!(m.read32(regs::FMR), want, "{} {instance:?}", p.name);
        m.write32(regs::FMR, write & !fmr::FINIT);
        assert_eq!(
            m.read32(regs::FMR),
            want & !fmr::FINIT,
            "{} {instance:?}: FINIT is writable everywhere",
            p.name
        );
    }
}

#[test]
fn f103_can_uses_all_14_banks_and_numbers_filters_across_them() {
    // RM0008 §24.7.4 "Filter match index": filters are numbered per FIFO in bank order,
    // "independently of whether the filter banks are active or not"; the F103's CAN owns
    // the whole block (no CAN2, no split at CAN2SB).
    let (mut a, mut b) = pair(&part::STM32F103);
    let mut bus = TinyBus::new(&[&a, &b]);
    for m in [&mut a, &mut b] {
        enter_init(m);
    }
    // Bank 13 (the last one): a 32-bit mask filter for standard 0x123 into FIFO 0. Banks
    // 0..=12 are inactive 16-bit mask banks of FIFO 0 (the reset state): 2 numbers each.
    mask32(&mut b, 13, 0, 0x123 << 21, 0xFFE0_0006);
    // Bank 12 into FIFO 1 accepting everything: its own FIFO's numbering starts at 0.
    mask32(&mut b, 12, 1, 0, 0);
    leave_init(&mut a, &mut bus);
    leave_init(&mut b, &mut bus);
    load(&mut a, 0, &std_frame(0x123, &[1, 2]));
    bus.run(2);
    // Both filters match, with equal scale and mode but in different FIFOs: the lower
    // bank wins (a model assumption, docs/models.md).
    assert_eq!(where_is(&mut b), Some((1, 0)), "bank 12 (FIFO 1) first");
    mask32(&mut b, 12, 1, 0x7FF << 21, 0xFFE0_0006); // bank 12 now takes 0x7FF only
    load(&mut a, 0, &std_frame(0x123, &[3]));
    bus.run(2);
    assert_eq!(
        where_is(&mut b),
        Some((0, 24)),
        "FIFO 0: banks 0..=11 give 2 numbers each, bank 13 is number 24"
    );
    assert_eq!(b.state().filter_hits[13], 1);
}

/// Two controllers of `part` (each a separate chip) on one bus.
fn pair(part: &'static Part) -> (BxCanModel, BxCanModel) {
    let a = BxCanModel::of_part(part).remove(0);
    let b = BxCanModel::of_part(part).remove(0);
    (a, b)
}

#[test]
fn two_blue_pills_exchange_time_stamped_frames() {
    // TTCM exists on the F103 too (RM0008 §24.2 "Time-triggered communication option",
    // §24.7.2): the 16-bit timer counts bit times and stamps the SOF of each frame.
    let (mut a, mut b) = pair(&part::STM32F103);
    let mut bus = TinyBus::new(&[&a, &b]);
    for m in [&mut a, &mut b] {
        enter_init(m);
        m.modify32(regs::MCR, |v| v | mcr::TTCM);
        accept_all(m, 0, 0);
    }
    leave_init(&mut a, &mut bus);
    leave_init(&mut b, &mut bus);
    load(&mut a, 0, &std_frame(0x100, &[1]));
    bus.run(2);
    bus.idle(1000);
    load(&mut b, 0, &std_frame(0x200, &[2]));
    bus.run(2);
    let first = receive(&mut b, 0).expect("b received");
    let second = receive(&mut a, 0).expect("a received");
    assert_eq!(first.frame, std_frame(0x100, &[1]));
    assert_eq!(second.frame, std_frame(0x200, &[2]));
    assert!(
        second.time >= first.time + 1000,
        "time stamps {} then {}",
        first.time,
        second.time
    );
}

#[test]
fn f446_can2_takes_the_banks_from_can2sb_to_27() {
    // RM0390 §30.2 "28 filter banks shared between CAN1 and CAN2"; §30.9.4 CAN2SB.
    for p in [
        &part::STM32F446,
        &part::STM32F405_F407,
        &part::STM32F105_F107,
    ] {
        let mut models = BxCanModel::of_part(p);
        let (mut can1, mut can2) = (models.remove(0), models.remove(0));
        let mut bus = TinyBus::new(&[&can1, &can2]);
        enter_init(&mut can1);
        enter_init(&mut can2);
        mask32(&mut can1, 27, 1, 0, 0); // the last bank: CAN2's (CAN2SB = 14)
        leave_init(&mut can1, &mut bus);
        leave_init(&mut can2, &mut bus);
        bus.inject(&std_frame(0x55, &[]));
        assert_eq!(where_is(&mut can1), None, "{}", p.name);
        // FIFO 1 numbering from CAN2SB: banks 14..=26 belong to FIFO 0.
        assert_eq!(where_is(&mut can2), Some((1, 0)), "{}", p.name);
        // CAN2SB = 28: every bank to CAN1, whose FIFO 1 numbering now starts at bank 27.
        can1.modify32(regs::FMR, |v| fmr::CAN2SB.set(v, 28));
        bus.inject(&std_frame(0x55, &[]));
        assert_eq!(where_is(&mut can1), Some((1, 0)), "{}", p.name);
        assert_eq!(where_is(&mut can2), None, "{}", p.name);
        // CAN2's filter window shows nothing (the registers are CAN1's).
        assert_eq!(can2.read32(regs::FA1R), 0, "{}", p.name);
        assert_eq!(can1.read32(regs::FA1R), fa1r::fact(27), "{}", p.name);
    }
}

#[test]
fn f413_can3_filters_are_independent_of_can1s_block() {
    // RM0430 §32.2 Table 219: CAN3 is a master with its own 14 filter banks.
    let models = BxCanModel::of_part(&part::STM32F413_F423);
    let (can1, can3) = (models[0].clone(), models[2].clone());
    assert_eq!(can3.instance(), Instance::Can3);
    can1.write32(regs::FA1R, u32::MAX);
    assert_eq!(can1.read32(regs::FA1R), banks_mask(28));
    assert_eq!(can3.read32(regs::FA1R), 0);
    can3.write32(regs::FA1R, 1);
    assert_eq!(can1.read32(regs::FA1R), banks_mask(28));
    assert_eq!(can3.read32(regs::FA1R), 1);
}

#[test]
fn debug_freeze_is_on_at_reset_on_the_f1_and_f4() {
    // RM0008 §24.9.2 / RM0390 §30.9.2 CAN_MCR.DBF, reset 1: reception and transmission
    // frozen while the core is halted by the debugger.
    for p in [&part::STM32F103, &part::STM32F446] {
        let (mut a, mut b) = pair(p);
        let mut bus = TinyBus::new(&[&a, &b]);
        start(&mut a, &mut bus);
        start(&mut b, &mut bus);
        b.set_debug_halt(true);
        load(&mut a, 0, &std_frame(0x10, &[]));
        bus.run(2);
        assert_eq!(b.state().fifo_depth, [0, 0], "{}: frozen", p.name);
        // Still halted, DBF cleared: the retransmitted frame is received.
        b.modify32(regs::MCR, |v| v & !mcr::DBF);
        bus.run(2);
        assert_eq!(
            receive(&mut b, 0).map(|r| r.frame.raw_id()),
            Some(0x10),
            "{}: DBF = 0 runs on",
            p.name
        );
    }
}
