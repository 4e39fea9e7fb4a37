//! Register offsets the model decodes beyond the ones of the driver's map (`crate::regs`),
//! from the IMXRT1060RM FlexCAN memory map, and the list of every register a variant
//! decodes ([`register_map`]), which `flexcan/tests/model_imxrt_ral.rs` checks against
//! the `imxrt-ral` register blocks.

use crate::regs;

use super::variant::Variant;

/// Interrupt Masks 2 (MB32–MB63).
pub const IMASK2: usize = 0x24;
/// Interrupt Flags 2 (MB32–MB63).
pub const IFLAG2: usize = 0x2C;
/// Error and Status 2 (read-only; not modelled: reads 0).
pub const ESR2: usize = 0x38;
/// CRC register (read-only; not modelled: reads 0).
pub const CRCR: usize = 0x44;
/// CAN Bit Timing (CAN3).
pub const CBT: usize = 0x50;
/// Debug 1 (CAN1/CAN2, read-only).
pub const DBG1: usize = 0x58;
/// Debug 2 (CAN1/CAN2, read-only).
pub const DBG2: usize = 0x5C;
/// First Rx Individual Mask register (RXIMR0; RXIMRn at `RXIMR0 + 4n`).
pub const RXIMR0: usize = 0x880;
/// Glitch Filter Width (CAN1/CAN2).
pub const GFWR: usize = 0x9E0;
/// CAN FD Control (CAN3).
pub const FDCTRL: usize = 0xC00;
/// CAN FD Bit Timing (CAN3).
pub const FDCBT: usize = 0xC04;
/// CAN FD CRC (CAN3, read-only).
pub const FDCRC: usize = 0xC08;
/// First message buffer (MB0's C/S word; MBn at `MB0 + 16n`).
pub const MB0: usize = 0x80;
/// Bytes per message buffer (8-byte payloads).
pub const MB_BYTES: usize = 16;

/// `MCR[FDEN]`, CAN FD operation enable (CAN3; stays 0 in this model).
pub const MCR_FDEN: u32 = 1 << 11;
/// `CBT[BTF]`: the extended bit timing fields of `CBT` are used instead of `CTRL1`'s.
pub const CBT_BTF: u32 = 1 << 31;

/// Every register `variant` decodes, by the manual's name, with its offset (the message
/// buffers as `MBn_CS`, the individual masks as `RXIMRn`).
pub fn register_map(variant: &Variant) -> Vec<(String, usize)> {
    let mut v: Vec<(String, usize)> = [
        ("MCR", regs::MCR),
        ("CTRL1", regs::CTRL1),
        ("TIMER", regs::TIMER),
        ("RXMGMASK", regs::RXMGMASK),
        ("RX14MASK", regs::RX14MASK),
        ("RX15MASK", regs::RX15MASK),
        ("ECR", regs::ECR),
        ("ESR1", regs::ESR1),
        ("IMASK1", regs::IMASK1),
        ("IFLAG1", regs::IFLAG1),
        ("CTRL2", regs::CTRL2),
        ("ESR2", ESR2),
        ("CRCR", CRCR),
        ("RXFGMASK", regs::RXFGMASK),
        ("RXFIR", regs::RXFIR),
    ]
    .into_iter()
    .map(|(n, o)| (n.to_string(), o))
    .collect();
    if variant.flags2_implemented() != 0 {
        v.push(("IMASK2".into(), IMASK2));
        v.push(("IFLAG2".into(), IFLAG2));
    }
    if variant.extras.cbt {
        v.push(("CBT".into(), CBT));
    }
    if variant.extras.debug {
        v.push(("DBG1".into(), DBG1));
        v.push(("DBG2".into(), DBG2));
    }
    if variant.extras.gfwr {
        v.push(("GFWR".into(), GFWR));
    }
    if variant.extras.can_fd {
        v.push(("FDCTRL".into(), FDCTRL));
        v.push(("FDCBT".into(), FDCBT));
        v.push(("FDCRC".into(), FDCRC));
    }
    for n in 0..variant.message_buffers {
        v.push((format!("MB{n}_CS"), MB0 + MB_BYTES * n));
        v.push((format!("RXIMR{n}"), RXIMR0 + 4 * n));
    }
    v
}
