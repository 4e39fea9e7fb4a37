//! ACAN §17: controller state (error active, passive, bus-off), REC and TEC (256 while
//! bus-off); mode changes with bounded waits; time stamps; pin set-up.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_core::{Error, ErrorCounters, ErrorState, LastErrorCode, Mode};
use twocan_flexcan::model::{FlexCanModel, ModelMode};
use twocan_flexcan::regs::port::{Port, PCR_MUX, PCR_ODE, PCR_PE, PCR_PS};
use twocan_flexcan::regs::sim;
use twocan_flexcan::{Board, FlexCan, HostSystem, Instance, Settings, Target};
use twocan_sim::{Fault, SimNode};

#[test]
fn error_active_after_begin() {
    let (_model, mut can) = begin::<32, 16>(&Settings::new(500_000), &[], &[]).unwrap();
    assert_eq!(can.state(), ErrorState::Active);
    assert_eq!(can.counters(), ErrorCounters { tec: 0, rec: 0 });
    assert_eq!(can.last_error(), LastErrorCode::None);
}

#[test]
fn lone_transmitter_becomes_error_passive() {
    // No other node acknowledges: every attempt is an acknowledge error, TEC += 8
    // until 128 (error passive), then stays (ISO 11898-1 exception 1).
    let (model, mut can) = begin::<32, 16>(&Settings::new(500_000), &[], &[]).unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    can.try_send(&std_data(0x55, &[1])).unwrap();
    run1(&mut bus, &mut can, 5_000);
    assert_eq!(can.state(), ErrorState::Passive);
    assert_eq!(can.counters().tec, 128);
    assert_eq!(can.counters().rec, 0);
    assert_eq!(can.last_error(), LastErrorCode::Acknowledge);
    assert!(can.error_stats().acknowledge >= 1);
    assert!(can.traffic().state_changes >= 1);
    // Another node joins and acknowledges: the frame goes, TEC starts to fall.
    let other = SimNode::new().shared();
    bus.attach("other", other.clone());
    run1(&mut bus, &mut can, 2_000);
    assert_eq!(other.borrow().received_frames(), vec![std_data(0x55, &[1])]);
    assert_eq!(can.counters().tec, 127);
    assert_eq!(can.traffic().sent, 1);
}

#[test]
fn bus_off_then_automatic_recovery() {
    let (model, mut can) = begin::<32, 16>(&Settings::new(500_000), &[], &[]).unwrap();
    let other = SimNode::new().shared();
    let mut bus = twocan_sim::Bus::new(500_000).unwrap();
    let me = bus.attach("can0", model.clone());
    bus.attach("other", other.clone());
    // 32 bit errors in a row: TEC 256, bus-off.
    bus.inject_from(me, 32, Fault::Bit { at: None });
    can.try_send(&std_data(0x66, &[6])).unwrap();
    let mut saw_bus_off = false;
    let until = bus.now() + 4_000;
    while bus.now() < until {
        run1(&mut bus, &mut can, 50);
        if can.state() == ErrorState::BusOff {
            saw_bus_off = true;
            assert_eq!(can.counters().tec, 256, "ACAN §17: 256 when bus-off");
            assert_eq!(
                can.try_send(&std_data(1, &[])),
                Err(nb::Error::Other(Error::BusOff))
            );
            break;
        }
    }
    assert!(saw_bus_off);
    assert_eq!(can.error_stats().bus_off, 1);
    assert!(matches!(
        can.last_error(),
        LastErrorCode::BitDominant | LastErrorCode::BitRecessive
    ));
    // Automatic recovery after 128 × 11 recessive bits; the pending frame then goes.
    run1(&mut bus, &mut can, 128 * 11 + 500);
    assert_ne!(can.state(), ErrorState::BusOff);
    assert_eq!(can.counters().tec, 0);
    assert_eq!(
        can.recover(),
        Err(twocan_core::Error::WrongMode),
        "refused: recovery is automatic (CTRL1.BOFFREC = 0)"
    );
    run1(&mut bus, &mut can, 500);
    assert_eq!(other.borrow().received_frames(), vec![std_data(0x66, &[6])]);
}

#[test]
fn receive_errors_count_rec() {
    let (model, mut can) = begin::<32, 16>(&Settings::new(500_000), &[], &[]).unwrap();
    let sender = SimNode::new().shared();
    let witness = SimNode::new().shared();
    let mut bus = twocan_sim::Bus::new(500_000).unwrap();
    let me = bus.attach("can0", model.clone());
    let sender_id = bus.attach("sender", sender.clone());
    bus.attach("witness", witness.clone());
    bus.run_for(20);
    // Only this node sees a CRC error, on the first three attempts; the witness
    // acknowledges. Each error adds to REC, the good fourth attempt takes one off.
    bus.inject_from(
        sender_id,
        3,
        Fault::Crc {
            who: twocan_sim::Receivers::Node(me),
        },
    );
    sender.borrow_mut().send(std_data(0x77, &[]));
    run1(&mut bus, &mut can, 1_000);
    assert_eq!(drain(&mut can).len(), 1);
    assert!(can.counters().rec > 0, "{:?}", can.counters());
    assert_eq!(can.state(), ErrorState::Active);
    assert_eq!(can.error_stats().crc, 3, "{:?}", can.error_stats());
    assert_eq!(can.last_error(), LastErrorCode::Crc);
}

#[test]
fn modes_and_bounded_waits() {
    let (model, mut can) = begin::<32, 16>(&loop_back(500_000), &[], &[]).unwrap();
    can.set_mode(Mode::Stopped).unwrap();
    assert_eq!(model.mode(), ModelMode::Freeze);
    assert_eq!(can.state(), ErrorState::Stopped);
    can.set_mode(Mode::Sleep).unwrap();
    assert_eq!(model.mode(), ModelMode::Disabled);
    assert_eq!(can.state(), ErrorState::Sleeping);
    assert_eq!(
        can.try_send(&std_data(1, &[])),
        Err(nb::Error::Other(Error::WrongMode))
    );
    can.set_mode(Mode::Normal).unwrap();
    assert_eq!(model.mode(), ModelMode::Normal);
    assert_eq!(can.state(), ErrorState::Active);
    // A module that never acknowledges: a typed timeout, no hang.
    model.set_freeze_ack_stuck(true);
    assert_eq!(can.set_mode(Mode::Stopped), Err(Error::Timeout));
    model.set_freeze_ack_stuck(false);
    let mut bus = bus_with(500_000, &[&model]);
    can.set_mode(Mode::Normal).unwrap();
    can.try_send(&std_data(2, &[2])).unwrap();
    run1(&mut bus, &mut can, 500);
    assert_eq!(drain(&mut can).len(), 1);
}

#[test]
fn filters_replaced_at_run_time() {
    use twocan_core::Filter;
    use twocan_flexcan::FilterTable;
    let s = loop_back(500_000);
    let (model, mut can) = begin::<32, 16>(&s, &[Filter::standard(0x10)], &[]).unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    let table = FilterTable::compile(
        s.configuration,
        &[Filter::standard(0x20)],
        &[Filter::standard(0x10)],
    )
    .unwrap();
    can.set_filters(&table).unwrap();
    assert_eq!(model.mode(), ModelMode::Normal);
    for id in [0x10, 0x20, 0x30] {
        can.try_send(&std_data(id, &[])).unwrap();
    }
    run1(&mut bus, &mut can, 1_000);
    let got: Vec<(u32, u16)> = drain(&mut can)
        .iter()
        .map(|rx| (rx.frame.raw_id(), rx.filter))
        .collect();
    assert_eq!(got, vec![(0x10, 1), (0x20, 0)]);
    let other = FilterTable::compile(twocan_flexcan::Configuration::Filters8_0, &[], &[]).unwrap();
    assert_eq!(can.set_filters(&other), Err(Error::InvalidArgument));
}

#[test]
fn time_stamps_follow_the_free_running_timer() {
    let (model, mut can) = begin::<32, 16>(&Settings::new(500_000), &[], &[]).unwrap();
    let other = SimNode::new().shared();
    let mut bus = bus_with(500_000, &[&model]);
    bus.attach("other", other.clone());
    bus.run_for(100);
    other.borrow_mut().send(std_data(0x1, &[]));
    run1(&mut bus, &mut can, 300);
    bus.run_for(1_000);
    other.borrow_mut().send(std_data(0x2, &[]));
    run1(&mut bus, &mut can, 300);
    let got = drain(&mut can);
    assert_eq!(got.len(), 2);
    let (a, b) = (got[0].timestamp.unwrap(), got[1].timestamp.unwrap());
    let delta = b.bit_times_since(a).unwrap();
    assert!((1_000..1_700).contains(&delta), "{a:?} {b:?}");
    assert!(can.hardware().timer().wrapping_sub(b.counter()) < 1_000);
    assert_eq!(can.hardware().timer(), model.timer());
}

#[test]
fn pins_and_clock_gates_7_16_7_5_16_7_6() {
    let cases = [
        (
            Board::Teensy32,
            Instance::Can0,
            false,
            (Port::A, 12),
            (Port::A, 13),
        ),
        (
            Board::Teensy32,
            Instance::Can0,
            true,
            (Port::B, 18),
            (Port::B, 19),
        ),
        (
            Board::Teensy35,
            Instance::Can0,
            true,
            (Port::B, 18),
            (Port::B, 19),
        ),
        (
            Board::Teensy36,
            Instance::Can0,
            false,
            (Port::A, 12),
            (Port::A, 13),
        ),
        (
            Board::Teensy36,
            Instance::Can1,
            false,
            (Port::E, 24),
            (Port::E, 25),
        ),
    ];
    for (board, instance, alternate, (tx_port, tx_pin), (rx_port, rx_pin)) in cases {
        let mut s = Settings::new(250_000);
        s.use_alternate_tx_pin = alternate;
        s.use_alternate_rx_pin = alternate;
        s.tx_pin_open_collector = true;
        s.rx_pin_pull_up = true;
        let mut sys = HostSystem::new();
        let model = model_for(board);
        let target = Target::new(board, instance);
        let can =
            FlexCan::begin(Ticking::new(model.clone()), &mut sys, target, &s, &[], &[]).unwrap();
        assert_eq!(sys.read32(tx_port.pcr(tx_pin)), PCR_MUX.val(2) | PCR_ODE);
        assert_eq!(
            sys.read32(rx_port.pcr(rx_pin)),
            PCR_MUX.val(2) | PCR_PE | PCR_PS
        );
        let (gate, bit) = target.clock_gate().unwrap();
        assert_ne!(sys.read32(gate) & bit, 0);
        assert_ne!(
            sys.read32(sim::SIM_SCGC5) & tx_port.scgc5_bit() & rx_port.scgc5_bit(),
            0
        );
        assert_eq!(can.target(), target);
        assert!(target.irqs().is_some());
        assert_eq!(can.message_irq_priority(), 64);
    }
    // Without open collector / pull-up: plain ALT2.
    let mut sys = HostSystem::new();
    let t = Target::new(Board::Teensy32, Instance::Can0);
    let _can = FlexCan::begin(
        Ticking::new(FlexCanModel::mk20dx256()),
        &mut sys,
        t,
        &Settings::new(250_000),
        &[],
        &[],
    )
    .unwrap();
    assert_eq!(sys.read32(Port::A.pcr(12)), PCR_MUX.val(2));
    assert_eq!(sys.read32(Port::A.pcr(13)), PCR_MUX.val(2));
}

use twocan_core::Registers as _;

/// A probe to run once, shared with the register access that runs it.
type Probe = std::rc::Rc<std::cell::RefCell<Option<Box<dyn FnOnce()>>>>;

/// Register access that runs a probe once, at the write of `RXFGMASK` (the last table
/// write of a filter switch, in Freeze mode).
struct Probed {
    inner: Ticking,
    probe: Probe,
}

impl twocan_core::Registers for Probed {
    fn read32(&self, offset: usize) -> u32 {
        self.inner.read32(offset)
    }
    fn write32(&self, offset: usize, value: u32) {
        self.inner.write32(offset, value);
        if offset == twocan_flexcan::regs::RXFGMASK {
            let probe = self.probe.borrow_mut().take();
            if let Some(probe) = probe {
                probe();
            }
        }
    }
}

/// Issue 26 (found by reading): `set_filters` froze the module through the mode
/// machinery, so meanwhile `on_bus()` read false — a concurrent async `send` with a
/// full queue failed with `WrongMode` — and the status handler could record `Stopped`
/// changes that the application never asked for. The switch is invisible to the other
/// contexts now: on the bus, error-active, no state change.
#[test]
fn a_filter_switch_is_not_a_mode_change() {
    use std::cell::RefCell;
    use std::rc::Rc;
    use twocan_core::split::State;
    use twocan_core::{Filter, Hardware};
    use twocan_flexcan::{FilterTable, FlexCanHw};

    let settings = loop_back(500_000);
    let model = model_for(Board::Teensy32);
    let probe: Probe = Rc::new(RefCell::new(None));
    let regs = Probed {
        inner: Ticking::new(model.clone()),
        probe: probe.clone(),
    };
    let target = Target::new(Board::Teensy32, Instance::Can0);
    let can = FlexCan::begin(
        regs,
        &mut HostSystem::new(),
        target,
        &settings,
        &[Filter::standard(0x10)],
        &[],
    )
    .unwrap();
    let state: &'static State<FlexCanHw<Probed>, 8> = Box::leak(Box::new(State::new()));
    let mut p = state.split(can.into_split()).ok().unwrap();
    let seen = Rc::new(RefCell::new(None));
    let seen_in_probe = seen.clone();
    let mut status = p.status_irq;
    *probe.borrow_mut() = Some(Box::new(move || {
        // Another context, while the table is written in Freeze mode.
        let hw = state.hardware().unwrap();
        status.poll_state();
        *seen_in_probe.borrow_mut() = Some((hw.on_bus(), hw.error_status().state));
    }) as Box<dyn FnOnce()>);
    let table =
        FilterTable::compile(settings.configuration, &[Filter::standard(0x20)], &[]).unwrap();
    p.rx.set_filters(&table).unwrap();
    assert_eq!(
        *seen.borrow(),
        Some((true, ErrorState::Active)),
        "seen during the switch"
    );
    assert_eq!(p.rx.take_state_change(), None, "no state change recorded");
    assert_eq!(model.mode(), ModelMode::Normal);
}
