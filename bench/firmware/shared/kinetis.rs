//! Teensy 3.6 (MK66FX1M0) start-up shared, byte for byte, by both FlexCAN loop-back
//! firmwares (included with `#[path]` as module `startup`), so that their size
//! difference is the CAN service alone; can-bench leaves this module's code out of the
//! "driver + application" flash figure.
//!
//! - the flash configuration field (K66 RM, FTFE "Flash Configuration Field
//!   Description"): no backdoor key, nothing protected, `FSEC` = 0xFE (unsecured, mass
//!   erase enabled), `FOPT` = 0xF9 (normal boot, EzPort and NMI pin off);
//! - the watchdog off (K66 RM, WDOG "Unlocking and updating the watchdog": the unlock
//!   sequence 0xC520, 0xD928 — the two words within 20 bus clocks — then `STCTRLH`
//!   without `WDOGEN` within the WCT window of 256 bus clocks after reset): so early
//!   that it runs as cortex-m-rt's `__pre_init`, before `.bss` is zeroed, in assembly
//!   (Rust must not run before RAM is initialised);
//! - the 16 MHz crystal oscillator on (MCG `C2`: very high frequency range, crystal;
//!   OSC `CR`: `ERCLKEN`, the load capacitors of PJRC's board), waiting for
//!   `MCG_S.OSCINIT0`: OSCERCLK is FlexCAN's engine clock (`CTRL1.CLKSRC` = 0). The
//!   core stays on the reset FLL clock (FEI, about 21 MHz), above the 16 MHz the
//!   FlexCAN bus clock must not go below.
//!
//! Clock gates and pins of FlexCAN0 belong to the CAN service (our driver's `begin`, the
//! hand-written `system_teensy36`).

/// The flash configuration field (placed at 0x400 by `memory/teensy36.x`).
#[link_section = ".flash_config"]
#[used]
#[no_mangle]
pub static FLASH_CONFIG: [u8; 16] = [
    0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, // backdoor key
    0xFF, 0xFF, 0xFF, 0xFF, // FPROT3..0
    0xFE, // FSEC
    0xF9, // FOPT
    0xFF, // FEPROT
    0xFF, // FDPROT
];

const WDOG_STCTRLH: usize = 0x4005_2000;
const WDOG_UNLOCK: usize = 0x4005_200E;
const MCG_C2: usize = 0x4006_4001;
const MCG_S: usize = 0x4006_4006;
const OSC_CR: usize = 0x4006_5000;

/// `STCTRLH` with `ALLOWUPDATE`, `WDOGEN` clear (the rest at 0).
const STCTRLH_OFF: u16 = 0x0010;
/// `MCG_C2`: `RANGE0` = 0b10 (very high frequency), `EREFS0` (crystal).
const C2_RANGE_VERY_HIGH_CRYSTAL: u8 = (0b10 << 4) | (1 << 2);
/// `OSC_CR`: `ERCLKEN`, `SC8P`, `SC2P` (10 pF of load, as PJRC's start-up).
const CR_ERCLKEN_SC10P: u8 = (1 << 7) | (1 << 1) | (1 << 3);
const S_OSCINIT0: u8 = 1 << 1;
/// Bound of the oscillator wait (register reads).
const WAIT: u32 = 1_000_000;

// The watchdog off, as the first code after reset (module docs). Uses r0 and r1 only,
// which a callee may clobber; two `nop`s give the bus clock the manual asks for between
// the second unlock word and the update.
core::arch::global_asm!(
    ".section .text.__pre_init,\"ax\",%progbits",
    ".global __pre_init",
    ".type __pre_init,%function",
    ".thumb_func",
    "__pre_init:",
    "ldr r0, ={unlock}",
    "movw r1, #{key1}",
    "strh r1, [r0]",
    "movw r1, #{key2}",
    "strh r1, [r0]",
    "nop",
    "nop",
    "ldr r0, ={stctrlh}",
    "movw r1, #{off}",
    "strh r1, [r0]",
    "bx lr",
    ".size __pre_init, . - __pre_init",
    unlock = const WDOG_UNLOCK,
    key1 = const 0xC520,
    key2 = const 0xD928,
    stctrlh = const WDOG_STCTRLH,
    off = const STCTRLH_OFF,
);

/// Crystal oscillator on (the watchdog is off already, `__pre_init`). `Err` if the
/// oscillator never starts.
#[inline(never)]
pub fn init() -> Result<(), ()> {
    // SAFETY: the MCG and OSC registers of the K66 (addresses above), written as the
    // reference manual prescribes, before anything uses the oscillator clock.
    unsafe {
        (OSC_CR as *mut u8).write_volatile(CR_ERCLKEN_SC10P);
        (MCG_C2 as *mut u8).write_volatile(C2_RANGE_VERY_HIGH_CRYSTAL);
        for _ in 0..WAIT {
            if (MCG_S as *const u8).read_volatile() & S_OSCINIT0 != 0 {
                return Ok(());
            }
        }
    }
    Err(())
}
