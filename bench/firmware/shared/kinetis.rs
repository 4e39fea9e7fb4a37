//! Teensy 3.6 (MK66FX1M0) start-up shared, byte for byte, by both FlexCAN loop-back
//! firmwares (included with `#[path]` as module `startup`), so that their size
//! difference is the CAN service alone; can-bench leaves this module's code out of the
//! "driver + application" flash figure.
//!
//! - the flash configuration field (K66 RM, FTFE "Flash Configuration Field
//!   Description"): no backdoor key, nothing protected, `FSEC` = 0xFE (unsecured, mass
//!   erase enabled), `FOPT` = 0xF9 (normal boot, EzPort and NMI pin off);
//! - the watchdog off (K66 RM, WDOG "Unlocking and updating the watchdog": the unlock
//!   sequence 0xC520, 0xD928, then `STCTRLH` without `WDOGEN`, within the allowed
//!   window after reset);
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

/// `STCTRLH` with `ALLOWUPDATE` and the reset defaults, `WDOGEN` clear.
const STCTRLH_OFF: u16 = 0x0010;
/// `MCG_C2`: `RANGE0` = 0b10 (very high frequency), `EREFS0` (crystal).
const C2_RANGE_VERY_HIGH_CRYSTAL: u8 = (0b10 << 4) | (1 << 2);
/// `OSC_CR`: `ERCLKEN`, `SC8P`, `SC2P` (10 pF of load, as PJRC's start-up).
const CR_ERCLKEN_SC10P: u8 = (1 << 7) | (1 << 1) | (1 << 3);
const S_OSCINIT0: u8 = 1 << 1;
/// Bound of the oscillator wait (register reads).
const WAIT: u32 = 1_000_000;

/// Watchdog off, crystal oscillator on. `Err` if the oscillator never starts.
#[inline(never)]
pub fn init() -> Result<(), ()> {
    // SAFETY: the WDOG, MCG and OSC registers of the K66 (addresses above), written as
    // the reference manual prescribes, before anything else runs.
    unsafe {
        (WDOG_UNLOCK as *mut u16).write_volatile(0xC520);
        (WDOG_UNLOCK as *mut u16).write_volatile(0xD928);
        (WDOG_STCTRLH as *mut u16).write_volatile(STCTRLH_OFF);
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
