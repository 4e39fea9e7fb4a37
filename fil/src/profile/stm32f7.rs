//! STM32F767ZI (NUCLEO-F767ZI) and STM32F746NG (32F746G-DISCO): the system registers the
//! start-up code uses, as rules.
//!
//! Sources: RM0410 (STM32F76xxx/77xxx) and RM0385 (STM32F75xxx/74xxx) — §2 "Memory
//! and bus architecture" (memory map, boot aliasing), §3 "Embedded Flash memory"
//! (`FLASH_ACR` wait states), §4 "Power controller" (`PWR_CR1.VOS`, `PWR_CSR1`), §5
//! "Reset and clock control" (`RCC_CR`, `RCC_PLLCFGR`, `RCC_CFGR`, enable registers), §6
//! "GPIO"; the boards' user manuals UM1974 (NUCLEO-144: HSE = 8 MHz from the ST-LINK in
//! bypass) and UM1907 (32F746G-DISCO: 25 MHz crystal).
//!
//! The rules of the RCC, flash, PWR, SYSCFG and GPIO registers are those of
//! [`super::stm32_rcc`] (the F4 and F7 share the layout), with the F7's limits: a PLL P
//! output and HCLK of at most 216 MHz (180 MHz without over-drive, RM0410 §4.1.4), APB1 at
//! most 54 MHz and APB2 at most 108 MHz. CAN1/CAN2 are gated by `RCC_APB1ENR` bits 25/26
//! (the [`twocan_bxcan::model::part::STM32F76X_F77X`] descriptor).

use twocan_bxcan::model::part;

use super::stm32_rcc::{Limits, SystemRegs, RCC_AHB1ENR, RCC_APB1ENR, RCC_APB2ENR};
#[cfg(test)]
use super::stm32_rcc::{RCC_CFGR, RCC_CR, RCC_PLLCFGR};
use super::{Access, CanInstance, Ctx, Memory, Profile};

/// The two chips.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Chip {
    /// STM32F767ZI on the NUCLEO-F767ZI.
    F767,
    /// STM32F746NG on the 32F746G-DISCO.
    F746,
}

/// The F7 limits (RM0410 §5.3.2, §3.3.2 Table 7; datasheet operating conditions), with the
/// board's HSE: 8 MHz from the ST-LINK in bypass (UM1974) or a 25 MHz crystal (UM1907).
const fn limits(hse_hz: u64, hse_bypass: bool) -> Limits {
    Limits {
        manual: "RM0410",
        hse_hz,
        hse_bypass,
        pll_p_max: 216_000_000,
        pll_r_sysclk: false,
        hclk_max: 216_000_000,
        hclk_max_without_overdrive: 180_000_000,
        apb1_max: 54_000_000,
        apb2_max: 108_000_000,
        gpio_ports: 11,
        rcc_last: 0x90,
    }
}
static F767_LIMITS: Limits = limits(8_000_000, true);
static F746_LIMITS: Limits = limits(25_000_000, false);

/// An STM32F7 chip on its board.
#[derive(Debug, Clone)]
pub struct Stm32f7 {
    chip: Chip,
    sys: SystemRegs,
}

impl Stm32f7 {
    /// The chip out of power-on reset.
    pub fn new(chip: Chip) -> Self {
        let limits = match chip {
            Chip::F767 => &F767_LIMITS,
            Chip::F746 => &F746_LIMITS,
        };
        Stm32f7 {
            chip,
            sys: SystemRegs::new(limits),
        }
    }

    /// APB1 clock now (bxCAN's clock).
    pub fn pclk1(&self) -> u64 {
        self.sys.pclk1()
    }

    fn part(&self) -> &'static twocan_bxcan::model::Part {
        match self.chip {
            Chip::F767 => &part::STM32F76X_F77X,
            Chip::F746 => &part::STM32F74X_F75X,
        }
    }
}

/// Names of the F7's clock gates.
fn gate_name(gate: (u32, u32)) -> &'static str {
    match gate {
        (RCC_APB1ENR, m) if m == 1 << 25 => "RCC_APB1ENR.CAN1EN",
        (RCC_APB1ENR, m) if m == 1 << 26 => "RCC_APB1ENR.CAN2EN",
        (RCC_APB1ENR, _) => "RCC_APB1ENR.PWREN",
        (RCC_APB2ENR, _) => "RCC_APB2ENR.SYSCFGEN",
        (RCC_AHB1ENR, _) => "RCC_AHB1ENR.GPIOxEN",
        _ => "?",
    }
}

impl Profile for Stm32f7 {
    fn name(&self) -> &'static str {
        match self.chip {
            Chip::F767 => "nucleo-f767zi",
            Chip::F746 => "disco-f746g",
        }
    }

    fn cpu_model(&self) -> i32 {
        unicorn_engine::ArmCpuModel::CORTEX_M7 as i32
    }

    fn memory(&self) -> Vec<Memory> {
        let (flash, ram_end) = match self.chip {
            Chip::F767 => (2048 << 10, 0x2008_0000),
            Chip::F746 => (1024 << 10, 0x2005_0000),
        };
        vec![
            Memory {
                name: "ITCM RAM",
                base: 0,
                size: 16 << 10,
                writable: true,
                alias_of: None,
            },
            Memory {
                name: "flash (ITCM)",
                base: 0x0020_0000,
                size: flash,
                writable: false,
                alias_of: Some(0x0800_0000),
            },
            Memory {
                name: "flash (AXIM)",
                base: 0x0800_0000,
                size: flash,
                writable: false,
                alias_of: None,
            },
            Memory {
                name: "DTCM + SRAM1 + SRAM2",
                base: 0x2000_0000,
                size: ram_end - 0x2000_0000,
                writable: true,
                alias_of: None,
            },
        ]
    }

    fn boot_address(&self) -> u32 {
        // BOOT0 = 0, BOOT_ADD0 = 0x0080 (factory): flash on the ITCM interface. VTOR
        // resets to it; the image is linked at the AXIM address 0x0800_0000.
        0x0020_0000
    }

    fn irq_count(&self) -> u32 {
        match self.chip {
            Chip::F767 => 110,
            Chip::F746 => 98,
        }
    }

    fn can_instances(&self) -> Vec<CanInstance> {
        // CAN1 and CAN2 (CAN3 of the F767 is not routed: its own block, another window).
        super::bxcan_instances(self.part(), &[1, 2])
    }

    fn read(&mut self, addr: u32, size: usize, _ctx: Ctx) -> Access {
        let names = |g| gate_name(g);
        self.sys.read(addr, size, names).unwrap_or(Access::Unmapped)
    }

    fn write(&mut self, addr: u32, size: usize, value: u32, _ctx: Ctx) -> Access {
        let names = |g| gate_name(g);
        self.sys
            .write(addr, size, value, names)
            .unwrap_or(Access::Unmapped)
    }

    fn gated_access_is_bus_error(&self) -> bool {
        false
    }

    fn gate_open(&self, gate: (u32, u32)) -> bool {
        self.sys.gate_open(gate)
    }

    fn gate_name(&self, gate: (u32, u32)) -> &'static str {
        gate_name(gate)
    }

    fn core_hz(&self) -> u64 {
        self.sys.hclk()
    }

    fn can_clock_hz(&self, _can: &CanInstance) -> u64 {
        self.pclk1()
    }

    fn systick_external_divider(&self) -> Option<u64> {
        Some(8) // HCLK / 8 (RM0410 Figure 13, clock tree)
    }

    fn take_findings(&mut self) -> Vec<String> {
        self.sys.take_findings()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(s: &mut Stm32f7, a: u32, v: u32) {
        s.write(a, 4, v, Ctx::default());
    }
    fn r(s: &mut Stm32f7, a: u32) -> u32 {
        match s.read(a, 4, Ctx::default()) {
            Access::Known(v) => v,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn hse_needs_the_board_source_and_pll_its_limits() {
        let mut s = Stm32f7::new(Chip::F767);
        w(&mut s, RCC_CR, 0x83 | (1 << 16));
        assert_eq!(r(&mut s, RCC_CR) & (1 << 17), 0, "NUCLEO HSE needs bypass");
        w(&mut s, RCC_CR, 0x83 | (1 << 16) | (1 << 18));
        assert_ne!(r(&mut s, RCC_CR) & (1 << 17), 0);
        // 8 MHz / 4 = 2 MHz, × 216 = 432 MHz, / 2 = 216 MHz: inside the limits.
        let cfg = 4 | (216 << 6) | (1 << 22);
        w(&mut s, RCC_PLLCFGR, cfg);
        w(&mut s, RCC_CR, 0x83 | (1 << 16) | (1 << 18) | (1 << 24));
        assert_ne!(r(&mut s, RCC_CR) & (1 << 25), 0);
        // PLLM = 2: VCO input 4 MHz, out of range: no lock.
        let mut s2 = Stm32f7::new(Chip::F767);
        w(&mut s2, RCC_CR, 0x83 | (1 << 16) | (1 << 18));
        w(&mut s2, RCC_PLLCFGR, 2 | (100 << 6) | (1 << 22));
        w(&mut s2, RCC_CR, 0x83 | (1 << 16) | (1 << 18) | (1 << 24));
        assert_eq!(r(&mut s2, RCC_CR) & (1 << 25), 0);
        w(&mut s2, RCC_CFGR, 2);
        assert_eq!((r(&mut s2, RCC_CFGR) >> 2) & 3, 0, "SWS stays on HSI");
        // Switch to the 216 MHz PLL with 0 wait states: reported.
        w(&mut s, RCC_CFGR, 2);
        assert_eq!((r(&mut s, RCC_CFGR) >> 2) & 3, 2);
        assert_eq!(s.core_hz(), 216_000_000);
        assert!(s.take_findings().iter().any(|f| f.contains("LATENCY")));
    }

    #[test]
    fn gates() {
        let mut s = Stm32f7::new(Chip::F746);
        assert!(matches!(
            s.read(0x4002_0400, 4, Ctx::default()),
            Access::Gated { .. }
        ));
        w(&mut s, RCC_AHB1ENR, 1 << 1);
        assert_eq!(r(&mut s, 0x4002_0400), 0x0000_0280);
        assert!(!s.gate_open((RCC_APB1ENR, 1 << 25)));
        assert_eq!(s.read(0x4000_0000, 4, Ctx::default()), Access::Unmapped);
    }
}
