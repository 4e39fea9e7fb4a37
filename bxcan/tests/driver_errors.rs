//! Error handling against the model: bus-off after repeated errors and both ways out of
//! it, bounded acknowledge waits (a model that never acknowledges), the last error code
//! and its clearing by software, sleep and wake-up.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{esr, ESR};
use twocan_bxcan::{Can, Recovery};
use twocan_core::sim::{Fault, NodeId, SimNode};
use twocan_core::{
    Controller, Driver, Error, ErrorState, LastErrorCode, Mode, Registers, TxPolicy,
};

fn bus_off_setup(recovery: Recovery) -> (Driver<Can<Clocked>, 8, 8>, Clocked, SharedBus, NodeId) {
    let bus = new_bus();
    let model = BxCanModel::can1();
    let me = bus.borrow_mut().attach("can1", model.clone());
    bus.borrow_mut().attach("peer", SimNode::new().shared());
    let regs = Clocked::new(model, &bus);
    let cfg = config().recovery(recovery);
    let mut init = Can::can1(regs.clone(), &cfg).map_err(|f| f.error).unwrap();
    init.set_filters(&pass_all()).unwrap();
    let can = init.enable().map_err(|f| f.error).unwrap();
    (Driver::new(can), regs, bus, me)
}

/// 32 bit errors on our transmissions: TEC + 8 each → 256 → bus-off.
fn drive_to_bus_off(d: &mut Driver<Can<Clocked>, 8, 8>, bus: &SharedBus, me: NodeId) {
    bus.borrow_mut()
        .inject_from(me, 32, Fault::Bit { at: None });
    d.try_send(&std(0x123)).unwrap();
    for _ in 0..200 {
        run(bus, 50);
        d.on_interrupt();
        if d.state() == ErrorState::BusOff {
            break;
        }
    }
    assert_eq!(d.state(), ErrorState::BusOff);
    assert_eq!(d.counters().tec, 256, "TEC reads 256 while bus-off");
    assert_eq!(d.error_stats().bus_off, 1);
    assert!(d.error_stats().bit >= 1);
    assert_eq!(d.try_send(&std(1)), Err(nb::Error::Other(Error::BusOff)));
}

#[test]
fn bus_off_with_automatic_recovery() {
    let (mut d, _regs, bus, me) = bus_off_setup(Recovery::Automatic);
    drive_to_bus_off(&mut d, &bus, me);
    // 128 × 11 recessive bits, then error-active again by itself.
    run(&bus, 128 * 11 + 100);
    d.on_interrupt();
    assert_eq!(d.state(), ErrorState::Active);
    assert_eq!(d.recover(), Ok(()), "a no-op with ABOM");
    // The pending frame goes out after recovery.
    settle(&bus);
    d.on_interrupt();
    assert_eq!(d.traffic().sent, 1);
}

#[test]
fn bus_off_with_manual_recovery() {
    let (mut d, regs, bus, me) = bus_off_setup(Recovery::Manual);
    drive_to_bus_off(&mut d, &bus, me);
    regs.ticking.set(false);
    run(&bus, 10 * 128 * 11);
    d.on_interrupt();
    assert_eq!(
        d.state(),
        ErrorState::BusOff,
        "stays bus-off without software"
    );
    regs.ticking.set(true);
    d.recover().unwrap(); // enter and leave initialization mode
    regs.ticking.set(false);
    run(&bus, 128 * 11 + 100);
    d.on_interrupt();
    assert_eq!(d.state(), ErrorState::Active);
    assert_eq!(d.counters().tec, 0);
}

#[test]
fn a_controller_that_never_acknowledges_times_out() {
    let bus = new_bus();
    let model = BxCanModel::can1();
    bus.borrow_mut().attach("can1", model.clone());
    let regs = Clocked::new(model.clone(), &bus);
    let cfg = loopback_config(TxPolicy::Fifo).wait_iterations(5_000);
    model.set_ack_stuck(true);
    let failed = Can::can1(regs, &cfg).unwrap_err();
    assert_eq!(failed.error, Error::Timeout);
    let e: Error = Can::can1(failed.value.release().0, &cfg)
        .map(|_| ())
        .unwrap_err()
        .into();
    assert_eq!(e, Error::Timeout);

    // Acknowledged into initialization, stuck on the way out: enable times out.
    model.set_ack_stuck(false);
    let regs = Clocked::new(model.clone(), &bus);
    let init = Can::can1(regs, &cfg).map_err(|f| f.error).unwrap();
    model.set_ack_stuck(true);
    let failed = init.enable().unwrap_err();
    assert_eq!(failed.error, Error::Timeout);
    model.set_ack_stuck(false);
    let mut can = failed.value.enable().map_err(|f| f.error).unwrap();
    assert_eq!(can.mode(), Mode::Normal);

    // Mode changes are bounded too.
    model.set_ack_stuck(true);
    assert_eq!(can.set_mode(Mode::Sleep), Err(Error::Timeout));
    assert_eq!(can.set_mode(Mode::Stopped), Err(Error::Timeout));
    model.set_ack_stuck(false);
    assert_eq!(can.set_mode(Mode::Normal), Ok(()));
}

#[test]
fn last_error_code_is_reported_then_cleared_by_software() {
    let (mut can, regs, bus, _peer) = can1_and_peer(&config(), &pass_all());
    regs.ticking.set(false);
    bus.borrow_mut().inject_next(Fault::Bit { at: None });
    can.transmit(&std(0x10)).unwrap();
    bus.borrow_mut().step(); // the failed attempt only
    let status = can.error_status();
    assert_ne!(status.last_error, LastErrorCode::None);
    assert_eq!(status.counters.tec, 8);
    let ev = can.take_events();
    assert_eq!(ev.bus_error, Some(status.last_error));
    assert!(ev.state_changed || status.state == ErrorState::Active);
    // The register holds 0b111 ("set by software") so the next error is seen as new...
    assert_eq!(
        esr::LEC.get(regs.model.read32(ESR)),
        esr::LEC_SOFTWARE,
        "LEC = 0b111 after the event was taken"
    );
    // ...but the last error the hardware latched stays readable (sticky).
    assert_eq!(can.error_status().last_error, status.last_error);
    assert_eq!(can.take_events().bus_error, None, "reported once");
    assert_eq!(can.error_status().last_error, status.last_error);
    settle(&bus);
    assert_eq!(can.take_events().sent, 1);
    assert_eq!(
        can.error_status().last_error,
        status.last_error,
        "a success does not replace the last error"
    );
    can.clear_last_error();
    assert_eq!(can.error_status().last_error, LastErrorCode::None);
}

#[test]
fn acknowledge_error_is_reported() {
    let (mut can, regs, bus, _peer) = can1_and_peer(&config(), &pass_all());
    regs.ticking.set(false);
    bus.borrow_mut().inject_next(Fault::Ack);
    can.transmit(&std(0x10)).unwrap();
    bus.borrow_mut().step();
    assert_eq!(
        can.take_events().bus_error,
        Some(LastErrorCode::Acknowledge)
    );
}

#[test]
fn sleep_and_wake_up() {
    let cfg = config().auto_wakeup(true);
    let (mut can, _regs, bus, peer) = can1_and_peer(&cfg, &pass_all());
    can.set_mode(Mode::Sleep).unwrap();
    assert_eq!(can.mode(), Mode::Sleep);
    assert_eq!(can.error_status().state, ErrorState::Sleeping);
    let _ = can.take_events();
    // Bus activity wakes it (AWUM): WKUI, then normal mode after the bus is idle.
    peer.borrow_mut().send(std(0x77));
    settle(&bus);
    run(&bus, 100);
    let ev = can.take_events();
    assert!(ev.wakeup);
    assert_ne!(can.mode(), Mode::Sleep);
    can.set_mode(Mode::Sleep).unwrap();
    can.set_mode(Mode::Normal).unwrap();
    assert_eq!(can.mode(), Mode::Normal);
    can.set_mode(Mode::Stopped).unwrap();
    assert_eq!(can.error_status().state, ErrorState::Stopped);
}
