//! Test support shared by the backends' tests (host only, `std`):
//!
//! - [`scenario`]: the seeded scenarios that check the simulated bus's fast path against
//!   its bit-level path with a peripheral model on the bus (each backend's
//!   `tests/model_fast_path.rs` plugs its model in through [`scenario::Model`]);
//! - [`filters`]: the filter lists and probe frames the planners' property tests draw
//!   (each backend's `tests/planner_props.rs`).
#![deny(missing_docs)]

pub mod filters;
pub mod scenario;
