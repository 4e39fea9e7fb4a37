//! The in-place constructors (`BxCan::can1_in` through `State::split_with`, issue 21):
//! the same registers as the by-value path (`Can::can1`, `set_filters`, `enable`,
//! `into_split`) for a `const` plan and a run-time plan of the same list, frames in and
//! out with their filter index, and every failure handing the slot and the registers
//! back (a retry after a timeout works).
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_bxcan::regs::{BTR, FA1R, FFA1R, FM1R, FMR, FS1R, IER, MCR};
use twocan_bxcan::{const_plan, BxCan, Can, PlanOptions};
use twocan_core::split::State;
use twocan_core::{
    Error, FifoQueue, Filter, Format, Frame, FrameKind, Hardware, Registers, TxPolicy,
};

const FILTERS: [Filter; 4] = [
    Filter::standard(0x100),
    Filter::standard(0x101),
    Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_FF00, 0x0001_2300),
    Filter::exact(FrameKind::Remote, Format::Standard, 0x542),
];

/// The configuration and filter registers (CAN1's whole block but the status ones).
fn config_registers(r: &Clocked) -> Vec<u32> {
    let mut v: Vec<u32> = [MCR, IER, BTR, FMR, FM1R, FS1R, FFA1R, FA1R]
        .iter()
        .map(|&o| r.model.read32(o))
        .collect();
    v.extend((0x240..0x320).step_by(4).map(|o| r.model.read32(o)));
    v
}

fn attached() -> (Clocked, SharedBus) {
    let bus = new_bus();
    let model = twocan_bxcan::model::BxCanModel::can1();
    bus.borrow_mut().attach("can1", model.clone());
    (Clocked::new(model, &bus), bus)
}

#[test]
fn in_place_writes_what_the_by_value_path_writes_and_moves_frames() {
    let config = loopback_config(TxPolicy::Fifo);
    const OPTIONS: PlanOptions = PlanOptions::new(14);
    let plan = const_plan!(FILTERS, OPTIONS);
    let runtime = twocan_bxcan::plan(&FILTERS, OPTIONS).unwrap();
    assert_eq!(
        plan.as_ref(),
        runtime.as_ref(),
        "const and run-time plans agree"
    );

    // By value.
    let (regs_v, _bus_v) = attached();
    let mut init = Can::can1(regs_v.clone(), &config)
        .map_err(|f| f.error)
        .unwrap();
    init.set_filters(&runtime).unwrap();
    let by_value = init.enable().map_err(|f| f.error).unwrap().into_split();

    // In place, with the map sized to the plan (no lookup key).
    let (regs, bus) = attached();
    let state: State<BxCan<Clocked, Clocked, 0>, 8, FifoQueue<4>, 0, 4> = State::new();
    let mut p = state
        .split_with(|slot| BxCan::can1_in(slot, regs.clone(), &config, plan).map_err(|f| f.error))
        .ok()
        .unwrap();
    assert_eq!(config_registers(&regs), config_registers(&regs_v));
    let hw = state.hardware().unwrap();
    assert_eq!(hw.mode(), by_value.mode());
    assert_eq!(hw.fed_rx_queues(), by_value.fed_rx_queues());

    let frames = [
        (Frame::standard(0x101, &[1]).unwrap(), 1),
        (Frame::extended(0x1_2345, &[2; 8]).unwrap(), 2),
        (Frame::remote(0x542, false, 0).unwrap(), 3),
        (Frame::standard(0x100, &[]).unwrap(), 0),
    ];
    for (f, _) in &frames {
        nb::block!(p.tx.try_send(f)).unwrap();
        run(&bus, 200);
        p.tx_irq.on_interrupt();
        p.rx0_irq.on_interrupt();
    }
    run(&bus, 500);
    p.tx_irq.on_interrupt();
    p.rx0_irq.on_interrupt();
    for (f, index) in &frames {
        let rx = p.rx.receive().unwrap();
        assert_eq!((&rx.frame, rx.filter), (f, *index));
    }
    assert_eq!(state.traffic().sent, 4);
}

#[test]
fn failures_hand_the_slot_and_registers_back_and_a_retry_works() {
    let config = loopback_config(TxPolicy::Fifo);
    let (regs, _bus) = attached();
    let mut slot = core::mem::MaybeUninit::<BxCan<Clocked, Clocked, 0>>::uninit();

    // A plan needing a lookup key does not fit K = 0: refused before any bank changes.
    let merged = twocan_bxcan::plan(
        &[
            Filter::standard(0x100),
            Filter::standard(0x102),
            Filter::standard(0x104),
            Filter::standard(0x106),
            Filter::standard(0x108),
        ],
        PlanOptions::new(1),
    )
    .unwrap();
    assert!(!merged.key_table().is_empty(), "one bank for five: merged");
    let f = BxCan::can1_in(&mut slot, regs.clone(), &config, &merged)
        .err()
        .unwrap();
    assert!(matches!(f.error, Error::FilterSpace { available: 0, .. }));
    assert_eq!(regs.model.read32(FA1R), 0, "no bank was activated");
    let back = f.value;

    // No acknowledge: a timeout, everything back; then a retry with the same slot.
    regs.model.set_ack_stuck(true);
    let plan = const_plan!([Filter::pass_all()], PlanOptions::new(14));
    let f = BxCan::can1_in(back.slot, back.regs, &config, plan)
        .err()
        .unwrap();
    assert_eq!(f.error, Error::Timeout);
    regs.model.set_ack_stuck(false);
    let back = f.value;
    let hw = BxCan::can1_in(back.slot, back.regs, &config, plan)
        .map_err(|f| f.error)
        .unwrap();
    assert_eq!(hw.mode(), twocan_core::Mode::Normal);
}

/// A map sized to the `const` plan (`M` = its match indices, issue 21): the same user
/// indices as the full-size map, a fraction of its bytes, and a later list that numbers
/// more match indices than it holds refused with a typed error, the old filters kept.
#[test]
fn a_map_sized_to_the_const_plan_resolves_and_refuses_a_larger_list() {
    const OPTIONS: PlanOptions = PlanOptions::new(14);
    const M: usize = const_plan!(FILTERS, OPTIONS).match_indices();
    let runtime = twocan_bxcan::plan(&FILTERS, OPTIONS).unwrap();
    assert_eq!(M, runtime.match_indices());
    assert!((1..twocan_bxcan::filters::MAX_FMI).contains(&M), "{M}");
    assert!(
        size_of::<twocan_bxcan::filters::FmiMap<0, M>>() * 8
            <= size_of::<twocan_bxcan::filters::FmiMap<0>>(),
        "the sized map is at most an eighth of the full one"
    );
    // The map's own capacity check: the plan fits exactly, one fewer is refused.
    assert!(runtime.fmi_map_sized::<0, M>().is_ok());
    assert_eq!(
        runtime.fmi_map_sized::<0, { M - 1 }>(),
        Err(twocan_bxcan::filters::PlanError::TooManyMatchIndices {
            needed: M as u16,
            max: M as u16 - 1
        })
    );

    let config = loopback_config(TxPolicy::Fifo);
    let (regs, bus) = attached();
    let state: State<BxCan<Clocked, Clocked, 0, M>, 8, FifoQueue<4>, 0, 4> = State::new();
    let mut p = state
        .split_with(|slot| {
            BxCan::can1_in(slot, regs.clone(), &config, const_plan!(FILTERS, OPTIONS))
                .map_err(|f| f.error)
        })
        .ok()
        .unwrap();

    // Sixteen exact identifiers: more match indices than the map holds.
    let larger: Vec<Filter> = (0..16u16)
        .map(|k| Filter::standard(0x013 + 0x71 * k))
        .collect();
    let larger = twocan_bxcan::plan(&larger, OPTIONS).unwrap();
    assert!(
        larger.match_indices() > M,
        "{} vs {M}",
        larger.match_indices()
    );
    let larger = twocan_bxcan::FilterPlan::<0>::from_ref(larger.as_ref()).unwrap();
    assert!(matches!(
        p.rx.set_filters(&larger),
        Err(Error::FilterSpace { .. })
    ));

    // The old list still in force, each frame with its user index.
    let frames = [
        (Frame::extended(0x1_2345, &[2; 8]).unwrap(), 2),
        (Frame::standard(0x101, &[1]).unwrap(), 1),
        (Frame::remote(0x542, false, 0).unwrap(), 3),
    ];
    for (f, _) in &frames {
        nb::block!(p.tx.try_send(f)).unwrap();
        run(&bus, 200);
        p.tx_irq.on_interrupt();
        p.rx0_irq.on_interrupt();
    }
    for (f, index) in &frames {
        let rx = p.rx.receive().unwrap();
        assert_eq!((&rx.frame, rx.filter), (f, *index));
    }
}

/// Filters fixed (`SWITCH` = false, issue 21): frames arrive with their user indices and
/// no generation is read or checked; a new list is refused with `Unsupported` and the
/// old one stays in force.
#[test]
fn fixed_filters_refuse_a_switch_and_keep_receiving() {
    const OPTIONS: PlanOptions = PlanOptions::new(14);
    const M: usize = const_plan!(FILTERS, OPTIONS).match_indices();
    let config = loopback_config(TxPolicy::Fifo);
    let (regs, bus) = attached();
    let state: State<BxCan<Clocked, Clocked, 0, M, false>, 8, FifoQueue<4>, 0, 4> = State::new();
    let mut p = state
        .split_with(|slot| {
            BxCan::can1_in(slot, regs.clone(), &config, const_plan!(FILTERS, OPTIONS))
                .map_err(|f| f.error)
        })
        .ok()
        .unwrap();
    let same =
        twocan_bxcan::FilterPlan::<0>::from_ref(const_plan!(FILTERS, OPTIONS).as_ref()).unwrap();
    assert_eq!(p.rx.set_filters(&same), Err(Error::Unsupported));
    let frames = [
        (Frame::standard(0x100, &[7]).unwrap(), 0),
        (Frame::extended(0x1_2345, &[2; 8]).unwrap(), 2),
    ];
    for (f, _) in &frames {
        nb::block!(p.tx.try_send(f)).unwrap();
        run(&bus, 200);
        p.tx_irq.on_interrupt();
        p.rx0_irq.on_interrupt();
    }
    for (f, index) in &frames {
        let rx = p.rx.receive().unwrap();
        assert_eq!((&rx.frame, rx.filter), (f, *index));
    }
    assert_eq!(state.traffic().rx_dropped, 0);

    // The by-value path gives the same choice.
    let (regs_v, _bus_v) = attached();
    let mut init = Can::can1(regs_v, &config).map_err(|f| f.error).unwrap();
    init.set_filters(&same).unwrap();
    let fixed = init
        .enable()
        .map_err(|f| f.error)
        .unwrap()
        .into_split_fixed();
    let by_value: State<
        BxCan<
            Clocked,
            Clocked,
            { twocan_bxcan::filters::LOOKUP_KEYS },
            { twocan_bxcan::filters::MAX_FMI },
            false,
        >,
        8,
    > = State::new();
    let mut q = by_value.split(fixed).ok().unwrap();
    let same_full =
        twocan_bxcan::FilterPlan::<{ twocan_bxcan::filters::LOOKUP_KEYS }>::from_ref(same.as_ref())
            .unwrap();
    assert_eq!(q.rx.set_filters(&same_full), Err(Error::Unsupported));
}

/// The quiet transmit mode (no completion ring, `Lean`, request order): `CAN_IER.TMEIE`
/// off while nothing is queued, an end left unacknowledged by the direct path, and the
/// way back (`unsplit`) acknowledging it and giving the interrupt back as configured, so
/// that a driver split next with completions reports nothing of this one's frames.
#[test]
fn the_quiet_mode_gives_the_controller_back_acknowledged_with_its_interrupt() {
    use twocan_bxcan::regs::{ier, tsr, TSR};
    use twocan_core::Lean;
    const OPTIONS: PlanOptions = PlanOptions::new(14);
    type Quiet = State<BxCan<Clocked, Clocked, 0>, 8, FifoQueue<4>, 0, 0, Lean>;
    const { assert!(Quiet::QUIET_TX) };
    let config = loopback_config(TxPolicy::Fifo);
    let (regs, bus) = attached();
    let state: Quiet = State::new();
    let p = state
        .split_with(|slot| {
            BxCan::can1_in(slot, regs.clone(), &config, const_plan!(FILTERS, OPTIONS))
                .map_err(|f| f.error)
        })
        .ok()
        .unwrap();
    assert_eq!(regs.model.read32(IER) & ier::TMEIE, 0, "off at split");
    let mut p = p;
    p.tx.try_send(&Frame::standard(0x100, &[1]).unwrap())
        .unwrap();
    run(&bus, 300);
    let tsr_now = regs.model.read32(TSR);
    assert_ne!(tsr_now & tsr::RQCP0, 0, "the end is left unacknowledged");
    assert_eq!(regs.model.read32(IER) & ier::TMEIE, 0, "and raises nothing");
    // A second frame reuses the mailbox without an acknowledgement.
    p.tx.try_send(&Frame::standard(0x100, &[2]).unwrap())
        .unwrap();
    run(&bus, 300);
    let (hw, _) = state.unsplit(p).map_err(|(e, _)| e).unwrap();
    let tsr_back = hw.registers().model.read32(TSR);
    assert_eq!(
        tsr_back & (tsr::RQCP0 | tsr::RQCP1 | tsr::RQCP2),
        0,
        "acknowledged on the way back"
    );
    assert_ne!(hw.registers().model.read32(IER) & ier::TMEIE, 0, "on again");
}
