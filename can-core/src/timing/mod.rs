//! CAN bit timing: controller limits, a `const` solver, adjustable segments with
//! a consistency check, register encodings and an iterator over every solution.
//!
//! ```
//! use twocan_core::timing::{cia_sample_point, solve, Limits, Timing, DEFAULT_TOLERANCE_PPM};
//!
//! // ACAN §16.1: 842 kbit/s from the 16 MHz FlexCAN clock, computed at compile time.
//! const T: Timing = match solve(16_000_000, 842_000, &Limits::FLEXCAN, cia_sample_point(842_000)) {
//!     Ok(t) => t,
//!     Err(_) => panic!("no timing"),
//! };
//! assert_eq!(T.actual_bitrate(), 842_105);
//! assert_eq!(T.ppm_from_wished(), 124);
//! assert!(T.within_tolerance(DEFAULT_TOLERANCE_PPM)); // ACAN's default 1,000 ppm
//! assert!(!T.within_tolerance(0)); // 0 ppm: exact only
//! assert!(T.validate(DEFAULT_TOLERANCE_PPM).is_ok()); // what a backend checks
//!
//! // Adjust the segments by hand (ACAN §16.1) and check them (ACAN §16.2).
//! let mut t = T;
//! t.phase_seg2 = 1; // FlexCAN needs PSEG2 ≥ 2, and RJW ≤ PSEG2
//! assert!(!t.consistency().is_ok());
//! assert!(t.flexcan_ctrl1().is_err());
//! ```
//!
//! * [`limits`]: [`Limits::FLEXCAN`], [`Limits::BXCAN`] — the ranges as data and
//!   how tseg1 splits into propagation and phase segment 1.
//! * [`solver`]: [`solve`] / [`solve_cia`] and the objective they follow;
//!   [`cia_sample_point`]; [`DEFAULT_TOLERANCE_PPM`].
//! * [`segments`]: [`Timing`] (the adjustable value and everything derived from
//!   it); [`consistency`]: [`Consistency`] (the rule flags).
//! * [`encode`]: bxCAN `CAN_BTR` and FlexCAN `CTRL1` values.
//! * [`iter`]: [`Solutions`], every timing within a tolerance.
//! * [`frame_time`]: worst-case frame durations and wait bounds at a bit rate.
//! * [`rule`]: [`TimingRule`], what one controller accepts — the one rule every entry
//!   point that takes a bit rate or a timing applies, and the fastest and slowest
//!   accepted timings the capabilities report.
//! * [`flexcan_rules`]: the FlexCAN manual's 8-quanta and clocks-per-bit rules, as a
//!   [`TimingRule`].
//!
//! All arithmetic is integer (u64/u128 where products would overflow); see
//! `docs/bit-timing.md` for worked examples.

pub mod consistency;
pub mod encode;
pub mod error;
pub mod flexcan_rules;
pub mod frame_time;
pub mod iter;
pub mod limits;
pub mod rule;
pub mod segments;
pub mod solver;

pub use consistency::Consistency;
pub use encode::{
    BxcanBtr, FlexcanCtrl1, BXCAN_BTR_LBKM, BXCAN_BTR_SILM, BXCAN_BTR_TIMING_MASK,
    FLEXCAN_CTRL1_SMP, FLEXCAN_CTRL1_TIMING_MASK,
};
pub use error::TimingError;
pub use iter::Solutions;
pub use limits::{Bounds, Controller, Limits};
pub use rule::{ManualViolation, PeripheralClockRule, TimingRule};
pub use segments::Timing;
pub use solver::{cia_sample_point, solve, solve_cia, DEFAULT_TOLERANCE_PPM};
