//! REC after a successful reception above 127, read through the driver: 120 on bxCAN
//! (the bxCAN notes after RM0410 §40.7.6 "Error management": "reset to 120"), not the
//! 127 of the other node kinds.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::Can;
use twocan_core::{ErrorCounters, ErrorState};
use twocan_sim::{Fault, Receivers, SimNode};

#[test]
fn rec_after_a_good_reception_above_127_is_120() {
    let bus = new_bus();
    let model = BxCanModel::can1();
    let me = bus.borrow_mut().attach("can1", model.clone());
    let t = SimNode::new().with_one_shot(true).shared();
    let other = SimNode::new().shared();
    bus.borrow_mut().attach("t", t.clone());
    bus.borrow_mut().attach("other", other.clone());
    let regs = Clocked::new(model, &bus);
    let mut init = Can::can1(regs.clone(), &config())
        .map_err(|f| f.error)
        .unwrap();
    init.set_filters(&pass_all()).unwrap();
    let can = init.enable().map_err(|f| f.error).unwrap();
    regs.ticking.set(false);
    let mut d = driver(can);
    // 15 CRC errors seen by CAN1 alone, each +1 (rule 1) +8 (rule 2: the others' flags
    // follow its own): REC 135, error-passive.
    for k in 0..15u16 {
        t.borrow_mut().send(std(0x200 + k));
        bus.borrow_mut().inject_next(Fault::Crc {
            who: Receivers::Node(me),
        });
        settle(&bus);
        d.on_interrupt();
    }
    assert_eq!(d.counters(), ErrorCounters { tec: 0, rec: 135 });
    assert_eq!(d.state(), ErrorState::Passive);
    // One good frame: REC 120 (bxCAN), error-warning (REC ≥ 96).
    t.borrow_mut().send(std(0x300));
    settle(&bus);
    d.on_interrupt();
    assert_eq!(d.counters(), ErrorCounters { tec: 0, rec: 120 });
    assert_eq!(d.state(), ErrorState::Warning);
    let got = drain(&mut d);
    assert_eq!(got.last().map(|r| r.frame), Some(std(0x300)));
}
