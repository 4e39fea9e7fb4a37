//! What `begin` reports (ACAN §15.2, table 5).
//!
//! `begin` checks everything first and collects every problem it finds in one
//! [`ConfigErrors`] value; when it is not empty, nothing has been written to any
//! register. Only once the settings are valid does `begin` touch the hardware, and a
//! controller that then fails to acknowledge a mode change gives
//! [`BeginError::Hardware`] with [`twocan_core::Error::Timeout`].

use core::fmt;

bitflags::bitflags! {
    /// The error flags of ACAN table 5 (bits 0–7 at ACAN's positions), plus bit 8 for
    /// an instance the board does not have.
    ///
    /// The table, as extracted from the manual's PDF, shows bits 1–0 as `0 0` on the
    /// rows of bits 2–7; read with the §15.2 text ("an error code could report several
    /// errors") they are "don't care": this driver reports every flag that applies, the
    /// timing flags included, in one value.
    ///
    /// ```
    /// use twocan_flexcan::ConfigErrors;
    ///
    /// let e = ConfigErrors::NO_ALTERNATE_RX_PIN | ConfigErrors::BIT_RATE_TOO_FAR;
    /// assert_eq!(e.bits(), 0x81); // ACAN's error code
    /// assert_eq!(format!("{e:?}"), "ConfigErrors(BIT_RATE_TOO_FAR | NO_ALTERNATE_RX_PIN)");
    /// assert!(ConfigErrors::NONE.is_empty());
    /// ```
    #[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct ConfigErrors: u32 {
        /// Bit 0: the bit timing is too far from the wished bit rate (ACAN §15.2.1,
        /// `kCANBitConfigurationTooFarFromWishedBitRateErrorMask`).
        const BIT_RATE_TOO_FAR = 1 << 0;
        /// Bit 1: the bit timing is inconsistent (ACAN §15.2.2, §16.2).
        const BIT_TIMING_INCONSISTENT = 1 << 1;
        /// Bit 2: more primary filters than the configuration allows (ACAN §15.2.3).
        const TOO_MANY_PRIMARY_FILTERS = 1 << 2;
        /// Bit 3: a primary filter does not conform (ACAN §15.3, §12.4).
        const PRIMARY_FILTER_NOT_CONFORM = 1 << 3;
        /// Bit 4: more secondary filters than the configuration allows (ACAN §15.3.1).
        const TOO_MANY_SECONDARY_FILTERS = 1 << 4;
        /// Bit 5: a secondary filter does not conform (ACAN §15.3.2, §13.4).
        const SECONDARY_FILTER_NOT_CONFORM = 1 << 5;
        /// Bit 6: an alternate Tx pin was asked for `can1`, which has none (ACAN §15.3.3).
        const NO_ALTERNATE_TX_PIN = 1 << 6;
        /// Bit 7: an alternate Rx pin was asked for `can1`, which has none (ACAN §15.3.4).
        const NO_ALTERNATE_RX_PIN = 1 << 7;
        /// Bit 8 (not in ACAN): the board has no such FlexCAN instance (`can1` exists on
        /// the Teensy 3.6 only, ACAN §6 table 2).
        const NO_SUCH_INSTANCE = 1 << 8;
        /// Bit 9 (not in ACAN): a bit timing the Kinetis reference manual forbids
        /// (FlexCAN chapter, "Arbitration and matching timing"): fewer than 8 time
        /// quanta per bit, fewer than 16 peripheral (bus) clocks per CAN bit with the
        /// 16 message buffers and the Rx FIFO, or a bus clock below the 16 MHz
        /// oscillator clock ([`twocan_core::timing::flexcan_rules`],
        /// [`crate::Settings::bus_clock_hz`]). ACAN checks only the field ranges.
        const BIT_TIMING_FORBIDDEN = 1 << 9;
        /// Bit 10 (not in ACAN): the wished bit rate is outside the range of the driver's
        /// bit-timing rule ([`crate::begin::timing_rule_in`],
        /// [`twocan_core::timing::TimingRule::check_bitrate`]): from 2,500 bit/s (PRESDIV
        /// 256, 25 quanta, ACAN §16.1) to the fastest timing the Kinetis manual allows
        /// with the bus clock (1 Mbit/s from 16 MHz, 2 Mbit/s from 32 MHz and above) —
        /// the range the capabilities report and `set_bitrate` applies. [`crate::check`]
        /// reports it; `begin` refuses such a rate before any other check, with
        /// [`BeginError::Timing`].
        const BIT_RATE_OUT_OF_RANGE = 1 << 10;
        /// Bit 11 (not in ACAN): the settings' CAN clock ([`crate::Settings::can_clock`])
        /// is not one the target's chip gives its FlexCAN modules: the 16 MHz
        /// oscillator on a Teensy 3.x, a CCM clock root (divider 1–64, at most 80 MHz,
        /// IMXRT1060RM "CCM_CSCMR2") on a Teensy 4.x.
        const CLOCK_NOT_ON_CHIP = 1 << 11;
        /// Bit 12 (not in ACAN): the configuration's Rx FIFO filter table
        /// (`CTRL2[RFFN]`, [`crate::Configuration`]) is larger than the controller
        /// accepts: RFFN 0–3 (ACAN's four configurations, MB0–MB15) with the default
        /// layout ([`crate::layout::Kinetis`]) and on the Teensy 3.x; up to 0xF with
        /// [`crate::layout::Imxrt1062`] on the i.MX RT1062
        /// ([`crate::Chip::accepted_max_rffn`]). Nothing is written.
        const CONFIGURATION_NOT_ON_CHIP = 1 << 12;
        /// Bit 13 (not in ACAN): the controller's message-buffer layout is not the
        /// target chip's: the Kinetis layout ([`crate::layout::Kinetis`], the default
        /// type parameter) on an i.MX RT1062 module, which would run without the
        /// ERR005829 workaround; begin a Teensy 4 module in
        /// [`crate::layout::Imxrt1062`] (`FlexCan::<_, Imxrt1062>::begin_with_layout`,
        /// the tokens, the one calls and the hand-over do). Nothing is written.
        const LAYOUT_NOT_FOR_CHIP = 1 << 13;
        /// Bit 14 (not in ACAN): on the i.MX RT1062, the settings' clock root
        /// ([`crate::Settings::can_clock`]) differs from the one `CCM_CSCMR2` selects
        /// and another FlexCAN module is in use on it (its clock gate on and its `MCR`
        /// changed from the reset value: running, frozen or asleep): switching the
        /// shared `CAN_CLK_ROOT` would change that module's bit rate (IMXRT1060RM
        /// "CCM_CSCMR2"; [`crate::imxrt::ImxrtPlan::apply`]). Found by `begin` from the
        /// hardware, not by [`crate::check`]; nothing is written.
        const CLOCK_ROOT_IN_USE = 1 << 14;
    }
}

impl ConfigErrors {
    /// No error (ACAN: error code 0).
    pub const NONE: ConfigErrors = ConfigErrors::empty();
    /// Every flag.
    pub const ALL: ConfigErrors = ConfigErrors::all();

    /// Number of flags set.
    pub const fn count(self) -> u32 {
        self.bits().count_ones()
    }

    /// Names of the set flags, lowest bit first.
    pub fn names(self) -> impl Iterator<Item = &'static str> {
        self.iter_names().map(|(name, _)| name)
    }
}

impl fmt::Debug for ConfigErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("ConfigErrors(")?;
        if self.is_empty() {
            f.write_str("NONE")?;
        }
        for (i, name) in self.names().enumerate() {
            if i > 0 {
                f.write_str(" | ")?;
            }
            f.write_str(name)?;
        }
        f.write_str(")")
    }
}

impl fmt::Display for ConfigErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self, f)
    }
}

impl core::error::Error for ConfigErrors {}

#[cfg(feature = "defmt")]
impl defmt::Format for ConfigErrors {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "ConfigErrors({=u32:#x})", self.bits());
    }
}

/// Why `begin` failed (ACAN §15).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BeginError {
    /// The wished bit rate is outside the range of the driver's bit-timing rule (the
    /// question every entry point of every backend asks first:
    /// [`twocan_core::timing::TimingRule::check_bitrate`] of
    /// [`crate::begin::timing_rule_in`]); no register was written. ACAN's tolerance
    /// check ([`ConfigErrors::BIT_RATE_TOO_FAR`]) applies in addition.
    Timing(twocan_core::timing::TimingError),
    /// The settings, filters or pins are invalid (ACAN table 5); no register was
    /// written.
    Config(ConfigErrors),
    /// The controller did not acknowledge a mode change within
    /// [`crate::Settings::handshake_polls`] ([`twocan_core::Error::Timeout`]); the
    /// module is left partly configured and should be given to `begin` again.
    Hardware(twocan_core::Error),
}

impl BeginError {
    /// The table-5 flags ([`ConfigErrors::NONE`] for a hardware failure).
    pub const fn flags(&self) -> ConfigErrors {
        match self {
            BeginError::Config(f) => *f,
            BeginError::Timing(_) | BeginError::Hardware(_) => ConfigErrors::NONE,
        }
    }
}

impl From<twocan_core::Error> for BeginError {
    fn from(e: twocan_core::Error) -> Self {
        BeginError::Hardware(e)
    }
}

impl fmt::Display for BeginError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BeginError::Timing(e) => write!(f, "bit rate out of range: {e}"),
            BeginError::Config(c) => write!(f, "invalid configuration: {c}"),
            BeginError::Hardware(e) => write!(f, "controller failure: {e}"),
        }
    }
}

impl core::error::Error for BeginError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            BeginError::Timing(e) => Some(e),
            BeginError::Hardware(e) => Some(e),
            BeginError::Config(_) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn acan_bit_positions_and_formatting() {
        assert_eq!(ConfigErrors::BIT_RATE_TOO_FAR.bits(), 0x01);
        assert_eq!(ConfigErrors::BIT_TIMING_INCONSISTENT.bits(), 0x02);
        assert_eq!(ConfigErrors::TOO_MANY_PRIMARY_FILTERS.bits(), 0x04);
        assert_eq!(ConfigErrors::PRIMARY_FILTER_NOT_CONFORM.bits(), 0x08);
        assert_eq!(ConfigErrors::TOO_MANY_SECONDARY_FILTERS.bits(), 0x10);
        assert_eq!(ConfigErrors::SECONDARY_FILTER_NOT_CONFORM.bits(), 0x20);
        assert_eq!(ConfigErrors::NO_ALTERNATE_TX_PIN.bits(), 0x40);
        assert_eq!(ConfigErrors::NO_ALTERNATE_RX_PIN.bits(), 0x80);
        let e = ConfigErrors::NO_ALTERNATE_RX_PIN | ConfigErrors::BIT_RATE_TOO_FAR;
        assert_eq!(
            format!("{e:?}"),
            "ConfigErrors(BIT_RATE_TOO_FAR | NO_ALTERNATE_RX_PIN)"
        );
        assert_eq!(format!("{:?}", ConfigErrors::NONE), "ConfigErrors(NONE)");
        assert_eq!(
            ConfigErrors::from_bits_truncate(u32::MAX),
            ConfigErrors::ALL
        );
        assert_eq!(ConfigErrors::BIT_TIMING_FORBIDDEN.bits(), 0x200);
        assert_eq!(ConfigErrors::BIT_RATE_OUT_OF_RANGE.bits(), 0x400);
        assert_eq!(ConfigErrors::CLOCK_NOT_ON_CHIP.bits(), 0x800);
        assert_eq!(ConfigErrors::CONFIGURATION_NOT_ON_CHIP.bits(), 0x1000);
        assert_eq!(ConfigErrors::LAYOUT_NOT_FOR_CHIP.bits(), 0x2000);
        assert_eq!(ConfigErrors::CLOCK_ROOT_IN_USE.bits(), 0x4000);
        assert_eq!(ConfigErrors::ALL.count(), 15);
        assert_eq!(BeginError::Config(e).flags(), e);
        assert_eq!(
            BeginError::from(twocan_core::Error::Timeout).flags(),
            ConfigErrors::NONE
        );
    }
}
