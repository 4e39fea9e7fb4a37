//! Time-triggered communication mode of the bxCAN model: the 16-bit bit-time counter and
//! the start-of-frame time stamps (RM0410 40.7.2 "Time triggered communication mode";
//! notes "The bxCAN Time Triggered Communication Mode"), through registers.

#[path = "model_bus.rs"]
mod bus;

use bus::*;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{self, mcr, tdtxr, tixr};
use twocan_core::Registers;

#[test]
fn received_frames_are_stamped_at_their_start_of_frame() {
    let (mut m, mut bus) = started(BxCanModel::can1());
    bus.inject(&std_frame(0x1, &[]));
    assert_eq!(
        receive(&mut m, 0).unwrap().time,
        0,
        "TTCM = 0: no time stamp"
    );

    m.modify32(regs::MCR, |v| v | mcr::TTCM);
    let t0 = bus.now;
    bus.idle(100);
    bus.inject(&std_frame(0x2, &[1, 2]));
    assert_eq!(receive(&mut m, 0).unwrap().time, 100);
    let sof = bus.now + 7;
    bus.idle(7);
    bus.inject(&std_frame(0x3, &[]));
    assert_eq!(receive(&mut m, 0).unwrap().time as u64, sof - t0);
    // 16-bit counter: wraps.
    bus.idle(65_536);
    let sof = bus.now;
    bus.inject(&std_frame(0x4, &[]));
    assert_eq!(receive(&mut m, 0).unwrap().time as u64, (sof - t0) % 65_536);
    assert_eq!(m.state().timer as u64, (bus.now - t0) % 65_536);
}

#[test]
fn transmitted_frames_are_stamped_in_tdtxr() {
    let (mut a, _b, mut bus) = started_pair(BxCanModel::can1(), BxCanModel::can3());
    a.modify32(regs::MCR, |v| v | mcr::TTCM);
    let t0 = bus.now;
    bus.idle(250);
    load(&mut a, 2, &std_frame(0x10, &[1, 2, 3]));
    bus.step();
    let tdtr = a.read32(regs::tdtxr(2));
    assert_eq!(tdtxr::TIME.get(tdtr), 250);
    assert_eq!(tdtxr::DLC.get(tdtr), 3);
    assert!(bus.now - t0 > 250);
}

#[test]
fn transmit_global_time_replaces_data_bytes_6_and_7() {
    let (a, mut b, mut bus) = started_pair(BxCanModel::can1(), BxCanModel::can3());
    a.modify32(regs::MCR, |v| v | mcr::TTCM);
    bus.idle(0x1234);
    a.write32(regs::tdtxr(0), tdtxr::DLC.val(8) | tdtxr::TGT);
    a.write32(regs::tdlxr(0), 0x0403_0201);
    a.write32(regs::tdhxr(0), 0x0807_0605);
    a.write32(regs::tixr(0), tixr::STID.val(0x77) | tixr::TXRQ);
    bus.step();
    let got = receive(&mut b, 0).unwrap().frame;
    assert_eq!(
        got.data(),
        &[1, 2, 3, 4, 5, 6, 0x12, 0x34],
        "TIME[15:8] in byte 6, TIME[7:0] in 7"
    );
    assert_eq!(tdtxr::TIME.get(a.read32(regs::tdtxr(0))), 0x1234);

    // Without TTCM, TGT has no effect.
    a.modify32(regs::MCR, |v| v & !mcr::TTCM);
    a.write32(regs::tixr(0), tixr::STID.val(0x77) | tixr::TXRQ);
    bus.idle(3);
    bus.step();
    assert_eq!(
        receive(&mut b, 0).unwrap().frame.data(),
        &[1, 2, 3, 4, 5, 6, 7, 8]
    );
}

#[test]
fn the_counter_stops_in_sleep_mode() {
    let (mut m, mut bus) = started(BxCanModel::can1());
    m.modify32(regs::MCR, |v| v | mcr::TTCM);
    bus.idle(40);
    m.modify32(regs::MCR, |v| v | mcr::SLEEP);
    bus.idle(1000);
    m.modify32(regs::MCR, |v| v & !mcr::SLEEP);
    bus.idle(11);
    // Counted: the 40 bits before sleep mode; the counter runs again once sleep mode is
    // left (SLAK cleared after SYNC), which is when the frame starts.
    bus.inject(&std_frame(0x1, &[]));
    assert_eq!(receive(&mut m, 0).unwrap().time, 40);
}
