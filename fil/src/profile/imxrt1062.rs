//! i.MX RT1062 on the Teensy 4.1: the boot ROM's reading of the boot image, the memory
//! map, and the system registers the start-up code uses, as rules.
//!
//! Sources: IMXRT1060RM (i.MX RT1060 Processor Reference Manual) — chapter "Memory
//! Maps" (ITCM 0x0000_0000, DTCM 0x2000_0000, OCRAM 0x2020_0000, FlexSPI 0x6000_0000,
//! peripheral addresses), "System Boot" (FlexSPI NOR boot: configuration block at offset
//! 0 with tag "FCFB", image vector table at offset 0x1000 with header tag 0xD1, boot data),
//! "Clock Controller Module (CCM)" (CCGR gates, `CSCMR2[CAN_CLK_SEL, CAN_CLK_PODF]`,
//! `CBCMR`/`CBCDR` root selection and dividers, `CDHIPR` handshakes), "Clock Control
//! Module Analog" (`PLL_ARM`, `PLL_USB1`, `PLL_SYS`, PFDs, SET/CLR/TOG aliases), "DCDC"
//! (`REG0[STS_DC_OK]`, `REG3[TRG]`), "IOMUXC" (pad mux, pad control, daisy chain); the
//! i.MX RT1060 data sheet (clock limits); the Teensy 4.1 schematic and pin card (pins
//! 22/23 = `GPIO_AD_B1_08/09`, 0/1 = `GPIO_AD_B0_03/02`, 30/31 = `GPIO_EMC_37/36`; 8 MB
//! flash). Reset values: the NXP SVD as `imxrt-ral` 0.6 (feature `imxrt1062`) carries it.
//!
//! Rules modelled:
//! - **Boot ROM** (FlexSPI NOR, execute in place): the configuration block's tag and
//!   version, the IVT header (tag 0xD1, length 0x0020, version 0x40–0x4F), its `self`
//!   pointer, no DCD and no plug-in, the boot data's image (which must start at
//!   0x6000_0000 and hold the IVT and the entry point). An even entry point is a vector
//!   table (SP from its word 0, PC from word 1); an odd one is the first instruction (the
//!   ROM's stack stays: `ROM_STACK`). VTOR is left at the ROM's table (0x0020_0000, not
//!   emulated): the firmware must set VTOR before its first exception.
//! - **Clocks after the ROM** (assumption, docs/fil.md): `PLL_SYS` (528 MHz) and
//!   `PLL_USB1` (480 MHz) locked, the core at 396 MHz (`PLL2_PFD2`), IPG at 99 MHz. The
//!   ARM PLL locks when powered with `DIV_SELECT` in 54–108 (648–1296 MHz); `CDHIPR`
//!   reads 0 (divider changes complete at once). Core above 600 MHz, IPG above 150 MHz,
//!   the CAN clock root above 80 MHz, or a core above 528 MHz with `DCDC_REG3[TRG]` below
//!   1.25 V are reported.
//! - **CAN clocks**: register access needs the module's CCGR gate (`can1_clk` CCGR0 CG7,
//!   `can2_clk` CG9, `can3_clk` CCGR7 CG3; a gated access is a bus error); the protocol
//!   engine needs the serial gate (CCGR0 CG8 / CG10, CCGR7 CG4) and the CAN clock root
//!   (`CAN_CLK_SEL` ≠ 3; 0 = `pll3_sw_clk`/8 = 60 MHz, 1 = 24 MHz oscillator, 2 =
//!   `pll3_sw_clk`/6 = 80 MHz, divided by `CAN_CLK_PODF` + 1) — or, on CAN3 with
//!   `CTRL1[CLKSRC]` = 1, the IPG clock. Without an engine clock no FlexCAN mode handshake
//!   completes. The root is off out of reset (`CSCMR2` = 0x1319_2F06: `CAN_CLK_SEL` = 3).
//! - **IOMUXC**: the CAN pads' mux (`ALT2` CAN1, `ALT0` CAN2, `ALT9` CAN3), pad control
//!   and daisy registers (`FLEXCAN1_RX_SELECT_INPUT` = 2, `FLEXCAN2_RX_SELECT_INPUT` = 1,
//!   `CANFD_IPP_IND_CANRX_SELECT_INPUT` = 0 for the Teensy pins) are known registers;
//!   a controller that joins the bus without them is reported. `IOMUXC_GPR14/16/17`
//!   (FlexRAM bank configuration) are stored: the profile maps the largest ITCM, DTCM and
//!   OCRAM and does not enforce the bank split.

use super::{Access, Boot, CanInstance, CanKind, Ctx, Memory, Profile, RegStore};
use twocan_flexcan::model::{Chip as FlexChip, Rt1062Can};

/// The 24 MHz crystal oscillator.
pub const OSC_HZ: u64 = 24_000_000;
/// `PLL_SYS` (PLL2) locked at 22 × 24 MHz.
pub const PLL2_HZ: u64 = 528_000_000;
/// `PLL_USB1` (PLL3, `pll3_sw_clk`) locked at 20 × 24 MHz.
pub const PLL3_HZ: u64 = 480_000_000;
/// The stack pointer the ROM leaves when it jumps to an odd entry point (its own stack in
/// OCRAM; the value is a stand-in: the firmware sets its own).
pub const ROM_STACK: u32 = 0x2020_8000;
/// The ROM's vector table, where VTOR stays after boot.
pub const ROM_VECTORS: u32 = 0x0020_0000;

/// FlexSPI (serial NOR flash) memory-mapped window.
pub const FLEXSPI: u32 = 0x6000_0000;
/// Teensy 4.1 flash size (W25Q64JV, 8 MiB).
pub const FLASH_SIZE: u32 = 8 << 20;
/// FlexSPI configuration block tag: "FCFB" little-endian.
pub const FCB_TAG: u32 = 0x4246_4346;
/// IVT offset in the flash for FlexSPI NOR boot.
pub const IVT_OFFSET: u32 = 0x1000;

const CCM: u32 = 0x400F_C000;
const CCM_CACRR: u32 = CCM + 0x10;
const CCM_CBCDR: u32 = CCM + 0x14;
const CCM_CBCMR: u32 = CCM + 0x18;
const CCM_CSCMR2: u32 = CCM + 0x20;
const CCM_CDHIPR: u32 = CCM + 0x48;
/// `CCM_CCGR0`: CG7 can1_clk (bits 15:14), CG8 can1_serial (17:16), CG9 can2_clk
/// (19:18), CG10 can2_serial (21:20).
pub const CCM_CCGR0: u32 = CCM + 0x68;
/// `CCM_CCGR7`: CG3 can3_clk (bits 7:6), CG4 can3_serial (9:8).
pub const CCM_CCGR7: u32 = CCM + 0x84;
/// `CCM_CSCMR2` (CAN clock root selection and divider).
pub const CSCMR2: u32 = CCM_CSCMR2;

const ANALOG: u32 = 0x400D_8000;
const PLL_ARM: u32 = ANALOG;
const PLL_USB1: u32 = ANALOG + 0x10;
const PLL_SYS: u32 = ANALOG + 0x30;
const PFD_480: u32 = ANALOG + 0xF0;
const PFD_528: u32 = ANALOG + 0x100;
const DCDC: u32 = 0x4008_0000;
const DCDC_REG0: u32 = DCDC;
const DCDC_REG3: u32 = DCDC + 0x0C;
const IOMUXC: u32 = 0x401F_8000;
const IOMUXC_GPR: u32 = 0x400A_C000;

/// The CAN pads of the Teensy 4.1: (instance, pad, mux register, mux value, pad
/// control register) for TX and RX, and the daisy register with the value that selects
/// the RX pad.
struct CanPins {
    name: &'static str,
    tx: (&'static str, u32, u32, u32),
    rx: (&'static str, u32, u32, u32),
    daisy: (u32, u32),
}

const PINS: [CanPins; 3] = [
    CanPins {
        name: "CAN1",
        tx: ("GPIO_AD_B1_08 (pin 22)", IOMUXC + 0x11C, 2, IOMUXC + 0x30C),
        rx: ("GPIO_AD_B1_09 (pin 23)", IOMUXC + 0x120, 2, IOMUXC + 0x310),
        daisy: (IOMUXC + 0x44C, 2),
    },
    CanPins {
        name: "CAN2",
        tx: ("GPIO_AD_B0_02 (pin 1)", IOMUXC + 0x0C4, 0, IOMUXC + 0x2B4),
        rx: ("GPIO_AD_B0_03 (pin 0)", IOMUXC + 0x0C8, 0, IOMUXC + 0x2B8),
        daisy: (IOMUXC + 0x450, 1),
    },
    CanPins {
        name: "CAN3",
        tx: ("GPIO_EMC_36 (pin 31)", IOMUXC + 0x0A4, 9, IOMUXC + 0x294),
        rx: ("GPIO_EMC_37 (pin 30)", IOMUXC + 0x0A8, 9, IOMUXC + 0x298),
        daisy: (IOMUXC + 0x78C, 0),
    },
];

/// Peripherals the profile keeps as storage (reported when touched): their name and
/// address range. Anything else in the peripheral space is a bus error.
const STORAGE: [(&str, u32, u32); 12] = [
    ("WDOG1", 0x400B_8000, 0x4000),
    ("RTWDOG", 0x400B_C000, 0x4000),
    ("WDOG2", 0x400D_0000, 0x4000),
    ("SNVS", 0x400D_4000, 0x4000),
    ("SRC", 0x400F_8000, 0x4000),
    ("PIT", 0x4008_4000, 0x4000),
    ("GPT1", 0x401E_C000, 0x4000),
    ("GPT2", 0x401F_0000, 0x4000),
    ("GPIO1-5", 0x401B_8000, 0x14000),
    ("GPIO6-9", 0x4200_0000, 0x10000),
    ("LPUART1-8", 0x4018_4000, 0x20000),
    // PMU, XTALOSC24M, USB_ANALOG and TEMPMON share the analog block after the PLLs.
    (
        "ANATOP (PMU, XTALOSC24M, USB_ANALOG, TEMPMON)",
        0x400D_8110,
        0xEF0,
    ),
];

/// The i.MX RT1062 of a Teensy 4.1.
#[derive(Debug, Clone)]
pub struct Imxrt1062 {
    regs: RegStore,
    findings: Vec<String>,
}

impl Default for Imxrt1062 {
    fn default() -> Self {
        Self::new()
    }
}

impl Imxrt1062 {
    /// The chip as the boot ROM leaves it.
    pub fn new() -> Self {
        let mut regs = RegStore::default();
        // CCM reset values (SVD).
        for (off, v) in [
            (0x00, 0x0401_107F), // CCR
            (0x08, 0x0000_0010), // CSR
            (0x0C, 0x0000_0100), // CCSR
            (0x10, 0x0000_0001), // CACRR: ARM_PODF = 1 (÷2)
            (0x14, 0x000A_8300), // CBCDR: IPG_PODF = 3, AHB_PODF = 0
            (0x18, 0x2DAE_8324), // CBCMR
            (0x1C, 0x0490_0000), // CSCMR1
            (0x20, 0x1319_2F06), // CSCMR2: CAN_CLK_SEL = 3 (off), CAN_CLK_PODF = 1
            (0x24, 0x0649_0B00), // CSCDR1
            (0x38, 0x0002_9150), // CSCDR2
            (0x3C, 0x0003_0841), // CSCDR3
            (0x54, 0x0000_0079), // CLPCR
            (0x5C, 0xFFFF_FFFF), // CIMR
            (0x60, 0x000A_0001), // CCOSR
            (0x64, 0x0000_FE62), // CGPR
            (0x68, 0xFFFF_FFFF), // CCGR0
            (0x6C, 0xFFFF_FFFF), // CCGR1
            (0x70, 0xFC3F_FFFF), // CCGR2
            (0x74, 0xFFFF_FFCF), // CCGR3
            (0x78, 0xFFFF_FFFF), // CCGR4
            (0x7C, 0xFFFF_FFFF), // CCGR5
            (0x80, 0xFFFF_FFFF), // CCGR6
            (0x84, 0xFFFF_FFFF), // CCGR7
            (0x88, 0xFFFF_FFFF), // CMEOR
        ] {
            regs.set(CCM + off, v);
        }
        // What the boot ROM changes (assumption, see the module documentation): the
        // core on PLL2_PFD2 (PRE_PERIPH_CLK_SEL = 1), PLL2 and PLL3 locked.
        let cbcmr = regs.get(CCM_CBCMR);
        regs.set(CCM_CBCMR, (cbcmr & !(3 << 18)) | (1 << 18));
        regs.set(PLL_ARM, 0x0001_3063); // powered down, bypassed (reset)
        regs.set(PLL_USB1, 0x8000_3040); // LOCK, POWER, ENABLE, EN_USB_CLKS, ×20
        regs.set(PLL_SYS, 0x8000_2001); // LOCK, ENABLE, ×22
        regs.set(PFD_480, 0x1311_100C);
        regs.set(PFD_528, 0x1018_101B); // PFD2 = 24: 528 × 18 / 24 = 396 MHz
        regs.set(DCDC_REG0, 0x1403_0111);
        regs.set(DCDC_REG3, 0x0000_010E); // TRG = 0x0E: 1.15 V
        for p in &PINS {
            for (_, mux, _, pad) in [p.tx, p.rx] {
                regs.set(mux, 5); // ALT5: GPIO
                regs.set(pad, 0x10B0);
            }
            regs.set(p.daisy.0, 0);
        }
        regs.set(IOMUXC_GPR + 0x40, 0x0020_0003); // GPR16
        Imxrt1062 {
            regs,
            findings: Vec::new(),
        }
    }

    fn field(&self, addr: u32, shift: u32, bits: u32) -> u32 {
        (self.regs.get(addr) >> shift) & ((1 << bits) - 1)
    }

    /// PLL2 PFD `n` output (Hz): PLL2 × 18 / FRAC (0 when gated).
    fn pll2_pfd(&self, n: u32) -> u64 {
        let v = self.regs.get(PFD_528) >> (8 * n);
        if v & 0x80 != 0 || v & 0x3F < 12 {
            return 0;
        }
        self.pll2() * 18 / u64::from(v & 0x3F)
    }

    fn pll2(&self) -> u64 {
        let v = self.regs.get(PLL_SYS);
        if v & (1 << 16) != 0 {
            OSC_HZ
        } else if v & (1 << 12) != 0 {
            0
        } else {
            OSC_HZ * if v & 1 != 0 { 22 } else { 20 }
        }
    }

    fn pll3(&self) -> u64 {
        let v = self.regs.get(PLL_USB1);
        if v & (1 << 16) != 0 {
            OSC_HZ
        } else if v & (1 << 12) == 0 {
            0
        } else {
            OSC_HZ * if v & 2 != 0 { 22 } else { 20 }
        }
    }

    /// Whether the ARM PLL locks: powered, DIV_SELECT 54–108.
    fn arm_pll_locks(&self) -> bool {
        let v = self.regs.get(PLL_ARM);
        v & (1 << 12) == 0 && (54..=108).contains(&(v & 0x7F))
    }

    /// ARM PLL output (Hz).
    fn pll1(&self) -> u64 {
        let v = self.regs.get(PLL_ARM);
        if v & (1 << 16) != 0 {
            OSC_HZ
        } else if self.arm_pll_locks() && v & (1 << 13) != 0 {
            OSC_HZ * u64::from(v & 0x7F) / 2
        } else {
            0
        }
    }

    /// The periph clock: `CBCDR[PERIPH_CLK_SEL]` between pre_periph and periph_clk2.
    fn periph_hz(&self) -> u64 {
        if self.field(CCM_CBCDR, 25, 1) == 0 {
            match self.field(CCM_CBCMR, 18, 2) {
                0 => self.pll2(),
                1 => self.pll2_pfd(2),
                2 => self.pll2_pfd(0),
                _ => self.pll1() / u64::from(self.field(CCM_CACRR, 0, 3) + 1),
            }
        } else {
            let src = match self.field(CCM_CBCMR, 12, 2) {
                0 => self.pll3(),
                1 => OSC_HZ,
                _ => self.pll2(),
            };
            src / u64::from(self.field(CCM_CBCDR, 27, 3) + 1)
        }
    }

    /// AHB_CLK_ROOT, the core clock.
    fn ahb_hz(&self) -> u64 {
        self.periph_hz() / u64::from(self.field(CCM_CBCDR, 10, 3) + 1)
    }

    /// IPG_CLK_ROOT.
    pub fn ipg_hz(&self) -> u64 {
        self.ahb_hz() / u64::from(self.field(CCM_CBCDR, 8, 2) + 1)
    }

    /// CAN_CLK_ROOT (Hz): 0 when `CAN_CLK_SEL` = 3.
    pub fn can_root_hz(&self) -> u64 {
        let src = match self.field(CSCMR2, 8, 2) {
            0 => self.pll3() / 8,
            1 => OSC_HZ,
            2 => self.pll3() / 6,
            _ => 0,
        };
        src / u64::from(self.field(CSCMR2, 2, 6) + 1)
    }

    /// The limits of the data sheet's clock table.
    fn check_limits(&mut self) {
        let (core, ipg, can) = (self.ahb_hz(), self.ipg_hz(), self.can_root_hz());
        let trg = self.field(DCDC_REG3, 0, 5);
        let mut f = Vec::new();
        if core > 600_000_000 {
            f.push(format!("core (AHB_CLK_ROOT) {core} Hz above 600 MHz"));
        } else if core > 528_000_000 && trg < 0x12 {
            f.push(format!(
                "core {core} Hz with DCDC_REG3.TRG = {trg:#x}: above 528 MHz needs 1.25 V (TRG 0x12)"
            ));
        }
        if ipg > 150_000_000 {
            f.push(format!("IPG_CLK_ROOT {ipg} Hz above 150 MHz"));
        }
        if can > 80_000_000 {
            f.push(format!("CAN_CLK_ROOT {can} Hz above 80 MHz"));
        }
        for x in f {
            if !self.findings.contains(&x) {
                self.findings.push(x);
            }
        }
    }

    fn peripheral(&self, addr: u32) -> Option<&'static str> {
        let ranges: [(&'static str, u32, u32); 5] = [
            ("CCM", CCM, 0x4000),
            ("CCM_ANALOG", ANALOG, 0x110),
            ("DCDC", DCDC, 0x4000),
            ("IOMUXC", IOMUXC, 0x4000),
            ("IOMUXC_GPR", IOMUXC_GPR, 0x4000),
        ];
        ranges
            .iter()
            .chain(STORAGE.iter())
            .find(|(_, base, size)| (*base..*base + *size).contains(&addr))
            .map(|(n, _, _)| *n)
    }

    fn known(&self, name: &str, addr: u32) -> bool {
        let w = addr & !3;
        match name {
            "CCM" => matches!(
                w - CCM,
                0x00 | 0x08
                    | 0x0C
                    | 0x10
                    | 0x14
                    | 0x18
                    | 0x1C
                    | 0x20
                    | 0x24
                    | 0x28
                    | 0x2C
                    | 0x30
                    | 0x38
                    | 0x3C
                    | 0x48
                    | 0x54
                    | 0x58
                    | 0x5C
                    | 0x60
                    | 0x64
                    | 0x68..=0x88
            ),
            "CCM_ANALOG" => matches!(w & !0xF, PLL_ARM | PLL_USB1 | PLL_SYS | PFD_480 | PFD_528),
            "DCDC" => w <= DCDC + 0x0C,
            "IOMUXC" => PINS
                .iter()
                .any(|p| [p.tx.1, p.tx.3, p.rx.1, p.rx.3, p.daisy.0].contains(&w)),
            "IOMUXC_GPR" => matches!(w - IOMUXC_GPR, 0x38 | 0x40 | 0x44),
            _ => false,
        }
    }

    /// Recomputes the status bits that follow control bits.
    fn settle(&mut self) {
        let lock = |v: u32, ok: bool| (v & !(1 << 31)) | (u32::from(ok) << 31);
        let arm = self.regs.get(PLL_ARM);
        self.regs.set(PLL_ARM, lock(arm, self.arm_pll_locks()));
        let usb = self.regs.get(PLL_USB1);
        self.regs.set(
            PLL_USB1,
            lock(usb, usb & (1 << 12) != 0 && usb & (1 << 16) == 0),
        );
        let sys = self.regs.get(PLL_SYS);
        self.regs.set(
            PLL_SYS,
            lock(sys, sys & (1 << 12) == 0 && sys & (1 << 16) == 0),
        );
        // DCDC_REG0[STS_DC_OK] (bit 31): the converter is in regulation.
        let reg0 = self.regs.get(DCDC_REG0);
        self.regs.set(DCDC_REG0, reg0 | (1 << 31));
        self.regs.set(CCM_CDHIPR, 0);
    }

    /// A write to a CCM_ANALOG register or its SET (+4), CLR (+8), TOG (+0xC) alias.
    fn analog_write(&mut self, addr: u32, size: usize, value: u32) {
        let w = addr & !3;
        let base = w & !0xF;
        let v = super::insert(0, addr, size, value);
        let cur = self.regs.get(base);
        let new = match w & 0xF {
            0x0 => super::insert(cur, addr, size, value),
            0x4 => cur | v,
            0x8 => cur & !v,
            _ => cur ^ v,
        };
        // LOCK (bit 31) is read-only.
        self.regs.set(base, (new & !(1 << 31)) | (cur & (1 << 31)));
    }

    fn gate_field(&self, reg: u32, cg: u32) -> bool {
        self.field(reg, 2 * cg, 2) != 0
    }

    fn instance(can: &CanInstance) -> usize {
        match can.name {
            "CAN1" => 0,
            "CAN2" => 1,
            _ => 2,
        }
    }
}

impl Profile for Imxrt1062 {
    fn name(&self) -> &'static str {
        "teensy41"
    }

    fn cpu_model(&self) -> i32 {
        unicorn_engine::ArmCpuModel::CORTEX_M7 as i32
    }

    fn memory(&self) -> Vec<Memory> {
        vec![
            Memory {
                name: "ITCM",
                base: 0,
                size: 512 << 10,
                writable: true,
                alias_of: None,
            },
            Memory {
                name: "DTCM",
                base: 0x2000_0000,
                size: 512 << 10,
                writable: true,
                alias_of: None,
            },
            Memory {
                name: "OCRAM",
                base: 0x2020_0000,
                size: 1 << 20,
                writable: true,
                alias_of: None,
            },
            Memory {
                name: "FlexSPI flash",
                base: FLEXSPI,
                size: FLASH_SIZE,
                writable: false,
                alias_of: None,
            },
        ]
    }

    fn boot_address(&self) -> u32 {
        ROM_VECTORS
    }

    fn boot(&self, read: &dyn Fn(u32) -> Option<u32>) -> Result<Option<Boot>, String> {
        let rd = |a: u32| read(a).ok_or_else(|| format!("cannot read 0x{a:08X}"));
        let tag = rd(FLEXSPI)?;
        if tag != FCB_TAG {
            return Err(format!(
                "no FlexSPI configuration block at 0x{FLEXSPI:08X} (tag 0x{tag:08X}, want \"FCFB\" 0x{FCB_TAG:08X})"
            ));
        }
        let version = rd(FLEXSPI + 4)?;
        if version >> 16 != 0x5601 {
            return Err(format!(
                "FlexSPI configuration block version 0x{version:08X} is not V1.x (0x5601xxxx)"
            ));
        }
        let ivt = FLEXSPI + IVT_OFFSET;
        let header = rd(ivt)?;
        let length = ((header >> 8) & 0xFF) << 8 | ((header >> 16) & 0xFF);
        let ivt_version = header >> 24;
        if header & 0xFF != 0xD1 || length != 0x20 || !(0x40..=0x4F).contains(&ivt_version) {
            return Err(format!(
                "no image vector table at 0x{ivt:08X} (header 0x{header:08X}: want tag 0xD1, length 0x0020, version 0x4x)"
            ));
        }
        let (entry, dcd, boot_data, this) =
            (rd(ivt + 4)?, rd(ivt + 12)?, rd(ivt + 16)?, rd(ivt + 20)?);
        if this != ivt {
            return Err(format!("IVT self pointer 0x{this:08X}, want 0x{ivt:08X}"));
        }
        if dcd != 0 {
            return Err(format!(
                "IVT names a DCD at 0x{dcd:08X}: device configuration data is not emulated"
            ));
        }
        let (start, size, plugin) = (rd(boot_data)?, rd(boot_data + 4)?, rd(boot_data + 8)?);
        if plugin != 0 {
            return Err("boot data: plug-in images are not emulated".into());
        }
        if start != FLEXSPI {
            return Err(format!(
                "boot data: image start 0x{start:08X} (a copy to RAM by the ROM) is not emulated; execute-in-place images start at 0x{FLEXSPI:08X}"
            ));
        }
        let inside = |a: u32| a >= start && u64::from(a) < u64::from(start) + u64::from(size);
        if !inside(ivt + 0x1F) || !inside(boot_data + 11) || !inside(entry & !1) {
            return Err(format!(
                "boot data: image 0x{start:08X}+0x{size:X} does not hold the IVT, the boot data and the entry 0x{entry:08X}"
            ));
        }
        let (sp, pc) = if entry & 1 == 0 {
            (rd(entry)?, rd(entry + 4)?)
        } else {
            (ROM_STACK, entry)
        };
        Ok(Some(Boot {
            sp,
            pc,
            vtor: ROM_VECTORS,
        }))
    }

    fn irq_count(&self) -> u32 {
        160
    }

    fn can_instances(&self) -> Vec<CanInstance> {
        [
            (
                "CAN1",
                0x401D_0000,
                (CCM_CCGR0, 3 << 14),
                Rt1062Can::Can1,
                36,
            ),
            (
                "CAN2",
                0x401D_4000,
                (CCM_CCGR0, 3 << 18),
                Rt1062Can::Can2,
                37,
            ),
            (
                "CAN3",
                0x401D_8000,
                (CCM_CCGR7, 3 << 6),
                Rt1062Can::Can3,
                154,
            ),
        ]
        .into_iter()
        .map(|(name, base, gate, can, irq)| CanInstance {
            name,
            base,
            size: 0x4000,
            gate,
            kind: CanKind::FlexCan(FlexChip::Imxrt1062(can)),
            irqs: vec![(name, irq)],
        })
        .collect()
    }

    fn read(&mut self, addr: u32, size: usize, _ctx: Ctx) -> Access {
        let Some(name) = self.peripheral(addr) else {
            return Access::Unmapped;
        };
        self.settle();
        let v = self.regs.read(addr, size);
        if self.known(name, addr) {
            Access::Known(v)
        } else {
            Access::Unknown { peripheral: name }
        }
    }

    fn write(&mut self, addr: u32, size: usize, value: u32, _ctx: Ctx) -> Access {
        let Some(name) = self.peripheral(addr) else {
            return Access::Unmapped;
        };
        let known = self.known(name, addr);
        match name {
            "CCM_ANALOG" if known => self.analog_write(addr, size, value),
            // CDHIPR is read-only.
            "CCM" if addr & !3 == CCM_CDHIPR => {}
            _ => self.regs.write(addr, size, value),
        }
        self.settle();
        if matches!(name, "CCM" | "CCM_ANALOG" | "DCDC") {
            self.check_limits();
        }
        if known {
            Access::Known(0)
        } else {
            Access::Unknown { peripheral: name }
        }
    }

    fn gated_access_is_bus_error(&self) -> bool {
        true
    }

    fn gate_open(&self, gate: (u32, u32)) -> bool {
        self.regs.get(gate.0) & gate.1 != 0
    }

    fn gate_name(&self, gate: (u32, u32)) -> &'static str {
        match gate {
            (CCM_CCGR0, m) if m == 3 << 14 => "CCM_CCGR0.CG7 (can1_clk)",
            (CCM_CCGR0, m) if m == 3 << 18 => "CCM_CCGR0.CG9 (can2_clk)",
            (CCM_CCGR7, m) if m == 3 << 6 => "CCM_CCGR7.CG3 (can3_clk)",
            _ => "CCM clock gate",
        }
    }

    fn core_hz(&self) -> u64 {
        self.ahb_hz()
    }

    fn can_clock_hz(&self, can: &CanInstance) -> u64 {
        let (reg, cg) = [(CCM_CCGR0, 8), (CCM_CCGR0, 10), (CCM_CCGR7, 4)][Self::instance(can)];
        if self.gate_field(reg, cg) {
            self.can_root_hz()
        } else {
            0
        }
    }

    fn can_bus_clock_hz(&self, _can: &CanInstance) -> u64 {
        self.ipg_hz()
    }

    fn can_engine_clocked(&self, can: &CanInstance, clksrc: bool) -> bool {
        if clksrc && Self::instance(can) == 2 {
            // CAN3 with CTRL1[CLKSRC] = 1: the peripheral (IPG) clock, behind the serial
            // gate like the root.
            let (reg, cg) = (CCM_CCGR7, 4);
            return self.gate_field(reg, cg) && self.ipg_hz() > 0;
        }
        self.can_clock_hz(can) > 0
    }

    fn can_pins(&self, can: &CanInstance) -> Result<(), String> {
        let p = &PINS[Self::instance(can)];
        let mut missing = Vec::new();
        for (pad, mux, alt, _) in [p.tx, p.rx] {
            let v = self.regs.get(mux) & 0xF;
            if v != alt {
                missing.push(format!("{pad} mux ALT{v} (want ALT{alt})"));
            }
        }
        let d = self.regs.get(p.daisy.0) & 3;
        if d != p.daisy.1 {
            missing.push(format!(
                "{} RX daisy select 0x{:08X} = {d} (want {})",
                p.name, p.daisy.0, p.daisy.1
            ));
        }
        if missing.is_empty() {
            Ok(())
        } else {
            Err(missing.join("; "))
        }
    }

    fn systick_external_divider(&self) -> Option<u64> {
        // The SysTick external reference is 100 kHz (the 24 MHz oscillator ÷ 240).
        Some((self.ahb_hz() / 100_000).max(1))
    }

    fn take_findings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.findings)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(p: &mut Imxrt1062, a: u32, v: u32) {
        assert!(matches!(p.write(a, 4, v, Ctx::default()), Access::Known(_)));
    }
    fn r(p: &mut Imxrt1062, a: u32) -> u32 {
        match p.read(a, 4, Ctx::default()) {
            Access::Known(v) => v,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn clocks_after_the_rom_and_the_arm_pll_to_600_mhz() {
        let mut p = Imxrt1062::new();
        assert_eq!(p.core_hz(), 396_000_000);
        assert_eq!(p.ipg_hz(), 99_000_000);
        assert_eq!(p.can_root_hz(), 0, "CAN_CLK_SEL = 3 out of reset");
        // ARM PLL: DIV_SELECT 100 → 1200 MHz, ARM_PODF ÷2 → 600 MHz.
        w(&mut p, PLL_ARM, (1 << 13) | 100);
        assert_ne!(r(&mut p, PLL_ARM) & (1 << 31), 0, "locked");
        w(&mut p, CCM_CACRR, 1);
        let cbcmr = r(&mut p, CCM_CBCMR);
        w(&mut p, CCM_CBCMR, cbcmr | (3 << 18));
        assert_eq!(p.core_hz(), 600_000_000);
        assert!(p.take_findings().iter().any(|f| f.contains("1.25 V")));
        w(&mut p, DCDC_REG3, 0x112);
        w(&mut p, PLL_ARM + 8, 1 << 13); // CLR ENABLE
        assert_eq!(p.core_hz(), 0);
        w(&mut p, PLL_ARM + 4, 1 << 13); // SET ENABLE
        assert_eq!(p.core_hz(), 600_000_000);
        assert_eq!(r(&mut p, DCDC_REG0) >> 31, 1);
        assert_eq!(r(&mut p, CCM_CDHIPR), 0);
        // DIV_SELECT out of 54..=108: no lock.
        w(&mut p, PLL_ARM, (1 << 13) | 120);
        assert_eq!(r(&mut p, PLL_ARM) >> 31, 0);
    }

    #[test]
    fn can_clock_root_gates_and_pins() {
        let mut p = Imxrt1062::new();
        let cans = p.can_instances();
        assert_eq!(
            cans.iter().map(|c| c.irqs[0].1).collect::<Vec<_>>(),
            [36, 37, 154]
        );
        assert!(!p.can_engine_clocked(&cans[0], false));
        // CAN_CLK_SEL = 2 (80 MHz), PODF = 0.
        let v = r(&mut p, CSCMR2);
        w(&mut p, CSCMR2, (v & !(0xFF << 2)) | (2 << 8));
        assert_eq!(p.can_clock_hz(&cans[0]), 80_000_000);
        assert!(p.can_engine_clocked(&cans[2], false));
        // The serial gate of CAN2 off: no engine clock for CAN2 only.
        let g = r(&mut p, CCM_CCGR0);
        w(&mut p, CCM_CCGR0, g & !(3 << 20));
        assert!(!p.can_engine_clocked(&cans[1], false));
        assert!(p.can_engine_clocked(&cans[0], false));
        assert!(p.gate_open(cans[1].gate), "register access gate still on");
        w(&mut p, CCM_CCGR0, g & !(3 << 18));
        assert!(!p.gate_open(cans[1].gate));
        // CAN3 on the IPG clock (CLKSRC = 1) with the root off.
        w(&mut p, CSCMR2, v);
        assert!(p.can_engine_clocked(&cans[2], true));
        assert!(!p.can_engine_clocked(&cans[2], false));
        // Pins: GPIO out of reset; CAN1 on pins 22/23 with its daisy value.
        assert!(p.can_pins(&cans[0]).is_err());
        w(&mut p, IOMUXC + 0x11C, 2);
        w(&mut p, IOMUXC + 0x120, 2);
        assert!(p.can_pins(&cans[0]).unwrap_err().contains("daisy"));
        w(&mut p, IOMUXC + 0x44C, 2);
        assert_eq!(p.can_pins(&cans[0]), Ok(()));
        w(&mut p, IOMUXC + 0xA4, 9);
        w(&mut p, IOMUXC + 0xA8, 9);
        assert_eq!(
            p.can_pins(&cans[2]),
            Ok(()),
            "CAN3 daisy 0 is the reset value"
        );
        assert_eq!(p.read(0x4000_0000, 4, Ctx::default()), Access::Unmapped);
        assert!(matches!(
            p.read(0x401B_8000, 4, Ctx::default()),
            Access::Unknown { .. }
        ));
    }

    fn image(words: &[(u32, u32)]) -> impl Fn(u32) -> Option<u32> + '_ {
        move |a| {
            words
                .iter()
                .find(|(at, _)| *at == a)
                .map(|(_, v)| *v)
                .or(Some(0xFFFF_FFFF))
        }
    }

    #[test]
    fn boot_rom_reads_fcb_ivt_and_boot_data() {
        let p = Imxrt1062::new();
        let ivt = FLEXSPI + 0x1000;
        let good = [
            (FLEXSPI, FCB_TAG),
            (FLEXSPI + 4, 0x5601_0400),
            (ivt, 0x4020_00D1),
            (ivt + 4, 0x6000_2000),
            (ivt + 12, 0),
            (ivt + 16, ivt + 0x20),
            (ivt + 20, ivt),
            (ivt + 0x20, FLEXSPI),
            (ivt + 0x24, 0x4000),
            (ivt + 0x28, 0),
            (0x6000_2000, 0x2007_0000),
            (0x6000_2004, 0x6000_2401),
        ];
        let b = p.boot(&image(&good)).unwrap().unwrap();
        assert_eq!(
            (b.sp, b.pc, b.vtor),
            (0x2007_0000, 0x6000_2401, ROM_VECTORS)
        );
        // Odd entry: a first instruction, the ROM's stack.
        let mut odd = good;
        odd[3].1 = 0x6000_2401;
        let b = p.boot(&image(&odd)).unwrap().unwrap();
        assert_eq!((b.sp, b.pc), (ROM_STACK, 0x6000_2401));
        for (i, v, why) in [
            (0, 0, "FCFB"),
            (2, 0x4020_00D2, "tag 0xD1"),
            (2, 0x3020_00D1, "version"),
            (4, 0x1, "DCD"),
            (6, ivt + 4, "self"),
            (7, 0x2020_0000, "copy"),
            (8, 0x100, "does not hold"),
            (9, 1, "plug-in"),
        ] {
            let mut bad = good;
            bad[i].1 = v;
            let e = p.boot(&image(&bad)).unwrap_err();
            assert!(e.contains(why), "{why}: {e}");
        }
    }
}
