//! Portable core of the `twocan` CAN drivers.
#![cfg_attr(not(any(test, feature = "std")), no_std)]
#![deny(missing_docs)]

#[cfg(feature = "std")]
extern crate std;

pub mod buffer;
pub mod controller;
pub mod dispatch;
pub mod driver;
pub mod error;
pub mod fault;
pub mod filter;
pub mod filter_set;
pub mod frame;
pub mod mailbox;
#[cfg(any(test, feature = "mock"))]
pub mod mock;
pub mod priority;
pub mod registers;
#[cfg(feature = "sim")]
pub mod sim;
pub mod timing;

pub use buffer::{BufferStats, Ring, TxQueue};
pub use controller::{Controller, ErrorStatus, Events, Mode};
pub use dispatch::Dispatcher;
pub use driver::{Driver, TrafficStats};
pub use embedded_can::{ExtendedId, Id, StandardId};
pub use error::{Error, ErrorCounters, ErrorState, ErrorStatistics, LastErrorCode};
pub use filter::{Filter, FilterError, Format, FrameKind};
pub use frame::{Frame, FrameError, RxFrame};
pub use mailbox::{MailboxId, MailboxState, TxOutcome, TxPolicy};
pub use priority::Priority;
pub use registers::{Mmio, Registers};
