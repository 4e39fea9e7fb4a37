//! Target-only start-up, the same interface on both families: [`boot`] (clocks with the
//! board's HAL, SysTick, LED, the CAN singletons consumed into their register windows),
//! the part's CAN interrupt lines, [`halt`] and the panic handler. The family module
//! (`f1.rs` for the Blue Pill, `f4.rs` for the NUCLEO-F446RE) holds what the HALs do
//! differently; everything the examples see is named the same in both.
//!
//! **Register windows.** The program gets the CAN registers only through [`Can1`] and
//! `Can2`, which hold the PAC singletons [`boot`] took (on the F103 the USB singleton
//! too: CAN and USB share their SRAM, RM0008 §24.2, so the USB peripheral is kept out of
//! the program's reach while CAN runs). Turning a singleton into the bounded window of
//! `twocan_bxcan::regs` is this module's one `unsafe` per instance, at the register
//! boundary; the base addresses are the part's, from `twocan_bxcan::chip`.

#[cfg(feature = "bluepill")]
mod f1;
#[cfg(feature = "bluepill")]
pub use f1::*;
#[cfg(feature = "nucleo-f446re")]
mod f4;
#[cfg(feature = "nucleo-f446re")]
pub use f4::*;

use twocan_bxcan::regs::{CanRegs, Instance};

use crate::board::BOARD;

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

/// The base address of `instance` on the board's part (`twocan_bxcan::chip`).
fn base(instance: Instance) -> usize {
    match BOARD.chip.instance(instance) {
        Some(c) => c.base as usize,
        None => halt(CAN_BLINKS),
    }
}

/// CAN1 (the F103's `CAN`) handed over by [`boot`]: its PAC singleton (and, on the F103,
/// USB's) and its pins, in their CAN function.
pub struct Can1 {
    _parts: Can1Parts,
}

impl Can1 {
    /// CAN1's whole register block (filters included): CAN1 alone.
    pub fn whole(self) -> CanRegs {
        // SAFETY: the block of CAN1 at the part's base address (`twocan_bxcan::chip`,
        // RM0008 §3.3 / RM0390 §2.3); its PAC singleton was taken by `boot` and is
        // consumed here with this value, so no other handle to these registers exists.
        unsafe { CanRegs::new(base(Instance::Can1)) }
    }
}

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
