//! The clock of the FlexCAN protocol engine, by chip family: the bit timing is counted
//! in its periods.
//!
//! - Kinetis (Teensy 3.x): the 16 MHz crystal oscillator, `CTRL1.CLKSRC` = 0 (ACAN
//!   §16.1), [`CanClock::Oscillator16MHz`].
//! - i.MX RT1062 (Teensy 4.x): the CCM's `CAN_CLK_ROOT`, shared by CAN1–CAN3
//!   ([`crate::imxrt::ccm`]), [`CanClock::Imxrt`]; `CTRL1.CLKSRC` stays 0 (CAN3 is the
//!   only module that has the bit: IMXRT1060RM, CTRL1 field descriptions).

use crate::board::Chip;
use crate::imxrt::ClockRoot;
use crate::settings::CAN_CLOCK_HZ;

/// The protocol engine clock a [`crate::Settings`] is computed for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CanClock {
    /// The Kinetis 16 MHz oscillator clock (every Teensy 3.x).
    #[default]
    Oscillator16MHz,
    /// The RT1062's CAN clock root (24 MHz oscillator, or 60 / 80 MHz from PLL3, divided).
    Imxrt(ClockRoot),
}

impl CanClock {
    /// The RT1062's default: the 24 MHz oscillator undivided.
    pub const IMXRT_24MHZ: CanClock = CanClock::Imxrt(ClockRoot::OSC_24MHZ);

    /// The clock in Hz.
    pub const fn hz(self) -> u32 {
        match self {
            CanClock::Oscillator16MHz => CAN_CLOCK_HZ,
            CanClock::Imxrt(root) => root.hz(),
        }
    }

    /// Whether `chip` can clock its FlexCAN modules so: the 16 MHz oscillator on the
    /// Kinetis parts, a valid root (divider 1–64, at most 80 MHz) on the RT1062.
    pub const fn fits(self, chip: Chip) -> bool {
        match self {
            CanClock::Oscillator16MHz => !chip.is_imxrt(),
            CanClock::Imxrt(root) => chip.is_imxrt() && root.is_valid(),
        }
    }

    /// The clock `chip`'s boards use unless told otherwise.
    pub const fn default_for(chip: Chip) -> CanClock {
        if chip.is_imxrt() {
            CanClock::IMXRT_24MHZ
        } else {
            CanClock::Oscillator16MHz
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imxrt::CanClockSource;

    #[test]
    fn clocks_fit_their_chips() {
        assert!(CanClock::Oscillator16MHz.fits(Chip::Mk66fx1m0));
        assert!(!CanClock::Oscillator16MHz.fits(Chip::Imxrt1062));
        assert!(CanClock::IMXRT_24MHZ.fits(Chip::Imxrt1062));
        assert!(!CanClock::IMXRT_24MHZ.fits(Chip::Mk20dx256));
        let bad = CanClock::Imxrt(ClockRoot::new(CanClockSource::Pll3Div6, 0));
        assert!(!bad.fits(Chip::Imxrt1062));
        assert_eq!(CanClock::IMXRT_24MHZ.hz(), 24_000_000);
        assert_eq!(CanClock::default_for(Chip::Imxrt1062).hz(), 24_000_000);
        assert_eq!(CanClock::default_for(Chip::Mk64fx512).hz(), 16_000_000);
    }
}
