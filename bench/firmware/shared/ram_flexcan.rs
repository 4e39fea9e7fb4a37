//! The RAM stand-in for FlexCAN0's registers that `insn-count-flexcan` runs our FlexCAN
//! driver and the hand-written one on under QEMU (mps2-an386), next to `qemu.rs`
//! (markers, stack painting). Included with `#[path]`.
//!
//! # The register block
//!
//! QEMU's board has no FlexCAN. A RAM block at [`REGS`] (above the bxCAN stand-in, below
//! the marker window, outside every section) stands in for the module's registers
//! (Kinetis K66 RM, FlexCAN "Memory map/register definition": `MCR` at 0 up to
//! `RXIMR15` at 0x8BC; offsets from `twocan_flexcan::regs`). Both drivers are configured
//! while a SysTick handler plays the mode handshakes in `MCR` as the module would
//! (`MDIS` → `LPMACK`, `FRZ` + `HALT` → `FRZACK` and `NOTRDY`, `SOFTRST` clears itself);
//! `ESR1.SYNCH` reads as set. The handler is stopped before anything is measured.
//!
//! # Write-1-to-clear on RAM
//!
//! `IFLAG1` and `ESR1` flags clear when 1 is written to them. On RAM a store of the
//! `BUF5I` bit alone leaves `BUF5I` set, so a receive loop that pops the Rx FIFO until
//! `BUF5I` reads 0 would never end. Both drivers therefore reach the block through an
//! accessor that plays the rule on these two registers — a write of `v` stores
//! `old & !v` ([`RamFlexCanRegs`] for ours, `RamBus` of `insn-count-flexcan` for the
//! hand-written one) — one extra load and `BIC` per such write on both sides, which
//! hardware would not execute.
//!
//! # One frame's work per measured call
//!
//! As for the bxCAN stand-in, each measured call starts from a restored snapshot showing
//! what FlexCAN0 would show for one frame's work, and its effect is checked afterwards:
//!
//! - `tx_free`: MB15 (the transmit mailbox) `INACTIVE`, its `IFLAG1` bit clear;
//! - `tx_done`: MB15 sent (code back to `INACTIVE`, DLC and time stamp written), its
//!   `IFLAG1` bit set;
//! - `rx_one`: the Rx FIFO holds one frame (`IFLAG1.BUF5I`, the output in MB0,
//!   `RXFIR.IDHIT` = 0).

// Each firmware that includes this module uses a part of it.
#![allow(dead_code)]

use core::ptr::{read_volatile, write_volatile};

use twocan_core::Registers;
use twocan_flexcan::regs::{
    self, code, cs, esr1, iflag1, mcr, FlexCanAt, BLOCK_END, ESR1, IFLAG1, MCR, RXFIR,
};

/// The FlexCAN register block in RAM.
pub const REGS: usize = 0x2010_8000;
/// Words of the register block.
pub const BLOCK_WORDS: usize = BLOCK_END / 4;
/// The transmit mailbox (both drivers: MB15).
pub const TX_MB: usize = 15;

/// The frame every path sends and receives (as in `ram_can.rs`).
pub const ID: u16 = 0x123;
/// Its data.
pub const DATA: [u8; 8] = [0x01, 0x23, 0x45, 0x67, 0x89, 0xAB, 0xCD, 0xEF];
/// The data as FlexCAN's two data words (byte 0 in the most significant byte).
pub const WORD0: u32 = 0x0123_4567;
pub const WORD1: u32 = 0x89AB_CDEF;
/// The time stamps the snapshots show.
pub const RX_STAMP: u16 = 0x1234;
pub const TX_STAMP: u16 = 0x2345;

// ------------------------------------------------------------------ the register block

pub fn reg_read(offset: usize) -> u32 {
    // SAFETY: `REGS + offset` lies in the RAM register block (see `REGS`), aligned.
    unsafe { read_volatile((REGS + offset) as *const u32) }
}

pub fn reg_write(offset: usize, value: u32) {
    // SAFETY: as `reg_read`; the block is RAM reserved for this stand-in.
    unsafe { write_volatile((REGS + offset) as *mut u32, value) }
}

/// The register block for our driver: volatile accesses at the block's compile-time
/// address (`FlexCanAt`, as `Can0At` on a Teensy), with the write-1-to-clear rule of
/// `IFLAG1` and `ESR1` played on RAM (module docs).
pub struct RamFlexCanRegs(FlexCanAt<REGS>);

impl RamFlexCanRegs {
    /// The stand-in at [`REGS`].
    ///
    /// # Safety
    /// One driver at a time uses the stand-in.
    pub unsafe fn new() -> Self {
        // SAFETY: the caller's contract; `REGS` is RAM reserved for the stand-in.
        RamFlexCanRegs(unsafe { FlexCanAt::new() })
    }
}

impl Registers for RamFlexCanRegs {
    #[inline(always)]
    fn read32(&self, offset: usize) -> u32 {
        self.0.read32(offset)
    }

    #[inline(always)]
    fn write32(&self, offset: usize, value: u32) {
        if offset == IFLAG1 || offset == ESR1 {
            let now = self.0.read32(offset);
            self.0.write32(offset, now & !value);
        } else {
            self.0.write32(offset, value);
        }
    }
}

pub type Block = [u32; BLOCK_WORDS];

pub fn save() -> Block {
    let mut b = [0; BLOCK_WORDS];
    for (i, w) in b.iter_mut().enumerate() {
        *w = reg_read(4 * i);
    }
    b
}

pub fn restore(b: &Block) {
    for (i, w) in b.iter().enumerate() {
        reg_write(4 * i, *w);
    }
}

/// Reset values (K66 RM, FlexCAN register descriptions): `MCR` disabled and frozen,
/// the rest 0 here; `ESR1.SYNCH` set (the stand-in is always synchronised).
pub fn reset_block() {
    restore(&[0; BLOCK_WORDS]);
    reg_write(MCR, mcr::RESET);
    reg_write(ESR1, esr1::SYNCH);
}

pub struct Snapshots {
    pub tx_free: Block,
    pub tx_done: Block,
    pub rx_one: Block,
}

/// The snapshots, from the block a driver's configuration left.
pub fn snapshots(configured: &Block) -> Snapshots {
    let idle = {
        let mut b = *configured;
        b[MCR / 4] &= !(mcr::MDIS | mcr::FRZ | mcr::HALT | mcr::FRZACK | mcr::NOTRDY);
        b[MCR / 4] &= !(mcr::LPMACK | mcr::SOFTRST);
        b[ESR1 / 4] = esr1::SYNCH;
        b[IFLAG1 / 4] = 0;
        b[regs::mb_cs(TX_MB) / 4] = cs::CODE.val(code::TX_INACTIVE);
        b
    };
    let tx_free = idle;
    let mut tx_done = idle;
    tx_done[regs::mb_cs(TX_MB) / 4] =
        cs::CODE.val(code::TX_INACTIVE) | cs::DLC.val(8) | cs::TIME_STAMP.val(TX_STAMP as u32);
    tx_done[IFLAG1 / 4] = iflag1::buf(TX_MB);
    let mut rx_one = idle;
    rx_one[IFLAG1 / 4] = iflag1::BUF5I;
    rx_one[regs::mb_cs(0) / 4] = cs::DLC.val(8) | cs::TIME_STAMP.val(RX_STAMP as u32);
    rx_one[regs::mb_id(0) / 4] = regs::id::STD.val(ID as u32);
    rx_one[regs::mb_word0(0) / 4] = WORD0;
    rx_one[regs::mb_word1(0) / 4] = WORD1;
    rx_one[RXFIR / 4] = 0;
    Snapshots {
        tx_free,
        tx_done,
        rx_one,
    }
}

/// Whether MB15 holds the frame [`ID`]/[`DATA`] with code `DATA` (sending).
pub fn loaded() -> bool {
    let c = reg_read(regs::mb_cs(TX_MB));
    cs::CODE.get(c) == code::TX_DATA
        && cs::DLC.get(c) == 8
        && c & (cs::IDE | cs::RTR) == 0
        && reg_read(regs::mb_id(TX_MB)) & regs::id::STD.mask() == regs::id::STD.val(ID as u32)
        && reg_read(regs::mb_word0(TX_MB)) == WORD0
        && reg_read(regs::mb_word1(TX_MB)) == WORD1
}

/// Whether the Rx FIFO output was popped (`BUF5I` cleared).
pub fn popped() -> bool {
    reg_read(IFLAG1) & iflag1::BUF5I == 0
}

/// Whether MB15's flag was acknowledged.
pub fn tx_acknowledged() -> bool {
    reg_read(IFLAG1) & iflag1::buf(TX_MB) == 0
}

// ------------------------------------------------------------------ mode handshake stand-in

const ACKS: u32 = mcr::LPMACK | mcr::FRZACK | mcr::NOTRDY | mcr::SOFTRST;
const FRZ_HALT: u32 = mcr::FRZ | mcr::HALT;
const FROZEN: u32 = mcr::FRZACK | mcr::NOTRDY;

/// Plays the `MCR` handshakes while `qemu::responder_on` runs it (K66 RM, FlexCAN
/// "Modes of operation"): `LPMACK` while `MDIS` is set; else `FRZACK` and `NOTRDY` while
/// `FRZ` and `HALT` are set; `SOFTRST` always reads back 0 (the reset is done). Written
/// in assembly so that it pushes nothing beyond its exception frame, which it records
/// for the stack figures (`qemu::record_irq_frame`, reached by a branch).
///
/// # Safety
/// The SysTick exception handler only (`cortex-m-rt` links it under this name).
#[unsafe(naked)]
#[no_mangle]
pub unsafe extern "C" fn SysTick() {
    core::arch::naked_asm!(
        "ldr r0, ={regs}",
        "ldr r1, [r0]",
        "ldr r3, ={acks}",
        "bic r2, r1, r3",
        "ldr r3, ={mdis}",
        "tst r1, r3",
        "beq 1f",
        "ldr r3, ={lpmack}",
        "orr r2, r2, r3",
        "b 2f",
        "1:",
        "ldr r12, ={frz_halt}",
        "and r3, r1, r12",
        "cmp r3, r12",
        "bne 2f",
        "ldr r3, ={frozen}",
        "orr r2, r2, r3",
        "2:",
        "str r2, [r0]",
        "b {record}",
        regs = const REGS,
        acks = const ACKS,
        mdis = const mcr::MDIS,
        lpmack = const mcr::LPMACK,
        frz_halt = const FRZ_HALT,
        frozen = const FROZEN,
        record = sym crate::qemu::record_irq_frame,
    );
}
