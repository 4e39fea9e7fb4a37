//! ACAN §16: the settings examples (842 kbit/s, 500 kbit/s, 440 kbit/s, 1 bit/s,
//! user-changed segments, the consistency flags), table 7's defaults, and what `begin`
//! writes to CTRL1 / MCR for them.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_core::timing::{solve, Consistency, Limits, Timing, TimingError};
use twocan_flexcan::regs::{self, ctrl1, mcr};
use twocan_flexcan::settings::{DEFAULT_IRQ_PRIORITY, SAMPLE_POINT_PERMILLE};
use twocan_flexcan::{
    Board, ConfigErrors, Configuration, Instance, Settings, Target, CAN_CLOCK_HZ,
};

fn t32() -> Target {
    Target::new(Board::Teensy32, Instance::Can0)
}

#[test]
fn one_mbit_16_1() {
    let s = Settings::new(1_000 * 1_000);
    assert!(s.bit_rate_close_to_wished());
    assert_eq!(s.actual_bit_rate(), 1_000_000);
}

#[test]
fn bit_rate_842_kbit_16_1_and_16_4_16_5() {
    let s = Settings::new(842 * 1_000);
    assert!(s.bit_rate_close_to_wished());
    assert_eq!(s.actual_bit_rate(), 842_105);
    assert_eq!(s.ppm_from_wished_bit_rate(), 124);
    assert!(!s.exact_bit_rate());
    assert!(s.consistency().is_ok());
    assert_eq!(
        twocan_flexcan::check(t32(), &s, &[], &[]),
        ConfigErrors::NONE
    );
}

#[test]
fn bit_rate_842_kbit_with_100_ppm_16_1() {
    let s = Settings::with_tolerance(842 * 1_000, 100);
    assert!(!s.bit_rate_close_to_wished());
    assert_eq!(s.actual_bit_rate(), 842_105);
    assert_eq!(s.ppm_from_wished_bit_rate(), 124);
    // The tolerance changes only the acceptance, not the computation.
    assert_eq!(s.timing, Settings::new(842_000).timing);
    assert_eq!(
        twocan_flexcan::check(t32(), &s, &[], &[]),
        ConfigErrors::BIT_RATE_TOO_FAR
    );
}

#[test]
fn bit_rate_500_kbit_exact_16_1() {
    let s = Settings::with_tolerance(500 * 1_000, 0);
    assert!(s.bit_rate_close_to_wished());
    assert_eq!(s.actual_bit_rate(), 500_000);
    assert_eq!(s.ppm_from_wished_bit_rate(), 0);
    assert!(s.exact_bit_rate());
    assert_eq!(s.sample_point_from_bit_start(), 68); // §16.6
}

#[test]
fn fastest_and_slowest_exact_rates_16_1() {
    // ACAN's fastest exact rate, 3.2 Mbit/s, is 5 quanta per bit: the solver reproduces
    // it with ACAN's field ranges (`Limits::FLEXCAN`). `Settings` solve within what the
    // driver accepts (at least 8 quanta, Kinetis RM "Arbitration and matching timing";
    // issue 22: one rule), where the fastest exact rate is 2 Mbit/s.
    let acan = solve(
        CAN_CLOCK_HZ,
        3_200_000,
        &Limits::FLEXCAN,
        SAMPLE_POINT_PERMILLE,
    )
    .unwrap();
    assert!(acan.is_exact());
    assert_eq!((acan.prescaler, acan.quanta()), (1, 5));
    let fast = Settings::with_tolerance(2_000_000, 0);
    assert!(fast.bit_rate_close_to_wished() && fast.exact_bit_rate());
    assert_eq!((fast.timing.prescaler, fast.timing.quanta()), (1, 8));
    assert!(!Settings::with_tolerance(3_200_000, 0).bit_rate_close_to_wished());
    let slow = Settings::with_tolerance(2_500, 0);
    assert!(slow.bit_rate_close_to_wished() && slow.exact_bit_rate());
    assert_eq!((slow.timing.prescaler, slow.timing.quanta()), (256, 25));
    assert!(!Settings::with_tolerance(3_300_000, 0).bit_rate_close_to_wished());
    assert!(!Settings::with_tolerance(2_400, 0).bit_rate_close_to_wished());
}

#[test]
fn fastest_rate_is_refused_even_in_loop_back_16_1() {
    // ACAN: "It works when the FlexCAN module is configured in both loop back mode and
    // self reception mode." Its 5 quanta per bit are below the Kinetis manual's 8
    // ("Arbitration and matching timing"), which makes no exception for loop-back:
    // `begin` refuses the rate (above the fastest the rule allows) and ACAN's timing for
    // it (docs/differences.md).
    let r = begin::<32, 16>(&loop_back(3_200_000), &[], &[]);
    assert!(
        matches!(
            r,
            Err(twocan_flexcan::BeginError::Timing(
                TimingError::BitrateTooHigh
            ))
        ),
        "{:?}",
        r.err()
    );
    let mut acan = loop_back(3_200_000);
    acan.timing = solve(
        CAN_CLOCK_HZ,
        3_200_000,
        &Limits::FLEXCAN,
        SAMPLE_POINT_PERMILLE,
    )
    .unwrap();
    assert_eq!(
        twocan_flexcan::check(t32(), &acan, &[], &[]),
        ConfigErrors::BIT_RATE_OUT_OF_RANGE | ConfigErrors::BIT_TIMING_FORBIDDEN
    );
    // The fastest rate the manual allows from the 16 MHz CAN clock, 2 Mbit/s (8
    // quanta), runs in loop-back with a bus clock of 32 MHz or more.
    let mut s = loop_back(2_000_000);
    s.bus_clock_hz = Some(48_000_000);
    let (model, mut can) = begin::<32, 16>(&s, &[], &[]).unwrap();
    let mut bus = bus_with(2_000_000, &[&model]);
    can.try_send(&std_data(0x7, &[7])).unwrap();
    run1(&mut bus, &mut can, 500);
    assert_eq!(drain(&mut can).len(), 1);
}

#[test]
fn bit_rate_440_kbit_decomposition_16_1() {
    let s = Settings::new(440 * 1_000);
    assert!(!s.bit_rate_close_to_wished());
    assert_eq!(s.actual_bit_rate(), 444_444);
    assert_eq!(s.ppm_from_wished_bit_rate(), 10_100);
    let t = s.timing;
    assert_eq!(t.prescaler, 2); // BRP = 2
    assert_eq!(t.prop_seg, 6); // PropSeg = 6
    assert_eq!(t.phase_seg1, 5); // PS1 = 5
    assert_eq!(t.phase_seg2, 6); // PS2 = 6
    assert_eq!(t.sjw, 4); // RJW = 4
    assert!(!t.triple_sampling);
    // The manual prints 68 %; its own formula gives 100 × (1 + 6 + 5) / 18 = 66.7 %:
    // the printed value is that of the 500 kbit/s example (see the report).
    assert_eq!(s.sample_point_from_bit_start(), 66);
    assert_eq!(s.consistency(), Consistency::OK);
    assert_eq!(
        twocan_flexcan::check(t32(), &s, &[], &[]),
        ConfigErrors::BIT_RATE_TOO_FAR
    );
}

#[test]
fn one_bit_per_second_15_2_1() {
    let s = Settings::new(1);
    assert!(!s.bit_rate_close_to_wished());
    assert!(s.consistency().is_ok(), "always consistent");
    assert_eq!(s.actual_bit_rate(), 2_500);
}

#[test]
fn user_changed_segments_16_1() {
    let mut s = Settings::new(500 * 1_000);
    assert!(s.bit_rate_close_to_wished());
    assert_eq!((s.timing.phase_seg1, s.timing.phase_seg2), (5, 5));
    s.timing.phase_seg1 += 1; // 5 -> 6
    s.timing.phase_seg2 -= 1; // 5 -> 4
    assert_eq!(s.sample_point_from_bit_start(), 75);
    assert_eq!(s.actual_bit_rate(), 500_000);
    assert_eq!(s.consistency(), Consistency::OK);

    // And `begin` writes exactly those counts to CTRL1.
    let (model, _can) = begin::<32, 16>(&s, &[], &[]).unwrap();
    let c = model.peek32(regs::CTRL1);
    assert_eq!(ctrl1::PRESDIV.get(c), 1);
    assert_eq!(ctrl1::PROPSEG.get(c), 4);
    assert_eq!(ctrl1::PSEG1.get(c), 5);
    assert_eq!(ctrl1::PSEG2.get(c), 3);
    assert_eq!(ctrl1::RJW.get(c), 3);
    // The register holds the counts; the settings' timing carries the driver's limits.
    assert_eq!(
        Timing {
            limits: Limits::FLEXCAN_KINETIS,
            ..Timing::from_flexcan_ctrl1(CAN_CLOCK_HZ, 500_000, c)
        },
        s.timing
    );
    assert_eq!(
        c & (ctrl1::CLKSRC | ctrl1::LOM | ctrl1::LPB | ctrl1::BOFFREC | ctrl1::SMP),
        0
    );
}

#[test]
fn consistency_flags_16_2() {
    let mut s = Settings::new(500 * 1_000);
    s.timing.phase_seg1 = 0; // Error, mPhaseSegment1 should be >= 1 (and <= 8)
    let c = s.consistency();
    assert_eq!(c.bits() & 0x7FF, 0x10, "table 6 bits: 0x10");
    assert!(c.contains(Consistency::PHASE_SEG1_TOO_SMALL));

    let table_6 = [
        (|t: &mut Timing| t.prescaler = 0) as fn(&mut Timing),
        |t| t.prescaler = 257,
        |t| t.prop_seg = 0,
        |t| t.prop_seg = 9,
        |t| t.phase_seg1 = 0,
        |t| t.phase_seg1 = 9,
        |t| t.phase_seg2 = 0,
        |t| t.phase_seg2 = 9,
        |t| t.sjw = 0,
        |t| t.sjw = 5,
        |t| {
            t.phase_seg2 = 3;
            t.phase_seg1 = 8;
            t.sjw = 4
        },
    ];
    for (bit, change) in table_6.iter().enumerate() {
        let mut s = Settings::new(500_000);
        change(&mut s.timing);
        let c = s.consistency();
        assert!(c.bits() & (1 << bit) != 0, "table 6 bit {bit}: {c:?}");
        assert!(twocan_flexcan::check(t32(), &s, &[], &[])
            .contains(ConfigErrors::BIT_TIMING_INCONSISTENT));
    }
}

#[test]
fn triple_sampling_is_written() {
    let mut s = Settings::new(125_000);
    s.timing.triple_sampling = true;
    assert!(s.consistency().is_ok());
    // First sample one quantum earlier (§16.1 "sampling first point").
    assert_eq!(s.sample_point_from_bit_start(), 62);
    let (model, _can) = begin::<32, 16>(&s, &[], &[]).unwrap();
    assert_ne!(model.peek32(regs::CTRL1) & ctrl1::SMP, 0);
}

#[test]
fn table_7_defaults() {
    let s = Settings::default();
    assert_eq!(s.wished_bit_rate(), 250_000);
    let t = s.timing;
    assert_eq!(
        (t.prescaler, t.prop_seg, t.phase_seg1, t.phase_seg2, t.sjw),
        (4, 5, 5, 5, 4)
    );
    assert!(!t.triple_sampling);
    assert!(s.bit_rate_close_to_wished());
    assert!(!s.listen_only && !s.self_reception && !s.loop_back);
    assert_eq!(s.configuration, Configuration::Filters12_12);
    assert!(!s.use_alternate_tx_pin && !s.use_alternate_rx_pin);
    assert_eq!(s.message_irq_priority, DEFAULT_IRQ_PRIORITY);
    assert_eq!(DEFAULT_IRQ_PRIORITY, 64);
    assert_eq!(
        (
            twocan_flexcan::RECEIVE_BUFFER_SIZE,
            twocan_flexcan::TRANSMIT_BUFFER_SIZE
        ),
        (32, 16)
    );
    assert!(!s.tx_pin_open_collector && !s.rx_pin_pull_up);
    assert_eq!(SAMPLE_POINT_PERMILLE, 687);
    const CONST_SETTINGS: Settings = Settings::new(125_000);
    assert!(CONST_SETTINGS.bit_rate_close_to_wished());
}

#[test]
fn modes_16_7_1_to_16_7_3() {
    let cases = [
        (false, false, false),
        (true, false, false),
        (false, true, false),
        (false, false, true),
        (true, true, true),
    ];
    for (listen_only, self_reception, loop_back) in cases {
        let mut s = Settings::new(250_000);
        s.listen_only = listen_only;
        s.self_reception = self_reception;
        s.loop_back = loop_back;
        let (model, _can) = begin::<32, 16>(&s, &[], &[]).unwrap();
        let c = model.peek32(regs::CTRL1);
        let m = model.peek32(regs::MCR);
        assert_eq!(c & ctrl1::LOM != 0, listen_only);
        assert_eq!(c & ctrl1::LPB != 0, loop_back);
        assert_eq!(
            m & mcr::SRXDIS == 0,
            self_reception,
            "self reception = !SRXDIS"
        );
        assert_ne!(m & mcr::RFEN, 0);
        assert_ne!(m & mcr::IRMQ, 0);
        assert_eq!(mcr::MAXMB.get(m), 15);
        assert_eq!(mcr::IDAM.get(m), mcr::IDAM_FORMAT_A);
    }
}

#[test]
fn configuration_sets_rffn_11() {
    for (c, rffn) in Configuration::ALL.iter().zip(0..) {
        let mut s = Settings::new(250_000);
        s.configuration = *c;
        let (model, can) = begin::<32, 16>(&s, &[], &[]).unwrap();
        assert_eq!(regs::ctrl2::RFFN.get(model.peek32(regs::CTRL2)), rffn);
        assert_eq!(can.hardware().configuration(), *c);
    }
}
