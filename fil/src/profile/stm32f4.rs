//! STM32F446RE on the NUCLEO-F446RE: a Cortex-M4F with CAN1 and CAN2, its clock tree and
//! pins as the examples need them.
//!
//! Sources: RM0390 (STM32F446xx) §2.3 "Memory map", §2.4 "Boot configuration", §3.4
//! "Read interface" (Table 5: flash wait states), §5.1.4 "Voltage regulator" (over-drive),
//! §6.2 "Clocks", §6.3 "RCC registers", §7 "GPIO", §10.2 (vector table), §30 "bxCAN";
//! datasheet DS10693 §6.3.1 (operating conditions: HCLK 180 MHz with over-drive, 168 MHz
//! without; APB1 45 MHz, APB2 90 MHz) and Table 11 (alternate functions); user manual
//! UM1724 (NUCLEO-64: HSE = 8 MHz MCO from the ST-LINK, in bypass).
//!
//! The RCC, flash, PWR, SYSCFG and GPIO rules are those of [`super::stm32_rcc`] (the F4
//! and F7 share the layout) with the F446's limits: VCO 100–432 MHz from a 1–2 MHz input,
//! a PLL P (or R: `RCC_CFGR.SW = 0b11` selects PLL_R on the F446) output of at most
//! 180 MHz, HCLK at most 180 MHz and 168 MHz without over-drive (`PWR_CR.ODEN`/`ODSWEN`,
//! handshake `PWR_CSR.ODRDY`/`ODSWRDY`), APB1 45 MHz, APB2 90 MHz, 5 flash wait states at
//! 180 MHz. Out of reset SYSCLK is the 16 MHz HSI.
//!
//! Memory: 512 KiB of flash at 0x0800_0000, aliased at 0x0000_0000 when booting from it
//! (BOOT0 = 0: VTOR = 0); 128 KiB of SRAM (SRAM1 112 KiB + SRAM2 16 KiB) at 0x2000_0000.
//! 97 interrupt lines (the last, 96, is FMPI2C1_ERR); 4 priority bits.
//!
//! bxCAN ([`twocan_bxcan::model::part::STM32F446`]): CAN1 at 0x4000_6400 (lines 19..=22),
//! CAN2 at 0x4000_6800 (lines 63..=66), clocks `RCC_APB1ENR.CAN1EN` (bit 25) and `CAN2EN`
//! (bit 26). CAN2 is the slave of the dual CAN: it works through CAN1's filters and
//! message SRAM (RM0390 §30.2), so the harness treats an access to CAN2 with either clock
//! off as gated. When a controller joins the bus, its pins must be in alternate function
//! 9: CAN1 RX/TX on PA11/PA12, PB8/PB9 or PD0/PD1; CAN2 on PB12/PB13 or PB5/PB6
//! (DS10693 Table 11) — otherwise it is reported.

use twocan_bxcan::model::part;

use super::stm32_rcc::{Limits, SystemRegs, GPIOA, RCC_AHB1ENR, RCC_APB1ENR, RCC_APB2ENR};
use super::{Access, CanInstance, CanKind, Ctx, Memory, Profile};

/// The F446's limits on the NUCLEO-F446RE.
static LIMITS: Limits = Limits {
    manual: "RM0390",
    hse_hz: 8_000_000,
    hse_bypass: true,
    pll_p_max: 180_000_000,
    pll_r_sysclk: true,
    hclk_max: 180_000_000,
    hclk_max_without_overdrive: 168_000_000,
    apb1_max: 45_000_000,
    apb2_max: 90_000_000,
    gpio_ports: 8,
    rcc_last: 0x94,
};

/// Alternate function of bxCAN on the F446 (DS10693 Table 11).
const AF_CAN: u32 = 9;

/// The (RX, TX) pin pairs of CAN1 and CAN2: (port index, pin).
const CAN1_PINS: [[(u32, u32); 2]; 3] = [[(0, 11), (0, 12)], [(1, 8), (1, 9)], [(3, 0), (3, 1)]];
const CAN2_PINS: [[(u32, u32); 2]; 2] = [[(1, 12), (1, 13)], [(1, 5), (1, 6)]];

/// The STM32F446RE of a NUCLEO-F446RE.
#[derive(Debug, Clone)]
pub struct Stm32f4 {
    sys: SystemRegs,
}

impl Default for Stm32f4 {
    fn default() -> Self {
        Self::new()
    }
}

impl Stm32f4 {
    /// The chip out of power-on reset.
    pub fn new() -> Self {
        Stm32f4 {
            sys: SystemRegs::new(&LIMITS),
        }
    }

    /// APB1 clock now (bxCAN's clock).
    pub fn pclk1(&self) -> u64 {
        self.sys.pclk1()
    }

    /// Whether pin `pin` of port `port` is in alternate function `af` with its port
    /// clocked.
    fn pin_in_af(&self, (port, pin): (u32, u32), af: u32) -> bool {
        let base = GPIOA + port * 0x400;
        let clocked = self.sys.gate_open((RCC_AHB1ENR, 1 << port));
        let mode = (self.sys.regs.get(base) >> (2 * pin)) & 3;
        let afr = self.sys.regs.get(base + 0x20 + 4 * (pin / 8));
        let function = (afr >> (4 * (pin % 8))) & 0xF;
        clocked && mode == 0b10 && function == af
    }
}

/// Names of the F446's clock gates.
fn gate_name(gate: (u32, u32)) -> &'static str {
    match gate {
        (RCC_APB1ENR, m) if m == 1 << 25 => "RCC_APB1ENR.CAN1EN",
        (RCC_APB1ENR, m) if m == (1 << 25) | (1 << 26) => "RCC_APB1ENR.CAN1EN+CAN2EN",
        (RCC_APB1ENR, _) => "RCC_APB1ENR.PWREN",
        (RCC_APB2ENR, _) => "RCC_APB2ENR.SYSCFGEN",
        (RCC_AHB1ENR, _) => "RCC_AHB1ENR.GPIOxEN",
        _ => "?",
    }
}

fn pin_name((port, pin): (u32, u32)) -> String {
    format!("P{}{pin}", char::from(b'A' + port as u8))
}

impl Profile for Stm32f4 {
    fn name(&self) -> &'static str {
        "nucleo-f446re"
    }

    fn cpu_model(&self) -> i32 {
        unicorn_engine::ArmCpuModel::CORTEX_M4 as i32
    }

    fn peripheral_bit_band(&self) -> bool {
        true
    }

    fn memory(&self) -> Vec<Memory> {
        vec![
            Memory {
                name: "flash (boot alias)",
                base: 0,
                size: 512 << 10,
                writable: false,
                alias_of: Some(0x0800_0000),
            },
            Memory {
                name: "flash",
                base: 0x0800_0000,
                size: 512 << 10,
                writable: false,
                alias_of: None,
            },
            Memory {
                name: "SRAM1 + SRAM2",
                base: 0x2000_0000,
                size: 128 << 10,
                writable: true,
                alias_of: None,
            },
        ]
    }

    fn boot_address(&self) -> u32 {
        0
    }

    fn irq_count(&self) -> u32 {
        97
    }

    fn can_instances(&self) -> Vec<CanInstance> {
        super::bxcan_instances(&part::STM32F446, &[1, 2])
    }

    fn read(&mut self, addr: u32, size: usize, _ctx: Ctx) -> Access {
        self.sys
            .read(addr, size, gate_name)
            .unwrap_or(Access::Unmapped)
    }

    fn write(&mut self, addr: u32, size: usize, value: u32, _ctx: Ctx) -> Access {
        self.sys
            .write(addr, size, value, gate_name)
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
        self.sys.pclk1()
    }

    fn systick_external_divider(&self) -> Option<u64> {
        Some(8) // HCLK / 8 (RM0390 §6.2, clock tree)
    }

    fn take_findings(&mut self) -> Vec<String> {
        self.sys.take_findings()
    }

    fn can_joined(&mut self, can: &CanInstance) {
        let pairs: &[[(u32, u32); 2]] = match can.kind {
            CanKind::BxCan { instance: 2, .. } => &CAN2_PINS,
            _ => &CAN1_PINS,
        };
        if pairs
            .iter()
            .any(|pair| pair.iter().all(|p| self.pin_in_af(*p, AF_CAN)))
        {
            return;
        }
        let options: Vec<String> = pairs
            .iter()
            .map(|[rx, tx]| format!("{}/{}", pin_name(*rx), pin_name(*tx)))
            .collect();
        self.sys.finding(format!(
            "{} joined the bus without its RX/TX pins in alternate function {AF_CAN} (any of {}, port clock on; DS10693 Table 11)",
            can.name,
            options.join(", ")
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::super::stm32_rcc::{FLASH_ACR, PWR, RCC_CFGR, RCC_CR, RCC_PLLCFGR};
    use super::*;

    fn w(s: &mut Stm32f4, a: u32, v: u32) {
        assert!(matches!(s.write(a, 4, v, Ctx::default()), Access::Known(_)));
    }
    fn r(s: &mut Stm32f4, a: u32) -> u32 {
        match s.read(a, 4, Ctx::default()) {
            Access::Known(v) => v,
            other => panic!("{other:?}"),
        }
    }

    /// HSE bypass → PLL (M = 4, N = 180, P = 2): 180 MHz; AHB /1, APB1 /4, APB2 /2.
    fn to_180_mhz(s: &mut Stm32f4, latency: u32, overdrive: bool) {
        w(s, RCC_CR, 0x83 | (1 << 16) | (1 << 18));
        assert_ne!(r(s, RCC_CR) & (1 << 17), 0, "HSERDY");
        w(s, RCC_PLLCFGR, 4 | (180 << 6) | (1 << 22) | (2 << 28));
        w(s, RCC_CR, 0x83 | (1 << 16) | (1 << 18) | (1 << 24));
        assert_ne!(r(s, RCC_CR) & (1 << 25), 0, "PLLRDY");
        w(s, RCC_APB1ENR, 1 << 28);
        if overdrive {
            w(s, PWR, 0xC000 | (1 << 16));
            assert_ne!(r(s, PWR + 4) & (1 << 16), 0, "ODRDY");
            w(s, PWR, 0xC000 | (3 << 16));
            assert_ne!(r(s, PWR + 4) & (1 << 17), 0, "ODSWRDY");
        }
        w(s, FLASH_ACR, latency);
        w(s, RCC_CFGR, (5 << 10) | (4 << 13) | 2);
        assert_eq!((r(s, RCC_CFGR) >> 2) & 3, 2, "SWS = PLL");
    }

    #[test]
    fn the_nucleo_clock_setup_gives_180_mhz_and_a_45_mhz_apb1() {
        let mut s = Stm32f4::new();
        assert_eq!(s.core_hz(), 16_000_000, "HSI out of reset");
        to_180_mhz(&mut s, 5, true);
        assert_eq!(s.core_hz(), 180_000_000);
        assert_eq!(s.pclk1(), 45_000_000);
        assert_eq!(s.take_findings(), Vec::<String>::new());
    }

    #[test]
    fn rule_violations_are_reported() {
        // Without over-drive, 180 MHz is above the 168 MHz limit.
        let mut s = Stm32f4::new();
        to_180_mhz(&mut s, 5, false);
        let f = s.take_findings();
        assert!(f.iter().any(|f| f.contains("over-drive")), "{f:?}");
        // 4 wait states are too few at 180 MHz (RM0390 Table 5).
        let mut s = Stm32f4::new();
        to_180_mhz(&mut s, 4, true);
        let f = s.take_findings();
        assert!(f.iter().any(|f| f.contains("LATENCY = 4")), "{f:?}");
        // APB1 /2 at 180 MHz: 90 MHz, twice the maximum.
        let mut s = Stm32f4::new();
        w(&mut s, RCC_CR, 0x83 | (1 << 16) | (1 << 18));
        w(&mut s, RCC_PLLCFGR, 4 | (180 << 6) | (1 << 22));
        w(&mut s, RCC_CR, 0x83 | (1 << 16) | (1 << 18) | (1 << 24));
        w(&mut s, RCC_APB1ENR, 1 << 28);
        w(&mut s, PWR, 0xC000 | (3 << 16));
        w(&mut s, FLASH_ACR, 5);
        w(&mut s, RCC_CFGR, (4 << 10) | (4 << 13) | 2);
        let f = s.take_findings();
        assert!(f.iter().any(|f| f.contains("APB1 90000000")), "{f:?}");
        // The NUCLEO's HSE is the ST-LINK's MCO: without bypass it never becomes ready.
        let mut s = Stm32f4::new();
        w(&mut s, RCC_CR, 0x83 | (1 << 16));
        assert_eq!(r(&mut s, RCC_CR) & (1 << 17), 0);
        // A 216 MHz PLL (the F7's) does not lock on the F446: P output above 180 MHz.
        let mut s = Stm32f4::new();
        w(&mut s, RCC_CR, 0x83 | (1 << 16) | (1 << 18));
        w(&mut s, RCC_PLLCFGR, 4 | (216 << 6) | (1 << 22));
        w(&mut s, RCC_CR, 0x83 | (1 << 16) | (1 << 18) | (1 << 24));
        w(&mut s, RCC_CFGR, 2);
        assert_eq!((r(&mut s, RCC_CFGR) >> 2) & 3, 0, "SWS stays on HSI");
    }

    #[test]
    fn pll_r_can_be_sysclk() {
        let mut s = Stm32f4::new();
        w(&mut s, RCC_CR, 0x83 | (1 << 16) | (1 << 18));
        // VCO 360 MHz, R = 3: 120 MHz.
        w(&mut s, RCC_PLLCFGR, 4 | (180 << 6) | (1 << 22) | (3 << 28));
        w(&mut s, RCC_CR, 0x83 | (1 << 16) | (1 << 18) | (1 << 24));
        w(&mut s, FLASH_ACR, 3);
        w(&mut s, RCC_CFGR, (5 << 10) | (4 << 13) | 3);
        assert_eq!((r(&mut s, RCC_CFGR) >> 2) & 3, 3);
        assert_eq!(s.core_hz(), 120_000_000);
        assert_eq!(s.take_findings(), Vec::<String>::new());
    }

    #[test]
    fn can_instances_gates_and_lines() {
        let mut s = Stm32f4::new();
        let cans = s.can_instances();
        assert_eq!(cans.len(), 2);
        assert_eq!(
            (cans[0].name, cans[0].base, cans[1].name, cans[1].base),
            ("CAN1", 0x4000_6400, "CAN2", 0x4000_6800)
        );
        let lines = |c: &CanInstance| c.irqs.iter().map(|(_, n)| *n).collect::<Vec<_>>();
        assert_eq!(lines(&cans[0]), [19, 20, 21, 22]);
        assert_eq!(lines(&cans[1]), [63, 64, 65, 66]);
        assert!(!s.gate_open(cans[0].gate) && !s.gate_open(cans[1].gate));
        w(&mut s, RCC_APB1ENR, 1 << 26);
        assert!(!s.gate_open(cans[1].gate), "CAN2 needs CAN1's clock too");
        w(&mut s, RCC_APB1ENR, 3 << 25);
        assert!(s.gate_open(cans[0].gate) && s.gate_open(cans[1].gate));
        assert_eq!(s.gate_name(cans[1].gate), "RCC_APB1ENR.CAN1EN+CAN2EN");
    }

    #[test]
    fn can_pins_must_be_in_af9() {
        let mut s = Stm32f4::new();
        let cans = s.can_instances();
        s.can_joined(&cans[0]);
        assert_eq!(s.take_findings().len(), 1, "no pin configured");
        // CAN1 on PB8/PB9 (MODER 10, AFRH 9), GPIOB clocked.
        w(&mut s, RCC_AHB1ENR, 1 << 1);
        w(&mut s, GPIOA + 0x400, 0x0000_0280 | (0b1010 << 16));
        w(&mut s, GPIOA + 0x400 + 0x24, 0x99);
        s.can_joined(&cans[0]);
        assert_eq!(s.take_findings(), Vec::<String>::new());
        // CAN2 on PB12/PB13 in AF9 too.
        s.can_joined(&cans[1]);
        assert_eq!(s.take_findings().len(), 1);
        let moder = r(&mut s, GPIOA + 0x400);
        w(&mut s, GPIOA + 0x400, moder | (0b1010 << 24));
        w(&mut s, GPIOA + 0x400 + 0x24, 0x0099_0099);
        s.can_joined(&cans[1]);
        assert_eq!(s.take_findings(), Vec::<String>::new());
    }

    #[test]
    fn memory_map() {
        let s = Stm32f4::new();
        let m = s.memory();
        let size = |name: &str| m.iter().find(|r| r.name == name).map(|r| r.size);
        assert_eq!(size("flash"), Some(512 << 10));
        assert_eq!(size("SRAM1 + SRAM2"), Some(128 << 10));
        assert_eq!(s.boot_address(), 0);
        assert_eq!(s.irq_count(), 97);
    }
}
