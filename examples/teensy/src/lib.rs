//! Firmware support and examples for the Teensy 3.2, 3.5 and 3.6 (NXP Kinetis K20, K64,
//! K66 with FlexCAN), on `twocan-flexcan`.
//!
//! Choose the board with one cargo feature (`teensy32`, `teensy35`, `teensy36`) and
//! cross-build for `thumbv7em-none-eabihf`; see `docs/firmware.md` for building, the
//! `.hex` conversion and flashing.
//!
//! What a bare Kinetis needs before `main`, written here (no vendor start-up code):
//! - `rt` (target only): the watchdog disabled by cortex-m-rt's `__pre_init` hook, the device
//!   interrupt vectors (`__INTERRUPTS`) with the FlexCAN ones, the flash configuration
//!   field at 0x400 ([`flash_config`]), the SysTick handler and the panic handler;
//! - [`clock`]: the 16 MHz crystal started and the MCG switched to FBE with bounded
//!   waits; OSCERCLK, FlexCAN's clock, enabled;
//! - [`led`]: pin 13; [`time`]: a SysTick millisecond time base; [`can`]: the split
//!   driver's `static` state type (`twocan_flexcan::rt::IrqState`: the library installs
//!   its interrupt handlers behind its `CAN0_*` entry points, then unmasks the lines).
//!
//! Everything except `rt` is plain code over the [`io::Io`] trait, built and tested on
//! the host as well.
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]

#[cfg(all(
    target_os = "none",
    not(any(feature = "teensy32", feature = "teensy35", feature = "teensy36"))
))]
compile_error!("choose the board: --features teensy32, teensy35 or teensy36");

#[cfg(any(
    all(feature = "teensy32", feature = "teensy35"),
    all(feature = "teensy32", feature = "teensy36"),
    all(feature = "teensy35", feature = "teensy36")
))]
compile_error!("choose one board feature only");

// `--features defmt`: the RTT transport of the defmt logger (`log`, docs/firmware.md).
#[cfg(all(target_os = "none", feature = "defmt"))]
use defmt_rtt as _;

pub mod board;
pub mod can;
pub mod clock;
pub mod configs;
pub mod filters_example;
pub mod flash_config;
pub mod io;
pub mod led;
pub mod log;
pub mod regs;
#[cfg(target_os = "none")]
pub mod rt;
pub mod time;

pub use board::Board;
#[cfg(any(feature = "teensy32", feature = "teensy35", feature = "teensy36"))]
pub use board::BOARD;

/// What the host build of a firmware example prints: how to build the real thing.
pub const HOST_NOTE: &str = "this is Teensy firmware: cross-build it with \
     `cargo build --release --target thumbv7em-none-eabihf -p twocan-teensy \
     --features teensy36 --bin <example>` (or teensy32 / teensy35), see docs/firmware.md";
