//! Each bin gets the linker script of its chip (flash at 0 for the Kinetis, at 0x0800_0000
//! for the STM32F7, STM32F103C8 and STM32F446RE, a FlexSPI boot image at 0x6000_0000 for
//! the i.MX RT1062); nothing is linked for a host build.
use std::env;
use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=kinetis.ld");
    println!("cargo:rerun-if-changed=stm32f7.ld");
    println!("cargo:rerun-if-changed=stm32f103c8.ld");
    println!("cargo:rerun-if-changed=stm32f446re.ld");
    println!("cargo:rerun-if-changed=imxrt1062.ld");
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let dir = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("manifest dir"));
    for (bin, script) in [
        ("kinetis-gate", "kinetis.ld"),
        ("kinetis-stuck", "kinetis.ld"),
        ("kinetis-no-wdog", "kinetis.ld"),
        ("kinetis-storm", "kinetis.ld"),
        ("kinetis-hang", "kinetis.ld"),
        ("core-check", "kinetis.ld"),
        ("stm32-gate", "stm32f7.ld"),
        ("stm32-stuck", "stm32f7.ld"),
        ("bluepill-can", "stm32f103c8.ld"),
        ("bluepill-gate", "stm32f103c8.ld"),
        ("bluepill-stuck", "stm32f103c8.ld"),
        ("nucleo-f446re-can", "stm32f446re.ld"),
        ("imxrt-boot", "imxrt1062.ld"),
        ("imxrt-gate", "imxrt1062.ld"),
        ("imxrt-stuck", "imxrt1062.ld"),
        ("imxrt-no-can-clock", "imxrt1062.ld"),
    ] {
        println!(
            "cargo:rustc-link-arg-bin={bin}=-T{}",
            dir.join(script).display()
        );
    }
}
