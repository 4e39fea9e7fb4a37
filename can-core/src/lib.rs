//! Portable core of the `twocan` CAN drivers: frames, portable filters, the split driver
//! (a shared [`State`] and handles per context), the [`Hardware`] seam the backends
//! implement, dispatch by filter index and bit timing. The simulated bus is the
//! `twocan-sim` crate (host only), which builds on this one.
//!
//! # Quick start
//!
//! The state lives in a `static` (zero-initialised); [`State::split`] hands out each
//! handle once. Here over the mock controller (feature `mock`); firmware passes a
//! backend's controller (`twocan_bxcan::BxCan`, `twocan_flexcan::FlexCanHw`) and moves
//! the interrupt handles to the vectors before unmasking them.
//!
#![doc = concat!("```\n", include_str!("../doc/quick_start.rs"), "```")]
//!
//! # Critical sections
//!
//! The drivers share state between thread code and the interrupt handler through the
//! [`critical_section`] crate, which needs exactly one implementation in the final program;
//! without one, linking fails with an undefined `_critical_section_1_0_acquire`. Firmware
//! on a single-core Cortex-M (Teensy 3.x, STM32F7) enables `cortex-m`'s
//! `critical-section-single-core` feature (or uses a HAL or RTOS that provides one); host
//! programs and tests enable `critical-section`'s `std` feature.
#![cfg_attr(not(test), no_std)]
// docs.rs (nightly rustdoc): mark feature-gated items with the feature they need.
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]

#[cfg(feature = "async")]
pub mod asynch;
pub mod capabilities;
pub mod controller;
pub mod dispatch;
pub mod driver;
pub mod error;
pub mod features;
pub mod filter;
pub mod filter_set;
pub mod frame;
pub mod hardware;
pub mod io;
pub mod irq_cell;
#[cfg(all(test, twocan_loom))]
mod loom_tests;
pub mod mailbox;
#[cfg(any(test, feature = "mock"))]
pub mod mock;
mod once;
pub mod priority;
pub mod registers;
pub mod split;
pub mod spsc;
mod sync;
pub mod take_once;
pub mod timestamp;
pub mod timing;
pub mod txqueue;
#[cfg(feature = "async")]
mod wakers;

#[cfg(feature = "async")]
pub use asynch::RxEvent;
pub use capabilities::{BusMode, BusOffRecovery, Capabilities, ModeSupport};
pub use controller::{ErrorStatus, Mode};
pub use dispatch::Dispatcher;
pub use driver::{Driver, TrafficStats};
pub use embedded_can::{ExtendedId, Id, StandardId};
pub use error::{
    AtomicLastError, Error, ErrorCounters, ErrorState, ErrorStatistics, LastErrorCode,
};
pub use features::{Features, Full, Lean};
pub use filter::{Filter, FilterError, Format, FrameKind};
pub use frame::{Frame, FrameError, RxFrame};
pub use hardware::{Completion, FifoEvents, Hardware, Settled, StatusEvents, Token, TxFailure};
#[cfg(feature = "async")]
pub use io::{AsyncCanRx, AsyncCanTx};
pub use io::{CanRx, CanStatus, CanTx};
pub use mailbox::{MailboxId, MailboxState, TxOutcome, TxPolicy};
pub use once::Lease;
pub use priority::Priority;
pub use registers::{Fixed, Mmio, Registers};
pub use split::State;
pub use split::{AbortRequest, Leftovers, Parts, StateChange, UnsplitError};
pub use spsc::BufferStats;
pub use spsc::SpscRing;
pub use take_once::TakeOnce;
pub use timestamp::Timestamp;
pub use txqueue::{AnyQueue, FifoQueue, PriorityQueue};
