//! Bit-timing quality: `twocan_core::timing::solve` against an exhaustive search under
//! the objective documented in `docs/bit-timing.md` and `can-core/src/timing/solver.rs`.
//!
//! The exhaustive search here is written from that documentation alone: every
//! (prescaler, tseg1, tseg2) the limits allow, ranked by
//!
//! 1. the bit rate error `|clock / (prescaler × quanta) − bitrate|` (exact rationals);
//! 2. the distance of the sample point `(1 + tseg1) / quanta` to the target (exact);
//! 3. more quanta; 4. smaller prescaler; 5. on an equal distance, the earlier sample
//!    point (smaller tseg1).

use std::cmp::Ordering;
use std::time::Instant;

use twocan_core::timing::{cia_sample_point, solve, Limits, Timing, DEFAULT_TOLERANCE_PPM};

/// CAN clocks of the grid, in MHz.
pub const CLOCKS_MHZ: [u32; 11] = [8, 16, 24, 36, 42, 45, 48, 50, 54, 72, 80];
/// Bit rates of the grid: the usual ones, then a few odd ones.
pub const BITRATES: [u32; 17] = [
    10_000, 20_000, 33_333, 50_000, 83_333, 100_000, 125_000, 250_000, 500_000, 800_000,
    1_000_000, // usual
    5_000, 31_250, 47_619, 440_000, 842_000, 900_000, // odd
];
/// How many of [`BITRATES`] are the usual ones.
pub const USUAL_BITRATES: usize = 11;

/// A candidate (prescaler, tseg1, tseg2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pick {
    /// Prescaler.
    pub prescaler: u64,
    /// Sync segment excluded: propagation + phase 1.
    pub tseg1: u64,
    /// Phase 2.
    pub tseg2: u64,
}

impl Pick {
    fn quanta(self) -> u64 {
        1 + self.tseg1 + self.tseg2
    }
}

/// `a` against `b` under the documented objective: `Less` when `a` is better.
fn rank(a: Pick, b: Pick, clock: u64, rate: u64, target: u64) -> Ordering {
    let (qa, qb) = (a.quanta() as u128, b.quanta() as u128);
    let (na, nb) = (a.prescaler as u128 * qa, b.prescaler as u128 * qb);
    let (clock, rate, target) = (clock as u128, rate as u128, target as u128);
    // error_a = |clock − rate·na| / na, compared by cross-multiplication.
    let ea = clock.abs_diff(rate * na) * nb;
    let eb = clock.abs_diff(rate * nb) * na;
    // distance_a = |1000(1 + tseg1_a) − target·qa| / (1000 qa).
    let da = (1000 * (1 + a.tseg1 as u128)).abs_diff(target * qa) * qb;
    let db = (1000 * (1 + b.tseg1 as u128)).abs_diff(target * qb) * qa;
    ea.cmp(&eb)
        .then(da.cmp(&db))
        .then(qb.cmp(&qa))
        .then(a.prescaler.cmp(&b.prescaler))
        .then(a.tseg1.cmp(&b.tseg1))
}

/// The best pick over every allowed (prescaler, tseg1, tseg2), `None` if none exists.
pub fn exhaustive(clock: u32, rate: u32, limits: &Limits, target: u16) -> Option<Pick> {
    let t1 = limits.tseg1();
    let t2 = limits.tseg2();
    let mut best: Option<Pick> = None;
    for prescaler in limits.prescaler.min as u64..=limits.prescaler.max as u64 {
        for tseg1 in t1.min as u64..=t1.max as u64 {
            for tseg2 in t2.min as u64..=t2.max as u64 {
                let c = Pick {
                    prescaler,
                    tseg1,
                    tseg2,
                };
                let better = match best {
                    None => true,
                    Some(b) => {
                        rank(c, b, clock as u64, rate as u64, target as u64) == Ordering::Less
                    }
                };
                if better {
                    best = Some(c);
                }
            }
        }
    }
    best
}

/// One grid point.
#[derive(Debug, Clone)]
pub struct Case {
    /// CAN clock, Hz.
    pub clock: u32,
    /// Wished bit rate.
    pub bitrate: u32,
    /// The solver's timing (`None`: it returned an error).
    pub solved: Option<Timing>,
    /// The exhaustive search's pick.
    pub best: Option<Pick>,
}

impl Case {
    /// The solver chose what the exhaustive search chose (or both found nothing).
    pub fn matches(&self) -> bool {
        match (&self.solved, self.best) {
            (Some(t), Some(b)) => {
                t.prescaler as u64 == b.prescaler
                    && t.tseg1() as u64 == b.tseg1
                    && t.tseg2() as u64 == b.tseg2
            }
            (None, None) => true,
            _ => false,
        }
    }

    /// Within the default tolerance (the backends accept it).
    pub fn accepted(&self) -> bool {
        self.solved
            .as_ref()
            .is_some_and(|t| t.within_tolerance(DEFAULT_TOLERANCE_PPM))
    }

    /// `ppm_from_wished` of the solver's timing.
    pub fn ppm(&self) -> Option<u64> {
        self.solved.as_ref().map(|t| t.ppm_from_wished())
    }

    /// Exact distance of the sample point to the CiA target, per mille.
    pub fn sample_point_error(&self) -> Option<f64> {
        self.solved.as_ref().map(|t| {
            let exact = 1000.0 * (1 + t.tseg1()) as f64 / t.quanta() as f64;
            (exact - cia_sample_point(self.bitrate) as f64).abs()
        })
    }
}

/// The results for one controller.
#[derive(Debug, Clone)]
pub struct ControllerQuality {
    /// `FlexCAN` or `bxCAN`.
    pub name: &'static str,
    /// Every grid point.
    pub cases: Vec<Case>,
    /// Host time of the exhaustive searches, seconds.
    pub exhaustive_secs: f64,
    /// Host time of the solver over the whole grid, seconds.
    pub solver_secs: f64,
}

impl ControllerQuality {
    /// Grid points where solver and exhaustive search agree.
    pub fn matching(&self) -> usize {
        self.cases.iter().filter(|c| c.matches()).count()
    }

    /// Grid points within the default tolerance.
    pub fn accepted(&self) -> usize {
        self.cases.iter().filter(|c| c.accepted()).count()
    }

    /// The case with the largest ppm, over `cases` filtered by `keep`.
    pub fn worst_ppm(&self, keep: impl Fn(&Case) -> bool) -> Option<&Case> {
        self.cases
            .iter()
            .filter(|c| keep(c) && c.solved.is_some())
            .max_by_key(|c| c.ppm().unwrap_or(0))
    }

    /// The case with the largest sample point error, over `cases` filtered by `keep`.
    pub fn worst_sample_point(&self, keep: impl Fn(&Case) -> bool) -> Option<&Case> {
        self.cases
            .iter()
            .filter(|c| keep(c) && c.solved.is_some())
            .max_by(|a, b| {
                let (x, y) = (
                    a.sample_point_error().unwrap_or(0.0),
                    b.sample_point_error().unwrap_or(0.0),
                );
                x.total_cmp(&y)
            })
    }
}

/// Runs the grid for one controller.
pub fn run(name: &'static str, limits: &Limits) -> ControllerQuality {
    let start = Instant::now();
    let mut solved = Vec::new();
    for &mhz in &CLOCKS_MHZ {
        for &rate in &BITRATES {
            let clock = mhz * 1_000_000;
            solved.push((
                clock,
                rate,
                solve(clock, rate, limits, cia_sample_point(rate)).ok(),
            ));
        }
    }
    let solver_secs = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let cases = solved
        .into_iter()
        .map(|(clock, bitrate, solved)| Case {
            clock,
            bitrate,
            solved,
            best: exhaustive(clock, bitrate, limits, cia_sample_point(bitrate)),
        })
        .collect();
    ControllerQuality {
        name,
        cases,
        exhaustive_secs: start.elapsed().as_secs_f64(),
        solver_secs,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pick(clock: u32, rate: u32, limits: &Limits) -> (u64, u64, u64) {
        let p = exhaustive(clock, rate, limits, cia_sample_point(rate)).unwrap();
        (p.prescaler, p.tseg1, p.tseg2)
    }

    #[test]
    fn exhaustive_search_gives_the_documented_examples() {
        // docs/bit-timing.md, bxCAN table: 54 MHz / 500 kbit/s → prescaler 6, 18 quanta
        // (TS1 15, TS2 2); 45 MHz / 1 Mbit/s → 3, 10 + 4; 54 MHz / 1 Mbit/s → 3, 12 + 5.
        assert_eq!(pick(54_000_000, 500_000, &Limits::BXCAN), (6, 15, 2));
        assert_eq!(pick(45_000_000, 1_000_000, &Limits::BXCAN), (3, 10, 4));
        assert_eq!(pick(54_000_000, 1_000_000, &Limits::BXCAN), (3, 12, 5));
        // FlexCAN at 16 MHz: 1 Mbit/s → 1 × 16 quanta, tseg1 11, tseg2 4; 842 kbit/s →
        // prescaler 1, 19 quanta.
        assert_eq!(pick(16_000_000, 1_000_000, &Limits::FLEXCAN), (1, 11, 4));
        let (p, t1, t2) = pick(16_000_000, 842_000, &Limits::FLEXCAN);
        assert_eq!((p, 1 + t1 + t2), (1, 19));
    }

    #[test]
    fn ranking_follows_the_objective_order() {
        let a = Pick {
            prescaler: 1,
            tseg1: 13,
            tseg2: 2,
        }; // 16 quanta, 875 ‰
        let b = Pick {
            prescaler: 2,
            tseg1: 6,
            tseg2: 1,
        }; // 8 quanta, 875 ‰
           // Same error (both exact at 16 MHz / 1 Mbit/s... here 16 MHz / 1 MHz = 16 clocks),
           // same sample point: more quanta wins.
        assert_eq!(rank(a, b, 16_000_000, 1_000_000, 875), Ordering::Less);
        // A smaller error beats everything else.
        let c = Pick {
            prescaler: 1,
            tseg1: 12,
            tseg2: 2,
        }; // 15 quanta: not exact
        assert_eq!(rank(a, c, 16_000_000, 1_000_000, 875), Ordering::Less);
    }

    #[test]
    fn a_case_matches_when_both_agree() {
        let limits = Limits::BXCAN;
        let clock = 54_000_000;
        let rate = 500_000;
        let case = Case {
            clock,
            bitrate: rate,
            solved: solve(clock, rate, &limits, cia_sample_point(rate)).ok(),
            best: exhaustive(clock, rate, &limits, cia_sample_point(rate)),
        };
        assert!(case.matches() && case.accepted());
        assert_eq!(case.ppm(), Some(0));
    }
}
