//! Typed pin choice (issue 16): the pins of the board feature, through `begin` on the
//! model — the PCRs `begin` writes are those of the chosen pin types, and frames flow.
//! Runs with a board feature (`--features model,teensy36` etc.); the compile-time half
//! (a pin the board lacks does not build) is the `compile_fail` examples of `pin`'s
//! documentation.
#![cfg(all(
    any(feature = "teensy32", feature = "teensy35", feature = "teensy36"),
    not(any(feature = "teensy40", feature = "teensy41"))
))]

mod common;

use common::*;
use twocan_core::{Driver, Filter, Registers};
use twocan_flexcan::pin::{self, RxPin, TxPin};
use twocan_flexcan::regs::port::PCR_MUX;
use twocan_flexcan::{Board, Can0, FlexCan, FlexCanHw, HostSystem, Instance, Target};

fn begin_with<T: TxPin<Can0>, X: RxPin<Can0>>(tx: T, rx: X) {
    let target = Target::new(Board::DEFAULT, Instance::Can0);
    let settings = pin::settings_for(&loop_back(125_000), tx, rx);
    let model = model_for(Board::DEFAULT);
    let mut sys = HostSystem::new();
    let controller = FlexCan::begin(
        Ticking::new(model.clone()),
        &mut sys,
        target,
        &settings,
        &[Filter::pass_all()],
        &[],
    )
    .expect("begin on typed pins");
    assert_eq!(
        controller.system().kinetis().expect("a Kinetis plan").tx.0,
        T::PIN
    );
    assert_eq!(
        controller.system().kinetis().expect("a Kinetis plan").rx.0,
        X::PIN
    );
    assert_eq!(PCR_MUX.get(sys.read32(T::PIN.pcr())), T::PIN.alt);
    assert_eq!(PCR_MUX.get(sys.read32(X::PIN.pcr())), X::PIN.alt);
    // Only those two PCRs were written (besides the SIM gates).
    let pcrs = sys
        .written()
        .iter()
        .filter(|(a, _)| (0x4004_9000..0x4004_E000).contains(a))
        .count();
    assert_eq!(pcrs, 2);

    let mut can: Driver<FlexCanHw<Ticking>, 32, 16> = Driver::new(controller.into_split());
    let mut bus = bus_with(125_000, &[&model]);
    can.try_send(&std_data(0x42, &[1])).unwrap();
    run(&mut bus, &mut [&mut can], 1_000);
    assert_eq!(can.receive().unwrap().frame, std_data(0x42, &[1]));
}

#[test]
fn default_pins() {
    begin_with(pin::Pin3, pin::Pin4);
}

#[cfg(all(
    feature = "teensy32",
    not(any(feature = "teensy35", feature = "teensy36"))
))]
#[test]
fn teensy32_alternate_pins() {
    begin_with(pin::Pin32, pin::Pin25);
    begin_with(pin::Pin32, pin::Pin4);
}

#[cfg(any(feature = "teensy35", feature = "teensy36"))]
#[test]
fn teensy35_36_alternate_pins() {
    begin_with(pin::Pin29, pin::Pin30);
    begin_with(pin::Pin3, pin::Pin30);
}
