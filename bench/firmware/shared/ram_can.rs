//! The RAM stand-in for CAN1's registers that the instruction-count firmwares
//! (`insn-count`, `insn-count-async`) run the drivers on under QEMU (mps2-an386), and
//! the marker stores the counting plugin (`bench/plugin/insn_count.c`) listens to.
//! Included by both with `#[path]`.
//!
//! # The register block
//!
//! QEMU's board has no bxCAN. A RAM block at [`REGS`] stands in for CAN1's registers
//! (RM0410 §40.9, offsets from `twocan_bxcan::regs`): our driver reaches it through
//! `twocan_core::Mmio::new(REGS)`, the `bxcan` crate through its `Instance::REGISTERS`
//! pointer set to the same address. Both are configured through their public APIs while
//! a SysTick handler acknowledges mode requests as the hardware would
//! (`CAN_MCR.INRQ` → `CAN_MSR.INAK`, `SLEEP` → `SLAK`); the handler is stopped before
//! anything is measured.
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
use core::sync::atomic::{compiler_fence, Ordering};

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::{SCB, SYST};
use cortex_m_rt::{exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hprintln};
use twocan_bxcan::regs::{self, mcr, msr, rdtxr, rfxr, rixr, tdtxr, tixr, tsr};
use twocan_bxcan::{Bank, BxCan, Can, Config, Fifo, FilterPlan};
use twocan_core::{Error, Filter, Mmio};

/// The bxCAN register block in RAM: above the 1 MiB the linker uses (memory.x), so no
/// section overlaps it.
pub const REGS: usize = 0x2010_0000;
/// Words of the register block (up to `CAN_F27R2` at 0x31C).
pub const BLOCK_WORDS: usize = 0x320 / 4;
/// The plugin's marker window: start of region `n` at `+ 8n`, end at `+ 8n + 4`.
pub const MARKERS: usize = 0x2011_0000;

/// The marker window's address, read from the ELF by can-bench and handed to the plugin.
#[no_mangle]
#[used]
static BENCH_MARKER_WINDOW: u32 = MARKERS as u32;

/// Measurements of each region.
pub const REPEAT: usize = 5;

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

/// Starts the SysTick handler that acknowledges mode requests (configuration only).
pub fn responder_on(syst: &mut SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(2_000);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

pub fn responder_off(syst: &mut SYST) {
    syst.disable_counter();
    syst.disable_interrupt();
    SCB::clear_pendst();
}

/// Acknowledges mode requests while [`responder_on`] runs it.
#[exception]
fn SysTick() {
    let m = reg_read(regs::MCR);
    let ack = if m & mcr::INRQ != 0 {
        msr::INAK
    } else if m & mcr::SLEEP != 0 {
        msr::SLAK
    } else {
        0
    };
    reg_write(regs::MSR, ack);
}

/// Configuration attempts after a timed-out mode request (see [`configure_ours`]).
const CONFIG_RETRIES: u32 = 20;

/// Our driver on the stand-in, configured with `config` and one accept-all bank to
/// FIFO 0, ready for `State::split` (run with [`responder_on`]).
///
/// The stand-in acknowledges from SysTick, whose rate under QEMU follows host time: a
/// wait the driver bounds in polls can run out first on a loaded host. The configuration
/// is not measured, so a timed-out request is retried (the driver hands the controller
/// back with the error).
pub fn configure_ours(config: &Config) -> BxCan<Mmio> {
    // SAFETY: `REGS` is the RAM stand-in for CAN1's registers; the caller gives it to
    // this driver alone from now on (the `bxcan` crate, if it used it, has freed it).
    let regs = unsafe { Mmio::new(REGS) };
    let mut attempt = Can::can1(regs, config);
    for _ in 0..CONFIG_RETRIES {
        match attempt {
            Err(f) if f.error == Error::Timeout => attempt = f.value.reconfigure(config),
            _ => break,
        }
    }
    let mut init = match attempt {
        Ok(i) => i,
        Err(_) => fail("twocan: can1"),
    };
    let mut plan = FilterPlan::manual();
    let bank = match Bank::mask32(&Filter::pass_all(), Fifo::Fifo0) {
        Ok(b) => b,
        Err(_) => fail("twocan: bank"),
    };
    check(plan.set_bank(0, bank).is_ok(), "twocan: set_bank");
    check(init.set_filters(&plan).is_ok(), "twocan: set_filters");
    let mut attempt = init.enable();
    for _ in 0..CONFIG_RETRIES {
        match attempt {
            Err(f) if f.error == Error::Timeout => attempt = f.value.enable(),
            _ => break,
        }
    }
    match attempt {
        Ok(can) => can.into_split(),
        Err(_) => fail("twocan: enable"),
    }
}

// ------------------------------------------------------------------ measuring

pub fn marker(offset: usize) {
    // SAFETY: the marker window is RAM outside every linker section (memory.x); the
    // store only signals the plugin.
    unsafe { write_volatile((MARKERS + offset) as *mut u32, 0) }
}

/// Runs `f` once between the start and end markers of region `N` (of [`REGIONS`]).
#[inline(always)]
pub fn measure<const N: usize, T>(f: impl FnOnce() -> T) -> T {
    marker(8 * N);
    compiler_fence(Ordering::SeqCst);
    let r = f();
    compiler_fence(Ordering::SeqCst);
    marker(8 * N + 4);
    r
}

pub fn fail(what: &str) -> ! {
    hprintln!("FAIL {}", what);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}

pub fn check(ok: bool, what: &str) {
    if !ok {
        fail(what);
    }
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

/// Prints the marker window and the region names (`region <n> <key>`).
pub fn announce(regions: &[&str]) {
    hprintln!("window {:#010x}", MARKERS);
    for (n, key) in regions.iter().enumerate() {
        hprintln!("region {} {}", n, key);
    }
}

/// Prints `done` and exits QEMU with success.
pub fn finish() -> ! {
    hprintln!("done");
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::bkpt();
    }
}

/// Reports a fault and fails the run (cortex-m-rt requires the handler to be an
/// `unsafe fn`; it touches no memory through the frame beyond reading the stacked PC).
#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    hprintln!("FAIL hard fault at {:#010x}", frame.pc());
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("FAIL panic: {}", info);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}
