//! What the RT1062 needs beyond cortex-m-rt: the device interrupt vectors (160, with the
//! library's `CAN1`, `CAN2`, `CAN3` entry points at 36, 37 and 154: IMXRT1060RM, "ARM
//! Cortex M7 domain interrupt summary"), the SysTick time base, the panic handler and
//! `halt`. Built only for the target.

use core::sync::atomic::{AtomicU32, Ordering};

use twocan_flexcan::imxrt::{CAN1_IRQ, CAN2_IRQ, CAN3_IRQ};

/// Number of device interrupt vectors of the RT1062's Cortex-M7.
pub const IRQ_COUNT: usize = 160;

/// A device vector.
pub type Vector = unsafe extern "C" fn();

extern "C" {
    // cortex-m-rt's default handler.
    fn DefaultHandler();
}

const fn device_vectors() -> [Vector; IRQ_COUNT] {
    let mut table = [DefaultHandler as Vector; IRQ_COUNT];
    table[CAN1_IRQ as usize] = twocan_flexcan::rt_imxrt::can1 as Vector;
    table[CAN2_IRQ as usize] = twocan_flexcan::rt_imxrt::can2 as Vector;
    table[CAN3_IRQ as usize] = twocan_flexcan::rt_imxrt::can3 as Vector;
    table
}

/// The device vectors cortex-m-rt's `device` feature places after the exceptions.
#[link_section = ".vector_table.interrupts"]
#[no_mangle]
pub static __INTERRUPTS: [Vector; IRQ_COUNT] = device_vectors();

#[cortex_m_rt::exception]
fn SysTick() {
    crate::time::tick();
}

/// SysTick's external reference on the RT1062: 100 kHz (the 24 MHz oscillator ÷ 240;
/// IMXRT1060RM, "ARM Cortex-M7 Platform", SysTick).
pub const SYSTICK_EXTERNAL_HZ: u32 = 100_000;

/// Starts the 1 ms SysTick from its external reference (independent of the core clock
/// the boot ROM chose).
pub fn start_systick(syst: &mut cortex_m::peripheral::SYST) {
    use cortex_m::peripheral::syst::SystClkSource;
    syst.set_clock_source(SystClkSource::External);
    syst.set_reload(SYSTICK_EXTERNAL_HZ / 1000 - 1);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// Why the firmware stopped (0 while running): [`CAN_HALT`] or [`PANIC_HALT`], for a
/// debugger or `can-fil` (the Teensy 4 has no LED blink codes here: the LED pad is left
/// alone).
pub static HALT: AtomicU32 = AtomicU32::new(0);

/// Halt code: FlexCAN `begin` or `start` failed.
pub const CAN_HALT: u32 = 5;
/// Halt code: panic.
pub const PANIC_HALT: u32 = 6;

/// Stops: records `code` in [`HALT`] and sleeps with interrupts off.
pub fn halt(code: u32) -> ! {
    crate::error!("halted: code {=u32}", code);
    cortex_m::interrupt::disable();
    HALT.store(code, Ordering::Relaxed);
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    halt(PANIC_HALT)
}

/// What `main` gets: the core peripherals, SysTick running.
pub struct Boot {
    /// The Cortex-M7 core peripherals.
    pub core: cortex_m::Peripherals,
}

/// The start of every example: the core peripherals taken, the 1 ms SysTick started.
pub fn boot() -> Boot {
    let mut core = cortex_m::Peripherals::take().unwrap_or_else(|| halt(PANIC_HALT));
    start_systick(&mut core.SYST);
    Boot { core }
}
