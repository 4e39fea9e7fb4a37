//! Checks of the cross-built firmware images (run by CI right after the cross-build):
//!
//! ```sh
//! cargo build --release --target thumbv7em-none-eabihf -p twocan-teensy --features teensy36 --bins
//! TWOCAN_REQUIRE_ELF=1 cargo test -p twocan-teensy --features teensy36 --test elf -- --nocapture
//! ```
//!
//! The test reads each ELF of the board the test itself is built for (the board feature)
//! and checks what a wrong build would brick or hang the chip with:
//! - the 16 bytes at 0x400..0x40F (the flash configuration field) are exactly the
//!   intended ones, and independently of that, `FSEC` leaves the chip unsecured and
//!   mass-erasable;
//! - the vector table: initial SP at the top of the board's RAM, reset vector odd (Thumb)
//!   and inside flash, the table ends before 0x400, SysTick and the FlexCAN vectors point
//!   where the symbols say;
//! - `__pre_init` is ours (it writes the watchdog unlock and control registers), not
//!   cortex-m-rt's empty default;
//! - and prints flash and RAM use.
//!
//! Where the ELFs are: `$TWOCAN_FIRMWARE_DIR`, else
//! `$CARGO_TARGET_DIR/thumbv7em-none-eabihf/release`, else the workspace's `target/`.
//! Without a board feature, or without the ELFs, the test says so and passes, unless
//! `TWOCAN_REQUIRE_ELF` is set (CI), when a missing ELF fails.

use std::path::PathBuf;

/// The firmware of this board, if the test is built with a board feature.
fn board() -> Option<twocan_teensy::Board> {
    #[cfg(any(feature = "teensy32", feature = "teensy35", feature = "teensy36"))]
    {
        Some(twocan_teensy::BOARD)
    }
    #[cfg(not(any(feature = "teensy32", feature = "teensy35", feature = "teensy36")))]
    {
        None
    }
}

fn firmware_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("TWOCAN_FIRMWARE_DIR") {
        return PathBuf::from(dir);
    }
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target"));
    target.join("thumbv7em-none-eabihf/release")
}

fn bins(board: &twocan_teensy::Board) -> Vec<&'static str> {
    let mut v = vec![
        "teensy-loopback",
        "teensy-loopback-lean",
        "teensy-filters",
        "teensy-app",
        "teensy-async-echo",
    ];
    if board.can_instances().len() > 1 {
        v.push("teensy-can0-can1");
    }
    v
}

#[test]
fn firmware_images() {
    let Some(board) = board() else {
        println!(
            "skipped: build the test with a board feature to check that board's ELFs \
             (e.g. cargo test -p twocan-teensy --features teensy36 --test elf)"
        );
        return;
    };
    let require = std::env::var_os("TWOCAN_REQUIRE_ELF").is_some();
    let dir = firmware_dir();
    let mut checked = 0;
    println!(
        "{:<10} {:<10} {:>8} {:>8}",
        "board", "example", "flash", "ram"
    );
    for bin in bins(&board) {
        let path = dir.join(bin);
        let Ok(data) = std::fs::read(&path) else {
            assert!(
                !require,
                "{} is missing: cross-build it first (cargo build --release --target \
                 thumbv7em-none-eabihf -p twocan-teensy --features {} --bins)",
                path.display(),
                board.name
            );
            println!(
                "skipped {}: not built (cargo build --release --target thumbv7em-none-eabihf \
                 -p twocan-teensy --features {} --bins)",
                path.display(),
                board.name
            );
            continue;
        };
        let image = elf::Image::parse(&data).unwrap_or_else(|e| panic!("{bin}: {e}"));
        let sizes = image.check(&board).unwrap_or_else(|e| panic!("{bin}: {e}"));
        println!(
            "{:<10} {:<18} {:>8} {:>8}",
            board.name, bin, sizes.flash, sizes.ram
        );
        checked += 1;
    }
    println!("checked {checked} image(s) in {}", dir.display());
}

mod elf {
    use object::{Object, ObjectSection, ObjectSegment, ObjectSymbol, SectionFlags};
    use twocan_teensy::flash_config::{
        FLASH_CONFIG_BYTES, FSEC_FIELD_DISABLED, FSEC_MEEN_SHIFT, FSEC_SEC_MASK, FSEC_SEC_UNSECURE,
    };
    use twocan_teensy::regs::{WDOG_STCTRLH, WDOG_UNLOCK};
    use twocan_teensy::Board;

    pub struct Sizes {
        /// Bytes stored in flash: vector table, flash configuration, code, read-only data
        /// and the initial values of `.data`.
        pub flash: u64,
        /// Bytes of RAM taken statically: `.data`, `.bss`, `.uninit` (the stack comes on
        /// top of that).
        pub ram: u64,
    }

    pub struct Image<'a> {
        file: object::File<'a>,
    }

    impl<'a> Image<'a> {
        pub fn parse(data: &'a [u8]) -> Result<Self, String> {
            let file = object::File::parse(data).map_err(|e| format!("not an ELF: {e}"))?;
            if file.architecture() != object::Architecture::Arm || !file.is_little_endian() {
                return Err("not a little-endian ARM image".into());
            }
            Ok(Image { file })
        }

        /// The file bytes of flash addresses `addr..addr + len`, from the loadable
        /// segment that covers them.
        fn flash_bytes(&self, addr: u64, len: u64) -> Result<&'a [u8], String> {
            for seg in self.file.segments() {
                let data = seg.data().map_err(|e| e.to_string())?;
                let start = seg.address();
                if start <= addr && addr + len <= start + data.len() as u64 {
                    let off = (addr - start) as usize;
                    return Ok(&data[off..off + len as usize]);
                }
            }
            Err(format!(
                "no loadable segment holds {len} bytes at {addr:#x}"
            ))
        }

        fn word(&self, addr: u64) -> Result<u32, String> {
            let b = self.flash_bytes(addr, 4)?;
            Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        }

        fn symbol(&self, name: &str) -> Option<object::Symbol<'a, '_>> {
            self.file.symbols().find(|s| s.name() == Ok(name))
        }

        /// The address of a symbol, without the Thumb bit of function symbols.
        fn symbol_address(&self, name: &str) -> Result<u64, String> {
            self.symbol(name)
                .map(|s| s.address() & !1)
                .ok_or_else(|| format!("symbol {name} missing"))
        }

        pub fn check(&self, board: &Board) -> Result<Sizes, String> {
            self.check_flash_config()?;
            self.check_vector_table(board)?;
            self.check_pre_init()?;
            Ok(self.sizes(board))
        }

        fn check_flash_config(&self) -> Result<(), String> {
            let bytes = self.flash_bytes(0x400, 16)?;
            if bytes != FLASH_CONFIG_BYTES {
                return Err(format!(
                    "flash configuration field at 0x400 is {bytes:02x?}, expected \
                     {FLASH_CONFIG_BYTES:02x?}"
                ));
            }
            // Independently of the constant: never a secured or non-erasable chip.
            let fsec = bytes[12];
            if fsec & FSEC_SEC_MASK != FSEC_SEC_UNSECURE {
                return Err(format!("FSEC = {fsec:#04x} would secure the chip"));
            }
            if (fsec >> FSEC_MEEN_SHIFT) & 0b11 == FSEC_FIELD_DISABLED {
                return Err(format!("FSEC = {fsec:#04x} disables mass erase"));
            }
            // Only `.flash_config` may cover 0x400..0x410.
            for s in self.file.sections() {
                let alloc =
                    matches!(s.flags(), SectionFlags::Elf { sh_flags, .. } if sh_flags.0 & 2 != 0);
                let (a, n) = (s.address(), s.size());
                if alloc && n > 0 && a < 0x410 && a + n > 0x400 {
                    let name = s.name().unwrap_or("?");
                    if name != ".flash_config" || a != 0x400 || n != 16 {
                        return Err(format!(
                            "section {name} ({a:#x}, {n} bytes) overlaps the flash \
                             configuration field"
                        ));
                    }
                }
            }
            Ok(())
        }

        fn check_vector_table(&self, board: &Board) -> Result<(), String> {
            let table = self
                .file
                .section_by_name(".vector_table")
                .ok_or("no .vector_table section")?;
            if table.address() != board.flash.0 as u64 {
                return Err(format!("vector table at {:#x}", table.address()));
            }
            if table.size() != board.vector_table_bytes() as u64 || table.size() > 0x400 {
                return Err(format!(
                    "vector table is {} bytes, expected {} (must end before 0x400)",
                    table.size(),
                    board.vector_table_bytes()
                ));
            }
            let sp = self.word(0)?;
            let (ram0, ram_len) = board.ram;
            if sp <= ram0 || sp > ram0 + ram_len || sp % 8 != 0 {
                return Err(format!(
                    "initial SP {sp:#x} is not in RAM {ram0:#x}..={:#x} (an image built \
                     for another board?)",
                    ram0 + ram_len
                ));
            }
            if sp != board.stack_top() {
                return Err(format!(
                    "initial SP {sp:#x}, expected the top of RAM {:#x} (an image built for \
                     another board?)",
                    board.stack_top()
                ));
            }
            let reset = self.word(4)?;
            let (flash0, flash_len) = board.flash;
            if reset & 1 == 0 {
                return Err(format!("reset vector {reset:#x} is not a Thumb address"));
            }
            let reset_addr = reset & !1;
            if reset_addr < 0x410 || reset_addr >= flash0 + flash_len {
                return Err(format!(
                    "reset vector {reset:#x} is not in flash after 0x410"
                ));
            }
            if u64::from(reset_addr) != self.symbol_address("Reset")? {
                return Err(format!("reset vector {reset:#x} is not the Reset handler"));
            }
            // Every non-reserved entry is a Thumb handler address in flash.
            let reserved = [7, 8, 9, 10, 13];
            for i in 2..16 + board.irq_count {
                let v = self.word(4 * i as u64)?;
                let ok = if reserved.contains(&i) {
                    v == 0
                } else {
                    v & 1 == 1 && (v & !1) < flash0 + flash_len
                };
                if !ok {
                    return Err(format!("vector {i} = {v:#x}"));
                }
            }
            let systick = self.word(4 * 15)?;
            if u64::from(systick & !1) != self.symbol_address("SysTick")? {
                return Err("the SysTick vector is not the SysTick handler".into());
            }
            for (n, &instance) in board.can_instances().iter().enumerate() {
                let base = board.can_irq_base(instance).ok_or("no FlexCAN IRQs")?;
                let name = format!("CAN{n}_ORED_MESSAGE_BUFFER");
                let v = self.word(4 * (16 + base as u64))?;
                if u64::from(v & !1) != self.symbol_address(&name)? {
                    return Err(format!("vector of IRQ {base} is not {name}"));
                }
            }
            Ok(())
        }

        fn check_pre_init(&self) -> Result<(), String> {
            let pre = self.symbol("__pre_init").ok_or("no __pre_init")?;
            if let Some(default) = self.symbol("DefaultPreInit") {
                if default.address() & !1 == pre.address() & !1 {
                    return Err("__pre_init is cortex-m-rt's empty default: the watchdog \
                                would stay enabled"
                        .into());
                }
            }
            // The function and its literal pool name both watchdog registers.
            let code = self.flash_bytes(pre.address() & !1, 48)?;
            let has = |addr: usize| {
                code.windows(4)
                    .any(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]) as usize == addr)
            };
            if !has(WDOG_UNLOCK) || !has(WDOG_STCTRLH) {
                return Err("__pre_init does not reference WDOG_UNLOCK and WDOG_STCTRLH".into());
            }
            Ok(())
        }

        fn sizes(&self, board: &Board) -> Sizes {
            let (mut flash, mut ram) = (0, 0);
            let (ram0, ram_len) = board.ram;
            for s in self.file.sections() {
                let alloc =
                    matches!(s.flags(), SectionFlags::Elf { sh_flags, .. } if sh_flags.0 & 2 != 0);
                if !alloc {
                    continue;
                }
                let in_ram = s.address() >= ram0 as u64 && s.address() < (ram0 + ram_len) as u64;
                let loaded = s.kind() != object::SectionKind::UninitializedData;
                if in_ram {
                    ram += s.size();
                }
                if loaded && (!in_ram || s.name() == Ok(".data")) {
                    flash += s.size();
                }
            }
            Sizes { flash, ram }
        }
    }
}
