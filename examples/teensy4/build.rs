//! Link set-up for the Teensy 4 firmware, applied only when cross-building: copies
//! `memory/<board>.x` (as `memory.x`) and `memory/boot.x` to `OUT_DIR`, writes an empty
//! `device.x` (cortex-m-rt's `device` feature includes it; `src/rt.rs` names every
//! handler of `__INTERRUPTS` itself), and passes `-Tlink.x` to the bins only (with
//! `defmt`, also `-Tdefmt.x`). On the host nothing is emitted: the bins are stubs there.

use std::env;
use std::fs;
use std::path::PathBuf;

const BOARDS: [&str; 2] = ["teensy40", "teensy41"];

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=memory");
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let selected: Vec<&str> = BOARDS
        .iter()
        .copied()
        .filter(|b| env::var_os(format!("CARGO_FEATURE_{}", b.to_uppercase())).is_some())
        .collect();
    let board = match selected.as_slice() {
        [one] => *one,
        [] => panic!("twocan-teensy4: choose the board: --features teensy40 or teensy41"),
        many => panic!("twocan-teensy4: several board features selected: {many:?}; choose one"),
    };
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    let memory = manifest.join("memory");
    fs::copy(memory.join(format!("{board}.x")), out.join("memory.x")).expect("memory.x");
    fs::copy(memory.join("boot.x"), out.join("boot.x")).expect("boot.x");
    fs::write(
        out.join("device.x"),
        "/* twocan-teensy4: every device vector is named in src/rt.rs. */\n",
    )
    .expect("device.x");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    if env::var_os("CARGO_FEATURE_DEFMT").is_some() {
        println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    }
}
