//! Why a bit timing could not be computed, encoded or accepted.

use core::fmt;

use super::consistency::Consistency;

/// Bit timing errors. Bad input always gives one of these, never a panic.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TimingError {
    /// The CAN clock is 0 Hz.
    ClockZero,
    /// The wished bit rate is 0 bit/s.
    BitrateZero,
    /// The wished bit rate is above the bit rate of the fastest timing the controller
    /// accepts ([`TimingRule::max_bitrate`](super::TimingRule::max_bitrate): smallest
    /// prescaler, fewest quanta, and the manual's rules; 16 MHz FlexCAN with a 16 MHz
    /// bus clock: 1 Mbit/s), or, for the solver, above clock / fewest quanta per bit.
    BitrateTooHigh,
    /// The wished bit rate is below the bit rate of the slowest timing the controller
    /// accepts ([`TimingRule::min_bitrate`](super::TimingRule::min_bitrate): largest
    /// prescaler, most quanta per bit: 16 MHz FlexCAN: 2.5 kbit/s, ACAN §16.1).
    BitrateTooLow,
    /// The sample point target is not strictly between 50 % and 100 %
    /// (valid: 501..=999 per mille).
    SamplePointOutOfRange,
    /// The [`Limits`](super::Limits) are unusable (see
    /// [`Limits::is_valid`](super::Limits::is_valid)).
    InvalidLimits,
    /// The timing is not within the tolerance of the wished bit rate (ACAN
    /// §15.2.1 "CAN Bit setting too far from wished rate").
    TooFarFromWishedBitrate,
    /// The counts break the listed rules (ACAN §15.2.2 "CAN Bit inconsistent
    /// configuration", §16.2).
    Inconsistent(Consistency),
    /// A register encoding for the other controller was asked for (e.g. a bxCAN
    /// BTR from FlexCAN limits), or a timing made for another controller's limits was
    /// handed to a controller ([`crate::Hardware::set_timing`]).
    WrongController,
    /// The timing was computed for another CAN clock than the controller's
    /// ([`crate::Capabilities::clock_hz`]).
    WrongClock,
    /// The timing is within the register ranges but the controller's reference manual
    /// forbids it (FlexCAN: fewer than 8 quanta per bit or fewer than 16 peripheral
    /// clocks per CAN bit, Kinetis RM "Arbitration and matching timing",
    /// [`super::flexcan_rules`]).
    ForbiddenByManual,
}

impl fmt::Display for TimingError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TimingError::ClockZero => f.write_str("CAN clock is 0 Hz"),
            TimingError::BitrateZero => f.write_str("bit rate is 0 bit/s"),
            TimingError::BitrateTooHigh => {
                f.write_str("bit rate above the fastest timing the controller accepts")
            }
            TimingError::BitrateTooLow => {
                f.write_str("bit rate below the slowest timing the controller accepts")
            }
            TimingError::SamplePointOutOfRange => {
                f.write_str("sample point must be above 50 % and below 100 %")
            }
            TimingError::InvalidLimits => f.write_str("invalid controller limits"),
            TimingError::TooFarFromWishedBitrate => {
                f.write_str("CAN bit setting too far from wished bit rate")
            }
            TimingError::Inconsistent(c) => write!(f, "inconsistent CAN bit setting: {c}"),
            TimingError::WrongController => {
                f.write_str("register encoding asked for another controller")
            }
            TimingError::WrongClock => {
                f.write_str("timing computed for another clock than the controller's")
            }
            TimingError::ForbiddenByManual => {
                f.write_str("bit timing forbidden by the controller's reference manual")
            }
        }
    }
}

impl core::error::Error for TimingError {}
