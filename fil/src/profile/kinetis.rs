//! Kinetis K20 (Teensy 3.1/3.2, MK20DX256), K64 (Teensy 3.5, MK64FX512) and K66
//! (Teensy 3.6, MK66FX1M0): the system registers the start-up code uses, as rules.
//!
//! Sources: K20P64M72SF1RM, K64P144M120SF5RM, K66P144M180SF5RMV2 — chapters "Memory
//! map", "System Integration Module (SIM)", "Multipurpose Clock Generator (MCG)",
//! "Oscillator (OSC)", "Watchdog Timer (WDOG)", "Port control and interrupts (PORT)",
//! "General-Purpose Input/Output (GPIO)"; the Teensy 3.x schematics (16 MHz crystal).
//!
//! Rules modelled:
//! - **WDOG** (16-bit registers, chapter "Watchdog Timer", "Unlocking and updating the
//!   watchdog" and "The watchdog configuration time (WCT)"): the first unlock word must
//!   come within the WCT (256 bus clocks) after reset; the unlock sequence is 0xC520 then
//!   0xD928 written to `WDOG_UNLOCK` within 20 bus clocks; a control register must then
//!   be updated within the WCT. Each of these missed, or a wrong unlock word, resets the
//!   chip; a control write outside the window is ignored (reported). Left enabled, the
//!   watchdog resets the chip after `TOVAL × (PRESCVAL + 1)` watchdog clocks unless
//!   refreshed (0xA602, 0xB480 to `WDOG_REFRESH`).
//! - **OSC/MCG**: the 16 MHz crystal starts (`MCG_S.OSCINIT0`) only when `MCG_C2.EREFS0`
//!   requests the oscillator and `MCG_C2.RANGE0` selects the 8–32 MHz range; `IREFST`
//!   follows `C1.IREFS` (the external reference only once it runs); `CLKST` follows
//!   `C1.CLKS` when the selected clock runs; the PLL locks (`LOCK0`) only with its
//!   reference (`OSCCLK / (PRDIV0+1)`) and VCO (`ref × multiplier`) inside the chip's
//!   limits (K20/K64: reference 2–4 MHz, ×24…55, output 48–100 MHz on the K20 and
//!   48–120 MHz on the K64; K66: reference 8–16 MHz, ×16…47, VCO 180–360 MHz, output
//!   VCO/2).
//! - **SIM**: clock gates `SCGC1..7` (an access to a gated peripheral is a bus error),
//!   `CLKDIV1` output dividers (core = MCGOUTCLK / (OUTDIV1+1)), `SDID` read-only.
//! - **PORT** (`PCRn`, gated by `SCGC5`) and **GPIO** (not gated) as storage, with the
//!   set/clear/toggle registers acting on `PDOR`.

use super::{Access, CanInstance, CanKind, Ctx, Memory, Profile, RegStore};
use twocan_flexcan::model::Chip as FlexChip;

/// The three chips.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Chip {
    /// MK20DX256 (Teensy 3.1/3.2).
    K20,
    /// MK64FX512 (Teensy 3.5).
    K64,
    /// MK66FX1M0 (Teensy 3.6).
    K66,
}

/// The Teensy 3.x crystal.
pub const CRYSTAL_HZ: u64 = 16_000_000;
/// FEI mode out of reset: FLL at 640 × the 32.768 kHz slow internal reference.
pub const FEI_HZ: u64 = 32_768 * 640;
/// The fast internal reference before its divider (MCG_SC.FCRDIV), 4 MHz nominal.
pub const FAST_IRC_HZ: u64 = 4_000_000;
/// The slow internal reference, 32.768 kHz nominal.
pub const SLOW_IRC_HZ: u64 = 32_768;

const WDOG: u32 = 0x4005_2000;
const WDOG_STCTRLH: u32 = WDOG;
const WDOG_UNLOCK: u32 = WDOG + 0x0E;
const WDOG_REFRESH: u32 = WDOG + 0x0C;
const MCG: u32 = 0x4006_4000;
const OSC0_CR: u32 = 0x4006_5000;
const SIM_LOW: u32 = SIM;
const SIM: u32 = 0x4004_7000;
const SIM_SCGC1: u32 = SIM + 0x1028;
const SIM_SCGC3: u32 = SIM + 0x1030;
const SIM_SCGC5: u32 = SIM + 0x1038;
const SIM_SCGC6: u32 = SIM + 0x103C;
const SIM_SCGC7: u32 = SIM + 0x1040;
const SIM_CLKDIV1: u32 = SIM + 0x1044;
const SIM_SDID: u32 = SIM + 0x1024;
const PORTA: u32 = 0x4004_9000;
const GPIO: u32 = 0x400F_F000;
const PMC: u32 = 0x4007_D000;
const SMC: u32 = 0x4007_E000;

const MCG_C1: u32 = MCG;
const MCG_C2: u32 = MCG + 1;
const MCG_C5: u32 = MCG + 4;
const MCG_C6: u32 = MCG + 5;
const MCG_S: u32 = MCG + 6;

/// A Kinetis chip on a Teensy board.
#[derive(Debug, Clone)]
pub struct Kinetis {
    chip: Chip,
    regs: RegStore,
    /// Cycle of the first unlock key, if the sequence is under way.
    unlock_first: Option<u64>,
    /// Cycle at which the WCT window after a complete unlock closes.
    unlock_window_end: Option<u64>,
    /// The first unlock key was written (within the WCT after reset).
    unlock_seen: bool,
    /// A control register was updated in the current unlock window.
    configured: bool,
    /// Cycle at which the watchdog counter last restarted (reset, refresh, update).
    wdog_epoch: u64,
    /// Cycle of the first refresh word, if the sequence is under way.
    refresh_first: Option<u64>,
    findings: Vec<String>,
}

impl Kinetis {
    /// The chip out of power-on reset.
    pub fn new(chip: Chip) -> Self {
        let mut regs = RegStore::default();
        // WDOG_STCTRLH reset 0x01D3: WDOGEN, CLKSRC, ALLOWUPDATE, ... (WDOG chapter).
        regs.write(WDOG_STCTRLH, 2, 0x01D3);
        regs.write(WDOG + 0x04, 2, 0x004C); // TOVALH
        regs.write(WDOG + 0x06, 2, 0x4B4C); // TOVALL
        regs.write(WDOG + 0x16, 2, 0x0400); // PRESC
                                            // MCG: C1 = 0x04 (IREFS, FEI), C2 = 0x80 (LOCRE0) on K20/K64; S computed.
        regs.write(MCG_C1, 1, 0x04);
        regs.write(MCG_C2, 1, 0x80);
        regs.write(MCG + 3, 1, 0x00); // C4: DRST_DRS = 0, DMX32 = 0
        regs.write(MCG + 8, 1, 0x02); // SC: FCRDIV = 1 (fast IRC ÷ 2)
                                      // SIM gates (reset values per chapter "SIM"): SCGC4 0xF0100030, SCGC5 0x00040182,
                                      // SCGC6 0x40000001, SCGC7 0x00000006; CLKDIV1 0x00010000 (flash ÷ 2).
        regs.set(SIM + 0x1034, 0xF010_0030);
        regs.set(SIM_SCGC5, 0x0004_0182);
        regs.set(SIM_SCGC6, 0x4000_0001);
        regs.set(SIM_SCGC7, 0x0000_0006);
        regs.set(SIM_CLKDIV1, 0x0001_0000);
        regs.set(
            SIM_SDID,
            match chip {
                Chip::K20 => 0x0000_1000,
                Chip::K64 => 0x0000_1003,
                Chip::K66 => 0x0000_1004,
            },
        );
        Kinetis {
            chip,
            regs,
            unlock_first: None,
            unlock_window_end: None,
            unlock_seen: false,
            configured: false,
            wdog_epoch: 0,
            refresh_first: None,
            findings: Vec::new(),
        }
    }

    fn byte(&self, addr: u32) -> u8 {
        self.regs.read(addr, 1) as u8
    }

    /// The crystal oscillator runs: requested (C2.EREFS0) with the range that a 16 MHz
    /// crystal needs (RANGE0 = 1x: 8–32 MHz).
    fn osc_running(&self) -> bool {
        let c2 = self.byte(MCG_C2);
        c2 & 0x04 != 0 && (c2 >> 4) & 0b11 >= 2
    }

    /// PLL reference, multiplier and output limits of the chip; `Some(output)` when the
    /// PLL can lock with the current C5/C6 values.
    fn pll_output(&self) -> Option<u64> {
        if !self.osc_running() {
            return None;
        }
        let prdiv = u64::from(self.byte(MCG_C5) & 0x1F);
        let vdiv = u64::from(self.byte(MCG_C6) & 0x1F);
        match self.chip {
            Chip::K20 | Chip::K64 => {
                // Reference 2–4 MHz, ×24…55; output 48–100 MHz (K20 data sheet) or
                // 48–120 MHz (K64).
                let reference = CRYSTAL_HZ / (prdiv + 1);
                let out = reference * (vdiv + 24);
                let max = if self.chip == Chip::K20 {
                    100_000_000
                } else {
                    120_000_000
                };
                ((2_000_000..=4_000_000).contains(&reference)
                    && (48_000_000..=max).contains(&out)
                    && vdiv + 24 <= 55)
                    .then_some(out)
            }
            Chip::K66 => {
                // Reference 8–16 MHz, ×16…47; VCO 180–360 MHz, MCGPLLCLK = VCO / 2.
                let reference = CRYSTAL_HZ / (prdiv + 1);
                let vco = reference * (vdiv + 16);
                ((8_000_000..=16_000_000).contains(&reference)
                    && (180_000_000..=360_000_000).contains(&vco)
                    && vdiv + 16 <= 47)
                    .then_some(vco / 2)
            }
        }
    }

    fn pll_enabled(&self) -> bool {
        self.byte(MCG_C6) & 0x40 != 0 || self.byte(MCG_C5) & 0x40 != 0
    }

    /// MCG_S from the control registers.
    fn mcg_s(&self) -> u8 {
        let c1 = self.byte(MCG_C1);
        let c6 = self.byte(MCG_C6);
        let osc = self.osc_running();
        let mut s = 0u8;
        if osc {
            s |= 1 << 1; // OSCINIT0
        }
        let irefs = c1 & 0x04 != 0;
        if irefs || !osc {
            s |= 1 << 4; // IREFST
        }
        let plls = c6 & 0x40 != 0;
        if plls {
            s |= 1 << 5; // PLLST
        }
        let lock = self.pll_enabled() && self.pll_output().is_some();
        if lock {
            s |= 1 << 6; // LOCK0
        }
        let clkst = match c1 >> 6 {
            0 if plls && lock => 3,
            0 if plls => self.current_clkst(),
            0 => 0,
            1 => 1,
            2 if osc => 2,
            _ => self.current_clkst(),
        };
        s | (clkst << 2)
    }

    /// The clock currently selected when a requested one does not run: the hardware
    /// keeps the old selection. The stored S value holds it.
    fn current_clkst(&self) -> u8 {
        (self.regs.read(MCG_S, 1) as u8 >> 2) & 0b11
    }

    fn mcgout_hz(&self) -> u64 {
        match (self.regs.read(MCG_S, 1) >> 2) & 0b11 {
            0 => FEI_HZ,
            // CLKS = 1: the internal reference C2.IRCS selects, the fast one divided by
            // 2^FCRDIV (MCG_SC bits 3:1).
            1 if self.byte(MCG_C2) & 1 != 0 => FAST_IRC_HZ >> ((self.byte(MCG + 8) >> 1) & 7),
            1 => SLOW_IRC_HZ,
            2 => CRYSTAL_HZ,
            _ => self.pll_output().unwrap_or(FEI_HZ),
        }
    }

    /// Recomputes and stores `MCG_S` (read-only for software).
    fn settle(&mut self) {
        let s = self.mcg_s();
        self.regs.write(MCG_S, 1, u32::from(s));
    }

    fn peripheral(&self, addr: u32) -> Option<(&'static str, Option<(u32, u32)>)> {
        let port = |n: u32| (PORTA + n * 0x1000, SIM_SCGC5, 1u32 << (9 + n));
        if (WDOG..WDOG + 0x18).contains(&addr) {
            return Some(("WDOG", None));
        }
        if (MCG..MCG + 0x1000).contains(&addr) {
            return Some(("MCG", None));
        }
        if (OSC0_CR..OSC0_CR + 0x1000).contains(&addr) {
            return Some(("OSC", None));
        }
        if (SIM_LOW..SIM + 0x1064).contains(&addr) {
            return Some(("SIM", None));
        }
        for n in 0..5 {
            let (base, reg, bit) = port(n);
            if (base..base + 0x1000).contains(&addr) {
                return Some((
                    ["PORTA", "PORTB", "PORTC", "PORTD", "PORTE"][n as usize],
                    Some((reg, bit)),
                ));
            }
        }
        if (GPIO..GPIO + 0x140).contains(&addr) {
            return Some(("GPIO", None));
        }
        if (PMC..PMC + 0x1000).contains(&addr) {
            return Some(("PMC", None));
        }
        if (SMC..SMC + 0x1000).contains(&addr) {
            return Some(("SMC", None));
        }
        None
    }

    fn known(&self, addr: u32) -> bool {
        let w = addr & !3;
        match self.peripheral(addr).map(|p| p.0) {
            Some("WDOG") => true,
            Some("MCG") => addr < MCG + 0x0E,
            Some("OSC") => addr == OSC0_CR,
            Some("SIM") => {
                w == SIM_LOW
                    || (SIM + 0x1004..=SIM + 0x1060).contains(&w)
                        && !matches!(w - SIM, 0x1008 | 0x1014 | 0x1020)
            }
            Some(p) if p.starts_with("PORT") => (w & 0xFFF) < 0x84 || (w & 0xFFF) == 0xA0,
            Some("GPIO") => (w & 0x3F) <= 0x14,
            _ => false,
        }
    }

    fn wdog_write(&mut self, addr: u32, size: usize, value: u32, ctx: Ctx) -> Access {
        if addr == WDOG_UNLOCK && size == 2 {
            match (value, self.unlock_first) {
                (0xC520, _) => {
                    self.unlock_first = Some(ctx.cycles);
                    self.unlock_seen = true;
                    return Access::Known(0);
                }
                (0xD928, Some(first)) if ctx.cycles - first <= self.core_cycles(20) => {
                    self.unlock_first = None;
                    self.unlock_window_end = Some(ctx.cycles + self.core_cycles(256));
                    self.configured = false;
                    return Access::Known(0);
                }
                (0xD928, Some(first)) => {
                    return Access::Reset(format!(
                        "WDOG unlock keys {} bus clocks apart (at most 20)",
                        ctx.cycles - first
                    ))
                }
                _ => {
                    return Access::Reset(format!(
                        "WDOG_UNLOCK written with 0x{value:04X} out of the unlock sequence"
                    ))
                }
            }
        }
        if addr == WDOG_REFRESH {
            // Refresh: 0xA602 then 0xB480 within 20 bus clocks restarts the counter.
            match (value, self.refresh_first) {
                (0xA602, _) => self.refresh_first = Some(ctx.cycles),
                (0xB480, Some(first)) if ctx.cycles - first <= self.core_cycles(20) => {
                    self.refresh_first = None;
                    self.wdog_epoch = ctx.cycles;
                }
                _ => self.refresh_first = None,
            }
            return Access::Known(0);
        }
        let open = self.unlock_window_end.is_some_and(|end| ctx.cycles <= end);
        let allow = self.regs.read(WDOG_STCTRLH, 2) & 0x10 != 0;
        if open && allow {
            self.regs.write(addr, size, value);
            self.configured = true;
            self.wdog_epoch = ctx.cycles;
        } else {
            self.findings.push(format!(
                "WDOG register 0x{addr:08X} written outside the unlock window: ignored"
            ));
        }
        Access::Known(0)
    }

    /// Core cycles for `bus` bus clocks at the current dividers.
    fn core_cycles(&self, bus: u64) -> u64 {
        bus * (self.core_hz() / self.bus_hz().max(1)).max(1)
    }

    /// The watchdog's time-out in core cycles: `TOVAL × (PRESCVAL + 1)` watchdog clocks,
    /// the watchdog clock being the bus clock (`STCTRLH.CLKSRC = 1`, the reset value) or
    /// the 1 kHz LPO.
    fn wdog_timeout(&self) -> u64 {
        let toval = (u64::from(self.regs.read(WDOG + 0x04, 2)) << 16)
            | u64::from(self.regs.read(WDOG + 0x06, 2));
        let presc = u64::from((self.regs.read(WDOG + 0x16, 2) >> 8) & 7) + 1;
        let ticks = toval.max(4) * presc;
        if self.regs.read(WDOG_STCTRLH, 2) & 0x02 != 0 {
            self.core_cycles(ticks)
        } else {
            ticks * (self.core_hz() / 1000)
        }
    }

    fn gpio_write(&mut self, addr: u32, value: u32) {
        let port = addr & !0x3F;
        let pdor = port;
        let cur = self.regs.get(pdor);
        match addr & 0x3F {
            0x04 => self.regs.set(pdor, cur | value),
            0x08 => self.regs.set(pdor, cur & !value),
            0x0C => self.regs.set(pdor, cur ^ value),
            _ => self.regs.set(addr, value),
        }
    }
}

impl Profile for Kinetis {
    fn name(&self) -> &'static str {
        match self.chip {
            Chip::K20 => "teensy32",
            Chip::K64 => "teensy35",
            Chip::K66 => "teensy36",
        }
    }

    fn cpu_model(&self) -> i32 {
        unicorn_engine::ArmCpuModel::CORTEX_M4 as i32
    }

    fn memory(&self) -> Vec<Memory> {
        let (flash, ram_base, ram_size) = match self.chip {
            Chip::K20 => (256 << 10, 0x1FFF_8000, 64 << 10),
            Chip::K64 => (512 << 10, 0x1FFF_0000, 192 << 10),
            Chip::K66 => (1024 << 10, 0x1FFF_0000, 256 << 10),
        };
        vec![
            Memory {
                name: "flash",
                base: 0,
                size: flash,
                writable: false,
                alias_of: None,
            },
            Memory {
                name: "SRAM",
                base: ram_base,
                size: ram_size,
                writable: true,
                alias_of: None,
            },
        ]
    }

    fn boot_address(&self) -> u32 {
        0
    }

    fn irq_count(&self) -> u32 {
        match self.chip {
            Chip::K20 => 92,
            Chip::K64 => 86,
            Chip::K66 => 100,
        }
    }

    fn can_instances(&self) -> Vec<CanInstance> {
        let (chip, base0) = match self.chip {
            Chip::K20 => (FlexChip::Mk20dx256, 29),
            Chip::K64 => (FlexChip::Mk64fx512, 75),
            Chip::K66 => (FlexChip::Mk66fx1m0, 75),
        };
        let lines = |b: u32| {
            vec![
                ("ORed message buffer", b),
                ("bus off", b + 1),
                ("error", b + 2),
                ("tx warning", b + 3),
                ("rx warning", b + 4),
                ("wake up", b + 5),
            ]
        };
        let mut v = vec![CanInstance {
            name: "CAN0",
            base: 0x4002_4000,
            size: 0x1000,
            gate: (SIM_SCGC6, 1 << 4),
            kind: CanKind::FlexCan(chip),
            irqs: lines(base0),
        }];
        if self.chip == Chip::K66 {
            v.push(CanInstance {
                name: "CAN1",
                base: 0x400A_4000,
                size: 0x1000,
                gate: (SIM_SCGC3, 1 << 4),
                kind: CanKind::FlexCan(chip),
                irqs: lines(94),
            });
        }
        v
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
        if (MCG..MCG + 0x10).contains(&addr) {
            self.settle();
        }
        let v = self.regs.read(addr, size);
        if self.known(addr) {
            Access::Known(v)
        } else {
            Access::Unknown { peripheral: name }
        }
    }

    fn write(&mut self, addr: u32, size: usize, value: u32, ctx: Ctx) -> Access {
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
        if !self.known(addr) {
            self.regs.write(addr, size, value);
            return Access::Unknown { peripheral: name };
        }
        match name {
            "WDOG" => return self.wdog_write(addr, size, value, ctx),
            "GPIO" => self.gpio_write(addr & !3, value),
            _ if addr == SIM_SDID || addr == MCG_S => {
                // read-only
            }
            _ => {
                self.regs.write(addr, size, value);
                if (MCG..MCG + 0x10).contains(&addr) {
                    self.settle();
                }
            }
        }
        Access::Known(0)
    }

    fn gated_access_is_bus_error(&self) -> bool {
        true
    }

    fn gate_open(&self, gate: (u32, u32)) -> bool {
        self.regs.get(gate.0) & gate.1 != 0
    }

    fn gate_name(&self, gate: (u32, u32)) -> &'static str {
        match gate {
            (SIM_SCGC6, 0x10) => "SIM_SCGC6.FLEXCAN0",
            (SIM_SCGC3, 0x10) => "SIM_SCGC3.FLEXCAN1",
            (SIM_SCGC5, m) => match m.trailing_zeros() {
                9 => "SIM_SCGC5.PORTA",
                10 => "SIM_SCGC5.PORTB",
                11 => "SIM_SCGC5.PORTC",
                12 => "SIM_SCGC5.PORTD",
                _ => "SIM_SCGC5.PORTE",
            },
            (SIM_SCGC1, _) => "SIM_SCGC1",
            _ => "SIM clock gate",
        }
    }

    fn core_hz(&self) -> u64 {
        let outdiv1 = u64::from(self.regs.get(SIM_CLKDIV1) >> 28);
        self.mcgout_hz() / (outdiv1 + 1)
    }

    fn can_clock_hz(&self, _can: &CanInstance) -> u64 {
        // CTRL1.CLKSRC = 0: OSCERCLK (the crystal, with OSC0_CR.ERCLKEN); 1: bus clock.
        // The harness decodes CLKSRC itself; this is OSCERCLK.
        if self.osc_running() && self.regs.read(OSC0_CR, 1) & 0x80 != 0 {
            CRYSTAL_HZ
        } else {
            0
        }
    }

    fn systick_external_divider(&self) -> Option<u64> {
        None
    }

    fn take_findings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.findings)
    }

    fn reset_deadline(&self) -> Option<(u64, String)> {
        if !self.unlock_seen {
            return Some((
                self.core_cycles(256),
                "watchdog reset: WDOG not unlocked within the WCT (256 bus clocks) after reset"
                    .into(),
            ));
        }
        if let (Some(end), false) = (self.unlock_window_end, self.configured) {
            return Some((
                end,
                "watchdog reset: WDOG unlocked but not updated within the WCT".into(),
            ));
        }
        (self.regs.read(WDOG_STCTRLH, 2) & 1 != 0).then(|| {
            (
                self.wdog_epoch + self.wdog_timeout(),
                "watchdog reset: time-out (WDOG left enabled and not refreshed)".into(),
            )
        })
    }
}

impl Kinetis {
    /// The bus clock now (Hz): MCGOUTCLK / (OUTDIV2 + 1).
    pub fn bus_hz(&self) -> u64 {
        let outdiv2 = u64::from((self.regs.get(SIM_CLKDIV1) >> 24) & 0xF);
        self.mcgout_hz() / (outdiv2 + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w8(k: &mut Kinetis, a: u32, v: u8) {
        assert_eq!(
            k.write(a, 1, u32::from(v), Ctx::default()),
            Access::Known(0)
        );
    }
    fn s(k: &mut Kinetis) -> u8 {
        match k.read(MCG_S, 1, Ctx::default()) {
            Access::Known(v) => v as u8,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn fei_to_fbe_needs_the_right_crystal_range() {
        let mut k = Kinetis::new(Chip::K66);
        assert_eq!(k.core_hz(), FEI_HZ);
        // RANGE0 = 1 (3–8 MHz) with a 16 MHz crystal: the oscillator does not start.
        w8(&mut k, MCG_C2, 0x14);
        w8(&mut k, MCG_C1, 0xA0);
        assert_eq!(s(&mut k) & 0x02, 0, "no OSCINIT0 with the wrong range");
        assert_eq!((s(&mut k) >> 2) & 3, 0, "CLKST stays on the FLL");
        w8(&mut k, MCG_C2, 0x24);
        let st = s(&mut k);
        assert_eq!(st & 0x02, 0x02);
        assert_eq!(st & 0x10, 0, "IREFST follows IREFS = 0");
        assert_eq!((st >> 2) & 3, 2);
        assert_eq!(k.core_hz(), CRYSTAL_HZ);
    }

    #[test]
    fn pll_locks_only_within_limits() {
        let mut k = Kinetis::new(Chip::K20);
        w8(&mut k, MCG_C2, 0x24);
        // ref = 16 MHz / 1: outside 2–4 MHz.
        w8(&mut k, MCG_C5, 0x00);
        w8(&mut k, MCG_C6, 0x40);
        assert_eq!(s(&mut k) & 0x40, 0);
        // ref = 16 / 4 = 4 MHz, ×24 = 96 MHz: locks.
        w8(&mut k, MCG_C5, 0x03);
        assert_eq!(s(&mut k) & 0x40, 0x40);
        // K66 at 180 MHz as Teensyduino sets it: 16 / 2 = 8 MHz × 45 = 360 MHz VCO.
        let mut k = Kinetis::new(Chip::K66);
        w8(&mut k, MCG_C2, 0x24);
        w8(&mut k, MCG_C5, 0x01);
        w8(&mut k, MCG_C6, 0x40 | 29);
        assert_eq!(s(&mut k) & 0x40, 0x40);
        assert_eq!(k.pll_output(), Some(180_000_000));
        // 16 MHz × 45 = 720 MHz: out of range.
        w8(&mut k, MCG_C5, 0x00);
        assert_eq!(s(&mut k) & 0x40, 0);
    }

    #[test]
    fn watchdog_unlock_rules_and_gates() {
        let mut k = Kinetis::new(Chip::K20);
        let at = |c| Ctx { cycles: c };
        assert_eq!(k.write(WDOG_UNLOCK, 2, 0xC520, at(0)), Access::Known(0));
        assert!(matches!(
            k.write(WDOG_UNLOCK, 2, 0xD928, at(30)),
            Access::Reset(_)
        ));
        let mut k = Kinetis::new(Chip::K20);
        k.write(WDOG_UNLOCK, 2, 0xC520, at(0));
        k.write(WDOG_UNLOCK, 2, 0xD928, at(2));
        k.write(WDOG_STCTRLH, 2, 0x0010, at(6));
        assert_eq!(k.read(WDOG_STCTRLH, 2, at(7)), Access::Known(0x0010));
        k.write(WDOG_STCTRLH, 2, 0x0011, at(1000));
        assert_eq!(k.read(WDOG_STCTRLH, 2, at(7)), Access::Known(0x0010));
        assert_eq!(k.take_findings().len(), 1);
        // PORTC is gated at reset? SCGC5 reset 0x00040182: PORTC (bit 11) is off.
        assert!(matches!(
            k.read(0x4004_B014, 4, at(0)),
            Access::Gated { .. }
        ));
        assert!(!k.gate_open((SIM_SCGC6, 1 << 4)), "FlexCAN0 gated at reset");
        assert_eq!(k.read(0x4008_8000, 4, at(0)), Access::Unmapped);
    }

    #[test]
    fn watchdog_deadlines() {
        let at = |c| Ctx { cycles: c };
        let k = Kinetis::new(Chip::K66);
        let (when, why) = k.reset_deadline().unwrap();
        assert_eq!(when, 256, "{why}");
        let mut k = Kinetis::new(Chip::K66);
        k.write(WDOG_UNLOCK, 2, 0xC520, at(10));
        k.write(WDOG_UNLOCK, 2, 0xD928, at(12));
        assert_eq!(
            k.reset_deadline().unwrap().0,
            12 + 256,
            "update within the WCT"
        );
        k.write(WDOG_STCTRLH, 2, 0x01D3, at(20)); // still enabled
                                                  // TOVAL 0x004C4B4C × (PRESCVAL 4 + 1) bus clocks from the update.
        assert_eq!(k.reset_deadline().unwrap().0, 20 + 0x004C_4B4C * 5);
        k.write(WDOG_REFRESH, 2, 0xA602, at(1000));
        k.write(WDOG_REFRESH, 2, 0xB480, at(1005));
        assert_eq!(k.reset_deadline().unwrap().0, 1005 + 0x004C_4B4C * 5);
        let mut k = Kinetis::new(Chip::K66);
        k.write(WDOG_UNLOCK, 2, 0xC520, at(10));
        k.write(WDOG_UNLOCK, 2, 0xD928, at(12));
        k.write(WDOG_STCTRLH, 2, 0x0010, at(16));
        assert_eq!(k.reset_deadline(), None, "disabled");
    }
}
