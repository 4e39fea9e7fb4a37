//! Helpers shared by the model tests (included with `#[path]`; as a test target of its own
//! it only checks that it builds). The tests use the model as software does, through its
//! registers, and act as the bus by calling its `BusNode` methods.
#![allow(dead_code)]

use twocan_core::registers::Registers;
use twocan_core::Frame;
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::regs::{self, code, cs, ctrl1, ctrl2, id, iflag1, mcr, rxfir};
use twocan_sim::{BusNode, BusTime, TxResult};

/// Takes `m` out of module disable and sets up what the bus tests start from, still
/// halted in freeze: the Rx FIFO (`RFEN`) with its eight ID filters accepting everything
/// (individual masks 0, `IRMQ`), MB8..15 inactive and matching nothing (masks all ones),
/// and `mcr_bits` besides (`SRXDIS`, ...). Kinetis RM, FlexCAN "Rx FIFO structure" and
/// "Rx Individual Mask Registers".
pub fn accept_all_into_fifo(m: &FlexCanModel, mcr_bits: u32) {
    m.modify32(regs::MCR, |v| v & !mcr::MDIS);
    m.modify32(regs::MCR, |v| v | mcr::RFEN | mcr::IRMQ | mcr_bits);
    for n in 0..8 {
        m.write32(regs::rx_fifo_filter(n), 0);
        m.write32(regs::rximr(n), 0);
    }
    for n in 8..16 {
        m.write32(regs::mb_cs(n), 0);
        m.write32(regs::rximr(n), u32::MAX);
    }
}

/// Bit times a test frame occupies on the simulated wire (any value will do).
pub const FRAME_BITS: u64 = 100;

/// A model with a clock of bus time.
pub struct Rig {
    /// The module (software side and bus side).
    pub m: FlexCanModel,
    /// The bus time.
    pub now: u64,
}

impl Rig {
    /// A K20 module straight from reset.
    pub fn new() -> Self {
        Rig {
            m: FlexCanModel::mk20dx256(),
            now: 0,
        }
    }

    /// Reads a register as software does.
    pub fn rd(&self, offset: usize) -> u32 {
        self.m.read32(offset)
    }

    /// Writes a register as software does.
    pub fn wr(&mut self, offset: usize, value: u32) {
        self.m.write32(offset, value);
    }

    /// Read-modify-write of a register.
    pub fn set_bits(&mut self, offset: usize, bits: u32) {
        self.m.modify32(offset, |v| v | bits);
    }

    /// Read-modify-write of a register.
    pub fn clear_bits(&mut self, offset: usize, bits: u32) {
        self.m.modify32(offset, |v| v & !bits);
    }

    /// Leaves Disable mode into Freeze mode (FRZ and HALT are set by reset).
    pub fn enable_into_freeze(&mut self) {
        self.set_bits(regs::MCR, mcr::FRZ | mcr::HALT);
        self.clear_bits(regs::MCR, mcr::MDIS);
        assert_ne!(self.rd(regs::MCR) & mcr::FRZACK, 0, "freeze acknowledged");
    }

    /// Leaves Freeze mode and lets 11 recessive bits pass for synchronisation.
    pub fn start(&mut self) {
        self.clear_bits(regs::MCR, mcr::HALT);
        assert_eq!(self.rd(regs::MCR) & mcr::FRZACK, 0, "freeze left");
        self.idle(11);
        assert!(self.m.is_synchronised());
    }

    /// Enter freeze (from normal mode).
    pub fn freeze(&mut self) {
        self.set_bits(regs::MCR, mcr::FRZ | mcr::HALT);
        assert_ne!(self.rd(regs::MCR) & mcr::FRZACK, 0);
    }

    /// Lets `bits` recessive bit times pass.
    pub fn idle(&mut self, bits: u64) {
        self.now += bits;
        self.m.advance(bits, true, self.now);
    }

    /// Lets `bits` bit times of bus traffic pass (ending on a dominant bit).
    pub fn busy(&mut self, bits: u64) {
        self.now += bits;
        self.m.advance(bits, false, self.now);
    }

    /// Another node's frame is received correctly.
    pub fn deliver(&mut self, frame: &Frame) {
        let sof = self.now;
        self.busy(FRAME_BITS);
        self.m.rx(frame, false, BusTime { sof, now: self.now });
        self.idle(3);
    }

    /// Lets the module send what it wants to, with the given outcome, as the bus would
    /// (internal frames take no time); returns the frame.
    pub fn transmit(&mut self, result: TxResult) -> Option<Frame> {
        let req = self.m.poll_tx(self.now)?;
        if req.internal {
            let t = BusTime {
                sof: self.now,
                now: self.now,
            };
            self.m.tx_result(&req.frame, result, t);
            if result == TxResult::Acked {
                self.m.rx(&req.frame, true, t);
            }
            return Some(req.frame);
        }
        let sof = self.now;
        self.busy(FRAME_BITS);
        let t = BusTime { sof, now: self.now };
        self.m.tx_result(&req.frame, result, t);
        if result == TxResult::Acked {
            self.m.rx(&req.frame, true, t);
        }
        self.idle(3);
        Some(req.frame)
    }

    /// Sends everything pending successfully; returns the frames in order.
    pub fn transmit_all(&mut self) -> Vec<Frame> {
        let mut out = Vec::new();
        while let Some(f) = self.transmit(TxResult::Acked) {
            out.push(f);
            assert!(out.len() < 100, "runaway transmission");
        }
        out
    }

    /// Loads mailbox `n` with `frame` and activates it with `code` (ID and data first,
    /// then the C/S word, as "Transmit process" says).
    pub fn load_mb(&mut self, n: usize, frame: &Frame, code: u32) {
        self.load_mb_prio(n, frame, code, 0);
    }

    /// Like [`Rig::load_mb`] with a local priority.
    pub fn load_mb_prio(&mut self, n: usize, frame: &Frame, code: u32, prio: u32) {
        let ext = frame.is_extended();
        let idw = id::PRIO.val(prio)
            | if ext {
                id::EXT_ID.val(frame.raw_id())
            } else {
                id::STD.val(frame.raw_id())
            };
        let d = frame.data_padded();
        self.wr(regs::mb_id(n), idw);
        self.wr(
            regs::mb_word0(n),
            u32::from_be_bytes([d[0], d[1], d[2], d[3]]),
        );
        self.wr(
            regs::mb_word1(n),
            u32::from_be_bytes([d[4], d[5], d[6], d[7]]),
        );
        let mut c = cs::CODE.val(code) | cs::DLC.val(u32::from(frame.dlc()));
        if ext {
            c |= cs::SRR | cs::IDE;
        }
        if frame.is_remote() {
            c |= cs::RTR;
        }
        self.wr(regs::mb_cs(n), c);
    }

    /// Configures a receive mailbox for `id` (standard unless `ext`).
    pub fn rx_mb(&mut self, n: usize, raw_id: u32, ext: bool) {
        let idw = if ext {
            id::EXT_ID.val(raw_id)
        } else {
            id::STD.val(raw_id)
        };
        self.wr(regs::mb_id(n), idw);
        let ide = if ext { cs::IDE } else { 0 };
        self.wr(regs::mb_cs(n), cs::CODE.val(code::RX_EMPTY) | ide);
    }

    /// The code of mailbox `n` (peeked: does not lock).
    pub fn code(&self, n: usize) -> u32 {
        cs::CODE.get(self.m.peek32(regs::mb_cs(n)))
    }

    /// Reads mailbox `n` as software does (C/S first, which locks it, then ID, data, then
    /// TIMER to unlock); returns the frame, its code and its time stamp.
    pub fn read_mb(&mut self, n: usize) -> (Frame, u32, u16) {
        let c = self.rd(regs::mb_cs(n));
        let idw = self.rd(regs::mb_id(n));
        let w0 = self.rd(regs::mb_word0(n));
        let w1 = self.rd(regs::mb_word1(n));
        self.rd(regs::TIMER);
        (
            decode(c, idw, w0, w1),
            cs::CODE.get(c),
            cs::TIME_STAMP.get(c) as u16,
        )
    }

    /// Pops the Rx FIFO output as software does: frame, IDHIT, time stamp.
    pub fn pop_fifo(&mut self) -> Option<(Frame, u32, u16)> {
        if self.rd(regs::IFLAG1) & iflag1::BUF5I == 0 {
            return None;
        }
        let c = self.rd(regs::mb_cs(0));
        let idw = self.rd(regs::mb_id(0));
        let w0 = self.rd(regs::mb_word0(0));
        let w1 = self.rd(regs::mb_word1(0));
        let hit = rxfir::IDHIT.get(self.rd(regs::RXFIR));
        self.wr(regs::IFLAG1, iflag1::BUF5I);
        Some((decode(c, idw, w0, w1), hit, cs::TIME_STAMP.get(c) as u16))
    }

    /// Drains the FIFO.
    pub fn drain_fifo(&mut self) -> Vec<(Frame, u32)> {
        let mut out = Vec::new();
        while let Some((f, hit, _)) = self.pop_fifo() {
            out.push((f, hit));
        }
        out
    }

    /// Freeze-mode setup of the Rx FIFO: RFEN, IDAM format A, RFFN, IRMQ, filter elements
    /// (written from element 0), individual masks and global mask.
    pub fn setup_fifo(
        &mut self,
        rffn: u32,
        irmq: bool,
        elements: &[u32],
        individual: &[u32],
        global: u32,
    ) {
        let mut m = self.rd(regs::MCR) | mcr::RFEN;
        m = mcr::IDAM.replace(m, mcr::IDAM_FORMAT_A);
        m = if irmq { m | mcr::IRMQ } else { m & !mcr::IRMQ };
        self.wr(regs::MCR, m);
        let c2 = ctrl2::RFFN.replace(self.rd(regs::CTRL2), rffn);
        self.wr(regs::CTRL2, c2);
        for (n, e) in elements.iter().enumerate() {
            self.wr(regs::rx_fifo_filter(n), *e);
        }
        for (n, mask) in individual.iter().enumerate() {
            self.wr(regs::rximr(n), *mask);
        }
        self.wr(regs::RXFGMASK, global);
    }

    /// Sets CTRL1 bits (must be in freeze for the protected ones).
    pub fn ctrl1(&mut self, bits: u32) {
        self.set_bits(regs::CTRL1, bits);
    }

    /// A module configured the ACAN way for loop-back tests: enabled, Rx FIFO with all
    /// eight format-A elements accepting everything, self reception, loop-back, started.
    pub fn loopback_fifo() -> Self {
        let mut r = Rig::new();
        r.enable_into_freeze();
        r.setup_fifo(0, true, &[0; 8], &[0; 8], 0);
        r.clear_bits(regs::MCR, mcr::SRXDIS);
        r.ctrl1(ctrl1::LPB);
        r.start();
        r
    }
}

impl Default for Rig {
    fn default() -> Self {
        Self::new()
    }
}

/// The frame that message-buffer words describe.
pub fn decode(c: u32, idw: u32, w0: u32, w1: u32) -> Frame {
    let ext = c & cs::IDE != 0;
    let raw = if ext {
        id::EXT_ID.get(idw)
    } else {
        id::STD.get(idw)
    };
    let a = w0.to_be_bytes();
    let b = w1.to_be_bytes();
    Frame::from_registers(
        raw,
        ext,
        c & cs::RTR != 0,
        cs::DLC.get(c).min(8) as u8,
        [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]],
    )
    .expect("valid frame")
}

/// A format A filter element.
pub fn elem_a(raw_id: u32, ext: bool, remote: bool) -> u32 {
    let mut e = if ext { raw_id << 1 } else { raw_id << 19 };
    if ext {
        e |= 1 << 30;
    }
    if remote {
        e |= 1 << 31;
    }
    e
}

/// A format A mask checking RTR, IDE and the whole (standard or extended) ID.
pub fn exact_mask_a(ext: bool) -> u32 {
    if ext {
        0xFFFF_FFFE
    } else {
        0xFFF8_0000
    }
}

/// A standard data frame.
pub fn std(raw: u16, data: &[u8]) -> Frame {
    Frame::standard(raw, data).unwrap()
}

/// An extended data frame.
pub fn ext(raw: u32, data: &[u8]) -> Frame {
    Frame::extended(raw, data).unwrap()
}

/// A remote frame.
pub fn remote(raw: u32, extended: bool, dlc: u8) -> Frame {
    Frame::remote(raw, extended, dlc).unwrap()
}

#[test]
fn support_builds() {
    let r = Rig::new();
    assert_eq!(r.now, 0);
}
