//! The system registers the STM32F4 and STM32F7 share — reset and clock control (RCC),
//! flash access control, power controller, SYSCFG and GPIO — as rules, with what differs
//! between chips as data ([`Limits`]). One register layout serves both families: RCC at
//! 0x4002_3800 (`CR`, `PLLCFGR`, `CFGR`, `AHB1ENR` +0x30, `APB1ENR` +0x40, `APB2ENR`
//! +0x44), `FLASH_ACR` at 0x4002_3C00, PWR at 0x4000_7000, SYSCFG at 0x4001_3800, GPIOx
//! from 0x4002_0000 every 0x400.
//!
//! Sources: RM0410 (STM32F76xxx/77xxx) and RM0385 (STM32F75xxx/74xxx) §3 "Embedded Flash
//! memory", §4 "Power controller", §5 "Reset and clock control", §6 "GPIO"; RM0390
//! (STM32F446) §3 "Embedded Flash memory interface", §5 "Power controller", §6 "Reset and
//! clock control", §7 "GPIO"; the datasheets' operating conditions for the clock maxima.
//!
//! Rules modelled:
//! - `HSIRDY` follows `HSION` (on-chip RC). `HSERDY` follows `HSEON` only when `HSEBYP`
//!   matches the board's source: an external clock signal needs bypass, a crystal needs
//!   the oscillator.
//! - `PLLRDY` follows `PLLON` only when the PLL source is ready and the configuration is
//!   inside the limits (RM0410 §5.3.2, RM0390 §6.3.2): PLLM 2…63 with a VCO input of
//!   1–2 MHz, PLLN 50…432 with a VCO output of 100–432 MHz, a P output at most
//!   [`Limits::pll_p_max`]. Writing `PLLCFGR` while the PLL is on is reported (the manual:
//!   "only when the PLL is disabled").
//! - `SWS` follows `SW` only when the selected clock is ready (`SW = 0b11` selects PLL_R
//!   where the chip has it, [`Limits::pll_r_sysclk`]); switching to a SYSCLK faster than
//!   `FLASH_ACR.LATENCY` allows (30 MHz per wait state at 2.7–3.6 V: RM0410 Table 7,
//!   RM0390 Table 5), an HCLK above the chip's maximum or above its maximum without
//!   over-drive while `PWR_CSR.ODSWRDY` = 0 (RM0390 §5.1.4, RM0410 §4.1.4), and an APB1 /
//!   APB2 above their maxima are reported.
//! - `PWR_CSR.VOSRDY` reads 1; `ODRDY`/`ODSWRDY` follow `ODEN`/`ODSWEN` (the regulator's
//!   handshake, without its delay).
//! - Enable registers gate the peripherals: GPIOx (`AHB1ENR`), PWR (`APB1ENR` bit 28),
//!   SYSCFG (`APB2ENR` bit 14). A gated STM32 peripheral raises no bus error: it reads as
//!   zero and ignores writes, so the core goes on; the harness records the access as a
//!   fault of the firmware all the same (it never works on the board).
//! - GPIO registers are storage, except `BSRR` (write-only: sets and resets `ODR` bits).

use super::{Access, RegStore};

/// What differs between the chips of this register layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// The reference manual, for findings.
    pub manual: &'static str,
    /// The board's HSE frequency (Hz).
    pub hse_hz: u64,
    /// Whether the board's HSE is an external clock signal (bypass) rather than a crystal.
    pub hse_bypass: bool,
    /// Highest PLL P output (SYSCLK from the PLL).
    pub pll_p_max: u64,
    /// `RCC_CFGR.SW = 0b11` selects PLL_R as SYSCLK (STM32F446).
    pub pll_r_sysclk: bool,
    /// Highest HCLK.
    pub hclk_max: u64,
    /// Highest HCLK without the over-drive mode.
    pub hclk_max_without_overdrive: u64,
    /// Highest APB1 clock (bxCAN's).
    pub apb1_max: u64,
    /// Highest APB2 clock.
    pub apb2_max: u64,
    /// GPIO ports (A, B, ...).
    pub gpio_ports: u32,
    /// Offset of the last RCC register.
    pub rcc_last: u32,
}

/// The on-chip RC oscillator.
pub const HSI_HZ: u64 = 16_000_000;

/// RCC base.
pub const RCC: u32 = 0x4002_3800;
/// `RCC_CR`.
pub const RCC_CR: u32 = RCC;
/// `RCC_PLLCFGR`.
pub const RCC_PLLCFGR: u32 = RCC + 0x04;
/// `RCC_CFGR`.
pub const RCC_CFGR: u32 = RCC + 0x08;
/// `RCC_AHB1ENR`.
pub const RCC_AHB1ENR: u32 = RCC + 0x30;
/// `RCC_APB1ENR`.
pub const RCC_APB1ENR: u32 = RCC + 0x40;
/// `RCC_APB2ENR`.
pub const RCC_APB2ENR: u32 = RCC + 0x44;
/// `FLASH_ACR`.
pub const FLASH_ACR: u32 = 0x4002_3C00;
/// PWR base (`PWR_CR`/`PWR_CR1`; `PWR_CSR`/`PWR_CSR1` at +4).
pub const PWR: u32 = 0x4000_7000;
/// GPIOA base.
pub const GPIOA: u32 = 0x4002_0000;
/// SYSCFG base.
pub const SYSCFG: u32 = 0x4001_3800;

/// The system registers of one chip.
#[derive(Debug, Clone)]
pub struct SystemRegs {
    limits: &'static Limits,
    /// The register values.
    pub regs: RegStore,
    findings: Vec<String>,
}

impl SystemRegs {
    /// Out of power-on reset.
    pub fn new(limits: &'static Limits) -> Self {
        let mut regs = RegStore::default();
        regs.set(RCC_CR, 0x0000_0083); // HSION, HSIRDY, HSITRIM = 16
        regs.set(RCC_PLLCFGR, 0x2400_3010);
        regs.set(RCC_AHB1ENR, 0x0010_0000);
        regs.set(RCC + 0x70, 0); // BDCR
        regs.set(RCC + 0x74, 0x0E00_0000); // CSR: reset flags
        regs.set(PWR, 0x0000_C000); // VOS = scale 1
                                    // GPIO reset values: MODER, PUPDR, OSPEEDR of ports A and B have the debug pins.
        regs.set(GPIOA, 0xA800_0000);
        regs.set(GPIOA + 0x400, 0x0000_0280);
        regs.set(GPIOA + 0x0C, 0x6400_0000);
        regs.set(GPIOA + 0x400 + 0x0C, 0x0000_0100);
        regs.set(GPIOA + 0x08, 0x0C00_0000);
        regs.set(GPIOA + 0x400 + 0x08, 0x0000_00C0);
        SystemRegs {
            limits,
            regs,
            findings: Vec::new(),
        }
    }

    fn hse_ready(&self) -> bool {
        let cr = self.regs.get(RCC_CR);
        let on = cr & (1 << 16) != 0;
        let bypass = cr & (1 << 18) != 0;
        on && bypass == self.limits.hse_bypass
    }

    /// The VCO output (Hz) if the PLL's configuration is within limits and its source runs.
    fn vco(&self) -> Option<u64> {
        let cfg = self.regs.get(RCC_PLLCFGR);
        let m = u64::from(cfg & 0x3F);
        let n = u64::from((cfg >> 6) & 0x1FF);
        let hse_src = cfg & (1 << 22) != 0;
        let (src, ready) = if hse_src {
            (self.limits.hse_hz, self.hse_ready())
        } else {
            (HSI_HZ, self.regs.get(RCC_CR) & 1 != 0)
        };
        if !ready || !(2..=63).contains(&m) || !(50..=432).contains(&n) {
            return None;
        }
        let vin = src / m;
        let vco = vin * n;
        ((1_000_000..=2_000_000).contains(&vin) && (100_000_000..=432_000_000).contains(&vco))
            .then_some(vco)
    }

    /// PLL output P (Hz) if the PLL's configuration is within limits.
    fn pll_p(&self) -> Option<u64> {
        let p = 2 * (u64::from((self.regs.get(RCC_PLLCFGR) >> 16) & 3) + 1);
        let out = self.vco()? / p;
        (out <= self.limits.pll_p_max).then_some(out)
    }

    /// PLL output R (Hz; PLLR 2…7), where the chip can take SYSCLK from it.
    fn pll_r(&self) -> Option<u64> {
        let r = u64::from((self.regs.get(RCC_PLLCFGR) >> 28) & 7);
        if !self.limits.pll_r_sysclk || r < 2 {
            return None;
        }
        let out = self.vco()? / r;
        (out <= self.limits.pll_p_max).then_some(out)
    }

    fn pll_ready(&self) -> bool {
        self.regs.get(RCC_CR) & (1 << 24) != 0 && self.vco().is_some()
    }

    fn source_ready(&self, sw: u32) -> bool {
        match sw {
            0 => self.regs.get(RCC_CR) & 1 != 0,
            1 => self.hse_ready(),
            2 => self.pll_ready() && self.pll_p().is_some(),
            3 => self.pll_ready() && self.pll_r().is_some(),
            _ => false,
        }
    }

    fn sysclk_of(&self, sws: u32) -> u64 {
        match sws {
            1 => self.limits.hse_hz,
            2 => self.pll_p().unwrap_or(HSI_HZ),
            3 => self.pll_r().unwrap_or(HSI_HZ),
            _ => HSI_HZ,
        }
    }

    /// SYSCLK now.
    pub fn sysclk(&self) -> u64 {
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
    pub fn hclk(&self) -> u64 {
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
        // PWR_CSR(1).VOSRDY (bit 14) once the regulator runs at the selected scale; the
        // over-drive handshake (ODRDY bit 16, ODSWRDY bit 17) follows ODEN/ODSWEN.
        let cr1 = self.regs.get(PWR);
        let mut csr1 = self.regs.get(PWR + 4) | (1 << 14);
        csr1 = (csr1 & !(1 << 16)) | (((cr1 >> 16) & 1) << 16);
        csr1 = (csr1 & !(1 << 17)) | (((cr1 >> 17) & 1) << 17);
        self.regs.set(PWR + 4, csr1);
    }

    fn check_clock_limits(&mut self) {
        let l = self.limits;
        let hclk = self.hclk();
        let latency = u64::from(self.regs.get(FLASH_ACR) & 0xF);
        let needed = hclk.div_ceil(30_000_000).saturating_sub(1);
        if latency < needed {
            self.findings.push(format!(
                "HCLK {hclk} Hz with FLASH_ACR.LATENCY = {latency}: at least {needed} wait states needed ({} flash wait states, 2.7–3.6 V)",
                l.manual
            ));
        }
        let overdrive = self.regs.get(PWR + 4) & (1 << 17) != 0;
        if hclk > l.hclk_max || (hclk > l.hclk_max_without_overdrive && !overdrive) {
            self.findings.push(format!(
                "HCLK {hclk} Hz above its maximum ({} Hz, {} Hz without over-drive; PWR_CSR.ODSWRDY = {}; {})",
                l.hclk_max,
                l.hclk_max_without_overdrive,
                u8::from(overdrive),
                l.manual
            ));
        }
        let cfgr = self.regs.get(RCC_CFGR);
        let apb1 = hclk / Self::apb_div((cfgr >> 10) & 7);
        let apb2 = hclk / Self::apb_div((cfgr >> 13) & 7);
        if apb1 > l.apb1_max || apb2 > l.apb2_max {
            self.findings.push(format!(
                "APB1 {apb1} Hz / APB2 {apb2} Hz above their maxima ({} / {} Hz)",
                l.apb1_max, l.apb2_max
            ));
        }
    }

    /// The peripheral at `addr` and its clock gate, if it is one of these.
    pub fn peripheral(&self, addr: u32) -> Option<(&'static str, Option<(u32, u32)>)> {
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
        let ports = self.limits.gpio_ports.min(GPIOS.len() as u32);
        if (GPIOA..GPIOA + ports * 0x400).contains(&addr) {
            let n = (addr - GPIOA) / 0x400;
            return Some((GPIOS[n as usize], Some((RCC_AHB1ENR, 1 << n))));
        }
        None
    }

    fn known(&self, name: &str, addr: u32) -> bool {
        let off = addr & 0x3FF & !3;
        match name {
            "RCC" => {
                off <= self.limits.rcc_last
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

    /// Whether the clock gate `(register, mask)` is open (every bit of `mask` set).
    pub fn gate_open(&self, gate: (u32, u32)) -> bool {
        self.regs.get(gate.0) & gate.1 == gate.1
    }

    fn gated(
        &self,
        name: &'static str,
        gate: Option<(u32, u32)>,
        gate_name: &'static str,
    ) -> Option<Access> {
        gate.filter(|g| !self.gate_open(*g)).map(|_| Access::Gated {
            peripheral: name,
            gate: gate_name,
        })
    }

    /// A read of the peripheral space (`None`: not one of these peripherals).
    pub fn read(
        &mut self,
        addr: u32,
        size: usize,
        gate_name: impl Fn((u32, u32)) -> &'static str,
    ) -> Option<Access> {
        let (name, gate) = self.peripheral(addr)?;
        if let Some(a) = gate.and_then(|g| self.gated(name, Some(g), gate_name(g))) {
            return Some(a);
        }
        self.settle();
        let v = self.regs.read(addr, size);
        Some(if self.known(name, addr) {
            Access::Known(v)
        } else {
            Access::Unknown { peripheral: name }
        })
    }

    /// A write of the peripheral space (`None`: not one of these peripherals).
    pub fn write(
        &mut self,
        addr: u32,
        size: usize,
        value: u32,
        gate_name: impl Fn((u32, u32)) -> &'static str,
    ) -> Option<Access> {
        let (name, gate) = self.peripheral(addr)?;
        if let Some(a) = gate.and_then(|g| self.gated(name, Some(g), gate_name(g))) {
            return Some(a);
        }
        let known = self.known(name, addr);
        let w = addr & !3;
        if w == RCC_PLLCFGR && self.regs.get(RCC_CR) & (1 << 24) != 0 {
            let old = self.regs.get(RCC_PLLCFGR);
            let new = super::insert(old, addr, size, value);
            if new != old {
                self.findings.push(format!(
                    "RCC_PLLCFGR changed while PLLON = 1 ({}: only when the PLL is disabled)",
                    self.limits.manual
                ));
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
        Some(if known {
            Access::Known(0)
        } else {
            Access::Unknown { peripheral: name }
        })
    }

    /// Findings the rules made since the last call.
    pub fn take_findings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.findings)
    }

    /// Adds a finding (from the chip's own rules).
    pub fn finding(&mut self, what: String) {
        self.findings.push(what);
    }
}
