//! The RAM stand-in for CAN1's registers that the bxCAN instruction-count firmwares
//! (`insn-count`, `insn-count-async`) run the drivers on under QEMU (mps2-an386).
//! Included by both with `#[path]`, next to `qemu.rs` (markers, stack painting).
//!
//! # The register block
//!
//! QEMU's board has no bxCAN. A RAM block at [`REGS`] stands in for CAN1's registers
//! (RM0410 §40.9, offsets from `twocan_bxcan::regs`): our driver reaches it through
//! `twocan_core::Mmio::new(REGS)`, the `bxcan` crate through its `Instance::REGISTERS`
//! pointer set to the same address. Both are configured through their public APIs while
//! a SysTick handler acknowledges mode requests as the hardware would
//! (`CAN_MCR.INRQ` → `CAN_MSR.INAK`, `SLEEP` → `SLAK`); the handler is stopped before
//! anything is measured. Its interrupts push their 8-word exception frame on the stack
//! the configuration runs on; it records where (`qemu::IRQ_FRAMES`), so that the
//! configuration's stack figure leaves those words out (`qemu::config_stack_depth`).
//!
//! # One frame's work per measured call
//!
//! RAM does not react: writing RFOM does not pop the FIFO, writing 1 to a flag does not
//! clear it only. So before every measured call the block is restored from a snapshot
//! showing exactly the state a real CAN1 would show for one frame's work, the call is
//! measured once, and its effect is checked afterwards; a failed check ends the run with
//! a failure exit code. The snapshots:
//!
//! - `tx_free`: three empty mailboxes (TSR.TME0..2, CODE = 0);
//! - `tx_one_busy`: mailbox 0 pending with a lower-priority frame (0x400), 1 and 2 empty;
//! - `tx_full`: three mailboxes pending with higher-priority frames (0x010..0x012);
//! - `tx_refill`: mailbox 0 empty, its completion already acknowledged (no RQCP: on RAM
//!   the write-1-to-clear store of RQCP would also wipe the read-only TME bits), 1 and 2
//!   pending;
//! - `tx_done`: mailbox 0 completed (RQCP0, TXOK0) and all mailboxes empty;
//! - `rx_one`: FIFO 0 holds one frame (FMP0 = 1, output mailbox filled), FIFO 1 empty.
//!
//! A receive handler that loops while `FMP0 > 0` ends after one frame on this block: its
//! release store (`RFOM0` alone) leaves `FMP0` = 0, as the hardware would after the last
//! frame.

// Each firmware that includes this module uses a part of it.
#![allow(dead_code)]

use core::ptr::{read_volatile, write_volatile};

use twocan_bxcan::regs::{self, mcr, msr, rdtxr, rfxr, rixr, tdtxr, tixr, tsr};

/// The bxCAN register block in RAM: above the 1 MiB the linker uses (memory.x), so no
/// section overlaps it.
pub const REGS: usize = 0x2010_0000;
/// Words of the register block (up to `CAN_F27R2` at 0x31C).
pub const BLOCK_WORDS: usize = 0x320 / 4;

/// The frame every path sends and receives.
pub const ID: u16 = 0x123;
/// Its data.
pub const DATA: [u8; 8] = [0x01, 0x23, 0x45, 0x67, 0x89, 0xAB, 0xCD, 0xEF];

// ------------------------------------------------------------------ the register block

pub fn reg_read(offset: usize) -> u32 {
    // SAFETY: `REGS + offset` lies in the RAM register block (see `REGS`), aligned.
    unsafe { read_volatile((REGS + offset) as *const u32) }
}

pub fn reg_write(offset: usize, value: u32) {
    // SAFETY: as `reg_read`; the block is RAM reserved for this stand-in.
    unsafe { write_volatile((REGS + offset) as *mut u32, value) }
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

/// RM0410 reset values (§40.9); mailboxes and filter banks read 0 here.
pub fn reset_block() {
    restore(&[0; BLOCK_WORDS]);
    reg_write(regs::MCR, mcr::RESET_VALUE);
    reg_write(regs::MSR, msr::RESET_VALUE);
    reg_write(regs::TSR, tsr::RESET_VALUE);
    reg_write(regs::BTR, regs::btr::RESET_VALUE);
    reg_write(regs::FMR, regs::fmr::RESET_VALUE);
}

/// Loads transmit mailbox `x` as pending with a standard frame `id` (8 bytes).
pub fn pending(b: &mut Block, x: usize, id: u32) {
    b[regs::tixr(x) / 4] = tixr::STID.val(id) | tixr::TXRQ;
    b[regs::tdtxr(x) / 4] = tdtxr::DLC.val(8);
    b[regs::tdlxr(x) / 4] = 0x0403_0201;
    b[regs::tdhxr(x) / 4] = 0x0807_0605;
}

pub fn tsr_value(empty: &[usize], code: u32) -> u32 {
    empty
        .iter()
        .fold(tsr::CODE.val(code), |v, &x| v | tsr::tme(x))
}

pub struct Snapshots {
    pub tx_free: Block,
    pub tx_one_busy: Block,
    pub tx_full: Block,
    pub tx_refill: Block,
    pub tx_done: Block,
    pub rx_one: Block,
}

pub fn snapshots(configured: &Block) -> Snapshots {
    let idle = {
        let mut b = *configured;
        b[regs::MSR / 4] = 0; // normal mode, no flags
        b[regs::RF0R / 4] = 0;
        b[regs::RF1R / 4] = 0;
        b[regs::ESR / 4] = 0;
        b[regs::TSR / 4] = tsr_value(&[0, 1, 2], 0);
        b
    };
    let tx_free = idle;
    let mut tx_one_busy = idle;
    pending(&mut tx_one_busy, 0, 0x400);
    tx_one_busy[regs::TSR / 4] = tsr_value(&[1, 2], 1);
    let mut tx_full = idle;
    for x in 0..3 {
        pending(&mut tx_full, x, 0x010 + x as u32);
    }
    // All pending: CODE names the lowest-priority mailbox.
    tx_full[regs::TSR / 4] = tsr_value(&[], 2) | tsr::LOW2;
    let mut tx_refill = tx_full;
    tx_refill[regs::TSR / 4] = tsr_value(&[0], 0);
    tx_refill[regs::tixr(0) / 4] &= !tixr::TXRQ;
    let mut tx_done = idle;
    tx_done[regs::TSR / 4] = tsr_value(&[0, 1, 2], 0) | tsr::RQCP0 | tsr::TXOK0;
    let mut rx_one = idle;
    rx_one[regs::RF0R / 4] = rfxr::FMP.val(1);
    rx_one[regs::rixr(0) / 4] = rixr::STID.val(ID as u32);
    rx_one[regs::rdtxr(0) / 4] = rdtxr::DLC.val(8) | rdtxr::FMI.val(0) | rdtxr::TIME.val(0x1234);
    rx_one[regs::rdlxr(0) / 4] = u32::from_le_bytes([DATA[0], DATA[1], DATA[2], DATA[3]]);
    rx_one[regs::rdhxr(0) / 4] = u32::from_le_bytes([DATA[4], DATA[5], DATA[6], DATA[7]]);
    Snapshots {
        tx_free,
        tx_one_busy,
        tx_full,
        tx_refill,
        tx_done,
        rx_one,
    }
}

// ------------------------------------------------------------------ mode handshake stand-in

/// Acknowledges mode requests while `qemu::responder_on` runs it: `CAN_MSR.INAK` while
/// `CAN_MCR.INRQ` is set, else `SLAK` while `SLEEP` is set, else neither (RM0410
/// §40.4). Written in assembly so that it pushes nothing beyond its exception frame,
/// which it records for the stack figures (`qemu::record_irq_frame`, reached by a
/// branch: it returns from the exception).
///
/// # Safety
/// The SysTick exception handler only (`cortex-m-rt` links it under this name).
#[unsafe(naked)]
#[no_mangle]
pub unsafe extern "C" fn SysTick() {
    core::arch::naked_asm!(
        "ldr r0, ={regs}",
        "ldr r1, [r0, #{mcr}]",
        "movs r2, #{inak}",
        "tst r1, #{inrq}",
        "bne 1f",
        "movs r2, #0",
        "tst r1, #{sleep}",
        "beq 1f",
        "movs r2, #{slak}",
        "1:",
        "str r2, [r0, #{msr}]",
        "b {record}",
        regs = const REGS,
        mcr = const regs::MCR,
        msr = const regs::MSR,
        inrq = const mcr::INRQ,
        sleep = const mcr::SLEEP,
        inak = const msr::INAK,
        slak = const msr::SLAK,
        record = sym crate::qemu::record_irq_frame,
    );
}

/// Whether transmit mailbox `x` holds the frame [`ID`]/[`DATA`] with its request set.
pub fn loaded(x: usize) -> bool {
    reg_read(regs::tixr(x)) == tixr::STID.val(ID as u32) | tixr::TXRQ
        && reg_read(regs::tdlxr(x)) == 0x6745_2301
        && reg_read(regs::tdhxr(x)) == 0xEFCD_AB89
        && tdtxr::DLC.get(reg_read(regs::tdtxr(x))) == 8
}

/// Whether FIFO 0's output mailbox was released (`RFOM0` written).
pub fn released() -> bool {
    reg_read(regs::RF0R) & rfxr::RFOM != 0
}
