//! Frames in and out of the mailbox registers (notes "Message storage"; RM0410 §40.9.3
//! "CAN mailbox registers"): `CAN_TIxR`/`CAN_RIxR` hold `STID[10:0]|EXID[17:0] IDE RTR`,
//! `CAN_TDTxR`/`CAN_RDTxR` the DLC (and FMI, TIME), `CAN_TDLxR`/`CAN_RDLxR` data bytes
//! 0..3 and `CAN_TDHxR`/`CAN_RDHxR` bytes 4..7, byte 0 in the least significant bits.

use twocan_core::{Frame, Priority, Registers};

use crate::regs::{rdtxr, rixr, tdhxr, tdlxr, tdtxr, tixr};

/// The identifier register value of `frame` (without `TXRQ`).
#[inline(always)]
pub(crate) fn id_register(frame: &Frame) -> u32 {
    let raw = frame.raw_id();
    let rtr = if frame.is_remote() { tixr::RTR } else { 0 };
    if frame.is_extended() {
        (raw << 3) | tixr::IDE | rtr
    } else {
        (raw << 21) | rtr
    }
}

/// The frame's identifier word ([`Frame::id_word`]) of a `CAN_RIxR`/`CAN_TIxR` value.
#[inline(always)]
pub(crate) fn id_word(ir: u32) -> u32 {
    let extended = ir & rixr::IDE != 0;
    let raw = if extended { ir >> 3 } else { ir >> 21 };
    Frame::id_word(raw, extended, ir & rixr::RTR != 0)
}

/// The arbitration key ([`Priority`]) of a `CAN_TIxR` value: identifier, `IDE`, `RTR`
/// (`TXRQ` ignored). Two mailboxes whose keys are equal tie in the hardware's identifier
/// order and go lower mailbox number first (RM0410 §40.7.3 "Transmit priority").
#[inline(always)]
pub(crate) fn priority_of(tir: u32) -> Priority {
    let extended = tir & tixr::IDE != 0;
    let raw = if extended {
        tir >> 3
    } else {
        (tir >> 21) & 0x7FF
    };
    Priority::from_raw(raw, extended, tir & tixr::RTR != 0)
}

/// The data registers' values of `frame`.
#[inline(always)]
pub(crate) fn data_words(frame: &Frame) -> (u32, u32) {
    let d = frame.data_padded();
    (
        u32::from_le_bytes([d[0], d[1], d[2], d[3]]),
        u32::from_le_bytes([d[4], d[5], d[6], d[7]]),
    )
}

/// The frame of mailbox words: identifier register, DLC (a code 9..=15 is kept as
/// written and means 8 bytes, ISO 11898-1), data registers.
#[inline(always)]
pub(crate) fn frame_of(ir: u32, dlc: u32, lo: u32, hi: u32) -> Frame {
    let mut data = [0u8; 8];
    data[..4].copy_from_slice(&lo.to_le_bytes());
    data[4..].copy_from_slice(&hi.to_le_bytes());
    Frame::from_words(id_word(ir), dlc as u8 & 0xF, data)
}

/// Loads `frame` into transmit mailbox `x` and requests its transmission (notes
/// "Transmission handling": DLC, data, then identifier with `TXRQ`).
#[inline(always)]
pub(crate) fn load<R: Registers>(regs: &R, x: usize, frame: &Frame) {
    let (lo, hi) = data_words(frame);
    regs.write32(tdtxr(x), frame.dlc() as u32);
    regs.write32(tdlxr(x), lo);
    regs.write32(tdhxr(x), hi);
    regs.write32(tixr(x), id_register(frame) | tixr::TXRQ);
}

/// Reads back the frame held by transmit mailbox `x` (the registers stay readable while
/// the mailbox is pending).
pub(crate) fn read_tx<R: Registers>(regs: &R, x: usize) -> Frame {
    frame_of(
        regs.read32(tixr(x)),
        rdtxr::DLC.get(regs.read32(tdtxr(x))),
        regs.read32(tdlxr(x)),
        regs.read32(tdhxr(x)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifier_round_trip() {
        let f = Frame::extended(0x1ABC_DEF1, &[1, 2, 3, 4, 5]).unwrap();
        let id = id_register(&f);
        assert_eq!(id, (0x1ABC_DEF1 << 3) | 0b100);
        let (lo, hi) = data_words(&f);
        assert_eq!(lo, 0x0403_0201);
        assert_eq!(hi, 0x05);
        assert_eq!(frame_of(id, 5, lo, hi), f);
        assert_eq!(priority_of(id | tixr::TXRQ), Priority::of(&f));
        let r = Frame::remote(0x7FF, false, 3).unwrap();
        assert_eq!(id_register(&r), (0x7FF << 21) | 0b10);
        assert_eq!(priority_of(id_register(&r)), Priority::of(&r));
        assert_eq!(frame_of(id_register(&r), 3, 0xFFFF_FFFF, 0), r);
        // DLC 15 is kept as written and reads as 8 bytes.
        let f = frame_of(0, 15, 0x0403_0201, 0x0807_0605);
        assert_eq!((f.dlc(), f.data()), (15, &[1, 2, 3, 4, 5, 6, 7, 8][..]));
        assert_eq!(data_words(&f), (0x0403_0201, 0x0807_0605));
    }
}
