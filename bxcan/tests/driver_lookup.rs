//! The merged-filter lookup capacity: a plan is made for the capacity of the driver it
//! will be installed in (`FilterPlan<K>`, the controller's `K`, default
//! [`LOOKUP_KEYS`]). A merged plan that would need more lookup keys gives way to one
//! that needs fewer (issue 22 item 8: 112 consecutive identifiers install in the
//! default driver), or the list is refused at planning time with both counts; a plan
//! made for a larger capacity is refused by a smaller controller before any bank
//! changes, and installs in a controller given that room, reporting every frame with
//! its user's index.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_bxcan::filters::LOOKUP_KEYS;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::planner::plan_for;
use twocan_bxcan::{plan, Can, PlanError, PlanOptions};
use twocan_core::{Error, Filter, Format, Frame, FrameKind, Hardware};

/// One exact filter per identifier `0x100..0x100 + n`: the planner merges aligned runs
/// into mask slots, each standing for several user filters, so every identifier of a
/// merged run needs a lookup key.
fn consecutive(n: u16) -> Vec<Filter> {
    (0..n)
        .map(|i| Filter::exact(FrameKind::Data, Format::Standard, 0x100 + i as u32))
        .collect()
}

#[test]
fn the_default_plan_fits_the_default_lookup_capacity() {
    // Issue 22 item 8: 112 consecutive identifiers merged need 111 lookup keys; the
    // plan for the default driver takes fewer (here the 28 banks of 16-bit lists).
    let filters = consecutive(112);
    let wide = plan_for::<1024>(&filters, PlanOptions::default()).unwrap();
    assert!(wide.key_table().len() > LOOKUP_KEYS);
    let p = plan(&filters, PlanOptions::default()).unwrap();
    assert!(p.key_table().len() <= LOOKUP_KEYS);
    assert!(p.bank_count() <= 28);
    for (i, f) in filters.iter().enumerate() {
        let frame = Frame::standard(f.id as u16, &[]).unwrap();
        assert_eq!(p.evaluate(&frame).unwrap().filter, i as u16);
    }
    // The capacity the driver reports for CAN1 alone (28 banks × 4 standard
    // identifiers) installs, whatever the identifiers: consecutive ones too.
    let all_banks = config().can2_start_bank(28).unwrap();
    let (can, _regs, _bus) = can1_with(&all_banks, &pass_all());
    let hw = can.into_split();
    let caps = hw.capabilities();
    assert_eq!(caps.max_standard_filters, 112);
    let p = hw.plan(&filters, twocan_bxcan::FifoPolicy::Fifo0).unwrap();
    // SAFETY (test): one context plays every role.
    unsafe { hw.install_filters(&p) }.unwrap();
    // Beyond the worst case the planner tells exactly: 113 consecutive identifiers
    // merge and fit.
    assert!(hw
        .plan(&consecutive(113), twocan_bxcan::FifoPolicy::Fifo0)
        .is_ok());
}

#[test]
fn a_plan_needing_more_lookup_keys_than_the_map_holds_is_refused_with_counts() {
    let filters = consecutive(128);
    // 0x100..0x17F is one cube of 128 identifiers: one mask slot, 128 lookup keys; in
    // 14 banks no plan does with the default 64 (one 64-key block and 64 identifiers in
    // lists take 17 banks): refused at planning time, with both counts.
    assert_eq!(
        plan(&filters, PlanOptions::new(14)).unwrap_err(),
        PlanError::TooManyLookupKeys {
            needed: 128,
            max: LOOKUP_KEYS as u16
        }
    );
    let p = plan_for::<128>(&filters, PlanOptions::new(14)).unwrap();
    assert_eq!(p.key_table().len(), 128);

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
    // The controller's own planner plans for its capacity.
    let own = init
        .can()
        .plan(&filters, twocan_bxcan::FifoPolicy::Fifo0)
        .unwrap();
    assert_eq!(own.key_table().len(), 128);
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
