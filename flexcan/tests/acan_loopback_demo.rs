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
