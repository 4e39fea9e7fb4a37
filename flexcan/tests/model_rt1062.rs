//! The FlexCAN model as the i.MX RT1062's CAN1, CAN2 and CAN3 (IMXRT1060RM, chapter
//! "Flexible Controller Area Network (FLEXCAN)"): what differs from the Kinetis modules,
//! from the manual's rules and tables. Sections cited per test.
//!
//! The message buffers are addressed here with the manual's memory map (MBn at
//! 0x80 + 16·n, RXIMRn at 0x880 + 4·n: `twocan_flexcan::model::layout`), not with the
//! driver's helpers.

#[path = "model_support.rs"]
mod support;

use support::{Rig, FRAME_BITS};
use twocan_core::registers::Registers;
use twocan_core::Frame;
use twocan_flexcan::model::layout::{self, MB0, MB_BYTES, RXIMR0};
use twocan_flexcan::model::{Chip, Erratum, FlexCanModel, ModelMode, Rt1062Can};
use twocan_flexcan::regs::{self, code, cs, ctrl1, ctrl2, id, iflag1, mcr};
use twocan_sim::{BusNode, TxResult};

const ALL: [Rt1062Can; 3] = [Rt1062Can::Can1, Rt1062Can::Can2, Rt1062Can::Can3];

fn rt(can: Rt1062Can) -> Rig {
    Rig {
        m: FlexCanModel::imxrt1062(can),
        now: 0,
    }
}

fn mb_cs(n: usize) -> usize {
    MB0 + MB_BYTES * n
}

fn rximr(n: usize) -> usize {
    RXIMR0 + 4 * n
}

/// Filter table element `n` (format A/B/C words from MB6 on: 0xE0 + 4·n).
fn filter(n: usize) -> usize {
    MB0 + 6 * MB_BYTES + 4 * n
}

fn std(raw: u16) -> Frame {
    Frame::standard(raw, &[raw as u8]).unwrap()
}

/// Loads a standard data frame into MB `n` and activates it (ID and data first, then the
/// C/S word: "Transmit process").
fn load_tx(r: &mut Rig, n: usize, raw: u16) {
    r.wr(mb_cs(n) + 4, id::STD.val(u32::from(raw)));
    r.wr(mb_cs(n) + 8, u32::from(raw as u8) << 24);
    r.wr(mb_cs(n), cs::CODE.val(code::TX_DATA) | cs::DLC.val(1));
}

/// Makes MB `n` an EMPTY receive mailbox for standard identifier `raw`.
fn rx_mb(r: &mut Rig, n: usize, raw: u16) {
    r.wr(mb_cs(n) + 4, id::STD.val(u32::from(raw)));
    r.wr(mb_cs(n), cs::CODE.val(code::RX_EMPTY));
}

fn code_of(r: &Rig, n: usize) -> u32 {
    cs::CODE.get(r.m.peek32(mb_cs(n)))
}

/// Out of Freeze mode (the RT1062 leaves reset frozen) and synchronised.
fn run(r: &mut Rig) {
    r.start();
}

// --- reset and the register set -------------------------------------------------------

/// "Module Configuration Register (MCR)": reset value 0x5980_000F — the module leaves
/// reset enabled (MDIS = 0) and in Freeze mode (FRZ, HALT, FRZACK, NOTRDY), unlike the
/// Kinetis parts (0xD890_000F, Disable mode). Reset values of CTRL2 and the masks per
/// instance (CAN1/CAN2: masks all ones, CTRL2 0; CAN3: masks 0, CTRL2[TASD] = 0x10).
#[test]
fn reset_leaves_the_module_enabled_in_freeze_mode() {
    for can in ALL {
        let m = FlexCanModel::imxrt1062(can);
        assert_eq!(m.read32(regs::MCR), 0x5980_000F, "{can:?}");
        assert_eq!(m.mode(), ModelMode::Freeze, "{can:?}");
        assert_eq!(m.message_buffers(), 64);
        assert_eq!(m.chip(), Chip::Imxrt1062(can));
        assert_eq!(m.read32(regs::CTRL1), 0);
        assert_eq!(m.read32(regs::ECR), 0);
        assert_eq!(m.read32(regs::ESR1), 0);
        assert_eq!(m.read32(layout::IMASK2), 0);
        assert_eq!(m.read32(layout::IFLAG2), 0);
        let (ctrl2, masks) = if can == Rt1062Can::Can3 {
            (0x0080_0000, 0)
        } else {
            (0, u32::MAX)
        };
        assert_eq!(m.read32(regs::CTRL2), ctrl2, "{can:?}");
        for r in [
            regs::RXMGMASK,
            regs::RX14MASK,
            regs::RX15MASK,
            regs::RXFGMASK,
        ] {
            assert_eq!(m.read32(r), masks, "{can:?} 0x{r:X}");
        }
    }
    // Without clock the handshakes do not complete; FRZACK is already 1 out of reset.
    let m = FlexCanModel::imxrt1062(Rt1062Can::Can1);
    m.set_freeze_ack_stuck(true);
    m.modify32(regs::MCR, |v| v & !mcr::HALT);
    assert_eq!(m.mode(), ModelMode::Freeze, "stays frozen without a clock");
    m.set_freeze_ack_stuck(false);
    assert_eq!(m.mode(), ModelMode::Normal);
}

/// The registers one instance has and the others lack: DBG1/DBG2 and GFWR (reset 0x7F)
/// on CAN1/CAN2, CBT and FDCTRL/FDCBT/FDCRC on CAN3 (FDCTRL reset 0x8000_0100); absent
/// ones read 0 and ignore writes.
#[test]
fn per_instance_registers() {
    let can1 = FlexCanModel::imxrt1062(Rt1062Can::Can1);
    let can3 = FlexCanModel::imxrt1062(Rt1062Can::Can3);
    assert_eq!(can1.read32(layout::GFWR), 0x7F);
    assert_eq!(can1.read32(layout::DBG1), 0x0001_0000);
    assert_eq!(can3.read32(layout::GFWR), 0);
    assert_eq!(can3.read32(layout::DBG1), 0);
    assert_eq!(can3.read32(layout::FDCTRL), 0x8000_0100);
    assert_eq!(can1.read32(layout::FDCTRL), 0);
    // GFWR: 8 bits, written in Freeze mode (reset state).
    can1.write32(layout::GFWR, 0x1234);
    assert_eq!(can1.read32(layout::GFWR), 0x34);
    can3.write32(layout::GFWR, 0x12);
    assert_eq!(can3.read32(layout::GFWR), 0);
    // CBT on CAN3 only, Freeze mode only.
    can3.write32(layout::CBT, layout::CBT_BTF | 0x55);
    assert_eq!(can3.read32(layout::CBT), layout::CBT_BTF | 0x55);
    can1.write32(layout::CBT, 0x55);
    assert_eq!(can1.read32(layout::CBT), 0);
    can3.modify32(regs::MCR, |v| v & !mcr::HALT);
    can3.write32(layout::CBT, 0);
    assert_eq!(
        can3.read32(layout::CBT),
        layout::CBT_BTF | 0x55,
        "not out of freeze"
    );
    // DBG1 is read-only.
    can1.write32(layout::DBG1, 0);
    assert_eq!(can1.read32(layout::DBG1), 0x0001_0000);
}

/// CAN3 in classic CAN: MCR[FDEN] (bit 11) stays 0 and the FD registers keep their reset
/// values whatever is written (the model is classic only).
#[test]
fn can3_stays_classic() {
    let m = FlexCanModel::imxrt1062(Rt1062Can::Can3);
    m.modify32(regs::MCR, |v| v | layout::MCR_FDEN);
    assert_eq!(m.read32(regs::MCR) & layout::MCR_FDEN, 0);
    m.write32(layout::FDCTRL, 0);
    m.write32(layout::FDCBT, 0x1234_5678);
    assert_eq!(m.read32(layout::FDCTRL), 0x8000_0100);
    assert_eq!(m.read32(layout::FDCBT), 0);
    assert_eq!(m.read32(layout::FDCRC), 0);
}

/// CTRL1[CLKSRC]: CAN1/CAN2 have no engine clock selection (the bit is reserved: reads 0);
/// on CAN3 it is writable in Disable mode only, as on the Kinetis parts.
#[test]
fn clksrc_exists_on_can3_only() {
    for can in ALL {
        let m = FlexCanModel::imxrt1062(can);
        m.modify32(regs::MCR, |v| v | mcr::MDIS);
        assert_eq!(m.mode(), ModelMode::Disabled);
        m.modify32(regs::CTRL1, |v| v | ctrl1::CLKSRC);
        let set = m.read32(regs::CTRL1) & ctrl1::CLKSRC != 0;
        assert_eq!(set, can == Rt1062Can::Can3, "{can:?}");
    }
    // Not in Freeze mode (CAN3).
    let m = FlexCanModel::imxrt1062(Rt1062Can::Can3);
    m.modify32(regs::CTRL1, |v| v | ctrl1::CLKSRC);
    assert_eq!(m.read32(regs::CTRL1) & ctrl1::CLKSRC, 0);
}

/// The Kinetis modules keep their 16 message buffers: IMASK2/IFLAG2, MB16 and RXIMR16
/// are reserved there (read 0, writes ignored); IMASK1 has 16 bits there and 32 on the
/// RT1062.
#[test]
fn kinetis_has_no_upper_buffers() {
    let k = FlexCanModel::mk66fx1m0();
    k.modify32(regs::MCR, |v| v & !mcr::MDIS);
    assert_eq!(k.mode(), ModelMode::Freeze);
    for off in [
        layout::IMASK2,
        mb_cs(16),
        mb_cs(16) + 4,
        rximr(16),
        layout::GFWR,
    ] {
        k.write32(off, 0xFFFF_FFFF);
        assert_eq!(k.read32(off), 0, "0x{off:X}");
    }
    k.write32(regs::IMASK1, u32::MAX);
    assert_eq!(k.read32(regs::IMASK1), 0xFFFF);
    let r = FlexCanModel::imxrt1062(Rt1062Can::Can2);
    r.write32(regs::IMASK1, u32::MAX);
    r.write32(layout::IMASK2, u32::MAX);
    assert_eq!(r.read32(regs::IMASK1), u32::MAX);
    assert_eq!(r.read32(layout::IMASK2), u32::MAX);
    r.write32(mb_cs(63) + 12, 0xA5A5_A5A5);
    assert_eq!(r.read32(mb_cs(63) + 12), 0xA5A5_A5A5);
    assert_eq!(r.read32(mb_cs(64)), 0, "0x480 is past the last buffer");
}

/// RXIMR0–63 are written in Freeze mode only ("Rx Individual Mask Registers": "can only
/// be written in Freeze mode").
#[test]
fn rximr63_is_written_in_freeze_mode_only() {
    let mut r = rt(Rt1062Can::Can1);
    r.wr(rximr(63), 0x1234_5678);
    assert_eq!(r.rd(rximr(63)), 0x1234_5678);
    run(&mut r);
    r.wr(rximr(63), 0);
    assert_eq!(r.rd(rximr(63)), 0x1234_5678);
}

// --- 64 message buffers ---------------------------------------------------------------

/// MCR[MAXMB] (7 bits): "the number of the last Message Buffer that will take part in the
/// matching and arbitration processes"; reset 0xF. Raised in Freeze mode up to 63.
fn all_buffers(r: &mut Rig) {
    r.m.modify32(regs::MCR, |v| mcr::MAXMB.replace(v, 63));
    assert_eq!(mcr::MAXMB.get(r.rd(regs::MCR)), 63);
}

/// "Interrupt Flags 2 register (IFLAG2)": one flag per MB32–MB63, write 1 to clear;
/// "Interrupt Masks 2 register (IMASK2)" enables its interrupt. A frame sent from MB63
/// sets IFLAG2 bit 31 and nothing in IFLAG1.
#[test]
fn mailboxes_32_to_63_flag_in_iflag2() {
    let mut r = rt(Rt1062Can::Can1);
    all_buffers(&mut r);
    r.set_bits(regs::CTRL1, ctrl1::LPB);
    r.set_bits(regs::MCR, mcr::SRXDIS);
    run(&mut r);
    load_tx(&mut r, 63, 0x3F);
    assert_eq!(r.transmit(TxResult::Acked), Some(std(0x3F)));
    assert_eq!(code_of(&r, 63), code::TX_INACTIVE);
    assert_eq!(r.rd(layout::IFLAG2), 1 << 31);
    assert_eq!(r.rd(regs::IFLAG1), 0);
    assert!(!r.m.irq().message_buffer, "IMASK2 bit 31 clear");
    r.wr(layout::IMASK2, 1 << 31);
    assert!(r.m.irq().message_buffer);
    assert!(r.m.irq().any(), "the one RT1062 line per module");
    r.wr(layout::IFLAG2, 1 << 30);
    assert_eq!(
        r.rd(layout::IFLAG2),
        1 << 31,
        "write 0/other bits: no change"
    );
    r.wr(layout::IFLAG2, 1 << 31);
    assert_eq!(r.rd(layout::IFLAG2), 0);
    assert!(!r.m.irq().any());
}

/// MAXMB limits arbitration: with MAXMB = 40 a frame waiting in MB50 is not sent; raising
/// MAXMB (Freeze mode only) lets it go. A value above 63 (the field has 7 bits) is taken
/// as the last buffer that exists ("MAXMB must be programmed with a value smaller than
/// the number of available MBs" — the model clamps).
#[test]
fn maxmb_limits_arbitration() {
    let mut r = rt(Rt1062Can::Can2);
    r.m.modify32(regs::MCR, |v| mcr::MAXMB.replace(v, 40));
    r.set_bits(regs::CTRL1, ctrl1::LPB);
    r.set_bits(regs::MCR, mcr::SRXDIS);
    run(&mut r);
    load_tx(&mut r, 50, 0x50);
    assert_eq!(r.transmit(TxResult::Acked), None, "MB50 above MAXMB = 40");
    // MAXMB is written in Freeze mode only.
    r.m.modify32(regs::MCR, |v| mcr::MAXMB.replace(v, 0x7F));
    assert_eq!(mcr::MAXMB.get(r.rd(regs::MCR)), 40);
    r.freeze();
    r.m.modify32(regs::MCR, |v| mcr::MAXMB.replace(v, 0x7F));
    r.start();
    assert_eq!(r.transmit(TxResult::Acked), Some(std(0x50)));
    assert_eq!(r.rd(layout::IFLAG2), 1 << (50 - 32));
}

/// Arbitration over all 64 buffers: lowest identifier first (CTRL1[LBUF] = 0), lowest
/// buffer first with LBUF = 1 ("Arbitration process").
#[test]
fn arbitration_spans_all_64_buffers() {
    let mut r = rt(Rt1062Can::Can3);
    all_buffers(&mut r);
    r.set_bits(regs::CTRL1, ctrl1::LPB);
    r.set_bits(regs::MCR, mcr::SRXDIS);
    run(&mut r);
    for (n, raw) in [(3, 0x300), (33, 0x100), (62, 0x200)] {
        load_tx(&mut r, n, raw);
    }
    let order: Vec<u32> = r.transmit_all().iter().map(|f| f.raw_id()).collect();
    assert_eq!(order, [0x100, 0x200, 0x300]);
    r.freeze();
    r.set_bits(regs::CTRL1, ctrl1::LBUF);
    r.start();
    for (n, raw) in [(3, 0x300), (33, 0x100), (62, 0x200)] {
        load_tx(&mut r, n, raw);
    }
    let order: Vec<u32> = r.transmit_all().iter().map(|f| f.raw_id()).collect();
    assert_eq!(order, [0x300, 0x100, 0x200]);
}

/// A receive mailbox above MB31 matches under its individual mask (MCR[IRMQ] = 1:
/// RXIMR45 for MB45) and flags in IFLAG2.
#[test]
fn upper_mailbox_receives_under_its_individual_mask() {
    let mut r = rt(Rt1062Can::Can1);
    all_buffers(&mut r);
    r.set_bits(regs::MCR, mcr::IRMQ);
    // Compare bits 28–22 of the ID word only: the standard ID's top 7 bits.
    r.wr(rximr(45), 0x1FC0_0000);
    rx_mb(&mut r, 45, 0x120);
    run(&mut r);
    r.deliver(&std(0x12F));
    assert_eq!(code_of(&r, 45), code::RX_FULL);
    assert_eq!(r.rd(layout::IFLAG2), 1 << 13);
    r.deliver(&std(0x220));
    assert_eq!(
        r.m.frames_discarded(),
        1,
        "0x220 differs in the compared bits"
    );
}

/// With MCR[IRMQ] = 0: RX14MASK for MB14, RX15MASK for MB15, RXMGMASK for every other
/// mailbox, MB46 included ("Rx Mailboxes Global Mask register").
#[test]
fn global_masks_without_irmq() {
    let mut r = rt(Rt1062Can::Can1);
    all_buffers(&mut r);
    r.wr(regs::RX14MASK, 0);
    r.wr(regs::RXMGMASK, u32::MAX);
    rx_mb(&mut r, 14, 0x7FF);
    rx_mb(&mut r, 46, 0x046);
    run(&mut r);
    r.deliver(&std(0x046));
    assert_eq!(
        code_of(&r, 14),
        code::RX_FULL,
        "MB14 accepts all (RX14MASK = 0)"
    );
    r.deliver(&std(0x046));
    assert_eq!(
        code_of(&r, 14),
        code::RX_OVERRUN,
        "IRMQ = 0: the first match takes it"
    );
    assert_eq!(code_of(&r, 46), code::RX_EMPTY);
    r.freeze();
    r.wr(regs::RX14MASK, u32::MAX);
    // The move-in wrote the received identifier into MB14: configure it again.
    rx_mb(&mut r, 14, 0x7FF);
    r.start();
    r.deliver(&std(0x046));
    assert_eq!(code_of(&r, 46), code::RX_FULL, "MB46 under RXMGMASK");
    r.deliver(&std(0x047));
    assert_eq!(r.m.frames_discarded(), 1);
}

// --- Rx FIFO with the larger filter tables --------------------------------------------

/// Enables the Rx FIFO with `rffn`, format `idam`, IRMQ; every mask "compare all".
fn fifo(r: &mut Rig, rffn: u32, idam: u32) {
    all_buffers(r);
    r.set_bits(regs::MCR, mcr::RFEN | mcr::IRMQ);
    r.m.modify32(regs::MCR, |v| mcr::IDAM.replace(v, idam));
    r.m.modify32(regs::CTRL2, |v| ctrl2::RFFN.replace(v, rffn));
    r.wr(regs::RXFGMASK, u32::MAX);
    for n in 0..64 {
        r.wr(rximr(n), u32::MAX);
    }
    // Elements that match nothing a test sends: extended remote 0 in format A.
    for n in 0..128 {
        r.wr(filter(n), (1 << 31) | (1 << 30));
    }
}

fn idhit(r: &Rig) -> u32 {
    r.m.peek32(regs::RXFIR) & 0x1FF
}

/// Table "Rx FIFO filter: possible structures", RFFN = 0xF: 128 filter elements, the
/// FIFO and table occupy MB0–MB37, MB38–MB63 remain mailboxes. Element 127 is the last
/// word of MB37 (0xE0 + 4·127 = 0x2DC). RXFIR[IDHIT] (9 bits) names it.
#[test]
fn rffn_15_has_128_elements_up_to_mb37() {
    let mut r = rt(Rt1062Can::Can1);
    fifo(&mut r, 0xF, mcr::IDAM_FORMAT_A);
    assert_eq!(filter(127), 0x2DC);
    assert_eq!(filter(127), mb_cs(37) + 12);
    r.wr(filter(127), 0x555 << 19);
    // MB37 is table storage, not a mailbox; MB38 is the first mailbox.
    rx_mb(&mut r, 38, 0x123);
    run(&mut r);
    r.deliver(&std(0x555));
    let (frame, hit, _) = r.pop_fifo().expect("in the FIFO");
    assert_eq!(frame, std(0x555));
    assert_eq!(hit, 127);
    r.deliver(&std(0x123));
    assert_eq!(code_of(&r, 38), code::RX_FULL);
    assert_eq!(r.rd(layout::IFLAG2), 1 << (38 - 32));
    assert_eq!(r.m.fifo_len(), 0);
}

/// Same table, last column: elements 0–31 are masked by RXIMR0–31 (IRMQ = 1) even when
/// the table occupies more buffers (RFFN ≥ 0xC); elements 32–127 by RXFGMASK, whatever
/// RXIMR32.. hold.
#[test]
fn individual_masks_cover_elements_0_to_31_only() {
    let mut r = rt(Rt1062Can::Can1);
    fifo(&mut r, 0xF, mcr::IDAM_FORMAT_A);
    // Element 31 with RXIMR31 = 0 accepts everything.
    r.wr(filter(31), 0x7FF << 19);
    r.wr(rximr(31), 0);
    // Element 32 wants 0x020; RXIMR32 = 0 must NOT make it accept everything.
    r.wr(filter(32), 0x020 << 19);
    r.wr(rximr(32), 0);
    run(&mut r);
    r.deliver(&std(0x444));
    assert_eq!(r.pop_fifo().map(|p| p.1), Some(31));
    r.freeze();
    r.wr(rximr(31), u32::MAX);
    r.start();
    r.deliver(&std(0x444));
    assert_eq!(r.m.fifo_len(), 0, "element 32 is under RXFGMASK (all ones)");
    assert_eq!(r.m.frames_discarded(), 1);
    r.deliver(&std(0x020));
    assert_eq!(r.pop_fifo().map(|p| p.1), Some(32));
    // RXFGMASK = 0: element 32 now accepts everything.
    r.freeze();
    r.wr(regs::RXFGMASK, 0);
    r.start();
    r.deliver(&std(0x444));
    assert_eq!(r.pop_fifo().map(|p| p.1), Some(32));
}

/// Format C (MCR[IDAM] = 0b10) with 128 elements: four 8-bit filters per element, so the
/// last is IDAF 511 — the full width of RXFIR[IDHIT] (bits 8–0).
#[test]
fn format_c_numbers_filters_up_to_511() {
    let mut r = rt(Rt1062Can::Can3);
    fifo(&mut r, 0xF, mcr::IDAM_FORMAT_C);
    // Format C compares the 8 MSBs of the standard ID (bits 10–3); none of the unused
    // elements (0xC0 in every slice) match 0x7A8 >> 3 = 0xF5.
    for n in 0..128 {
        r.wr(filter(n), 0xC0C0_C0C0);
    }
    r.wr(filter(127), 0xC0C0_C0F5);
    run(&mut r);
    r.deliver(&std(0x7A8));
    assert_eq!(idhit(&r), 511);
    assert_eq!(r.pop_fifo().map(|p| p.1), Some(511));
}

/// The six-deep FIFO and its flags are those of the Kinetis parts (IFLAG1 bits 5–7).
/// RFFN = 7: 64 elements, "elements 0–21" under the individual masks, 22–63 under
/// RXFGMASK — with RXFGMASK = 0 element 22 is the first to accept any frame.
#[test]
fn fifo_depth_and_flags_unchanged() {
    let mut r = rt(Rt1062Can::Can2);
    fifo(&mut r, 0x7, mcr::IDAM_FORMAT_A);
    r.wr(regs::RXFGMASK, 0);
    run(&mut r);
    for k in 0..7u16 {
        r.deliver(&std(0x100 + k));
    }
    assert_eq!(r.m.fifo_len(), 6);
    let f = r.rd(regs::IFLAG1);
    assert_ne!(f & iflag1::BUF5I, 0);
    assert_ne!(f & iflag1::BUF6I, 0);
    assert_ne!(f & iflag1::BUF7I, 0);
    assert_eq!(r.m.fifo_overflows(), 1);
    assert_eq!(idhit(&r), 22);
}

// --- soft reset, errata --------------------------------------------------------------

/// MCR[SOFTRST] resets IMASK2 and IFLAG2 with IMASK1/IFLAG1 ("Soft Reset": "IMASK1,
/// IMASK2, IFLAG1, IFLAG2" among the registers reset), MCR to its reset configuration
/// (Freeze requested: FRZ, HALT) and leaves the message buffers and RXIMR.
#[test]
fn soft_reset_clears_the_upper_flags_and_masks() {
    let mut r = rt(Rt1062Can::Can1);
    all_buffers(&mut r);
    r.set_bits(regs::CTRL1, ctrl1::LPB);
    r.set_bits(regs::MCR, mcr::SRXDIS);
    r.wr(rximr(50), 0xABCD);
    run(&mut r);
    load_tx(&mut r, 40, 0x40);
    r.transmit_all();
    r.wr(layout::IMASK2, u32::MAX);
    assert_eq!(r.rd(layout::IFLAG2), 1 << 8);
    r.set_bits(regs::MCR, mcr::SOFTRST);
    assert_eq!(
        r.rd(regs::MCR) & mcr::SOFTRST,
        0,
        "done at once with the clock on"
    );
    assert_eq!(r.rd(layout::IFLAG2), 0);
    assert_eq!(r.rd(layout::IMASK2), 0);
    assert_eq!(r.m.mode(), ModelMode::Freeze);
    assert_eq!(mcr::MAXMB.get(r.rd(regs::MCR)), 0xF);
    assert_eq!(r.rd(rximr(50)), 0xABCD);
    assert_eq!(code_of(&r, 40), code::TX_INACTIVE);
}

/// The RT1062's FlexCAN errata as data (NXP's MIMXRT1062 feature list marks 5829, 6032
/// and 9595, not 5641) and the buffer counts of both families.
#[test]
fn variant_descriptors() {
    let rt = Chip::Imxrt1062(Rt1062Can::Can3).variant();
    assert_eq!(rt.errata, &[Erratum::E5829, Erratum::E6032, Erratum::E9595]);
    assert_eq!(rt.message_buffers, 64);
    assert_eq!(rt.max_rffn(), 15);
    let k = Chip::Mk66fx1m0.variant();
    assert_eq!(k.message_buffers, 16);
    assert!(k.errata.is_empty());
    assert_eq!(k.max_rffn(), 4);
    let map = layout::register_map(rt);
    assert!(map.iter().any(|(n, o)| n == "FDCTRL" && *o == 0xC00));
    assert!(map.iter().any(|(n, o)| n == "RXIMR63" && *o == 0x97C));
    assert!(!map.iter().any(|(n, _)| n == "GFWR"));
    let map = layout::register_map(k);
    assert!(!map.iter().any(|(n, _)| n == "IMASK2"));
    assert_eq!(map.iter().filter(|(n, _)| n.starts_with("MB")).count(), 16);
}

/// The model on the simulated bus as the RT1062: two modules exchange a frame from MB60
/// to MB61 (one bus time advance per frame; no loop-back).
#[test]
fn two_modules_exchange_through_upper_buffers() {
    let mut a = rt(Rt1062Can::Can1);
    let b = FlexCanModel::imxrt1062(Rt1062Can::Can2);
    all_buffers(&mut a);
    let mut rb = Rig {
        m: b.clone(),
        now: 0,
    };
    all_buffers(&mut rb);
    rx_mb(&mut rb, 61, 0x61);
    run(&mut a);
    run(&mut rb);
    load_tx(&mut a, 60, 0x61);
    let req = a.m.poll_tx(a.now).expect("a transmits");
    let t = twocan_sim::BusTime {
        sof: a.now,
        now: a.now + FRAME_BITS,
    };
    b.clone().rx(&req.frame, false, t);
    a.m.tx_result(&req.frame, TxResult::Acked, t);
    assert_eq!(code_of(&rb, 61), code::RX_FULL);
    assert_eq!(rb.rd(layout::IFLAG2), 1 << (61 - 32));
    assert_eq!(a.rd(layout::IFLAG2), 1 << (60 - 32));
}
