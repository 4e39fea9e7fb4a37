//! The bit timing solver: from a clock and a wished bit rate to a [`Timing`].
//!
//! # Objective
//!
//! Among every (prescaler, tseg1, tseg2) the [`Limits`] allow, [`solve`] picks
//! the one that is best by, in this order:
//!
//! 1. the smallest bit rate error `|clock / (prescaler × quanta) − bitrate|`,
//!    compared exactly (rationals, no rounding);
//! 2. the sample point `(1 + tseg1) / quanta` closest to the target, compared
//!    exactly (default target [`cia_sample_point`]);
//! 3. the larger number of quanta per bit;
//! 4. the smaller prescaler.
//!
//! For equal distances to the target in step 2, the earlier sample point (the
//! larger tseg2, hence the larger SJW and oscillator tolerance) wins. Then
//! tseg1 is split by [`Limits::split_tseg1`], SJW is the largest the limits and
//! phase segments allow ([`Limits::max_sjw`]) and triple sampling is off.
//!
//! Like ACAN §16.1, the solver only fails on impossible input; a result far
//! from the wished rate is returned and the caller checks it with
//! [`Timing::within_tolerance`] / [`Timing::validate`] (default tolerance
//! [`DEFAULT_TOLERANCE_PPM`]).

use super::error::TimingError;
use super::limits::Limits;
use super::segments::Timing;

/// ACAN's default acceptance distance from the wished bit rate: 1,000 ppm = 0.1 %
/// (ACAN §16.1).
pub const DEFAULT_TOLERANCE_PPM: u32 = 1_000;

/// The CiA recommended sample point for a bit rate, in per mille: 875 up to
/// 500 kbit/s, 800 up to 800 kbit/s, 750 above (CiA 301 / DS 102).
pub const fn cia_sample_point(bitrate: u32) -> u16 {
    if bitrate <= 500_000 {
        875
    } else if bitrate <= 800_000 {
        800
    } else {
        750
    }
}

/// One candidate (prescaler, quanta, tseg1, tseg2).
#[derive(Clone, Copy)]
struct Candidate {
    prescaler: u64,
    quanta: u64,
    tseg1: u64,
    tseg2: u64,
}

/// Whether `a` is strictly better than `b` under the objective of the module docs.
const fn better(a: &Candidate, b: &Candidate, clock: u64, bitrate: u64, target: u64) -> bool {
    // 1. bit rate error |clock/n − bitrate| = |clock − bitrate·n| / n, n = prescaler·quanta.
    let na = a.prescaler * a.quanta;
    let nb = b.prescaler * b.quanta;
    let ea = clock.abs_diff(bitrate * na) as u128 * nb as u128;
    let eb = clock.abs_diff(bitrate * nb) as u128 * na as u128;
    if ea != eb {
        return ea < eb;
    }
    // 2. sample point distance |(1+tseg1)/q − target/1000| = |1000(1+tseg1) − target·q| / (1000 q).
    let da = (1000 * (1 + a.tseg1)).abs_diff(target * a.quanta) * b.quanta;
    let db = (1000 * (1 + b.tseg1)).abs_diff(target * b.quanta) * a.quanta;
    if da != db {
        return da < db;
    }
    // 3. more quanta; 4. smaller prescaler.
    if a.quanta != b.quanta {
        return a.quanta > b.quanta;
    }
    a.prescaler < b.prescaler
}

/// For a bit of `quanta` quanta, the (tseg1, tseg2) whose sample point is closest
/// to `target` per mille; on a tie the smaller tseg1. `None` if no split fits.
pub(crate) const fn best_split(quanta: u64, limits: &Limits, target: u64) -> Option<(u64, u64)> {
    let t1 = limits.tseg1();
    let t2 = limits.tseg2();
    let segs = quanta - 1;
    // tseg1 range so that tseg2 = segs − tseg1 also fits.
    let mut lo = t1.min as u64;
    if segs > t2.max as u64 && segs - t2.max as u64 > lo {
        lo = segs - t2.max as u64;
    }
    if segs < t2.min as u64 {
        return None;
    }
    let mut hi = segs - t2.min as u64;
    if (t1.max as u64) < hi {
        hi = t1.max as u64;
    }
    if lo > hi {
        return None;
    }
    // Ideal 1 + tseg1 = target·q / 1000; try the two integers around it.
    let ideal = target * quanta / 1000;
    let mut a = ideal.saturating_sub(1);
    let mut b = ideal;
    if a < lo {
        a = lo;
    }
    if a > hi {
        a = hi;
    }
    if b < lo {
        b = lo;
    }
    if b > hi {
        b = hi;
    }
    let da = (1000 * (1 + a)).abs_diff(target * quanta);
    let db = (1000 * (1 + b)).abs_diff(target * quanta);
    let t = if db < da { b } else { a };
    Some((t, segs - t))
}

/// Checks the inputs shared by [`solve`] and the solution iterator.
pub(crate) const fn check_inputs(
    clock_hz: u32,
    bitrate: u32,
    limits: &Limits,
) -> Result<(), TimingError> {
    if clock_hz == 0 {
        Err(TimingError::ClockZero)
    } else if bitrate == 0 {
        Err(TimingError::BitrateZero)
    } else if !limits.is_valid() {
        Err(TimingError::InvalidLimits)
    } else {
        Ok(())
    }
}

/// Computes the bit timing for `bitrate` from a `clock_hz` CAN clock under
/// `limits`, aiming at a sample point of `sample_point_permille` (per mille, e.g.
/// [`cia_sample_point`]), by the objective of the [module docs](self).
///
/// Usable in `const` items. Errors: [`TimingError::ClockZero`],
/// [`TimingError::BitrateZero`], [`TimingError::SamplePointOutOfRange`] (target
/// not in 501..=999), [`TimingError::InvalidLimits`],
/// [`TimingError::BitrateTooHigh`] (bitrate > clock / minimum quanta). A wished
/// rate below the slowest possible one is not an error: as in ACAN §15.2.1
/// (1 bit/s), the closest timing is returned and fails
/// [`Timing::within_tolerance`].
///
/// ```
/// use twocan_core::timing::{solve, Limits, Timing, TimingError};
///
/// // bxCAN on a 54 MHz APB1, 500 kbit/s, 87.5 % asked: solved at compile time, and a
/// // `CAN_BTR` value as a constant.
/// const T: Timing = match solve(54_000_000, 500_000, &Limits::BXCAN, 875) {
///     Ok(t) => t,
///     Err(_) => panic!("no timing"),
/// };
/// assert!(T.is_exact());
/// assert_eq!((T.prescaler, T.quanta()), (6, 18));
/// assert_eq!(T.bxcan_btr(), Ok(0x011E_0005));
///
/// // Bad input is a typed error.
/// assert_eq!(solve(0, 500_000, &Limits::BXCAN, 875), Err(TimingError::ClockZero));
/// assert_eq!(solve(54_000_000, 500_000, &Limits::BXCAN, 500), Err(TimingError::SamplePointOutOfRange));
/// assert_eq!(solve(16_000_000, 4_000_000, &Limits::FLEXCAN, 750), Err(TimingError::BitrateTooHigh));
/// ```
pub const fn solve(
    clock_hz: u32,
    bitrate: u32,
    limits: &Limits,
    sample_point_permille: u16,
) -> Result<Timing, TimingError> {
    if let Err(e) = check_inputs(clock_hz, bitrate, limits) {
        return Err(e);
    }
    if sample_point_permille <= 500 || sample_point_permille >= 1000 {
        return Err(TimingError::SamplePointOutOfRange);
    }
    let clock = clock_hz as u64;
    let rate = bitrate as u64;
    let target = sample_point_permille as u64;
    let min_q = limits.min_quanta() as u64;
    let max_q = limits.max_quanta() as u64;
    if rate * min_q > clock {
        return Err(TimingError::BitrateTooHigh);
    }
    let p_min = limits.prescaler.min as u64;
    let p_max = limits.prescaler.max as u64;

    let mut best: Option<Candidate> = None;
    let mut q = min_q;
    while q <= max_q {
        if let Some((tseg1, tseg2)) = best_split(q, limits, target) {
            // For a fixed q the error is V-shaped in the prescaler: only the two
            // prescalers around clock / (bitrate·q) can be best.
            let below = clock / (rate * q);
            let mut i = 0;
            while i < 2 {
                let mut p = below + i;
                if p < p_min {
                    p = p_min;
                }
                if p > p_max {
                    p = p_max;
                }
                let c = Candidate {
                    prescaler: p,
                    quanta: q,
                    tseg1,
                    tseg2,
                };
                best = match best {
                    None => Some(c),
                    Some(b) => {
                        if better(&c, &b, clock, rate, target) {
                            Some(c)
                        } else {
                            Some(b)
                        }
                    }
                };
                i += 1;
            }
        }
        q += 1;
    }
    match best {
        // Cannot happen with valid limits (every q in min..=max has a split).
        None => Err(TimingError::InvalidLimits),
        Some(c) => Ok(Timing::from_tsegs(
            clock_hz,
            bitrate,
            limits,
            c.prescaler as u16,
            c.tseg1 as u8,
            c.tseg2 as u8,
        )),
    }
}

/// [`solve`] with the CiA sample point for the bit rate ([`cia_sample_point`]).
pub const fn solve_cia(
    clock_hz: u32,
    bitrate: u32,
    limits: &Limits,
) -> Result<Timing, TimingError> {
    solve(clock_hz, bitrate, limits, cia_sample_point(bitrate))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cia_defaults() {
        assert_eq!(cia_sample_point(125_000), 875);
        assert_eq!(cia_sample_point(500_000), 875);
        assert_eq!(cia_sample_point(500_001), 800);
        assert_eq!(cia_sample_point(800_000), 800);
        assert_eq!(cia_sample_point(800_001), 750);
        assert_eq!(cia_sample_point(1_000_000), 750);
    }

    #[test]
    fn best_split_prefers_closest_then_earlier() {
        // 16 quanta, target 875: 1 + 13 = 14/16 exactly.
        assert_eq!(best_split(16, &Limits::FLEXCAN, 875), Some((13, 2)));
        // 5 quanta FlexCAN: only 2 + 2.
        assert_eq!(best_split(5, &Limits::FLEXCAN, 750), Some((2, 2)));
        // 4 quanta FlexCAN: impossible.
        assert_eq!(best_split(4, &Limits::FLEXCAN, 750), None);
        // 10 quanta, target 750: 7/10 and 8/10 are equally far: earlier wins.
        assert_eq!(best_split(10, &Limits::BXCAN, 750), Some((6, 3)));
    }
}
