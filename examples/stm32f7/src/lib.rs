//! Firmware support and examples for two STM32F7 boards with bxCAN, on `twocan-bxcan`:
//! the NUCLEO-F767ZI (feature `nucleo-f767zi`) and the 32F746G-DISCOVERY (feature
//! `disco-f746g`). Cross-build for `thumbv7em-none-eabihf`; see `docs/firmware.md`.
//!
//! - [`board`]: the board facts (oscillator, CAN pins, LED), plain data;
//! - `rt` (target only): clocks with `stm32f7xx-hal` after a bounded probe of the
//!   external oscillator, the CAN singletons and pins (AF9) for the hand-over of
//!   `twocan_bxcan::hal`, SysTick, the panic handler;
//! - [`can`]: the split driver's state and its interrupt vectors' handles;
//! - [`time`]: the SysTick time base — the very file of `twocan-teensy` (nothing in it
//!   is chip-specific).
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]

#[cfg(all(
    target_os = "none",
    not(any(feature = "nucleo-f767zi", feature = "disco-f746g"))
))]
compile_error!("choose the board: --features nucleo-f767zi or disco-f746g");

#[cfg(all(feature = "nucleo-f767zi", feature = "disco-f746g"))]
compile_error!("choose one board feature only");

// `--features defmt`: the RTT transport of the defmt logger (docs/firmware.md, runners).
#[cfg(all(target_os = "none", feature = "defmt"))]
use defmt_rtt as _;

pub mod board;
pub mod can;
/// The examples' log (`info!`, `warn!`, `error!`): the very file of `twocan-teensy`.
#[path = "../../teensy/src/log.rs"]
pub mod log;
#[cfg(target_os = "none")]
pub mod rt;
#[path = "../../teensy/src/time.rs"]
pub mod time;

pub use board::Board;
#[cfg(any(feature = "nucleo-f767zi", feature = "disco-f746g"))]
pub use board::BOARD;

/// What the host build of a firmware example prints: how to build the real thing.
pub const HOST_NOTE: &str = "this is STM32F7 firmware: cross-build it with \
     `cargo build --release --target thumbv7em-none-eabihf -p twocan-stm32f7 \
     --features nucleo-f767zi --bin <example>` (or disco-f746g), see docs/firmware.md";
