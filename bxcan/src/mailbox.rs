//! Frames in and out of the mailbox registers (notes "Message storage"; RM0410 §40.9.3
//! "CAN mailbox registers"): `CAN_TIxR`/`CAN_RIxR` hold `STID[10:0]|EXID[17:0] IDE RTR`,
//! `CAN_TDTxR`/`CAN_RDTxR` the DLC (and FMI, TIME), `CAN_TDLxR`/`CAN_RDLxR` data bytes
//! 0..3 and `CAN_TDHxR`/`CAN_RDHxR` bytes 4..7, byte 0 in the least significant bits.

use twocan_core::{Frame, FrameError, Registers};

use crate::regs::{rdhxr, rdlxr, rdtxr, rixr, tdhxr, tdlxr, tdtxr, tixr};

/// The identifier register value of `frame` (without TXRQ).
pub(crate) fn id_register(frame: &Frame) -> u32 {
    let rtr = if frame.is_remote() { tixr::RTR } else { 0 };
    if frame.is_extended() {
        tixr::STID.val(frame.raw_id() >> 18) | tixr::EXID.val(frame.raw_id()) | tixr::IDE | rtr
    } else {
        tixr::STID.val(frame.raw_id()) | rtr
    }
}

fn data_words(frame: &Frame) -> (u32, u32) {
    let mut bytes = [0u8; 8];
    let d = frame.data();
    bytes[..d.len()].copy_from_slice(d);
    let lo = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
    let hi = u32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]);
    (lo, hi)
}

/// Loads `frame` into transmit mailbox `x` and requests its transmission (notes
/// "Transmission handling": identifier, DLC, data, then TXRQ in `CAN_TIxR`).
pub(crate) fn load<R: Registers>(regs: &mut R, x: usize, frame: &Frame) {
    let (lo, hi) = data_words(frame);
    regs.write32(tdtxr(x), tdtxr::DLC.val(frame.dlc() as u32));
    regs.write32(tdlxr(x), lo);
    regs.write32(tdhxr(x), hi);
    regs.write32(tixr(x), id_register(frame) | tixr::TXRQ);
}

fn decode(id: u32, dlc: u32, lo: u32, hi: u32) -> Result<Frame, FrameError> {
    let extended = id & rixr::IDE != 0;
    let remote = id & rixr::RTR != 0;
    let raw = if extended {
        (rixr::STID.get(id) << 18) | rixr::EXID.get(id)
    } else {
        rixr::STID.get(id)
    };
    // DLC 9..15 means 8 bytes (ISO 11898-1).
    let dlc = dlc.min(8) as u8;
    let mut data = [0u8; 8];
    data[..4].copy_from_slice(&lo.to_le_bytes());
    data[4..].copy_from_slice(&hi.to_le_bytes());
    Frame::from_registers(raw, extended, remote, dlc, data)
}

/// Reads back the frame held by transmit mailbox `x` (the registers stay readable while
/// the mailbox is pending).
pub(crate) fn read_tx<R: Registers>(regs: &R, x: usize) -> Result<Frame, FrameError> {
    decode(
        regs.read32(tixr(x)),
        tdtxr::DLC.get(regs.read32(tdtxr(x))),
        regs.read32(tdlxr(x)),
        regs.read32(tdhxr(x)),
    )
}

/// A frame read from the output mailbox of a receive FIFO, with its FMI and time stamp.
pub(crate) struct Received {
    pub frame: Result<Frame, FrameError>,
    pub fmi: u8,
    pub time: u16,
}

/// Reads the output mailbox of FIFO `x` (does not release it).
pub(crate) fn read_rx<R: Registers>(regs: &R, x: usize) -> Received {
    let id = regs.read32(rixr(x));
    let dt = regs.read32(rdtxr(x));
    let lo = regs.read32(rdlxr(x));
    let hi = regs.read32(rdhxr(x));
    Received {
        frame: decode(id, rdtxr::DLC.get(dt), lo, hi),
        fmi: rdtxr::FMI.get(dt) as u8,
        time: rdtxr::TIME.get(dt) as u16,
    }
}

/// The time stamp (`CAN_RDTxR.TIME`) of the output mailbox of FIFO `x`.
pub(crate) fn read_rx_time<R: Registers>(regs: &R, x: usize) -> u16 {
    rdtxr::TIME.get(regs.read32(rdtxr(x))) as u16
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
        assert_eq!(decode(id, 5, lo, hi).unwrap(), f);
        let r = Frame::remote(0x7FF, false, 3).unwrap();
        assert_eq!(id_register(&r), (0x7FF << 21) | 0b10);
        assert_eq!(decode(id_register(&r), 3, 0xFFFF_FFFF, 0).unwrap(), r);
        // DLC 15 reads as 8 bytes.
        assert_eq!(decode(0, 15, 0, 0).unwrap().dlc(), 8);
    }
}
