//! What a Kinetis needs beyond cortex-m-rt: the watchdog disabled at the first
//! instruction, the device interrupt vectors, the flash configuration field at 0x400, a
//! SysTick handler and the panic handler. Built only for the target (`target_os = "none"`).
//!
//! The FlexCAN entries of the vector table name the entry points `twocan-flexcan`
//! exports with its `rt` feature (`CAN0_ORED_MESSAGE_BUFFER` ...): the library installs
//! the driver's handlers behind them and enables the lines (`IrqState::start`).

use crate::board::{BOARD, CAN_VECTORS_PER_INSTANCE};
use crate::regs::{
    WDOG_STCTRLH, WDOG_STCTRLH_DISABLED, WDOG_UNLOCK, WDOG_UNLOCK_KEY1, WDOG_UNLOCK_KEY2,
};

// The watchdog is enabled out of reset, and its control registers can only be written
// inside a window after an unlock (WDOG chapter,
// "Unlocking and updating the watchdog"): the two unlock words must be written within
// 20 bus clocks of each other, and the new control value within the WCT window (256 bus
// clocks) that follows. That is why this runs as cortex-m-rt's `__pre_init` — the first
// code after reset, before `.bss`/`.data` are initialised — and why it is assembly:
// cortex-m-rt 0.7.6 deprecated `#[pre_init]` because Rust code must not run before RAM
// is initialised, and recommends a `__pre_init` symbol written with `global_asm!`.
// Between the unlock and the write there are two `nop`s (the manual asks for at least
// one bus clock between the second unlock word and the update) and a literal load: about six core clocks, far inside
// the window. Only r0 and r1 are used, which the AAPCS lets a callee clobber.
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
    "movw r1, #{disabled}",
    "strh r1, [r0]",
    "bx lr",
    ".size __pre_init, . - __pre_init",
    unlock = const WDOG_UNLOCK,
    key1 = const WDOG_UNLOCK_KEY1,
    key2 = const WDOG_UNLOCK_KEY2,
    stctrlh = const WDOG_STCTRLH,
    disabled = const WDOG_STCTRLH_DISABLED,
);

/// The flash configuration field, placed at 0x400 by `memory/flash_config.x`.
#[link_section = ".flash_config"]
#[no_mangle]
#[used]
pub static FLASH_CONFIG: [u8; 16] = crate::flash_config::FLASH_CONFIG_BYTES;

/// One entry of the device part of the vector table. Reserved entries of the vendor
/// tables also get `DefaultHandler`, so no entry needs to be 0.
pub type Vector = unsafe extern "C" fn();

extern "C" {
    // cortex-m-rt's default handler (an infinite loop unless the application defines
    // `DefaultHandler`).
    fn DefaultHandler();
    // The FlexCAN entry points of `twocan_flexcan::rt` (feature `rt`).
    fn CAN0_ORED_MESSAGE_BUFFER();
    fn CAN0_BUS_OFF();
    fn CAN0_ERROR();
    fn CAN0_TX_WARNING();
    fn CAN0_RX_WARNING();
    #[cfg(feature = "teensy36")]
    fn CAN1_ORED_MESSAGE_BUFFER();
    #[cfg(feature = "teensy36")]
    fn CAN1_BUS_OFF();
    #[cfg(feature = "teensy36")]
    fn CAN1_ERROR();
    #[cfg(feature = "teensy36")]
    fn CAN1_TX_WARNING();
    #[cfg(feature = "teensy36")]
    fn CAN1_RX_WARNING();
    // The FlexCAN wake-up vectors, weakly aliased to `DefaultHandler` by the `device.x`
    // build.rs writes (the library never enables them).
    fn CAN0_WAKE_UP();
    #[cfg(feature = "teensy36")]
    fn CAN1_WAKE_UP();
}

const CAN0: [Vector; CAN_VECTORS_PER_INSTANCE] = [
    CAN0_ORED_MESSAGE_BUFFER,
    CAN0_BUS_OFF,
    CAN0_ERROR,
    CAN0_TX_WARNING,
    CAN0_RX_WARNING,
    CAN0_WAKE_UP,
];

#[cfg(feature = "teensy36")]
const CAN1: [Vector; CAN_VECTORS_PER_INSTANCE] = [
    CAN1_ORED_MESSAGE_BUFFER,
    CAN1_BUS_OFF,
    CAN1_ERROR,
    CAN1_TX_WARNING,
    CAN1_RX_WARNING,
    CAN1_WAKE_UP,
];

/// The handlers of each FlexCAN instance of the board, in [`Board::can_instances`]
/// order.
///
/// [`Board::can_instances`]: crate::board::Board::can_instances
const fn handlers() -> &'static [[Vector; CAN_VECTORS_PER_INSTANCE]] {
    #[cfg(feature = "teensy36")]
    {
        &[CAN0, CAN1]
    }
    #[cfg(not(feature = "teensy36"))]
    {
        &[CAN0]
    }
}

/// Every device vector goes to `DefaultHandler` except the FlexCAN ones.
const fn device_vectors() -> [Vector; BOARD.irq_count] {
    let mut table = [DefaultHandler as Vector; BOARD.irq_count];
    let can = handlers();
    let instances = BOARD.can_instances();
    assert!(can.len() == instances.len());
    let mut i = 0;
    while i < can.len() {
        let base = match BOARD.can_irq_base(instances[i]) {
            Some(base) => base as usize,
            None => panic!("a FlexCAN instance without interrupt numbers"),
        };
        let mut j = 0;
        while j < CAN_VECTORS_PER_INSTANCE {
            table[base + j] = can[i][j];
            j += 1;
        }
        i += 1;
    }
    table
}

/// The device interrupt vectors (cortex-m-rt `device` feature: placed right after the 16
/// exception entries, `ORIGIN(FLASH) + 0x40`).
#[link_section = ".vector_table.interrupts"]
#[no_mangle]
pub static __INTERRUPTS: [Vector; BOARD.irq_count] = device_vectors();

#[cortex_m_rt::exception]
fn SysTick() {
    crate::time::tick();
}

/// Blinks `code` short flashes, pauses, forever: how the examples report a fatal error
/// (2–4: clock start-up, see [`crate::clock::ClockError::blink_code`]; 5: CAN start;
/// 6: panic). Interrupts are disabled; the delays are counted in core clocks assuming
/// 16 MHz (after a clock error the core runs at ~21 MHz: a little faster blinking).
pub fn halt(code: u8) -> ! {
    crate::error!("halted: blink code {=u8}", code);
    cortex_m::interrupt::disable();
    // SAFETY: interrupts are off and this never returns, so nothing else uses the LED
    // or port C any more.
    let mut led = crate::led::Led::new(unsafe { crate::io::Mmio::new() });
    let ms = crate::board::CRYSTAL_HZ / 1000;
    loop {
        for _ in 0..code {
            led.on();
            cortex_m::asm::delay(150 * ms);
            led.off();
            cortex_m::asm::delay(250 * ms);
        }
        cortex_m::asm::delay(1200 * ms);
    }
}

/// Blink code of a panic.
pub const PANIC_BLINKS: u8 = 6;

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    halt(PANIC_BLINKS)
}

/// Blink code of a FlexCAN `begin` failure (or a token taken twice).
pub const CAN_BLINKS: u8 = 5;

/// What [`boot`] hands the example.
pub struct Boot {
    /// The Cortex-M core peripherals (SysTick already running).
    pub core: cortex_m::Peripherals,
    /// The clock frequencies.
    pub clocks: crate::clock::Clocks,
    /// The LED on pin 13, off.
    pub led: crate::led::Led<crate::io::Mmio>,
}

/// The common start of every example: clocks (halting with a blink code on error), the
/// SysTick millisecond time base and the LED. Call once, first thing in `main`.
pub fn boot() -> Boot {
    let mut core = cortex_m::Peripherals::take().unwrap_or_else(|| halt(PANIC_BLINKS));
    // SAFETY: first thing in `main`: nothing else uses the clock generator registers.
    let mut sys = unsafe { crate::io::Mmio::new() };
    let clocks = match crate::clock::init(&mut sys, crate::clock::DEFAULT_POLLS) {
        Ok(clocks) => clocks,
        Err(e) => halt(e.blink_code()),
    };
    crate::time::start(&mut core.SYST, clocks.core_hz);
    // SAFETY: the LED pin (PTC5) belongs to this value only; FlexCAN's pins are on other
    // ports or pins and `begin` only read-modify-writes SIM_SCGC5 in a critical section.
    let led = crate::led::Led::new(unsafe { crate::io::Mmio::new() });
    Boot { core, clocks, led }
}
