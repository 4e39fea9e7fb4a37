//! The `imxrt-ral` hand-over takes the pins a `teensy4-bsp` program has as they come:
//! `teensy4_pins::t41::Pins` (what the BSP's `board::t41` hands out) `p22`/`p23` for
//! CAN1, `p1`/`p0` for CAN2, `p31`/`p30` for CAN3, by value, and gives the same pads back
//! from `free` — before `begin`, and after `begin` in exchange for the controller. Run
//! with `--features model,imxrt-ral,teensy41` (or `teensy40` with `t40::from_pads`).

#![cfg(any(feature = "teensy40", feature = "teensy41"))]

use twocan_core::{Filter, Registers};
use twocan_flexcan::imxrt::ral::{self, RalCan};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::regs::{self, mcr};
use twocan_flexcan::{Board, CanClock, HostSystem, IdleClocked, Instance, Settings, Target};

#[cfg(all(feature = "teensy40", not(feature = "teensy41")))]
use teensy4_pins::t40::{from_pads, Pins};
#[cfg(feature = "teensy41")]
use teensy4_pins::t41::{from_pads, Pins};

fn pins() -> Pins {
    // SAFETY: host test; the pads are taken once per test and never dereferenced (the
    // host system stands for the IOMUXC).
    from_pads(unsafe { imxrt_iomuxc::imxrt1060::Pads::new() })
}

/// Begins the handed-over module over the model, checks it runs and that the pads'
/// registers were muxed, frees it and returns what came back.
fn begin_and_free<C: RalCan>(can: ral::HandOver<C>, instance: Instance) -> ral::Owned<C> {
    let target = Target::new(Board::DEFAULT, instance);
    let model = FlexCanModel::new(target.model_chip());
    let mut sys = HostSystem::new();
    let settings = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
    let (controller, parked) = can
        .begin_over(
            IdleClocked::new(model.clone()),
            &mut sys,
            &settings,
            &[Filter::pass_all()],
            &[],
        )
        .unwrap_or_else(|(_, e)| panic!("{instance:?}: {e:?}"));
    assert_eq!(
        model.read32(regs::MCR) & mcr::MDIS,
        0,
        "{instance:?} running"
    );
    // The two pads the hand-over holds are the ones begin muxed (MUX_MODE = the CAN
    // function's ALTn, not the reset GPIO function ALT5).
    for mux in [
        <C::Tx as ral::PadRegisters>::MUX,
        <C::Rx as ral::PadRegisters>::MUX,
    ] {
        let written = sys.written().iter().find(|(a, _)| *a == mux).map(|w| w.1);
        assert!(
            matches!(written, Some(v) if v != twocan_flexcan::imxrt::pads::MUX_RESET),
            "{instance:?}: pad {mux:#x} muxed: {written:?}"
        );
    }
    let (owned, _regs) = parked
        .free_over(controller, &mut sys)
        .map_err(|(_, _, e)| e)
        .unwrap();
    assert_ne!(
        model.read32(regs::MCR) & mcr::MDIS,
        0,
        "{instance:?} stopped"
    );
    owned
}

#[test]
fn the_bsp_pins_are_taken_and_given_back() {
    // SAFETY: host test; the instances are never dereferenced.
    let (can1, can2, can3) = unsafe {
        (
            imxrt_ral::can::CAN1::instance(),
            imxrt_ral::can::CAN2::instance(),
            imxrt_ral::can3::CAN3::instance(),
        )
    };
    let pins = pins();
    // Before begin: the same instance and pads back.
    let back = ral::hand_over(can1, pins.p22, pins.p23).free();
    let one = begin_and_free(ral::hand_over(back.can, back.tx, back.rx), Instance::Can1);
    let two = begin_and_free(ral::hand_over(can2, pins.p1, pins.p0), Instance::Can2);
    let three = begin_and_free(ral::hand_over(can3, pins.p31, pins.p30), Instance::Can3);
    // What came back is what was given (the types say so): the program can hand the
    // same instances and pads over again.
    begin_and_free(ral::hand_over(one.can, one.tx, one.rx), Instance::Can1);
    begin_and_free(ral::hand_over(two.can, two.tx, two.rx), Instance::Can2);
    begin_and_free(
        ral::hand_over(three.can, three.tx, three.rx),
        Instance::Can3,
    );
}
