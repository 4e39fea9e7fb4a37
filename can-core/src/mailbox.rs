//! Transmit mailboxes: their states and the order in which a controller sends them.

/// State of one hardware transmit mailbox (bxCAN notes §"transmit mailbox states";
/// FlexCAN message-buffer codes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MailboxState {
    /// Free: may be loaded.
    Empty,
    /// Transmission requested, waiting to become the highest-priority mailbox.
    Pending,
    /// The highest-priority pending mailbox: the next to go when the bus is idle.
    Scheduled,
    /// On the bus now.
    Transmitting,
}

/// How a controller chooses among several loaded mailboxes — and how the software
/// transmit queue in front of them is ordered.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TxPolicy {
    /// Frames leave in the order they were handed to the driver (bxCAN TXFP = 1,
    /// ACAN's single data mailbox: "sequentiality").
    #[default]
    Fifo,
    /// The frame of highest arbitration priority ([`crate::priority::Priority`]) goes
    /// first (bxCAN TXFP = 0); equal priorities leave in request order.
    Priority,
}

/// Index of a transmit mailbox in its controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MailboxId(pub u8);

/// How a mailbox's last transmission request ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TxOutcome {
    /// Sent and acknowledged.
    Sent,
    /// Aborted before it was sent.
    Aborted,
    /// Failed (one-shot mode: arbitration lost or an error, no retry).
    Failed,
}
