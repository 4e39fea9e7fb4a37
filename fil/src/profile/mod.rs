//! Board profiles: what a board's chip looks like to its firmware apart from the CPU core
//! and the CAN controllers — memory map, system registers with their reset values and
//! rules (clock generator, clock gates, watchdog), CAN instances and interrupt numbers.
//!
//! A profile answers every access in the peripheral space with [`Access`]: a register it
//! knows (with the manual's behaviour), a register of a known peripheral it does not know
//! (reported, behaves as plain storage so that the run goes on), an access to a gated
//! peripheral or to unmapped space (a bus error, which the core turns into a fault).

pub mod imxrt1062;
pub mod kinetis;
pub mod stm32_rcc;
pub mod stm32f1;
pub mod stm32f4;
pub mod stm32f7;

use std::collections::HashMap;

/// A memory region of the chip (flash or RAM).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Memory {
    /// Name in reports.
    pub name: &'static str,
    /// First address.
    pub base: u32,
    /// Size in bytes (a multiple of 4 KiB).
    pub size: u32,
    /// Writable (RAM) or not (flash).
    pub writable: bool,
    /// Where the ELF's load image is copied, if this region aliases another (the
    /// STM32F7's flash seen at 0x0020_0000 through the ITCM interface).
    pub alias_of: Option<u32>,
}

/// Where the core starts, as a boot ROM leaves it (chips whose ROM reads a boot image
/// instead of the core reading a vector table at its reset VTOR).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Boot {
    /// Initial main stack pointer.
    pub sp: u32,
    /// First instruction (Thumb bit set or not).
    pub pc: u32,
    /// VTOR as the ROM leaves it.
    pub vtor: u32,
}

/// The family of CAN controller of an instance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CanKind {
    /// NXP FlexCAN of a Kinetis or i.MX RT chip.
    FlexCan(twocan_flexcan::model::Chip),
    /// ST bxCAN: CAN1 (master of the filter block) or CAN2.
    BxCan {
        /// 1 or 2.
        instance: u8,
        /// The chip's bxCAN facts (bank count, instances sharing a filter block).
        part: &'static twocan_bxcan::model::Part,
    },
}

/// The bxCAN instances `numbers` (1 = CAN1, ...) of `part` as CAN instances of a board: their
/// windows, `RCC_APB1ENR` clock gates and interrupt lines from the part descriptor. CAN2
/// also needs CAN1's clock: CAN1 is the master that holds the filters and the message SRAM
/// CAN2 works through (RM0390 §30.2, RM0008 §24.2 "Dual CAN").
pub fn bxcan_instances(
    part: &'static twocan_bxcan::model::Part,
    numbers: &[u8],
) -> Vec<CanInstance> {
    use twocan_bxcan::regs::Instance;
    let can1_bit = part
        .instance(Instance::Can1)
        .map_or(0, |c| 1u32 << c.apb1enr_bit);
    part.instances
        .iter()
        .zip(1u8..)
        .filter(|(_, n)| numbers.contains(n))
        .map(|(c, n)| CanInstance {
            name: c.name,
            base: c.base,
            size: 0x400,
            gate: (
                part.rcc_apb1enr,
                (1u32 << c.apb1enr_bit)
                    | if c.instance == Instance::Can2 {
                        can1_bit
                    } else {
                        0
                    },
            ),
            kind: CanKind::BxCan { instance: n, part },
            irqs: c
                .irqs
                .iter()
                .map(|(name, line)| (*name, u32::from(*line)))
                .collect(),
        })
        .collect()
}

/// A CAN controller of the chip.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CanInstance {
    /// Name in reports (`CAN0`, `CAN1`, ...).
    pub name: &'static str,
    /// Register base address.
    pub base: u32,
    /// Size of the register window.
    pub size: u32,
    /// The clock gate: register address and bit mask.
    pub gate: (u32, u32),
    /// Controller family.
    pub kind: CanKind,
    /// Interrupt numbers of the controller's lines, in the order of [`crate::can::Model::lines`].
    pub irqs: Vec<(&'static str, u32)>,
}

/// The outcome of an access to the peripheral space.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Access {
    /// A register the profile models; the value read (0 for writes).
    Known(u32),
    /// A known peripheral, a register the profile does not model: reported.
    Unknown {
        /// The peripheral.
        peripheral: &'static str,
    },
    /// A peripheral whose bus clock is gated: bus error.
    Gated {
        /// The peripheral.
        peripheral: &'static str,
        /// The gate register's name and bit.
        gate: &'static str,
    },
    /// Nothing at this address: bus error.
    Unmapped,
    /// The access makes the chip reset (e.g. a watchdog unlock sequence violated).
    Reset(String),
}

/// Context a profile's register rules may need.
#[derive(Debug, Clone, Copy, Default)]
pub struct Ctx {
    /// Core clock cycles since reset.
    pub cycles: u64,
}

/// A board as seen by the harness.
pub trait Profile {
    /// Board name (`teensy36`, `nucleo-f767zi`, ...).
    fn name(&self) -> &'static str;
    /// Unicorn CPU model (`UC_CPU_ARM_CORTEX_M4`/`M7`).
    fn cpu_model(&self) -> i32;
    /// Flash and RAM regions.
    fn memory(&self) -> Vec<Memory>;
    /// Where the vector table is at reset (VTOR's reset value, after the boot aliasing).
    fn boot_address(&self) -> u32;
    /// What a boot ROM does before the firmware runs, read from the loaded image
    /// (`read` gives a word of target memory): `Ok(None)` where the core starts from the
    /// vector table at [`Profile::boot_address`] (ARMv7-M B1.5.5), `Err` with the reason
    /// where the ROM would refuse the image (the board then halts).
    fn boot(&self, read: &dyn Fn(u32) -> Option<u32>) -> Result<Option<Boot>, String> {
        let _ = read;
        Ok(None)
    }
    /// Number of external interrupts.
    fn irq_count(&self) -> u32;
    /// Whether the core maps the peripheral bit-band alias (0x4200_0000..0x4400_0000 onto
    /// 0x4000_0000..0x4010_0000, one word per bit: ARMv7-M ARM §B3.1 "bit-banding", an
    /// option of the Cortex-M3/M4 that the STM32F1/F4 implement, RM0008 §3.3.2, RM0390
    /// §2.2.5; the Cortex-M7 has none). The HALs of those families set RCC enable and
    /// reset bits through it.
    fn peripheral_bit_band(&self) -> bool {
        false
    }
    /// Implemented NVIC priority bits.
    fn priority_bits(&self) -> u8 {
        4
    }
    /// The CAN controllers.
    fn can_instances(&self) -> Vec<CanInstance>;
    /// A read of `size` bytes at `addr` in the peripheral space (not a CAN window).
    fn read(&mut self, addr: u32, size: usize, ctx: Ctx) -> Access;
    /// A write of `size` bytes at `addr` in the peripheral space (not a CAN window).
    fn write(&mut self, addr: u32, size: usize, value: u32, ctx: Ctx) -> Access;
    /// Whether an access to a peripheral whose clock is gated ends in a bus error (Kinetis:
    /// "an attempt to access a gated module's registers generates an error termination",
    /// SIM chapter) or is answered without one (STM32: reads as 0, writes ignored). The
    /// harness reports both as faults of the firmware.
    fn gated_access_is_bus_error(&self) -> bool;
    /// Whether the clock gate `(register, mask)` is open.
    fn gate_open(&self, gate: (u32, u32)) -> bool;
    /// Name of a gate for reports.
    fn gate_name(&self, gate: (u32, u32)) -> &'static str;
    /// The core clock now (Hz).
    fn core_hz(&self) -> u64;
    /// The clock of a CAN instance's protocol engine now (Hz), for decoding its bit timing.
    fn can_clock_hz(&self, can: &CanInstance) -> u64;
    /// The peripheral (bus) clock a FlexCAN takes with `CTRL1[CLKSRC]` = 1 (Hz).
    fn can_bus_clock_hz(&self, can: &CanInstance) -> u64 {
        let _ = can;
        self.core_hz()
    }
    /// Whether the protocol engine of `can` has a clock now (`clksrc`: its
    /// `CTRL1[CLKSRC]`). Without one no mode handshake of the controller completes.
    fn can_engine_clocked(&self, can: &CanInstance, clksrc: bool) -> bool {
        let _ = (can, clksrc);
        true
    }
    /// Whether the pins of `can` are routed to it (pad multiplexing, input selection);
    /// `Err` with what is missing. Checked when the controller joins the bus.
    fn can_pins(&self, can: &CanInstance) -> Result<(), String> {
        let _ = can;
        Ok(())
    }
    /// SysTick's external reference divider from the core clock (`CSR.CLKSOURCE = 0`),
    /// `None` where the chip has none.
    fn systick_external_divider(&self) -> Option<u64>;
    /// Findings the register rules made (violations of the manual's sequences).
    fn take_findings(&mut self) -> Vec<String>;
    /// The core cycle at which the chip resets by itself (a watchdog), and why.
    fn reset_deadline(&self) -> Option<(u64, String)> {
        None
    }
    /// A CAN controller joined the bus (left initialization mode, not in internal loop
    /// back): the profile may check what the chip needs for it outside the controller
    /// (pins, alternate functions) and report findings through [`Profile::take_findings`].
    fn can_joined(&mut self, _can: &CanInstance) {}
}

/// Byte-addressed storage for registers a profile keeps as plain values, with sub-word
/// access (8/16/32 bits, little-endian).
#[derive(Debug, Clone, Default)]
pub struct RegStore {
    words: HashMap<u32, u32>,
}

impl RegStore {
    /// Sets a word (aligned address).
    pub fn set(&mut self, addr: u32, value: u32) {
        self.words.insert(addr & !3, value);
    }

    /// The word at an aligned address (0 if never written).
    pub fn get(&self, addr: u32) -> u32 {
        self.words.get(&(addr & !3)).copied().unwrap_or(0)
    }

    /// Reads `size` bytes at `addr`.
    pub fn read(&self, addr: u32, size: usize) -> u32 {
        extract(self.get(addr), addr, size)
    }

    /// Writes `size` bytes at `addr`.
    pub fn write(&mut self, addr: u32, size: usize, value: u32) {
        let w = insert(self.get(addr), addr, size, value);
        self.set(addr, w);
    }
}

/// The `size` bytes at `addr` of the aligned word `word`.
pub fn extract(word: u32, addr: u32, size: usize) -> u32 {
    let shift = (addr & 3) * 8;
    let v = word >> shift;
    match size {
        1 => v & 0xFF,
        2 => v & 0xFFFF,
        _ => v,
    }
}

/// `word` with the `size` bytes at `addr` replaced by `value`.
pub fn insert(word: u32, addr: u32, size: usize, value: u32) -> u32 {
    let shift = (addr & 3) * 8;
    let mask: u32 = match size {
        1 => 0xFF,
        2 => 0xFFFF,
        _ => return value,
    };
    (word & !(mask << shift)) | ((value & mask) << shift)
}

/// The profile of a board name, as the CLI spells it.
pub fn by_name(name: &str) -> Option<Box<dyn Profile>> {
    match name {
        "teensy32" => Some(Box::new(kinetis::Kinetis::new(kinetis::Chip::K20))),
        "teensy35" => Some(Box::new(kinetis::Kinetis::new(kinetis::Chip::K64))),
        "teensy36" => Some(Box::new(kinetis::Kinetis::new(kinetis::Chip::K66))),
        "nucleo-f767zi" => Some(Box::new(stm32f7::Stm32f7::new(stm32f7::Chip::F767))),
        "disco-f746g" => Some(Box::new(stm32f7::Stm32f7::new(stm32f7::Chip::F746))),
        "bluepill" => Some(Box::new(stm32f1::Stm32f1::new())),
        "nucleo-f446re" => Some(Box::new(stm32f4::Stm32f4::new())),
        "teensy41" => Some(Box::new(imxrt1062::Imxrt1062::new())),
        _ => None,
    }
}

/// Every board name [`by_name`] knows.
pub const BOARDS: [&str; 8] = [
    "teensy32",
    "teensy35",
    "teensy36",
    "nucleo-f767zi",
    "disco-f746g",
    "bluepill",
    "nucleo-f446re",
    "teensy41",
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sub_word_access() {
        let mut s = RegStore::default();
        s.write(0x4006_4001, 1, 0xA5);
        assert_eq!(s.get(0x4006_4000), 0x0000_A500);
        s.write(0x4005_200E, 2, 0xC520);
        assert_eq!(s.read(0x4005_200E, 2), 0xC520);
        assert_eq!(s.read(0x4005_200C, 4), 0xC520_0000);
        for b in BOARDS {
            assert_eq!(by_name(b).map(|p| p.name()), Some(b));
        }
        assert!(by_name("teensy40").is_none());
    }
}
