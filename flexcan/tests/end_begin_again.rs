//! `end` (issue 17): the module stopped and disabled, its pins back to `MUX` 0, its
//! clock gate cleared, and `begin` working again on the same registers — on the
//! behavioural model (modes, interrupt lines) and the SIM/PORT seam ([`HostSystem`]),
//! through the driver.

mod common;

use common::*;
use twocan_core::{Driver, Error, Filter, Registers};
use twocan_flexcan::model::{FlexCanModel, ModelMode};
use twocan_flexcan::regs::sim;
use twocan_flexcan::{Board, FlexCan, FlexCanHw, HostSystem, Instance, Settings, Target};

type Drv = Driver<FlexCanHw<Ticking>, 32, 16>;

fn start(regs: Ticking, sys: &mut HostSystem, target: Target, settings: &Settings) -> Drv {
    let controller = FlexCan::begin(regs, sys, target, settings, &[Filter::pass_all()], &[])
        .expect("begin: valid settings");
    Driver::new(controller.into_split())
}

/// Sends one frame in loop-back and checks it comes back.
fn round_trip(bus: &mut twocan_sim::Bus, can: &mut Drv, id: u16) {
    can.try_send(&std_data(id, &[id as u8])).unwrap();
    run(bus, &mut [can], 1_000);
    let got: Vec<_> = core::iter::from_fn(|| can.receive().ok()).collect();
    assert_eq!(got.len(), 1, "{got:?}");
    assert_eq!(got[0].frame, std_data(id, &[id as u8]));
}

fn gate(target: Target) -> (usize, u32) {
    target.clock_gate().unwrap()
}

#[test]
fn end_releases_everything_and_begin_runs_again() {
    let settings = loop_back(125_000);
    for (target, model) in [
        (
            Target::new(Board::Teensy32, Instance::Can0),
            FlexCanModel::mk20dx256(),
        ),
        (
            Target::new(Board::Teensy36, Instance::Can1),
            FlexCanModel::mk66fx1m0(),
        ),
    ] {
        let mut sys = HostSystem::new();
        let (reg, bit) = gate(target);
        let mut can = start(Ticking::new(model.clone()), &mut sys, target, &settings);
        let mut bus = bus_with(125_000, &[&model]);
        assert_eq!(
            sys.read32(reg) & bit,
            bit,
            "{target:?}: gate open after begin"
        );
        round_trip(&mut bus, &mut can, 0x123);

        // The driver gives the controller back; `end` stops it.
        let controller = can.release().into_controller();
        let released = *controller.system().kinetis().unwrap();
        let (tx, rx) = (released.tx.0, released.rx.0);
        assert_ne!(sys.read32(tx.pcr()), 0, "{target:?}: Tx pin muxed by begin");
        let regs = controller.end(&mut sys).expect("end");
        assert_eq!(model.mode(), ModelMode::Disabled, "{target:?}");
        assert!(!model.irq_pending(), "{target:?}: no line left asserted");
        assert_eq!(model.peek32(twocan_flexcan::regs::IMASK1), 0);
        assert_eq!(sys.read32(reg) & bit, 0, "{target:?}: gate cleared");
        assert_eq!(sys.read32(tx.pcr()), 0, "{target:?}: Tx pin released");
        assert_eq!(sys.read32(rx.pcr()), 0, "{target:?}: Rx pin released");
        // The port gates stay open (other pins of the ports may be in use).
        assert_eq!(
            sys.read32(sim::SIM_SCGC5) & (tx.port.scgc5_bit() | rx.port.scgc5_bit()),
            tx.port.scgc5_bit() | rx.port.scgc5_bit()
        );

        // `begin` again on the registers `end` gave back.
        let mut can = start(regs, &mut sys, target, &settings);
        assert_eq!(sys.read32(reg) & bit, bit, "{target:?}: gate open again");
        assert_ne!(sys.read32(tx.pcr()), 0);
        round_trip(&mut bus, &mut can, 0x321);
    }
}

#[test]
fn end_of_an_unsplit_controller_and_alternate_pins() {
    let mut settings = loop_back(125_000);
    settings.use_alternate_tx_pin = true;
    settings.use_alternate_rx_pin = true;
    let target = Target::new(Board::Teensy35, Instance::Can0);
    let model = FlexCanModel::mk64fx512();
    let mut sys = HostSystem::new();
    let controller = FlexCan::begin(
        Ticking::new(model.clone()),
        &mut sys,
        target,
        &settings,
        &[],
        &[],
    )
    .unwrap();
    let plan = *controller.system().kinetis().unwrap();
    // Teensy 3.5 alternates: pins 29 and 30 (ACAN §7 table 3).
    assert_eq!((plan.tx.0.teensy_pin, plan.rx.0.teensy_pin), (29, 30));
    let regs = controller.end(&mut sys).unwrap();
    assert_eq!(sys.read32(plan.tx.0.pcr()), 0);
    assert_eq!(sys.read32(plan.rx.0.pcr()), 0);
    assert_eq!(sys.read32(sim::SIM_SCGC6) & sim::SCGC6_FLEXCAN0, 0);
    assert_eq!(model.mode(), ModelMode::Disabled);
    // Again, with the default pins this time.
    let again = FlexCan::begin(
        regs,
        &mut sys,
        target,
        &loop_back(125_000),
        &[Filter::pass_all()],
        &[],
    )
    .unwrap();
    assert_eq!(again.system().teensy_pins().0, 3);
    assert_eq!(
        sys.read32(sim::SIM_SCGC6) & sim::SCGC6_FLEXCAN0,
        sim::SCGC6_FLEXCAN0
    );
}

#[test]
fn end_that_cannot_freeze_gives_the_controller_back_and_releases_nothing() {
    let target = Target::new(Board::Teensy32, Instance::Can0);
    let model = FlexCanModel::mk20dx256();
    let mut sys = HostSystem::new();
    let controller = FlexCan::begin(
        Ticking::new(model.clone()),
        &mut sys,
        target,
        &loop_back(125_000),
        &[],
        &[],
    )
    .unwrap();
    model.set_freeze_ack_stuck(true);
    let (controller, e) = controller.end(&mut sys).unwrap_err();
    assert_eq!(e, Error::Timeout);
    assert_eq!(
        sys.read32(sim::SIM_SCGC6) & sim::SCGC6_FLEXCAN0,
        sim::SCGC6_FLEXCAN0,
        "the gate stays open: the module is still running"
    );
    assert_ne!(
        sys.read32(controller.system().kinetis().unwrap().tx.0.pcr()),
        0
    );
    // Once the module acknowledges again, `end` completes.
    model.set_freeze_ack_stuck(false);
    controller
        .end(&mut sys)
        .expect("end after the fault cleared");
    assert_eq!(model.mode(), ModelMode::Disabled);
}

#[test]
fn end_of_a_sleeping_controller() {
    let target = Target::new(Board::Teensy36, Instance::Can0);
    let model = FlexCanModel::mk66fx1m0();
    let mut sys = HostSystem::new();
    let mut can = start(
        Ticking::new(model.clone()),
        &mut sys,
        target,
        &loop_back(125_000),
    );
    can.set_mode(twocan_core::Mode::Sleep).unwrap();
    assert_eq!(model.mode(), ModelMode::Disabled);
    let controller = can.release().into_controller();
    assert_eq!(controller.mode(), twocan_core::Mode::Sleep);
    let regs = controller.end(&mut sys).expect("end from sleep");
    assert_eq!(model.mode(), ModelMode::Disabled);
    assert_eq!(model.peek32(twocan_flexcan::regs::IMASK1), 0);
    assert_eq!(sys.read32(sim::SIM_SCGC6) & sim::SCGC6_FLEXCAN0, 0);
    let mut can = start(regs, &mut sys, target, &loop_back(125_000));
    let mut bus = bus_with(125_000, &[&model]);
    round_trip(&mut bus, &mut can, 0x55);
}
