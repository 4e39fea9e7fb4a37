//! Error states, counters, last-error codes and the driver's error type.
//!
//! The fault-confinement states and thresholds are those of ISO 11898-1 §12.1.4:
//! error-active while both counters are below 128 (with a warning level at 96, as both
//! bxCAN EWGF and FlexCAN TXWRN/RXWRN report it), error-passive at 128 or more, bus-off
//! when the transmit error counter exceeds 255.

/// Fault-confinement state of a controller, plus the modes in which it is off the bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ErrorState {
    /// Both counters below 96.
    Active,
    /// A counter at 96 or more, both below 128 (still error-active on the bus).
    Warning,
    /// A counter at 128 or more.
    Passive,
    /// Transmit error counter above 255: the controller does not take part in bus traffic.
    BusOff,
    /// Configuration / initialization / freeze mode: off the bus by request.
    Stopped,
    /// Low-power sleep mode.
    Sleeping,
}

impl ErrorState {
    /// The state the counters give (ISO 11898-1 §12.1.4, warning level 96).
    pub const fn from_counters(c: ErrorCounters) -> Self {
        if c.tec > 255 {
            ErrorState::BusOff
        } else if c.tec >= 128 || c.rec >= 128 {
            ErrorState::Passive
        } else if c.tec >= 96 || c.rec >= 96 {
            ErrorState::Warning
        } else {
            ErrorState::Active
        }
    }
}

/// The error counters (ACAN §17: TEC reads 256 while bus-off).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ErrorCounters {
    /// Transmit error counter; 256 means bus-off.
    pub tec: u16,
    /// Receive error counter.
    pub rec: u16,
}

/// The last error seen on the bus (bxCAN ESR.LEC, FlexCAN ESR1 error bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LastErrorCode {
    /// No error since the code was last cleared.
    #[default]
    None,
    /// Six equal consecutive bits.
    Stuff,
    /// A fixed-form field held an illegal value.
    Form,
    /// The transmitter saw no dominant bit in the ACK slot.
    Acknowledge,
    /// Sent recessive, read dominant (outside arbitration).
    BitRecessive,
    /// Sent dominant, read recessive.
    BitDominant,
    /// CRC mismatch.
    Crc,
}

/// Error statistics counters the driver keeps (saturating).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ErrorStatistics {
    /// Stuff errors seen.
    pub stuff: u32,
    /// Form errors seen.
    pub form: u32,
    /// Acknowledge errors seen.
    pub acknowledge: u32,
    /// Bit errors (recessive or dominant) seen.
    pub bit: u32,
    /// CRC errors seen.
    pub crc: u32,
    /// Times the controller entered bus-off.
    pub bus_off: u32,
    /// Frames lost by a hardware receive FIFO overrun.
    pub hardware_overruns: u32,
}

impl ErrorStatistics {
    /// Counts one occurrence of `code`.
    pub fn record(&mut self, code: LastErrorCode) {
        let slot = match code {
            LastErrorCode::None => return,
            LastErrorCode::Stuff => &mut self.stuff,
            LastErrorCode::Form => &mut self.form,
            LastErrorCode::Acknowledge => &mut self.acknowledge,
            LastErrorCode::BitRecessive | LastErrorCode::BitDominant => &mut self.bit,
            LastErrorCode::Crc => &mut self.crc,
        };
        *slot = slot.saturating_add(1);
    }
}

/// The error type of every driver operation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error {
    /// The controller is bus-off.
    BusOff,
    /// The controller is not in a mode where it can do this (stopped, sleeping, listen-only).
    WrongMode,
    /// A hardware acknowledge bit (freeze, init, sleep) did not come within the bound.
    Timeout,
    /// A bus error reported by the controller.
    Bus(LastErrorCode),
    /// A receive FIFO overran: frames were lost in hardware.
    Overrun,
    /// A frame could not be built.
    Frame(crate::frame::FrameError),
    /// A filter did not conform.
    Filter(crate::filter::FilterError),
    /// An argument is out of range (mailbox index, filter index, ...).
    InvalidArgument,
    /// A filter list does not fit the hardware: it `needs` more filter space than is
    /// `available` (bxCAN: filter banks after merging; FlexCAN: ID table elements; a list
    /// longer than a planner takes: filters given against the most it takes).
    FilterSpace {
        /// What the list needs.
        needed: u16,
        /// What the hardware (or planner) has.
        available: u16,
    },
}

impl embedded_can::Error for Error {
    fn kind(&self) -> embedded_can::ErrorKind {
        use embedded_can::ErrorKind as K;
        match self {
            Error::Overrun => K::Overrun,
            Error::Bus(LastErrorCode::Stuff) => K::Stuff,
            Error::Bus(LastErrorCode::Form) => K::Form,
            Error::Bus(LastErrorCode::Acknowledge) => K::Acknowledge,
            Error::Bus(LastErrorCode::BitRecessive | LastErrorCode::BitDominant) => K::Bit,
            Error::Bus(LastErrorCode::Crc) => K::Crc,
            _ => K::Other,
        }
    }
}

impl From<crate::frame::FrameError> for Error {
    fn from(e: crate::frame::FrameError) -> Self {
        Error::Frame(e)
    }
}

impl From<crate::filter::FilterError> for Error {
    fn from(e: crate::filter::FilterError) -> Self {
        Error::Filter(e)
    }
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        core::fmt::Debug::fmt(self, f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_can::{Error as _, ErrorKind};

    #[test]
    fn states_from_counters() {
        let s = |tec, rec| ErrorState::from_counters(ErrorCounters { tec, rec });
        assert_eq!(s(0, 0), ErrorState::Active);
        assert_eq!(s(95, 95), ErrorState::Active);
        assert_eq!(s(96, 0), ErrorState::Warning);
        assert_eq!(s(0, 127), ErrorState::Warning);
        assert_eq!(s(0, 128), ErrorState::Passive);
        assert_eq!(s(255, 0), ErrorState::Passive);
        assert_eq!(s(256, 0), ErrorState::BusOff);
    }

    #[test]
    fn error_kinds() {
        assert_eq!(Error::Overrun.kind(), ErrorKind::Overrun);
        assert_eq!(Error::Bus(LastErrorCode::Stuff).kind(), ErrorKind::Stuff);
        assert_eq!(Error::Bus(LastErrorCode::Form).kind(), ErrorKind::Form);
        assert_eq!(
            Error::Bus(LastErrorCode::Acknowledge).kind(),
            ErrorKind::Acknowledge
        );
        assert_eq!(
            Error::Bus(LastErrorCode::BitDominant).kind(),
            ErrorKind::Bit
        );
        assert_eq!(
            Error::Bus(LastErrorCode::BitRecessive).kind(),
            ErrorKind::Bit
        );
        assert_eq!(Error::Bus(LastErrorCode::Crc).kind(), ErrorKind::Crc);
        assert_eq!(Error::BusOff.kind(), ErrorKind::Other);
        assert_eq!(Error::Timeout.kind(), ErrorKind::Other);
    }

    #[test]
    fn statistics_count_codes() {
        let mut s = ErrorStatistics::default();
        s.record(LastErrorCode::Crc);
        s.record(LastErrorCode::BitDominant);
        s.record(LastErrorCode::BitRecessive);
        s.record(LastErrorCode::None);
        assert_eq!((s.crc, s.bit, s.stuff), (1, 2, 0));
    }
}
