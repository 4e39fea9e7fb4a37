//! The Teensy 4.0 / 4.1 pins of the three FlexCAN modules and their IOMUXC registers
//! (IMXRT1060RM, chapter "IOMUX Controller (IOMUXC)": `SW_MUX_CTL_PAD_*`,
//! `SW_PAD_CTL_PAD_*`, `*_SELECT_INPUT`; pin numbers from the Teensy 4.0 and 4.1
//! schematics).
//!
//! | module | Tx pin (pad, ALT) | Rx pin (pad, ALT) | Rx daisy select |
//! |---|---|---|---|
//! | CAN1 | 22 (`GPIO_AD_B1_08`, ALT2) | 23 (`GPIO_AD_B1_09`, ALT2) | `FLEXCAN1_RX_SELECT_INPUT` = 2 |
//! | CAN2 | 1 (`GPIO_AD_B0_02`, ALT0) | 0 (`GPIO_AD_B0_03`, ALT0) | `FLEXCAN2_RX_SELECT_INPUT` = 1 |
//! | CAN3 | 31 (`GPIO_EMC_36`, ALT9) | 30 (`GPIO_EMC_37`, ALT9) | `CANFD_IPP_IND_CANRX_SELECT_INPUT` = 0 |
//!
//! Both boards break out all six (on the Teensy 4.0, pins 30 and 31 are pads on the
//! underside). No module has an alternate pin pair on these boards.

use crate::regs::Field;

/// IOMUXC base address.
pub const IOMUXC_BASE: usize = 0x401F_8000;

/// `SW_MUX_CTL_PAD_*[MUX_MODE]`: the pad's function (ALTn).
pub const MUX_MODE: Field = Field::new(0, 4);
/// `SW_MUX_CTL_PAD_*` out of reset for these pads: ALT5, GPIO.
pub const MUX_RESET: u32 = 0x5;

/// `SW_PAD_CTL_PAD_*[SRE]`: fast slew rate.
pub const PAD_SRE: u32 = 1 << 0;
/// `SW_PAD_CTL_PAD_*[DSE]`: drive strength (0 off, 1 = R0 (150 Ω) … 7 = R0/7).
pub const PAD_DSE: Field = Field::new(3, 3);
/// `SW_PAD_CTL_PAD_*[SPEED]`: 0 low (50 MHz) … 3 max (200 MHz).
pub const PAD_SPEED: Field = Field::new(6, 2);
/// `SW_PAD_CTL_PAD_*[ODE]`: open drain.
pub const PAD_ODE: u32 = 1 << 11;
/// `SW_PAD_CTL_PAD_*[PKE]`: pull / keeper enabled.
pub const PAD_PKE: u32 = 1 << 12;
/// `SW_PAD_CTL_PAD_*[PUE]`: pull (1) rather than keeper (0).
pub const PAD_PUE: u32 = 1 << 13;
/// `SW_PAD_CTL_PAD_*[PUS]`: 0 100 kΩ pull-down, 1 47 kΩ, 2 100 kΩ, 3 22 kΩ pull-up.
pub const PAD_PUS: Field = Field::new(14, 2);
/// `SW_PAD_CTL_PAD_*[HYS]`: Schmitt trigger input.
pub const PAD_HYS: u32 = 1 << 16;
/// `SW_PAD_CTL_PAD_*` out of reset for these pads (0x10B0: keeper, medium speed,
/// R0/6 drive): what `end` restores.
pub const PAD_RESET: u32 = 0x0000_10B0;

/// A FlexCAN signal on a Teensy 4 pin.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ImxPin {
    /// The Teensy (Arduino) pin number.
    pub teensy_pin: u8,
    /// The pad's name in the reference manual.
    pub pad: &'static str,
    /// Address of `SW_MUX_CTL_PAD_<pad>`.
    pub mux: usize,
    /// The `MUX_MODE` (ALTn) selecting the FlexCAN signal.
    pub alt: u32,
    /// Address of `SW_PAD_CTL_PAD_<pad>`.
    pub pad_ctl: usize,
    /// The daisy-chain input selection of an Rx signal: `<signal>_SELECT_INPUT`'s
    /// address and the value that picks this pad (`None` for a Tx signal).
    pub daisy: Option<(usize, u32)>,
}

/// The Tx and Rx pins of one module.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ImxPins {
    /// Tx pin.
    pub tx: ImxPin,
    /// Rx pin.
    pub rx: ImxPin,
}

const fn pin(
    teensy_pin: u8,
    pad: &'static str,
    mux: usize,
    alt: u32,
    pad_ctl: usize,
    daisy: Option<(usize, u32)>,
) -> ImxPin {
    ImxPin {
        teensy_pin,
        pad,
        mux: IOMUXC_BASE + mux,
        alt,
        pad_ctl: IOMUXC_BASE + pad_ctl,
        daisy,
    }
}

/// `FLEXCAN1_RX_SELECT_INPUT`.
pub const FLEXCAN1_RX_SELECT_INPUT: usize = IOMUXC_BASE + 0x44C;
/// `FLEXCAN2_RX_SELECT_INPUT`.
pub const FLEXCAN2_RX_SELECT_INPUT: usize = IOMUXC_BASE + 0x450;
/// `CANFD_IPP_IND_CANRX_SELECT_INPUT` (CAN3's Rx).
pub const CANFD_IPP_IND_CANRX_SELECT_INPUT: usize = IOMUXC_BASE + 0x78C;

/// CAN1 Tx: pin 22, `GPIO_AD_B1_08` ALT2.
pub const CAN1_TX: ImxPin = pin(22, "GPIO_AD_B1_08", 0x11C, 2, 0x30C, None);
/// CAN1 Rx: pin 23, `GPIO_AD_B1_09` ALT2, daisy 2.
pub const CAN1_RX: ImxPin = pin(
    23,
    "GPIO_AD_B1_09",
    0x120,
    2,
    0x310,
    Some((FLEXCAN1_RX_SELECT_INPUT, 2)),
);
/// CAN2 Tx: pin 1, `GPIO_AD_B0_02` ALT0.
pub const CAN2_TX: ImxPin = pin(1, "GPIO_AD_B0_02", 0x0C4, 0, 0x2B4, None);
/// CAN2 Rx: pin 0, `GPIO_AD_B0_03` ALT0, daisy 1.
pub const CAN2_RX: ImxPin = pin(
    0,
    "GPIO_AD_B0_03",
    0x0C8,
    0,
    0x2B8,
    Some((FLEXCAN2_RX_SELECT_INPUT, 1)),
);
/// CAN3 Tx: pin 31, `GPIO_EMC_36` ALT9.
pub const CAN3_TX: ImxPin = pin(31, "GPIO_EMC_36", 0x0A4, 9, 0x294, None);
/// CAN3 Rx: pin 30, `GPIO_EMC_37` ALT9, daisy 0.
pub const CAN3_RX: ImxPin = pin(
    30,
    "GPIO_EMC_37",
    0x0A8,
    9,
    0x298,
    Some((CANFD_IPP_IND_CANRX_SELECT_INPUT, 0)),
);

/// The pad control value of a Tx pin: the reset drive and speed, open drain if asked
/// (the counterpart of the Kinetis `PORTx_PCRn.ODE`, ACAN §16.7.5).
pub const fn tx_pad(open_drain: bool) -> u32 {
    PAD_RESET | if open_drain { PAD_ODE } else { 0 }
}

/// The pad control value of an Rx pin: the 22 kΩ pull-up if asked (ACAN §16.7.6),
/// else the reset keeper.
pub const fn rx_pad(pull_up: bool) -> u32 {
    if pull_up {
        PAD_RESET | PAD_PKE | PAD_PUE | PAD_PUS.val(3)
    } else {
        PAD_RESET
    }
}

/// CAN1's pins (Teensy 4.x pins 22 and 23).
pub const CAN1: ImxPins = ImxPins {
    tx: CAN1_TX,
    rx: CAN1_RX,
};
/// CAN2's pins (Teensy 4.x pins 1 and 0).
pub const CAN2: ImxPins = ImxPins {
    tx: CAN2_TX,
    rx: CAN2_RX,
};
/// CAN3's pins (Teensy 4.x pins 31 and 30).
pub const CAN3: ImxPins = ImxPins {
    tx: CAN3_TX,
    rx: CAN3_RX,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pad_values() {
        assert_eq!(tx_pad(false), 0x10B0);
        assert_eq!(tx_pad(true), 0x18B0);
        assert_eq!(rx_pad(true), 0xF0B0);
        assert_eq!(PAD_DSE.get(PAD_RESET), 6);
        assert_eq!(PAD_SPEED.get(PAD_RESET), 2);
        for p in [CAN1_RX, CAN2_RX, CAN3_RX] {
            assert!(p.daisy.is_some());
        }
        for p in [CAN1_TX, CAN2_TX, CAN3_TX] {
            assert!(p.daisy.is_none());
            assert_eq!(MUX_MODE.val(p.alt), p.alt);
        }
    }
}
