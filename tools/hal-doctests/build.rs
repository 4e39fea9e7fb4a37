//! Points `src/lib.rs` at the example to compile: the file named by `TWOCAN_HAL_DOCTEST`
//! (written by `run.sh`), or an empty one.

use std::env;
use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-env-changed=TWOCAN_HAL_DOCTEST");
    let file = match env::var_os("TWOCAN_HAL_DOCTEST") {
        Some(path) => PathBuf::from(path),
        None => {
            let empty = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR")).join("none.rs");
            std::fs::write(&empty, "").expect("none.rs");
            empty
        }
    };
    println!("cargo:rerun-if-changed={}", file.display());
    println!("cargo:rustc-env=TWOCAN_HAL_DOCTEST_FILE={}", file.display());
}
