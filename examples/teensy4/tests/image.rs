//! Checks of the cross-built Teensy 4 images (run by CI right after the cross-build):
//!
//! ```sh
//! cargo build --release --target thumbv7em-none-eabihf -p twocan-teensy4 --features teensy41 --bins
//! TWOCAN_REQUIRE_ELF=1 cargo test -p twocan-teensy4 --test image -- --nocapture
//! ```
//!
//! What the i.MX RT1062 boot ROM needs to start the image (IMXRT1060RM, "System Boot"):
//! the FlexSPI configuration block at 0x6000_0000 (tag "FCFB"), the image vector table at
//! 0x6000_1000 (header 0xD1/0x0020/0x40, entry, boot data, self), the boot data (image
//! start 0x6000_0000, a size covering every loaded byte); and what cortex-m-rt's reset
//! needs: the vector table the IVT names, its stack pointer at the top of the DTCM, its
//! reset vector odd (Thumb) and in the flash, and the CAN1/CAN2/CAN3 device vectors at 36,
//! 37 and 154 pointing at the library's entry points. The configuration block's
//! `sflashA1Size` (offset 0x50) is a Teensy 4 flash — 2 MiB (4.0) or 8 MiB (4.1), the one
//! `$TWOCAN_TEENSY4_BOARD` (`teensy40`/`teensy41`, set by CI) names — and the image
//! ends inside it (`runner.sh` picks `--mcu` from the same word). Prints flash and RAM
//! use.
//!
//! Where the ELFs are: `$TWOCAN_FIRMWARE_DIR`, else the workspace's
//! `target/thumbv7em-none-eabihf/release`. Without them the test says so and passes,
//! unless `TWOCAN_REQUIRE_ELF` is set (CI).

use std::path::PathBuf;

use object::{Object, ObjectSection, ObjectSymbol};

const BINS: [&str; 6] = [
    "teensy4-loopback",
    "teensy4-loopback-lean",
    "teensy4-filters",
    "teensy4-app",
    "teensy4-async-echo",
    "teensy4-can1-can2",
];

fn firmware_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("TWOCAN_FIRMWARE_DIR") {
        return PathBuf::from(dir);
    }
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target"));
    target.join("thumbv7em-none-eabihf/release")
}

/// The 32-bit little-endian word at `addr` of the loaded image.
fn word(elf: &object::File<'_>, addr: u64) -> u32 {
    for s in elf.sections() {
        let (start, size) = (s.address(), s.size());
        if (start..start + size).contains(&addr) {
            let data = s.data().expect("section data");
            let at = (addr - start) as usize;
            return u32::from_le_bytes(data[at..at + 4].try_into().unwrap());
        }
    }
    panic!("0x{addr:08X} is in no section");
}

fn symbol(elf: &object::File<'_>, name: &str) -> u64 {
    elf.symbols()
        .find(|s| s.name() == Ok(name))
        .unwrap_or_else(|| panic!("no symbol {name}"))
        .address()
}

#[test]
fn boot_header_and_vector_table() {
    let dir = firmware_dir();
    let mut checked = 0;
    for bin in BINS {
        let path = dir.join(bin);
        let Ok(bytes) = std::fs::read(&path) else {
            if std::env::var_os("TWOCAN_REQUIRE_ELF").is_some() {
                panic!(
                    "{} missing: cross-build the Teensy 4 examples first",
                    path.display()
                );
            }
            eprintln!("skipped: {} missing", path.display());
            continue;
        };
        let elf = object::File::parse(&*bytes).expect("ELF");
        // FlexSPI configuration block: tag "FCFB", version 1.4.0.
        assert_eq!(word(&elf, 0x6000_0000), 0x4246_4346, "{bin}: FCB tag");
        assert_eq!(word(&elf, 0x6000_0004), 0x5601_0400, "{bin}: FCB version");
        // The board's flash: `sflashA1Size`, and the image inside it.
        let flash_bytes = word(&elf, 0x6000_0050);
        let board = match flash_bytes {
            0x0020_0000 => "teensy40",
            0x0080_0000 => "teensy41",
            other => panic!("{bin}: sflashA1Size 0x{other:X} is no Teensy 4 flash"),
        };
        if let Some(expected) = std::env::var_os("TWOCAN_TEENSY4_BOARD") {
            assert_eq!(expected.to_str(), Some(board), "{bin}: built for {board}");
        }
        // Image vector table.
        let ivt = 0x6000_1000;
        assert_eq!(word(&elf, ivt), 0x4020_00D1, "{bin}: IVT header");
        let entry = word(&elf, ivt + 4);
        let boot_data = word(&elf, ivt + 16);
        assert_eq!(word(&elf, ivt + 20), ivt as u32, "{bin}: IVT self");
        assert_eq!(word(&elf, ivt + 12), 0, "{bin}: no DCD");
        assert_eq!(u64::from(entry), symbol(&elf, "__vector_table"), "{bin}");
        assert_eq!(
            entry, 0x6000_2000,
            "{bin}: the vector table follows the header"
        );
        // Boot data: the image from 0x6000_0000, every loaded byte inside.
        assert_eq!(word(&elf, u64::from(boot_data)), 0x6000_0000, "{bin}");
        let size = u64::from(word(&elf, u64::from(boot_data) + 4));
        let mut loaded_end = 0;
        for s in elf.segments() {
            use object::ObjectSegment;
            let (_, file_size) = s.file_range();
            if file_size > 0 && (0x6000_0000..0x6100_0000).contains(&s.address()) {
                loaded_end = loaded_end.max(s.address() + file_size);
            }
        }
        // `.data`'s load image sits after `.rodata` in the flash.
        let data_end =
            symbol(&elf, "__sidata") + (symbol(&elf, "__edata") - symbol(&elf, "__sdata"));
        let end = loaded_end.max(data_end);
        assert!(
            0x6000_0000 + size >= end,
            "{bin}: image size 0x{size:X} ends before 0x{end:X}"
        );
        assert!(
            size <= u64::from(flash_bytes),
            "{bin}: image of 0x{size:X} bytes larger than the {board}'s flash"
        );
        // Vector table: SP at the top of the DTCM, reset in the flash (Thumb).
        let vt = u64::from(entry);
        assert_eq!(word(&elf, vt), 0x2002_0000, "{bin}: initial SP");
        let reset = word(&elf, vt + 4);
        assert!(
            reset & 1 == 1 && (0x6000_2000..0x6080_0000).contains(&reset),
            "{bin}: reset 0x{reset:08X}"
        );
        for (irq, name) in [(36, "CAN1"), (37, "CAN2"), (154, "CAN3")] {
            let v = word(&elf, vt + 4 * (16 + irq));
            assert_eq!(
                u64::from(v & !1),
                symbol(&elf, name) & !1,
                "{bin}: {name} vector"
            );
        }
        let flash = size;
        let ram = symbol(&elf, "__ebss").max(symbol(&elf, "__edata")) - 0x2000_0000;
        println!("{bin} ({board}): image {flash} bytes, static RAM {ram} bytes");
        checked += 1;
    }
    println!("{checked} images checked");
}
