//! Frames to and from the four words of a message buffer (Kinetis reference
//! manuals, FlexCAN "Message buffer structure"): control and status (CODE, SRR, IDE,
//! RTR, DLC, TIME STAMP), identifier (standard in bits 28–18, extended in 28–0), and
//! two data words with byte 0 in the most significant byte of the first.

use twocan_core::{Frame, Registers};

use crate::regs::{self, code, cs, id};

/// The four words of a message buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MbWords {
    /// Control and status.
    pub cs: u32,
    /// Identifier.
    pub id: u32,
    /// Data bytes 0–3.
    pub word0: u32,
    /// Data bytes 4–7.
    pub word1: u32,
}

impl MbWords {
    /// The words that transmit `frame` once: CODE `DATA` (`REMOTE` with RTR for a
    /// remote frame), SRR and IDE for an extended identifier.
    pub fn transmit(frame: &Frame) -> Self {
        let extended = frame.is_extended();
        let id = if extended {
            id::EXT_ID.val(frame.raw_id())
        } else {
            id::STD.val(frame.raw_id())
        };
        let mut control = cs::CODE.val(code::TX_DATA) | cs::DLC.val(frame.dlc() as u32);
        if extended {
            control |= cs::SRR | cs::IDE;
        }
        if frame.is_remote() {
            control |= cs::RTR;
        }
        let d = frame.data_padded();
        MbWords {
            cs: control,
            id,
            word0: u32::from_be_bytes([d[0], d[1], d[2], d[3]]),
            word1: u32::from_be_bytes([d[4], d[5], d[6], d[7]]),
        }
    }

    /// Reads message buffer `n` (CS first, as the reference manual's reading
    /// sequence wants).
    pub fn read<R: Registers>(regs: &R, n: usize) -> Self {
        MbWords {
            cs: regs.read32(regs::mb_cs(n)),
            id: regs.read32(regs::mb_id(n)),
            word0: regs.read32(regs::mb_word0(n)),
            word1: regs.read32(regs::mb_word1(n)),
        }
    }

    /// Writes message buffer `n`: identifier and data first, the control word (which
    /// holds CODE and so activates the buffer) last.
    pub fn write<R: Registers>(&self, regs: &R, n: usize) {
        regs.write32(regs::mb_id(n), self.id);
        regs.write32(regs::mb_word0(n), self.word0);
        regs.write32(regs::mb_word1(n), self.word1);
        regs.write32(regs::mb_cs(n), self.cs);
    }

    /// The frame these words hold. A DLC code of 9–15 is kept as written and means
    /// 8 bytes (ISO 11898-1).
    #[inline(always)]
    pub fn frame(&self) -> Frame {
        let extended = self.cs & cs::IDE != 0;
        let raw = if extended {
            id::EXT_ID.get(self.id)
        } else {
            id::STD.get(self.id)
        };
        let w0 = self.word0.to_be_bytes();
        let w1 = self.word1.to_be_bytes();
        Frame::from_words(
            Frame::id_word(raw, extended, self.cs & cs::RTR != 0),
            cs::DLC.get(self.cs) as u8,
            [w0[0], w0[1], w0[2], w0[3], w1[0], w1[1], w1[2], w1[3]],
        )
    }

    /// The TIME STAMP field of a control/status word.
    pub const fn timestamp_of(control: u32) -> u16 {
        cs::TIME_STAMP.get(control) as u16
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let frames = [
            Frame::standard(0x542, &[]).unwrap(),
            Frame::standard(0x7FF, &[1, 2, 3]).unwrap(),
            Frame::extended(0x1234_5678, &[1, 2, 3, 4, 5, 6, 7, 8]).unwrap(),
            Frame::remote(0x123, false, 4).unwrap(),
            Frame::remote(0x1FFF_FFFF, true, 8).unwrap(),
        ];
        for f in frames {
            let w = MbWords::transmit(&f);
            assert_eq!(cs::CODE.get(w.cs), code::TX_DATA);
            assert_eq!(w.frame(), f);
            assert_eq!(MbWords::timestamp_of(w.cs), 0);
        }
        let w = MbWords::transmit(&frames[2]);
        assert_eq!(w.cs & (cs::SRR | cs::IDE), cs::SRR | cs::IDE);
        assert_eq!(w.word0, 0x0102_0304);
        assert_eq!(MbWords::transmit(&frames[0]).id, 0x542 << 18);
        let long = MbWords {
            cs: cs::DLC.val(15),
            word0: 0x0102_0304,
            word1: 0x0506_0708,
            ..Default::default()
        };
        let f = long.frame();
        assert_eq!((f.dlc(), f.data()), (15, &[1, 2, 3, 4, 5, 6, 7, 8][..]));
        let back = MbWords::transmit(&f);
        assert_eq!(cs::DLC.get(back.cs), 15, "the code goes back as written");
    }
}
