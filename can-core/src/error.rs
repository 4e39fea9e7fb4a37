//! Error states, counters, last-error codes, the driver's error type and the errors of
//! frames and filters ([`FrameError`], [`FilterError`], re-exported by their modules).
//!
//! The floor of the core: it names no other module but the bit-timing errors it wraps,
//! so every module can return these types (`frame`, `filter` and `timestamp` among
//! them) without a loop of imports.
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

/// A [`LastErrorCode`] shared between contexts (the status interrupt writes it, any
/// context reads it): one relaxed atomic byte, zero-initialised as
/// [`LastErrorCode::None`].
#[derive(Debug, Default)]
pub struct AtomicLastError(core::sync::atomic::AtomicU8);

impl AtomicLastError {
    const CODES: [LastErrorCode; 7] = [
        LastErrorCode::None,
        LastErrorCode::Stuff,
        LastErrorCode::Form,
        LastErrorCode::Acknowledge,
        LastErrorCode::BitRecessive,
        LastErrorCode::BitDominant,
        LastErrorCode::Crc,
    ];

    /// Holding `code`.
    pub const fn new(code: LastErrorCode) -> Self {
        AtomicLastError(core::sync::atomic::AtomicU8::new(code as u8))
    }

    /// The code held.
    pub fn load(&self) -> LastErrorCode {
        let i = self.0.load(core::sync::atomic::Ordering::Relaxed) as usize;
        Self::CODES[i % Self::CODES.len()]
    }

    /// Replaces the code held.
    pub fn store(&self, code: LastErrorCode) {
        self.0
            .store(code as u8, core::sync::atomic::Ordering::Relaxed);
    }
}

/// Error statistics counters the driver keeps (saturating).
///
/// The per-kind counts (`stuff`, `form`, `acknowledge`, `bit`, `crc`) are taken from the
/// controller's last-error code when its status interrupt is serviced. On bxCAN that code
/// (`CAN_ESR.LEC`, RM0410 §40.7.6 "Error management") holds one error only and is re-armed
/// by writing `0b111` after the read; an error latched between two services, or between
/// the read and that write, overwrites or is overwritten (no register sequence avoids
/// it), so there these counts are a **lower bound** of the errors on the bus. FlexCAN
/// (`ESR1`, its error bits cleared by the read and its `ERRINT` acknowledged exactly as
/// read) keeps a new error pending, but two errors of one kind between two services
/// still count once. The error counters and state ([`ErrorCounters`], [`ErrorState`])
/// come from the hardware's TEC/REC and are exact.
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
    /// Hardware receive FIFO overrun occurrences seen by the interrupt handler. Neither
    /// FlexCAN (`IFLAG1` bit 7) nor bxCAN (`FOVR`) counts the frames an overrun drops, so
    /// this counts occurrences, not lost frames (at least one frame per occurrence).
    pub hardware_overruns: u32,
    /// Hardware receive FIFO warning occurrences seen by the interrupt handler: FlexCAN's
    /// Rx FIFO held 5 of its 6 frames (`IFLAG1` bit 6), a bxCAN FIFO all 3 (`FULLx`).
    /// Each means the receive interrupt was served late; frames are lost only when an
    /// overrun follows.
    pub hardware_fifo_warnings: u32,
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

/// Why a frame could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrameError {
    /// A standard identifier above `0x7FF`.
    StandardIdOutOfRange(u32),
    /// An extended identifier above `0x1FFF_FFFF`.
    ExtendedIdOutOfRange(u32),
    /// A data length code above 15 (the field has four bits; [`Frame::check_dlc`](crate::frame::Frame::check_dlc)).
    DlcTooLarge(u8),
    /// A DLC code that does not agree with the data: a code `0..=8` other than the
    /// number of data bytes, or a code `9..=15` with fewer than 8 data bytes.
    DlcMismatch {
        /// The DLC code asked for.
        dlc: u8,
        /// The number of data bytes.
        len: usize,
    },
    /// More than 8 data bytes.
    TooMuchData(usize),
    /// A data-bearing operation was asked of a remote frame.
    DataOnRemoteFrame,
    /// A word view that does not fit inside the frame's DLC.
    OutOfBounds,
}

/// Why a filter does not conform.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FilterError {
    /// The identifier (acceptance value) is wider than the format allows.
    IdOutOfRange,
    /// The mask is wider than the format allows.
    MaskOutOfRange,
    /// The acceptance value has bits set where the mask is zero: it could never match.
    AcceptanceOutsideMask,
    /// [`Format::Any`](crate::filter::Format::Any) with a non-zero mask: an identifier comparison needs a format.
    AnyFormatWithIdentifier,
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
    Frame(FrameError),
    /// A filter did not conform.
    Filter(FilterError),
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
    /// A bit timing the controller cannot take (wrong clock, out of range, inconsistent).
    Timing(crate::timing::TimingError),
    /// The controller does not offer this mode or feature
    /// ([`crate::Capabilities::modes`]).
    Unsupported,
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

impl From<FrameError> for Error {
    fn from(e: FrameError) -> Self {
        Error::Frame(e)
    }
}

impl From<FilterError> for Error {
    fn from(e: FilterError) -> Self {
        Error::Filter(e)
    }
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::BusOff => f.write_str("the controller is bus-off"),
            Error::WrongMode => f.write_str("the controller is not in a mode that allows this"),
            Error::Timeout => f.write_str("the controller did not acknowledge in time"),
            Error::Bus(code) => write!(f, "bus error: {code:?}"),
            Error::Overrun => f.write_str("a receive FIFO overran: frames were lost in hardware"),
            Error::Frame(_) => f.write_str("invalid frame"),
            Error::Filter(_) => f.write_str("invalid filter"),
            Error::InvalidArgument => f.write_str("argument out of range"),
            Error::FilterSpace { needed, available } => write!(
                f,
                "the filter list needs {needed} units of filter space, {available} available"
            ),
            Error::Timing(_) => f.write_str("invalid bit timing for this controller"),
            Error::Unsupported => f.write_str("the controller does not offer this mode"),
        }
    }
}

impl core::error::Error for Error {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            Error::Frame(e) => Some(e),
            Error::Filter(e) => Some(e),
            Error::Timing(e) => Some(e),
            _ => None,
        }
    }
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        use FrameError as E;
        match self {
            E::StandardIdOutOfRange(id) => {
                write!(f, "standard identifier {id:#X} above 0x7FF")
            }
            E::ExtendedIdOutOfRange(id) => {
                write!(f, "extended identifier {id:#X} above 0x1FFFFFFF")
            }
            E::DlcTooLarge(dlc) => write!(f, "data length code {dlc} out of range"),
            E::DlcMismatch { dlc, len } => {
                write!(f, "data length code {dlc} does not fit {len} data bytes")
            }
            E::TooMuchData(n) => write!(f, "{n} data bytes, more than 8"),
            E::DataOnRemoteFrame => f.write_str("a remote frame carries no data"),
            E::OutOfBounds => f.write_str("word view outside the frame's data length"),
        }
    }
}

impl core::error::Error for FrameError {}

impl core::fmt::Display for FilterError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        use FilterError as E;
        f.write_str(match self {
            E::IdOutOfRange => "filter identifier wider than its format",
            E::MaskOutOfRange => "filter mask wider than its format",
            E::AcceptanceOutsideMask => {
                "filter identifier has bits outside its mask: it never matches"
            }
            E::AnyFormatWithIdentifier => {
                "an identifier comparison needs a format (not Format::Any)"
            }
        })
    }
}

impl core::error::Error for FilterError {}

#[cfg(test)]
mod tests {

    #[test]
    fn atomic_last_error_keeps_every_code() {
        use super::{AtomicLastError, LastErrorCode as L};
        let cell = AtomicLastError::default();
        assert_eq!(cell.load(), L::None);
        for c in [
            L::Stuff,
            L::Form,
            L::Acknowledge,
            L::BitRecessive,
            L::BitDominant,
            L::Crc,
            L::None,
        ] {
            cell.store(c);
            assert_eq!(cell.load(), c);
        }
    }

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
    fn errors_display_and_chain() {
        use core::error::Error as _;
        let e = Error::from(FrameError::StandardIdOutOfRange(0x800));
        assert_eq!(e.to_string(), "invalid frame");
        let source = e.source().expect("the frame error is the source");
        assert_eq!(source.to_string(), "standard identifier 0x800 above 0x7FF");
        let e = Error::from(FilterError::MaskOutOfRange);
        assert_eq!(
            e.source().unwrap().to_string(),
            "filter mask wider than its format"
        );
        assert!(Error::Timeout.source().is_none());
        assert_eq!(Error::BusOff.to_string(), "the controller is bus-off");
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
