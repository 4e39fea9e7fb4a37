//! What one controller instance accepts, as data: the one rule every entry point that
//! takes a bit rate or a bit timing applies (issue 22: "what is reported is what is
//! accepted").
//!
//! A [`TimingRule`] is the CAN clock, the [`Limits`] (register ranges and the quanta per
//! bit allowed) and, where the controller's manual has one, a minimum ratio between a
//! peripheral clock and the bit rate ([`PeripheralClockRule`]: FlexCAN,
//! [`super::flexcan_rules`]). It answers the three questions an entry point asks:
//!
//! 1. **Is this timing accepted?** [`TimingRule::check_timing`]: made for this clock
//!    ([`TimingError::WrongClock`]) and this register layout
//!    ([`TimingError::WrongController`]); consistent with the register ranges (ACAN §16.2,
//!    [`TimingError::Inconsistent`]); allowed by the manual's rules beyond them
//!    ([`TimingError::ForbiddenByManual`], [`TimingRule::manual_violation`]). Nothing
//!    else: no bit-rate range is checked on a timing, so no rounding can refuse a timing
//!    the registers hold (the slowest bxCAN timing, 2,109.375 bit/s at 54 MHz, is
//!    accepted).
//! 2. **Is this wished bit rate in range?** [`TimingRule::check_bitrate`]: between the
//!    bit rates of the slowest and the fastest accepted timings
//!    ([`TimingRule::slowest`], [`TimingRule::fastest`]), each rounded down as every
//!    bit rate here ([`Timing::actual_bitrate`], ACAN §16.3): [`TimingRule::min_bitrate`]
//!    ..= [`TimingRule::max_bitrate`], else [`TimingError::BitrateTooLow`] /
//!    [`TimingError::BitrateTooHigh`] (one bit per second beyond is refused, even where
//!    the solver would find a timing within the tolerance).
//! 3. **Is the timing close enough to its wished rate?** [`Timing::within_tolerance`]
//!    (ACAN §16.1; [`TimingError::TooFarFromWishedBitrate`]).
//!
//! [`TimingRule::timing_for`] (a wished rate → a timing) asks 2, solves among the
//! accepted timings only, then asks 1 and 3; [`TimingRule::accept`] (a timing with its
//! wished rate and a tolerance, as `begin` and `Config::from_timing` get it) asks 2, 1
//! and 3. Writing a timing to a stopped controller (`Hardware::set_timing`) asks 1.
//!
//! ```
//! use twocan_core::timing::{flexcan_rules, Limits, TimingError, TimingRule};
//!
//! // bxCAN on a 54 MHz APB1: the registers are the whole rule.
//! let bx = TimingRule::new(54_000_000, Limits::BXCAN);
//! let slowest = bx.slowest().unwrap();
//! assert_eq!((slowest.prescaler, slowest.quanta()), (1024, 25));
//! assert_eq!(bx.check_timing(&slowest), Ok(()));
//! assert_eq!((bx.min_bitrate(), bx.max_bitrate()), (2_109, 18_000_000));
//! assert_eq!(bx.check_bitrate(2_108), Err(TimingError::BitrateTooLow));
//!
//! // FlexCAN with a 16 MHz bus clock: 8 quanta and 16 bus clocks per bit.
//! let flex = flexcan_rules::rule(16_000_000, 16_000_000, 16, true);
//! assert_eq!(flex.max_bitrate(), 1_000_000);
//! assert_eq!(flex.check_bitrate(1_000_001), Err(TimingError::BitrateTooHigh));
//! let t = flex.timing_for(1_000_000, 750, 0).unwrap();
//! assert_eq!(flex.check_timing(&t), Ok(()));
//! ```

use core::fmt;

use super::error::TimingError;
use super::limits::Limits;
use super::segments::{consistency_with, Timing};
use super::solver::{best_split, cia_sample_point, solve};

/// A minimum ratio between a peripheral clock and the CAN bit rate, as a controller's
/// manual states it (Kinetis FlexCAN, "Arbitration and matching timing": the module
/// scans the message buffers within one bit time). The peripheral clock may not be
/// slower than the CAN clock ("The peripheral clock frequency can not be smaller than
/// the oscillator clock frequency").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PeripheralClockRule {
    /// The peripheral (bus) clock, Hz.
    pub peripheral_hz: u32,
    /// The least number of peripheral clocks per CAN bit.
    pub min_clocks_per_bit: u32,
}

/// A timing the controller's manual forbids although its registers hold it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ManualViolation {
    /// Fewer quanta per bit than [`Limits::quanta`] allows (FlexCAN: 8).
    TooFewQuanta {
        /// The timing's quanta per bit.
        quanta: u32,
        /// The least the manual allows.
        min: u32,
    },
    /// More quanta per bit than [`Limits::quanta`] allows.
    TooManyQuanta {
        /// The timing's quanta per bit.
        quanta: u32,
        /// The most the manual allows.
        max: u32,
    },
    /// Fewer peripheral clocks per CAN bit than the manual requires.
    TooFewPeripheralClocks {
        /// Peripheral clocks per bit, `peripheral_hz × clocks_per_bit / clock_hz`
        /// rounded down.
        clocks_per_bit: u64,
        /// The least the manual allows.
        min: u32,
    },
    /// A peripheral clock slower than the timing's CAN clock.
    PeripheralClockBelowCanClock {
        /// The peripheral clock, Hz.
        peripheral_hz: u32,
        /// The CAN clock the timing is made from, Hz.
        can_clock_hz: u32,
    },
    /// A peripheral clock of 0 Hz, or a timing of 0 clocks per bit.
    Zero,
}

impl fmt::Display for ManualViolation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ManualViolation::TooFewQuanta { quanta, min } => write!(
                f,
                "{quanta} time quanta per bit, fewer than the {min} the controller's manual requires"
            ),
            ManualViolation::TooManyQuanta { quanta, max } => write!(
                f,
                "{quanta} time quanta per bit, more than the {max} the controller's manual allows"
            ),
            ManualViolation::TooFewPeripheralClocks {
                clocks_per_bit,
                min,
            } => write!(
                f,
                "{clocks_per_bit} peripheral clocks per CAN bit, fewer than the {min} the controller's manual requires"
            ),
            ManualViolation::PeripheralClockBelowCanClock {
                peripheral_hz,
                can_clock_hz,
            } => write!(
                f,
                "peripheral clock {peripheral_hz} Hz below the CAN clock {can_clock_hz} Hz"
            ),
            ManualViolation::Zero => f.write_str("a clock or bit rate of 0"),
        }
    }
}

impl core::error::Error for ManualViolation {}

/// What one controller instance accepts (see the [module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TimingRule {
    /// The CAN clock timings are made from, Hz.
    pub clock_hz: u32,
    /// The register ranges and the quanta per bit allowed.
    pub limits: Limits,
    /// The manual's peripheral-clock ratio, where there is one.
    pub peripheral_clock: Option<PeripheralClockRule>,
}

impl TimingRule {
    /// The rule of a controller whose registers are the whole rule.
    pub const fn new(clock_hz: u32, limits: Limits) -> Self {
        TimingRule {
            clock_hz,
            limits,
            peripheral_clock: None,
        }
    }

    /// The same rule with a peripheral-clock ratio.
    pub const fn with_peripheral_clock(mut self, rule: PeripheralClockRule) -> Self {
        self.peripheral_clock = Some(rule);
        self
    }

    /// Whether a bit of `clocks_per_bit` CAN clocks satisfies the peripheral-clock
    /// ratio: `peripheral_hz / bit rate ≥ min`, i.e. `clocks_per_bit × peripheral_hz ≥
    /// min × clock_hz`, compared exactly; and the peripheral clock not below the CAN
    /// clock. `Err` says why not.
    const fn peripheral_ok(&self, clocks_per_bit: u64) -> Result<(), ManualViolation> {
        let Some(p) = self.peripheral_clock else {
            return Ok(());
        };
        if p.peripheral_hz == 0 || clocks_per_bit == 0 || self.clock_hz == 0 {
            return Err(ManualViolation::Zero);
        }
        if p.peripheral_hz < self.clock_hz {
            return Err(ManualViolation::PeripheralClockBelowCanClock {
                peripheral_hz: p.peripheral_hz,
                can_clock_hz: self.clock_hz,
            });
        }
        let have = clocks_per_bit as u128 * p.peripheral_hz as u128;
        let need = p.min_clocks_per_bit as u128 * self.clock_hz as u128;
        if have < need {
            return Err(ManualViolation::TooFewPeripheralClocks {
                clocks_per_bit: (have / self.clock_hz as u128) as u64,
                min: p.min_clocks_per_bit,
            });
        }
        Ok(())
    }

    /// The manual's rules beyond the register ranges that `t` breaks, if any: quanta per
    /// bit inside [`Limits::quanta`], then the peripheral-clock ratio.
    pub const fn manual_violation(&self, t: &Timing) -> Option<ManualViolation> {
        let quanta = t.quanta();
        if quanta < self.limits.min_quanta() {
            return Some(ManualViolation::TooFewQuanta {
                quanta,
                min: self.limits.min_quanta(),
            });
        }
        if quanta > self.limits.max_quanta() {
            return Some(ManualViolation::TooManyQuanta {
                quanta,
                max: self.limits.max_quanta(),
            });
        }
        match self.peripheral_ok(t.clocks_per_bit()) {
            Ok(()) => None,
            Err(v) => Some(v),
        }
    }

    /// Question 1 of the [module docs](self): whether the controller accepts `t`.
    pub const fn check_timing(&self, t: &Timing) -> Result<(), TimingError> {
        if self.clock_hz == 0 {
            return Err(TimingError::ClockZero);
        }
        if t.clock_hz != self.clock_hz {
            return Err(TimingError::WrongClock);
        }
        if !matches_controller(&t.limits, &self.limits) {
            return Err(TimingError::WrongController);
        }
        let c = consistency_with(t, &self.limits);
        if !c.is_ok() {
            return Err(TimingError::Inconsistent(c));
        }
        if self.manual_violation(t).is_some() {
            return Err(TimingError::ForbiddenByManual);
        }
        Ok(())
    }

    /// The (prescaler, quanta) of an accepted timing of `n` clocks per bit, the most
    /// quanta first; `None` when no accepted timing has `n` clocks per bit.
    const fn shape(&self, n: u64) -> Option<(u16, u32)> {
        if self.peripheral_ok(n).is_err() {
            return None;
        }
        let mut q = self.limits.max_quanta();
        while q >= self.limits.min_quanta() && q > 0 {
            if n.is_multiple_of(q as u64) {
                let p = n / q as u64;
                if p >= self.limits.prescaler.min as u64 && p <= self.limits.prescaler.max as u64 {
                    return Some((p as u16, q));
                }
            }
            q -= 1;
        }
        None
    }

    /// The accepted timing of `n` clocks per bit (most quanta, sample point nearest the
    /// CiA one, largest SJW), wished at its own bit rate.
    const fn timing_of(&self, n: u64) -> Option<Timing> {
        let Some((p, q)) = self.shape(n) else {
            return None;
        };
        let rate = (self.clock_hz as u64 / n) as u32;
        match best_split(q as u64, &self.limits, cia_sample_point(rate) as u64) {
            Some((t1, t2)) => Some(Timing::from_tsegs(
                self.clock_hz,
                rate,
                &self.limits,
                p,
                t1 as u8,
                t2 as u8,
            )),
            None => None,
        }
    }

    /// The fewest and the most CAN clocks per bit the registers can express.
    const fn clock_range(&self) -> (u64, u64) {
        (
            self.limits.prescaler.min as u64 * self.limits.min_quanta() as u64,
            self.limits.prescaler.max as u64 * self.limits.max_quanta() as u64,
        )
    }

    /// The fastest accepted timing (fewest clocks per bit; `None` when nothing is
    /// accepted: a clock of 0, invalid limits, a peripheral clock below the CAN clock).
    pub const fn fastest(&self) -> Option<Timing> {
        if self.clock_hz == 0 || !self.limits.is_valid() {
            return None;
        }
        let (mut n, hi) = self.clock_range();
        // The peripheral-clock ratio needs at least ⌈min × clock / peripheral⌉ clocks.
        if let Some(p) = self.peripheral_clock {
            if p.peripheral_hz < self.clock_hz {
                return None;
            }
            let need = (p.min_clocks_per_bit as u64 * self.clock_hz as u64)
                .div_ceil(p.peripheral_hz as u64);
            if need > n {
                n = need;
            }
        }
        while n <= hi {
            if let Some(t) = self.timing_of(n) {
                return Some(t);
            }
            n += 1;
        }
        None
    }

    /// The slowest accepted timing (most clocks per bit: the largest prescaler and the
    /// most quanta, which the peripheral-clock ratio allows whenever it allows any;
    /// `None` when nothing is accepted).
    pub const fn slowest(&self) -> Option<Timing> {
        if self.clock_hz == 0 || !self.limits.is_valid() {
            return None;
        }
        self.timing_of(self.clock_range().1)
    }

    /// The bit rate of the fastest accepted timing, rounded down (0 when nothing is
    /// accepted).
    pub const fn max_bitrate(&self) -> u32 {
        match self.fastest() {
            Some(t) => t.actual_bitrate(),
            None => 0,
        }
    }

    /// The bit rate of the slowest accepted timing, rounded down (0 when nothing is
    /// accepted).
    pub const fn min_bitrate(&self) -> u32 {
        match self.slowest() {
            Some(t) => t.actual_bitrate(),
            None => 0,
        }
    }

    /// Question 2 of the [module docs](self): [`TimingError::ClockZero`],
    /// [`TimingError::BitrateZero`], [`TimingError::ForbiddenByManual`] when no timing
    /// at all is accepted (a peripheral clock below the CAN clock),
    /// [`TimingError::BitrateTooHigh`] above [`TimingRule::max_bitrate`],
    /// [`TimingError::BitrateTooLow`] below [`TimingRule::min_bitrate`].
    pub const fn check_bitrate(&self, bitrate: u32) -> Result<(), TimingError> {
        if self.clock_hz == 0 {
            return Err(TimingError::ClockZero);
        }
        if bitrate == 0 {
            return Err(TimingError::BitrateZero);
        }
        if !self.limits.is_valid() {
            return Err(TimingError::InvalidLimits);
        }
        let (Some(fast), Some(slow)) = (self.fastest(), self.slowest()) else {
            return Err(TimingError::ForbiddenByManual);
        };
        if bitrate > fast.actual_bitrate() {
            Err(TimingError::BitrateTooHigh)
        } else if bitrate < slow.actual_bitrate() {
            Err(TimingError::BitrateTooLow)
        } else {
            Ok(())
        }
    }

    /// A wished bit rate → the accepted timing nearest to it ([`solve`]'s objective,
    /// among the accepted timings only), aiming at `sample_point_permille`: question 2,
    /// the solver's errors ([`TimingError::SamplePointOutOfRange`]), question 1, then
    /// question 3 with `tolerance_ppm` (0: exact only).
    pub const fn timing_for(
        &self,
        bitrate: u32,
        sample_point_permille: u16,
        tolerance_ppm: u32,
    ) -> Result<Timing, TimingError> {
        if let Err(e) = self.check_bitrate(bitrate) {
            return Err(e);
        }
        let t = match solve(self.clock_hz, bitrate, &self.limits, sample_point_permille) {
            Ok(t) => t,
            Err(e) => return Err(e),
        };
        // A wished rate in range is nearest to a timing of at least the fastest
        // timing's clocks per bit (a bit of fewer clocks is faster still), so the
        // peripheral-clock ratio holds; checked all the same.
        if let Err(e) = self.check_timing(&t) {
            return Err(e);
        }
        if !t.within_tolerance(tolerance_ppm) {
            return Err(TimingError::TooFarFromWishedBitrate);
        }
        Ok(t)
    }

    /// A timing as `begin` or a configuration builder gets it, with its wished bit rate
    /// ([`Timing::bitrate`]) and a tolerance: question 2 on the wished rate (as `begin`
    /// refuses it first), question 1, question 3.
    pub const fn accept(&self, t: &Timing, tolerance_ppm: u32) -> Result<(), TimingError> {
        if let Err(e) = self.check_bitrate(t.bitrate) {
            return Err(e);
        }
        if let Err(e) = self.check_timing(t) {
            return Err(e);
        }
        if !t.within_tolerance(tolerance_ppm) {
            return Err(TimingError::TooFarFromWishedBitrate);
        }
        Ok(())
    }
}

/// Whether a timing made with `made` can be written by a controller of `rule`: the same
/// register layout and the same field ranges (the quanta per bit are the manual's part
/// of the rule, checked by [`TimingRule::manual_violation`]: a timing computed with
/// [`Limits::FLEXCAN`], ACAN's ranges, is judged by the FlexCAN driver's
/// [`Limits::FLEXCAN_KINETIS`]).
const fn matches_controller(made: &Limits, rule: &Limits) -> bool {
    // `Limits` has no const `PartialEq`: field by field, `quanta` left out.
    made.controller as u8 == rule.controller as u8
        && made.prescaler.min == rule.prescaler.min
        && made.prescaler.max == rule.prescaler.max
        && made.prop_seg.min == rule.prop_seg.min
        && made.prop_seg.max == rule.prop_seg.max
        && made.phase_seg1.min == rule.phase_seg1.min
        && made.phase_seg1.max == rule.phase_seg1.max
        && made.phase_seg2.min == rule.phase_seg2.min
        && made.phase_seg2.max == rule.phase_seg2.max
        && made.sjw.min == rule.sjw.min
        && made.sjw.max == rule.sjw.max
        && made.sjw_le_phase_seg1 == rule.sjw_le_phase_seg1
        && match (
            made.triple_sampling_min_phase_seg1,
            rule.triple_sampling_min_phase_seg1,
        ) {
            (None, None) => true,
            (Some(x), Some(y)) => x == y,
            _ => false,
        }
}

/// The bit-rate range of bare limits: [`TimingRule`] with no rule beyond them (here, so
/// that `limits` stays below the rule that reads it).
impl Limits {
    /// The fastest bit rate these limits reach from `clock_hz` (smallest prescaler,
    /// fewest quanta per bit), rounded down like every bit rate here
    /// ([`Timing::actual_bitrate`](crate::timing::Timing::actual_bitrate), ACAN §16.3):
    /// [`TimingRule::max_bitrate`] without a rule beyond these limits.
    pub const fn max_bitrate(&self, clock_hz: u32) -> u32 {
        TimingRule::new(clock_hz, *self).max_bitrate()
    }

    /// The slowest bit rate these limits reach from `clock_hz` (largest prescaler, most
    /// quanta per bit), rounded down ([`TimingRule::min_bitrate`]).
    pub const fn min_bitrate(&self, clock_hz: u32) -> u32 {
        TimingRule::new(clock_hz, *self).min_bitrate()
    }

    /// [`TimingRule::check_bitrate`] for these limits alone (no rule beyond them):
    /// [`TimingError::ClockZero`], [`TimingError::BitrateZero`],
    /// [`TimingError::BitrateTooHigh`] above [`Limits::max_bitrate`],
    /// [`TimingError::BitrateTooLow`] below [`Limits::min_bitrate`].
    ///
    /// ```
    /// use twocan_core::timing::{Limits, TimingError};
    /// const OK: Result<(), TimingError> = Limits::FLEXCAN.check_bitrate(16_000_000, 500_000);
    /// assert_eq!(OK, Ok(()));
    /// assert_eq!(Limits::FLEXCAN.max_bitrate(16_000_000), 3_200_000); // ACAN §16.1
    /// assert_eq!(Limits::FLEXCAN_KINETIS.max_bitrate(16_000_000), 2_000_000); // 8 quanta
    /// assert_eq!(Limits::FLEXCAN.min_bitrate(16_000_000), 2_500);
    /// // 54 MHz / (1024 × 25) = 2,109.375 bit/s, rounded down.
    /// assert_eq!(Limits::BXCAN.min_bitrate(54_000_000), 2_109);
    /// assert_eq!(
    ///     Limits::FLEXCAN.check_bitrate(16_000_000, 3_200_001),
    ///     Err(TimingError::BitrateTooHigh)
    /// );
    /// assert_eq!(
    ///     Limits::BXCAN.check_bitrate(54_000_000, 1),
    ///     Err(TimingError::BitrateTooLow)
    /// );
    /// ```
    pub const fn check_bitrate(&self, clock_hz: u32, bitrate: u32) -> Result<(), TimingError> {
        TimingRule::new(clock_hz, *self).check_bitrate(bitrate)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timing::flexcan_rules;

    #[test]
    fn extremes_of_the_register_ranges() {
        let bx = TimingRule::new(54_000_000, Limits::BXCAN);
        let fast = bx.fastest().unwrap();
        assert_eq!(
            (fast.prescaler, fast.quanta(), fast.actual_bitrate()),
            (1, 3, 18_000_000)
        );
        let slow = bx.slowest().unwrap();
        assert_eq!((slow.prescaler, slow.quanta()), (1024, 25));
        assert_eq!(slow.actual_bitrate(), 2_109);
        for t in [fast, slow] {
            assert_eq!(bx.check_timing(&t), Ok(()));
            assert_eq!(bx.accept(&t, 1_000), Ok(()));
        }
        assert_eq!(bx.check_bitrate(2_109), Ok(()));
        assert_eq!(bx.check_bitrate(2_108), Err(TimingError::BitrateTooLow));
        assert_eq!(
            bx.check_bitrate(18_000_001),
            Err(TimingError::BitrateTooHigh)
        );
    }

    #[test]
    fn flexcan_extremes_follow_the_bus_clock() {
        // 16 MHz bus: 16 clocks per bit → 1 Mbit/s (16 quanta, prescaler 1).
        let r = flexcan_rules::rule(16_000_000, 16_000_000, 16, true);
        let f = r.fastest().unwrap();
        assert_eq!(
            (f.clocks_per_bit(), f.quanta(), f.actual_bitrate()),
            (16, 16, 1_000_000)
        );
        // 60 MHz bus: 8 quanta → 2 Mbit/s.
        let r = flexcan_rules::rule(16_000_000, 60_000_000, 16, true);
        assert_eq!(r.fastest().unwrap().quanta(), 8);
        assert_eq!(r.max_bitrate(), 2_000_000);
        // 24 MHz bus: 11 clocks (11 × 24 ≥ 16 × 16), 1,454,545 bit/s: a rate the 16 MHz
        // clock reaches, not 24 MHz / 16 = 1.5 Mbit/s.
        let r = flexcan_rules::rule(16_000_000, 24_000_000, 16, true);
        assert_eq!(r.max_bitrate(), 1_454_545);
        // A bus clock below the CAN clock accepts nothing.
        let r = flexcan_rules::rule(16_000_000, 8_000_000, 16, true);
        assert_eq!((r.fastest(), r.slowest(), r.max_bitrate()), (None, None, 0));
        assert_eq!(
            r.check_bitrate(125_000),
            Err(TimingError::ForbiddenByManual)
        );
    }

    #[test]
    fn a_timing_made_with_acan_ranges_is_judged_by_the_driver_rule() {
        let r = flexcan_rules::rule(16_000_000, 60_000_000, 16, true);
        let five = Timing::from_tsegs(16_000_000, 800_000, &Limits::FLEXCAN, 4, 2, 2);
        assert_eq!(five.quanta(), 5);
        assert_eq!(r.check_timing(&five), Err(TimingError::ForbiddenByManual));
        assert_eq!(
            r.manual_violation(&five),
            Some(ManualViolation::TooFewQuanta { quanta: 5, min: 8 })
        );
        let ok = Timing::from_tsegs(16_000_000, 800_000, &Limits::FLEXCAN, 1, 13, 6);
        assert_eq!(r.check_timing(&ok), Ok(()));
        let bx = Timing::from_tsegs(16_000_000, 800_000, &Limits::BXCAN, 1, 13, 6);
        assert_eq!(r.check_timing(&bx), Err(TimingError::WrongController));
        let other_clock = Timing {
            clock_hz: 8_000_000,
            ..ok
        };
        assert_eq!(r.check_timing(&other_clock), Err(TimingError::WrongClock));
    }

    #[test]
    fn timing_for_stays_among_accepted_timings() {
        // 16 MHz / 1,055 clocks (211 × 5 quanta) is 15,165.9 bit/s: with ACAN's ranges
        // the solver takes those 5 quanta; the driver's rule finds 1,056 clocks
        // (66 × 16) within the default tolerance instead.
        let r = flexcan_rules::rule(16_000_000, 16_000_000, 16, true);
        let t = r.timing_for(15_166, 875, 1_000).unwrap();
        assert!(t.quanta() >= 8, "{t:?}");
        assert_eq!(r.check_timing(&t), Ok(()));
        let acan = solve(16_000_000, 15_166, &Limits::FLEXCAN, 875).unwrap();
        assert_eq!(acan.quanta(), 5);
    }
}
