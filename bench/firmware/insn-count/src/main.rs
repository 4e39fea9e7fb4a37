//! Instructions per frame of the twocan bxCAN driver and of the `bxcan` crate 0.8, on a
//! Cortex-M4 under QEMU (`-machine mps2-an386`), counted by the TCG plugin
//! `bench/plugin/insn_count.c` between marker stores (see [`measure`]).
//!
//! # The register block
//!
//! QEMU's board has no bxCAN. A RAM block at [`REGS`] stands in for CAN1's registers
//! (RM0410 §40.9, offsets from `twocan_bxcan::regs`): our driver reaches it through
//! `twocan_core::Mmio::new(REGS)`, the `bxcan` crate through its `Instance::REGISTERS`
//! pointer set to the same address. Both are configured through their public APIs
//! (loop-back, 500 kbit/s from 54 MHz, one accept-all bank to FIFO 0) while a SysTick
//! handler acknowledges mode requests as the hardware would (`CAN_MCR.INRQ` → `CAN_MSR.INAK`,
//! `SLEEP` → `SLAK`); the handler is stopped before anything is measured.
//!
//! # One frame's work per measured call
//!
//! RAM does not react: writing RFOM does not pop the FIFO, writing 1 to a flag does not
//! clear it only. So before every measured call the block is restored from a snapshot
//! showing exactly the state a real CAN1 would show for one frame's work, the call is
//! measured once, and its effect is checked afterwards (frame loaded in the expected
//! mailbox, frame in the ring, FIFO released, ...); a failed check ends the run with a
//! failure exit code. The snapshots:
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
//! The firmware prints `region <n> <key>` for each measured region and `done` through
//! semihosting, then exits with the semihosting exit call.
#![no_std]
#![no_main]

use core::hint::black_box;
use core::ptr::{read_volatile, write_volatile};
use core::sync::atomic::{compiler_fence, Ordering};

use bxcan::filter::Mask32;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::{SCB, SYST};
use cortex_m_rt::{entry, exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hprintln};
use twocan_bxcan::regs::{self, mcr, msr, rdtxr, rfxr, rixr, tdtxr, tixr, tsr};
use twocan_bxcan::{Bank, Can, Config, Fifo, FilterPlan};
use twocan_core::timing::{solve_cia, Limits};
use twocan_core::{Driver, Filter, Frame, Mmio, TxPolicy};

/// The bxCAN register block in RAM: above the 1 MiB the linker uses (memory.x), so no
/// section overlaps it.
const REGS: usize = 0x2010_0000;
/// Bytes of the register block (up to `CAN_F27R2` at 0x31C).
const BLOCK_WORDS: usize = 0x320 / 4;
/// The plugin's marker window: start of region `n` at `+ 8n`, end at `+ 8n + 4`.
const MARKERS: usize = 0x2011_0000;

/// The marker window's address, read from the ELF by can-bench and handed to the plugin.
#[no_mangle]
#[used]
static BENCH_MARKER_WINDOW: u32 = MARKERS as u32;

/// Measurements of each region.
const REPEAT: usize = 5;

const APB1_HZ: u32 = 54_000_000;
const BITRATE: u32 = 500_000;
const ID: u16 = 0x123;
const DATA: [u8; 8] = [0x01, 0x23, 0x45, 0x67, 0x89, 0xAB, 0xCD, 0xEF];

/// As the loop-back firmwares: loop-back, identifier-priority order (TXFP = 0).
const CONFIG: Config = match Config::from_bitrate(APB1_HZ, BITRATE) {
    Ok(c) => c.loopback(true).tx_policy(TxPolicy::Priority),
    Err(_) => panic!("no bit timing"),
};
const BTR: u32 = match solve_cia(APB1_HZ, BITRATE, &Limits::BXCAN) {
    Ok(t) => match t.bxcan_btr() {
        Ok(v) => v,
        Err(_) => panic!("no CAN_BTR value"),
    },
    Err(_) => panic!("no bit timing"),
};

/// The measured regions, in the order of their numbers.
const REGIONS: [&str; 11] = [
    "empty",
    "twocan.try_send.direct",
    "twocan.try_send.one_busy",
    "twocan.try_send.queued",
    "twocan.on_interrupt.refill",
    "twocan.on_interrupt.tx_done",
    "twocan.on_interrupt.rx",
    "twocan.receive",
    "bxcan.transmit",
    "bxcan.transmit.one_busy",
    "bxcan.receive",
];

const EMPTY: usize = 0;
const OURS_SEND_DIRECT: usize = 1;
const OURS_SEND_ONE_BUSY: usize = 2;
const OURS_SEND_QUEUED: usize = 3;
const OURS_IRQ_REFILL: usize = 4;
const OURS_IRQ_TX_DONE: usize = 5;
const OURS_IRQ_RX: usize = 6;
const OURS_RECEIVE: usize = 7;
const THEIRS_TRANSMIT: usize = 8;
const THEIRS_TRANSMIT_ONE_BUSY: usize = 9;
const THEIRS_RECEIVE: usize = 10;

// ------------------------------------------------------------------ the register block

fn reg_read(offset: usize) -> u32 {
    // SAFETY: `REGS + offset` lies in the RAM register block (see `REGS`), aligned.
    unsafe { read_volatile((REGS + offset) as *const u32) }
}

fn reg_write(offset: usize, value: u32) {
    // SAFETY: as `reg_read`; the block is RAM reserved for this stand-in.
    unsafe { write_volatile((REGS + offset) as *mut u32, value) }
}

type Block = [u32; BLOCK_WORDS];

fn save() -> Block {
    let mut b = [0; BLOCK_WORDS];
    for (i, w) in b.iter_mut().enumerate() {
        *w = reg_read(4 * i);
    }
    b
}

fn restore(b: &Block) {
    for (i, w) in b.iter().enumerate() {
        reg_write(4 * i, *w);
    }
}

/// RM0410 reset values (§40.9); mailboxes and filter banks read 0 here.
fn reset_block() {
    restore(&[0; BLOCK_WORDS]);
    reg_write(regs::MCR, mcr::RESET_VALUE);
    reg_write(regs::MSR, msr::RESET_VALUE);
    reg_write(regs::TSR, tsr::RESET_VALUE);
    reg_write(regs::BTR, regs::btr::RESET_VALUE);
    reg_write(regs::FMR, regs::fmr::RESET_VALUE);
}

/// Loads transmit mailbox `x` as pending with a standard frame `id` (8 bytes).
fn pending(b: &mut Block, x: usize, id: u32) {
    b[regs::tixr(x) / 4] = tixr::STID.val(id) | tixr::TXRQ;
    b[regs::tdtxr(x) / 4] = tdtxr::DLC.val(8);
    b[regs::tdlxr(x) / 4] = 0x0403_0201;
    b[regs::tdhxr(x) / 4] = 0x0807_0605;
}

fn tsr_value(empty: &[usize], code: u32) -> u32 {
    empty
        .iter()
        .fold(tsr::CODE.val(code), |v, &x| v | tsr::tme(x))
}

struct Snapshots {
    tx_free: Block,
    tx_one_busy: Block,
    tx_full: Block,
    tx_refill: Block,
    tx_done: Block,
    rx_one: Block,
}

fn snapshots(configured: &Block) -> Snapshots {
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
fn responder_on(syst: &mut SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(2_000);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

fn responder_off(syst: &mut SYST) {
    syst.disable_counter();
    syst.disable_interrupt();
    SCB::clear_pendst();
}

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

// ------------------------------------------------------------------ measuring

fn marker(offset: usize) {
    // SAFETY: the marker window is RAM outside every linker section (memory.x); the
    // store only signals the plugin.
    unsafe { write_volatile((MARKERS + offset) as *mut u32, 0) }
}

/// Runs `f` once between the start and end markers of region `N` (of [`REGIONS`]).
#[inline(always)]
fn measure<const N: usize, T>(f: impl FnOnce() -> T) -> T {
    marker(8 * N);
    compiler_fence(Ordering::SeqCst);
    let r = f();
    compiler_fence(Ordering::SeqCst);
    marker(8 * N + 4);
    r
}

fn fail(what: &str) -> ! {
    hprintln!("FAIL {}", what);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}

fn check(ok: bool, what: &str) {
    if !ok {
        fail(what);
    }
}

type Ours = Driver<Can<Mmio>, 8, 8>;

#[inline(never)]
fn ours_try_send(d: &mut Ours, f: &Frame) -> bool {
    d.try_send(f).is_ok()
}

#[inline(never)]
fn ours_on_interrupt(d: &mut Ours) {
    d.on_interrupt()
}

#[inline(never)]
fn ours_receive(d: &mut Ours) -> Option<twocan_core::RxFrame> {
    d.receive().ok()
}

#[inline(never)]
fn theirs_transmit(c: &mut bxcan::Can<RamCan1>, f: &bxcan::Frame) -> bool {
    c.transmit(f).is_ok()
}

#[inline(never)]
fn theirs_receive(c: &mut bxcan::Can<RamCan1>) -> Option<bxcan::Frame> {
    c.receive().ok()
}

fn loaded(x: usize) -> bool {
    reg_read(regs::tixr(x)) == tixr::STID.val(ID as u32) | tixr::TXRQ
        && reg_read(regs::tdlxr(x)) == 0x6745_2301
        && reg_read(regs::tdhxr(x)) == 0xEFCD_AB89
        && tdtxr::DLC.get(reg_read(regs::tdtxr(x))) == 8
}

fn released() -> bool {
    reg_read(regs::RF0R) & rfxr::RFOM != 0
}

fn configure_ours() -> Ours {
    // SAFETY: `REGS` is the RAM stand-in for CAN1's registers, used by one driver at a time.
    let regs = unsafe { Mmio::new(REGS) };
    let mut init = match Can::can1(regs, &CONFIG) {
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
    match init.enable() {
        Ok(can) => Driver::new(can),
        Err(_) => fail("twocan: enable"),
    }
}

fn run_ours(snap: &Snapshots, d: &mut Ours) {
    let frame = match Frame::standard(ID, &DATA) {
        Ok(f) => f,
        Err(_) => fail("frame"),
    };
    for _ in 0..REPEAT {
        restore(&snap.tx_free);
        let (dd, ff) = (black_box(&mut *d), black_box(&frame));
        let ok = measure::<OURS_SEND_DIRECT, _>(|| ours_try_send(dd, ff));
        check(
            ok && loaded(0) && d.tx_stats().count == 0,
            "twocan try_send direct",
        );

        restore(&snap.tx_one_busy);
        let (dd, ff) = (black_box(&mut *d), black_box(&frame));
        let ok = measure::<OURS_SEND_ONE_BUSY, _>(|| ours_try_send(dd, ff));
        check(
            ok && loaded(1) && d.tx_stats().count == 0,
            "twocan try_send one busy",
        );

        restore(&snap.tx_full);
        let (dd, ff) = (black_box(&mut *d), black_box(&frame));
        let ok = measure::<OURS_SEND_QUEUED, _>(|| ours_try_send(dd, ff));
        check(ok && d.tx_stats().count == 1, "twocan try_send queued");

        restore(&snap.tx_refill);
        let dd = black_box(&mut *d);
        measure::<OURS_IRQ_REFILL, _>(|| ours_on_interrupt(dd));
        check(
            loaded(0) && d.tx_stats().count == 0,
            "twocan on_interrupt refill",
        );

        restore(&snap.tx_done);
        let sent = d.traffic().sent;
        let dd = black_box(&mut *d);
        measure::<OURS_IRQ_TX_DONE, _>(|| ours_on_interrupt(dd));
        check(d.traffic().sent == sent + 1, "twocan on_interrupt tx done");

        restore(&snap.rx_one);
        let dd = black_box(&mut *d);
        measure::<OURS_IRQ_RX, _>(|| ours_on_interrupt(dd));
        check(
            released() && d.rx_stats().count == 1,
            "twocan on_interrupt rx",
        );

        let dd = black_box(&mut *d);
        let rx = measure::<OURS_RECEIVE, _>(|| ours_receive(dd));
        check(
            rx.is_some_and(|r| r.frame == frame) && d.rx_stats().count == 0,
            "twocan receive",
        );
    }
}

/// The RAM stand-in as a `bxcan` instance.
struct RamCan1;

// SAFETY: `REGISTERS` points to the RAM block at `REGS`, laid out as bxCAN's register
// block (0x320 bytes, aligned), used by one driver at a time.
unsafe impl bxcan::Instance for RamCan1 {
    const REGISTERS: *mut bxcan::RegisterBlock = REGS as *mut _;
}

// SAFETY: the stand-in has CAN1's 28 filter banks.
unsafe impl bxcan::FilterOwner for RamCan1 {
    const NUM_FILTER_BANKS: u8 = 28;
}

// SAFETY: the stand-in is CAN1, the master instance.
unsafe impl bxcan::MasterInstance for RamCan1 {}

type Theirs = bxcan::Can<RamCan1>;

fn configure_theirs() -> Theirs {
    let mut can = bxcan::Can::builder(RamCan1)
        .set_bit_timing(BTR)
        .set_loopback(true)
        .leave_disabled();
    can.modify_filters()
        .enable_bank(0, bxcan::Fifo::Fifo0, Mask32::accept_all());
    check(
        nb::block!(can.enable_non_blocking()).is_ok(),
        "bxcan enable",
    );
    can
}

fn run_theirs(snap: &Snapshots, can: &mut Theirs) {
    let id = match bxcan::StandardId::new(ID) {
        Some(id) => id,
        None => fail("bxcan id"),
    };
    let frame = bxcan::Frame::new_data(id, DATA);
    for _ in 0..REPEAT {
        restore(&snap.tx_free);
        let (cc, ff) = (black_box(&mut *can), black_box(&frame));
        let ok = measure::<THEIRS_TRANSMIT, _>(|| theirs_transmit(cc, ff));
        check(ok && loaded(0), "bxcan transmit");

        restore(&snap.tx_one_busy);
        let (cc, ff) = (black_box(&mut *can), black_box(&frame));
        let ok = measure::<THEIRS_TRANSMIT_ONE_BUSY, _>(|| theirs_transmit(cc, ff));
        check(ok && loaded(1), "bxcan transmit one busy");

        restore(&snap.rx_one);
        let cc = black_box(&mut *can);
        let rx = measure::<THEIRS_RECEIVE, _>(|| theirs_receive(cc));
        check(rx.as_ref() == Some(&frame) && released(), "bxcan receive");
    }
}

#[entry]
fn main() -> ! {
    let Some(mut core) = cortex_m::Peripherals::take() else {
        fail("core peripherals");
    };
    hprintln!("window {:#010x}", MARKERS);
    for (n, key) in REGIONS.iter().enumerate() {
        hprintln!("region {} {}", n, key);
    }
    for _ in 0..REPEAT {
        measure::<EMPTY, _>(|| ());
    }

    // Ours: configure with the handshake stand-in, snapshot, measure.
    reset_block();
    responder_on(&mut core.SYST);
    let mut ours = configure_ours();
    responder_off(&mut core.SYST);
    run_ours(&snapshots(&save()), &mut ours);
    // Our driver gives the register block up before the `bxcan` crate takes it.
    let _ = ours.release().release();

    // Theirs: the same from a fresh reset block.
    reset_block();
    responder_on(&mut core.SYST);
    let mut theirs = configure_theirs();
    responder_off(&mut core.SYST);
    run_theirs(&snapshots(&save()), &mut theirs);

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
