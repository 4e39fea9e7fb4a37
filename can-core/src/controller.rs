//! The seam between the portable driver and a controller backend.
//!
//! A backend (FlexCAN, bxCAN, a mock) implements [`Controller`] over its registers; the
//! generic [`crate::driver::Driver`] does everything else — software rings, transmit
//! ordering, dispatch, statistics, error-state tracking — once for every controller.

use crate::error::{Error, ErrorCounters, ErrorState, LastErrorCode};
use crate::frame::{Frame, RxFrame};
use crate::mailbox::{MailboxId, MailboxState, TxPolicy};

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

/// What happened since the controller's interrupt causes were last taken.
///
/// Backends read and acknowledge their flags in [`Controller::take_events`]; counts
/// rather than flags, so that the driver's statistics stay exact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Events {
    /// Transmissions completed successfully.
    pub sent: u8,
    /// Transmissions that ended without being sent (one-shot failure).
    pub failed: u8,
    /// Transmissions aborted on request.
    pub aborted: u8,
    /// Frames lost by a hardware receive FIFO overrun (or overrun occurrences where the
    /// hardware cannot count lost frames: see the backend).
    pub overruns: u16,
    /// A bus error latched (last-error code), if any.
    pub bus_error: Option<LastErrorCode>,
    /// The fault-confinement state may have changed.
    pub state_changed: bool,
    /// The controller woke up from sleep.
    pub wakeup: bool,
}

/// The narrow interface a CAN controller backend implements.
///
/// Rules every backend follows:
/// - strict `nb` semantics: "no free mailbox" and "nothing received" are
///   [`nb::Error::WouldBlock`]; only real faults are errors;
/// - nothing blocks: every wait on a hardware acknowledge bit is bounded and ends in
///   [`Error::Timeout`];
/// - filter indices in [`RxFrame::filter`] are those of the user's filter list, not the
///   hardware's match index.
pub trait Controller {
    /// The backend's compiled form of a filter list (ID table, filter banks) with the map
    /// from hardware match index back to the user's filter index.
    type Filters;

    /// Installs compiled filters (the backend leaves and re-enters its configuration mode
    /// as its hardware requires, and restores the mode it was in).
    fn install_filters(&mut self, filters: &Self::Filters) -> Result<(), Error>;

    /// How this controller orders its loaded mailboxes (and so the driver's queue).
    fn tx_policy(&self) -> TxPolicy;

    /// Number of transmit mailboxes available to [`Controller::transmit`].
    fn mailbox_count(&self) -> u8;

    /// Loads `frame` into a free transmit mailbox and requests its transmission.
    ///
    /// `WouldBlock` when no mailbox is free. Under [`TxPolicy::Priority`], when every
    /// mailbox is busy and `frame` wins arbitration against the lowest-priority pending
    /// mailbox, the backend may abort that mailbox, load `frame` instead and return the
    /// displaced frame (`Ok(Some(old))`), which the driver queues again: this is how
    /// priority inversion between software queue and hardware is avoided.
    fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, Error>;

    /// State of one transmit mailbox.
    fn mailbox_state(&self, mailbox: MailboxId) -> MailboxState;

    /// Requests the abort of a mailbox's transmission. Returns `true` when the mailbox
    /// was pending and is now empty; a mailbox on the bus finishes (or fails) first.
    fn abort(&mut self, mailbox: MailboxId) -> bool;

    /// Takes one received frame from the hardware (FIFO order), with the user's filter
    /// index and the time stamp. `WouldBlock` when nothing is there.
    fn receive(&mut self) -> nb::Result<RxFrame, Error>;

    /// Reads and acknowledges the controller's interrupt causes.
    fn take_events(&mut self) -> Events;

    /// The controller's error status.
    fn error_status(&self) -> ErrorStatus;

    /// Changes the operating mode (bounded wait on the acknowledge bit).
    fn set_mode(&mut self, mode: Mode) -> Result<(), Error>;

    /// Starts bus-off recovery by software (for controllers configured for manual
    /// recovery; a no-op returning `Ok` where recovery is automatic).
    fn recover(&mut self) -> Result<(), Error>;
}
