//! Conversion between [`Frame`]s and the four words of a message buffer ("Message buffer
//! structure": CS, ID, WORD0, WORD1; data byte 0 is the most significant byte of WORD0).

use twocan_core::frame::Frame;

use crate::regs::{cs, id};

/// The four words a received frame occupies in a message buffer (or the FIFO output):
/// `code` in CS\[CODE\], SRR set for extended frames (received recessive), `prio` kept in
/// ID\[PRIO\] (not transmitted, so it survives a move-in).
pub(crate) fn encode(frame: &Frame, stamp: u16, code: u32, prio: u32) -> [u32; 4] {
    let ext = frame.is_extended();
    let mut c = cs::CODE.val(code)
        | cs::DLC.val(u32::from(frame.dlc()))
        | cs::TIME_STAMP.val(u32::from(stamp));
    if ext {
        c |= cs::SRR | cs::IDE;
    }
    if frame.is_remote() {
        c |= cs::RTR;
    }
    let idw = id::PRIO.val(prio)
        | if ext {
            id::EXT_ID.val(frame.raw_id())
        } else {
            id::STD.val(frame.raw_id())
        };
    let d = frame.data_padded();
    let w0 = u32::from_be_bytes([d[0], d[1], d[2], d[3]]);
    let w1 = u32::from_be_bytes([d[4], d[5], d[6], d[7]]);
    [c, idw, w0, w1]
}

/// The frame a transmit message buffer describes: IDE, RTR and DLC from CS, the identifier
/// from ID (standard: bits 28–18), the data from WORD0/WORD1. A DLC code above 8 is kept
/// as written and sends eight bytes ("Transmit process": FlexCAN transmits up to eight
/// data bytes; ISO 11898-1 reads codes 9..15 as eight bytes).
pub(crate) fn decode(words: [u32; 4]) -> Option<Frame> {
    let [c, idw, w0, w1] = words;
    let ext = c & cs::IDE != 0;
    let remote = c & cs::RTR != 0;
    let dlc = cs::DLC.get(c) as u8;
    let raw = if ext {
        id::EXT_ID.get(idw)
    } else {
        id::STD.get(idw)
    };
    let a = w0.to_be_bytes();
    let b = w1.to_be_bytes();
    let data = [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]];
    Frame::from_registers(raw, ext, remote, dlc, data).ok()
}
