//! The STM32F4 family against the vendor SVD data of the `stm32f4` PAC, chip STM32F446
//! (RM0390: CAN1 + CAN2 sharing 28 filter banks):
//!
//! - `twocan_bxcan::regs` (offsets, bits, fields) against the PAC's CAN1 block (the
//!   driver's one register map serves the F446);
//! - the model of the part read at the PAC's offsets: reset values, filter registers as
//!   wide as the PAC's 28 banks, `CAN2SB` stored;
//! - the part descriptor: base addresses, interrupt numbers, `RCC_APB1ENR` address and
//!   clock-enable bits.
//!
//! As for the F7 (`regmap.rs`), the SVD gives `CAN_BTR` a reset value of 0 where RM0390
//! §30.9.2 gives 0x0123_0000 (SJW = 1, TS2 = 2, TS1 = 3); the model follows RM0390.
//!
//! A PAC crate builds one chip at a time. The other F4 parts of `model::part` were
//! checked by hand against the same crate's sources: `stm32f405` (CAN1 0x4000_6400, CAN2
//! 0x4000_6800, lines 19..=22 / 63..=66) and `stm32f413` (CAN3 at 0x4000_6C00, lines
//! 74..=77, `RCC_APB1ENR.CAN3EN` bit 27 — where the F76x has CAN3 at 0x4000_3400 with
//! `CAN3EN` bit 13).

#[macro_use]
mod pac_regmap;

pac_helpers!(stm32f4);

use stm32f4::stm32f446 as f446;
use twocan_bxcan::model::{part, BxCanModel};
use twocan_bxcan::regs::{fmr, Instance};
use twocan_core::Registers;

/// The value the model must show out of reset: the SVD's, except `CAN_BTR`.
fn rm0390_reset(name: &str, svd: u32) -> u32 {
    if name == "BTR" {
        assert_eq!(svd, 0, "the SVD's CAN_BTR reset value changed: compare it");
        0x0123_0000
    } else {
        svd
    }
}

#[test]
fn f446_register_map_matches_the_pac() {
    let rb = block::<f446::can1::RegisterBlock>();
    let banks = can_layout_matches!(rb);
    assert_eq!(
        banks, 28,
        "RM0390 §30.2: 28 filter banks shared by CAN1 and CAN2"
    );
    assert_eq!(banks, part::STM32F446.can1_banks);
    fields!(rb.fmr(), can2sb => fmr::CAN2SB);
}

#[test]
fn f446_model_matches_the_pac() {
    let rb = block::<f446::can1::RegisterBlock>();
    let models = BxCanModel::of_part(&part::STM32F446);
    assert_eq!(models.len(), 2);
    model_matches_pac!(&models[0], rb, 28, rm0390_reset);
    // The reset values the SVD gives are RM0390's (§30.9.2, §30.9.4).
    assert_eq!(reset_of(rb.mcr()), 0x0001_0002);
    assert_eq!(reset_of(rb.msr()), 0x0000_0C02);
    assert_eq!(reset_of(rb.tsr()), 0x1C00_0000);
    assert_eq!(reset_of(rb.fmr()), 0x2A1C_0E01);
    // CAN2SB is a field of the PAC's FMR and the model keeps it.
    let can1 = &models[0];
    can1.write32(offset(rb, rb.fmr()), fmr::CAN2SB.set(0x2A1C_0E01, 7));
    poke(rb.fmr(), can1.read32(offset(rb, rb.fmr())));
    assert_eq!(rb.fmr().read().can2sb().bits(), 7);
    assert!(rb.fmr().read().finit().bit());
    // CAN2 (the other instance) has no filter block of its own: its window reads 0.
    assert_eq!(models[1].read32(offset(rb, rb.fmr())), 0);
}

#[test]
fn f446_instances_and_interrupts_match_the_pac() {
    use f446::Interrupt as I;
    let p = &part::STM32F446;
    let (can1, can2) = (
        p.instance(Instance::Can1).unwrap(),
        p.instance(Instance::Can2).unwrap(),
    );
    assert!(p.instance(Instance::Can3).is_none());
    assert_eq!(f446::CAN1::PTR as u32, can1.base);
    assert_eq!(f446::CAN2::PTR as u32, can2.base);
    assert_eq!(
        can1.irqs.map(|(_, n)| n),
        [
            I::CAN1_TX as u16,
            I::CAN1_RX0 as u16,
            I::CAN1_RX1 as u16,
            I::CAN1_SCE as u16
        ]
    );
    assert_eq!(
        can2.irqs.map(|(_, n)| n),
        [
            I::CAN2_TX as u16,
            I::CAN2_RX0 as u16,
            I::CAN2_RX1 as u16,
            I::CAN2_SCE as u16
        ]
    );
    assert_eq!(
        [can1.irqs.map(|(s, _)| s), can2.irqs.map(|(s, _)| s)],
        [
            ["CAN1_TX", "CAN1_RX0", "CAN1_RX1", "CAN1_SCE"],
            ["CAN2_TX", "CAN2_RX0", "CAN2_RX1", "CAN2_SCE"]
        ]
    );
    let rcc = block::<f446::rcc::RegisterBlock>();
    assert_eq!(
        f446::RCC::PTR as u32 + offset(rcc, rcc.apb1enr()) as u32,
        p.rcc_apb1enr
    );
    bits!(rcc.apb1enr(),
        can1en => 1 << can1.apb1enr_bit, can2en => 1 << can2.apb1enr_bit);
}

#[test]
fn the_driver_base_addresses_hold_on_the_f446() {
    use twocan_bxcan::regs;
    assert_eq!(f446::CAN1::PTR as usize, regs::CAN1_BASE);
    assert_eq!(f446::CAN2::PTR as usize, regs::CAN2_BASE);
    assert_eq!(Instance::Can2.filter_base(), regs::CAN1_BASE);
    assert_eq!(Instance::Can1.filter_banks(), 28);
}

/// The base of a fixed-base register type.
fn base<const B: usize, const E: usize, const S: usize>(
    _: std::marker::PhantomData<twocan_core::Fixed<B, E, S>>,
) -> usize {
    B
}

#[test]
fn the_fixed_register_types_of_the_f446_are_at_the_pac_s_addresses() {
    use std::marker::PhantomData as T;
    use twocan_bxcan::regs::{Can1At, Can1ControlAt, Can2At};
    assert_eq!(base(T::<Can1At>), f446::CAN1::PTR as usize);
    assert_eq!(base(T::<Can1ControlAt>), f446::CAN1::PTR as usize);
    assert_eq!(base(T::<Can2At>), f446::CAN2::PTR as usize);
}
