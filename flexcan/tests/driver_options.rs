//! The controller's compile-time choices (`twocan_flexcan::options`): the lean
//! controller delivers the same frames and completions without time stamps and refuses
//! a filter switch; the transmit interrupt settles one or several mailboxes alike.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_core::{Driver, Error, Filter, Hardware, TxOutcome};
use twocan_flexcan::installed::PlannedTable;
use twocan_flexcan::options::{Full, Lean};
use twocan_flexcan::planner::PlanOptions;
use twocan_flexcan::{
    const_plan, Board, FilterTable, FlexCan, FlexCanHw, HostSystem, Instance, Target,
};

type LeanCan = Driver<FlexCanHw<Ticking, Lean>, 32, 16>;

const FILTERS: [Filter; 2] = [Filter::standard(0x10), Filter::standard(0x20)];

fn lean_begin(plan: PlannedTable) -> (twocan_flexcan::model::FlexCanModel, LeanCan) {
    let model = model_for(Board::Teensy36);
    let hw = FlexCan::begin_planned(
        Ticking::new(model.clone()),
        &mut HostSystem::new(),
        Target::new(Board::Teensy36, Instance::Can0),
        &loop_back(500_000),
        plan,
    )
    .unwrap();
    (model, Driver::new(hw))
}

/// Runs the bus, servicing the lean driver's interrupt after each event.
fn run_lean(bus: &mut twocan_sim::Bus, can: &mut LeanCan, bits: u64) {
    let until = bus.now() + bits;
    loop {
        if can.hardware().registers().irq_pending() {
            can.on_interrupt();
        }
        if bus.step_until(until).is_none() {
            break;
        }
    }
    if can.hardware().registers().irq_pending() {
        can.on_interrupt();
    }
}

#[test]
fn lean_controller_delivers_without_time_stamps() {
    let (model, mut can) = lean_begin(const_plan!(FILTERS, PlanOptions::choose()).planned());
    assert!(!can.hardware().capabilities().modes.timestamps);
    let mut tokens = Vec::new();
    for id in [0x20, 0x10, 0x30] {
        tokens.push(can.try_send(&std_data(id, &[id as u8])).unwrap());
    }
    let mut bus = bus_with(500_000, &[&model]);
    run_lean(&mut bus, &mut can, 2_000);
    let got: Vec<_> = core::iter::from_fn(|| can.receive().ok()).collect();
    let seen: Vec<(u32, u16, Option<_>)> = got
        .iter()
        .map(|rx| (rx.frame.raw_id(), rx.filter, rx.timestamp))
        .collect();
    // 0x30 passes no filter; the others come back with their filter and no stamp.
    assert_eq!(seen, vec![(0x20, 1, None), (0x10, 0, None)]);
    let done: Vec<_> = core::iter::from_fn(|| can.take_completion()).collect();
    assert_eq!(done.len(), 3);
    for (c, t) in done.iter().zip(&tokens) {
        assert_eq!(
            (c.token, c.outcome, c.timestamp),
            (*t, TxOutcome::Sent, None)
        );
    }
}

#[test]
fn lean_controller_refuses_a_filter_switch() {
    let (model, mut can) = lean_begin(const_plan!(FILTERS, PlanOptions::choose()).planned());
    let c = can.hardware().configuration();
    let table = FilterTable::compile(c, &[Filter::standard(0x20)], &[]).unwrap();
    assert_eq!(can.set_filters(&table), Err(Error::Unsupported));
    // The list `begin` installed stays in force.
    can.try_send(&std_data(0x10, &[])).unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    run_lean(&mut bus, &mut can, 1_000);
    let rx = can.receive().unwrap();
    assert_eq!((rx.frame.raw_id(), rx.filter), (0x10, 0));
}

#[test]
fn full_controller_stamps_what_the_lean_one_does_not() {
    let (model, mut can) = begin::<32, 16>(&loop_back(500_000), &[], &[]).unwrap();
    assert!(can.hardware().capabilities().modes.timestamps);
    let _: &FlexCanHw<Ticking, Full> = can.hardware();
    can.try_send(&std_data(0x10, &[])).unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    run1(&mut bus, &mut can, 1_000);
    assert!(can.receive().unwrap().timestamp.is_some());
    assert!(can.take_completion().unwrap().timestamp.is_some());
}

/// Several transmit mailboxes ended before the interrupt is serviced: one interrupt
/// settles them all, each once, in the order they were requested (token order, not
/// mailbox order), and leaves every mailbox empty.
#[test]
fn several_mailboxes_settled_by_one_interrupt_in_request_order() {
    use twocan_core::{AbortRequest, Mode};
    use twocan_flexcan::regs::{self, IFLAG1};
    let (model, mut can) = begin::<32, 16>(&loop_back(500_000), &[], &[]).unwrap();
    let c = can.hardware().configuration();
    let r = c.remote_mailbox_count() as usize;
    assert!(r >= 3);
    let first = c.first_remote_mailbox() as usize;
    let mask = 0b111 << first;
    // Frozen: the mailboxes are loaded (MB first, first + 1, first + 2, in request
    // order) and wait.
    can.set_mode(Mode::Stopped).unwrap();
    let mut tokens = [
        can.try_send_now(&remote(0x300, false)).unwrap(),
        can.try_send_now(&remote(0x100, false)).unwrap(),
        can.try_send_now(&remote(0x200, false)).unwrap(),
    ];
    // The first one aborted and settled: its mailbox takes a later request, so that
    // mailbox order is no longer request order.
    assert_eq!(can.abort(tokens[0]), AbortRequest::Requested);
    can.on_interrupt();
    let aborted = can.take_completion().unwrap();
    assert_eq!(
        (aborted.token, aborted.outcome),
        (tokens[0], TxOutcome::Aborted)
    );
    tokens[0] = can.try_send_now(&remote(0x050, false)).unwrap();
    assert_eq!(cs_code(&model, first), regs::code::TX_DATA);
    can.set_mode(Mode::Normal).unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    bus.run_for(2_000); // no interrupt serviced meanwhile
    assert_eq!(model.peek32(IFLAG1) & mask, mask, "all three ended");
    can.on_interrupt();
    let done: Vec<_> = core::iter::from_fn(|| can.take_completion()).collect();
    let got: Vec<_> = done.iter().map(|c| (c.token, c.outcome)).collect();
    let mut want: Vec<_> = tokens.iter().map(|t| (*t, TxOutcome::Sent)).collect();
    want.sort_by_key(|(t, _)| t.0);
    assert_ne!(
        want.iter().map(|w| w.0).collect::<Vec<_>>(),
        tokens,
        "a real reordering"
    );
    assert_eq!(got, want);
    assert_eq!(can.traffic().sent, 3);
    for mb in 0..=r {
        assert_eq!(
            can.mailbox_state(twocan_core::MailboxId(mb as u8)),
            twocan_core::MailboxState::Empty
        );
    }
}

fn cs_code(model: &twocan_flexcan::model::FlexCanModel, mb: usize) -> u32 {
    use twocan_flexcan::regs::{self, cs};
    cs::CODE.get(model.peek32(regs::mb_cs(mb)))
}

/// A `const` plan written by `begin_planned` and the run-time planner's table for the
/// same list (installed with `set_filters`) leave the same register contents: the ID
/// table, the individual masks, `RXFGMASK` and `MCR.IDAM`; and resolve frames alike.
#[test]
fn const_plan_and_runtime_planner_write_the_same_registers() {
    use twocan_flexcan::planner;
    use twocan_flexcan::regs::{self, MCR, RXFGMASK};
    const LIST: [Filter; 4] = [
        Filter::standard(0x100),
        Filter::standard(0x101),
        Filter::extended(0x18FE_F100),
        Filter::standard(0x7F0),
    ];
    const OPTIONS: PlanOptions = PlanOptions::choose();
    let planned = const_plan!(LIST, OPTIONS).planned();
    let (a, mut lean) = lean_begin(planned);
    let runtime = planner::plan(&LIST, OPTIONS).unwrap();
    assert_eq!(runtime.configuration(), planned.configuration());
    let mut settings = loop_back(500_000);
    settings.configuration = runtime.configuration();
    let (b, mut full) = begin::<32, 16>(&settings, &[Filter::pass_all()], &[]).unwrap();
    full.set_filters(&runtime).unwrap();
    let c = planned.configuration();
    let words = |m: &twocan_flexcan::model::FlexCanModel| {
        let mut w: Vec<u32> = (0..c.table_elements())
            .map(|i| m.peek32(regs::rx_fifo_filter(i)))
            .collect();
        w.extend((0..c.primary_filter_capacity()).map(|i| m.peek32(regs::rximr(i))));
        w.push(m.peek32(RXFGMASK));
        w.push(regs::mcr::IDAM.get(m.peek32(MCR)));
        w
    };
    assert_eq!(words(&a), words(&b));
    // The same frames come back with the same filter index.
    let frames = [0x100u16, 0x101, 0x102, 0x7F0];
    let mut bus_a = bus_with(500_000, &[&a]);
    let mut bus_b = bus_with(500_000, &[&b]);
    for id in frames {
        lean.try_send(&std_data(id, &[])).unwrap();
        full.try_send(&std_data(id, &[])).unwrap();
    }
    full.try_send(&ext_data(0x18FE_F100, &[1])).unwrap();
    lean.try_send(&ext_data(0x18FE_F100, &[1])).unwrap();
    run_lean(&mut bus_a, &mut lean, 3_000);
    run1(&mut bus_b, &mut full, 3_000);
    let got_a: Vec<_> = core::iter::from_fn(|| lean.receive().ok())
        .map(|rx| (rx.frame.raw_id(), rx.filter))
        .collect();
    let got_b: Vec<_> = drain(&mut full)
        .iter()
        .map(|rx| (rx.frame.raw_id(), rx.filter))
        .collect();
    assert_eq!(got_a, got_b);
    assert_eq!(
        got_a,
        vec![(0x100, 0), (0x101, 1), (0x7F0, 3), (0x18FE_F100, 2)]
    );
}

/// Settings checked in `const` evaluation ([`twocan_flexcan::BeginPlan`]) give the same
/// controller as `begin_planned`; the checks refuse what `begin` refuses; a table of
/// another configuration than the checked one is refused before any register is written.
#[test]
fn settings_checked_at_compile_time() {
    use twocan_flexcan::{check, BeginError, BeginPlan, ConfigErrors, Configuration};
    const T: Target = Target::new(Board::Teensy36, Instance::Can0);
    const SETTINGS: twocan_flexcan::Settings = {
        let mut s = twocan_flexcan::Settings::new(500_000);
        s.loop_back = true;
        s.self_reception = true;
        s
    };
    const PLAN: PlannedTable = const_plan!(FILTERS, PlanOptions::choose()).planned();
    const CHECKED: BeginPlan = BeginPlan::new_or_panic(T, &SETTINGS, PLAN.configuration());
    let model = model_for(Board::Teensy36);
    let hw: FlexCanHw<Ticking, Lean> = FlexCan::begin_checked(
        Ticking::new(model.clone()),
        &mut HostSystem::new(),
        &CHECKED,
        PLAN,
    )
    .unwrap();
    let mut can: LeanCan = Driver::new(hw);
    can.try_send(&std_data(0x20, &[])).unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    run_lean(&mut bus, &mut can, 1_000);
    assert_eq!(can.receive().map(|rx| rx.filter), Ok(1));

    // Refused as `begin` refuses them, with the same flags.
    let bad = SETTINGS;
    let t35_can1 = Target::new(Board::Teensy35, Instance::Can1); // no such module
    let want = check(t35_can1, &bad, &[], &[]);
    assert_eq!(want, ConfigErrors::NO_SUCH_INSTANCE);
    assert_eq!(
        BeginPlan::new(t35_can1, &bad, Configuration::Filters8_0).err(),
        Some(BeginError::Config(want))
    );
    // A table of another configuration: nothing written.
    let other = BeginPlan::new(T, &SETTINGS, Configuration::Filters14_18).unwrap();
    assert_ne!(other.configuration(), PLAN.configuration());
    let model = model_for(Board::Teensy36);
    let before = model.peek32(twocan_flexcan::regs::MCR);
    let r: Result<FlexCanHw<Ticking, Lean>, _> = FlexCan::begin_checked(
        Ticking::new(model.clone()),
        &mut HostSystem::new(),
        &other,
        PLAN,
    );
    assert_eq!(
        r.err(),
        Some(BeginError::Hardware(twocan_core::Error::InvalidArgument))
    );
    assert_eq!(model.peek32(twocan_flexcan::regs::MCR), before);
}

/// `begin_in` compiles into a `static` slot; the controller keeps the reference, takes
/// filter switches and stamps as the owned-table controller does; an error gives the
/// slot back.
#[test]
fn table_in_a_static_slot() {
    use twocan_flexcan::filters::TableSlot;
    use twocan_flexcan::options::FullInSlot;
    static TABLE: TableSlot = TableSlot::new();
    let model = model_for(Board::Teensy36);
    let target = Target::new(Board::Teensy36, Instance::Can0);
    let slot = TABLE.take().unwrap();
    assert!(TABLE.take().is_none());
    // Refused first (no such module on a Teensy 3.5): the slot comes back.
    let bad = Target::new(Board::Teensy35, Instance::Can1);
    let r: Result<FlexCanHw<Ticking, FullInSlot>, _> = FlexCan::begin_in(
        Ticking::new(model.clone()),
        &mut HostSystem::new(),
        bad,
        &loop_back(500_000),
        &[Filter::standard(0x10)],
        &[],
        slot,
    );
    let Err((twocan_flexcan::BeginError::Config(_), slot)) = r else {
        panic!("refused with the slot back");
    };
    let hw: FlexCanHw<Ticking, FullInSlot> = FlexCan::begin_in(
        Ticking::new(model.clone()),
        &mut HostSystem::new(),
        target,
        &loop_back(500_000),
        &[Filter::standard(0x10)],
        &[],
        slot,
    )
    .map_err(|(e, _)| e)
    .unwrap();
    let mut can: Driver<FlexCanHw<Ticking, FullInSlot>, 32, 16> = Driver::new(hw);
    let mut bus = bus_with(500_000, &[&model]);
    let table = FilterTable::compile(
        can.hardware().configuration(),
        &[Filter::standard(0x20)],
        &[Filter::standard(0x10)],
    )
    .unwrap();
    can.set_filters(&table).unwrap();
    for id in [0x10, 0x20, 0x30] {
        can.try_send(&std_data(id, &[])).unwrap();
    }
    let until = bus.now() + 1_000;
    loop {
        if can.hardware().registers().irq_pending() {
            can.on_interrupt();
        }
        if bus.step_until(until).is_none() {
            break;
        }
    }
    if can.hardware().registers().irq_pending() {
        can.on_interrupt();
    }
    let got: Vec<_> = core::iter::from_fn(|| can.receive().ok())
        .map(|rx| (rx.frame.raw_id(), rx.filter, rx.timestamp.is_some()))
        .collect();
    assert_eq!(got, vec![(0x10, 1, true), (0x20, 0, true)]);
}
