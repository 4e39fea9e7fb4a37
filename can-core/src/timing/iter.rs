//! Every valid timing for a clock and a bit rate, without allocation.
//!
//! [`Solutions`] walks every (prescaler, tseg1, tseg2) the [`Limits`] allow and
//! yields, as a [`Timing`] built by [`Timing::from_tsegs`] (documented tseg1 split,
//! largest SJW, single sampling), those
//! [within the tolerance](Timing::within_tolerance) of the wished bit rate.
//! Order: prescaler ascending, then quanta per bit ascending, then tseg1 descending
//! (sample point from late to early).

use super::error::TimingError;
use super::limits::Limits;
use super::segments::Timing;
use super::solver::check_inputs;

/// Iterator over every timing within a tolerance of a wished bit rate.
///
/// ```
/// use twocan_core::timing::{Limits, Solutions};
/// // 500 kbit/s exactly from 16 MHz on FlexCAN: 16 quanta (prescaler 2, 7 ways
/// // to place the sample point) or 8 quanta (prescaler 4, 4 ways).
/// let all = Solutions::new(16_000_000, 500_000, &Limits::FLEXCAN, 0).unwrap();
/// assert_eq!(all.count(), 11);
/// ```
#[derive(Debug, Clone)]
pub struct Solutions {
    clock_hz: u32,
    bitrate: u32,
    limits: Limits,
    tolerance_ppm: u32,
    prescaler: u32,
    quanta: u32,
    tseg1: u32,
    done: bool,
}

impl Solutions {
    /// All timings for `bitrate` from `clock_hz` under `limits` within
    /// `tolerance_ppm` (0: exact only). Errors: [`TimingError::ClockZero`],
    /// [`TimingError::BitrateZero`], [`TimingError::InvalidLimits`].
    pub const fn new(
        clock_hz: u32,
        bitrate: u32,
        limits: &Limits,
        tolerance_ppm: u32,
    ) -> Result<Solutions, TimingError> {
        if let Err(e) = check_inputs(clock_hz, bitrate, limits) {
            return Err(e);
        }
        let mut s = Solutions {
            clock_hz,
            bitrate,
            limits: *limits,
            tolerance_ppm,
            prescaler: limits.prescaler.min as u32,
            quanta: limits.min_quanta(),
            tseg1: 0,
            done: false,
        };
        if s.pair_ok() {
            s.tseg1 = s.tseg1_hi();
        } else {
            s.next_pair();
        }
        Ok(s)
    }

    /// Largest tseg1 for the current quanta count.
    const fn tseg1_hi(&self) -> u32 {
        let hi = (self.quanta - 1).saturating_sub(self.limits.phase_seg2.min as u32);
        let max = self.limits.tseg1().max as u32;
        if hi < max {
            hi
        } else {
            max
        }
    }

    /// Smallest tseg1 for the current quanta count.
    const fn tseg1_lo(&self) -> u32 {
        let lo = (self.quanta - 1).saturating_sub(self.limits.phase_seg2.max as u32);
        let min = self.limits.tseg1().min as u32;
        if lo > min {
            lo
        } else {
            min
        }
    }

    /// Moves to the next (prescaler, quanta) whose rate is within tolerance, on
    /// its largest tseg1; sets `done` when there is none.
    const fn next_pair(&mut self) {
        loop {
            if self.quanta < self.limits.max_quanta() {
                self.quanta += 1;
            } else if self.prescaler < self.limits.prescaler.max as u32 {
                self.prescaler += 1;
                self.quanta = self.limits.min_quanta();
            } else {
                self.done = true;
                return;
            }
            if self.pair_ok() {
                self.tseg1 = self.tseg1_hi();
                return;
            }
        }
    }

    /// Whether the current (prescaler, quanta) is within tolerance (the rate only
    /// depends on prescaler × quanta).
    const fn pair_ok(&self) -> bool {
        self.timing_at(self.tseg1_hi())
            .within_tolerance(self.tolerance_ppm)
    }

    /// The timing of the current (prescaler, quanta) with tseg1 = `t1`.
    const fn timing_at(&self, t1: u32) -> Timing {
        Timing::from_tsegs(
            self.clock_hz,
            self.bitrate,
            &self.limits,
            self.prescaler as u16,
            t1 as u8,
            (self.quanta - 1 - t1) as u8,
        )
    }
}

impl Iterator for Solutions {
    type Item = Timing;

    fn next(&mut self) -> Option<Timing> {
        if self.done {
            return None;
        }
        let t1 = self.tseg1;
        let t = self.timing_at(t1);
        if t1 > self.tseg1_lo() {
            self.tseg1 -= 1;
        } else {
            self.next_pair();
        }
        Some(t)
    }
}

impl core::iter::FusedIterator for Solutions {}
