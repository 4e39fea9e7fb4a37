//! The driver's own register map (`twocan_flexcan::regs`) against `imxrt-ral` (the NXP
//! SVD for the i.MX RT1062, feature `imxrt1062`), as `regmap.rs` checks it against the
//! Kinetis PACs: every offset the driver writes on a Teensy 4 — the control registers,
//! `IMASK2`/`IFLAG2` of the RT1062 layout's transmit mailboxes above MB31, the message
//! buffers MB0–MB63 and `RXIMR0`–`RXIMR63` (the end of the block, the register window
//! `regs::IMXRT_BLOCK_END`) — and the masks of the fields it uses. CAN1/CAN2 are
//! `imxrt_ral::can::RegisterBlock`, CAN3 `imxrt_ral::can3::RegisterBlock` (which alone
//! names the message-buffer words); the RT1062's register set is the same at these
//! offsets in both.

use core::mem::offset_of;

use imxrt_ral::can::RegisterBlock as Can12;
use imxrt_ral::can3::RegisterBlock as Can3;
use twocan_flexcan::regs::{
    self, cs, ctrl1, ctrl2, ecr, esr1, esr2, id, iflag1, mcr, rxfir, Field,
};

#[test]
fn control_registers_are_where_imxrt_ral_puts_them_in_every_module() {
    let ours = [
        ("MCR", regs::MCR),
        ("CTRL1", regs::CTRL1),
        ("TIMER", regs::TIMER),
        ("RXMGMASK", regs::RXMGMASK),
        ("RX14MASK", regs::RX14MASK),
        ("RX15MASK", regs::RX15MASK),
        ("ECR", regs::ECR),
        ("ESR1", regs::ESR1),
        ("IMASK2", regs::IMASK2),
        ("IMASK1", regs::IMASK1),
        ("IFLAG2", regs::IFLAG2),
        ("IFLAG1", regs::IFLAG1),
        ("CTRL2", regs::CTRL2),
        ("ESR2", regs::ESR2),
        ("CRCR", regs::CRCR),
        ("RXFGMASK", regs::RXFGMASK),
        ("RXFIR", regs::RXFIR),
    ];
    let can12 = [
        offset_of!(Can12, MCR),
        offset_of!(Can12, CTRL1),
        offset_of!(Can12, TIMER),
        offset_of!(Can12, RXMGMASK),
        offset_of!(Can12, RX14MASK),
        offset_of!(Can12, RX15MASK),
        offset_of!(Can12, ECR),
        offset_of!(Can12, ESR1),
        offset_of!(Can12, IMASK2),
        offset_of!(Can12, IMASK1),
        offset_of!(Can12, IFLAG2),
        offset_of!(Can12, IFLAG1),
        offset_of!(Can12, CTRL2),
        offset_of!(Can12, ESR2),
        offset_of!(Can12, CRCR),
        offset_of!(Can12, RXFGMASK),
        offset_of!(Can12, RXFIR),
    ];
    let can3 = [
        offset_of!(Can3, MCR),
        offset_of!(Can3, CTRL1),
        offset_of!(Can3, TIMER),
        offset_of!(Can3, RXMGMASK),
        offset_of!(Can3, RX14MASK),
        offset_of!(Can3, RX15MASK),
        offset_of!(Can3, ECR),
        offset_of!(Can3, ESR1),
        offset_of!(Can3, IMASK2),
        offset_of!(Can3, IMASK1),
        offset_of!(Can3, IFLAG2),
        offset_of!(Can3, IFLAG1),
        offset_of!(Can3, CTRL2),
        offset_of!(Can3, ESR2),
        offset_of!(Can3, CRCR),
        offset_of!(Can3, RXFGMASK),
        offset_of!(Can3, RXFIR),
    ];
    for (((name, offset), a), b) in ours.iter().zip(can12).zip(can3) {
        assert_eq!(*offset, a, "{name} (CAN1/CAN2)");
        assert_eq!(*offset, b, "{name} (CAN3)");
    }
}

#[test]
fn message_buffers_and_individual_masks_up_to_mb63_and_the_window_end() {
    // CAN3's block names every message buffer's control/status and identifier words;
    // the first and last, and a stride of 16 bytes in between (the 8-byte payload
    // words follow the identifier).
    assert_eq!(regs::mb_cs(0), offset_of!(Can3, CS0));
    assert_eq!(regs::mb_id(0), offset_of!(Can3, ID0));
    assert_eq!(regs::mb_word0(0), offset_of!(Can3, MB0_16B_WORD0));
    assert_eq!(regs::mb_word1(0), offset_of!(Can3, MB0_16B_WORD1));
    assert_eq!(regs::mb_cs(1), offset_of!(Can3, CS1));
    assert_eq!(regs::mb_cs(31), offset_of!(Can3, CS31));
    assert_eq!(regs::mb_cs(32), offset_of!(Can3, CS32));
    assert_eq!(regs::mb_cs(63), offset_of!(Can3, CS63));
    assert_eq!(regs::mb_id(63), offset_of!(Can3, ID63));
    for n in 0..64 {
        assert_eq!(regs::mb_id(n), regs::mb_cs(n) + 4, "MB{n}");
        assert_eq!(regs::mb_word0(n), regs::mb_cs(n) + 8, "MB{n}");
        assert_eq!(regs::mb_word1(n), regs::mb_cs(n) + 12, "MB{n}");
    }
    // RXIMR0..RXIMR63: an array in both blocks, 4 bytes apart; the block (and the
    // driver's register window on a Teensy 4) ends right after RXIMR63.
    for n in 0..64 {
        assert_eq!(regs::rximr(n), offset_of!(Can12, RXIMR) + 4 * n, "RXIMR{n}");
        assert_eq!(regs::rximr(n), offset_of!(Can3, RXIMR) + 4 * n, "RXIMR{n}");
    }
    assert_eq!(regs::IMXRT_BLOCK_END, regs::rximr(63) + 4);
    assert!(regs::mb_word1(63) + 4 <= regs::RXIMR_BASE);
}

/// `ours` (a field or a one-bit mask) has imxrt-ral's mask.
fn same(name: &str, ours: u32, ral: u32) {
    assert_eq!(
        ours, ral,
        "{name}: ours {ours:#010x}, imxrt-ral {ral:#010x}"
    );
}

fn f(field: Field) -> u32 {
    field.mask()
}

#[test]
fn fields_the_driver_uses_have_imxrt_ral_masks() {
    use imxrt_ral::can::{CRCR, CTRL1, CTRL2, ECR, ESR1, ESR2, IFLAG1, MCR, RXFIR};
    // MCR
    for (name, ours, ral) in [
        ("MCR.MDIS", mcr::MDIS, MCR::MDIS::mask),
        ("MCR.FRZ", mcr::FRZ, MCR::FRZ::mask),
        ("MCR.RFEN", mcr::RFEN, MCR::RFEN::mask),
        ("MCR.HALT", mcr::HALT, MCR::HALT::mask),
        ("MCR.NOTRDY", mcr::NOTRDY, MCR::NOTRDY::mask),
        ("MCR.WAKMSK", mcr::WAKMSK, MCR::WAKMSK::mask),
        ("MCR.SOFTRST", mcr::SOFTRST, MCR::SOFTRST::mask),
        ("MCR.FRZACK", mcr::FRZACK, MCR::FRZACK::mask),
        ("MCR.SUPV", mcr::SUPV, MCR::SUPV::mask),
        ("MCR.SLFWAK", mcr::SLFWAK, MCR::SLFWAK::mask),
        ("MCR.WRNEN", mcr::WRNEN, MCR::WRNEN::mask),
        ("MCR.LPMACK", mcr::LPMACK, MCR::LPMACK::mask),
        ("MCR.WAKSRC", mcr::WAKSRC, MCR::WAKSRC::mask),
        ("MCR.SRXDIS", mcr::SRXDIS, MCR::SRXDIS::mask),
        ("MCR.IRMQ", mcr::IRMQ, MCR::IRMQ::mask),
        ("MCR.LPRIOEN", mcr::LPRIOEN, MCR::LPRIOEN::mask),
        ("MCR.AEN", mcr::AEN, MCR::AEN::mask),
        ("MCR.IDAM", f(mcr::IDAM), MCR::IDAM::mask),
        ("MCR.MAXMB", f(mcr::MAXMB), MCR::MAXMB::mask),
        // CTRL1 (CLKSRC: CAN3's block only, below)
        ("CTRL1.PRESDIV", f(ctrl1::PRESDIV), CTRL1::PRESDIV::mask),
        ("CTRL1.RJW", f(ctrl1::RJW), CTRL1::RJW::mask),
        ("CTRL1.PSEG1", f(ctrl1::PSEG1), CTRL1::PSEG1::mask),
        ("CTRL1.PSEG2", f(ctrl1::PSEG2), CTRL1::PSEG2::mask),
        ("CTRL1.BOFFMSK", ctrl1::BOFFMSK, CTRL1::BOFFMSK::mask),
        ("CTRL1.ERRMSK", ctrl1::ERRMSK, CTRL1::ERRMSK::mask),
        ("CTRL1.LPB", ctrl1::LPB, CTRL1::LPB::mask),
        ("CTRL1.TWRNMSK", ctrl1::TWRNMSK, CTRL1::TWRNMSK::mask),
        ("CTRL1.RWRNMSK", ctrl1::RWRNMSK, CTRL1::RWRNMSK::mask),
        ("CTRL1.SMP", ctrl1::SMP, CTRL1::SMP::mask),
        ("CTRL1.BOFFREC", ctrl1::BOFFREC, CTRL1::BOFFREC::mask),
        ("CTRL1.TSYN", ctrl1::TSYN, CTRL1::TSYN::mask),
        ("CTRL1.LBUF", ctrl1::LBUF, CTRL1::LBUF::mask),
        ("CTRL1.LOM", ctrl1::LOM, CTRL1::LOM::mask),
        ("CTRL1.PROPSEG", f(ctrl1::PROPSEG), CTRL1::PROPSEG::mask),
        (
            "CTRL1.CLKSRC (CAN3)",
            ctrl1::CLKSRC,
            imxrt_ral::can3::CTRL1::CLKSRC::mask,
        ),
        // ECR
        ("ECR.TXERRCNT", f(ecr::TXERRCNT), ECR::TX_ERR_COUNTER::mask),
        ("ECR.RXERRCNT", f(ecr::RXERRCNT), ECR::RX_ERR_COUNTER::mask),
        // ESR1
        ("ESR1.WAKINT", esr1::WAKINT, ESR1::WAKINT::mask),
        ("ESR1.ERRINT", esr1::ERRINT, ESR1::ERRINT::mask),
        ("ESR1.BOFFINT", esr1::BOFFINT, ESR1::BOFFINT::mask),
        ("ESR1.RX", esr1::RX, ESR1::RX::mask),
        ("ESR1.FLTCONF", f(esr1::FLTCONF), ESR1::FLTCONF::mask),
        ("ESR1.TX", esr1::TX, ESR1::TX::mask),
        ("ESR1.IDLE", esr1::IDLE, ESR1::IDLE::mask),
        ("ESR1.RXWRN", esr1::RXWRN, ESR1::RXWRN::mask),
        ("ESR1.TXWRN", esr1::TXWRN, ESR1::TXWRN::mask),
        ("ESR1.STFERR", esr1::STFERR, ESR1::STFERR::mask),
        ("ESR1.FRMERR", esr1::FRMERR, ESR1::FRMERR::mask),
        ("ESR1.CRCERR", esr1::CRCERR, ESR1::CRCERR::mask),
        ("ESR1.ACKERR", esr1::ACKERR, ESR1::ACKERR::mask),
        ("ESR1.BIT0ERR", esr1::BIT0ERR, ESR1::BIT0ERR::mask),
        ("ESR1.BIT1ERR", esr1::BIT1ERR, ESR1::BIT1ERR::mask),
        ("ESR1.RWRNINT", esr1::RWRNINT, ESR1::RWRNINT::mask),
        ("ESR1.TWRNINT", esr1::TWRNINT, ESR1::TWRNINT::mask),
        ("ESR1.SYNCH", esr1::SYNCH, ESR1::SYNCH::mask),
        // CTRL2
        ("CTRL2.WRMFRZ", ctrl2::WRMFRZ, CTRL2::WRMFRZ::mask),
        ("CTRL2.RFFN", f(ctrl2::RFFN), CTRL2::RFFN::mask),
        ("CTRL2.TASD", f(ctrl2::TASD), CTRL2::TASD::mask),
        ("CTRL2.MRP", ctrl2::MRP, CTRL2::MRP::mask),
        ("CTRL2.RRS", ctrl2::RRS, CTRL2::RRS::mask),
        ("CTRL2.EACEN", ctrl2::EACEN, CTRL2::EACEN::mask),
        // ESR2, CRCR, RXFIR, IFLAG1 (the Rx FIFO flags)
        ("ESR2.IMB", esr2::IMB, ESR2::IMB::mask),
        ("ESR2.VPS", esr2::VPS, ESR2::VPS::mask),
        ("ESR2.LPTM", f(esr2::LPTM), ESR2::LPTM::mask),
        ("CRCR.TXCRC", f(regs::crcr::TXCRC), CRCR::TXCRC::mask),
        ("CRCR.MBCRC", f(regs::crcr::MBCRC), CRCR::MBCRC::mask),
        ("RXFIR.IDHIT", f(rxfir::IDHIT), RXFIR::IDHIT::mask),
        ("IFLAG1.BUF5I", iflag1::BUF5I, IFLAG1::BUF5I::mask),
        ("IFLAG1.BUF6I", iflag1::BUF6I, IFLAG1::BUF6I::mask),
        ("IFLAG1.BUF7I", iflag1::BUF7I, IFLAG1::BUF7I::mask),
        // Message-buffer words (CAN3's block names them).
        ("CS.CODE", f(cs::CODE), imxrt_ral::can3::CS0::CODE::mask),
        ("CS.SRR", cs::SRR, imxrt_ral::can3::CS0::SRR::mask),
        ("CS.IDE", cs::IDE, imxrt_ral::can3::CS0::IDE::mask),
        ("CS.RTR", cs::RTR, imxrt_ral::can3::CS0::RTR::mask),
        ("CS.DLC", f(cs::DLC), imxrt_ral::can3::CS0::DLC::mask),
        (
            "CS.TIME_STAMP",
            f(cs::TIME_STAMP),
            imxrt_ral::can3::CS0::TIME_STAMP::mask,
        ),
        ("ID.PRIO", f(id::PRIO), imxrt_ral::can3::ID0::PRIO::mask),
        ("ID.STD", f(id::STD), imxrt_ral::can3::ID0::STD::mask),
        ("ID.EXT", f(id::EXT), imxrt_ral::can3::ID0::EXT::mask),
    ] {
        same(name, ours, ral);
    }
}
