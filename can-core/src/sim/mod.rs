//! A deterministic simulated CAN bus for host tests and demos (feature `sim`).
//!
//! Time is counted in bit times and advanced only by the caller.

mod node;
pub use node::{BusNode, BusTime, TxRequest, TxResult};
