//! ACAN §4, LoopBackDemo: 125 kbit/s, loop-back and self reception, no filter; send a
//! standard data frame 0x542, receive it back.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_flexcan::model::ModelMode;
use twocan_flexcan::ConfigErrors;

#[test]
fn loop_back_demo() {
    let settings = loop_back(125_000);
    assert_eq!(
        twocan_flexcan::check(
            twocan_flexcan::Target::new(
                twocan_flexcan::Board::Teensy32,
                twocan_flexcan::Instance::Can0
            ),
            &settings,
            &[],
            &[]
        ),
        ConfigErrors::NONE
    );
    let (model, mut can) = begin::<32, 16>(&settings, &[], &[]).expect("begin");
    assert_eq!(model.mode(), ModelMode::Normal);
    let mut bus = bus_with(125_000, &[&model]);

    let mut sent = 0;
    let mut received = 0;
    for _ in 0..5 {
        // Line 25: a standard data frame, identifier 0x542, no data.
        let message = std_data(0x542, &[]);
        can.try_send(&message).expect("tryToSend");
        sent += 1;
        run1(&mut bus, &mut can, 2_000);
        for rx in drain(&mut can) {
            assert_eq!(rx.frame, message);
            assert_eq!(rx.filter, 0, "no filter: everything is received, index 0");
            assert!(rx.timestamp.is_some());
            received += 1;
        }
    }
    assert_eq!((sent, received), (5, 5));
    let t = can.traffic();
    assert_eq!((t.queued, t.sent, t.received), (5, 5, 5));
}

#[test]
fn no_filter_at_all_receives_nothing_unlike_acan() {
    // twocan's portable rule: an empty pair of lists receives nothing (ID table format
    // D, MCR.IDAM = 0b11); ACAN's demo relies on the opposite (see docs/differences.md).
    let settings = loop_back(125_000);
    let (model, mut can) = begin_on_exact::<32, 16>(
        twocan_flexcan::Target::new(
            twocan_flexcan::Board::Teensy32,
            twocan_flexcan::Instance::Can0,
        ),
        &settings,
        &[],
        &[],
    )
    .expect("begin");
    assert_eq!(
        twocan_flexcan::regs::mcr::IDAM.get(model.peek32(twocan_flexcan::regs::MCR)),
        twocan_flexcan::regs::mcr::IDAM_FORMAT_D
    );
    let mut bus = bus_with(125_000, &[&model]);
    for _ in 0..5 {
        can.try_send(&std_data(0x542, &[])).expect("tryToSend");
        run1(&mut bus, &mut can, 2_000);
        assert!(drain(&mut can).is_empty());
    }
    let t = can.traffic();
    assert_eq!((t.queued, t.sent, t.received), (5, 5, 0));
    assert_eq!(model.frames_discarded(), 5);
}
