//! A deterministic simulated CAN bus for host tests and demos, and the ISO 11898-1
//! fault-confinement rules the peripheral models share with it (host only: `std`).
//!
//! The portable core (`twocan-core`, `no_std`) knows nothing of this crate; the
//! backends' behavioural models (feature `model` of `twocan-bxcan` and `twocan-flexcan`)
//! attach to its bus as [`BusNode`]s.
//!
//! Time is counted in bit times and advanced only by the caller.
//!
//! - [`bits`]: CRC-15, bit stuffing and exact frame lengths ([`frame_bits`]).
//! - `node`: the [`BusNode`] trait every peripheral model implements (re-exported here).
//! - [`bus`]: the [`Bus`] — nodes, time, arbitration, frame attempts played bit by bit,
//!   acknowledgement, error frames, statistics.
//! - [`inject`]: faults at chosen frames, on a node's frames, or at random with a seed.
//! - [`trace`]: the record of every frame attempt and its `candump -l` form.
//! - [`simple_node`]: [`SimNode`], a bare ISO node.
//! - [`fault`]: ISO 11898-1 fault confinement (error counters and the rules that move
//!   them), shared by [`SimNode`] and the peripheral models.
//! - [`poll_clock`]: [`PollClock`], register access that lets bus time pass while a
//!   driver spins on an acknowledge bit.
//!
//! ```
//! use twocan_sim::{Bus, SimNode};
//! use twocan_core::Frame;
//!
//! let mut bus = Bus::new(500_000).unwrap();
//! let a = SimNode::new().shared();
//! let b = SimNode::new().shared();
//! bus.attach("a", a.clone());
//! bus.attach("b", b.clone());
//! a.borrow_mut().send(Frame::standard(0x123, &[0xDE, 0xAD]).unwrap());
//! bus.run_until_idle(10_000).unwrap();
//! assert_eq!(b.borrow().received_frames(), vec![Frame::standard(0x123, &[0xDE, 0xAD]).unwrap()]);
//! let mut log = Vec::new();
//! bus.trace().write_candump(&mut log, "can0").unwrap();
//! assert_eq!(String::from_utf8(log).unwrap(), "(0000000000.000000) can0 123#DEAD\n");
//! ```

#![deny(missing_docs)]

pub mod bits;
pub mod bus;
mod engine;
mod fast;
pub mod fault;
pub mod inject;
mod node;
pub mod poll_clock;
pub mod simple_node;
pub mod stats;
pub mod trace;

pub use bits::{crc15, frame_bits, FrameBits};
pub use bus::{Bus, BusClock, BusEvent, NodeId, SimError, StillBusy};
pub use inject::{Fault, FaultError, FaultKind, FormField, RandomFaults, Receivers, Sees};
pub use node::{BusNode, BusTime, ConfinementEvent, TxRequest, TxResult};
pub use poll_clock::{PollClock, SharedBus, SpinWatchdog, SPIN_LIMIT};
pub use simple_node::SimNode;
pub use stats::{BusStats, NodeStats};
pub use trace::{NodeOutcome, NodeReport, Trace, TraceRecord};
