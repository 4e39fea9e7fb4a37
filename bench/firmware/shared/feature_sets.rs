//! What the bench variants of both drivers share (`shared/bxcan_variant.rs`,
//! `shared/flexcan_variant.rs`): the variant's cargo features checked, its name
//! ([`VARIANT`]), its completion ring ([`DONE`]) and the split driver's feature set
//! ([`Fe`]), including the one-feature sets of the one-feature variants (issue 21,
//! "each choice with its own measured cost"): `lean` with the receive and transmit time
//! stamps alone ([`StampsOnly`]) or the traffic statistics alone ([`CountsOnly`])
//! switched on.

// Each firmware that includes this module uses a part of it.
#![allow(dead_code)]

#[cfg(all(feature = "lean", feature = "full"))]
compile_error!("features `lean` and `full` are exclusive");
#[cfg(not(any(feature = "lean", feature = "full")))]
compile_error!("enable feature `lean` or `full`");
#[cfg(all(
    any(
        feature = "done",
        feature = "stamps",
        feature = "counts",
        feature = "switch",
        feature = "planner"
    ),
    not(feature = "lean")
))]
compile_error!(
    "features `done`, `stamps`, `counts`, `switch` and `planner` switch one choice of \
     `lean` to its full setting: enable them with `lean` only"
);
#[cfg(any(
    all(
        feature = "done",
        any(
            feature = "stamps",
            feature = "counts",
            feature = "switch",
            feature = "planner"
        )
    ),
    all(
        feature = "stamps",
        any(feature = "counts", feature = "switch", feature = "planner")
    ),
    all(feature = "counts", any(feature = "switch", feature = "planner")),
    all(feature = "switch", feature = "planner"),
))]
compile_error!(
    "enable at most one of `done`, `stamps`, `counts`, `switch`, `planner`: each \
     one-feature variant measures one choice alone"
);

/// The variant's name in the bench output (and what the firmware prints).
#[cfg(all(
    feature = "lean",
    not(any(
        feature = "done",
        feature = "stamps",
        feature = "counts",
        feature = "switch",
        feature = "planner"
    ))
))]
pub const VARIANT: &str = "lean";
#[cfg(feature = "done")]
pub const VARIANT: &str = "lean+done";
#[cfg(feature = "stamps")]
pub const VARIANT: &str = "lean+stamps";
#[cfg(feature = "counts")]
pub const VARIANT: &str = "lean+counts";
#[cfg(feature = "switch")]
pub const VARIANT: &str = "lean+switch";
#[cfg(feature = "planner")]
pub const VARIANT: &str = "lean+planner";
#[cfg(feature = "full")]
pub const VARIANT: &str = "full";

/// Completion ring capacity: 8 in full and `lean+done`, else 0 (fire and forget).
pub const DONE: usize = if cfg!(any(feature = "full", feature = "done")) {
    8
} else {
    0
};

/// The split driver's compile-time feature set: `Lean` (no statistics, no time stamps
/// read), one of the one-feature sets below, or `Full`.
#[cfg(all(feature = "lean", not(any(feature = "stamps", feature = "counts"))))]
pub type Fe = twocan_core::Lean;
/// `lean+stamps`: time stamps only.
#[cfg(feature = "stamps")]
pub type Fe = StampsOnly;
/// `lean+counts`: statistics only.
#[cfg(feature = "counts")]
pub type Fe = CountsOnly;
/// Full: statistics and time stamps.
#[cfg(feature = "full")]
pub type Fe = twocan_core::Full;

/// A split-driver feature set with receive and transmit time stamps read and widened,
/// and no traffic statistics (`twocan_core::Features`, the `lean+stamps` variants).
#[derive(Debug, Clone, Copy)]
pub enum StampsOnly {}

impl twocan_core::Features for StampsOnly {
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
    const COUNTS: bool = true;
    type Counter = twocan_core::spsc::Counter;
    type Clock = twocan_core::features::NoClock;
}
