//! Every part of the chip table (`twocan_bxcan::chip`) through the driver and the model:
//! the instances the part has (and the typed refusal of those it lacks), the banks each
//! instance owns (14 or 28, a single-CAN block never split), the planner's limit and the
//! capabilities' filter counts read from them, the APB1 limit, and a frame through each
//! instance's filters in loop-back.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_bxcan::chip::{self, Chip};
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::Instance;
use twocan_bxcan::{Can, Config, ConfigError, FifoPolicy, PlanError};
use twocan_core::{Driver, Filter, Format, FrameKind, TxPolicy};

/// Loop-back at 500 kbit/s from the part's highest APB1 clock, for `chip`.
fn config_for(chip: &'static Chip) -> Config {
    Config::from_bitrate(chip.apb1_max_hz, BITRATE)
        .unwrap()
        .loopback(true)
        .tx_policy(TxPolicy::Fifo)
        .chip(chip)
        .unwrap()
}

/// `n` extended mask filters that no bank can share (one 32-bit mask bank each).
fn wide_filters(n: u32) -> Vec<Filter> {
    (0..n)
        .map(|i| Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_FFF0, i << 8))
        .collect()
}

fn model(chip: &'static Chip, instance: Instance) -> BxCanModel {
    BxCanModel::of_part(chip)
        .into_iter()
        .find(|m| m.instance() == instance)
        .unwrap()
}

/// Checks an instance in initialization mode owning `banks` banks: the planner's limit,
/// then installs one filter, enables, and receives a matching frame in loop-back (and
/// not a non-matching one); the running driver's capabilities report the banks.
fn exercise<F: twocan_core::Registers>(
    chip: &Chip,
    init: twocan_bxcan::Init<Clocked, F>,
    banks: usize,
    bus: &SharedBus,
) {
    let mut init = init;
    let (s, e) = init.can().bank_range();
    assert_eq!(e - s, banks, "{}", chip.name);
    assert_eq!(
        init.can()
            .plan(&wide_filters(banks as u32 + 1), FifoPolicy::Fifo0),
        Err(PlanError::TooManyBanks {
            needed: banks as u16 + 1,
            available: banks as u8
        }),
        "{}",
        chip.name
    );
    assert!(init
        .can()
        .plan(&wide_filters(banks as u32), FifoPolicy::Fifo0)
        .is_ok());
    let p = init
        .can()
        .plan(&[Filter::standard(0x123)], FifoPolicy::Fifo0)
        .unwrap();
    init.set_filters(&p).unwrap();
    let can = init.enable().map_err(|f| f.error).unwrap();
    let mut d: Driver<_, 16, 8, 16> = Driver::new(can.into_split());
    let caps = d.capabilities();
    assert_eq!(
        caps.max_standard_filters as usize,
        4 * banks,
        "{}",
        chip.name
    );
    assert_eq!(
        caps.max_extended_filters as usize,
        2 * banks,
        "{}",
        chip.name
    );
    d.try_send(&std(0x122)).unwrap();
    d.try_send(&std(0x123)).unwrap();
    settle(bus);
    d.on_interrupt();
    let mut got = Vec::new();
    while let Ok(f) = d.receive() {
        got.push((f.frame, f.filter));
    }
    assert_eq!(got, vec![(std(0x123), 0)], "{}", chip.name);
}

#[test]
fn every_part_single_controllers() {
    for chip in Chip::ALL {
        for c in chip.instances {
            if c.instance == Instance::Can2 {
                continue;
            }
            let bus = new_bus();
            let m = model(chip, c.instance);
            bus.borrow_mut().attach(c.name, m.clone());
            let regs = Clocked::new(m, &bus);
            let cfg = config_for(chip);
            let init = match c.instance {
                Instance::Can3 => Can::can3(regs, &cfg),
                _ => Can::can1(regs, &cfg),
            }
            .map_err(|f| f.error)
            .unwrap();
            // At reset CAN2SB = 14: CAN1 of a dual part owns 14 of 28, a single block
            // (the F103's CAN, CAN3) all 14 of its own.
            exercise(chip, init, 14, &bus);
            let block = if c.instance == Instance::Can3 {
                14
            } else {
                chip.can1_banks
            };
            assert_eq!(chip.banks_of(c.instance), Some(block), "{}", chip.name);
        }
    }
}

#[test]
fn every_dual_part_gives_can1_all_28_banks_or_splits_them() {
    for chip in Chip::ALL.iter().filter(|c| c.dual()) {
        // All 28 to CAN1.
        let bus = new_bus();
        let m = model(chip, Instance::Can1);
        bus.borrow_mut().attach("can1", m.clone());
        let cfg = config_for(chip).can2_start_bank(28).unwrap();
        let init = Can::can1(Clocked::new(m, &bus), &cfg)
            .map_err(|f| f.error)
            .unwrap();
        exercise(chip, init, 28, &bus);

        // Split at 10: CAN2 owns 18, its filters written through CAN1's block.
        let bus = new_bus();
        let models = BxCanModel::of_part(chip);
        let (m1, m2) = (models[0].clone(), models[1].clone());
        assert_eq!(m2.instance(), Instance::Can2);
        bus.borrow_mut().attach("can1", m1.clone());
        bus.borrow_mut().attach("can2", m2.clone());
        let cfg1 = config_for(chip).can2_start_bank(10).unwrap();
        let init1 = Can::can1(Clocked::new(m1.clone(), &bus), &cfg1)
            .map_err(|f| f.error)
            .unwrap();
        assert_eq!(init1.can().bank_range(), (0, 10));
        let init2 = Can::can2(Clocked::new(m2, &bus), m1, &config_for(chip))
            .map_err(|f| f.error)
            .unwrap();
        assert_eq!(init2.can().bank_range(), (10, 28));
        exercise(chip, init2, 18, &bus);
    }
}

#[test]
fn a_missing_instance_is_refused_before_any_register_is_touched() {
    // CAN2 and CAN3 on an F103; CAN3 on an F446 and an F405.
    let cases: [(&'static Chip, Instance); 4] = [
        (&chip::STM32F103, Instance::Can2),
        (&chip::STM32F103, Instance::Can3),
        (&chip::STM32F446, Instance::Can3),
        (&chip::STM32F405_F407, Instance::Can3),
    ];
    for (chip, missing) in cases {
        assert!(!chip.has(missing));
        let bus = new_bus();
        // Registers of some controller (not reached: the refusal comes first).
        let m = BxCanModel::can1();
        let regs = Clocked::new(m.clone(), &bus);
        let before = m.state();
        let cfg = config_for(chip);
        let err = match missing {
            Instance::Can3 => Can::can3(regs, &cfg).map(|_| ()).map_err(|f| f.error),
            _ => Can::can2(regs, m.clone(), &cfg)
                .map(|_| ())
                .map_err(|f| f.error),
        };
        assert_eq!(
            err,
            Err(twocan_core::Error::InvalidArgument),
            "{}",
            chip.name
        );
        assert_eq!(m.state(), before, "{}", chip.name);
    }
}

#[test]
fn start_bank_and_clock_limits_come_from_the_part() {
    // The F103 has no CAN2: CAN2SB is reserved, so no start bank, in either order.
    let base = Config::from_bitrate(36_000_000, BITRATE).unwrap();
    assert_eq!(
        base.chip(&chip::STM32F103)
            .unwrap()
            .can2_start_bank(14)
            .unwrap_err(),
        ConfigError::StartBankOutOfRange
    );
    assert_eq!(
        base.can2_start_bank(14)
            .unwrap()
            .chip(&chip::STM32F103)
            .unwrap_err(),
        ConfigError::StartBankOutOfRange
    );
    assert!(base
        .chip(&chip::STM32F105_F107)
        .unwrap()
        .can2_start_bank(28)
        .is_ok());
    assert_eq!(
        base.chip(&chip::STM32F446)
            .unwrap()
            .can2_start_bank(29)
            .unwrap_err(),
        ConfigError::StartBankOutOfRange
    );
    // Each part's APB1 maximum is accepted, one hertz more is not.
    for chip in Chip::ALL {
        let at = Config::from_bitrate(chip.apb1_max_hz, 250_000).unwrap();
        assert!(at.chip(chip).is_ok(), "{}", chip.name);
        let above = Config::from_bitrate(chip.apb1_max_hz + 1_000_000, 250_000).unwrap();
        assert_eq!(
            above.chip(chip).unwrap_err(),
            ConfigError::ClockAboveChipLimit,
            "{}",
            chip.name
        );
    }
    // A raw CAN_BTR (clock unknown) is not judged against the limit.
    let raw = Config::from_btr(0x001C_0005).unwrap();
    assert!(raw.chip(&chip::STM32F103).is_ok());
    // The default part is the F76x/F77x.
    assert_eq!(base.get_chip(), &chip::STM32F76X_F77X);
}

#[test]
fn the_f103_block_is_whole_whatever_its_reserved_can2sb_bits_hold() {
    // Even if the reserved CAN2SB bits read something else than their reset value,
    // the F103's CAN owns all 14 banks (RM0008 §24.9.4).
    let bus = new_bus();
    let m = model(&chip::STM32F103, Instance::Can1);
    bus.borrow_mut().attach("can", m.clone());
    let init = Can::can1(Clocked::new(m, &bus), &config_for(&chip::STM32F103))
        .map_err(|f| f.error)
        .unwrap();
    assert_eq!(init.can().bank_range(), (0, 14));
    assert_eq!(chip::STM32F103.bank_range(Instance::Can1, 3), (0, 14));
    assert_eq!(chip::STM32F103.plan_options(Instance::Can1).banks, 14);
}

#[test]
fn frames_cross_between_two_blue_pills_and_a_nucleo_f446re() {
    // Three parts on one bus: each CAN receives what the others send, through its
    // own part's bank count.
    let bus = new_bus();
    let a = model(&chip::STM32F103, Instance::Can1);
    let b = model(&chip::STM32F103, Instance::Can1);
    let c = model(&chip::STM32F446, Instance::Can1);
    let mut drivers = Vec::new();
    for (name, m, chip, id) in [
        ("a", a, &chip::STM32F103, 0x10u16),
        ("b", b, &chip::STM32F103, 0x20),
        ("c", c, &chip::STM32F446, 0x30),
    ] {
        bus.borrow_mut().attach(name, m.clone());
        let cfg = Config::from_bitrate(chip.apb1_max_hz, BITRATE)
            .unwrap()
            .chip(chip)
            .unwrap();
        let mut init = Can::can1(Clocked::new(m, &bus), &cfg)
            .map_err(|f| f.error)
            .unwrap();
        let p = init
            .can()
            .plan(&[Filter::pass_all()], FifoPolicy::Fifo0)
            .unwrap();
        init.set_filters(&p).unwrap();
        let can = init.enable().map_err(|f| f.error).unwrap();
        let d: Driver<_, 16, 8, 16> = Driver::new(can.into_split());
        drivers.push((d, id));
    }
    for (d, id) in drivers.iter_mut() {
        d.try_send(&std(*id)).unwrap();
        settle(&bus);
    }
    for (i, (d, own)) in drivers.iter_mut().enumerate() {
        d.on_interrupt();
        let mut got = Vec::new();
        while let Ok(f) = d.receive() {
            got.push(f.frame.id());
        }
        let want: Vec<_> = [0x10u16, 0x20, 0x30]
            .into_iter()
            .filter(|x| x != own)
            .map(|x| std(x).id())
            .collect();
        assert_eq!(got, want, "node {i}");
    }
}
