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
//! Rules modelled:
//! - `HSIRDY` follows `HSION` (on-chip RC). `HSERDY` follows `HSEON` only when `HSEBYP`
//!   matches the board's source: an external clock signal needs bypass, a crystal needs
//!   the oscillator.
//! - `PLLRDY` follows `PLLON` only when the PLL source is ready and the configuration is
//!   inside the limits of §5.3.2: PLLM 2…63 with a VCO input of 1–2 MHz, PLLN 50…432
//!   with a VCO output of 100–432 MHz, a P output at most 216 MHz. Writing `PLLCFGR`
//!   while the PLL is on is reported (the manual: "only when the PLL is disabled").
//! - `SWS` follows `SW` only when the selected clock is ready; switching to a SYSCLK
//!   faster than `FLASH_ACR.LATENCY` allows (Table 7, 2.7–3.6 V: 30 MHz per wait state)
//!   and an APB1 above 54 MHz / APB2 above 108 MHz are reported.
//! - Enable registers gate the peripherals: GPIOx (`AHB1ENR`), PWR and CAN1/CAN2
//!   (`APB1ENR`), SYSCFG (`APB2ENR`). A gated STM32 peripheral raises no bus error: it
//!   reads as zero and ignores writes, so the core goes on; the harness records the
//!   access as a fault of the firmware all the same (it never works on the board).

use super::{Access, CanInstance, CanKind, Ctx, Memory, Profile, RegStore};

/// The two chips.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Chip {
    /// STM32F767ZI on the NUCLEO-F767ZI.
    F767,
    /// STM32F746NG on the 32F746G-DISCO.
    F746,
}

const HSI_HZ: u64 = 16_000_000;

const RCC: u32 = 0x4002_3800;
const RCC_CR: u32 = RCC;
const RCC_PLLCFGR: u32 = RCC + 0x04;
const RCC_CFGR: u32 = RCC + 0x08;
const RCC_AHB1ENR: u32 = RCC + 0x30;
const RCC_APB1ENR: u32 = RCC + 0x40;
const RCC_APB2ENR: u32 = RCC + 0x44;
const FLASH_ACR: u32 = 0x4002_3C00;
const PWR: u32 = 0x4000_7000;
const GPIOA: u32 = 0x4002_0000;
const SYSCFG: u32 = 0x4001_3800;

/// An STM32F7 chip on its board.
#[derive(Debug, Clone)]
pub struct Stm32f7 {
    chip: Chip,
    regs: RegStore,
    findings: Vec<String>,
}

impl Stm32f7 {
    /// The chip out of power-on reset.
    pub fn new(chip: Chip) -> Self {
        let mut regs = RegStore::default();
        regs.set(RCC_CR, 0x0000_0083); // HSION, HSIRDY, HSITRIM = 16
        regs.set(RCC_PLLCFGR, 0x2400_3010);
        regs.set(RCC_AHB1ENR, 0x0010_0000); // DTCMRAMEN
        regs.set(RCC + 0x70, 0); // BDCR
        regs.set(RCC + 0x74, 0x0E00_0000); // CSR: reset flags
        regs.set(PWR, 0x0000_C000); // CR1: VOS = scale 1
                                    // GPIO reset values (§6.4): MODER A/B have the debug pins in AF.
        regs.set(GPIOA, 0xA800_0000);
        regs.set(GPIOA + 0x400, 0x0000_0280);
        regs.set(GPIOA + 0x0C, 0x6400_0000);
        regs.set(GPIOA + 0x400 + 0x0C, 0x0000_0100);
        regs.set(GPIOA + 0x08, 0x0C00_0000);
        regs.set(GPIOA + 0x400 + 0x08, 0x0000_00C0);
        Stm32f7 {
            chip,
            regs,
            findings: Vec::new(),
        }
    }

    /// The board's HSE: frequency and whether it is an external clock (bypass).
    fn hse(&self) -> (u64, bool) {
        match self.chip {
            Chip::F767 => (8_000_000, true),
            Chip::F746 => (25_000_000, false),
        }
    }

    fn hse_ready(&self) -> bool {
        let cr = self.regs.get(RCC_CR);
        let on = cr & (1 << 16) != 0;
        let bypass = cr & (1 << 18) != 0;
        on && bypass == self.hse().1
    }

    /// PLL output P (Hz) if its configuration is within limits and its source runs.
    fn pll_p(&self) -> Option<u64> {
        let cfg = self.regs.get(RCC_PLLCFGR);
        let m = u64::from(cfg & 0x3F);
        let n = u64::from((cfg >> 6) & 0x1FF);
        let p = 2 * (u64::from((cfg >> 16) & 3) + 1);
        let hse_src = cfg & (1 << 22) != 0;
        let (src, ready) = if hse_src {
            (self.hse().0, self.hse_ready())
        } else {
            (HSI_HZ, self.regs.get(RCC_CR) & 1 != 0)
        };
        if !ready || !(2..=63).contains(&m) || !(50..=432).contains(&n) {
            return None;
        }
        let vin = src / m;
        let vco = vin * n;
        let out = vco / p;
        ((1_000_000..=2_000_000).contains(&vin)
            && (100_000_000..=432_000_000).contains(&vco)
            && out <= 216_000_000)
            .then_some(out)
    }

    fn pll_ready(&self) -> bool {
        self.regs.get(RCC_CR) & (1 << 24) != 0 && self.pll_p().is_some()
    }

    fn source_ready(&self, sw: u32) -> bool {
        match sw {
            0 => self.regs.get(RCC_CR) & 1 != 0,
            1 => self.hse_ready(),
            2 => self.pll_ready(),
            _ => false,
        }
    }

    fn sysclk_of(&self, sws: u32) -> u64 {
        match sws {
            1 => self.hse().0,
            2 => self.pll_p().unwrap_or(HSI_HZ),
            _ => HSI_HZ,
        }
    }

    fn sysclk(&self) -> u64 {
        self.sysclk_of((self.regs.get(RCC_CFGR) >> 2) & 3)
    }

    fn ahb_div(cfgr: u32) -> u64 {
        let hpre = (cfgr >> 4) & 0xF;
        if hpre < 8 {
            1
        } else {
            [2, 4, 8, 16, 64, 128, 256, 512][(hpre - 8) as usize]
        }
    }

    fn apb_div(bits: u32) -> u64 {
        if bits < 4 {
            1
        } else {
            1 << (bits - 3)
        }
    }

    /// HCLK now.
    fn hclk(&self) -> u64 {
        self.sysclk() / Self::ahb_div(self.regs.get(RCC_CFGR))
    }

    /// APB1 clock now (bxCAN's clock).
    pub fn pclk1(&self) -> u64 {
        self.hclk() / Self::apb_div((self.regs.get(RCC_CFGR) >> 10) & 7)
    }

    /// Recomputes the status bits that follow control bits.
    fn settle(&mut self) {
        let mut cr = self.regs.get(RCC_CR);
        cr = (cr & !(1 << 1)) | ((cr & 1) << 1);
        cr = (cr & !(1 << 17)) | (u32::from(self.hse_ready()) << 17);
        cr = (cr & !(1 << 25)) | (u32::from(self.pll_ready()) << 25);
        self.regs.set(RCC_CR, cr);
        let cfgr = self.regs.get(RCC_CFGR);
        let sw = cfgr & 3;
        let sws = (cfgr >> 2) & 3;
        if sw != sws && self.source_ready(sw) {
            self.regs.set(RCC_CFGR, (cfgr & !(3 << 2)) | (sw << 2));
            self.check_clock_limits();
        }
        // PWR_CSR1.VOSRDY (bit 14) once the regulator runs at the selected scale; the
        // over-drive handshake follows ODEN/ODSWEN when the PLL or HSE/HSI runs.
        let cr1 = self.regs.get(PWR);
        let mut csr1 = self.regs.get(PWR + 4) | (1 << 14);
        csr1 = (csr1 & !(1 << 16)) | (((cr1 >> 16) & 1) << 16);
        csr1 = (csr1 & !(1 << 17)) | (((cr1 >> 17) & 1) << 17);
        self.regs.set(PWR + 4, csr1);
    }

    fn check_clock_limits(&mut self) {
        let hclk = self.hclk();
        let latency = u64::from(self.regs.get(FLASH_ACR) & 0xF);
        let needed = hclk.div_ceil(30_000_000).saturating_sub(1);
        if latency < needed {
            self.findings.push(format!(
                "HCLK {hclk} Hz with FLASH_ACR.LATENCY = {latency}: at least {needed} wait states needed (RM0410 Table 7, 2.7–3.6 V)"
            ));
        }
        let cfgr = self.regs.get(RCC_CFGR);
        let apb1 = hclk / Self::apb_div((cfgr >> 10) & 7);
        let apb2 = hclk / Self::apb_div((cfgr >> 13) & 7);
        if apb1 > 54_000_000 || apb2 > 108_000_000 {
            self.findings.push(format!(
                "APB1 {apb1} Hz / APB2 {apb2} Hz above their maxima (54 / 108 MHz)"
            ));
        }
    }

    fn peripheral(&self, addr: u32) -> Option<(&'static str, Option<(u32, u32)>)> {
        const GPIOS: [&str; 11] = [
            "GPIOA", "GPIOB", "GPIOC", "GPIOD", "GPIOE", "GPIOF", "GPIOG", "GPIOH", "GPIOI",
            "GPIOJ", "GPIOK",
        ];
        if (RCC..RCC + 0x400).contains(&addr) {
            return Some(("RCC", None));
        }
        if (FLASH_ACR..FLASH_ACR + 0x400).contains(&addr) {
            return Some(("FLASH", None));
        }
        if (PWR..PWR + 0x400).contains(&addr) {
            return Some(("PWR", Some((RCC_APB1ENR, 1 << 28))));
        }
        if (SYSCFG..SYSCFG + 0x400).contains(&addr) {
            return Some(("SYSCFG", Some((RCC_APB2ENR, 1 << 14))));
        }
        if (GPIOA..GPIOA + 11 * 0x400).contains(&addr) {
            let n = (addr - GPIOA) / 0x400;
            return Some((GPIOS[n as usize], Some((RCC_AHB1ENR, 1 << n))));
        }
        None
    }

    fn known(&self, name: &str, addr: u32) -> bool {
        let off = addr & 0x3FF & !3;
        match name {
            "RCC" => {
                off <= 0x90
                    && !matches!(
                        off,
                        0x1C | 0x2C | 0x3C | 0x48 | 0x4C | 0x5C | 0x68 | 0x6C | 0x78 | 0x7C
                    )
            }
            "FLASH" => off <= 0x1C,
            "PWR" => off <= 0x1C,
            "SYSCFG" => off <= 0x20,
            _ if name.starts_with("GPIO") => off <= 0x24,
            _ => false,
        }
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
        let can1 = CanInstance {
            name: "CAN1",
            base: 0x4000_6400,
            size: 0x400,
            gate: (RCC_APB1ENR, 1 << 25),
            kind: CanKind::BxCan { instance: 1 },
            irqs: vec![("TX", 19), ("RX0", 20), ("RX1", 21), ("SCE", 22)],
        };
        let can2 = CanInstance {
            name: "CAN2",
            base: 0x4000_6800,
            size: 0x400,
            gate: (RCC_APB1ENR, 1 << 26),
            kind: CanKind::BxCan { instance: 2 },
            irqs: vec![("TX", 63), ("RX0", 64), ("RX1", 65), ("SCE", 66)],
        };
        vec![can1, can2]
    }

    fn read(&mut self, addr: u32, size: usize, _ctx: Ctx) -> Access {
        let Some((name, gate)) = self.peripheral(addr) else {
            return Access::Unmapped;
        };
        if let Some(g) = gate {
            if !self.gate_open(g) {
                return Access::Gated {
                    peripheral: name,
                    gate: self.gate_name(g),
                };
            }
        }
        self.settle();
        let v = self.regs.read(addr, size);
        if self.known(name, addr) {
            Access::Known(v)
        } else {
            Access::Unknown { peripheral: name }
        }
    }

    fn write(&mut self, addr: u32, size: usize, value: u32, _ctx: Ctx) -> Access {
        let Some((name, gate)) = self.peripheral(addr) else {
            return Access::Unmapped;
        };
        if let Some(g) = gate {
            if !self.gate_open(g) {
                return Access::Gated {
                    peripheral: name,
                    gate: self.gate_name(g),
                };
            }
        }
        let known = self.known(name, addr);
        let w = addr & !3;
        if w == RCC_PLLCFGR && self.regs.get(RCC_CR) & (1 << 24) != 0 {
            let old = self.regs.get(RCC_PLLCFGR);
            let new = super::insert(old, addr, size, value);
            if new != old {
                self.findings
                    .push("RCC_PLLCFGR changed while PLLON = 1 (RM0410 §5.3.2)".into());
            }
        }
        if name.starts_with("GPIO") && (w & 0x3FF) == 0x18 {
            // BSRR: set bits 0–15, reset bits 16–31 of ODR (write-only).
            let v = super::insert(0, addr, size, value);
            let odr = w - 0x18 + 0x14;
            let cur = self.regs.get(odr);
            self.regs.set(odr, (cur | (v & 0xFFFF)) & !(v >> 16));
        } else if w == RCC_CFGR {
            // SWS (bits 3:2) is read-only.
            let sws = self.regs.get(RCC_CFGR) & (3 << 2);
            let new = super::insert(self.regs.get(RCC_CFGR), addr, size, value);
            self.regs.set(RCC_CFGR, (new & !(3 << 2)) | sws);
        } else {
            self.regs.write(addr, size, value);
        }
        self.settle();
        if known {
            Access::Known(0)
        } else {
            Access::Unknown { peripheral: name }
        }
    }

    fn gated_access_is_bus_error(&self) -> bool {
        false
    }

    fn gate_open(&self, gate: (u32, u32)) -> bool {
        self.regs.get(gate.0) & gate.1 != 0
    }

    fn gate_name(&self, gate: (u32, u32)) -> &'static str {
        match gate {
            (RCC_APB1ENR, m) if m == 1 << 25 => "RCC_APB1ENR.CAN1EN",
            (RCC_APB1ENR, m) if m == 1 << 26 => "RCC_APB1ENR.CAN2EN",
            (RCC_APB1ENR, _) => "RCC_APB1ENR.PWREN",
            (RCC_APB2ENR, _) => "RCC_APB2ENR.SYSCFGEN",
            _ => "RCC_AHB1ENR.GPIOxEN",
        }
    }

    fn core_hz(&self) -> u64 {
        self.hclk()
    }

    fn can_clock_hz(&self, _can: &CanInstance) -> u64 {
        self.pclk1()
    }

    fn systick_external_divider(&self) -> Option<u64> {
        Some(8) // HCLK / 8 (RM0410 Figure 13, clock tree)
    }

    fn take_findings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.findings)
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
