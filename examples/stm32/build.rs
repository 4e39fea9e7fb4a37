//! Link set-up for the STM32 firmware, applied only when cross-building: checks that
//! exactly one board feature is on, writes the board's `memory.x` (the HALs of these
//! families ship none) and passes `-Tlink.x` to the bins only (`rustc-link-arg-bins`).
//! `device.x` and `__INTERRUPTS` come from the PAC (`rt` feature).
//!
//! Memory: STM32F103C8 64 KiB flash at 0x0800_0000, 20 KiB SRAM at 0x2000_0000 (RM0008
//! §3.3, DS5319); STM32F446RE 512 KiB flash, 128 KiB SRAM (RM0390 §2.3, DS10693).

use std::env;
use std::path::PathBuf;

/// (feature, flash KiB, RAM KiB).
const BOARDS: [(&str, u32, u32); 2] = [("bluepill", 64, 20), ("nucleo-f446re", 512, 128)];

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let selected: Vec<_> = BOARDS
        .iter()
        .filter(|(b, _, _)| {
            let var = format!("CARGO_FEATURE_{}", b.to_uppercase().replace('-', "_"));
            env::var_os(var).is_some()
        })
        .collect();
    let (name, flash, ram) = match selected.as_slice() {
        [one] => **one,
        [] => panic!(
            "twocan-stm32: choose the board with one feature: --features bluepill or nucleo-f446re"
        ),
        many => panic!("twocan-stm32: several board features selected: {many:?}; choose one"),
    };
    let target = env::var("TARGET").unwrap_or_default();
    let want = if name == "bluepill" {
        "thumbv7m-none-eabi"
    } else {
        "thumbv7em-none-eabihf"
    };
    if target != want {
        panic!("twocan-stm32: the {name} firmware builds for --target {want} (not {target})");
    }
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    std::fs::write(
        out.join("memory.x"),
        format!(
            "MEMORY\n{{\n  FLASH : ORIGIN = 0x08000000, LENGTH = {flash}K\n  RAM : ORIGIN = 0x20000000, LENGTH = {ram}K\n}}\n"
        ),
    )
    .expect("memory.x");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    if env::var_os("CARGO_FEATURE_DEFMT").is_some() {
        println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    }
}
