//! The split driver's one-feature sets of the one-feature bench variants (issue 21,
//! "each choice with its own measured cost"), shared by the bxCAN and FlexCAN variants
//! (`shared/bxcan_variant.rs`, `shared/flexcan_variant.rs`): `lean` with the receive
//! and transmit time stamps alone ([`StampsOnly`]) or the traffic statistics alone
//! ([`CountsOnly`]) switched on.

// Each firmware that includes this module uses a part of it.
#![allow(dead_code)]

/// A split-driver feature set with receive and transmit time stamps read and widened,
/// and no traffic statistics (`twocan_core::Features`, the `lean+stamps` variants).
#[derive(Debug, Clone, Copy)]
pub enum StampsOnly {}

impl twocan_core::Features for StampsOnly {
    const TIMESTAMPS: bool = true;
    const COUNTS: bool = false;
    type Counter = twocan_core::features::NoTally;
    type Clock = twocan_core::timestamp::Extender;
}

/// A split-driver feature set with the traffic statistics counted, as
/// `twocan_core::Full` counts them, and no time stamps read (the `lean+counts`
/// variants).
#[derive(Debug, Clone, Copy)]
pub enum CountsOnly {}

impl twocan_core::Features for CountsOnly {
    const TIMESTAMPS: bool = false;
    const COUNTS: bool = true;
    type Counter = twocan_core::spsc::Counter;
    type Clock = twocan_core::features::NoClock;
}
