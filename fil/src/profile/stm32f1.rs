//! STM32F103C8 on a "Blue Pill" board: a Cortex-M3 (no FPU) with one bxCAN, its clock
//! tree and pins as the examples need them.
//!
//! Sources: RM0008 (STM32F101/102/103/105/107) §3.3 "Memory map", §3.3.3 "Embedded Flash
//! memory" (wait states), §3.4 "Boot configuration", §7.2 "Clocks", §7.3 "RCC registers",
//! §9.1.11 "GPIO configurations for device peripherals", §9.2 "GPIO registers", §9.3.3
//! "CAN alternate function remapping", §9.4.2 `AFIO_MAPR`, §10.1.2 (vector table of the
//! "other" STM32F10x devices), §24 "bxCAN"; datasheet DS5319 (STM32F103x8/xB) §5.3.1
//! (operating conditions) and §5.3.x "PLL characteristics" (input 1–25 MHz, output
//! 16–72 MHz). The Blue Pill has an 8 MHz crystal on OSC_IN/OSC_OUT.
//!
//! Rules modelled:
//! - `HSIRDY` follows `HSION`; `HSERDY` follows `HSEON` only with `HSEBYP` = 0 (the board
//!   has a crystal: in bypass nothing drives OSC_IN).
//! - The PLL takes HSI/2 (`PLLSRC` = 0) or HSE, halved by `PLLXTPRE`, times `PLLMUL` + 2
//!   (×16 for 0b1110 and 0b1111). `PLLRDY` follows `PLLON` only when its source runs, its
//!   input is 1–25 MHz and its output 16–72 MHz (RM0008 §7.2.3: "The PLL output
//!   frequency must not exceed 72 MHz"). `PLLSRC`, `PLLXTPRE` and `PLLMUL` "can be
//!   written only when PLL is disabled" (§7.3.2): a change while `PLLON` = 1 is reported
//!   and not applied.
//! - `SWS` follows `SW` once the selected clock is ready (`SW` = 0b11 is "not allowed":
//!   nothing happens). Whenever the clock configuration changes, a SYSCLK above what
//!   `FLASH_ACR.LATENCY` allows (0 wait states up to 24 MHz, 1 up to 48 MHz, 2 up to
//!   72 MHz), an HCLK above 72 MHz, an APB1 above 36 MHz or an APB2 above 72 MHz (§7.2:
//!   "The maximum allowed frequency of the APB1 domain is 36 MHz") is reported.
//! - Clock gates (`RCC_APB2ENR`: AFIO bit 0, GPIOA..E bits 2..6; `RCC_APB1ENR`: CAN bit
//!   25, USB bit 23, PWR bit 28): a gated STM32 peripheral reads 0 and ignores writes
//!   without a bus error; the harness records the access as a fault of the firmware.
//! - **USB and CAN**: on this device they "share a dedicated 512-byte SRAM memory for data
//!   transmission and reception, and so they cannot be used concurrently (the shared SRAM
//!   is accessed through CAN and USB exclusively)" (RM0008 §24.2 note). Both clocks on at
//!   once (`RCC_APB1ENR.USBEN` and `CANEN`) is reported. The USB registers (0x4000_5C00)
//!   and the shared SRAM (0x4000_6000) are plain storage, reported as unknown registers.
//! - GPIO registers are storage (`CRL`/`CRH` reset 0x4444_4444: floating inputs), except
//!   `BSRR` and `BRR` (write-only: set/reset `ODR` bits). `AFIO_MAPR.SWJ_CFG` is
//!   write-only and reads 0.
//! - When the CAN joins the bus its pins must be set up for the `AFIO_MAPR.CAN_REMAP` in
//!   force (§9.3.3): 00 → RX PA11, TX PA12; 10 → RX PB8, TX PB9; 11 → PD0/PD1, "only on
//!   100-pin and 144-pin packages" (not on the 48-pin STM32F103C8); 01 is not used. TX must
//!   be an alternate-function push-pull output and RX an input (floating or pull-up),
//!   with the port clocked (§9.1.11, "CAN" table); otherwise it is reported.

use twocan_bxcan::model::part;

use super::{Access, CanInstance, Ctx, Memory, Profile, RegStore};

/// The on-chip RC oscillator (RM0008 §7.2.1).
const HSI_HZ: u64 = 8_000_000;
/// The Blue Pill's crystal.
const HSE_HZ: u64 = 8_000_000;

const RCC: u32 = 0x4002_1000;
const RCC_CR: u32 = RCC;
const RCC_CFGR: u32 = RCC + 0x04;
const RCC_AHBENR: u32 = RCC + 0x14;
const RCC_APB2ENR: u32 = RCC + 0x18;
const RCC_APB1ENR: u32 = RCC + 0x1C;
const RCC_CSR: u32 = RCC + 0x24;
const FLASH: u32 = 0x4002_2000;
const FLASH_ACR: u32 = FLASH;
const PWR: u32 = 0x4000_7000;
const AFIO: u32 = 0x4001_0000;
const AFIO_MAPR: u32 = AFIO + 0x04;
const GPIOA: u32 = 0x4001_0800;
const USB: u32 = 0x4000_5C00;
const USB_CAN_SRAM: u32 = 0x4000_6000;

const USBEN: u32 = 1 << 23;
const CANEN: u32 = 1 << 25;
/// `RCC_CFGR` bits written only while the PLL is off: PLLSRC, PLLXTPRE, PLLMUL.
const CFGR_PLL_BITS: u32 = 0x3F << 16;

/// The STM32F103C8 of a Blue Pill.
#[derive(Debug, Clone)]
pub struct Stm32f1 {
    regs: RegStore,
    findings: Vec<String>,
    /// The clocks last checked: (SYSCLK, HCLK, APB1, APB2, LATENCY).
    checked: (u64, u64, u64, u64, u32),
}

impl Default for Stm32f1 {
    fn default() -> Self {
        Self::new()
    }
}

impl Stm32f1 {
    /// The chip out of power-on reset.
    pub fn new() -> Self {
        let mut regs = RegStore::default();
        regs.set(RCC_CR, 0x0000_0083); // HSION, HSIRDY, HSITRIM = 16
        regs.set(RCC_AHBENR, 0x0000_0014); // SRAMEN, FLITFEN
        regs.set(RCC_CSR, 0x0C00_0000); // PINRSTF, PORRSTF
        regs.set(FLASH_ACR, 0x0000_0030); // PRFTBE, PRFTBS
        regs.set(FLASH + 0x10, 0x0000_0080); // FLASH_CR.LOCK
        regs.set(FLASH + 0x1C, 0x03FF_FFFC); // FLASH_OBR
        regs.set(FLASH + 0x20, 0xFFFF_FFFF); // FLASH_WRPR
        for port in 0..5 {
            regs.set(GPIOA + port * 0x400, 0x4444_4444);
            regs.set(GPIOA + port * 0x400 + 4, 0x4444_4444);
        }
        let mut s = Stm32f1 {
            regs,
            findings: Vec::new(),
            checked: (0, 0, 0, 0, 0),
        };
        s.checked = s.clocks();
        s
    }

    fn hse_ready(&self) -> bool {
        let cr = self.regs.get(RCC_CR);
        cr & (1 << 16) != 0 && cr & (1 << 18) == 0
    }

    /// The PLL output (Hz) if its source runs and its input and output are in range.
    fn pll_out(&self) -> Option<u64> {
        let cfgr = self.regs.get(RCC_CFGR);
        let (input, ready) = if cfgr & (1 << 16) == 0 {
            (HSI_HZ / 2, self.regs.get(RCC_CR) & 1 != 0)
        } else {
            let div = if cfgr & (1 << 17) != 0 { 2 } else { 1 };
            (HSE_HZ / div, self.hse_ready())
        };
        let mul = u64::from(((cfgr >> 18) & 0xF).min(14) + 2);
        let out = input * mul;
        (ready
            && (1_000_000..=25_000_000).contains(&input)
            && (16_000_000..=72_000_000).contains(&out))
        .then_some(out)
    }

    fn pll_ready(&self) -> bool {
        self.regs.get(RCC_CR) & (1 << 24) != 0 && self.pll_out().is_some()
    }

    fn source_ready(&self, sw: u32) -> bool {
        match sw {
            0 => self.regs.get(RCC_CR) & 1 != 0,
            1 => self.hse_ready(),
            2 => self.pll_ready(),
            _ => false,
        }
    }

    /// SYSCLK now.
    fn sysclk(&self) -> u64 {
        match (self.regs.get(RCC_CFGR) >> 2) & 3 {
            1 => HSE_HZ,
            2 => self.pll_out().unwrap_or(HSI_HZ),
            _ => HSI_HZ,
        }
    }

    fn hclk(&self) -> u64 {
        let hpre = (self.regs.get(RCC_CFGR) >> 4) & 0xF;
        let div = if hpre < 8 {
            1
        } else {
            [2, 4, 8, 16, 64, 128, 256, 512][(hpre - 8) as usize]
        };
        self.sysclk() / div
    }

    fn apb_div(bits: u32) -> u64 {
        if bits < 4 {
            1
        } else {
            1 << (bits - 3)
        }
    }

    /// APB1 clock now (bxCAN's clock).
    pub fn pclk1(&self) -> u64 {
        self.hclk() / Self::apb_div((self.regs.get(RCC_CFGR) >> 8) & 7)
    }

    fn pclk2(&self) -> u64 {
        self.hclk() / Self::apb_div((self.regs.get(RCC_CFGR) >> 11) & 7)
    }

    fn clocks(&self) -> (u64, u64, u64, u64, u32) {
        (
            self.sysclk(),
            self.hclk(),
            self.pclk1(),
            self.pclk2(),
            self.regs.get(FLASH_ACR) & 7,
        )
    }

    /// Recomputes the status bits that follow control bits, then checks the limits if
    /// the clocks changed.
    fn settle(&mut self) {
        let mut cr = self.regs.get(RCC_CR);
        cr = (cr & !(1 << 1)) | ((cr & 1) << 1);
        cr = (cr & !(1 << 17)) | (u32::from(self.hse_ready()) << 17);
        cr = (cr & !(1 << 25)) | (u32::from(self.pll_ready()) << 25);
        self.regs.set(RCC_CR, cr);
        let cfgr = self.regs.get(RCC_CFGR);
        let (sw, sws) = (cfgr & 3, (cfgr >> 2) & 3);
        if sw != sws && self.source_ready(sw) {
            self.regs.set(RCC_CFGR, (cfgr & !(3 << 2)) | (sw << 2));
        }
        let now = self.clocks();
        if now != self.checked {
            self.checked = now;
            self.check_clock_limits();
        }
    }

    fn check_clock_limits(&mut self) {
        let (sysclk, hclk, apb1, apb2, latency) = self.checked;
        let needed = match sysclk {
            0..=24_000_000 => 0,
            24_000_001..=48_000_000 => 1,
            _ => 2,
        };
        if latency < needed {
            self.findings.push(format!(
                "SYSCLK {sysclk} Hz with FLASH_ACR.LATENCY = {latency}: at least {needed} wait states needed (RM0008 §3.3.3)"
            ));
        }
        if hclk > 72_000_000 || apb1 > 36_000_000 || apb2 > 72_000_000 {
            self.findings.push(format!(
                "HCLK {hclk} Hz / APB1 {apb1} Hz / APB2 {apb2} Hz above their maxima (72 / 36 / 72 MHz; RM0008 §7.2)"
            ));
        }
    }

    fn peripheral(&self, addr: u32) -> Option<(&'static str, Option<(u32, u32)>)> {
        const GPIOS: [&str; 5] = ["GPIOA", "GPIOB", "GPIOC", "GPIOD", "GPIOE"];
        let p = match addr {
            a if (RCC..RCC + 0x400).contains(&a) => ("RCC", None),
            a if (FLASH..FLASH + 0x400).contains(&a) => ("FLASH", None),
            a if (PWR..PWR + 0x400).contains(&a) => ("PWR", Some((RCC_APB1ENR, 1 << 28))),
            a if (AFIO..AFIO + 0x400).contains(&a) => ("AFIO", Some((RCC_APB2ENR, 1))),
            a if (GPIOA..GPIOA + 5 * 0x400).contains(&a) => {
                let n = (a - GPIOA) / 0x400;
                (GPIOS[n as usize], Some((RCC_APB2ENR, 1 << (2 + n))))
            }
            a if (USB..USB + 0x400).contains(&a) => ("USB", Some((RCC_APB1ENR, USBEN))),
            a if (USB_CAN_SRAM..USB_CAN_SRAM + 0x400).contains(&a) => {
                ("USB/CAN SRAM", Some((RCC_APB1ENR, USBEN)))
            }
            _ => return None,
        };
        Some(p)
    }

    fn known(name: &str, addr: u32) -> bool {
        let off = addr & 0x3FF & !3;
        match name {
            "RCC" => off <= 0x24,
            "FLASH" => off <= 0x20 && off != 0x18,
            "PWR" => off <= 0x04,
            "AFIO" => off <= 0x14 || off == 0x1C,
            _ if name.starts_with("GPIO") => off <= 0x18,
            _ => false,
        }
    }

    fn gated(&self, name: &'static str, gate: Option<(u32, u32)>) -> Option<Access> {
        gate.filter(|g| !self.gate_open(*g)).map(|g| Access::Gated {
            peripheral: name,
            gate: self.gate_name(g),
        })
    }

    /// The 4-bit configuration (`MODE[1:0]` low, `CNF[1:0]` high) of a pin, if its port
    /// is clocked.
    fn pin_config(&self, (port, pin): (u32, u32)) -> Option<u32> {
        if !self.gate_open((RCC_APB2ENR, 1 << (2 + port))) {
            return None;
        }
        let cr = GPIOA + port * 0x400 + if pin < 8 { 0 } else { 4 };
        Some((self.regs.get(cr) >> (4 * (pin % 8))) & 0xF)
    }
}

fn pin_name((port, pin): (u32, u32)) -> String {
    format!("P{}{pin}", char::from(b'A' + port as u8))
}

impl Profile for Stm32f1 {
    fn name(&self) -> &'static str {
        "bluepill"
    }

    fn cpu_model(&self) -> i32 {
        unicorn_engine::ArmCpuModel::CORTEX_M3 as i32
    }

    fn peripheral_bit_band(&self) -> bool {
        true
    }

    fn memory(&self) -> Vec<Memory> {
        vec![
            Memory {
                name: "flash (boot alias)",
                base: 0,
                size: 64 << 10,
                writable: false,
                alias_of: Some(0x0800_0000),
            },
            Memory {
                name: "flash",
                base: 0x0800_0000,
                size: 64 << 10,
                writable: false,
                alias_of: None,
            },
            Memory {
                name: "SRAM",
                base: 0x2000_0000,
                size: 20 << 10,
                writable: true,
                alias_of: None,
            },
        ]
    }

    fn boot_address(&self) -> u32 {
        // BOOT0 = 0: main flash aliased at 0 (RM0008 §3.4); VTOR resets to 0.
        0
    }

    fn irq_count(&self) -> u32 {
        // Medium-density devices: lines 0..=42 (USBWakeup is the last; RM0008 §10.1.2).
        43
    }

    fn can_instances(&self) -> Vec<CanInstance> {
        super::bxcan_instances(&part::STM32F103, &[1])
    }

    fn read(&mut self, addr: u32, size: usize, _ctx: Ctx) -> Access {
        let Some((name, gate)) = self.peripheral(addr) else {
            return Access::Unmapped;
        };
        if let Some(a) = self.gated(name, gate) {
            return a;
        }
        self.settle();
        let v = self.regs.read(addr, size);
        if Self::known(name, addr) {
            Access::Known(v)
        } else {
            Access::Unknown { peripheral: name }
        }
    }

    fn write(&mut self, addr: u32, size: usize, value: u32, _ctx: Ctx) -> Access {
        let Some((name, gate)) = self.peripheral(addr) else {
            return Access::Unmapped;
        };
        if let Some(a) = self.gated(name, gate) {
            return a;
        }
        let w = addr & !3;
        let old = self.regs.get(w);
        let new = super::insert(old, addr, size, value);
        let both_before = old & (USBEN | CANEN) == USBEN | CANEN;
        match w {
            RCC_CFGR => {
                // SWS is read-only; the PLL bits only while the PLL is off.
                let mut v = (new & !(3 << 2)) | (old & (3 << 2));
                if self.regs.get(RCC_CR) & (1 << 24) != 0 && (v ^ old) & CFGR_PLL_BITS != 0 {
                    self.findings.push(
                        "RCC_CFGR PLLSRC/PLLXTPRE/PLLMUL changed while PLLON = 1: ignored (RM0008 §7.3.2)"
                            .into(),
                    );
                    v = (v & !CFGR_PLL_BITS) | (old & CFGR_PLL_BITS);
                }
                self.regs.set(w, v);
            }
            AFIO_MAPR => self.regs.set(w, new & !(7 << 24)), // SWJ_CFG: write-only
            _ if name.starts_with("GPIO") && matches!(w & 0x3FF, 0x10 | 0x14) => {
                // BSRR (set 0–15, reset 16–31) and BRR (reset 0–15): write-only.
                let v = super::insert(0, addr, size, value);
                let (set, reset) = if w & 0x3FF == 0x10 {
                    (v & 0xFFFF, v >> 16)
                } else {
                    (0, v & 0xFFFF)
                };
                let odr = (w & !0x3FF) + 0x0C;
                let cur = self.regs.get(odr);
                self.regs.set(odr, (cur | set) & !reset);
            }
            _ => self.regs.set(w, new),
        }
        if w == RCC_APB1ENR && !both_before && new & (USBEN | CANEN) == USBEN | CANEN {
            self.findings.push(
                "RCC_APB1ENR: USBEN and CANEN both set: the USB and CAN share one 512-byte SRAM and cannot be used at the same time (RM0008 §24.2)"
                    .into(),
            );
        }
        self.settle();
        if Self::known(name, addr) {
            Access::Known(0)
        } else {
            Access::Unknown { peripheral: name }
        }
    }

    fn gated_access_is_bus_error(&self) -> bool {
        false
    }

    fn gate_open(&self, gate: (u32, u32)) -> bool {
        self.regs.get(gate.0) & gate.1 == gate.1
    }

    fn gate_name(&self, gate: (u32, u32)) -> &'static str {
        match gate {
            (RCC_APB1ENR, CANEN) => "RCC_APB1ENR.CANEN",
            (RCC_APB1ENR, USBEN) => "RCC_APB1ENR.USBEN",
            (RCC_APB1ENR, _) => "RCC_APB1ENR.PWREN",
            (RCC_APB2ENR, 1) => "RCC_APB2ENR.AFIOEN",
            (RCC_APB2ENR, _) => "RCC_APB2ENR.IOPxEN",
            _ => "?",
        }
    }

    fn core_hz(&self) -> u64 {
        self.hclk()
    }

    fn can_clock_hz(&self, _can: &CanInstance) -> u64 {
        self.pclk1()
    }

    fn systick_external_divider(&self) -> Option<u64> {
        Some(8) // HCLK / 8 (RM0008 §7.2, clock tree)
    }

    fn take_findings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.findings)
    }

    fn can_joined(&mut self, can: &CanInstance) {
        let remap = (self.regs.get(AFIO_MAPR) >> 13) & 3;
        let (rx, tx) = match remap {
            0 => ((0, 11), (0, 12)),
            2 => ((1, 8), (1, 9)),
            3 => {
                self.findings.push(format!(
                    "{} joined the bus with AFIO_MAPR.CAN_REMAP = 11 (PD0/PD1): only on 100- and 144-pin packages, not on the 48-pin STM32F103C8 (RM0008 §9.3.3)",
                    can.name
                ));
                return;
            }
            _ => {
                self.findings.push(format!(
                    "{} joined the bus with AFIO_MAPR.CAN_REMAP = 01, which is not used (RM0008 §9.4.2)",
                    can.name
                ));
                return;
            }
        };
        // TX: alternate-function push-pull output (CNF = 10, MODE ≠ 00); RX: input
        // (MODE = 00) floating (CNF = 01) or with pull-up/down (CNF = 10).
        let tx_ok = self
            .pin_config(tx)
            .is_some_and(|c| c >> 2 == 0b10 && c & 3 != 0);
        let rx_ok = self
            .pin_config(rx)
            .is_some_and(|c| c & 3 == 0 && matches!(c >> 2, 0b01 | 0b10));
        if !(tx_ok && rx_ok) {
            self.findings.push(format!(
                "{} joined the bus with CAN_REMAP = {remap:02b} but TX {} is {} and RX {} is {} (RM0008 §9.1.11: TX alternate-function push-pull, RX input floating or pull-up, port clocked)",
                can.name,
                pin_name(tx),
                if tx_ok { "right" } else { "not an AF push-pull output" },
                pin_name(rx),
                if rx_ok { "right" } else { "not an input" },
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(s: &mut Stm32f1, a: u32, v: u32) {
        assert!(matches!(s.write(a, 4, v, Ctx::default()), Access::Known(_)));
    }
    fn r(s: &mut Stm32f1, a: u32) -> u32 {
        match s.read(a, 4, Ctx::default()) {
            Access::Known(v) => v,
            other => panic!("{other:?}"),
        }
    }

    /// The usual Blue Pill set-up: HSE 8 MHz, PLL ×9 = 72 MHz, APB1 /2, 2 wait states.
    fn to_72_mhz(s: &mut Stm32f1, latency: u32, ppre1: u32) {
        w(s, FLASH_ACR, 0x30 | latency);
        w(s, RCC_CR, 0x83 | (1 << 16));
        assert_ne!(r(s, RCC_CR) & (1 << 17), 0, "HSERDY");
        w(s, RCC_CFGR, (7 << 18) | (1 << 16) | (ppre1 << 8));
        w(s, RCC_CR, 0x83 | (1 << 16) | (1 << 24));
        assert_ne!(r(s, RCC_CR) & (1 << 25), 0, "PLLRDY");
        w(s, RCC_CFGR, (7 << 18) | (1 << 16) | (ppre1 << 8) | 2);
        assert_eq!((r(s, RCC_CFGR) >> 2) & 3, 2, "SWS = PLL");
    }

    #[test]
    fn the_blue_pill_clock_setup_gives_72_mhz_and_a_36_mhz_apb1() {
        let mut s = Stm32f1::new();
        assert_eq!(s.core_hz(), 8_000_000, "HSI out of reset");
        to_72_mhz(&mut s, 2, 4);
        assert_eq!(s.core_hz(), 72_000_000);
        assert_eq!(s.pclk1(), 36_000_000);
        assert_eq!(s.take_findings(), Vec::<String>::new());
    }

    #[test]
    fn clock_rule_violations_are_reported() {
        let mut s = Stm32f1::new();
        to_72_mhz(&mut s, 1, 4);
        let f = s.take_findings();
        assert!(f.iter().any(|f| f.contains("LATENCY = 1")), "{f:?}");
        let mut s = Stm32f1::new();
        to_72_mhz(&mut s, 2, 0);
        let f = s.take_findings();
        assert!(f.iter().any(|f| f.contains("APB1 72000000")), "{f:?}");
        // The crystal does not start in bypass.
        let mut s = Stm32f1::new();
        w(&mut s, RCC_CR, 0x83 | (1 << 16) | (1 << 18));
        assert_eq!(r(&mut s, RCC_CR) & (1 << 17), 0);
        // PLL ×16 from HSE: 128 MHz does not lock; SW stays on HSI.
        let mut s = Stm32f1::new();
        w(&mut s, RCC_CR, 0x83 | (1 << 16));
        w(&mut s, RCC_CFGR, (14 << 18) | (1 << 16));
        w(&mut s, RCC_CR, 0x83 | (1 << 16) | (1 << 24));
        assert_eq!(r(&mut s, RCC_CR) & (1 << 25), 0);
        w(&mut s, RCC_CFGR, (14 << 18) | (1 << 16) | 2);
        assert_eq!((r(&mut s, RCC_CFGR) >> 2) & 3, 0);
        // PLLMUL written while the PLL runs: reported, not applied.
        let mut s = Stm32f1::new();
        to_72_mhz(&mut s, 2, 4);
        s.take_findings();
        w(&mut s, RCC_CFGR, (6 << 18) | (1 << 16) | (4 << 8) | 2);
        assert_eq!((r(&mut s, RCC_CFGR) >> 18) & 0xF, 7);
        assert_eq!(s.core_hz(), 72_000_000);
        assert_eq!(s.take_findings().len(), 1);
    }

    #[test]
    fn usb_and_can_together_are_reported() {
        let mut s = Stm32f1::new();
        w(&mut s, RCC_APB1ENR, CANEN);
        assert!(s.take_findings().is_empty());
        w(&mut s, RCC_APB1ENR, CANEN | USBEN);
        let f = s.take_findings();
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(f[0].contains("512-byte SRAM"));
        w(&mut s, RCC_APB1ENR, CANEN | USBEN | (1 << 28));
        assert!(s.take_findings().is_empty(), "reported once");
        w(&mut s, RCC_APB1ENR, USBEN);
        w(&mut s, RCC_APB1ENR, USBEN | CANEN);
        assert_eq!(s.take_findings().len(), 1, "again after a pause");
    }

    #[test]
    fn can_instance_gate_and_lines() {
        let s = Stm32f1::new();
        let cans = s.can_instances();
        assert_eq!(cans.len(), 1);
        let c = &cans[0];
        assert_eq!(
            (c.name, c.base, c.gate),
            ("CAN", 0x4000_6400, (RCC_APB1ENR, CANEN))
        );
        assert_eq!(
            c.irqs,
            [
                ("USB_HP_CAN_TX", 19),
                ("USB_LP_CAN_RX0", 20),
                ("CAN_RX1", 21),
                ("CAN_SCE", 22)
            ]
        );
        assert!(!s.gate_open(c.gate));
        assert_eq!(s.gate_name(c.gate), "RCC_APB1ENR.CANEN");
    }

    #[test]
    fn can_pins_follow_the_remap() {
        let mut s = Stm32f1::new();
        let can = s.can_instances().remove(0);
        // Reset: PA11/PA12 floating inputs, port A not clocked.
        s.can_joined(&can);
        assert_eq!(s.take_findings().len(), 1);
        // PA12 AF push-pull 50 MHz (0xB), PA11 floating input (0x4).
        w(&mut s, RCC_APB2ENR, 1 | (1 << 2) | (1 << 3));
        w(&mut s, GPIOA + 4, 0x444B_4444);
        s.can_joined(&can);
        assert_eq!(s.take_findings(), Vec::<String>::new());
        // Remap to PB8/PB9 (CAN_REMAP = 10): PB9 must now be the AF output.
        w(&mut s, AFIO_MAPR, 2 << 13);
        assert_eq!(r(&mut s, AFIO_MAPR), 2 << 13);
        s.can_joined(&can);
        assert_eq!(s.take_findings().len(), 1);
        w(&mut s, GPIOA + 0x400 + 4, 0x4444_44B8); // PB9 AF PP, PB8 input pull-up/down
        s.can_joined(&can);
        assert_eq!(s.take_findings(), Vec::<String>::new());
        // PD0/PD1 do not exist as CAN pins on the 48-pin package.
        w(&mut s, AFIO_MAPR, 3 << 13);
        s.can_joined(&can);
        assert!(s.take_findings()[0].contains("48-pin"));
    }

    #[test]
    fn gates_storage_and_memory() {
        let mut s = Stm32f1::new();
        assert!(matches!(
            s.write(AFIO_MAPR, 4, 2 << 13, Ctx::default()),
            Access::Gated { .. }
        ));
        w(&mut s, RCC_APB2ENR, 1 | (1 << 2));
        w(&mut s, AFIO_MAPR, (2 << 13) | (2 << 24));
        assert_eq!(r(&mut s, AFIO_MAPR), 2 << 13, "SWJ_CFG reads 0");
        assert_eq!(r(&mut s, GPIOA), 0x4444_4444);
        w(&mut s, GPIOA + 0x10, 1 << 5); // BSRR: set PA5
        assert_eq!(r(&mut s, GPIOA + 0x0C), 1 << 5);
        w(&mut s, GPIOA + 0x14, 1 << 5); // BRR: reset PA5
        assert_eq!(r(&mut s, GPIOA + 0x0C), 0);
        assert_eq!(s.read(0x4000_0000, 4, Ctx::default()), Access::Unmapped);
        assert_eq!(s.irq_count(), 43);
        let m = s.memory();
        assert_eq!(m[1].size, 64 << 10);
        assert_eq!(m[2].size, 20 << 10);
        assert_eq!(s.boot_address(), 0);
    }
}
