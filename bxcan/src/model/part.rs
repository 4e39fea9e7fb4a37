//! Part descriptors: what differs between the STM32 parts that carry the bxCAN cell, as
//! data the model (and the firmware-in-the-loop board profiles) read.
//!
//! The bxCAN cell is the same on every part below: the same register offsets, bit
//! positions and reset values (`CAN_MCR` 0x0001_0002 with `DBF`, `CAN_MSR` 0x0000_0C02,
//! `CAN_TSR` 0x1C00_0000, `CAN_BTR` 0x0123_0000 with `BRP[9:0]`, `TS1[3:0]`, `TS2[2:0]`,
//! `SJW[1:0]`, `CAN_FMR` 0x2A1C_0E01), the time-triggered communication option (`TTCM`)
//! and debug freeze (`DBF`) everywhere — RM0008 §24.9, RM0090 §32.9, RM0390 §30.9, RM0430
//! §32.9, RM0385 §40.9, RM0410 §40.9. What differs, and is therefore data here:
//!
//! - **the instances** (CAN1 alone; CAN1 + CAN2; CAN1 + CAN2 + CAN3), their base
//!   addresses, clock-enable bits and interrupt numbers;
//! - **the filter banks of CAN1's block**: 14 on single-CAN parts, 28 shared with CAN2 on
//!   dual-CAN parts (RM0008 §24.2 "28 filter banks shared between CAN1 and CAN2 in
//!   connectivity line devices, 14 filter banks in other STM32F10xxx devices"). The
//!   width of `CAN_FM1R`, `CAN_FS1R`, `CAN_FFA1R` and `CAN_FA1R` is the bank count (the
//!   bits above are reserved), and `CAN_FiRx` exists for `i < banks` only;
//! - **`CAN_FMR.CAN2SB`**: present on dual-CAN parts only (RM0008 §24.9.4: "available in
//!   connectivity line devices only and are reserved otherwise"); its bits keep their
//!   reset value (14) where reserved, so `CAN_FMR` resets to 0x2A1C_0E01 on every part;
//! - **CAN3**, where it exists, has its own block of 14 banks and no `CAN2SB`, but its
//!   base address and clock-enable bit differ between the F413/F423 (0x4000_6C00,
//!   `RCC_APB1ENR` bit 27, RM0430) and the F76x/F77x (0x4000_3400, bit 13, RM0410);
//! - **the clock**: bxCAN runs on APB1 (PCLK1), whose maximum differs per part (the
//!   datasheets' "general operating conditions");
//! - **the F103's message SRAM**: on the low-, medium-, high- and XL-density STM32F103
//!   the CAN and USB share a dedicated 512-byte SRAM and "cannot be used concurrently"
//!   (RM0008 §24.2, note under "Dual CAN"); the connectivity line has no such sharing.

use crate::regs::Instance;

/// One bxCAN instance of a part.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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
}

/// The bxCAN facts of one STM32 part (or family of parts with the same facts).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Part {
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
    /// cannot run at the same time.
    pub sram_shared_with_usb: bool,
}

impl Part {
    /// Whether CAN2 exists: then `CAN_FMR.CAN2SB` splits CAN1's banks between the two.
    pub fn dual(&self) -> bool {
        self.instance(Instance::Can2).is_some()
    }

    /// The description of `instance`, if the part has it.
    pub fn instance(&self, instance: Instance) -> Option<&'static CanInstance> {
        self.instances.iter().find(|i| i.instance == instance)
    }

    /// Filter banks of the block `instance` configures and uses: CAN1's block for CAN1
    /// and CAN2, CAN3's own 14; `None` if the part has no such instance.
    pub fn banks_of(&self, instance: Instance) -> Option<usize> {
        self.instance(instance).map(|_| match instance {
            Instance::Can3 => CAN3_BANKS,
            _ => self.can1_banks,
        })
    }

    /// Every part described here.
    pub const ALL: [&'static Part; 7] = [
        &STM32F103,
        &STM32F105_F107,
        &STM32F405_F407,
        &STM32F446,
        &STM32F413_F423,
        &STM32F74X_F75X,
        &STM32F76X_F77X,
    ];
}

/// CAN3's own filter block (RM0410 §40.2 Table 289, RM0430 §32.2 Table 219).
const CAN3_BANKS: usize = 14;

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

const CAN1: CanInstance = CanInstance {
    instance: Instance::Can1,
    name: "CAN1",
    base: 0x4000_6400,
    apb1enr_bit: 25,
    irqs: CAN1_IRQS,
};
const CAN2: CanInstance = CanInstance {
    instance: Instance::Can2,
    name: "CAN2",
    base: 0x4000_6800,
    apb1enr_bit: 26,
    irqs: CAN2_IRQS,
};

/// STM32F103 (performance line, low- to XL-density; the Blue Pill's STM32F103C8): one
/// controller, `CAN`, with 14 filter banks; its TX and RX0 lines are shared with the USB
/// device (RM0008 §10.1.2, vector table of the other devices: `USB_HP_CAN_TX` 19, `USB_LP_CAN_RX0` 20, `CAN_RX1`
/// 21, `CAN_SCE` 22); clock enable `RCC_APB1ENR.CANEN` (bit 25, §7.3.8); APB1 at most
/// 36 MHz (§7.2, datasheet DS5319 §5.3.1).
pub const STM32F103: Part = Part {
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
    }],
    can1_banks: 14,
    rcc_apb1enr: F1_APB1ENR,
    apb1_max_hz: 36_000_000,
    sram_shared_with_usb: true,
};

/// STM32F105/F107 (connectivity line): CAN1 and CAN2 sharing 28 filter banks (RM0008
/// §24.2 "Dual CAN"), `CAN1EN`/`CAN2EN` bits 25/26 (§7.3.8); lines 19..=22 and 63..=66
/// (§10.1.2); APB1 at most 36 MHz (datasheet DS6014).
pub const STM32F105_F107: Part = Part {
    name: "STM32F105/STM32F107",
    manual: "RM0008 §24",
    instances: &[CAN1, CAN2],
    can1_banks: 28,
    rcc_apb1enr: F1_APB1ENR,
    apb1_max_hz: 36_000_000,
    sram_shared_with_usb: false,
};

/// STM32F405/F407/F415/F417 (RM0090 §32): CAN1 + CAN2, 28 banks; APB1 at most 42 MHz
/// (datasheet DS8626 §6.3.1).
pub const STM32F405_F407: Part = Part {
    name: "STM32F405/F407/F415/F417",
    manual: "RM0090 §32",
    instances: &[CAN1, CAN2],
    can1_banks: 28,
    rcc_apb1enr: F4_APB1ENR,
    apb1_max_hz: 42_000_000,
    sram_shared_with_usb: false,
};

/// STM32F446 (the NUCLEO-F446RE's STM32F446RE; RM0390 §30): CAN1 + CAN2, 28 banks; APB1
/// at most 45 MHz (datasheet DS10693 §6.3.1).
pub const STM32F446: Part = Part {
    name: "STM32F446",
    manual: "RM0390 §30",
    instances: &[CAN1, CAN2],
    can1_banks: 28,
    rcc_apb1enr: F4_APB1ENR,
    apb1_max_hz: 45_000_000,
    sram_shared_with_usb: false,
};

/// STM32F413/F423 (RM0430 §32): CAN1 + CAN2 (28 banks) and CAN3 with its own 14 at
/// 0x4000_6C00, `RCC_APB1ENR.CAN3EN` bit 27, lines 74..=77 (§10.2); APB1 at most
/// 50 MHz (datasheet DS11581 §6.3.1).
pub const STM32F413_F423: Part = Part {
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
        },
    ],
    can1_banks: 28,
    rcc_apb1enr: F4_APB1ENR,
    apb1_max_hz: 50_000_000,
    sram_shared_with_usb: false,
};

/// STM32F745/F746/F756 (RM0385 §40): CAN1 + CAN2, 28 banks; APB1 at most 54 MHz.
pub const STM32F74X_F75X: Part = Part {
    name: "STM32F74x/F75x",
    manual: "RM0385 §40",
    instances: &[CAN1, CAN2],
    can1_banks: 28,
    rcc_apb1enr: F4_APB1ENR,
    apb1_max_hz: 54_000_000,
    sram_shared_with_usb: false,
};

/// STM32F76x/F77x (RM0410 §40): CAN1 + CAN2 (28 banks) and CAN3 with its own 14 at
/// 0x4000_3400, `RCC_APB1ENR.CAN3EN` bit 13, lines 104..=107 (§10.2); APB1 at
/// most 54 MHz.
pub const STM32F76X_F77X: Part = Part {
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
        },
    ],
    can1_banks: 28,
    rcc_apb1enr: F4_APB1ENR,
    apb1_max_hz: 54_000_000,
    sram_shared_with_usb: false,
};
