//! Firmware support and examples for two bxCAN boards of the STM32 family, on
//! `twocan-bxcan`, from one source: the Blue Pill (STM32F103C8, Cortex-M3, feature
//! `bluepill`, target `thumbv7m-none-eabi`) and the NUCLEO-F446RE (STM32F446RE,
//! Cortex-M4F, feature `nucleo-f446re`, target `thumbv7em-none-eabihf`). See
//! `docs/firmware.md`.
//!
//! What differs between the boards is data or one family module, never a copy of an
//! example:
//!
//! - [`board`]: the board facts (the part's [`twocan_bxcan::chip::Chip`], oscillator,
//!   clocks, CAN pins, LED), plain data;
//! - `rt` (target only): one module per family (`rt/f1.rs`, `rt/f4.rs`) with the same
//!   interface: clocks with the board's HAL after a bounded probe of the external
//!   oscillator, the CAN singletons and pins given to the library's HAL hand-over
//!   (`twocan_bxcan::hal::f1`, `hal::f4`: no `unsafe` in the CAN set-up), SysTick, LED,
//!   halt; the CAN interrupt lines of the part;
//! - [`can`]: the split driver's state and interrupt handlers (the library's
//!   `twocan_bxcan::rt::IrqState`, as in `twocan-stm32f7`), started on the part's lines;
//! - [`time`], `log`: the very files of `twocan-teensy`;
//! - the `can1_vectors!` / `can2_vectors!` macros: the four CAN vectors of the part
//!   (their names differ: `USB_HP_CAN_TX` on the F103, `CAN1_TX` on the F446), each one
//!   call of `twocan_bxcan::rt::dispatch` with its instance and line.
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]

#[cfg(all(
    target_os = "none",
    not(any(feature = "bluepill", feature = "nucleo-f446re"))
))]
compile_error!("choose the board: --features bluepill or nucleo-f446re");

#[cfg(all(feature = "bluepill", feature = "nucleo-f446re"))]
compile_error!("choose one board feature only");

// `--features defmt`: the RTT transport of the defmt logger.
#[cfg(all(target_os = "none", feature = "defmt"))]
use defmt_rtt as _;

pub mod board;
pub mod can;
/// The examples' log (`info!`, `warn!`, `error!`): the very file of `twocan-teensy`.
#[path = "../../teensy/src/log.rs"]
pub mod log;
#[cfg(target_os = "none")]
pub mod rt;
// The SysTick time base: the very file of `twocan-teensy`.
#[path = "../../teensy/src/time.rs"]
pub mod time;

pub use board::Board;

/// What the vector macros name through `$crate` (not an API).
#[doc(hidden)]
#[cfg(target_os = "none")]
pub mod __private {
    pub use twocan_bxcan::regs::Instance;
    pub use twocan_bxcan::rt::{dispatch, Line};
}
#[cfg(any(feature = "bluepill", feature = "nucleo-f446re"))]
pub use board::BOARD;

/// What the host build of a firmware example prints: how to build the real thing.
pub const HOST_NOTE: &str = "this is STM32 firmware: cross-build it with \
     `cargo build --release --target thumbv7m-none-eabi -p twocan-stm32 --features bluepill \
     --bin <example>` (or `--target thumbv7em-none-eabihf --features nucleo-f446re`), see \
     docs/firmware.md";
