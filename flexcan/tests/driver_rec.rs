//! REC after a successful reception above 127, read through the driver: 127 on FlexCAN
//! (the Kinetis RM, "Error Counter (CANx_ECR)", allows 119..=127 as ISO 11898-1
//! §12.1.4.2 rule 8; the model takes 127), not bxCAN's 120.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_core::{ErrorCounters, ErrorState};
use twocan_flexcan::Settings;
use twocan_sim::{Bus, Fault, Receivers, SimNode};

#[test]
fn rec_after_a_good_reception_above_127_is_127() {
    let (model, mut can) = begin::<32, 16>(&Settings::new(500_000), &[], &[]).unwrap();
    let mut bus = Bus::new(500_000).unwrap();
    let me = bus.attach("can0", model.clone());
    let t = SimNode::new().with_one_shot(true).shared();
    let other = SimNode::new().shared();
    bus.attach("t", t.clone());
    bus.attach("other", other.clone());
    run1(&mut bus, &mut can, 20);
    // 15 CRC errors seen by can0 alone, each +1 (rule 1) +8 (rule 2): REC 135.
    for k in 0..15u16 {
        t.borrow_mut().send(std_data(0x200 + k, &[1]));
        bus.inject_next(Fault::Crc {
            who: Receivers::Node(me),
        });
        run1(&mut bus, &mut can, 300);
    }
    assert_eq!(can.counters(), ErrorCounters { tec: 0, rec: 135 });
    assert_eq!(can.state(), ErrorState::Passive);
    t.borrow_mut().send(std_data(0x300, &[2]));
    run1(&mut bus, &mut can, 300);
    assert_eq!(can.counters(), ErrorCounters { tec: 0, rec: 127 });
    assert_eq!(can.state(), ErrorState::Warning);
    let got = drain(&mut can);
    assert_eq!(got.last().map(|r| r.frame), Some(std_data(0x300, &[2])));
}
