//! Helpers shared by the model tests (included with `#[path]`; as a test target of its own
//! it only checks that it builds). The tests use the model as software does, through its
//! registers, and act as the bus by calling its `BusNode` methods.
//!
//! The behaviour tests (`model_modes`, `model_rx_fifo`, `model_mailboxes`, `model_errors`,
//! `model_bus`, `model_races`) are written once, as functions of the [`Chip`], and
//! [`on_every_chip!`] makes one `#[test]` per module of [`CHIPS`] from each. Where a rule's
//! outcome differs between the modules, the test reads the expectation from [`Manual`]
//! (the reference manuals' values, kept here independently of the model's own
//! `Variant` table so that a wrong entry there fails a test).
#![allow(dead_code)]

use twocan_core::registers::Registers;
use twocan_core::Frame;
use twocan_flexcan::model::{Chip, FlexCanModel, ModelMode, Rt1062Can};
use twocan_flexcan::regs::{self, code, cs, ctrl1, ctrl2, id, iflag1, mcr, rxfir};
use twocan_sim::{BusNode, BusTime, TxResult};

/// Every FlexCAN module the model covers: the Kinetis K20, K64 and K66 modules and the
/// i.MX RT1062's CAN1, CAN2 and CAN3.
pub const CHIPS: [Chip; 6] = [
    Chip::Mk20dx256,
    Chip::Mk64fx512,
    Chip::Mk66fx1m0,
    Chip::Imxrt1062(Rt1062Can::Can1),
    Chip::Imxrt1062(Rt1062Can::Can2),
    Chip::Imxrt1062(Rt1062Can::Can3),
];

/// One `#[test]` per module of [`CHIPS`] for each named test body (a `fn(Chip)` of the
/// calling file): `body::mk20dx256`, `body::mk64fx512`, `body::mk66fx1m0`,
/// `body::rt1062_can1`, `body::rt1062_can2`, `body::rt1062_can3`. `cargo test rt1062`
/// runs the i.MX RT1062 half.
#[allow(unused_macros)]
macro_rules! on_every_chip {
    ($($body:ident),* $(,)?) => {$(
        mod $body {
            use twocan_flexcan::model::{Chip, Rt1062Can};
            #[test]
            fn mk20dx256() {
                super::$body(Chip::Mk20dx256)
            }
            #[test]
            fn mk64fx512() {
                super::$body(Chip::Mk64fx512)
            }
            #[test]
            fn mk66fx1m0() {
                super::$body(Chip::Mk66fx1m0)
            }
            #[test]
            fn rt1062_can1() {
                super::$body(Chip::Imxrt1062(Rt1062Can::Can1))
            }
            #[test]
            fn rt1062_can2() {
                super::$body(Chip::Imxrt1062(Rt1062Can::Can2))
            }
            #[test]
            fn rt1062_can3() {
                super::$body(Chip::Imxrt1062(Rt1062Can::Can3))
            }
        }
    )*};
}
#[allow(unused_imports)]
pub(crate) use on_every_chip;

/// What the reference manual gives for one module where the behaviour tests' outcomes
/// differ between modules. Kinetis: K20P64M72SF1RM, K64P144M120SF5RM,
/// K66P144M180SF5RMV2, chapter "FlexCAN"; i.MX RT1062: IMXRT1060RM chapter "Flexible
/// Controller Area Network (FLEXCAN)" (CAN1, CAN2 and the CAN FD capable CAN3), with the
/// reset values and fields of the NXP SVD as `imxrt-ral` 0.6 (`imxrt1062`) carries them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Manual {
    /// Message buffers: 16 (Kinetis "Message buffer structure") or 64 (IMXRT1060RM
    /// "Message buffer structure": MB0–MB63 at 0x80–0x47F).
    pub message_buffers: usize,
    /// `MCR` reset value ("Module Configuration Register"): Kinetis 0xD890_000F (MDIS,
    /// LPMACK: Disable mode); RT1062 0x5980_000F (MDIS = 0, FRZACK: enabled, in Freeze
    /// mode).
    pub reset_mcr: u32,
    /// The mode that reset value means.
    pub reset_mode: ModelMode,
    /// `CTRL2` reset value: Kinetis 0x00B0_0000 (TASD = 0x16); RT1062 CAN1/CAN2 0, CAN3
    /// 0x0080_0000 (TASD = 0x10) (SVD reset values).
    pub reset_ctrl2: u32,
    /// `RXMGMASK`, `RX14MASK`, `RX15MASK`, `RXFGMASK` reset value: all ones, except on
    /// the RT1062's CAN3 (0; SVD reset values).
    pub reset_masks: u32,
    /// `CTRL2` bits 15–0 that are reserved (read 0): all of them on the Kinetis parts
    /// (MK20D7 SVD: no field below bit 16) and on CAN1/CAN2 (SVD `can::CTRL2`); bits 10
    /// and 5–0 on CAN3, whose other low bits are the CAN FD and time stamp fields
    /// (`TIMER_SRC`, `PREXCEN`, `BTE`, `ISOCANFDEN`, `EDFLTDIS`, `MBTSBASE`, `TSTAMPCAP`:
    /// SVD `can3::CTRL2`).
    pub ctrl2_reserved_low: u32,
    /// `IMASK1`/`IFLAG1` bits that exist: one per MB0–MB15 (Kinetis) or MB0–MB31.
    pub flags1: u32,
    /// `IMASK2`/`IFLAG2` bits that exist: one per MB32–MB63 on the RT1062 ("Interrupt
    /// Masks 2 register (IMASK2)"); none on the 16-buffer Kinetis parts (there is no
    /// MB32–MB63 for a bit to stand for; the MK20D7 SVD lists the two registers all the
    /// same).
    pub flags2: u32,
    /// `MCR[WAKSRC]` is implemented (reserved on the MK20DX256: K20P64M72SF1RM MCR
    /// field description; present on the K64, K66 and the RT1062 modules).
    pub waksrc: bool,
    /// `CTRL1[CLKSRC]` is implemented (Kinetis, RT1062 CAN3); reserved on CAN1/CAN2
    /// (SVD `can::CTRL1` has no CLKSRC; NXP feature list "engine clock selection
    /// removed").
    pub clksrc: bool,
    /// Rows (RFFN, filter elements under the individual masks) of table "Rx FIFO filter:
    /// possible structures" (CTRL2\[RFFN\] field description), last column ("Rx FIFO ID
    /// filter table elements affected by Rx Individual Masks"): elements 0 … 7 + 2·RFFN,
    /// never beyond element 31. The Kinetis rows end where a mailbox is still left
    /// (RFFN 3: MB14, MB15); the RT1062 rows cover the whole table (RFFN 0xF: MB0–MB37).
    pub fifo_individual: &'static [(u32, usize)],
}

const KINETIS_FIFO_ROWS: &[(u32, usize)] = &[(0, 8), (1, 10), (2, 12), (3, 14)];
const RT1062_FIFO_ROWS: &[(u32, usize)] = &[
    (0x0, 8),
    (0x1, 10),
    (0x2, 12),
    (0x3, 14),
    (0x4, 16),
    (0x5, 18),
    (0x6, 20),
    (0x7, 22),
    (0x8, 24),
    (0x9, 26),
    (0xA, 28),
    (0xB, 30),
    (0xC, 32),
    (0xD, 32),
    (0xE, 32),
    (0xF, 32),
];

const KINETIS: Manual = Manual {
    message_buffers: 16,
    reset_mcr: 0xD890_000F,
    reset_mode: ModelMode::Disabled,
    reset_ctrl2: 0x00B0_0000,
    reset_masks: u32::MAX,
    ctrl2_reserved_low: 0xFFFF,
    flags1: 0xFFFF,
    flags2: 0,
    waksrc: true,
    clksrc: true,
    fifo_individual: KINETIS_FIFO_ROWS,
};

const RT1062_CAN1: Manual = Manual {
    message_buffers: 64,
    reset_mcr: 0x5980_000F,
    reset_mode: ModelMode::Freeze,
    reset_ctrl2: 0,
    reset_masks: u32::MAX,
    ctrl2_reserved_low: 0xFFFF,
    flags1: u32::MAX,
    flags2: u32::MAX,
    waksrc: true,
    clksrc: false,
    fifo_individual: RT1062_FIFO_ROWS,
};

impl Manual {
    /// The manual's values for `chip`.
    pub const fn of(chip: Chip) -> Manual {
        match chip {
            Chip::Mk20dx256 => Manual {
                waksrc: false,
                ..KINETIS
            },
            Chip::Mk64fx512 | Chip::Mk66fx1m0 => KINETIS,
            Chip::Imxrt1062(Rt1062Can::Can1 | Rt1062Can::Can2) => RT1062_CAN1,
            Chip::Imxrt1062(Rt1062Can::Can3) => Manual {
                reset_ctrl2: 0x0080_0000,
                reset_masks: 0,
                ctrl2_reserved_low: 0x043F,
                clksrc: true,
                ..RT1062_CAN1
            },
        }
    }

    /// `MCR` once the module is enabled and frozen (MDIS and LPMACK negated, FRZACK
    /// asserted, the rest as out of reset): what a soft reset leaves in Freeze mode.
    pub const fn frozen_mcr(&self) -> u32 {
        self.reset_mcr & !(mcr::MDIS | mcr::LPMACK) | mcr::FRZACK
    }
}

/// `(IFLAG1, IFLAG2)` with only message buffer `n`'s flag set, and the mask register
/// (`IMASK1` or `IMASK2`) and bit that enable its interrupt: MB0–MB31 in IFLAG1/IMASK1
/// bit n, MB32–MB63 in IFLAG2/IMASK2 bit n − 32 (IMXRT1060RM "Interrupt Flags 2 register
/// (IFLAG2)", "Interrupt Masks 2 register (IMASK2)"; the Kinetis parts stop at MB15).
pub fn mb_flag(n: usize) -> ((u32, u32), usize, u32) {
    if n < 32 {
        ((1 << n, 0), regs::IMASK1, 1 << n)
    } else {
        (
            (0, 1 << (n - 32)),
            twocan_flexcan::model::layout::IMASK2,
            1 << (n - 32),
        )
    }
}

/// Takes `m` out of module disable and sets up what the bus tests start from, still
/// halted in freeze: the Rx FIFO (`RFEN`) with its eight ID filters accepting everything
/// (individual masks 0, `IRMQ`), the mailboxes after the FIFO (MB8 up to `MCR[MAXMB]`,
/// 0xF out of reset on every module: MB8..15) inactive and matching nothing (masks all
/// ones), and `mcr_bits` besides (`SRXDIS`, ...). Kinetis RM, FlexCAN "Rx FIFO structure"
/// and "Rx Individual Mask Registers"; on the RT1062 MB16..MB63 stay out of matching and
/// arbitration above `MAXMB` (IMXRT1060RM MCR\[MAXMB\]), and RFFN = 0 puts all eight
/// elements under `RXIMR0–7`, so CAN3's zero reset masks (`RXMGMASK`, `RXFGMASK`) play no
/// part.
pub fn accept_all_into_fifo(m: &FlexCanModel, mcr_bits: u32) {
    m.modify32(regs::MCR, |v| v & !mcr::MDIS);
    m.modify32(regs::MCR, |v| v | mcr::RFEN | mcr::IRMQ | mcr_bits);
    for n in 0..8 {
        m.write32(regs::rx_fifo_filter(n), 0);
        m.write32(regs::rximr(n), 0);
    }
    let last = mcr::MAXMB.get(m.read32(regs::MCR)) as usize;
    for n in 8..=last {
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
        Self::on(Chip::Mk20dx256)
    }

    /// A module of `chip` straight from reset.
    pub fn on(chip: Chip) -> Self {
        Rig {
            m: FlexCanModel::new(chip),
            now: 0,
        }
    }

    /// The manual's values for this module.
    pub fn manual(&self) -> Manual {
        Manual::of(self.m.chip())
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

    /// Leaves Disable mode into Freeze mode (FRZ and HALT are set by reset); on the
    /// RT1062, which leaves reset in Freeze mode, it asserts that mode.
    pub fn enable_into_freeze(&mut self) {
        self.set_bits(regs::MCR, mcr::FRZ | mcr::HALT);
        self.clear_bits(regs::MCR, mcr::MDIS);
        assert_ne!(self.rd(regs::MCR) & mcr::FRZACK, 0, "freeze acknowledged");
    }

    /// Enters Module Disable mode (MDIS = 1, acknowledged by LPMACK): the Kinetis reset
    /// state already; the RT1062 leaves reset in Freeze mode (IMXRT1060RM MCR reset
    /// 0x5980_000F) and gets there by MDIS = 1 ("Module disable mode").
    pub fn enter_disable(&mut self) {
        self.set_bits(regs::MCR, mcr::MDIS);
        assert_ne!(self.rd(regs::MCR) & mcr::LPMACK, 0, "disable acknowledged");
        assert_eq!(self.m.mode(), ModelMode::Disabled);
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
    pub fn loopback_fifo(chip: Chip) -> Self {
        let mut r = Rig::on(chip);
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
