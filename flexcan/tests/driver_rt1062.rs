//! The driver on the i.MX RT1062 (Teensy 4.0 / 4.1), over the FlexCAN model's RT1062
//! variants (64 message buffers, reset into Freeze mode, one interrupt line): `begin` on
//! CAN1, CAN2 and CAN3, the CCM clock root and gates, the IOMUXC pads and daisy select,
//! `end`, two modules of one board on one bus, and the errors of a wrong clock or
//! instance.

mod common;

use common::*;
use twocan_core::{Filter, Hardware, Registers};
use twocan_flexcan::imxrt::ccm::{CAN_CLK_PODF, CAN_CLK_SEL, CCM_CCGR0, CCM_CCGR7, CCM_CSCMR2};
use twocan_flexcan::imxrt::pads::{MUX_RESET, PAD_RESET};
use twocan_flexcan::imxrt::{CanClockSource, ClockRoot};
use twocan_flexcan::layout::{Imxrt1062, Layout};
use twocan_flexcan::regs::{self, mcr};
use twocan_flexcan::{
    check, BeginError, Board, CanClock, ConfigErrors, FlexCan, HostSystem, Instance, Settings,
    Target,
};

const T41: [Target; 3] = [
    Target::new(Board::Teensy41, Instance::Can1),
    Target::new(Board::Teensy41, Instance::Can2),
    Target::new(Board::Teensy41, Instance::Can3),
];

fn rt_loop_back(bit_rate: u32, clock: CanClock) -> Settings {
    let mut s = Settings::with_clock(bit_rate, clock);
    s.loop_back = true;
    s.self_reception = true;
    s
}

#[test]
fn loop_back_on_every_module_of_both_boards() {
    for board in Board::IMXRT {
        for instance in [Instance::Can1, Instance::Can2, Instance::Can3] {
            let target = Target::new(board, instance);
            let (model, mut can) = begin_rt_on::<32, 16>(
                target,
                &rt_loop_back(500_000, CanClock::IMXRT_24MHZ),
                &[],
                &[],
            )
            .unwrap_or_else(|e| panic!("{target:?}: {e:?}"));
            assert_eq!(model.message_buffers(), 64);
            let mut bus = bus_with(500_000, &[&model]);
            for id in [0x100u16, 0x7FF, 0x001] {
                can.try_send(&std_data(id, &[id as u8, 2])).unwrap();
            }
            can.try_send(&ext_data(0x1234_5678, &[9; 8])).unwrap();
            run1(&mut bus, &mut can, 2_000);
            let got: Vec<_> = drain(&mut can).into_iter().map(|r| r.frame).collect();
            assert_eq!(got.len(), 4, "{target:?}: {got:?}");
            assert!(got.contains(&ext_data(0x1234_5678, &[9; 8])));
            // The RT1062 layout with ACAN's default 12/12: MAXMB = the data mailbox
            // after the ERR005829 reserved one (MB16), nothing above MB31 enabled.
            let r = can.hardware().registers();
            assert_eq!(
                mcr::MAXMB.get(r.read32(regs::MCR)) as usize,
                <Imxrt1062 as Layout>::data_mailbox(twocan_flexcan::Configuration::Filters12_12)
                    as usize
            );
            assert_eq!(mcr::MAXMB.get(r.read32(regs::MCR)), 16);
            assert_eq!(r.read32(regs::IMASK2), 0);
            assert_eq!(r.read32(regs::IFLAG2), 0);
        }
    }
}

#[test]
fn begin_sets_the_clock_root_gates_and_pads() {
    let cases = [
        (
            T41[0],
            (CCM_CCGR0, 0xF << 14),
            (0x401F_811C, 2),
            (0x401F_8120, 2),
            (0x401F_844C, 2),
        ),
        (
            T41[1],
            (CCM_CCGR0, 0xF << 18),
            (0x401F_80C4, 0),
            (0x401F_80C8, 0),
            (0x401F_8450, 1),
        ),
        (
            T41[2],
            (CCM_CCGR7, 0xF << 6),
            (0x401F_80A4, 9),
            (0x401F_80A8, 9),
            (0x401F_878C, 0),
        ),
    ];
    for (target, (gate, bits), (tx_mux, tx_alt), (rx_mux, rx_alt), (daisy, select)) in cases {
        for (clock, sel, podf) in [
            (ClockRoot::OSC_24MHZ, 1, 0),
            (ClockRoot::PLL3_60MHZ, 0, 0),
            (ClockRoot::new(CanClockSource::Pll3Div6, 2), 2, 1),
        ] {
            let mut s = Settings::with_clock(1_000_000, CanClock::Imxrt(clock));
            s.tx_pin_open_collector = true;
            s.rx_pin_pull_up = true;
            let mut sys = HostSystem::new();
            // Another gate of CCGR0 already open, a foreign CSCMR2 field set: both kept.
            sys.write32(CCM_CCGR0, 0b11);
            sys.write32(CCM_CSCMR2, CAN_CLK_SEL.val(3) | 1 << 31);
            let model = model_of(target);
            let can = FlexCan::<_, Imxrt1062>::begin_with_layout(
                Ticking::new(model.clone()),
                &mut sys,
                target,
                &s,
                &[],
                &[],
            )
            .unwrap_or_else(|e| panic!("{target:?} {clock:?}: {e:?}"));
            let cscmr2 = sys.read32(CCM_CSCMR2);
            assert_eq!(CAN_CLK_SEL.get(cscmr2), sel);
            assert_eq!(CAN_CLK_PODF.get(cscmr2), podf);
            assert_ne!(cscmr2 & 1 << 31, 0, "other CSCMR2 fields kept");
            assert_eq!(sys.read32(gate) & bits, bits, "{target:?}: both gates on");
            assert_eq!(sys.read32(CCM_CCGR0) & 0b11, 0b11, "other gates kept");
            assert_eq!(sys.read32(tx_mux), tx_alt);
            assert_eq!(sys.read32(rx_mux), rx_alt);
            assert_eq!(sys.read32(daisy), select);
            assert_eq!(
                sys.read32(tx_mux + 0x1F0),
                PAD_RESET | 1 << 11,
                "Tx open drain"
            );
            assert_eq!(sys.read32(rx_mux + 0x1F0), 0xF0B0, "Rx 22 kΩ pull-up");
            // The timing is counted in the root's periods, and the running controller
            // reports that clock.
            assert_eq!(s.timing.clock_hz, clock.hz());
            assert_eq!(s.actual_bit_rate(), 1_000_000);
            let hw = can.into_split();
            assert_eq!(hw.capabilities().clock_hz, clock.hz());

            // `end`: pads back to GPIO with their reset control, the gates closed,
            // the root left for the other modules.
            let controller = hw.into_controller();
            controller.end(&mut sys).unwrap();
            assert_eq!(sys.read32(tx_mux), MUX_RESET);
            assert_eq!(sys.read32(rx_mux + 0x1F0), PAD_RESET);
            assert_eq!(sys.read32(gate) & bits, 0, "{target:?}: gates closed");
            assert_eq!(sys.read32(CCM_CCGR0) & 0b11, 0b11);
            assert_eq!(sys.read32(CCM_CSCMR2), cscmr2);
            assert_eq!(model.mode(), twocan_flexcan::model::ModelMode::Disabled);
        }
    }
}

#[test]
fn a_running_root_is_not_switched_again() {
    // CAN1 runs on 24 MHz; beginning CAN2 on the same root leaves CSCMR2 and CAN1's
    // gates untouched (no glitch for the running module).
    let mut sys = HostSystem::new();
    let s = rt_loop_back(250_000, CanClock::IMXRT_24MHZ);
    let _can1 = FlexCan::<_, Imxrt1062>::begin_with_layout(
        Ticking::new(model_of(T41[0])),
        &mut sys,
        T41[0],
        &s,
        &[],
        &[],
    )
    .unwrap();
    let before = sys.read32(CCM_CSCMR2);
    let _can2 = FlexCan::<_, Imxrt1062>::begin_with_layout(
        Ticking::new(model_of(T41[1])),
        &mut sys,
        T41[1],
        &s,
        &[],
        &[],
    )
    .unwrap();
    assert_eq!(sys.read32(CCM_CSCMR2), before);
    assert_eq!(sys.read32(CCM_CCGR0), 0xF << 14 | 0xF << 18);
}

#[test]
fn can1_and_can2_of_one_board_exchange_frames() {
    let s = Settings::with_clock(500_000, CanClock::Imxrt(ClockRoot::PLL3_60MHZ));
    let (m1, mut can1) = begin_rt_on::<32, 16>(T41[0], &s, &[], &[]).unwrap();
    let (m2, mut can2) =
        begin_rt_on::<32, 16>(T41[1], &s, &[Filter::standard(0x321)], &[]).unwrap();
    let mut bus = bus_with(500_000, &[&m1, &m2]);
    for i in 0..7u8 {
        can1.try_send(&std_data(0x321, &[i])).unwrap();
        can1.try_send(&std_data(0x322, &[i])).unwrap();
    }
    can2.try_send(&ext_data(0x1ABC_DEF0, &[1, 2, 3])).unwrap();
    run(&mut bus, &mut [&mut can1, &mut can2], 20_000);
    let at2 = drain(&mut can2);
    assert_eq!(at2.len(), 7, "only 0x321 passes CAN2's filter: {at2:?}");
    assert!(at2
        .iter()
        .enumerate()
        .all(|(i, r)| r.frame == std_data(0x321, &[i as u8])));
    let at1 = drain(&mut can1);
    assert_eq!(at1.len(), 1);
    assert_eq!(at1[0].frame, ext_data(0x1ABC_DEF0, &[1, 2, 3]));
}

#[test]
fn wrong_clock_instance_or_pins_are_refused_before_any_write() {
    let t41 = |i| Target::new(Board::Teensy41, i);
    // The Kinetis 16 MHz clock on a Teensy 4, the RT root on a Teensy 3.6.
    let kinetis_clock = Settings::new(500_000);
    assert_eq!(
        check(t41(Instance::Can1), &kinetis_clock, &[], &[]),
        ConfigErrors::CLOCK_NOT_ON_CHIP
    );
    let rt = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
    assert_eq!(
        check(Target::new(Board::Teensy36, Instance::Can0), &rt, &[], &[]),
        ConfigErrors::CLOCK_NOT_ON_CHIP
    );
    // A root above the data sheet's 80 MHz, or a divider of 0.
    let mut too_fast = rt;
    too_fast.can_clock = CanClock::Imxrt(ClockRoot::new(CanClockSource::Pll3Div6, 0));
    assert!(
        check(t41(Instance::Can1), &too_fast, &[], &[]).contains(ConfigErrors::CLOCK_NOT_ON_CHIP)
    );
    // No Can0 on a Teensy 4; no alternate pins either.
    assert_eq!(
        check(t41(Instance::Can0), &rt, &[], &[]),
        ConfigErrors::NO_SUCH_INSTANCE
    );
    let mut alt = rt;
    alt.use_alternate_tx_pin = true;
    alt.use_alternate_rx_pin = true;
    assert_eq!(
        check(t41(Instance::Can3), &alt, &[], &[]),
        ConfigErrors::NO_ALTERNATE_TX_PIN | ConfigErrors::NO_ALTERNATE_RX_PIN
    );
    // begin refuses without a single write.
    let mut sys = HostSystem::new();
    let model = model_of(t41(Instance::Can1));
    let e = FlexCan::<_, Imxrt1062>::begin_with_layout(
        Ticking::new(model.clone()),
        &mut sys,
        t41(Instance::Can1),
        &kinetis_clock,
        &[],
        &[],
    )
    .unwrap_err();
    assert_eq!(e, BeginError::Config(ConfigErrors::CLOCK_NOT_ON_CHIP));
    assert!(sys.written().is_empty());
    assert_eq!(
        model.mode(),
        twocan_flexcan::model::ModelMode::Freeze,
        "RT1062 reset state untouched"
    );
}

#[test]
fn bit_rates_from_each_root() {
    // 1 Mbit/s needs at least 16 bus clocks per bit: with the bus clock defaulting to the
    // CAN clock, every root gives it exactly (24, 60 and 80 MHz are multiples of 8 MHz).
    for root in [
        ClockRoot::OSC_24MHZ,
        ClockRoot::PLL3_60MHZ,
        ClockRoot::PLL3_80MHZ,
    ] {
        for rate in [1_000_000, 500_000, 250_000, 125_000, 50_000] {
            let s = Settings::with_clock(rate, CanClock::Imxrt(root));
            assert!(s.exact_bit_rate(), "{root:?} {rate}");
            assert_eq!(
                check(T41[2], &s, &[Filter::pass_all()], &[]),
                ConfigErrors::NONE,
                "{root:?} {rate}"
            );
        }
    }
}

/// With a Teensy 4 board feature: the typed pins' pads are the ones `begin` muxes.
#[cfg(any(feature = "teensy40", feature = "teensy41"))]
#[test]
fn typed_pins_are_the_pads_begin_muxes() {
    use twocan_flexcan::pin::{self, RxPin, TxPin};
    use twocan_flexcan::{Can1, Can2, Can3};

    fn check_pins<I, T: TxPin<I>, X: RxPin<I>>(instance: Instance, tx: T, rx: X) {
        let target = Target::new(Board::DEFAULT, instance);
        let s = pin::settings_for(&rt_loop_back(250_000, CanClock::IMXRT_24MHZ), tx, rx);
        let mut sys = HostSystem::new();
        let c = FlexCan::<_, Imxrt1062>::begin_with_layout(
            Ticking::new(model_of(target)),
            &mut sys,
            target,
            &s,
            &[],
            &[],
        )
        .unwrap();
        let plan = *c.system().imxrt().unwrap();
        assert_eq!((plan.tx.0, plan.rx.0), (T::PIN, X::PIN));
        assert_eq!(sys.read32(T::PIN.mux), T::PIN.alt);
        assert_eq!(sys.read32(X::PIN.mux), X::PIN.alt);
        let (select, value) = X::PIN.daisy.unwrap();
        assert_eq!(sys.read32(select), value);
    }
    check_pins::<Can1, _, _>(Instance::Can1, pin::Pin22, pin::Pin23);
    check_pins::<Can2, _, _>(Instance::Can2, pin::Pin1, pin::Pin0);
    check_pins::<Can3, _, _>(Instance::Can3, pin::Pin31, pin::Pin30);
}

/// The Rx FIFO sizes per chip ([`twocan_flexcan::Chip`]) against the RT1062 model
/// (written from the reference manual's table "Rx FIFO filter: possible structures"):
/// the largest table fits the module with room left for transmit mailboxes, its
/// individually masked elements are the model's; the chip accepts RFFN 0xF
/// (`driver_rt1062_large.rs` runs those tables), and the default layout (ACAN's,
/// MB0–MB15) is what the running controller reports: 14/18 at most, `IMASK2` = 0, a
/// larger table refused with a typed error.
#[test]
fn rx_fifo_sizes_are_data_per_chip_and_the_accepted_limit_is_reported() {
    use twocan_flexcan::{Chip, Configuration};
    for target in T41 {
        let model = model_of(target);
        let variant = model.variant();
        let chip = target.board.chip();
        assert_eq!(chip, Chip::Imxrt1062);
        assert_eq!(chip.message_buffers(), model.message_buffers());
        let rffn = u32::from(chip.max_rffn());
        assert!(rffn <= variant.max_rffn(), "{target:?}");
        assert_eq!(
            chip.max_primary_filters(),
            variant.rx_fifo_individually_masked(rffn),
            "{target:?}"
        );
        assert_eq!(
            chip.max_table_elements(),
            twocan_flexcan::model::Variant::rx_fifo_filters(rffn)
        );
        assert_eq!(
            (chip.max_primary_filters(), chip.max_secondary_filters()),
            (32, 96)
        );

        // The chip accepts its largest table; the default layout ACAN's 14/18, and the
        // capabilities say so.
        assert_eq!(chip.accepted_max_rffn(), chip.max_rffn());
        assert_eq!(chip.accepted_max_rffn(), 0xF);
        let mut settings = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
        settings.configuration = Configuration::Filters14_18;
        let primary: Vec<Filter> = (0..14u32)
            .map(|i| Filter::standard(0x100 + i as u16))
            .collect();
        let secondary: Vec<Filter> = (0..18u32)
            .map(|i| Filter::standard(0x200 + i as u16))
            .collect();
        let (_, can) = begin_rt_on_exact::<32, 16>(target, &settings, &primary, &secondary)
            .unwrap_or_else(|e| panic!("{target:?}: {e:?}"));
        let caps = can.hardware().capabilities();
        assert_eq!(
            (caps.max_standard_filters, caps.max_extended_filters),
            (32, 32),
            "{target:?}"
        );
        let r = can.hardware().registers();
        // The RT1062 layout: 14/18's data mailbox after the ERR005829 reserved one.
        assert_eq!(
            mcr::MAXMB.get(r.read32(regs::MCR)) as usize,
            <Imxrt1062 as Layout>::data_mailbox(Configuration::Filters14_18) as usize
        );
        assert_eq!(r.read32(regs::IMASK2), 0);
        // One filter more than 14/18 holds is refused, with the ACAN errors.
        let more: Vec<Filter> = (0..19u32)
            .map(|i| Filter::standard(0x200 + i as u16))
            .collect();
        let e = begin_rt_on_exact::<32, 16>(target, &settings, &primary, &more)
            .map(|_| ())
            .unwrap_err();
        assert!(
            matches!(e, BeginError::Config(c) if c.contains(ConfigErrors::TOO_MANY_SECONDARY_FILTERS)),
            "{e:?}"
        );
        // The Kinetis layout (the default type) is not the RT1062's: a typed error, from
        // `check_with_layout` and from `begin` alike, nothing written; `check` answers
        // for the chip's own layout.
        let expected = ConfigErrors::LAYOUT_NOT_FOR_CHIP;
        assert_eq!(
            twocan_flexcan::begin::check_with_layout::<twocan_flexcan::layout::Kinetis>(
                target, &settings, &primary, &secondary
            ),
            expected
        );
        assert_eq!(
            check(target, &settings, &primary, &secondary),
            ConfigErrors::NONE
        );
        let model = model_of(target);
        let mut sys = HostSystem::new();
        let e = FlexCan::begin(
            Ticking::new(model.clone()),
            &mut sys,
            target,
            &settings,
            &primary,
            &secondary,
        )
        .map(|_| ())
        .unwrap_err();
        assert_eq!(e, BeginError::Config(expected), "{target:?}");
        assert!(sys.written().is_empty());
        // A table above RFFN 3 in the RT1062 layout: accepted.
        settings.configuration = Configuration::Filters16_24;
        assert_eq!(
            check(target, &settings, &primary, &secondary),
            ConfigErrors::NONE
        );
        begin_rt_on_exact::<32, 16>(target, &settings, &primary, &secondary)
            .unwrap_or_else(|e| panic!("{target:?}: {e:?}"));
    }
}
