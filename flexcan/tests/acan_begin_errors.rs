//! ACAN §15, table 5: every error of `begin`, all found at once, nothing configured on
//! error; the bounded handshake waits (a typed timeout, not a table-5 flag).
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_core::timing::{Limits, Timing, TimingError};
use twocan_core::{Error, Filter, Format, FrameKind};
use twocan_flexcan::model::{FlexCanModel, ModelMode};
use twocan_flexcan::regs::{self, mcr};
use twocan_flexcan::{
    BeginError, Board, ConfigErrors, Configuration, FlexCan, HostSystem, Instance, Settings, Target,
};

const T32_CAN0: Target = Target::new(Board::Teensy32, Instance::Can0);
const T36_CAN1: Target = Target::new(Board::Teensy36, Instance::Can1);

/// Runs `begin` over a fresh model and checks that an error leaves every register
/// untouched: the module still in reset (disabled), no SIM / PORT write.
fn begin_error(
    target: Target,
    settings: &Settings,
    primary: &[Filter],
    secondary: &[Filter],
) -> ConfigErrors {
    let model = model_for(target.board);
    let reset_mcr = model.peek32(regs::MCR);
    let reset_ctrl1 = model.peek32(regs::CTRL1);
    let mut sys = HostSystem::new();
    let flags = twocan_flexcan::check(target, settings, primary, secondary);
    match FlexCan::begin(
        model.clone(),
        &mut sys,
        target,
        settings,
        primary,
        secondary,
    ) {
        Ok(_) => panic!("begin succeeded"),
        Err(BeginError::Hardware(e)) => panic!("hardware error {e:?}"),
        Err(BeginError::Timing(e)) => panic!("bit rate out of range {e:?}"),
        Err(BeginError::Config(f)) => {
            assert_eq!(f, flags, "check() and begin() agree");
            assert!(
                sys.written().is_empty(),
                "no SIM / PORT write: {:?}",
                sys.written()
            );
            assert_eq!(model.mode(), ModelMode::Disabled);
            assert_eq!(model.peek32(regs::MCR), reset_mcr);
            assert_eq!(model.peek32(regs::CTRL1), reset_ctrl1);
            f
        }
    }
}

#[test]
fn no_error() {
    let flags = twocan_flexcan::check(T32_CAN0, &Settings::new(125_000), &[], &[]);
    assert_eq!(flags, ConfigErrors::NONE);
    assert_eq!(flags.bits(), 0);
}

/// Runs `begin` with a wished rate outside the driver's rule: refused with
/// `BeginError::Timing` before anything is written; `check` reports the rate as a flag
/// among the others. Gives (the error, `check`'s flags).
fn rate_error(target: Target, settings: &Settings) -> (TimingError, ConfigErrors) {
    let model = model_for(target.board);
    let mut sys = HostSystem::new();
    let flags = twocan_flexcan::check(target, settings, &[], &[]);
    let r = FlexCan::begin(model.clone(), &mut sys, target, settings, &[], &[]);
    let e = match r {
        Err(BeginError::Timing(e)) => e,
        other => panic!("{:?}", other.err()),
    };
    assert!(sys.written().is_empty());
    assert_eq!(model.mode(), ModelMode::Disabled);
    assert!(
        flags.contains(ConfigErrors::BIT_RATE_OUT_OF_RANGE),
        "{flags:?}"
    );
    (e, flags)
}

/// Issue 14: the Kinetis reference manual ("Arbitration and matching timing") asks for
/// at least 8 time quanta per bit and, with 16 message buffers and the Rx FIFO, at
/// least 16 peripheral (bus) clocks per CAN bit, with a bus clock not below the 16 MHz
/// oscillator clock. `begin` refuses what it forbids, writing nothing; the edges of
/// each rule are accepted. Issue 22: the wished rate is judged by the same rule, so a
/// rate above the fastest the rule allows is `BeginError::Timing(BitrateTooHigh)`, as
/// `set_bitrate` refuses it; a hand-made timing the rule forbids at a rate in range is
/// `BIT_TIMING_FORBIDDEN`, as `set_timing` refuses it.
#[test]
fn bit_timing_the_manual_forbids_is_refused() {
    let accepted = |s: &Settings| {
        assert_eq!(
            twocan_flexcan::check(T32_CAN0, s, &[], &[]),
            ConfigErrors::NONE
        );
        let model = model_for(T32_CAN0.board);
        let regs = twocan_flexcan::IdleClocked::new(model);
        let r = FlexCan::begin(regs, &mut HostSystem::new(), T32_CAN0, s, &[], &[]);
        assert!(r.is_ok(), "{:?}: {:?}", s.timing, r.err());
    };
    let with_bus = |rate: u32, bus: Option<u32>| {
        let mut s = Settings::new(rate);
        s.bus_clock_hz = bus;
        s
    };
    // A timing the solver with ACAN's field ranges (5..=25 quanta) would give.
    let hand_made = |rate: u32, prescaler: u16, tseg1: u8, tseg2: u8, bus: Option<u32>| {
        let mut s = with_bus(rate, bus);
        s.timing = Timing::from_tsegs(16_000_000, rate, &Limits::FLEXCAN, prescaler, tseg1, tseg2);
        s
    };
    // 1 Mbit/s from the least bus clock the manual allows (16 MHz, the default
    // assumption): 16 clocks and 16 quanta per bit, the edge of the clock rule.
    let one = with_bus(1_000_000, None);
    assert_eq!(one.timing.quanta(), 16);
    accepted(&one);
    // 2 Mbit/s: 8 quanta (the edge of the quanta rule); from a 32 MHz bus, 16 clocks:
    // accepted. From a 16 MHz bus (8 clocks per bit) and a 31 MHz one (15.5), above the
    // fastest rate the rule allows (1 Mbit/s; 16 MHz / 9 = 1,777,777 bit/s): the rate is
    // refused, and `check` flags the timing too.
    accepted(&with_bus(2_000_000, Some(32_000_000)));
    accepted(&with_bus(2_000_000, Some(60_000_000)));
    for bus in [None, Some(31_000_000)] {
        let two = with_bus(2_000_000, bus);
        assert_eq!(two.timing.quanta(), 8);
        assert_eq!(
            rate_error(T32_CAN0, &two),
            (
                TimingError::BitrateTooHigh,
                ConfigErrors::BIT_RATE_OUT_OF_RANGE | ConfigErrors::BIT_TIMING_FORBIDDEN
            ),
            "{bus:?}"
        );
    }
    // 7 quanta (prescaler 2, 1,142,857 bit/s) and 5 quanta (prescaler 4, 800 kbit/s):
    // rates in range with a 60 MHz bus, timings the quanta rule forbids.
    let seven = hand_made(1_142_857, 2, 4, 2, Some(60_000_000));
    assert_eq!(seven.timing.quanta(), 7);
    assert_eq!(
        begin_error(T32_CAN0, &seven, &[], &[]),
        ConfigErrors::BIT_TIMING_FORBIDDEN
    );
    let five = hand_made(800_000, 4, 2, 2, Some(60_000_000));
    assert_eq!(five.timing.quanta(), 5);
    assert_eq!(
        begin_error(T32_CAN0, &five, &[], &[]),
        ConfigErrors::BIT_TIMING_FORBIDDEN
    );
    // ACAN's 3.2 Mbit/s (5 quanta, prescaler 1): above the range whatever the bus clock.
    let acan_fastest = hand_made(3_200_000, 1, 2, 2, Some(60_000_000));
    assert_eq!(
        rate_error(T32_CAN0, &acan_fastest),
        (
            TimingError::BitrateTooHigh,
            ConfigErrors::BIT_RATE_OUT_OF_RANGE | ConfigErrors::BIT_TIMING_FORBIDDEN
        )
    );
    // A bus clock below the oscillator clock is refused even at a slow rate: no timing
    // at all is allowed (a flag, not a rate error).
    assert_eq!(
        begin_error(T32_CAN0, &with_bus(125_000, Some(15_999_999)), &[], &[]),
        ConfigErrors::BIT_TIMING_FORBIDDEN
    );
    accepted(&with_bus(125_000, Some(16_000_000)));
    // Reported together with ACAN's own flags.
    let mut both = hand_made(800_000, 4, 2, 2, None);
    both.use_alternate_rx_pin = true;
    assert_eq!(
        begin_error(T36_CAN1, &both, &[], &[]),
        ConfigErrors::BIT_TIMING_FORBIDDEN | ConfigErrors::NO_ALTERNATE_RX_PIN
    );
}

#[test]
fn bit_rate_too_far_15_2_1() {
    // `ACANSettings settings (1)`: 1 bit/s; ACAN's error code (bits 0-7) is exactly
    // bit 0; this driver also flags the rate as outside the clock's range (bit 10,
    // which `begin` reports as `BeginError::Timing(BitrateTooLow)`).
    let f = twocan_flexcan::check(T32_CAN0, &Settings::new(1), &[], &[]);
    assert_eq!(
        f,
        ConfigErrors::BIT_RATE_TOO_FAR | ConfigErrors::BIT_RATE_OUT_OF_RANGE
    );
    assert_eq!(f.bits() & 0xFF, 1 << 0);
}

/// A wished rate outside the driver's rule (2,500 bit/s to 1 Mbit/s from the default
/// 16 MHz bus clock) is refused by `begin` with the portable error every backend gives
/// (before ACAN's tolerance check, which alone lets 1,000,001 bit/s through at 1 ppm),
/// and nothing is written.
#[test]
fn bit_rates_out_of_range_are_refused_as_on_every_backend() {
    for (rate, want) in [
        (1, TimingError::BitrateTooLow),
        (2_499, TimingError::BitrateTooLow),
        (1_000_001, TimingError::BitrateTooHigh),
        (3_200_000, TimingError::BitrateTooHigh),
        (0, TimingError::BitrateZero),
    ] {
        let model = model_for(T32_CAN0.board);
        let mut sys = HostSystem::new();
        let r = FlexCan::begin(
            model.clone(),
            &mut sys,
            T32_CAN0,
            &Settings::new(rate),
            &[],
            &[],
        );
        assert!(
            matches!(r, Err(BeginError::Timing(e)) if e == want),
            "{rate}"
        );
        assert!(sys.written().is_empty());
        assert_eq!(model.mode(), ModelMode::Disabled);
        // `check` finds the same problem, as a flag.
        let flags = twocan_flexcan::check(T32_CAN0, &Settings::new(rate), &[], &[]);
        assert!(
            flags.contains(ConfigErrors::BIT_RATE_OUT_OF_RANGE),
            "{rate}: {flags:?}"
        );
    }
    // In range: no flag at all (the slowest and the fastest of the rule, and between).
    for rate in [2_500, 1_000_000, 125_000] {
        let flags = twocan_flexcan::check(T32_CAN0, &Settings::new(rate), &[], &[]);
        assert_eq!(flags, ConfigErrors::NONE, "{rate}");
    }
    // The slowest, 2,500 bit/s, and the fastest the manual allows from the least bus
    // clock, 1 Mbit/s.
    for rate in [2_500, 1_000_000] {
        let model = model_for(T32_CAN0.board);
        let r = FlexCan::begin(
            twocan_flexcan::IdleClocked::new(model),
            &mut HostSystem::new(),
            T32_CAN0,
            &Settings::new(rate),
            &[],
            &[],
        );
        assert!(r.is_ok(), "{rate}: {:?}", r.err());
    }
}

#[test]
fn inconsistent_bit_configuration_15_2_2() {
    let mut s = Settings::new(500_000);
    s.timing.sjw = 0; // RJW 0: inconsistent, the bit rate is unchanged.
    assert_eq!(
        begin_error(T32_CAN0, &s, &[], &[]),
        ConfigErrors::BIT_TIMING_INCONSISTENT
    );
    // §16.2's example (PS1 = 0) also moves the bit rate 45 % away: both flags.
    let mut s = Settings::new(500_000);
    s.timing.phase_seg1 = 0;
    assert_eq!(
        begin_error(T32_CAN0, &s, &[], &[]),
        ConfigErrors::BIT_TIMING_INCONSISTENT | ConfigErrors::BIT_RATE_TOO_FAR
    );
    // Counts for another clock than the 16 MHz oscillator.
    let mut s = Settings::new(500_000);
    s.timing.clock_hz = 8_000_000;
    assert!(begin_error(T32_CAN0, &s, &[], &[]).contains(ConfigErrors::BIT_TIMING_INCONSISTENT));
}

#[test]
fn too_many_primary_filters_15_2_3() {
    for c in Configuration::ALL {
        let mut s = Settings::new(125_000);
        s.configuration = c;
        let list: Vec<Filter> = (0..=c.primary_filter_capacity() as u16)
            .map(Filter::standard)
            .collect();
        assert_eq!(
            begin_error(T32_CAN0, &s, &list, &[]),
            ConfigErrors::TOO_MANY_PRIMARY_FILTERS,
            "{c:?}"
        );
    }
}

#[test]
fn primary_filter_conformance_15_3() {
    let s = Settings::new(125_000);
    let not_conform = [
        Filter::masked(FrameKind::Data, Format::Standard, 0x7FC, 0x541), // §12.3's example
        Filter::standard(0x800),
        Filter::extended(0x2000_0000),
        Filter::masked(FrameKind::Data, Format::Standard, 0xFFF, 0),
    ];
    for f in not_conform {
        assert_eq!(
            begin_error(T32_CAN0, &s, &[f], &[]),
            ConfigErrors::PRIMARY_FILTER_NOT_CONFORM,
            "{f:?}"
        );
    }
}

#[test]
fn too_many_secondary_filters_15_3_1() {
    for c in Configuration::ALL {
        let mut s = Settings::new(125_000);
        s.configuration = c;
        let list: Vec<Filter> = (0..=c.secondary_filter_capacity() as u16)
            .map(Filter::standard)
            .collect();
        assert_eq!(
            begin_error(T32_CAN0, &s, &[], &list),
            ConfigErrors::TOO_MANY_SECONDARY_FILTERS,
            "{c:?}"
        );
    }
}

#[test]
fn secondary_filter_conformance_15_3_2() {
    let s = Settings::new(125_000);
    let not_conform = [
        Filter::standard(0x800),
        Filter::extended(0x2000_0000),
        // A secondary filter names one identifier: no mask, no "any" kind.
        Filter::masked(FrameKind::Data, Format::Standard, 0x7FC, 0x540),
        Filter::exact(FrameKind::Any, Format::Standard, 0x123),
        Filter::kind_format(FrameKind::Remote, Format::Any),
    ];
    for f in not_conform {
        assert_eq!(
            begin_error(T32_CAN0, &s, &[], &[f]),
            ConfigErrors::SECONDARY_FILTER_NOT_CONFORM,
            "{f:?}"
        );
    }
}

#[test]
fn can1_has_no_alternate_pins_15_3_3_and_15_3_4() {
    let mut s = Settings::new(125_000);
    s.use_alternate_tx_pin = true;
    assert_eq!(
        begin_error(T36_CAN1, &s, &[], &[]),
        ConfigErrors::NO_ALTERNATE_TX_PIN
    );
    s.use_alternate_rx_pin = true;
    assert_eq!(
        begin_error(T36_CAN1, &s, &[], &[]),
        ConfigErrors::NO_ALTERNATE_TX_PIN | ConfigErrors::NO_ALTERNATE_RX_PIN
    );
    s.use_alternate_tx_pin = false;
    assert_eq!(
        begin_error(T36_CAN1, &s, &[], &[]),
        ConfigErrors::NO_ALTERNATE_RX_PIN
    );
    assert_eq!(ConfigErrors::NO_ALTERNATE_TX_PIN.bits(), 0x40);
    assert_eq!(ConfigErrors::NO_ALTERNATE_RX_PIN.bits(), 0x80);
}

#[test]
fn can1_only_on_teensy_36() {
    let s = Settings::new(125_000);
    for board in [Board::Teensy32, Board::Teensy35] {
        assert_eq!(
            begin_error(Target::new(board, Instance::Can1), &s, &[], &[]),
            ConfigErrors::NO_SUCH_INSTANCE
        );
    }
}

#[test]
fn every_flag_at_once() {
    // In range, but the prescaler moved by hand puts the rate far from the wished one.
    let mut s = Settings::new(125_000);
    s.timing.prescaler += 3;
    s.timing.sjw = 0;
    s.configuration = Configuration::Filters8_0;
    s.use_alternate_tx_pin = true;
    s.use_alternate_rx_pin = true;
    let primary: Vec<Filter> = (0..9).map(|_| Filter::standard(0x800)).collect();
    let secondary = [Filter::extended(0x2000_0000)];
    let f = begin_error(T36_CAN1, &s, &primary, &secondary);
    assert_eq!(f.bits(), 0xFF);
    assert_eq!(f.count(), 8);
}

#[test]
fn alternate_pins_accepted_on_can0() {
    for board in Board::KINETIS {
        let mut s = Settings::new(125_000);
        s.use_alternate_tx_pin = true;
        s.use_alternate_rx_pin = true;
        assert_eq!(
            twocan_flexcan::check(Target::new(board, Instance::Can0), &s, &[], &[]),
            ConfigErrors::NONE
        );
    }
}

#[test]
fn handshake_timeout_is_typed_and_retry_works() {
    let model = FlexCanModel::mk20dx256();
    model.set_freeze_ack_stuck(true);
    let mut s = Settings::new(125_000);
    s.handshake_polls = 1_000;
    let e = FlexCan::begin(
        model.clone(),
        &mut HostSystem::new(),
        T32_CAN0,
        &s,
        &[],
        &[],
    )
    .unwrap_err();
    assert_eq!(e, BeginError::Hardware(Error::Timeout));
    assert_eq!(e.flags(), ConfigErrors::NONE);
    // Once the module acknowledges again, `begin` succeeds on the same module.
    model.set_freeze_ack_stuck(false);
    let can = FlexCan::begin(
        Ticking::new(model.clone()),
        &mut HostSystem::new(),
        T32_CAN0,
        &s,
        &[],
        &[],
    )
    .unwrap();
    assert_eq!(model.mode(), ModelMode::Normal);
    assert_eq!(
        model.peek32(regs::MCR) & (mcr::FRZACK | mcr::LPMACK | mcr::NOTRDY),
        0
    );
    // `begin` returned once the module was synchronised to the (idle) bus.
    assert!(model.is_synchronised());
    assert_ne!(model.peek32(regs::ESR1) & regs::esr1::SYNCH, 0);
    drop(can);
}

#[test]
fn begin_keeps_the_model_by_reference() {
    // `regs` may be `&mut M`: the caller keeps the registers after an error.
    let mut model = FlexCanModel::mk20dx256();
    let too_many: Vec<Filter> = (0..20).map(Filter::standard).collect();
    let e = FlexCan::begin(
        &mut model,
        &mut HostSystem::new(),
        T32_CAN0,
        &Settings::new(125_000),
        &too_many,
        &[],
    );
    assert!(matches!(e, Err(BeginError::Config(_))));
    assert_eq!(model.mode(), ModelMode::Disabled);
}
