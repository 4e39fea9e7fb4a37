//! The two parts whose instances are laid out least like the boards', through the driver
//! and the model from their chip data (`twocan_bxcan::chip`):
//!
//! - **STM32F105/F107** (connectivity line; RM0008 §24.2 "Dual CAN"): CAN1 and CAN2
//!   share CAN1's 28 filter banks, split at `CAN_FMR.CAN2SB` (0 gives CAN1 none, 28 gives
//!   CAN2 none; RM0008 §24.9.5), CAN1's lines 19..=22 and CAN2's 63..=66 (§10.1.2,
//!   connectivity-line vector table), APB1 at most 36 MHz (DS6014);
//! - **STM32F413/F423** (RM0430 §32.2 Table 219): CAN1 and CAN2 sharing 28 banks as
//!   above, and CAN3, a master with its own 14 banks at 0x4000_6C00, `CAN3EN` bit 27 of
//!   `RCC_APB1ENR`, lines 74..=77 (RM0430 §10.2), APB1 at most 50 MHz (DS11581).
//!
//! The expected values are written here from those manuals, not read from the table.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_bxcan::chip::{self, Chip};
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{self, Instance};
use twocan_bxcan::{BxCan, Can, Config, FifoPolicy, Init, PlanError};
use twocan_core::{Driver, Filter, Format, FrameKind, Registers};

type Node<F> = Driver<BxCan<Clocked, F>, 16, 8, 16>;

/// 500 kbit/s from the part's highest APB1 clock, for `chip`.
fn config_for(chip: &'static Chip) -> Config {
    Config::from_bitrate(chip.apb1_max_hz, BITRATE)
        .unwrap()
        .chip(chip)
        .unwrap()
}

/// `n` extended mask filters that no bank can share (one 32-bit mask bank each).
fn wide_filters(n: usize) -> Vec<Filter> {
    (0..n as u32)
        .map(|i| Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_FFF0, i << 8))
        .collect()
}

/// The planner of `init` accepts as many one-bank filters as it owns banks, and refuses
/// one more with the count it owns.
fn plans_up_to<F: Registers>(init: &Init<Clocked, F>, banks: usize, what: &str) {
    assert_eq!(init.can().bank_range().1 - init.can().bank_range().0, banks);
    if banks > 0 {
        assert!(
            init.can()
                .plan(&wide_filters(banks), FifoPolicy::Fifo0)
                .is_ok(),
            "{what}"
        );
    }
    assert_eq!(
        init.can().plan(&wide_filters(banks + 1), FifoPolicy::Fifo0),
        Err(PlanError::TooManyBanks {
            needed: banks as u16 + 1,
            available: banks as u8
        }),
        "{what}"
    );
}

/// Installs `accept` (one filter per identifier, in this order) and starts the driver.
fn start<F: Registers>(mut init: Init<Clocked, F>, accept: &[u16]) -> Node<F> {
    let list: Vec<Filter> = accept.iter().map(|&id| Filter::standard(id)).collect();
    let plan = init.can().plan(&list, FifoPolicy::Fifo0).unwrap();
    init.set_filters(&plan).unwrap();
    Driver::new(init.enable().map_err(|f| f.error).unwrap().into_split())
}

/// What a node received: (identifier, the index of the node's own filter).
fn received<F: Registers>(d: &mut Node<F>) -> Vec<(u16, usize)> {
    d.on_interrupt();
    let mut got = Vec::new();
    while let Ok(f) = d.receive() {
        let id = match f.frame.id() {
            embedded_can::Id::Standard(s) => s.as_raw(),
            embedded_can::Id::Extended(_) => panic!("an extended frame"),
        };
        got.push((id, f.filter as usize));
    }
    got
}

#[test]
fn the_f105_f107_and_f413_f423_facts_are_the_manuals() {
    let f105 = &chip::STM32F105_F107;
    let lines =
        |c: &Chip, i: Instance| -> Vec<u16> { (0..4).filter_map(|l| c.irq(i, l)).collect() };
    assert_eq!(
        f105.instances
            .iter()
            .map(|i| i.instance)
            .collect::<Vec<_>>(),
        [Instance::Can1, Instance::Can2]
    );
    assert!(f105.dual() && !f105.has(Instance::Can3));
    assert_eq!(f105.can1_banks, 28);
    assert_eq!(f105.apb1_max_hz, 36_000_000);
    assert_eq!(lines(f105, Instance::Can1), [19, 20, 21, 22]);
    assert_eq!(lines(f105, Instance::Can2), [63, 64, 65, 66]);
    let can2 = f105.instance(Instance::Can2).unwrap();
    assert_eq!((can2.base, can2.apb1enr_bit), (0x4000_6800, 26));
    // RCC_APB1ENR of the F1 (RM0008 §7.3.8): RCC at 0x4002_1000 + 0x1C.
    assert_eq!(f105.rcc_apb1enr, 0x4002_101C);
    // CAN2's pins: PB12/PB13 (CAN2_REMAP = 0), PB5/PB6 (1) (RM0008 §9.3.3 Table 37).
    let pins: Vec<_> = can2
        .pins
        .iter()
        .map(|p| ((p.rx.port, p.rx.number), (p.tx.port, p.tx.number), p.mux))
        .collect();
    assert_eq!(
        pins,
        [
            (('B', 12), ('B', 13), chip::PinMux::F1Can2Remap(0)),
            (('B', 5), ('B', 6), chip::PinMux::F1Can2Remap(1)),
        ]
    );
    assert!(!f105.sram_shared_with_usb);

    let f413 = &chip::STM32F413_F423;
    assert_eq!(
        f413.instances
            .iter()
            .map(|i| i.instance)
            .collect::<Vec<_>>(),
        [Instance::Can1, Instance::Can2, Instance::Can3]
    );
    assert_eq!(f413.apb1_max_hz, 50_000_000);
    let can3 = f413.instance(Instance::Can3).unwrap();
    assert_eq!((can3.base, can3.apb1enr_bit), (0x4000_6C00, 27));
    assert_eq!(lines(f413, Instance::Can3), [74, 75, 76, 77]);
    assert_eq!(lines(f413, Instance::Can2), [63, 64, 65, 66]);
    assert_eq!(f413.banks_of(Instance::Can1), Some(28));
    assert_eq!(f413.banks_of(Instance::Can3), Some(14));
    // CAN3's block is never split, whatever CAN2SB holds.
    for sb in [0, 14, 28] {
        assert_eq!(f413.bank_range(Instance::Can3, sb), (0, 14));
    }
}

#[test]
fn f105_can1_and_can2_split_the_28_banks_at_every_can2sb() {
    let chip = &chip::STM32F105_F107;
    for sb in [0u8, 1, 10, 14, 27, 28] {
        let bus = new_bus();
        let models = BxCanModel::of_part(chip);
        let (m1, m2) = (models[0].clone(), models[1].clone());
        assert_eq!(
            (m1.instance(), m2.instance()),
            (Instance::Can1, Instance::Can2)
        );
        bus.borrow_mut().attach("can1", m1.clone());
        bus.borrow_mut().attach("can2", m2.clone());
        let cfg1 = config_for(chip).can2_start_bank(sb).unwrap();
        let init1 = Can::can1(Clocked::new(m1.clone(), &bus), &cfg1)
            .map_err(|f| f.error)
            .unwrap();
        let init2 = Can::can2(Clocked::new(m2, &bus), m1.clone(), &config_for(chip))
            .map_err(|f| f.error)
            .unwrap();
        let sb = sb as usize;
        assert_eq!(init1.can().bank_range(), (0, sb), "CAN2SB {sb}");
        assert_eq!(init2.can().bank_range(), (sb, 28), "CAN2SB {sb}");
        plans_up_to(&init1, sb, &format!("CAN1, CAN2SB {sb}"));
        plans_up_to(&init2, 28 - sb, &format!("CAN2, CAN2SB {sb}"));
        assert_eq!(
            regs::fmr::CAN2SB.get(m1.read32(regs::FMR)) as usize,
            sb,
            "CAN2SB written by CAN1's configuration"
        );
        if sb == 0 || sb == 28 {
            continue;
        }
        // Both on the bus, each through its own banks: CAN1 sends 0x101, CAN2 0x202;
        // each accepts the other's identifier as its own filter 1.
        let mut can1 = start(init1, &[0x7F0, 0x202]);
        let fa1r_can1 = m1.read32(regs::FA1R);
        let mut can2 = start(init2, &[0x7F1, 0x101]);
        let fa1r = m1.read32(regs::FA1R);
        assert_eq!(
            fa1r & fa1r_can1,
            fa1r_can1,
            "CAN2's filters leave CAN1's banks"
        );
        let below = (1u32 << sb) - 1;
        assert_eq!(fa1r_can1 & !below, 0, "CAN1's banks lie below CAN2SB {sb}");
        assert_ne!(fa1r & !below, 0, "CAN2's banks lie from CAN2SB {sb}");
        can1.try_send(&std(0x101)).unwrap();
        settle(&bus);
        can2.try_send(&std(0x202)).unwrap();
        settle(&bus);
        assert_eq!(received(&mut can1), [(0x202, 1)], "CAN2SB {sb}");
        assert_eq!(received(&mut can2), [(0x101, 1)], "CAN2SB {sb}");
    }
}

#[test]
fn f413_can1_can2_and_can3_share_one_bus_with_can3_s_own_banks() {
    let chip = &chip::STM32F413_F423;
    let bus = new_bus();
    let models = BxCanModel::of_part(chip);
    let (m1, m2, m3) = (models[0].clone(), models[1].clone(), models[2].clone());
    assert_eq!(m3.instance(), Instance::Can3);
    for (name, m) in [("can1", &m1), ("can2", &m2), ("can3", &m3)] {
        bus.borrow_mut().attach(name, m.clone());
    }
    // CAN1 takes 20 of the shared 28, CAN2 the other 8; CAN3 has 14 of its own.
    let cfg1 = config_for(chip).can2_start_bank(20).unwrap();
    let init1 = Can::can1(Clocked::new(m1.clone(), &bus), &cfg1)
        .map_err(|f| f.error)
        .unwrap();
    let init2 = Can::can2(Clocked::new(m2, &bus), m1.clone(), &config_for(chip))
        .map_err(|f| f.error)
        .unwrap();
    let init3 = Can::can3(Clocked::new(m3.clone(), &bus), &config_for(chip))
        .map_err(|f| f.error)
        .unwrap();
    plans_up_to(&init1, 20, "CAN1");
    plans_up_to(&init2, 8, "CAN2");
    plans_up_to(&init3, 14, "CAN3");
    assert_eq!(init3.can().bank_range(), (0, 14));

    let mut can3 = start(init3, &[0x101, 0x202]);
    let fa1r3 = m3.read32(regs::FA1R);
    assert_ne!(fa1r3, 0);
    assert_eq!(
        m1.read32(regs::FA1R),
        0,
        "CAN3's filters are not in CAN1's block"
    );
    let mut can1 = start(init1, &[0x202, 0x303]);
    let mut can2 = start(init2, &[0x303, 0x101]);
    assert_eq!(
        m3.read32(regs::FA1R),
        fa1r3,
        "CAN1/CAN2's filters leave CAN3's block"
    );
    assert_eq!(
        regs::fmr::CAN2SB.get(m1.read32(regs::FMR)),
        20,
        "CAN2SB as CAN1's configuration wrote it"
    );

    for (d, id) in [(0, 0x101u16), (1, 0x202), (2, 0x303)] {
        let frame = std(id);
        match d {
            0 => can1.try_send(&frame).unwrap(),
            1 => can2.try_send(&frame).unwrap(),
            _ => can3.try_send(&frame).unwrap(),
        };
        settle(&bus);
    }
    // Each receives the two others' frames, numbered by its own filter list.
    assert_eq!(received(&mut can1), [(0x202, 0), (0x303, 1)]);
    assert_eq!(received(&mut can2), [(0x101, 1), (0x303, 0)]);
    assert_eq!(received(&mut can3), [(0x101, 0), (0x202, 1)]);
}
