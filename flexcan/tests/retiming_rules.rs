//! Re-timing a stopped FlexCAN applies the same rules as `begin`: the register ranges,
//! and the Kinetis manual's rule beyond them ("Arbitration and matching timing": at
//! least 8 time quanta per bit and 16 peripheral (bus) clocks per CAN bit with 16 message
//! buffers and the Rx FIFO), with the bus clock `begin` was given. The capabilities
//! report the fastest rate that rule allows.

mod common;

use common::*;
use twocan_core::timing::{Limits, Timing, TimingError};
use twocan_core::{Error, Hardware, Mode};
use twocan_flexcan::{Board, ConfigErrors, Instance, Settings, Target};

fn teensy36() -> Target {
    Target::new(Board::Teensy36, Instance::Can0)
}

fn settings(bit_rate: u32, bus_clock_hz: Option<u32>) -> Settings {
    let mut s = loop_back(bit_rate);
    s.bus_clock_hz = bus_clock_hz;
    s
}

#[test]
fn default_bus_clock_refuses_what_begin_refuses() {
    // `begin` refuses 2 and 3.2 Mbit/s with the default (16 MHz) bus clock: 8 and 5
    // bus clocks per bit, fewer than 16.
    for rate in [2_000_000, 3_200_000] {
        let flags = twocan_flexcan::check(teensy36(), &settings(rate, None), &[], &[]);
        assert!(
            flags.contains(ConfigErrors::BIT_TIMING_FORBIDDEN),
            "{rate}: {flags:?}"
        );
    }
    let (_model, mut can) =
        begin_on::<8, 4>(teensy36(), &settings(500_000, None), &[], &[]).expect("500 kbit/s");
    // 16 MHz / 16 bus clocks per bit = 1 Mbit/s (16 MHz / 8 quanta = 2 Mbit/s is above).
    assert_eq!(can.capabilities().max_bitrate, 1_000_000);
    can.set_mode(Mode::Stopped).unwrap();
    for rate in [2_000_000, 3_200_000, 1_000_001] {
        assert_eq!(
            can.set_bitrate(rate, 750),
            Err(Error::Timing(TimingError::BitrateTooHigh)),
            "{rate}"
        );
    }
    // 800 kbit/s in 5 quanta (prescaler 4): 20 bus clocks per bit, but fewer than 8
    // quanta: within the register ranges (ACAN's 3.2 Mbit/s shape), refused by the
    // manual's rule, nothing written.
    let five = Timing::from_tsegs(16_000_000, 800_000, &Limits::FLEXCAN, 4, 2, 2);
    assert_eq!(five.quanta(), 5);
    assert_eq!(five.actual_bitrate(), 800_000);
    assert!(five.consistency().is_ok(), "{:?}", five.consistency());
    let before = can.hardware().capabilities();
    assert_eq!(
        can.set_timing(&five),
        Err(Error::Timing(TimingError::ForbiddenByManual))
    );
    assert_eq!(can.hardware().capabilities(), before);
    // The fastest allowed rate is accepted.
    let t = can.set_bitrate(1_000_000, 750).expect("1 Mbit/s");
    assert_eq!(t.actual_bitrate(), 1_000_000);
    assert!(t.quanta() >= 8);
    can.set_mode(Mode::Normal).unwrap();
}

#[test]
fn a_faster_bus_clock_allows_two_megabits() {
    // 60 MHz bus clock: 60 MHz / 16 = 3.75 Mbit/s, 16 MHz / 8 quanta = 2 Mbit/s.
    let s = settings(500_000, Some(60_000_000));
    let (_model, mut can) = begin_on::<8, 4>(teensy36(), &s, &[], &[]).expect("500 kbit/s");
    assert_eq!(can.capabilities().max_bitrate, 2_000_000);
    can.set_mode(Mode::Stopped).unwrap();
    assert_eq!(
        can.set_bitrate(3_200_000, 750),
        Err(Error::Timing(TimingError::BitrateTooHigh))
    );
    let t = can.set_bitrate(2_000_000, 750).expect("2 Mbit/s");
    assert_eq!((t.actual_bitrate(), t.quanta()), (2_000_000, 8));
    // `begin` agrees.
    assert_eq!(
        twocan_flexcan::check(teensy36(), &settings(2_000_000, Some(60_000_000)), &[], &[]),
        ConfigErrors::NONE
    );
}

/// Issue 22, item 5: one bit-rate rule. 1,000,001 bit/s is one above the fastest rate the
/// capabilities report from the default bus clock (the solver would round it to
/// 1 Mbit/s, 1 ppm away): `check`, `begin` and `set_bitrate` all refuse it as too high;
/// 1,000,000 bit/s is accepted by all three.
#[test]
fn one_above_the_fastest_rate_is_refused_by_every_entry_point() {
    use twocan_flexcan::{BeginError, FlexCan, HostSystem};
    let (_model, mut can) =
        begin_on::<8, 4>(teensy36(), &settings(500_000, None), &[], &[]).expect("500 kbit/s");
    let max = can.capabilities().max_bitrate;
    assert_eq!(max, 1_000_000);
    can.set_mode(Mode::Stopped).unwrap();
    for (rate, ok) in [(max, true), (max + 1, false)] {
        let s = settings(rate, None);
        let flags = twocan_flexcan::check(teensy36(), &s, &[], &[]);
        let begun = FlexCan::begin(
            Ticking::new(model_for(Board::Teensy36)),
            &mut HostSystem::new(),
            teensy36(),
            &s,
            &[],
            &[],
        );
        let retimed = can.set_bitrate(rate, 750);
        if ok {
            assert_eq!(flags, ConfigErrors::NONE, "{rate}");
            assert!(begun.is_ok(), "{rate}: {:?}", begun.err());
            assert_eq!(retimed.map(|t| t.actual_bitrate()), Ok(rate));
        } else {
            assert_eq!(flags, ConfigErrors::BIT_RATE_OUT_OF_RANGE, "{rate}");
            assert!(
                matches!(begun, Err(BeginError::Timing(TimingError::BitrateTooHigh))),
                "{rate}: {:?}",
                begun.err()
            );
            assert_eq!(
                retimed,
                Err(Error::Timing(TimingError::BitrateTooHigh)),
                "{rate}"
            );
        }
    }
}

/// Issue 22, item 7: the timing limits the capabilities report are the ones the driver
/// accepts. Their fewest quanta per bit is the Kinetis manual's 8, not the CTRL1 fields'
/// 5; a consistent timing with that many quanta (at a rate the clock rule allows) is
/// accepted by `set_timing`, one quantum fewer is refused.
#[test]
fn reported_timing_limits_are_what_set_timing_accepts() {
    let s = settings(500_000, Some(60_000_000));
    let (_model, mut can) = begin_on::<8, 4>(teensy36(), &s, &[], &[]).expect("500 kbit/s");
    let caps = can.capabilities();
    let l = caps.timing_limits;
    assert_eq!((l.min_quanta(), l.max_quanta()), (8, 25));
    can.set_mode(Mode::Stopped).unwrap();
    // Prescaler 2: 8 quanta → 1 Mbit/s, 7 quanta → 1.14 Mbit/s (both within 60 MHz / 16).
    let q = l.min_quanta() as u8;
    let fewest = Timing::from_tsegs(16_000_000, 1_000_000, &l, 2, q - 3, 2);
    assert_eq!(fewest.quanta(), 8);
    assert_eq!(can.set_timing(&fewest), Ok(()));
    let fewer = Timing::from_tsegs(16_000_000, 1_142_857, &l, 2, q - 4, 2);
    assert_eq!(fewer.quanta(), 7);
    assert_eq!(
        can.set_timing(&fewer),
        Err(Error::Timing(TimingError::ForbiddenByManual))
    );
}
