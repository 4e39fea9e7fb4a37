//! Bit timing: ACAN facts, brute-force comparison, errors, property tests.

use proptest::prelude::*;
use twocan_core::timing::{
    cia_sample_point, flexcan_rules, solve, solve_cia, Bounds, Consistency, Controller, Limits,
    Solutions, Timing, TimingError, TimingRule, DEFAULT_TOLERANCE_PPM,
};

const MHZ: u32 = 1_000_000;
const ACAN_CLOCK: u32 = 16 * MHZ;

fn flexcan(bitrate: u32) -> Timing {
    solve_cia(ACAN_CLOCK, bitrate, &Limits::FLEXCAN).unwrap()
}

// ---------------------------------------------------------------- compile time

const T842: Timing = match solve(
    ACAN_CLOCK,
    842_000,
    &Limits::FLEXCAN,
    cia_sample_point(842_000),
) {
    Ok(t) => t,
    Err(_) => panic!("no timing"),
};
const BTR_54M_500K: u32 = match solve_cia(54 * MHZ, 500_000, &Limits::BXCAN) {
    Ok(t) => match t.bxcan_btr() {
        Ok(v) => v,
        Err(_) => panic!("not encodable"),
    },
    Err(_) => panic!("no timing"),
};
const OK_AT_DEFAULT: bool = T842.within_tolerance(DEFAULT_TOLERANCE_PPM);

#[test]
fn const_items_computed_at_compile_time() {
    assert_eq!(T842.actual_bitrate(), 842_105);
    assert_eq!(BTR_54M_500K, 0x011E_0005);
    const { assert!(OK_AT_DEFAULT) };
}

// ---------------------------------------------------------------- ACAN facts (§16.1)

#[test]
fn acan_classic_rates_are_exact() {
    for rate in [1_000_000, 500_000, 250_000, 125_000] {
        let t = flexcan(rate);
        assert!(t.is_exact(), "{rate}");
        assert_eq!(t.actual_bitrate(), rate);
        assert_eq!(t.ppm_from_wished(), 0);
        assert!(t.within_tolerance(0));
        assert!(t.consistency().is_ok());
    }
}

#[test]
fn acan_842k() {
    let t = flexcan(842_000);
    assert_eq!(t.actual_bitrate(), 842_105);
    assert_eq!(t.ppm_from_wished(), 124);
    assert!(!t.is_exact());
    assert!(t.within_tolerance(DEFAULT_TOLERANCE_PPM));
    assert!(t.validate(DEFAULT_TOLERANCE_PPM).is_ok());
    // ACAN §16.1 second example: max distance 100 ppm -> refused.
    assert!(!t.within_tolerance(100));
    assert!(t.within_tolerance(124));
    // 0 ppm means exact: 842 kbit/s refused.
    assert!(!t.within_tolerance(0));
    assert_eq!(t.validate(0), Err(TimingError::TooFarFromWishedBitrate));
    assert_eq!((t.prescaler, t.quanta()), (1, 19));
}

#[test]
fn acan_440k_is_outside_default_tolerance() {
    let t = flexcan(440_000);
    assert_eq!(t.actual_bitrate(), 444_444);
    assert_eq!(t.ppm_from_wished(), 10_100);
    assert_eq!(t.prescaler, 2); // ACAN: BRP = 2
    assert_eq!(t.quanta(), 18);
    assert!(!t.within_tolerance(DEFAULT_TOLERANCE_PPM));
    assert_eq!(
        t.validate(DEFAULT_TOLERANCE_PPM),
        Err(TimingError::TooFarFromWishedBitrate)
    );
    // "always consistent" (ACAN §16.1)
    assert!(t.consistency().is_ok());
}

#[test]
fn acan_500k_with_zero_tolerance() {
    let t = flexcan(500_000);
    assert!(t.within_tolerance(0));
    assert_eq!(t.validate(0), Ok(t));
}

#[test]
fn acan_fastest_exact_is_3_2_mbit() {
    let t = flexcan(3_200_000);
    assert!(t.is_exact());
    assert_eq!(
        (t.prescaler, t.prop_seg, t.phase_seg1, t.phase_seg2),
        (1, 1, 1, 2)
    );
    assert_eq!(t.quanta(), 5);
    assert!(t.consistency().is_ok());
    assert_eq!(
        solve_cia(ACAN_CLOCK, 3_200_001, &Limits::FLEXCAN),
        Err(TimingError::BitrateTooHigh)
    );
    // Nothing faster is exact: an exact rate is 16 MHz / (prescaler × quanta), and
    // quanta ≥ 5; the one exact 3.2 Mbit/s timing is 1 × 5.
    assert_eq!(
        Solutions::new(ACAN_CLOCK, 3_200_000, &Limits::FLEXCAN, 0)
            .unwrap()
            .count(),
        1
    );
    for n in 1..5 {
        assert_eq!(
            Solutions::new(ACAN_CLOCK, ACAN_CLOCK / n, &Limits::FLEXCAN, 0)
                .unwrap()
                .count(),
            0
        );
        assert_eq!(
            solve_cia(ACAN_CLOCK, ACAN_CLOCK / n, &Limits::FLEXCAN),
            Err(TimingError::BitrateTooHigh)
        );
    }
}

#[test]
fn acan_slowest_exact_is_2_5_kbit() {
    let t = flexcan(2_500);
    assert!(t.is_exact());
    assert_eq!((t.prescaler, t.quanta()), (256, 25));
    for rate in 1..2_500 {
        let t = flexcan(rate);
        assert!(!t.is_exact(), "{rate}");
        assert_eq!(t.actual_bitrate(), 2_500, "{rate}");
    }
    assert_eq!(
        Solutions::new(ACAN_CLOCK, 2_499, &Limits::FLEXCAN, 0)
            .unwrap()
            .count(),
        0
    );
}

#[test]
fn acan_1_bit_per_second_is_too_far() {
    // ACAN §15.2.1: a result exists but begin() reports "too far from wished rate".
    let t = flexcan(1);
    assert_eq!(t.actual_bitrate(), 2_500);
    assert!(t.consistency().is_ok());
    assert!(!t.within_tolerance(DEFAULT_TOLERANCE_PPM));
    assert_eq!(
        t.validate(DEFAULT_TOLERANCE_PPM),
        Err(TimingError::TooFarFromWishedBitrate)
    );
}

#[test]
fn acan_segment_examples_reproduced_with_their_sample_point() {
    // With ACAN's own sample point (≈ 68.75 % / 66.7 %) the solver and the documented
    // split give exactly ACAN's decompositions.
    let t = solve(ACAN_CLOCK, 500_000, &Limits::FLEXCAN, 688).unwrap();
    assert_eq!(
        (t.prescaler, t.prop_seg, t.phase_seg1, t.phase_seg2, t.sjw),
        (2, 5, 5, 5, 4)
    );
    assert_eq!(t.sample_point() / 10, 68); // §16.6: 68 %
                                           // Table 7 defaults (250 kbit/s): BRP 4, PropSeg 5, PS1 5, PS2 5, RJW 4, single sampling.
    let t = solve(ACAN_CLOCK, 250_000, &Limits::FLEXCAN, 688).unwrap();
    assert_eq!(
        (
            t.prescaler,
            t.prop_seg,
            t.phase_seg1,
            t.phase_seg2,
            t.sjw,
            t.triple_sampling
        ),
        (4, 5, 5, 5, 4, false)
    );
    // §16.1 440 kbit/s: BRP 2, PropSeg 6, PS1 5, PS2 6, RJW 4.
    let t = solve(ACAN_CLOCK, 440_000, &Limits::FLEXCAN, 667).unwrap();
    assert_eq!(
        (t.prescaler, t.prop_seg, t.phase_seg1, t.phase_seg2, t.sjw),
        (2, 6, 5, 6, 4)
    );
    // 12/18 = 66.6 %: the manual prints 68 for this example (see docs/bit-timing.md).
    assert_eq!(t.sample_point(), 666);
}

#[test]
fn cia_defaults_at_16mhz() {
    let t = flexcan(500_000);
    assert_eq!(t.sample_point(), 875);
    assert_eq!(
        (t.prescaler, t.prop_seg, t.phase_seg1, t.phase_seg2, t.sjw),
        (2, 7, 6, 2, 2)
    );
    let t = flexcan(1_000_000);
    assert_eq!(t.sample_point(), 750);
}

#[test]
fn bxcan_worked_examples() {
    let t = solve_cia(54 * MHZ, 500_000, &Limits::BXCAN).unwrap();
    assert_eq!((t.prescaler, t.tseg1(), t.tseg2(), t.sjw), (6, 15, 2, 2));
    assert!(t.is_exact());
    assert_eq!(t.sample_point(), 888);
    assert_eq!(t.bxcan_btr(), Ok(0x011E_0005));
    let t = solve_cia(45 * MHZ, 1_000_000, &Limits::BXCAN).unwrap();
    assert_eq!((t.prescaler, t.tseg1(), t.tseg2(), t.sjw), (3, 10, 4, 4));
    assert!(t.is_exact());
    assert_eq!(t.sample_point(), 733);
    assert_eq!(t.bxcan_btr(), Ok(0x0339_0002));
}

// ---------------------------------------------------------------- errors

#[test]
fn every_error_variant_is_reachable() {
    let l = Limits::FLEXCAN;
    assert_eq!(solve(0, 500_000, &l, 875), Err(TimingError::ClockZero));
    assert_eq!(solve(ACAN_CLOCK, 0, &l, 875), Err(TimingError::BitrateZero));
    assert_eq!(
        solve(ACAN_CLOCK, 4_000_000, &l, 875),
        Err(TimingError::BitrateTooHigh)
    );
    assert_eq!(solve(ACAN_CLOCK, 10, &l, 875), Ok(flexcan(10)));
    assert_eq!(
        solve(8_000_000, 16_000_000, &l, 875),
        Err(TimingError::BitrateTooHigh)
    );
    for sp in [0, 500, 1000, 1001, u16::MAX] {
        assert_eq!(
            solve(ACAN_CLOCK, 500_000, &l, sp),
            Err(TimingError::SamplePointOutOfRange)
        );
    }
    assert!(solve(ACAN_CLOCK, 500_000, &l, 501).is_ok());
    assert!(solve(ACAN_CLOCK, 500_000, &l, 999).is_ok());
    let mut bad = l;
    bad.prescaler = Bounds::new(0, 256);
    assert_eq!(
        solve(ACAN_CLOCK, 500_000, &bad, 875),
        Err(TimingError::InvalidLimits)
    );
    assert_eq!(
        Solutions::new(ACAN_CLOCK, 500_000, &bad, 0).err(),
        Some(TimingError::InvalidLimits)
    );
    assert_eq!(
        flexcan(440_000).validate(DEFAULT_TOLERANCE_PPM),
        Err(TimingError::TooFarFromWishedBitrate)
    );
    let mut t = flexcan(500_000);
    t.sjw = 5;
    assert_eq!(
        t.validate(DEFAULT_TOLERANCE_PPM),
        Err(TimingError::Inconsistent(
            Consistency::SJW_TOO_LARGE | Consistency::SJW_ABOVE_PHASE_SEG2
        ))
    );
    assert_eq!(
        flexcan(500_000).bxcan_btr(),
        Err(TimingError::WrongController)
    );
    // Messages exist for all of them.
    for e in [
        TimingError::ClockZero,
        TimingError::BitrateZero,
        TimingError::BitrateTooHigh,
        TimingError::SamplePointOutOfRange,
        TimingError::InvalidLimits,
        TimingError::TooFarFromWishedBitrate,
        TimingError::Inconsistent(Consistency::PRESCALER_TOO_SMALL),
        TimingError::WrongController,
    ] {
        assert!(!e.to_string().is_empty());
    }
}

// ---------------------------------------------------------------- brute force

/// A (prescaler, tseg1, tseg2) choice.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Pick {
    p: u64,
    t1: u64,
    t2: u64,
}

/// `a` strictly before `b` under the documented objective, written out plainly:
/// smaller |clock/(p·q) − rate|, then |(1+t1)/q − target/1000| smaller, then more
/// quanta, then smaller prescaler, then smaller tseg1.
fn before(a: Pick, b: Pick, clock: u64, rate: u64, target: u64) -> bool {
    let qa = 1 + a.t1 + a.t2;
    let qb = 1 + b.t1 + b.t2;
    let (na, nb) = (a.p * qa, b.p * qb);
    // error_a = |clock − rate·na| / na ; compare by cross-multiplying.
    let err_a = (clock as i128 - (rate * na) as i128).unsigned_abs() * nb as u128;
    let err_b = (clock as i128 - (rate * nb) as i128).unsigned_abs() * na as u128;
    if err_a != err_b {
        return err_a < err_b;
    }
    let sp_a = ((1000 * (1 + a.t1)) as i128 - (target * qa) as i128).unsigned_abs() * qb as u128;
    let sp_b = ((1000 * (1 + b.t1)) as i128 - (target * qb) as i128).unsigned_abs() * qa as u128;
    if sp_a != sp_b {
        return sp_a < sp_b;
    }
    if qa != qb {
        return qa > qb;
    }
    if a.p != b.p {
        return a.p < b.p;
    }
    a.t1 < b.t1
}

fn brute_force(clock: u32, rate: u32, l: &Limits, target: u16) -> Pick {
    let t1_min = (l.prop_seg.min + l.phase_seg1.min) as u64;
    let t1_max = (l.prop_seg.max + l.phase_seg1.max) as u64;
    let mut best: Option<Pick> = None;
    for p in l.prescaler.min as u64..=l.prescaler.max as u64 {
        for t1 in t1_min..=t1_max {
            for t2 in l.phase_seg2.min as u64..=l.phase_seg2.max as u64 {
                let c = Pick { p, t1, t2 };
                if best.is_none_or(|b| before(c, b, clock as u64, rate as u64, target as u64)) {
                    best = Some(c);
                }
            }
        }
    }
    best.unwrap()
}

/// Largest SJW over every way of splitting tseg1 into (prop, phase 1).
fn best_sjw(l: &Limits, t1: u64, t2: u64) -> u64 {
    let mut best = 0;
    for prop in l.prop_seg.min as u64..=l.prop_seg.max as u64 {
        let Some(ps1) = t1.checked_sub(prop) else {
            continue;
        };
        if !(l.phase_seg1.min as u64..=l.phase_seg1.max as u64).contains(&ps1) {
            continue;
        }
        let mut sjw = (l.sjw.max as u64).min(t2);
        if l.sjw_le_phase_seg1 {
            sjw = sjw.min(ps1);
        }
        best = best.max(sjw);
    }
    best
}

#[test]
fn solver_matches_brute_force_on_grid() {
    let clocks = [8, 16, 24, 36, 42, 45, 48, 50, 54, 72, 80].map(|m| m * MHZ);
    let rates = [
        10_000, 20_000, 33_333, 50_000, 83_333, 100_000, 125_000, 250_000, 500_000, 800_000,
        1_000_000, // classic
        1_234, 12_345, 47_619, 440_000, 615_384, 842_000, 2_000_000, // odd
    ];
    let mut compared = 0;
    for limits in [Limits::FLEXCAN, Limits::BXCAN] {
        for clock in clocks {
            for rate in rates {
                for target in [cia_sample_point(rate), 700] {
                    let got = solve(clock, rate, &limits, target);
                    if rate as u64 * limits.min_quanta() as u64 > clock as u64 {
                        assert_eq!(got, Err(TimingError::BitrateTooHigh));
                        continue;
                    }
                    let t = got.unwrap();
                    let want = brute_force(clock, rate, &limits, target);
                    let ctx = format!("{:?} {clock} {rate} {target}", limits.controller);
                    assert_eq!(
                        (t.prescaler as u64, t.tseg1() as u64, t.tseg2() as u64),
                        (want.p, want.t1, want.t2),
                        "{ctx}"
                    );
                    assert_eq!(t.sjw as u64, best_sjw(&limits, want.t1, want.t2), "{ctx}");
                    assert!(t.consistency().is_ok(), "{ctx}");
                    assert!(!t.triple_sampling);
                    match limits.controller {
                        Controller::FlexCan => assert!(t.flexcan_ctrl1().is_ok()),
                        Controller::BxCan => assert!(t.bxcan_btr().is_ok()),
                    }
                    compared += 1;
                }
            }
        }
    }
    assert!(compared > 700, "{compared}");
}

#[test]
fn split_rule_is_acan_halving_unless_sjw_needs_more() {
    let l = Limits::FLEXCAN;
    for t1 in 2..=16u8 {
        for t2 in 2..=8u8 {
            let t = Timing::from_tsegs(ACAN_CLOCK, 500_000, &l, 1, t1, t2);
            let half = t1 / 2;
            let wanted = t2.min(4);
            let expect_ps1 = half
                .max(wanted)
                .min(t1 - 1)
                .min(8)
                .max(t1.saturating_sub(8));
            assert_eq!(t.phase_seg1, expect_ps1, "{t1} {t2}");
            assert_eq!(t.prop_seg + t.phase_seg1, t1);
            assert!(t.consistency().is_ok(), "{t1} {t2}");
        }
    }
}

// ---------------------------------------------------------------- iterator

/// Count of (p, t1, t2) within tolerance, counted plainly.
fn brute_count(clock: u32, rate: u32, l: &Limits, tol: u32) -> usize {
    let mut n = 0;
    for p in l.prescaler.min..=l.prescaler.max {
        for t1 in l.prop_seg.min + l.phase_seg1.min..=l.prop_seg.max + l.phase_seg1.max {
            for t2 in l.phase_seg2.min..=l.phase_seg2.max {
                let q = 1 + t1 as u64 + t2 as u64;
                let actual = clock as u64 / (p as u64 * q);
                let exact = actual * p as u64 * q == clock as u64 && actual == rate as u64;
                let ppm = actual.abs_diff(rate as u64) * 1_000_000 / rate as u64;
                if if tol == 0 { exact } else { ppm <= tol as u64 } {
                    n += 1;
                }
            }
        }
    }
    n
}

#[test]
fn solutions_iterator() {
    let all: Vec<Timing> = Solutions::new(ACAN_CLOCK, 500_000, &Limits::FLEXCAN, 0)
        .unwrap()
        .collect();
    assert_eq!(all.len(), 11);
    assert!(all.iter().all(|t| t.is_exact() && t.consistency().is_ok()));
    assert!(all.contains(&flexcan(500_000)));

    for (l, clock, rate, tol) in [
        (Limits::FLEXCAN, ACAN_CLOCK, 842_000, 1_000),
        (Limits::FLEXCAN, ACAN_CLOCK, 125_000, 0),
        (Limits::BXCAN, 54 * MHZ, 500_000, 0),
        (Limits::BXCAN, 42 * MHZ, 83_333, 5_000),
        (Limits::BXCAN, 45 * MHZ, 1_000_000, 1_000),
    ] {
        let sols: Vec<Timing> = Solutions::new(clock, rate, &l, tol).unwrap().collect();
        assert_eq!(
            sols.len(),
            brute_count(clock, rate, &l, tol),
            "{clock} {rate}"
        );
        assert!(sols
            .iter()
            .all(|t| t.within_tolerance(tol) && t.consistency().is_ok()));
        // No duplicates.
        for (i, a) in sols.iter().enumerate() {
            assert!(!sols[i + 1..].contains(a));
        }
        // The solver's choice is among them and best by the objective.
        let chosen = solve_cia(clock, rate, &l).unwrap();
        assert!(sols.contains(&chosen), "{clock} {rate}");
    }
    assert_eq!(
        Solutions::new(0, 1, &Limits::BXCAN, 0).err(),
        Some(TimingError::ClockZero)
    );
    assert_eq!(
        Solutions::new(1, 0, &Limits::BXCAN, 0).err(),
        Some(TimingError::BitrateZero)
    );
}

// ---------------------------------------------------------------- properties

fn edge_u32() -> impl Strategy<Value = u32> {
    prop_oneof![
        Just(0u32),
        Just(1u32),
        Just(u32::MAX),
        Just(u32::MAX - 1),
        1u32..200_000_000,
        any::<u32>(),
    ]
}

fn any_limits() -> impl Strategy<Value = Limits> {
    let b = || (any::<u16>(), any::<u16>()).prop_map(|(a, b)| Bounds::new(a % 300, b % 300));
    prop_oneof![
        Just(Limits::FLEXCAN),
        Just(Limits::BXCAN),
        (
            b(),
            b(),
            b(),
            b(),
            b(),
            any::<bool>(),
            proptest::option::of(any::<u8>()),
            b()
        )
            .prop_map(|(p, prop, ps1, ps2, sjw, le, triple, quanta)| Limits {
                controller: Controller::FlexCan,
                prescaler: Bounds::new(p.min, p.max % 2000),
                prop_seg: prop,
                phase_seg1: ps1,
                phase_seg2: ps2,
                sjw,
                triple_sampling_min_phase_seg1: triple,
                sjw_le_phase_seg1: le,
                quanta,
            }),
    ]
}

proptest! {
    #[test]
    fn solve_never_panics(clock in edge_u32(), rate in edge_u32(), sp in any::<u16>(), limits in any_limits()) {
        match solve(clock, rate, &limits, sp) {
            Ok(t) => {
                prop_assert!(clock > 0 && rate > 0 && sp > 500 && sp < 1000 && limits.is_valid());
                prop_assert!(rate as u64 * limits.min_quanta() as u64 <= clock as u64);
                prop_assert!(t.consistency().is_ok());
                prop_assert_eq!(t.prescaler as u64 * t.quanta() as u64 * t.actual_bitrate() as u64 <= clock as u64, true);
                let _ = t.ppm_from_wished();
                let _ = t.oscillator_tolerance_ppm();
                let _ = t.sample_point();
            }
            Err(TimingError::ClockZero) => prop_assert_eq!(clock, 0),
            Err(TimingError::BitrateZero) => prop_assert_eq!(rate, 0),
            Err(TimingError::InvalidLimits) => prop_assert!(!limits.is_valid()),
            Err(TimingError::SamplePointOutOfRange) => prop_assert!(sp <= 500 || sp >= 1000),
            Err(TimingError::BitrateTooHigh) => {
                prop_assert!(rate as u64 * limits.min_quanta() as u64 > clock as u64)
            }
            Err(e) => prop_assert!(false, "unexpected {:?}", e),
        }
    }

    #[test]
    fn solve_builtin_limits_never_panics(clock in edge_u32(), rate in edge_u32(), sp in 400u16..1100, bx in any::<bool>()) {
        let limits = if bx { Limits::BXCAN } else { Limits::FLEXCAN };
        if let Ok(t) = solve(clock, rate, &limits, sp) {
            prop_assert!(t.consistency().is_ok());
            let enc = if bx { t.bxcan_btr() } else { t.flexcan_ctrl1() };
            prop_assert!(enc.is_ok());
            if t.is_exact() {
                prop_assert!(t.within_tolerance(0));
            }
        }
    }

    #[test]
    fn timing_methods_never_panic(
        clock in edge_u32(), rate in edge_u32(), p in any::<u16>(), prop in any::<u8>(),
        ps1 in any::<u8>(), ps2 in any::<u8>(), sjw in any::<u8>(), triple in any::<bool>(),
        tol in edge_u32(), bx in any::<bool>(),
    ) {
        let t = Timing {
            clock_hz: clock, bitrate: rate,
            limits: if bx { Limits::BXCAN } else { Limits::FLEXCAN },
            prescaler: p, prop_seg: prop, phase_seg1: ps1, phase_seg2: ps2, sjw, triple_sampling: triple,
        };
        let _ = (t.actual_bitrate(), t.is_exact(), t.ppm_from_wished(), t.sample_point(),
                 t.first_sample_point(), t.oscillator_tolerance_ppm(), t.within_tolerance(tol),
                 t.consistency(), t.validate(tol), t.bxcan_btr(), t.flexcan_ctrl1());
    }

    #[test]
    fn solutions_never_panic(clock in edge_u32(), rate in edge_u32(), tol in edge_u32(), bx in any::<bool>()) {
        let limits = if bx { Limits::BXCAN } else { Limits::FLEXCAN };
        match Solutions::new(clock, rate, &limits, tol) {
            Ok(sols) => {
                for t in sols.take(64) {
                    prop_assert!(t.within_tolerance(tol));
                    prop_assert!(t.consistency().is_ok());
                }
            }
            Err(e) => prop_assert!(clock == 0 || rate == 0, "{:?}", e),
        }
    }

    #[test]
    fn register_round_trips(btr in any::<u32>(), ctrl1 in any::<u32>()) {
        let b = Timing::from_bxcan_btr(54 * MHZ, 500_000, btr);
        if let Ok(v) = b.bxcan_btr() {
            prop_assert_eq!(v, btr & twocan_core::timing::BXCAN_BTR_TIMING_MASK);
        } else {
            prop_assert!(b.sjw > b.phase_seg2);
        }
        let f = Timing::from_flexcan_ctrl1(ACAN_CLOCK, 500_000, ctrl1);
        if let Ok(v) = f.flexcan_ctrl1() {
            prop_assert_eq!(v, ctrl1 & twocan_core::timing::FLEXCAN_CTRL1_TIMING_MASK);
        } else {
            prop_assert!(!f.consistency().is_ok());
        }
    }
}

/// A driver's rule: one of the three built-in limits from a clock, FlexCAN's with a
/// peripheral clock (below the CAN clock now and then: nothing accepted then).
fn any_rule() -> impl Strategy<Value = TimingRule> {
    (
        1_000_000u32..100_000_000,
        0u8..3,
        proptest::option::of(8_000_000u32..120_000_000),
    )
        .prop_map(|(clock, which, bus)| match (which, bus) {
            (0, _) => TimingRule::new(clock, Limits::BXCAN),
            (1, _) | (_, None) => TimingRule::new(clock, Limits::FLEXCAN_KINETIS),
            (_, Some(bus)) => flexcan_rules::rule(clock, bus, 16, true),
        })
}

proptest! {
    /// Issue 22, items 5–7: what a rule reports is what it accepts. Its fastest and
    /// slowest timings pass `check_timing` and `accept`; their rates bound the wished
    /// rates `check_bitrate` takes, one beyond is refused; every timing `timing_for`
    /// gives passes `check_timing` and lies in the reported range and limits.
    #[test]
    fn a_rule_accepts_what_it_reports(rule in any_rule(), rate in 1u32..20_000_000) {
        match (rule.fastest(), rule.slowest()) {
            (Some(fast), Some(slow)) => {
                for t in [fast, slow] {
                    prop_assert_eq!(rule.check_timing(&t), Ok(()));
                    prop_assert_eq!(rule.accept(&t, DEFAULT_TOLERANCE_PPM), Ok(()));
                }
                let (min, max) = (rule.min_bitrate(), rule.max_bitrate());
                prop_assert_eq!((slow.actual_bitrate(), fast.actual_bitrate()), (min, max));
                prop_assert!(min <= max);
                prop_assert_eq!(rule.check_bitrate(max), Ok(()));
                prop_assert_eq!(rule.check_bitrate(max + 1), Err(TimingError::BitrateTooHigh));
                if min > 1 {
                    prop_assert_eq!(rule.check_bitrate(min), Ok(()));
                    prop_assert_eq!(rule.check_bitrate(min - 1), Err(TimingError::BitrateTooLow));
                }
                match rule.timing_for(rate, cia_sample_point(rate), DEFAULT_TOLERANCE_PPM) {
                    Ok(t) => {
                        prop_assert_eq!(rule.check_timing(&t), Ok(()));
                        prop_assert!(rule.limits.min_quanta() <= t.quanta());
                        prop_assert!(t.quanta() <= rule.limits.max_quanta());
                        prop_assert!(min <= t.actual_bitrate() && t.actual_bitrate() <= max);
                        prop_assert!(t.within_tolerance(DEFAULT_TOLERANCE_PPM));
                    }
                    Err(e) => {
                        let in_range = rule.check_bitrate(rate).is_ok();
                        prop_assert_eq!(
                            e == TimingError::TooFarFromWishedBitrate,
                            in_range,
                            "{:?} for {} in {}..={}", e, rate, min, max
                        );
                    }
                }
            }
            (None, None) => {
                prop_assert_eq!(rule.check_bitrate(rate), Err(TimingError::ForbiddenByManual));
            }
            other => prop_assert!(false, "one extreme without the other: {:?}", other),
        }
    }
}
