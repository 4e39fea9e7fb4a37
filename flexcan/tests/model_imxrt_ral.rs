//! Every register offset the FlexCAN model decodes for the i.MX RT1062
//! (`model::layout::register_map`) against the `imxrt-ral` register blocks (NXP SVD,
//! feature `imxrt1062`): `can::RegisterBlock` for CAN1/CAN2, `can3::RegisterBlock` for
//! CAN3; and the field positions the model relies on.

use core::mem::offset_of;

use imxrt_ral::can::RegisterBlock as Can12;
use imxrt_ral::can3::RegisterBlock as Can3;
use twocan_flexcan::model::layout;
use twocan_flexcan::model::{Chip, Rt1062Can};
use twocan_flexcan::regs::{ctrl2, mcr};

/// The offset `imxrt-ral` gives a register of CAN1/CAN2, by the manual's name.
fn can12(name: &str) -> Option<usize> {
    Some(match name {
        "MCR" => offset_of!(Can12, MCR),
        "CTRL1" => offset_of!(Can12, CTRL1),
        "TIMER" => offset_of!(Can12, TIMER),
        "RXMGMASK" => offset_of!(Can12, RXMGMASK),
        "RX14MASK" => offset_of!(Can12, RX14MASK),
        "RX15MASK" => offset_of!(Can12, RX15MASK),
        "ECR" => offset_of!(Can12, ECR),
        "ESR1" => offset_of!(Can12, ESR1),
        "IMASK2" => offset_of!(Can12, IMASK2),
        "IMASK1" => offset_of!(Can12, IMASK1),
        "IFLAG2" => offset_of!(Can12, IFLAG2),
        "IFLAG1" => offset_of!(Can12, IFLAG1),
        "CTRL2" => offset_of!(Can12, CTRL2),
        "ESR2" => offset_of!(Can12, ESR2),
        "CRCR" => offset_of!(Can12, CRCR),
        "RXFGMASK" => offset_of!(Can12, RXFGMASK),
        "RXFIR" => offset_of!(Can12, RXFIR),
        "DBG1" => offset_of!(Can12, DBG1),
        "DBG2" => offset_of!(Can12, DBG2),
        "GFWR" => offset_of!(Can12, GFWR),
        // The CAN1/CAN2 block of imxrt-ral has no message-buffer fields; CAN3's has
        // (CS0 at 0x80, one per 16 bytes): the RAM layout is the same.
        n if n.starts_with("MB") => mb(n)?,
        n if n.starts_with("RXIMR") => {
            offset_of!(Can12, RXIMR) + 4 * n["RXIMR".len()..].parse::<usize>().ok()?
        }
        _ => return None,
    })
}

/// The offset `imxrt-ral` gives a register of CAN3.
fn can3(name: &str) -> Option<usize> {
    Some(match name {
        "MCR" => offset_of!(Can3, MCR),
        "CTRL1" => offset_of!(Can3, CTRL1),
        "TIMER" => offset_of!(Can3, TIMER),
        "RXMGMASK" => offset_of!(Can3, RXMGMASK),
        "RX14MASK" => offset_of!(Can3, RX14MASK),
        "RX15MASK" => offset_of!(Can3, RX15MASK),
        "ECR" => offset_of!(Can3, ECR),
        "ESR1" => offset_of!(Can3, ESR1),
        "IMASK2" => offset_of!(Can3, IMASK2),
        "IMASK1" => offset_of!(Can3, IMASK1),
        "IFLAG2" => offset_of!(Can3, IFLAG2),
        "IFLAG1" => offset_of!(Can3, IFLAG1),
        "CTRL2" => offset_of!(Can3, CTRL2),
        "ESR2" => offset_of!(Can3, ESR2),
        "CRCR" => offset_of!(Can3, CRCR),
        "RXFGMASK" => offset_of!(Can3, RXFGMASK),
        "RXFIR" => offset_of!(Can3, RXFIR),
        "CBT" => offset_of!(Can3, CBT),
        "FDCTRL" => offset_of!(Can3, FDCTRL),
        "FDCBT" => offset_of!(Can3, FDCBT),
        "FDCRC" => offset_of!(Can3, FDCRC),
        n if n.starts_with("MB") => mb(n)?,
        n if n.starts_with("RXIMR") => {
            offset_of!(Can3, RXIMR) + 4 * n["RXIMR".len()..].parse::<usize>().ok()?
        }
        _ => return None,
    })
}

/// `MBn_CS` from CAN3's `CSn` fields (CS0, and CS63 checked separately).
fn mb(name: &str) -> Option<usize> {
    let n: usize = name.strip_prefix("MB")?.strip_suffix("_CS")?.parse().ok()?;
    Some(offset_of!(Can3, CS0) + 16 * n)
}

#[test]
fn every_register_the_model_decodes_is_where_imxrt_ral_puts_it() {
    assert_eq!(offset_of!(Can3, CS63), offset_of!(Can3, CS0) + 16 * 63);
    assert_eq!(offset_of!(Can3, ID63), offset_of!(Can3, CS63) + 4);
    for (can, lookup) in [
        (Rt1062Can::Can1, can12 as fn(&str) -> Option<usize>),
        (Rt1062Can::Can2, can12),
        (Rt1062Can::Can3, can3),
    ] {
        let map = layout::register_map(Chip::Imxrt1062(can).variant());
        assert_eq!(
            map.len(),
            15 + 2 * 64 + if can == Rt1062Can::Can3 { 6 } else { 5 }
        );
        for (name, offset) in &map {
            let ral = lookup(name).unwrap_or_else(|| panic!("{can:?}: {name} not in imxrt-ral"));
            assert_eq!(*offset, ral, "{can:?} {name}");
        }
    }
}

#[test]
fn registers_one_instance_lacks_are_absent_from_its_imxrt_ral_block() {
    let map1 = layout::register_map(Chip::Imxrt1062(Rt1062Can::Can1).variant());
    let map3 = layout::register_map(Chip::Imxrt1062(Rt1062Can::Can3).variant());
    for name in ["CBT", "FDCTRL", "FDCBT", "FDCRC"] {
        assert!(can12(name).is_none());
        assert!(!map1.iter().any(|(n, _)| n == name), "{name}");
        assert!(map3.iter().any(|(n, _)| n == name), "{name}");
    }
    for name in ["DBG1", "DBG2", "GFWR"] {
        assert!(can3(name).is_none());
        assert!(!map3.iter().any(|(n, _)| n == name), "{name}");
        assert!(map1.iter().any(|(n, _)| n == name), "{name}");
    }
}

#[test]
fn fields_the_model_relies_on() {
    use imxrt_ral::can::{CTRL2, MCR, RXFIR};
    // MAXMB: 7 bits (up to MB63), IDAM at 8, RFFN 4 bits at 24 (up to 0xF), IDHIT 9 bits.
    assert_eq!(mcr::MAXMB.mask(), MCR::MAXMB::mask);
    assert_eq!(mcr::IDAM.mask(), MCR::IDAM::mask);
    assert_eq!(ctrl2::RFFN.mask(), CTRL2::RFFN::mask);
    assert_eq!(RXFIR::IDHIT::mask, 0x1FF);
    assert_eq!(mcr::IRMQ, MCR::IRMQ::mask);
    assert_eq!(mcr::RFEN, imxrt_ral::can::MCR::RFEN::mask);
    assert_eq!(layout::MCR_FDEN, imxrt_ral::can3::MCR::FDEN::mask);
    assert_eq!(layout::CBT_BTF, imxrt_ral::can3::CBT::BTF::mask);
    // CAN1/CAN2 have no FDEN nor CLKSRC field in imxrt-ral; CAN3 has CLKSRC.
    assert_eq!(imxrt_ral::can3::CTRL1::CLKSRC::mask, 1 << 13);
    // Base addresses (for the board profile): CAN1, CAN2, CAN3.
    assert_eq!(imxrt_ral::can::CAN1 as usize, 0x401D_0000);
    assert_eq!(imxrt_ral::can::CAN2 as usize, 0x401D_4000);
    assert_eq!(imxrt_ral::can3::CAN3 as usize, 0x401D_8000);
    // Interrupt numbers: one line per module.
    assert_eq!(imxrt_ral::Interrupt::CAN1 as u16, 36);
    assert_eq!(imxrt_ral::Interrupt::CAN2 as u16, 37);
    assert_eq!(imxrt_ral::Interrupt::CAN3 as u16, 154);
}
