//! The driver's merged-filter lookup ([`twocan_bxcan::filters::FmiMap`]) is sized by the
//! controller's `K` (default [`LOOKUP_KEYS`]): a plan whose merged slots need more keys is
//! refused before any bank changes, with both counts; a controller given more room takes
//! it and reports every frame with its user's index.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_bxcan::filters::LOOKUP_KEYS;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::{plan, Can, PlanOptions};
use twocan_core::{Error, Filter, Format, Frame, FrameKind};

/// One exact filter per identifier `0x100..0x100 + n`: the planner merges aligned runs
/// into mask slots, each standing for several user filters, so every identifier of a
/// merged run needs a lookup key.
fn consecutive(n: u16) -> Vec<Filter> {
    (0..n)
        .map(|i| Filter::exact(FrameKind::Data, Format::Standard, 0x100 + i as u32))
        .collect()
}

#[test]
fn a_plan_needing_more_lookup_keys_than_the_map_holds_is_refused_with_counts() {
    let filters = consecutive(128);
    let p = plan(&filters, PlanOptions::new(14)).unwrap();
    // 0x100..0x17F is one cube of 128 identifiers: one mask slot, 128 lookup keys.
    assert_eq!(p.key_table().len(), 128);
    assert!(p.key_table().len() > LOOKUP_KEYS);

    let bus = new_bus();
    let model = BxCanModel::can1();
    bus.borrow_mut().attach("can1", model.clone());
    let regs = Clocked::new(model, &bus);
    let mut init = Can::can1(regs.clone(), &config())
        .map_err(|f| f.error)
        .unwrap();
    init.set_filters(&pass_all()).unwrap();
    assert_eq!(
        init.set_filters(&p),
        Err(Error::FilterSpace {
            needed: 128,
            available: LOOKUP_KEYS as u16
        })
    );
    let mut init = init.with_lookup_capacity::<128>();
    init.set_filters(&p).unwrap();
    let can = init.enable().map_err(|f| f.error).unwrap();
    let mut d = twocan_core::Driver::<_, 16, 8, 16>::new(can.into_split());
    let peer = twocan_sim::SimNode::new().shared();
    bus.borrow_mut().attach("peer", peer.clone());
    settle(&bus);
    for id in [0x100u16, 0x13F, 0x17F, 0x180, 0x0FF] {
        peer.borrow_mut().send(Frame::standard(id, &[1]).unwrap());
        settle(&bus);
    }
    d.on_interrupt();
    let mut got = Vec::new();
    while let Ok(f) = d.receive() {
        got.push((f.frame.raw_id(), f.filter));
    }
    // Each identifier reported with its own user filter (index = id - 0x100); 0x180 and
    // 0x0FF match none and are not received.
    assert_eq!(got, vec![(0x100, 0), (0x13F, 0x3F), (0x17F, 0x7F)]);
}
