//! Flash and RAM of a firmware ELF, from its section headers.
//!
//! Only allocated sections (`SHF_ALLOC`) occupy the target's memories:
//!
//! - `SHT_NOBITS` (`.bss`, `.uninit`): RAM only (zeroed or left alone at start-up);
//! - `SHT_PROGBITS` with `SHF_WRITE` (`.data`): RAM, **and** flash for its initial image
//!   that the start-up code copies;
//! - any other allocated section (`.vector_table`, `.text`, `.rodata`, `.flash_config`):
//!   flash-resident code and constants.
//!
//! So `flash = code + data` and `RAM = data + bss`. The stack (the rest of RAM, placed by
//! cortex-m-rt) is not a section and is not counted.

use std::path::Path;

use object::elf::{SHF_ALLOC, SHF_WRITE, SHT_NOBITS};
use object::read::elf::{ElfFile32, SectionHeader};
use object::{LittleEndian, Object, ObjectSection, ObjectSymbol, SymbolKind};

use crate::cmd::{Context, Error, Result};

/// Where a section lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Class {
    /// Flash-resident code and constants.
    Code,
    /// Initialised data: RAM, and its image in flash.
    Data,
    /// Zero-initialised or uninitialised data: RAM only.
    Bss,
}

impl Class {
    /// A short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            Class::Code => "code",
            Class::Data => "data",
            Class::Bss => "bss",
        }
    }
}

/// One allocated section.
#[derive(Debug, Clone)]
pub struct Section {
    /// Its name.
    pub name: String,
    /// Bytes.
    pub size: u64,
    /// Where it lives.
    pub class: Class,
}

/// The memory use of one ELF.
#[derive(Debug, Clone)]
pub struct Size {
    /// Allocated sections, in file order (empty ones left out).
    pub sections: Vec<Section>,
    /// Bytes of the shared start-up module's code and constants: the symbols of a module
    /// named `startup` ([`STARTUP_MODULE`]; the bench firmware include
    /// `shared/stm32f7.rs` or `shared/kinetis.rs` under that name) and a `__pre_init`
    /// of more than cortex-m-rt's empty default ([`PRE_INIT`]). 0 for an ELF without
    /// them.
    pub startup: u64,
    /// Code (function symbols) by the crate that defines it, largest first, start-up
    /// module left out ([`crate_of`]): where the flash goes. Code inlined into another
    /// crate's function counts for that function's crate.
    pub code_by_crate: Vec<(String, u64)>,
    /// The largest functions (readable names, [`readable`]), largest first, start-up
    /// module left out: up to [`LARGEST`].
    pub largest: Vec<(String, u64)>,
}

/// How many of the largest functions [`Size::largest`] keeps.
pub const LARGEST: usize = 6;

/// The path component (in legacy Rust symbol mangling, length-prefixed) of the bench
/// firmware's shared start-up module.
pub const STARTUP_MODULE: &str = "7startup";

/// cortex-m-rt's hook before RAM initialisation: part of the start-up where a firmware
/// defines it (the Kinetis watchdog, `shared/kinetis.rs`).
pub const PRE_INIT: &str = "__pre_init";

/// Sections that are not driver or application code: the vector table and, on the
/// Kinetis parts, the flash configuration field.
pub const NOT_APPLICATION: [&str; 2] = [".vector_table", ".flash_config"];

impl Size {
    fn total(&self, class: Class) -> u64 {
        self.sections
            .iter()
            .filter(|s| s.class == class)
            .map(|s| s.size)
            .sum()
    }

    /// Flash-resident code and constants.
    pub fn code(&self) -> u64 {
        self.total(Class::Code)
    }

    /// Initialised data.
    pub fn data(&self) -> u64 {
        self.total(Class::Data)
    }

    /// Zero-initialised / uninitialised data.
    pub fn bss(&self) -> u64 {
        self.total(Class::Bss)
    }

    /// Flash: code + data.
    pub fn flash(&self) -> u64 {
        self.code() + self.data()
    }

    /// RAM: data + bss.
    pub fn ram(&self) -> u64 {
        self.data() + self.bss()
    }

    /// Flash of the driver and the application: [`Size::flash`] without the vector
    /// table, the flash configuration field and the shared start-up module.
    pub fn app_flash(&self) -> u64 {
        let left_out: u64 = self
            .sections
            .iter()
            .filter(|s| NOT_APPLICATION.contains(&s.name.as_str()))
            .map(|s| s.size)
            .sum();
        self.flash() - left_out - self.startup
    }

    /// `name size, ...` of the non-empty sections, for the report.
    pub fn section_list(&self) -> String {
        self.sections
            .iter()
            .map(|s| format!("`{}` {} ({})", s.name, s.size, s.class.name()))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

fn parse(data: &[u8]) -> Result<ElfFile32<'_, LittleEndian>> {
    ElfFile32::<LittleEndian>::parse(data).context("not a 32-bit little-endian ELF")
}

/// Reads the section headers of the ELF at `path`.
pub fn measure(path: &Path) -> Result<Size> {
    let data = std::fs::read(path).context(format!("reading {}", path.display()))?;
    let elf = parse(&data).context(path.display())?;
    let endian = elf.endian();
    let mut sections = Vec::new();
    for section in elf.sections() {
        let header = section.elf_section_header();
        let flags = header.sh_flags(endian).0;
        if flags & SHF_ALLOC.0 == 0 {
            continue;
        }
        let size = u64::from(header.sh_size(endian));
        if size == 0 {
            continue;
        }
        let class = if header.sh_type(endian) == SHT_NOBITS {
            Class::Bss
        } else if flags & SHF_WRITE.0 != 0 {
            Class::Data
        } else {
            Class::Code
        };
        let name = section.name().unwrap_or("?").to_string();
        sections.push(Section { name, size, class });
    }
    if sections.is_empty() {
        return Err(Error::new(format!(
            "{}: no allocated section",
            path.display()
        )));
    }
    // Symbols of the start-up module, each address once (aliases share one).
    let mut seen = std::collections::BTreeSet::new();
    let mut startup = 0;
    for sym in elf.symbols() {
        let Ok(name) = sym.name() else { continue };
        if (name.contains(STARTUP_MODULE) || name == PRE_INIT)
            && sym.size() > 0
            && matches!(sym.kind(), SymbolKind::Text | SymbolKind::Data)
            && seen.insert(sym.address() & !1)
        {
            startup += sym.size();
        }
    }
    let mut by_crate: std::collections::BTreeMap<String, u64> = Default::default();
    let mut seen_code = std::collections::BTreeSet::new();
    let mut functions: Vec<(String, u64)> = Vec::new();
    for sym in elf.symbols() {
        let Ok(name) = sym.name() else { continue };
        if sym.kind() != SymbolKind::Text
            || sym.size() == 0
            || name.contains(STARTUP_MODULE)
            || name == PRE_INIT
            || !seen_code.insert(sym.address() & !1)
        {
            continue;
        }
        *by_crate.entry(crate_of(name)).or_default() += sym.size();
        functions.push((readable(name), sym.size()));
    }
    functions.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    functions.truncate(LARGEST);
    let mut code_by_crate: Vec<(String, u64)> = by_crate.into_iter().collect();
    code_by_crate.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    Ok(Size {
        sections,
        startup,
        code_by_crate,
        largest: functions,
    })
}

/// A function symbol as a reader names it: a legacy Rust mangled name's last two path
/// components, decoded (`State<H, _, Q, _, _, Fe>::service_tx`), the hash left out; a
/// v0 mangled name's last identifier; any other name as it is.
pub fn readable(symbol: &str) -> String {
    let Some(mut rest) = symbol.strip_prefix("_ZN") else {
        if symbol.starts_with("_R") {
            // The last length-prefixed identifier.
            let b = symbol.as_bytes();
            let mut i = b.len();
            while i > 0 && !b[i - 1].is_ascii_digit() {
                i -= 1;
            }
            let tail = &symbol[i..];
            return if tail.is_empty() {
                symbol.into()
            } else {
                tail.into()
            };
        }
        return symbol.into();
    };
    let mut parts: Vec<String> = Vec::new();
    loop {
        let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
        let Ok(len) = digits.parse::<usize>() else {
            break;
        };
        let Some(ident) = rest.get(digits.len()..digits.len() + len) else {
            break;
        };
        parts.push(ident.to_string());
        rest = &rest[digits.len() + len..];
    }
    if parts
        .last()
        .is_some_and(|p| p.len() == 17 && p.starts_with('h'))
    {
        parts.pop();
    }
    let decode = |p: &str| {
        p.replace("$LT$", "<")
            .replace("$GT$", ">")
            .replace("$u20$", " ")
            .replace("$C$", ",")
            .replace("$RF$", "&")
            .replace("..", "::")
            .replace(',', ", ")
            .trim_start_matches('_')
            .to_string()
    };
    let n = parts.len();
    parts[n.saturating_sub(2)..]
        .iter()
        .map(|p| decode(p))
        .collect::<Vec<_>>()
        .join("::")
}

/// The crate a function symbol belongs to: the first path component of a legacy Rust
/// mangled name (`_ZN11twocan_core5split...` → `twocan_core`; for a trait method
/// `<Type as Trait>::f`, the crate of `Type`), `compiler_builtins` for the unmangled
/// memory and ARM EABI helpers it exports (a v0 mangled name, `_R...`: its first crate
/// root), `cortex_m_rt` for its exception handlers,
/// the application for `main`, and `other` for the rest.
pub fn crate_of(symbol: &str) -> String {
    if let Some(rest) = symbol.strip_prefix("_ZN") {
        let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
        if let Ok(len) = digits.parse::<usize>() {
            let ident = rest.get(digits.len()..digits.len() + len).unwrap_or("");
            // `_$LT$Type$u20$as$u20$Trait$GT$`, `_$LT$impl$u20$...`: the type's crate.
            let ident = ident
                .trim_start_matches('_')
                .trim_start_matches("$LT$")
                .trim_start_matches("impl$u20$")
                .trim_start_matches('&')
                .trim_start_matches("$RF$")
                .trim_start_matches("mut$u20$")
                .trim_start_matches("$u5b$");
            let krate: String = ident
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if !krate.is_empty() {
                return krate;
            }
        }
        return "other".into();
    }
    if let Some(rest) = symbol.strip_prefix("_R") {
        // v0 mangling: the first crate root, `C` with an optional `s<hash>_`
        // disambiguator, then the length-prefixed crate name.
        let b = rest.as_bytes();
        let mut i = 0;
        while i < b.len() {
            if b[i] == b'C' {
                let mut j = i + 1;
                if b.get(j) == Some(&b's') {
                    while j < b.len() && b[j] != b'_' {
                        j += 1;
                    }
                    j += 1;
                }
                let start = j;
                while j < b.len() && b[j].is_ascii_digit() {
                    j += 1;
                }
                if let Ok(len) = rest[start..j].parse::<usize>() {
                    let ident = rest.get(j..j + len).unwrap_or("");
                    let ident = ident.strip_prefix('_').unwrap_or(ident);
                    if !ident.is_empty()
                        && ident.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                    {
                        return ident.to_string();
                    }
                }
            }
            i += 1;
        }
        return "other".into();
    }
    if symbol.starts_with("__aeabi_")
        || symbol.starts_with("mem")
        || symbol.starts_with("__udiv")
        || symbol.starts_with("__div")
        || symbol.starts_with("compiler_builtins")
    {
        return "compiler_builtins".into();
    }
    match symbol {
        "main" => "application (main)".into(),
        "Reset"
        | "DefaultHandler"
        | "DefaultHandler_"
        | "HardFault_"
        | "HardFaultTrampoline"
        | "DefaultPreInit" => "cortex_m_rt".into(),
        _ => "other".into(),
    }
}

/// The 32-bit little-endian value of the static `symbol` in the ELF at `path`.
pub fn read_u32_symbol(path: &Path, symbol: &str) -> Result<u32> {
    Ok(read_u32_array_symbol(path, symbol, 1)?[0])
}

/// The `n` 32-bit little-endian values of the static array `symbol` in the ELF at `path`.
pub fn read_u32_array_symbol(path: &Path, symbol: &str, n: usize) -> Result<Vec<u32>> {
    let data = std::fs::read(path).context(format!("reading {}", path.display()))?;
    let elf = parse(&data).context(path.display())?;
    let sym = elf
        .symbols()
        .find(|s| s.name() == Ok(symbol))
        .ok_or_else(|| Error::new(format!("{}: no symbol `{symbol}`", path.display())))?;
    let addr = sym.address();
    for section in elf.sections() {
        if let Ok(Some(bytes)) = section.data_range(addr, 4 * n as u64) {
            return Ok(bytes
                .chunks_exact(4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect());
        }
    }
    Err(Error::new(format!(
        "{}: symbol `{symbol}` at {addr:#x} has no {n} words of data",
        path.display()
    )))
}

/// The size of the symbol `symbol` in the ELF at `path` (its `st_size`).
pub fn symbol_size(path: &Path, symbol: &str) -> Result<u64> {
    let data = std::fs::read(path).context(format!("reading {}", path.display()))?;
    let elf = parse(&data).context(path.display())?;
    elf.symbols()
        .find(|s| s.name() == Ok(symbol))
        .map(|s| s.size())
        .ok_or_else(|| Error::new(format!("{}: no symbol `{symbol}`", path.display())))
}

/// What a split driver's `State` spends its bytes on (`twocan_core::split::Footprint`,
/// exported by the instruction-count firmware as `BENCH_FOOTPRINT`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Footprint {
    /// The whole `State`.
    pub total: u64,
    /// The controller value (with its publication stage and lease count).
    pub controller: u64,
    /// Receive, transmit, completion and state-change slots.
    pub slots: [u64; 4],
    /// The rings' indices, peaks and overflow counts.
    pub ring_bookkeeping: u64,
    /// The transmit queue's indices, length, peak and overflow count.
    pub queue_bookkeeping: u64,
    /// The time-stamp widening reference.
    pub clock: u64,
    /// Traffic statistics.
    pub statistics: u64,
    /// Rare-event counts and the error state.
    pub errors: u64,
    /// Async wakers.
    pub wakers: u64,
    /// Alignment padding.
    pub padding: u64,
}

impl Footprint {
    /// From the 13 words of `BENCH_FOOTPRINT`; refuses words that do not add up.
    pub fn from_words(w: &[u32]) -> Result<Footprint> {
        let w: Vec<u64> = w.iter().map(|&v| u64::from(v)).collect();
        let [total, controller, rx, tx, done, changes, rings, queue, clock, statistics, errors, wakers, padding] =
            w[..]
        else {
            return Err(Error::new(format!(
                "BENCH_FOOTPRINT: {} words, not 13",
                w.len()
            )));
        };
        let f = Footprint {
            total,
            controller,
            slots: [rx, tx, done, changes],
            ring_bookkeeping: rings,
            queue_bookkeeping: queue,
            clock,
            statistics,
            errors,
            wakers,
            padding,
        };
        let sum = controller
            + f.slots.iter().sum::<u64>()
            + rings
            + queue
            + clock
            + statistics
            + errors
            + wakers
            + padding;
        if sum != total {
            return Err(Error::new(format!(
                "BENCH_FOOTPRINT parts add up to {sum} B, not the total {total} B"
            )));
        }
        Ok(f)
    }

    /// The slots the capacities buy.
    pub fn slot_bytes(&self) -> u64 {
        self.slots.iter().sum()
    }
}

/// What the driver's shared `State` static of the loop-back firmware holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StateFigures {
    /// Size of the `State` static (`BENCH_CAN_STATE` of the loop-back firmware).
    pub static_bytes: u64,
    /// Of which ring and queue slots (the footprint's slots, from `insn-count`, which
    /// holds a `State` of the same type and checks its size in `BENCH_STATE_BYTES`).
    pub ring_bytes: u64,
    /// The whole footprint (`BENCH_FOOTPRINT` of the instruction-count firmware).
    pub footprint: Footprint,
    /// Of which the controller value (`BENCH_HW_BYTES`, where the firmware exports it).
    pub hw_bytes: Option<u64>,
    /// Of which, inside the controller value, the filter map (bxCAN) or the filter
    /// table the controller keeps (FlexCAN) (`BENCH_FMI_BYTES`).
    pub fmi_bytes: Option<u64>,
    /// Of which, inside the controller value, the clock gate and pin plan kept for
    /// `end` (`BENCH_SYSTEM_BYTES`, FlexCAN).
    pub system_bytes: Option<u64>,
}

impl StateFigures {
    /// Driver state beyond the rings.
    pub fn state_bytes(&self) -> u64 {
        self.static_bytes - self.ring_bytes
    }
}

/// Reads [`StateFigures`] from a loop-back firmware (its `BENCH_CAN_STATE` static) and
/// the instruction-count firmware of the same variant (which exports the footprint of
/// the same `State` type); refuses figures of two different sizes.
pub fn state_figures(loopback: &Path, insn_count: &Path) -> Result<StateFigures> {
    let static_bytes = symbol_size(loopback, "BENCH_CAN_STATE")?;
    let same_type = u64::from(read_u32_symbol(insn_count, "BENCH_STATE_BYTES")?);
    if same_type != static_bytes {
        return Err(Error::new(format!(
            "the State of {} is {same_type} B, that of {} {static_bytes} B: they must be \
             the same type",
            insn_count.display(),
            loopback.display()
        )));
    }
    let footprint =
        Footprint::from_words(&read_u32_array_symbol(insn_count, "BENCH_FOOTPRINT", 13)?)?;
    if footprint.total != static_bytes {
        return Err(Error::new(format!(
            "the footprint of {} says {} B, the State is {static_bytes} B",
            insn_count.display(),
            footprint.total
        )));
    }
    let optional = |symbol: &str| read_u32_symbol(insn_count, symbol).ok().map(u64::from);
    Ok(StateFigures {
        static_bytes,
        ring_bytes: footprint.slot_bytes(),
        footprint,
        hw_bytes: optional("BENCH_HW_BYTES"),
        fmi_bytes: optional("BENCH_FMI_BYTES"),
        system_bytes: optional("BENCH_SYSTEM_BYTES"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symbols_are_charged_to_their_crate() {
        assert_eq!(
            crate_of("_ZN11twocan_core5split5State8try_send17h0123456789abcdefE"),
            "twocan_core"
        );
        assert_eq!(
            crate_of(
                "_ZN83_$LT$twocan_bxcan..BxCan$LT$R$C$F$GT$$u20$as$u20$twocan_core..Hardware$GT$8try_load17h0123456789abcdefE"
            ),
            "twocan_bxcan"
        );
        assert_eq!(crate_of("__aeabi_memcpy"), "compiler_builtins");
        assert_eq!(
            crate_of("_RNvNtCs7NhdfSRABLd_17compiler_builtins3mem6memcpy"),
            "compiler_builtins"
        );
        assert_eq!(
            crate_of("_RNvNtCs7ldSeZOOJos_4core9panicking9panic_fmt"),
            "core"
        );
        assert_eq!(crate_of("memcpy"), "compiler_builtins");
        assert_eq!(crate_of("main"), "application (main)");
        assert_eq!(crate_of("Reset"), "cortex_m_rt");
        assert_eq!(crate_of("CAN1_RX0"), "other");
        assert_eq!(
            readable(
                "_ZN11twocan_core5split35State$LT$H$C$_$C$Q$C$_$C$_$C$Fe$GT$10service_tx17h7cb210191959023fE"
            ),
            "State<H, _, Q, _, _, Fe>::service_tx"
        );
        assert_eq!(readable("main"), "main");
    }

    fn section(name: &str, size: u64, class: Class) -> Section {
        Section {
            name: name.into(),
            size,
            class,
        }
    }

    #[test]
    fn driver_and_application_flash_leaves_out_vectors_config_field_and_start_up() {
        let z = Size {
            code_by_crate: Vec::new(),
            largest: Vec::new(),
            sections: vec![
                section(".vector_table", 1024, Class::Code),
                section(".flash_config", 16, Class::Code),
                section(".text", 5000, Class::Code),
                section(".rodata", 100, Class::Code),
                section(".data", 8, Class::Data),
                section(".bss", 700, Class::Bss),
            ],
            startup: 150,
        };
        assert_eq!(z.flash(), 1024 + 16 + 5000 + 100 + 8);
        assert_eq!(z.ram(), 708);
        // The .data image stays: it is the application's.
        assert_eq!(z.app_flash(), 5000 + 100 + 8 - 150);
    }
}
