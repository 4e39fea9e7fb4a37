//! Firmware support and examples for the Teensy 4.0 and 4.1 (NXP i.MX RT1062, FlexCAN
//! CAN1, CAN2, CAN3) on `twocan-flexcan` (features `teensy40` / `teensy41`).
//!
//! What the RT1062 needs before `main`, written here (no vendor start-up code):
//! - the boot header the ROM reads from the start of the flash ([`boot`] and
//!   `memory/boot.x`): FlexSPI NOR configuration block, image vector table, boot data;
//! - `rt` (target only): the device vector table with the library's `CAN1`, `CAN2` and
//!   `CAN3` entry points, SysTick on its 100 kHz external reference, the panic handler.
//!   cortex-m-rt's reset handler initialises `.data`/`.bss` in the DTCM and (feature
//!   `set-vtor`) moves VTOR to this image's table.
//!
//! The clocks stay as the boot ROM leaves them (core on PLL2 PFD2); the CAN clock root is
//! set by `begin` (the 24 MHz oscillator, [`configs`]). Every example runs its modules in
//! the RT1062 message-buffer layout (`twocan_flexcan::layout::Imxrt1062`: the ERR005829
//! workaround; [`can`]). The portable application, the filter example's lists, the time
//! base and the log are the Teensy 3 examples' modules, included, not copied.
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]

#[cfg(all(
    target_os = "none",
    not(any(feature = "teensy40", feature = "teensy41"))
))]
compile_error!("choose the board: --features teensy40 or teensy41");

#[cfg(all(feature = "teensy40", feature = "teensy41"))]
compile_error!("choose one board feature only");

#[cfg(all(target_os = "none", feature = "defmt"))]
use defmt_rtt as _;

pub mod boot;
pub mod can;
pub mod configs;
#[path = "../../teensy/src/filters_example.rs"]
pub mod filters_example;
#[path = "../../teensy/src/log.rs"]
pub mod log;
#[cfg(target_os = "none")]
pub mod rt;
#[path = "../../teensy/src/time.rs"]
pub mod time;

/// What the host build of a firmware example prints: how to build the real thing.
pub const HOST_NOTE: &str = "this is Teensy 4 firmware: cross-build it with \
     `cargo build --release --target thumbv7em-none-eabihf -p twocan-teensy4 \
     --features teensy41 --bin <example>` (or teensy40), see docs/firmware.md";
