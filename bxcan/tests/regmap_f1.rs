//! The STM32F1 family (RM0008) against the vendor SVD data of the `stm32f1` PAC, chip
//! STM32F103 (one CAN, 14 filter banks, its SRAM shared with USB). A PAC crate builds one
//! chip at a time; the connectivity line (STM32F105/F107: CAN1 + CAN2, 28 banks) was
//! checked by hand against the same crate's `stm32f107` sources (CAN1 0x4000_6400, CAN2
//! 0x4000_6800, 28 `fb` banks, `FMR.CAN2SB` bits 13:8, lines 19..=22 and 63..=66,
//! `RCC_APB1ENR.CAN1EN`/`CAN2EN` bits 25/26).
//!
//! - `twocan_bxcan::regs` (offsets, bits, fields) against each PAC CAN block, for the
//!   banks the PAC gives (tells whether the driver's one register map serves the F1);
//! - the model of each part read at the PAC's offsets: reset values, filter registers as
//!   wide as the PAC's bank count, nothing beyond it;
//! - the part descriptors (`twocan_bxcan::model::part`): base addresses, interrupt
//!   numbers, `RCC_APB1ENR` address and clock-enable bits.
//!
//! The STM32F1 SVD gives every CAN register a reset value of 0; RM0008 §24.9.2 and
//! §24.9.4 give `CAN_MCR` 0x0001_0002, `CAN_MSR` 0x0000_0C02, `CAN_TSR` 0x1C00_0000,
//! `CAN_BTR` 0x0123_0000 and `CAN_FMR` 0x2A1C_0E01. The model follows RM0008; the test
//! asserts the SVD's zeros too, so that a PAC that gains reset values is noticed.

#[macro_use]
mod pac_regmap;

pac_helpers!(stm32f1);

use stm32f1::stm32f103 as f103;
use twocan_bxcan::model::{part, BxCanModel};
use twocan_bxcan::regs::{fmr, Instance};

/// RM0008 §24.9 reset values, for the registers the F1 SVD leaves at 0.
fn rm0008_reset(name: &str, svd: u32) -> u32 {
    assert_eq!(
        svd, 0,
        "{name}: the STM32F1 SVD has a reset value now: compare it"
    );
    match name {
        "MCR" => 0x0001_0002,
        "MSR" => 0x0000_0C02,
        "TSR" => 0x1C00_0000,
        "BTR" => 0x0123_0000,
        "FMR" => 0x2A1C_0E01,
        _ => 0,
    }
}

#[test]
fn f103_register_map_matches_the_pac() {
    let rb = block::<f103::can::RegisterBlock>();
    let banks = can_layout_matches!(rb);
    assert_eq!(banks, 14, "RM0008 §24.2: 14 filter banks in the STM32F103");
    assert_eq!(banks, part::STM32F103.can1_banks);
    // FMR has no CAN2SB on the F103 (RM0008 §24.9.4: reserved outside the connectivity
    // line): the PAC names FINIT only.
    let r = rb.fmr();
    poke(r, fmr::CAN2SB.mask());
    assert_eq!(format!("{:?}", r.read()), "FMR { finit: false }");
}

#[test]
fn f103_model_matches_the_pac() {
    let rb = block::<f103::can::RegisterBlock>();
    let models = BxCanModel::of_part(&part::STM32F103);
    assert_eq!(models.len(), 1);
    model_matches_pac!(&models[0], rb, 14, rm0008_reset);
}

#[test]
fn f103_instances_and_interrupts_match_the_pac() {
    use f103::Interrupt as I;
    let p = &part::STM32F103;
    let can = p.instance(Instance::Can1).unwrap();
    assert_eq!(can.name, "CAN");
    assert_eq!(f103::CAN::PTR as u32, can.base);
    assert_eq!(
        can.irqs.map(|(_, n)| n),
        [
            I::USB_HP_CAN_TX as u16,
            I::USB_LP_CAN_RX0 as u16,
            I::CAN_RX1 as u16,
            I::CAN_SCE as u16
        ]
    );
    assert_eq!(
        can.irqs.map(|(name, _)| name),
        ["USB_HP_CAN_TX", "USB_LP_CAN_RX0", "CAN_RX1", "CAN_SCE"]
    );
    // RCC_APB1ENR: address, CANEN and (for the shared-SRAM rule) USBEN.
    let rcc = block::<f103::rcc::RegisterBlock>();
    assert_eq!(
        f103::RCC::PTR as u32 + offset(rcc, rcc.apb1enr()) as u32,
        p.rcc_apb1enr
    );
    bits!(rcc.apb1enr(), canen => 1 << can.apb1enr_bit, usben => 1 << 23);
    assert!(p.sram_shared_with_usb);
}

#[test]
fn the_driver_base_addresses_hold_on_the_f1() {
    // What the driver's register map assumes, on the F103: its CAN where the F7's CAN1 is.
    assert_eq!(f103::CAN::PTR as usize, twocan_bxcan::regs::CAN1_BASE);
}

/// The base of a fixed-base register type.
fn base<const B: usize, const E: usize, const S: usize>(
    _: std::marker::PhantomData<twocan_core::Fixed<B, E, S>>,
) -> usize {
    B
}

#[test]
fn the_fixed_register_type_of_the_f103_s_can_is_at_the_pac_s_address() {
    use std::marker::PhantomData as T;
    assert_eq!(
        base(T::<twocan_bxcan::regs::Can1At>),
        f103::CAN::PTR as usize
    );
}
