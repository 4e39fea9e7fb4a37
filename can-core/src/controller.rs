//! Operating modes and the error status a controller reports (the controller seam
//! itself is [`crate::hardware::Hardware`]).

use crate::error::{ErrorCounters, ErrorState, LastErrorCode};

/// The operating modes a driver can ask for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mode {
    /// On the bus.
    Normal,
    /// Off the bus for configuration (bxCAN initialization, FlexCAN freeze).
    Stopped,
    /// Low-power sleep (bxCAN sleep; FlexCAN stop/disable).
    Sleep,
}

/// Error status as the controller reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ErrorStatus {
    /// Fault-confinement state (or stopped / sleeping).
    pub state: ErrorState,
    /// TEC (256 while bus-off) and REC.
    pub counters: ErrorCounters,
    /// The last error code the controller latched.
    pub last_error: LastErrorCode,
}
