//! Link set-up for the STM32F7 firmware, applied only when cross-building: checks that
//! exactly one board feature is on and passes `-Tlink.x` to the bins only
//! (`rustc-link-arg-bins`), so the library and the rest of the workspace are unaffected.
//! `memory.x` comes from stm32f7xx-hal's build script, chosen by the chip feature the
//! board feature turns on (F767: 2 MiB flash, 384 KiB SRAM1+2 + 128 KiB DTCM; F746:
//! 1 MiB flash, 320 KiB RAM); `device.x` and `__INTERRUPTS` from the `stm32f7` PAC.

use std::env;

const BOARDS: [&str; 2] = ["nucleo-f767zi", "disco-f746g"];

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let selected: Vec<&str> = BOARDS
        .iter()
        .copied()
        .filter(|b| {
            let var = format!("CARGO_FEATURE_{}", b.to_uppercase().replace('-', "_"));
            env::var_os(var).is_some()
        })
        .collect();
    match selected.as_slice() {
        [_] => {}
        [] => panic!(
            "twocan-stm32f7: choose the board with one feature: --features nucleo-f767zi \
             or disco-f746g"
        ),
        many => panic!("twocan-stm32f7: several board features selected: {many:?}; choose one"),
    }
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    // defmt's linker script: its interned strings go to the `.defmt` section of the ELF,
    // which probe-rs reads to decode the RTT output.
    if env::var_os("CARGO_FEATURE_DEFMT").is_some() {
        println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    }
}
