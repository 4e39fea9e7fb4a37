//! The firmware image: loadable segments (at their load addresses), symbols with
//! demangled names, and the addresses of `WFI` instructions.

use object::{Object, ObjectSection, ObjectSegment, ObjectSymbol, SectionKind};

/// A loadable segment.
#[derive(Debug, Clone)]
pub struct Segment {
    /// Load (physical) address.
    pub address: u32,
    /// Contents.
    pub data: Vec<u8>,
}

/// A symbol.
#[derive(Debug, Clone)]
pub struct Symbol {
    /// Demangled name without the hash (`teensy_loopback::firmware::SENT`).
    pub name: String,
    /// Address.
    pub address: u32,
    /// Size in bytes.
    pub size: u64,
    /// A data object (a static), not code.
    pub is_data: bool,
}

/// A loaded ELF.
#[derive(Debug, Clone)]
pub struct Image {
    /// Path it came from.
    pub path: String,
    /// Segments to load.
    pub segments: Vec<Segment>,
    /// Data and function symbols.
    pub symbols: Vec<Symbol>,
    /// The `defmt` table (from the `.defmt` section and the symbols), when the firmware
    /// logs with `defmt`.
    pub defmt: Option<defmt_decoder::Table>,
    /// Addresses of `WFI` (0xBF30) at instruction boundaries of the code sections'
    /// halfwords; the harness hooks them (a hook fires only where an instruction starts).
    pub wfi_sites: Vec<u32>,
    /// Addresses of `WFE` (0xBF20), found the same way.
    pub wfe_sites: Vec<u32>,
    /// Addresses of `SEV` (0xBF40), found the same way.
    pub sev_sites: Vec<u32>,
}

impl Image {
    /// Reads an ELF file.
    pub fn load(path: &str) -> Result<Image, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("{path}: {e}"))?;
        Self::parse(path, &bytes)
    }

    /// Parses ELF bytes.
    pub fn parse(path: &str, bytes: &[u8]) -> Result<Image, String> {
        let file = object::File::parse(bytes).map_err(|e| format!("{path}: {e}"))?;
        if file.architecture() != object::Architecture::Arm {
            return Err(format!("{path}: not an ARM ELF"));
        }
        let mut segments = Vec::new();
        // Load addresses: program headers' p_paddr (initialised data is copied from its
        // load address by the start-up code).
        if let object::File::Elf32(elf) = &file {
            use object::read::elf::ProgramHeader;
            let endian = elf.endian();
            for ph in elf.elf_program_headers() {
                if ph.p_type(endian) != object::elf::PT_LOAD {
                    continue;
                }
                let data = ph
                    .data(endian, bytes)
                    .map_err(|_| format!("{path}: bad segment"))?;
                if data.is_empty() {
                    continue;
                }
                segments.push(Segment {
                    address: ph.p_paddr(endian),
                    data: data.to_vec(),
                });
            }
        } else {
            for seg in file.segments() {
                let data = seg.data().map_err(|e| e.to_string())?;
                if !data.is_empty() {
                    segments.push(Segment {
                        address: seg.address() as u32,
                        data: data.to_vec(),
                    });
                }
            }
        }
        let symbols = file
            .symbols()
            .filter_map(|s| {
                let raw = s.name().ok()?;
                let name = format!("{:#}", rustc_demangle::demangle(raw));
                Some(Symbol {
                    name,
                    address: s.address() as u32,
                    size: s.size(),
                    is_data: s.kind() == object::SymbolKind::Data,
                })
            })
            .collect();
        let mut wfi_sites = Vec::new();
        let mut wfe_sites = Vec::new();
        let mut sev_sites = Vec::new();
        for sec in file.sections() {
            if sec.kind() != SectionKind::Text {
                continue;
            }
            let Ok(data) = sec.data() else { continue };
            let base = sec.address() as u32;
            // Walk Thumb-2 instruction boundaries: a halfword whose top five bits are
            // 0b11101, 0b11110 or 0b11111 starts a 32-bit instruction.
            let mut i = 0;
            while i + 1 < data.len() {
                let hw = u16::from_le_bytes([data[i], data[i + 1]]);
                match hw {
                    0xBF30 => wfi_sites.push(base + i as u32),
                    0xBF20 => wfe_sites.push(base + i as u32),
                    0xBF40 => sev_sites.push(base + i as u32),
                    _ => {}
                }
                i += if hw >> 11 >= 0b11101 { 4 } else { 2 };
            }
        }
        // defmt-decoder checks that the firmware's defmt wire format is one it knows.
        let defmt = if file.section_by_name(".defmt").is_some() {
            defmt_decoder::Table::parse(bytes).map_err(|e| format!("{path}: defmt table: {e}"))?
        } else {
            None
        };
        Ok(Image {
            path: path.to_string(),
            segments,
            symbols,
            defmt,
            wfi_sites,
            wfe_sites,
            sev_sites,
        })
    }

    /// The function symbol containing `address` (Thumb bit ignored), for reports.
    pub fn function_at(&self, address: u32) -> Option<&Symbol> {
        self.symbols.iter().find(|s| {
            let start = s.address & !1;
            s.size > 0 && address >= start && u64::from(address - start) < s.size
        })
    }

    /// The symbol named `suffix` or whose demangled path ends with `::suffix`
    /// (`SENT` finds `teensy_loopback::firmware::SENT`), data objects first.
    pub fn symbol(&self, suffix: &str) -> Option<&Symbol> {
        let tail = format!("::{suffix}");
        let matches = |s: &&Symbol| s.name == suffix || s.name.ends_with(&tail);
        self.symbols
            .iter()
            .filter(matches)
            .find(|s| s.is_data)
            .or_else(|| self.symbols.iter().find(matches))
    }
}
