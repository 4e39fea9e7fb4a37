//! What every instruction-count firmware under QEMU (mps2-an386) shares, included with
//! `#[path]`: the marker stores the counting plugin (`bench/plugin/insn_count.c`) listens
//! to, the stack painting that gives the stack high-water marks, the lines can-bench
//! reads from the semihosting console, and the fault and panic handlers that fail a run.
//!
//! # Console lines (read by `bench/src/qemu.rs`)
//!
//! - `window <address>`: the marker window;
//! - `region <n> <key>`: the name of marker region `n`;
//! - `stack <key> <bytes>`: a stack high-water mark (see [`stack_depth`]);
//! - `roundtrip <name> <key> <key> ...`: the regions a round trip sums (the firmware
//!   says which handlers its configuration runs per frame);
//! - `note <key> <value>`: a fact of the run (how deep an interrupt went);
//! - `variant <name>`: the build's variant (`lean`, `full`);
//! - `done` at the end, `FAIL <what>` when a check failed.
//!
//! # Stack painting
//!
//! [`stack_depth`] fills the [`PAINT_BYTES`] below the stack pointer with [`PATTERN`]
//! (one inline-assembly loop that pushes nothing, so the words right below the stack
//! pointer are painted too), runs the measured call, and then scans upwards from the
//! bottom of the painted window for the first word that no longer holds the pattern:
//! the bytes from that word up to the stack pointer at the call are the call's stack
//! high-water mark — its frame, the frames of everything it called, and whatever an
//! exception pushed meanwhile. A call that reserves stack without writing it is not
//! seen (painting measures what is written); a call that runs out of the painted
//! window fails the run.

// Each firmware that includes this module uses a part of it.
#![allow(dead_code)]

use core::arch::asm;
use core::ptr::{read_volatile, write_volatile};
use core::sync::atomic::{compiler_fence, AtomicU32, Ordering};

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::{SCB, SYST};
use cortex_m_rt::{exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hprint, hprintln};

/// The plugin's marker window: start of region `n` at `+ 8n`, end at `+ 8n + 4`. Above
/// the 1 MiB of RAM the linker uses (`memory/mps2-an386.x`) and above the register
/// stand-ins, outside every section.
pub const MARKERS: usize = 0x2011_0000;

/// The marker window's address, read from the ELF by can-bench and handed to the plugin.
#[no_mangle]
#[used]
static BENCH_MARKER_WINDOW: u32 = MARKERS as u32;

/// Measurements of each region.
pub const REPEAT: usize = 5;

/// The word the stack is painted with before a measured call.
pub const PATTERN: u32 = 0xA5C3_5AE1;

/// Bytes painted below the stack pointer (more than any measured call uses: a call that
/// reaches the bottom fails the run).
pub const PAINT_BYTES: u32 = 256 * 1024;

fn marker(offset: usize) {
    // SAFETY: the marker window is RAM outside every linker section (memory.x); the
    // store only signals the plugin.
    unsafe { write_volatile((MARKERS + offset) as *mut u32, 0) }
}

/// Runs `f` once between the start and end markers of region `N` (of the firmware's
/// region list).
#[inline(always)]
pub fn measure<const N: usize, T>(f: impl FnOnce() -> T) -> T {
    marker(8 * N);
    compiler_fence(Ordering::SeqCst);
    let r = f();
    compiler_fence(Ordering::SeqCst);
    marker(8 * N + 4);
    r
}

/// Runs `f` with the [`PAINT_BYTES`] below the stack pointer painted; returns its
/// result, the bytes below the stack pointer (at the call) that it overwrote, and that
/// stack pointer.
#[inline(always)]
pub fn stack_depth<T>(f: impl FnOnce() -> T) -> (T, u32, u32) {
    let top: u32;
    // SAFETY: the words below the stack pointer are free (nothing lives there between
    // calls; exceptions that would push there are off or only push their frame); the
    // loop uses registers only and stays within the RAM below the stack pointer, which
    // `memory/mps2-an386.x` leaves to the stack (1 MiB minus the statics).
    unsafe {
        asm!(
            "mov {top}, sp",
            "sub {p}, {top}, {n}",
            "2:",
            "str {pat}, [{p}], #4",
            "cmp {p}, {top}",
            "blo 2b",
            top = out(reg) top,
            p = out(reg) _,
            n = in(reg) PAINT_BYTES,
            pat = in(reg) PATTERN,
            options(nostack),
        );
    }
    compiler_fence(Ordering::SeqCst);
    let r = f();
    compiler_fence(Ordering::SeqCst);
    let bottom = top - PAINT_BYTES;
    let mut a = bottom;
    // SAFETY: the painted window, RAM below `top`; reads only.
    while a < top && unsafe { read_volatile(a as *const u32) } == PATTERN {
        a += 4;
    }
    if a == bottom {
        fail("stack: the measured call used the whole painted window");
    }
    (r, top - a, top)
}

/// Exception frames a mode-handshake stand-in pushed during a configuration: word 0
/// counts the distinct frame addresses, words 1.. hold them (written by the stand-ins'
/// SysTick handlers, `ram_can.rs` and `ram_flexcan.rs`, in assembly).
pub static IRQ_FRAMES: [AtomicU32; 1 + MAX_IRQ_FRAMES] =
    [const { AtomicU32::new(0) }; 1 + MAX_IRQ_FRAMES];

/// Distinct exception frame addresses [`IRQ_FRAMES`] holds.
pub const MAX_IRQ_FRAMES: usize = 128;

/// Bytes of the basic exception frame (ARMv7-M B1.5.6: R0–R3, R12, LR, PC, xPSR); the
/// stand-ins turn FP context stacking off, so their frames have no FP part.
pub const FRAME_BYTES: u32 = 32;

/// Like [`stack_depth`] for a configuration during which a mode-handshake stand-in's
/// SysTick interrupts push their exception frames on the measured stack: returns the
/// result and two figures, `(low, high)`. `high` is the painted figure, the frames
/// included: an upper bound of the configuration's own need. `low` is a lower bound:
/// the larger of the deepest word written outside the recorded frames and the deepest
/// stack pointer an interrupt found (each frame lies right below the stack pointer it
/// interrupted, with at most one word of alignment padding). Where no frame is the
/// deepest word, the two are equal; where more distinct frames came than
/// [`MAX_IRQ_FRAMES`] records, `low` is given as `high`.
#[inline(always)]
pub fn config_stack_depth<T>(f: impl FnOnce() -> T) -> (T, u32, u32) {
    for w in &IRQ_FRAMES {
        w.store(0, Ordering::Relaxed);
    }
    let (r, high, top) = stack_depth(f);
    let n = IRQ_FRAMES[0].load(Ordering::Relaxed) as usize;
    if n > MAX_IRQ_FRAMES {
        // Not every frame was recorded: no lower bound.
        return (r, high, high);
    }
    let frames = &IRQ_FRAMES[1..=n];
    let in_frame = |a: u32| {
        frames.iter().any(|b| {
            let b = b.load(Ordering::Relaxed);
            a >= b && a < b + FRAME_BYTES
        })
    };
    let mut a = top - PAINT_BYTES;
    // SAFETY: the painted window, RAM below `top`; reads only.
    while a < top && (in_frame(a) || unsafe { read_volatile(a as *const u32) } == PATTERN) {
        a += 4;
    }
    let outside = top - a;
    let interrupted = frames
        .iter()
        .map(|b| b.load(Ordering::Relaxed) + FRAME_BYTES + 4)
        .filter(|&sp| sp <= top)
        .map(|sp| top - sp)
        .max()
        .unwrap_or(0);
    (r, outside.max(interrupted).min(high), high)
}

/// `FPCCR` (ARMv7-M B3.2.23): `ASPEN` (bit 31) and `LSPEN` (bit 30).
const FPCCR: usize = 0xE000_EF34;
const FPCCR_ASPEN_LSPEN: u32 = 0b11 << 30;

/// Starts the SysTick handler of a register stand-in that acknowledges mode requests
/// (configuration only; the handler is the stand-in's `SysTick`). Automatic FP context
/// stacking is turned off meanwhile (the handler uses no FP register), so each of its
/// interrupts pushes the [`FRAME_BYTES`] basic frame only.
pub fn responder_on(syst: &mut SYST) {
    // SAFETY: FPCCR is the core's FP context control register; with ASPEN and LSPEN
    // clear no FP state is stacked, which is sound because the one handler that runs
    // meanwhile (the stand-in's SysTick) touches no FP register.
    unsafe {
        let v = read_volatile(FPCCR as *const u32);
        write_volatile(FPCCR as *mut u32, v & !FPCCR_ASPEN_LSPEN);
    }
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(2_000);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// Stops the handshake stand-in (before anything is measured).
pub fn responder_off(syst: &mut SYST) {
    syst.disable_counter();
    syst.disable_interrupt();
    SCB::clear_pendst();
    // SAFETY: as in `responder_on`: back to the reset value's automatic lazy stacking.
    unsafe {
        let v = read_volatile(FPCCR as *const u32);
        write_volatile(FPCCR as *mut u32, v | FPCCR_ASPEN_LSPEN);
    }
}

/// The tail of the stand-ins' SysTick handlers, reached by a branch with the stack
/// pointer at the exception frame: records the frame's address in [`IRQ_FRAMES`] (once
/// per distinct address; past [`MAX_IRQ_FRAMES`] the count goes on growing, which
/// [`config_stack_depth`] sees) and returns from the exception. Uses R0–R3 and R12
/// only (stacked by the exception entry) and pushes nothing.
///
/// # Safety
/// Only as the last instruction of a stand-in's SysTick handler (a `b`, not a call).
#[unsafe(naked)]
pub unsafe extern "C" fn record_irq_frame() {
    core::arch::naked_asm!(
        "mov r1, sp",
        "ldr r0, ={frames}",
        "ldr r2, [r0]",
        "movs r3, #0",
        "2:",
        "cmp r3, r2",
        "bhs 3f",
        "add r12, r0, r3, lsl #2",
        "ldr r12, [r12, #4]",
        "cmp r12, r1",
        "beq 4f",
        "adds r3, r3, #1",
        "b 2b",
        "3:",
        "cmp r2, #{max}",
        "bhs 5f",
        "add r3, r0, r2, lsl #2",
        "str r1, [r3, #4]",
        "5:",
        "adds r2, r2, #1",
        "str r2, [r0]",
        "4:",
        "bx lr",
        frames = sym IRQ_FRAMES,
        max = const MAX_IRQ_FRAMES,
    );
}

/// Prints a stack high-water mark (`stack <key> <bytes>`).
pub fn report_stack(key: &str, bytes: u32) {
    hprintln!("stack {} {}", key, bytes);
}

/// Prints the regions a round trip sums (`roundtrip <name> <keys...>`).
pub fn report_roundtrip(name: &str, keys: &[&str]) {
    hprint!("roundtrip {}", name);
    for k in keys {
        hprint!(" {}", k);
    }
    hprintln!();
}

/// Prints a fact of the run (`note <key><suffix> <value>`).
pub fn note(key: &str, suffix: &str, value: u32) {
    hprintln!("note {}{} {}", key, suffix, value);
}

/// Prints the build's variant (`variant <name>`).
pub fn variant(name: &str) {
    hprintln!("variant {}", name);
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

/// Prints the marker window and the region names (`region <n> <key>`).
pub fn announce(regions: &[&str]) {
    hprintln!("window {:#010x}", MARKERS);
    hprintln!("note stack.painted_bytes {}", PAINT_BYTES);
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

/// A split driver state's [`twocan_core::split::Footprint`] as the words can-bench reads
/// from a `BENCH_FOOTPRINT` static, in this order: total, controller, receive slots,
/// transmit slots, completion slots, state-change slots, ring bookkeeping, queue
/// bookkeeping, clock, statistics, errors, wakers, padding.
pub const fn footprint_words(f: twocan_core::split::Footprint) -> [u32; 13] {
    [
        f.total as u32,
        f.controller as u32,
        f.receive_slots as u32,
        f.transmit_slots as u32,
        f.completion_slots as u32,
        f.state_change_slots as u32,
        f.ring_bookkeeping as u32,
        f.queue_bookkeeping as u32,
        f.clock as u32,
        f.statistics as u32,
        f.errors as u32,
        f.wakers as u32,
        f.padding as u32,
    ]
}
