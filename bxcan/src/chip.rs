//! The STM32 parts that carry the bxCAN cell, as data: what differs between them is read
//! from a [`Chip`] by the driver ([`crate::Config::chip`]: which instances exist, the
//! banks each owns, the APB1 limit), by the planner ([`Chip::plan_options`]), the
//! capabilities report, the HAL hand-over, the behavioural model
//! (`model::BxCanModel::of_part`, feature `model`) and the firmware-in-the-loop board profiles.
//! A new part of a supported family is a new `Chip` value, not new code.
//!
//! The bxCAN cell is the same on every part below: the same register offsets, bit
//! positions and reset values (`CAN_MCR` 0x0001_0002 with `DBF`, `CAN_MSR` 0x0000_0C02,
//! `CAN_TSR` 0x1C00_0000, `CAN_BTR` 0x0123_0000 with `BRP[9:0]`, `TS1[3:0]`, `TS2[2:0]`,
//! `SJW[1:0]`, `CAN_FMR` 0x2A1C_0E01), the time-triggered communication option (`TTCM`)
//! and debug freeze (`DBF`) everywhere — RM0008 §24.9, RM0090 §32.9, RM0390 §30.9, RM0430
//! §32.9, RM0385 §40.9, RM0410 §40.9 ([`crate::regs`] is that one map). What differs:
//!
//! - **the instances** (CAN1 alone; CAN1 + CAN2; CAN1 + CAN2 + CAN3), their base
//!   addresses, clock-enable bits, interrupt numbers and pins;
//! - **the filter banks of CAN1's block**: 14 on single-CAN parts, 28 shared with CAN2 on
//!   dual-CAN parts (RM0008 §24.2 "28 filter banks shared between CAN1 and CAN2 in
//!   connectivity line devices, 14 filter banks in other STM32F10xxx devices"), and
//!   **`CAN_FMR.CAN2SB`**, present on dual-CAN parts only (RM0008 §24.9.4: "available in
//!   connectivity line devices only and are reserved otherwise"): the driver never
//!   writes it on a single-CAN part;
//! - **CAN3**, where it exists, has its own block of 14 banks and no `CAN2SB`, at a base
//!   address and clock-enable bit that differ between the F413/F423 (0x4000_6C00,
//!   `RCC_APB1ENR` bit 27, RM0430) and the F76x/F77x (0x4000_3400, bit 13, RM0410);
//! - **the clock**: bxCAN runs on APB1 (PCLK1), whose maximum differs per part (the
//!   datasheets' "general operating conditions");
//! - **the pins**: alternate-function numbers on the F2/F4/F7 (GPIO AF tables of the
//!   datasheets), `AFIO_MAPR` remap values on the F1 (RM0008 §9.3.3, §9.4.2);
//! - **the F103's message SRAM**: on the low-, medium-, high- and XL-density STM32F103 the
//!   CAN and the USB device share a dedicated 512-byte SRAM and "cannot be used
//!   concurrently" (RM0008 §24.2, note). The driver cannot see the USB peripheral: the
//!   program must keep `RCC_APB1ENR.USBEN` clear while CAN runs
//!   ([`Chip::sram_shared_with_usb`]; the `bluepill` board profile reports both clocks on
//!   at once as a finding).

use crate::regs::Instance;

/// Filter banks of a single-CAN block (CAN3; the CAN of a single-CAN part): RM0008 §24.2,
/// RM0410 §40.2 Table 289, RM0430 §32.2 Table 219.
pub const SINGLE_BLOCK_BANKS: usize = 14;
/// Filter banks of a dual-CAN block (CAN1's, shared with CAN2 at `CAN2SB`): RM0008 §24.2,
/// RM0390 §30.2, RM0410 §40.2.
pub const DUAL_BLOCK_BANKS: usize = 28;

/// A GPIO pin, as the datasheets name it (`PA11`: port `'A'`, number 11).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Pin {
    /// The port letter.
    pub port: char,
    /// The pin number in the port (0..=15).
    pub number: u8,
}

/// `PXn` as a [`Pin`].
const fn p(port: char, number: u8) -> Pin {
    Pin { port, number }
}

/// How a pin pair is routed to the controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PinMux {
    /// The GPIO alternate function number (F2/F4/F7: `GPIOx_AFRL`/`AFRH`).
    Af(u8),
    /// The F1's `AFIO_MAPR.CAN_REMAP[1:0]` (bits 14:13) value (RM0008 §9.4.2; CAN1 on the
    /// connectivity line: `CAN1_REMAP`), pins in input (RX) and alternate-function
    /// push-pull output (TX) mode (RM0008 §9.1.11 Table 27).
    F1CanRemap(u8),
    /// The F105/F107's `AFIO_MAPR.CAN2_REMAP` (bit 22) value (RM0008 §9.4.2).
    F1Can2Remap(u8),
}

/// One pin pair a controller can use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanPins {
    /// The receive pin (`CANx_RX`).
    pub rx: Pin,
    /// The transmit pin (`CANx_TX`).
    pub tx: Pin,
    /// How it is routed.
    pub mux: PinMux,
}

/// One bxCAN instance of a part.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanInstance {
    /// Which controller this is (the F103's single `CAN` is [`Instance::Can1`]).
    pub instance: Instance,
    /// Name as the reference manual spells it (`CAN` on the STM32F103).
    pub name: &'static str,
    /// Base address of its register window (1 KiB).
    pub base: u32,
    /// Bit of `RCC_APB1ENR` that gates its clock.
    pub apb1enr_bit: u8,
    /// Interrupt numbers of its four lines (TX, RX0, RX1, SCE), with the vector names of
    /// the manual's vector table.
    pub irqs: [(&'static str, u16); 4],
    /// The pin pairs of the datasheet's alternate-function table (the pins the part's
    /// packages bond out may be fewer).
    pub pins: &'static [CanPins],
}

/// The bxCAN facts of one STM32 part (or family of parts with the same facts).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Chip {
    /// The parts this describes.
    pub name: &'static str,
    /// The reference manual and its bxCAN chapter.
    pub manual: &'static str,
    /// The bxCAN instances, CAN1 first.
    pub instances: &'static [CanInstance],
    /// Filter banks of CAN1's block (shared with CAN2 on dual-CAN parts): 14 or 28.
    pub can1_banks: usize,
    /// Address of `RCC_APB1ENR` (the clock enables of [`CanInstance::apb1enr_bit`]).
    pub rcc_apb1enr: u32,
    /// Highest APB1 clock (bxCAN's clock) the part allows, in Hz.
    pub apb1_max_hz: u32,
    /// The CAN shares its message SRAM with the USB device peripheral (STM32F103): the two
    /// cannot run at the same time (RM0008 §24.2, note).
    pub sram_shared_with_usb: bool,
}

#[cfg(feature = "defmt")]
impl defmt::Format for Chip {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "{=str}", self.name)
    }
}

impl Chip {
    /// Whether CAN2 exists: then `CAN_FMR.CAN2SB` splits CAN1's banks between the two.
    pub const fn dual(&self) -> bool {
        self.has(Instance::Can2)
    }

    /// Whether the part has `instance`.
    pub const fn has(&self, instance: Instance) -> bool {
        self.instance(instance).is_some()
    }

    /// The description of `instance`, if the part has it.
    pub const fn instance(&self, instance: Instance) -> Option<&'static CanInstance> {
        let mut i = 0;
        while i < self.instances.len() {
            let c = &self.instances[i];
            if c.instance as u8 == instance as u8 {
                return Some(c);
            }
            i += 1;
        }
        None
    }

    /// Filter banks of the block `instance` configures and uses: CAN1's block for CAN1
    /// and CAN2, CAN3's own 14; `None` if the part has no such instance.
    pub const fn banks_of(&self, instance: Instance) -> Option<usize> {
        if !self.has(instance) {
            return None;
        }
        Some(match instance {
            Instance::Can3 => SINGLE_BLOCK_BANKS,
            _ => self.can1_banks,
        })
    }

    /// The banks (`start..end`, hardware numbering) `instance` owns, given the `CAN2SB`
    /// value read from the block (values above the block's size read as its size): on a
    /// dual-CAN part CAN1 `0..CAN2SB`, CAN2 `CAN2SB..28`; a single-CAN block (the F103's
    /// CAN, CAN3) is all the instance's whatever its reserved `CAN2SB` bits hold
    /// (RM0008 §24.9.4). `(0, 0)` for an instance the part does not have.
    pub const fn bank_range(&self, instance: Instance, can2sb: u32) -> (usize, usize) {
        let Some(banks) = self.banks_of(instance) else {
            return (0, 0);
        };
        let shared = self.dual() && !matches!(instance, Instance::Can3);
        if !shared {
            return (0, banks);
        }
        let split = if can2sb as usize > banks {
            banks
        } else {
            can2sb as usize
        };
        match instance {
            Instance::Can2 => (split, banks),
            _ => (0, split),
        }
    }

    /// Whether `bank` is a valid `CAN2SB` (start bank of CAN2) here: only on a dual-CAN
    /// part, at most the block's size (RM0008 §24.9.4, RM0390 §30.9.4).
    pub const fn start_bank_valid(&self, bank: u8) -> bool {
        self.dual() && bank as usize <= self.can1_banks
    }

    /// Planner options for the most banks `instance` can own here (`CAN2SB` moved to
    /// give it the whole block): 28 for CAN1 or CAN2 of a dual-CAN part, 14 for the
    /// F103's CAN and CAN3; 0 (nothing fits) for an instance the part lacks. A running
    /// controller plans for the banks it owns now ([`crate::Can::plan_options`]).
    pub const fn plan_options(&self, instance: Instance) -> crate::planner::PlanOptions {
        let banks = match self.banks_of(instance) {
            Some(b) => b,
            None => 0,
        };
        crate::planner::PlanOptions::new(banks as u8)
    }

    /// Whether `apb1_hz` is within the part's APB1 limit (0, an unknown clock, is).
    pub const fn clock_allowed(&self, apb1_hz: u32) -> bool {
        apb1_hz <= self.apb1_max_hz
    }

    /// The interrupt number of `instance`'s `line` (0 TX, 1 RX0, 2 RX1, 3 SCE).
    pub const fn irq(&self, instance: Instance, line: usize) -> Option<u16> {
        match self.instance(instance) {
            Some(c) if line < 4 => Some(c.irqs[line].1),
            _ => None,
        }
    }

    /// Every part described here.
    pub const ALL: [&'static Chip; 7] = [
        &STM32F103,
        &STM32F105_F107,
        &STM32F405_F407,
        &STM32F446,
        &STM32F413_F423,
        &STM32F74X_F75X,
        &STM32F76X_F77X,
    ];
}

/// `RCC_APB1ENR` of the STM32F1 (RCC at 0x4002_1000, offset 0x1C; RM0008 §7.3.8).
const F1_APB1ENR: u32 = 0x4002_101C;
/// `RCC_APB1ENR` of the STM32F2/F4/F7 (RCC at 0x4002_3800, offset 0x40; RM0090 §7.3.13,
/// RM0390 §6.3.13, RM0410 §5.3.13).
const F4_APB1ENR: u32 = 0x4002_3840;

/// The interrupt lines of CAN1 on every part but the F1 performance line (the vector
/// tables of RM0090 §12.2, RM0390 §10.2, RM0430 §10.2, RM0410 §10.2): 19..=22.
const CAN1_IRQS: [(&str, u16); 4] = [
    ("CAN1_TX", 19),
    ("CAN1_RX0", 20),
    ("CAN1_RX1", 21),
    ("CAN1_SCE", 22),
];
/// CAN2's lines (same tables; RM0008 §10.1.2, connectivity line table): 63..=66.
const CAN2_IRQS: [(&str, u16); 4] = [
    ("CAN2_TX", 63),
    ("CAN2_RX0", 64),
    ("CAN2_RX1", 65),
    ("CAN2_SCE", 66),
];

/// CAN1's pins on the F1 (RM0008 §9.3.3 Table 36, `CAN_REMAP` / `CAN1_REMAP`): PA11/PA12
/// (00), PB8/PB9 (10), PD0/PD1 (11).
const F1_CAN1_PINS: &[CanPins] = &[
    CanPins {
        rx: p('A', 11),
        tx: p('A', 12),
        mux: PinMux::F1CanRemap(0b00),
    },
    CanPins {
        rx: p('B', 8),
        tx: p('B', 9),
        mux: PinMux::F1CanRemap(0b10),
    },
    CanPins {
        rx: p('D', 0),
        tx: p('D', 1),
        mux: PinMux::F1CanRemap(0b11),
    },
];
/// CAN2's pins on the F105/F107 (RM0008 §9.3.3 Table 37, `CAN2_REMAP`): PB12/PB13 (0),
/// PB5/PB6 (1).
const F1_CAN2_PINS: &[CanPins] = &[
    CanPins {
        rx: p('B', 12),
        tx: p('B', 13),
        mux: PinMux::F1Can2Remap(0),
    },
    CanPins {
        rx: p('B', 5),
        tx: p('B', 6),
        mux: PinMux::F1Can2Remap(1),
    },
];
/// CAN1's pins on the F4/F7 (datasheets' alternate-function tables, AF9): PA11/PA12,
/// PB8/PB9, PD0/PD1 and, on the larger packages, PI9/PH13.
const AF9_CAN1_PINS: &[CanPins] = &[
    CanPins {
        rx: p('A', 11),
        tx: p('A', 12),
        mux: PinMux::Af(9),
    },
    CanPins {
        rx: p('B', 8),
        tx: p('B', 9),
        mux: PinMux::Af(9),
    },
    CanPins {
        rx: p('D', 0),
        tx: p('D', 1),
        mux: PinMux::Af(9),
    },
    CanPins {
        rx: p('I', 9),
        tx: p('H', 13),
        mux: PinMux::Af(9),
    },
];
/// CAN2's pins on the F4/F7 (AF9): PB12/PB13, PB5/PB6.
const AF9_CAN2_PINS: &[CanPins] = &[
    CanPins {
        rx: p('B', 12),
        tx: p('B', 13),
        mux: PinMux::Af(9),
    },
    CanPins {
        rx: p('B', 5),
        tx: p('B', 6),
        mux: PinMux::Af(9),
    },
];
/// CAN3's pins on the F413/F423 and F76x/F77x (AF11): PA8/PA15, PB3/PB4.
const AF11_CAN3_PINS: &[CanPins] = &[
    CanPins {
        rx: p('A', 8),
        tx: p('A', 15),
        mux: PinMux::Af(11),
    },
    CanPins {
        rx: p('B', 3),
        tx: p('B', 4),
        mux: PinMux::Af(11),
    },
];

const CAN1: CanInstance = CanInstance {
    instance: Instance::Can1,
    name: "CAN1",
    base: 0x4000_6400,
    apb1enr_bit: 25,
    irqs: CAN1_IRQS,
    pins: AF9_CAN1_PINS,
};
const CAN2: CanInstance = CanInstance {
    instance: Instance::Can2,
    name: "CAN2",
    base: 0x4000_6800,
    apb1enr_bit: 26,
    irqs: CAN2_IRQS,
    pins: AF9_CAN2_PINS,
};

/// STM32F103 (performance line, low- to XL-density; the Blue Pill's STM32F103C8): one
/// controller, `CAN`, with 14 filter banks; its TX and RX0 lines are shared with the USB
/// device (RM0008 §10.1.2, vector table of the other devices: `USB_HP_CAN_TX` 19,
/// `USB_LP_CAN_RX0` 20, `CAN_RX1` 21, `CAN_SCE` 22); clock enable `RCC_APB1ENR.CANEN`
/// (bit 25, §7.3.8); APB1 at most 36 MHz (§7.2, datasheet DS5319 §5.3.1). CAN and USB
/// share their SRAM ([`Chip::sram_shared_with_usb`]).
pub const STM32F103: Chip = Chip {
    name: "STM32F103",
    manual: "RM0008 §24",
    instances: &[CanInstance {
        instance: Instance::Can1,
        name: "CAN",
        base: 0x4000_6400,
        apb1enr_bit: 25,
        irqs: [
            ("USB_HP_CAN_TX", 19),
            ("USB_LP_CAN_RX0", 20),
            ("CAN_RX1", 21),
            ("CAN_SCE", 22),
        ],
        pins: F1_CAN1_PINS,
    }],
    can1_banks: SINGLE_BLOCK_BANKS,
    rcc_apb1enr: F1_APB1ENR,
    apb1_max_hz: 36_000_000,
    sram_shared_with_usb: true,
};

/// STM32F105/F107 (connectivity line): CAN1 and CAN2 sharing 28 filter banks (RM0008
/// §24.2 "Dual CAN"), `CAN1EN`/`CAN2EN` bits 25/26 (§7.3.8); lines 19..=22 and 63..=66
/// (§10.1.2); APB1 at most 36 MHz (datasheet DS6014).
pub const STM32F105_F107: Chip = Chip {
    name: "STM32F105/STM32F107",
    manual: "RM0008 §24",
    instances: &[
        CanInstance {
            pins: F1_CAN1_PINS,
            ..CAN1
        },
        CanInstance {
            pins: F1_CAN2_PINS,
            ..CAN2
        },
    ],
    can1_banks: DUAL_BLOCK_BANKS,
    rcc_apb1enr: F1_APB1ENR,
    apb1_max_hz: 36_000_000,
    sram_shared_with_usb: false,
};

/// STM32F405/F407/F415/F417 (RM0090 §32): CAN1 + CAN2, 28 banks; APB1 at most 42 MHz
/// (datasheet DS8626 §6.3.1).
pub const STM32F405_F407: Chip = Chip {
    name: "STM32F405/F407/F415/F417",
    manual: "RM0090 §32",
    instances: &[CAN1, CAN2],
    can1_banks: DUAL_BLOCK_BANKS,
    rcc_apb1enr: F4_APB1ENR,
    apb1_max_hz: 42_000_000,
    sram_shared_with_usb: false,
};

/// STM32F446 (the NUCLEO-F446RE's STM32F446RE; RM0390 §30): CAN1 + CAN2, 28 banks; APB1
/// at most 45 MHz (datasheet DS10693 §6.3.1).
pub const STM32F446: Chip = Chip {
    name: "STM32F446",
    manual: "RM0390 §30",
    instances: &[CAN1, CAN2],
    can1_banks: DUAL_BLOCK_BANKS,
    rcc_apb1enr: F4_APB1ENR,
    apb1_max_hz: 45_000_000,
    sram_shared_with_usb: false,
};

/// STM32F413/F423 (RM0430 §32): CAN1 + CAN2 (28 banks) and CAN3 with its own 14 at
/// 0x4000_6C00, `RCC_APB1ENR.CAN3EN` bit 27, lines 74..=77 (§10.2); APB1 at most
/// 50 MHz (datasheet DS11581 §6.3.1).
pub const STM32F413_F423: Chip = Chip {
    name: "STM32F413/F423",
    manual: "RM0430 §32",
    instances: &[
        CAN1,
        CAN2,
        CanInstance {
            instance: Instance::Can3,
            name: "CAN3",
            base: 0x4000_6C00,
            apb1enr_bit: 27,
            irqs: [
                ("CAN3_TX", 74),
                ("CAN3_RX0", 75),
                ("CAN3_RX1", 76),
                ("CAN3_SCE", 77),
            ],
            pins: AF11_CAN3_PINS,
        },
    ],
    can1_banks: DUAL_BLOCK_BANKS,
    rcc_apb1enr: F4_APB1ENR,
    apb1_max_hz: 50_000_000,
    sram_shared_with_usb: false,
};

/// STM32F745/F746/F756 (RM0385 §40): CAN1 + CAN2, 28 banks; APB1 at most 54 MHz.
pub const STM32F74X_F75X: Chip = Chip {
    name: "STM32F74x/F75x",
    manual: "RM0385 §40",
    instances: &[CAN1, CAN2],
    can1_banks: DUAL_BLOCK_BANKS,
    rcc_apb1enr: F4_APB1ENR,
    apb1_max_hz: 54_000_000,
    sram_shared_with_usb: false,
};

/// STM32F76x/F77x (RM0410 §40): CAN1 + CAN2 (28 banks) and CAN3 with its own 14 at
/// 0x4000_3400, `RCC_APB1ENR.CAN3EN` bit 13, lines 104..=107 (§10.2); APB1 at
/// most 54 MHz. The default of [`crate::Config`] (the driver's first target).
pub const STM32F76X_F77X: Chip = Chip {
    name: "STM32F76x/F77x",
    manual: "RM0410 §40",
    instances: &[
        CAN1,
        CAN2,
        CanInstance {
            instance: Instance::Can3,
            name: "CAN3",
            base: 0x4000_3400,
            apb1enr_bit: 13,
            irqs: [
                ("CAN3_TX", 104),
                ("CAN3_RX0", 105),
                ("CAN3_RX1", 106),
                ("CAN3_SCE", 107),
            ],
            pins: AF11_CAN3_PINS,
        },
    ],
    can1_banks: DUAL_BLOCK_BANKS,
    rcc_apb1enr: F4_APB1ENR,
    apb1_max_hz: 54_000_000,
    sram_shared_with_usb: false,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bank_ranges_per_part() {
        let f103 = &STM32F103;
        // The F103's reserved CAN2SB bits do not split its block.
        assert_eq!(f103.bank_range(Instance::Can1, 14), (0, 14));
        assert_eq!(f103.bank_range(Instance::Can1, 3), (0, 14));
        assert_eq!(f103.bank_range(Instance::Can2, 3), (0, 0));
        assert_eq!(f103.bank_range(Instance::Can3, 3), (0, 0));
        let f446 = &STM32F446;
        assert_eq!(f446.bank_range(Instance::Can1, 10), (0, 10));
        assert_eq!(f446.bank_range(Instance::Can2, 10), (10, 28));
        assert_eq!(f446.bank_range(Instance::Can1, 40), (0, 28));
        assert_eq!(f446.bank_range(Instance::Can3, 0), (0, 0));
        let f413 = &STM32F413_F423;
        assert_eq!(f413.bank_range(Instance::Can3, 3), (0, 14));
    }

    #[test]
    fn start_banks_only_where_can2_exists() {
        assert!(!STM32F103.start_bank_valid(0));
        assert!(!STM32F103.start_bank_valid(14));
        assert!(STM32F446.start_bank_valid(28));
        assert!(!STM32F446.start_bank_valid(29));
        assert!(STM32F105_F107.start_bank_valid(0));
    }

    #[test]
    fn planner_options_and_clocks() {
        assert_eq!(STM32F103.plan_options(Instance::Can1).banks, 14);
        assert_eq!(STM32F103.plan_options(Instance::Can2).banks, 0);
        assert_eq!(STM32F446.plan_options(Instance::Can2).banks, 28);
        assert_eq!(STM32F76X_F77X.plan_options(Instance::Can3).banks, 14);
        assert!(STM32F103.clock_allowed(36_000_000));
        assert!(!STM32F103.clock_allowed(36_000_001));
        assert!(STM32F446.clock_allowed(45_000_000));
        assert!(!STM32F405_F407.clock_allowed(45_000_000));
        assert_eq!(STM32F446.irq(Instance::Can2, 3), Some(66));
        assert_eq!(STM32F103.irq(Instance::Can1, 4), None);
    }

    #[test]
    fn pins_are_routed_as_the_family_does() {
        for chip in Chip::ALL {
            for c in chip.instances {
                assert!(!c.pins.is_empty(), "{} {}", chip.name, c.name);
                for pins in c.pins {
                    let f1 = chip.rcc_apb1enr == F1_APB1ENR;
                    assert_eq!(
                        matches!(pins.mux, PinMux::Af(_)),
                        !f1,
                        "{} {}",
                        chip.name,
                        c.name
                    );
                    assert!(pins.rx.number < 16 && pins.tx.number < 16);
                }
            }
        }
    }
}
