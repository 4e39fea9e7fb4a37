//! The CAN clock root and the FlexCAN clock gates of the i.MX RT1062 (IMXRT1060RM,
//! chapter "Clock Controller Module (CCM)": "CCM Serial Clock Multiplexer Register 2
//! (CCM_CSCMR2)", "CCM Clock Gating Register 0 / 7").
//!
//! One clock root, `CAN_CLK_ROOT`, feeds the protocol engines of all three modules: it
//! is chosen by `CSCMR2[CAN_CLK_SEL]` (00: `pll3_sw_clk` ÷ 8 = 60 MHz, 01: the 24 MHz
//! oscillator, 10: `pll3_sw_clk` ÷ 6 = 80 MHz, 11: disabled) and divided by
//! `CSCMR2[CAN_CLK_PODF]` + 1 (1 to 64). The data sheet (IMXRT1060CEC, "System clock
//! frequency requirements") limits the root to 80 MHz. The PLL3 figures assume
//! `pll3_sw_clk` at its 480 MHz, as every Teensy 4 start-up code leaves it.
//!
//! Each module has two gates, the module clock and the serial (engine) clock, each a 2-bit
//! `CGn` field (11: on in run and wait modes): CAN1 `CCGR0[CG7, CG8]`, CAN2
//! `CCGR0[CG9, CG10]`, CAN3 `CCGR7[CG3, CG4]`.

use crate::regs::Field;

/// CCM base address.
pub const CCM_BASE: usize = 0x400F_C000;
/// CCM Serial Clock Multiplexer Register 2.
pub const CCM_CSCMR2: usize = CCM_BASE + 0x20;
/// CCM Clock Gating Register 0 (CAN1, CAN2).
pub const CCM_CCGR0: usize = CCM_BASE + 0x68;
/// CCM Clock Gating Register 7 (CAN3).
pub const CCM_CCGR7: usize = CCM_BASE + 0x84;

/// `CSCMR2[CAN_CLK_PODF]`: the root's divider minus one.
pub const CAN_CLK_PODF: Field = Field::new(2, 6);
/// `CSCMR2[CAN_CLK_SEL]`: the root's source.
pub const CAN_CLK_SEL: Field = Field::new(8, 2);

/// The 2-bit gate field `CGn` of a `CCGR` register, all ones (on in run and wait).
pub const fn cg_on(n: u32) -> u32 {
    0b11 << (2 * n)
}

/// The three modules on the root, for the check that a running module keeps its root
/// ([`crate::imxrt::ImxrtPlan::apply`]): the `CCGR` register and bits of the module's
/// register-access gate (`can1_clk` CCGR0 CG7, `can2_clk` CG9, `can3_clk` CCGR7 CG3;
/// a gated module's registers are not read) and the address of its `MCR` (the base).
pub const MODULES_ON_ROOT: [(usize, u32, usize); 3] = [
    (CCM_CCGR0, cg_on(7), super::CAN1_BASE),
    (CCM_CCGR0, cg_on(9), super::CAN2_BASE),
    (CCM_CCGR7, cg_on(3), super::CAN3_BASE),
];

/// Highest `CAN_CLK_ROOT` frequency the data sheet allows.
pub const MAX_ROOT_HZ: u32 = 80_000_000;

/// The source of `CAN_CLK_ROOT` (`CSCMR2[CAN_CLK_SEL]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CanClockSource {
    /// 01: the 24 MHz crystal oscillator (`osc_clk`).
    Oscillator24MHz,
    /// 00: `pll3_sw_clk` ÷ 8, 60 MHz.
    Pll3Div8,
    /// 10: `pll3_sw_clk` ÷ 6, 80 MHz.
    Pll3Div6,
}

impl CanClockSource {
    /// The `CAN_CLK_SEL` code.
    pub const fn sel(self) -> u32 {
        match self {
            CanClockSource::Pll3Div8 => 0b00,
            CanClockSource::Oscillator24MHz => 0b01,
            CanClockSource::Pll3Div6 => 0b10,
        }
    }

    /// The source frequency in Hz.
    pub const fn hz(self) -> u32 {
        match self {
            CanClockSource::Oscillator24MHz => 24_000_000,
            CanClockSource::Pll3Div8 => 60_000_000,
            CanClockSource::Pll3Div6 => 80_000_000,
        }
    }
}

/// A `CAN_CLK_ROOT` setting: a source and a divider (1 to 64).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ClockRoot {
    /// `CAN_CLK_SEL`.
    pub source: CanClockSource,
    /// `CAN_CLK_PODF` + 1: 1 to 64 (others are refused by [`ClockRoot::is_valid`]).
    pub divider: u8,
}

impl ClockRoot {
    /// The 24 MHz oscillator undivided: the root the driver uses unless told otherwise
    /// (it does not depend on the PLL set-up of the start-up code).
    pub const OSC_24MHZ: ClockRoot = ClockRoot::new(CanClockSource::Oscillator24MHz, 1);
    /// 60 MHz from PLL3.
    pub const PLL3_60MHZ: ClockRoot = ClockRoot::new(CanClockSource::Pll3Div8, 1);
    /// 80 MHz from PLL3 (the data sheet's maximum).
    pub const PLL3_80MHZ: ClockRoot = ClockRoot::new(CanClockSource::Pll3Div6, 1);

    /// `source` divided by `divider`.
    pub const fn new(source: CanClockSource, divider: u8) -> Self {
        ClockRoot { source, divider }
    }

    /// Whether the divider is within `CAN_CLK_PODF`'s range (1 to 64) and the root at
    /// most [`MAX_ROOT_HZ`].
    pub const fn is_valid(self) -> bool {
        self.divider >= 1 && self.divider <= 64 && self.hz() <= MAX_ROOT_HZ
    }

    /// The root frequency in Hz (0 for a divider of 0).
    pub const fn hz(self) -> u32 {
        if self.divider == 0 {
            0
        } else {
            self.source.hz() / self.divider as u32
        }
    }

    /// `CSCMR2` with the CAN fields replaced by this root.
    pub const fn cscmr2(self, cscmr2: u32) -> u32 {
        let v = CAN_CLK_SEL.replace(cscmr2, self.source.sel());
        CAN_CLK_PODF.replace(v, self.divider.saturating_sub(1) as u32)
    }

    /// The root a `CSCMR2` value selects (`None` when `CAN_CLK_SEL` = 11, disabled).
    pub const fn from_cscmr2(cscmr2: u32) -> Option<Self> {
        let source = match CAN_CLK_SEL.get(cscmr2) {
            0b00 => CanClockSource::Pll3Div8,
            0b01 => CanClockSource::Oscillator24MHz,
            0b10 => CanClockSource::Pll3Div6,
            _ => return None,
        };
        Some(ClockRoot::new(source, CAN_CLK_PODF.get(cscmr2) as u8 + 1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_and_limits() {
        assert_eq!(ClockRoot::OSC_24MHZ.hz(), 24_000_000);
        assert_eq!(ClockRoot::PLL3_60MHZ.hz(), 60_000_000);
        assert_eq!(ClockRoot::PLL3_80MHZ.hz(), 80_000_000);
        assert_eq!(ClockRoot::new(CanClockSource::Pll3Div6, 2).hz(), 40_000_000);
        assert!(ClockRoot::PLL3_80MHZ.is_valid());
        assert!(!ClockRoot::new(CanClockSource::Pll3Div6, 0).is_valid());
        assert!(!ClockRoot::new(CanClockSource::Pll3Div6, 65).is_valid());
        // Every root round-trips through CSCMR2, other bits kept.
        for source in [
            CanClockSource::Oscillator24MHz,
            CanClockSource::Pll3Div8,
            CanClockSource::Pll3Div6,
        ] {
            for divider in [1, 2, 3, 64] {
                let r = ClockRoot::new(source, divider);
                let v = r.cscmr2(0x8000_0003 | CAN_CLK_SEL.mask());
                assert_eq!(v & 0x8000_0003, 0x8000_0003);
                assert_eq!(ClockRoot::from_cscmr2(v), Some(r));
            }
        }
        assert_eq!(ClockRoot::from_cscmr2(CAN_CLK_SEL.mask()), None);
        assert_eq!(cg_on(7) | cg_on(8), 0xF << 14);
    }
}
