//! Shared test harness: the real driver over the FlexCAN model on twocan-sim's
//! simulated bus, interrupts serviced by the test between bus events.
#![allow(dead_code)]

use twocan_core::{Driver, Filter, Frame, RxFrame};
use twocan_flexcan::layout::{Imxrt1062, Kinetis, Layout};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::{
    BeginError, Board, FlexCan, FlexCanHw, HostSystem, Instance, Settings, Target,
};
use twocan_sim::Bus;

/// The model as the driver sees it: back-to-back reads of `MCR` or `ESR1` (a mode
/// acknowledge or `SYNCH` wait) let one bit time of idle bus pass for the module.
pub use twocan_flexcan::IdleClocked as Ticking;

/// The driver over the model with receive ring `RX` and transmit ring `TX`.
pub type Can<const RX: usize, const TX: usize> = Driver<FlexCanHw<Ticking>, RX, TX>;

/// A fresh model of the board's chip (a Teensy 4.x: its CAN1; see [`model_of`]).
pub fn model_for(board: Board) -> FlexCanModel {
    model_of(Target::new(board, Instance::Can1))
}

/// A fresh model of the target's module: the chip's, and on the RT1062 the instance's
/// (CAN3 differs from CAN1/CAN2).
pub fn model_of(target: Target) -> FlexCanModel {
    FlexCanModel::new(target.model_chip())
}

/// The driver over the model in the layout `L` with receive ring `RX` and transmit
/// ring `TX`.
pub type CanIn<L, const RX: usize, const TX: usize> =
    Driver<FlexCanHw<Ticking, twocan_flexcan::options::Full<L>>, RX, TX>;

/// The driver over the model in the RT1062 layout (a Teensy 4 module: the only layout
/// `begin` takes there, with the ERR005829 workaround).
pub type CanRt<const RX: usize, const TX: usize> = CanIn<Imxrt1062, RX, TX>;

/// `begin` on `target` over a fresh model; gives the model handle and the driver.
///
/// These tests follow ACAN's examples, whose "no filter" form receives everything: with
/// both lists empty the helper passes twocan's explicit [`Filter::pass_all`] (an empty
/// list receives nothing in twocan, see [`begin_on_exact`]).
pub fn begin_on<const RX: usize, const TX: usize>(
    target: Target,
    settings: &Settings,
    primary: &[Filter],
    secondary: &[Filter],
) -> Result<(FlexCanModel, Can<RX, TX>), BeginError> {
    begin_in_on::<Kinetis, RX, TX>(target, settings, primary, secondary)
}

/// `begin` with exactly these lists (both empty: nothing is received).
pub fn begin_on_exact<const RX: usize, const TX: usize>(
    target: Target,
    settings: &Settings,
    primary: &[Filter],
    secondary: &[Filter],
) -> Result<(FlexCanModel, Can<RX, TX>), BeginError> {
    begin_in_on_exact::<Kinetis, RX, TX>(target, settings, primary, secondary)
}

/// [`begin_on`] for a Teensy 4 module, in the RT1062 layout.
pub fn begin_rt_on<const RX: usize, const TX: usize>(
    target: Target,
    settings: &Settings,
    primary: &[Filter],
    secondary: &[Filter],
) -> Result<(FlexCanModel, CanRt<RX, TX>), BeginError> {
    begin_in_on::<Imxrt1062, RX, TX>(target, settings, primary, secondary)
}

/// [`begin_on_exact`] for a Teensy 4 module, in the RT1062 layout.
pub fn begin_rt_on_exact<const RX: usize, const TX: usize>(
    target: Target,
    settings: &Settings,
    primary: &[Filter],
    secondary: &[Filter],
) -> Result<(FlexCanModel, CanRt<RX, TX>), BeginError> {
    begin_in_on_exact::<Imxrt1062, RX, TX>(target, settings, primary, secondary)
}

/// [`begin_on`] in the layout `L`.
fn begin_in_on<L: Layout, const RX: usize, const TX: usize>(
    target: Target,
    settings: &Settings,
    primary: &[Filter],
    secondary: &[Filter],
) -> Result<(FlexCanModel, CanIn<L, RX, TX>), BeginError> {
    if primary.is_empty() && secondary.is_empty() {
        return begin_in_on_exact::<L, RX, TX>(target, settings, &[Filter::pass_all()], &[]);
    }
    begin_in_on_exact::<L, RX, TX>(target, settings, primary, secondary)
}

/// [`begin_on_exact`] in the layout `L` (`FlexCan::begin` is the Kinetis layout's).
fn begin_in_on_exact<L: Layout, const RX: usize, const TX: usize>(
    target: Target,
    settings: &Settings,
    primary: &[Filter],
    secondary: &[Filter],
) -> Result<(FlexCanModel, CanIn<L, RX, TX>), BeginError> {
    let model = model_of(target);
    model.scramble_ram(0x5EED);
    let controller = FlexCan::<_, L>::begin_with_layout(
        Ticking::new(model.clone()),
        &mut HostSystem::new(),
        target,
        settings,
        primary,
        secondary,
    )?;
    Ok((model, Driver::new(controller.into_split())))
}

/// `begin` on can0 of a Teensy 3.2.
pub fn begin<const RX: usize, const TX: usize>(
    settings: &Settings,
    primary: &[Filter],
    secondary: &[Filter],
) -> Result<(FlexCanModel, Can<RX, TX>), BeginError> {
    begin_on(
        Target::new(Board::Teensy32, Instance::Can0),
        settings,
        primary,
        secondary,
    )
}

/// ACAN §4's settings: loop-back and self reception.
pub fn loop_back(bit_rate: u32) -> Settings {
    let mut s = Settings::new(bit_rate);
    s.loop_back = true;
    s.self_reception = true;
    s
}

/// Something whose interrupt the test services.
pub trait Service {
    /// Calls `on_interrupt` if the model raises an interrupt line.
    fn service(&mut self);
}

impl<O: twocan_flexcan::options::Options, const RX: usize, const TX: usize> Service
    for Driver<FlexCanHw<Ticking, O>, RX, TX>
{
    fn service(&mut self) {
        if self.hardware().registers().irq_pending() {
            self.on_interrupt();
        }
    }
}

/// A bus with the given models attached in order.
pub fn bus_with(bit_rate: u32, models: &[&FlexCanModel]) -> Bus {
    let mut bus = Bus::new(bit_rate).expect("bus");
    for (i, m) in models.iter().enumerate() {
        bus.attach(&format!("can{i}"), (*m).clone());
    }
    bus
}

/// Runs the bus for `bits` bit times, servicing every driver after each event.
pub fn run(bus: &mut Bus, nodes: &mut [&mut dyn Service], bits: u64) {
    let until = bus.now() + bits;
    loop {
        for n in nodes.iter_mut() {
            n.service();
        }
        if bus.step_until(until).is_none() {
            break;
        }
    }
    for n in nodes.iter_mut() {
        n.service();
    }
}

/// Runs one driver's bus for `bits` bit times.
pub fn run1<O: twocan_flexcan::options::Options, const RX: usize, const TX: usize>(
    bus: &mut Bus,
    can: &mut Driver<FlexCanHw<Ticking, O>, RX, TX>,
    bits: u64,
) {
    run(bus, &mut [can], bits);
}

/// Every frame in the receive ring.
pub fn drain<O: twocan_flexcan::options::Options, const RX: usize, const TX: usize>(
    can: &mut Driver<FlexCanHw<Ticking, O>, RX, TX>,
) -> Vec<RxFrame> {
    core::iter::from_fn(|| can.receive().ok()).collect()
}

/// A standard data frame.
pub fn std_data(id: u16, data: &[u8]) -> Frame {
    Frame::standard(id, data).unwrap()
}

/// An extended data frame.
pub fn ext_data(id: u32, data: &[u8]) -> Frame {
    Frame::extended(id, data).unwrap()
}

/// A remote frame.
pub fn remote(id: u32, extended: bool) -> Frame {
    Frame::remote(id, extended, 0).unwrap()
}

/// Sends each frame alone and gives the filter index it was received with, or `None`
/// if the filters rejected it.
pub fn indices(
    settings: &Settings,
    primary: &[Filter],
    secondary: &[Filter],
    frames: &[Frame],
) -> Vec<Option<u16>> {
    let (model, mut can) = begin::<32, 16>(settings, primary, secondary).expect("begin");
    let mut bus = bus_with(125_000, &[&model]);
    frames
        .iter()
        .map(|f| {
            can.try_send(f).unwrap();
            run1(&mut bus, &mut can, 1_000);
            let got = drain(&mut can);
            assert!(got.len() <= 1, "{got:?}");
            got.first().map(|rx| {
                assert_eq!(rx.frame, *f);
                rx.filter
            })
        })
        .collect()
}
