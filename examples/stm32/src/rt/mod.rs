//! Target-only start-up, the same interface on both families: [`boot`] (clocks with the
//! board's HAL, SysTick, LED, the CAN singletons and pins), the part's CAN interrupt
//! lines, [`halt`] and the panic handler. The family module (`f1.rs` for the Blue Pill,
//! `f4.rs` for the NUCLEO-F446RE) holds what the HALs do differently; everything the
//! examples see is named the same in both.
//!
//! **The HAL hand-over.** The program reaches the CAN registers only through the
//! library's hand-over from the board's HAL (`twocan_bxcan::hal::f1`, `hal::f4`):
//! [`boot`] keeps the PAC singletons, the pins in their CAN function and the HAL's RCC in
//! `CanParts`, and `CanParts::can1` (both boards) or `CanParts::dual` (the F446's CAN1 +
//! CAN2) gives them **by value** to the hand-over, which enables and resets the clocks
//! and returns a handle whose `config` solves the bit timing from the HAL's APB1 clock
//! and whose `configure` puts the controller in initialization mode. On the F103 the
//! USB singleton goes with the CAN's: CAN and USB share their SRAM (RM0008 §24.2). No
//! `unsafe` here but the halt path's LED.

#[cfg(feature = "bluepill")]
mod f1;
#[cfg(feature = "bluepill")]
pub use f1::*;
#[cfg(feature = "nucleo-f446re")]
mod f4;
#[cfg(feature = "nucleo-f446re")]
pub use f4::*;

/// Blink code of a bxCAN configuration failure.
pub const CAN_BLINKS: u8 = 5;
/// Blink code of a panic.
pub const PANIC_BLINKS: u8 = 6;

/// Reads of `RCC_CR` allowed for the HSE to become ready: at the 8/16 MHz HSI of reset
/// and a few cycles per read, tens of milliseconds; HSE start-up is 2 ms typical (data
/// sheets' `t_SU(HSE)`).
pub const HSE_POLLS: u32 = 200_000;

/// Priority of the CAN interrupt lines: one for all (0, the highest, as after reset).
pub const CAN_PRIORITY: u8 = 0;

#[cortex_m_rt::exception]
fn SysTick() {
    crate::time::tick();
}

/// Blinks `code` short flashes, pauses, forever: how the examples report a fatal error
/// (5: bxCAN configuration, 6: panic). Interrupts are disabled; delays assume the clock
/// after reset (8 MHz HSI on the F1, 16 MHz on the F4) and run faster on the PLL.
pub fn halt(code: u8) -> ! {
    crate::error!("halted: blink code {=u8}", code);
    cortex_m::interrupt::disable();
    let ms = 8_000;
    loop {
        for _ in 0..code {
            led_raw(true);
            cortex_m::asm::delay(150 * ms);
            led_raw(false);
            cortex_m::asm::delay(250 * ms);
        }
        cortex_m::asm::delay(1200 * ms);
    }
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    halt(PANIC_BLINKS)
}

/// The `#[interrupt]` handlers of one instance under the part's vector names, each one
/// call of `twocan_bxcan::rt::dispatch` (used by the family's `can1_vectors!` and
/// `can2_vectors!`).
#[doc(hidden)]
#[macro_export]
macro_rules! __can_vectors {
    ($module:ident, $instance:ident: $tx:ident, $rx0:ident, $rx1:ident, $sce:ident) => {
        mod $module {
            use $crate::__private::{dispatch, Instance, Line};
            use $crate::rt::pac::interrupt;
            #[interrupt]
            fn $tx() {
                let _ = dispatch(Instance::$instance, Line::Tx);
            }
            #[interrupt]
            fn $rx0() {
                let _ = dispatch(Instance::$instance, Line::Rx0);
            }
            #[interrupt]
            fn $rx1() {
                let _ = dispatch(Instance::$instance, Line::Rx1);
            }
            #[interrupt]
            fn $sce() {
                let _ = dispatch(Instance::$instance, Line::Sce);
            }
        }
    };
}
