//! Error handling against the model: bus-off after repeated errors and both ways out of
//! it, bounded acknowledge waits (a model that never acknowledges), the last error code
//! and its clearing by software, sleep and wake-up.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{esr, ESR};
use twocan_bxcan::{Can, Recovery};
use twocan_core::{Error, ErrorState, LastErrorCode, Mode, Registers, TxOutcome, TxPolicy};
use twocan_sim::{Fault, NodeId, SimNode};

fn bus_off_setup(recovery: Recovery) -> (Drv, Clocked, SharedBus, NodeId) {
    let bus = new_bus();
    let model = BxCanModel::can1();
    let me = bus.borrow_mut().attach("can1", model.clone());
    bus.borrow_mut().attach("peer", SimNode::new().shared());
    let regs = Clocked::new(model, &bus);
    let cfg = config().recovery(recovery);
    let mut init = Can::can1(regs.clone(), &cfg).map_err(|f| f.error).unwrap();
    init.set_filters(&pass_all()).unwrap();
    let can = init.enable().map_err(|f| f.error).unwrap();
    (driver(can), regs, bus, me)
}

/// 32 bit errors on our transmissions: TEC + 8 each → 256 → bus-off.
fn drive_to_bus_off(d: &mut Drv, bus: &SharedBus, me: NodeId) {
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
    // In order, with the counters at each change.
    let changes: Vec<_> = std::iter::from_fn(|| d.take_state_change()).collect();
    let states: Vec<_> = changes.iter().map(|c| c.state).collect();
    assert_eq!(
        states,
        [ErrorState::Warning, ErrorState::Passive, ErrorState::BusOff],
        "{changes:?}"
    );
    assert_eq!(changes[2].counters.tec, 256);
}

#[test]
fn bus_off_with_automatic_recovery() {
    let (mut d, _regs, bus, me) = bus_off_setup(Recovery::Automatic);
    drive_to_bus_off(&mut d, &bus, me);
    // 128 × 11 recessive bits, then error-active again by itself.
    run(&bus, 128 * 11 + 100);
    d.on_interrupt();
    assert_eq!(d.state(), ErrorState::Active);
    assert_eq!(
        d.recover(),
        Err(Error::WrongMode),
        "refused: recovery is automatic (ABOM)"
    );
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
    let can = failed.value.enable().map_err(|f| f.error).unwrap();
    assert_eq!(can.mode(), Mode::Normal);
    let mut d = driver(can);

    // Mode changes are bounded too.
    model.set_ack_stuck(true);
    assert_eq!(d.set_mode(Mode::Sleep), Err(Error::Timeout));
    assert_eq!(d.set_mode(Mode::Stopped), Err(Error::Timeout));
    model.set_ack_stuck(false);
    assert_eq!(d.set_mode(Mode::Normal), Ok(()));
}

#[test]
fn last_error_code_is_reported_then_cleared_by_software() {
    let (can, regs, bus, _peer) = can1_and_peer(&config(), &pass_all());
    regs.ticking.set(false);
    let mut d = driver(can);
    bus.borrow_mut().inject_next(Fault::Bit { at: None });
    d.try_send(&std(0x10)).unwrap();
    bus.borrow_mut().step(); // the failed attempt only
    let status = d.error_status();
    assert_ne!(status.last_error, LastErrorCode::None);
    assert_eq!(status.counters.tec, 8);
    d.on_status();
    assert_eq!(d.error_stats().bit, 1, "counted once, by kind");
    // The register holds 0b111 ("set by software") so the next error is seen as new...
    assert_eq!(
        esr::LEC.get(regs.model.read32(ESR)),
        esr::LEC_SOFTWARE,
        "LEC = 0b111 after the status handler took it"
    );
    // ...but the last error the hardware latched stays readable (sticky).
    assert_eq!(d.error_status().last_error, status.last_error);
    d.on_status();
    assert_eq!(d.error_stats().bit, 1, "reported once");
    assert_eq!(d.error_status().last_error, status.last_error);
    settle(&bus);
    d.on_interrupt();
    assert_eq!(d.traffic().sent, 1);
    assert_eq!(
        d.error_status().last_error,
        status.last_error,
        "a success does not replace the last error"
    );
    d.hardware().clear_last_error();
    assert_eq!(d.error_status().last_error, LastErrorCode::None);
}

#[test]
fn acknowledge_error_is_reported() {
    let (can, regs, bus, _peer) = can1_and_peer(&config(), &pass_all());
    regs.ticking.set(false);
    let mut d = driver(can);
    bus.borrow_mut().inject_next(Fault::Ack);
    d.try_send(&std(0x10)).unwrap();
    bus.borrow_mut().step();
    d.on_status();
    assert_eq!(d.error_stats().acknowledge, 1);
    assert_eq!(d.last_error(), LastErrorCode::Acknowledge);
}

#[test]
fn wake_up_events_only_with_wkuie() {
    use twocan_bxcan::config::DEFAULT_INTERRUPTS;
    use twocan_bxcan::regs::ier;
    let cfg = config().interrupts(DEFAULT_INTERRUPTS & !ier::WKUIE);
    let (can, _regs, _bus, _peer) = can1_and_peer(&cfg, &pass_all());
    assert!(!driver(can).capabilities().wakeup_events);
}

#[test]
fn sleep_and_wake_up() {
    let cfg = config().auto_wakeup(true);
    let (can, _regs, bus, peer) = can1_and_peer(&cfg, &pass_all());
    let mut d = driver(can);
    // The default interrupts include WKUIE: the controller reports wake-ups.
    assert!(d.capabilities().wakeup_events);
    assert_eq!(d.wakeups(), 0);
    d.set_mode(Mode::Sleep).unwrap();
    assert_eq!(d.hardware().mode(), Mode::Sleep);
    assert_eq!(d.error_status().state, ErrorState::Sleeping);
    d.on_interrupt();
    // Bus activity wakes it (AWUM): WKUI, then normal mode after the bus is idle.
    peer.borrow_mut().send(std(0x77));
    settle(&bus);
    run(&bus, 100);
    d.on_status();
    assert_eq!(d.shared_state().wakeups(), 1);
    assert_eq!(d.wakeups(), 1);
    assert_ne!(d.hardware().mode(), Mode::Sleep);
    d.set_mode(Mode::Sleep).unwrap();
    d.set_mode(Mode::Normal).unwrap();
    assert_eq!(d.hardware().mode(), Mode::Normal);
    d.set_mode(Mode::Stopped).unwrap();
    assert_eq!(d.error_status().state, ErrorState::Stopped);
}

#[test]
fn blocking_transmit_fails_off_the_bus_instead_of_spinning() {
    use embedded_can::blocking::Can as _;
    let (can, _regs, _bus, _peer) = can1_and_peer(&config(), &pass_all());
    let mut d: twocan_core::Driver<twocan_bxcan::BxCan<Clocked>, 8, 2> =
        twocan_core::Driver::new(can.into_split());
    d.set_mode(Mode::Stopped).unwrap();
    // Three mailboxes and two queue slots take frames while stopped...
    for id in 0..5 {
        assert!(d.try_send(&std(id)).is_ok(), "frame {id} accepted");
    }
    // ...the sixth would wait for ever: the blocking call says why instead.
    assert_eq!(d.transmit(&std(9)), Err(Error::WrongMode));
    assert_eq!(d.traffic().queued, 5, "the refused frame was not accepted");
    // Back on the bus, the five go and complete once each.
    d.set_mode(Mode::Normal).unwrap();
    let done = (0..200)
        .map(|_| {
            _bus.borrow_mut().run_for(100);
            d.on_interrupt();
            std::iter::from_fn(|| d.take_completion()).count()
        })
        .sum::<usize>();
    assert_eq!(done, 5);
    assert_eq!(d.traffic().sent, 5);
    let _ = TxOutcome::Sent;
}

#[test]
fn master_reset_puts_every_register_back_and_the_instance_can_start_again() {
    use twocan_bxcan::regs::{BTR, MCR, MSR};
    let (can, regs, bus, _peer) = can1_and_peer(&config().loopback(true), &pass_all());
    let d = driver(can);
    assert_ne!(regs.model.read32(BTR), 0x0123_0000, "configured");
    let (r, _) = d.release().master_reset().map_err(|f| f.error).unwrap();
    // Reset values (RM0410 §40.9.2): MCR 0x0001_0002, MSR 0x0000_0C02 (asleep), BTR
    // 0x0123_0000.
    assert_eq!(regs.model.read32(MCR), 0x0001_0002);
    assert_eq!(regs.model.read32(MSR) & 0x3, 0x2, "SLAK, not INAK");
    assert_eq!(regs.model.read32(BTR), 0x0123_0000);
    // And it configures again from scratch.
    let mut init = Can::can1(r, &config()).map_err(|f| f.error).unwrap();
    init.set_filters(&pass_all()).unwrap();
    let mut d = driver(init.enable().map_err(|f| f.error).unwrap());
    d.try_send(&std(0x42)).unwrap();
    settle(&bus);
    d.on_interrupt();
    assert_eq!(d.traffic().sent, 1);
}
