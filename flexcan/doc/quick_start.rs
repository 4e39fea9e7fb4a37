// ACAN §4's LoopBackDemo on the host: FlexCAN's behavioural model (feature `model`) on
// the simulated bus. This file is the crate documentation's quick start and, verbatim,
// the workspace test `tests/tests/first_program.rs`.
use twocan_sim::Bus;
use twocan_core::{Filter, Format, Frame, FrameKind};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::{
    AcanDriver, Board, FlexCan, HostSystem, IdleClocked, Instance, Settings, Target,
};

fn main() {
    // ACAN §4, §16: 125 kbit/s from the 16 MHz clock, loop-back, self reception.
    let mut settings = Settings::new(125_000);
    settings.loop_back = true;
    settings.self_reception = true;
    assert!(settings.bit_rate_close_to_wished());

    // ACAN §12, §13: filter 0 is primary, filter 1 secondary.
    let primary = [Filter::exact(FrameKind::Data, Format::Standard, 0x542)];
    let secondary = [Filter::exact(FrameKind::Remote, Format::Extended, 0x1234)];

    // The model stands for FlexCAN0 of a Teensy 3.2 (firmware: `Can0::take()`).
    // `begin` waits for the module to synchronise (11 recessive bits): `IdleClocked`
    // lets idle bus time pass while the driver polls.
    let model = FlexCanModel::mk20dx256();
    let target = Target::new(Board::Teensy32, Instance::Can0);
    let regs = IdleClocked::new(model.clone());
    let controller =
        FlexCan::begin(regs, &mut HostSystem::new(), target, &settings, &primary, &secondary)
            .expect("begin: no error of ACAN table 5");
    // ACAN's buffers: receive 32, transmit 16.
    let mut can: AcanDriver<IdleClocked> = AcanDriver::new(controller.into_split());

    can.try_send(&Frame::standard(0x542, &[1, 2]).unwrap()).unwrap(); // tryToSend
    can.try_send(&Frame::remote(0x1234, true, 0).unwrap()).unwrap();

    // The bus runs; the "interrupt handler" runs between bus events.
    let mut bus = Bus::new(125_000).unwrap();
    bus.attach("can0", model.clone());
    while bus.step_until(1_000).is_some() {
        if model.irq_pending() {
            can.on_interrupt();
        }
    }
    // `receive`, with the filter index (ACAN `idx`). `try_send` keeps the request order,
    // remote frames included (ACAN's direct path to the remote-frame mailboxes, where
    // the extended 0x1234 would win arbitration over the standard 0x542, is
    // `try_send_now`).
    let first = can.receive().unwrap();
    assert_eq!((first.frame.raw_id(), first.filter), (0x542, 0));
    let second = can.receive().unwrap();
    assert_eq!((second.frame.raw_id(), second.filter), (0x1234, 1));
    assert_eq!(can.rx_stats().peak, 2); // receiveBufferPeakCount
}
