//! The FlexCAN planner through the model at register level: a planned table is written
//! to the ID filter table, `RXIMRn` and `RXFGMASK` (format A, IRMQ = 1) as a driver
//! would, frames are delivered from the bus, and each frame popped from the Rx FIFO is
//! resolved on the "thread side" with `FilterTable::filter_index(RXFIR.IDHIT, frame)`.
//! Every standard identifier (data and remote) and a sample of extended ones are sent:
//! exactly the requested frames must be delivered, with the index of the first user
//! filter that matches (reference: `Filter::matches` in list order).

#[path = "model_support.rs"]
mod support;

use support::*;
use twocan_core::{Filter, Format, Frame, FrameKind};
use twocan_flexcan::filters::{LOOKUP_KEYS, MAX_LOOKUP_KEYS};
use twocan_flexcan::planner::{plan_for, PlanError, PlanOptions};
use twocan_flexcan::Configuration;

/// Tables with room for every lookup key: the planner unconstrained by a driver's
/// capacity (the default capacity is checked at the end of each test).
type FilterTable = twocan_flexcan::FilterTable<MAX_LOOKUP_KEYS>;

fn plan(filters: &[Filter], options: PlanOptions) -> Result<FilterTable, PlanError> {
    plan_for::<MAX_LOOKUP_KEYS>(filters, options)
}

fn frames(filters: &[Filter]) -> Vec<Frame> {
    let mut out = Vec::new();
    for id in 0..0x800u32 {
        out.push(Frame::standard(id as u16, &[]).unwrap());
        out.push(Frame::remote(id, false, 0).unwrap());
    }
    let mut ext = |id: u32| {
        out.push(Frame::extended(id & 0x1FFF_FFFF, &[]).unwrap());
        out.push(Frame::remote(id & 0x1FFF_FFFF, true, 0).unwrap());
    };
    for f in filters {
        for d in 0..8 {
            ext(f.id ^ d);
        }
    }
    let mut s = 0x1234_5678u32;
    for _ in 0..1500 {
        s = s.wrapping_mul(1_103_515_245).wrapping_add(12345);
        ext(s);
    }
    out
}

/// `(delivered (frame, index), dropped)` through the model.
fn run(t: &FilterTable, frames: &[Frame]) -> (Vec<(Frame, u16)>, u64) {
    let mut r = Rig::new();
    r.enable_into_freeze();
    r.setup_fifo(
        t.configuration().rffn() as u32,
        true,
        t.elements(),
        t.individual_masks(),
        t.global_mask(),
    );
    r.start();
    let mut delivered = Vec::new();
    let mut dropped = 0;
    for f in frames {
        r.deliver(f);
        while let Some((got, hit, _)) = r.pop_fifo() {
            assert_eq!(got, *f);
            match t.filter_index(hit as usize, &got) {
                Some(i) => delivered.push((got, i)),
                None => dropped += 1,
            }
        }
    }
    (delivered, dropped)
}

fn check(filters: &[Filter], options: PlanOptions) -> FilterTable {
    let t = plan(filters, options).unwrap();
    let frames = frames(filters);
    let (delivered, dropped) = run(&t, &frames);
    let want: Vec<(Frame, u16)> = frames
        .iter()
        .filter_map(|f| {
            filters
                .iter()
                .position(|x| x.matches(f))
                .map(|i| (*f, i as u16))
        })
        .collect();
    assert_eq!(delivered, want);
    if t.superset_extra() == 0 {
        assert_eq!(dropped, 0);
    }
    t
}

#[test]
fn merged_tables_deliver_exactly_through_the_model() {
    // A DBC-like set that fits no configuration without merging (75 identifiers).
    let mut f: Vec<Filter> = (0x500..0x540).map(Filter::standard).collect();
    f.extend([0x4E0, 0x4E1, 0x4E2, 0x4E3, 0x5D0, 0x5D1, 0x21].map(Filter::standard));
    f.push(Filter::extended(0x18FE_F100));
    f.push(Filter::masked(
        FrameKind::Data,
        Format::Standard,
        0x7F0,
        0x600,
    ));
    f.push(Filter::exact(FrameKind::Any, Format::Standard, 0x123));
    f.push(Filter::standard(0x605)); // shadowed by the mask filter: its index
    assert!(plan(&f, PlanOptions::default().merge(false)).is_err());
    let t = check(&f, PlanOptions::default());
    assert_eq!(t.configuration(), Configuration::Filters8_0);
    for c in Configuration::ALL {
        check(&f, PlanOptions::new(c));
    }
    // The 64-identifier block alone needs 64 lookup keys: with the default capacity
    // the planner splits blocks and takes a larger configuration, still exact.
    assert!(t.key_table().len() > LOOKUP_KEYS);
    let small = twocan_flexcan::planner::plan(&f, PlanOptions::default()).unwrap();
    assert!(small.key_table().len() <= LOOKUP_KEYS);
    for frame in frames(&f) {
        let want = f.iter().position(|x| x.matches(&frame)).map(|i| i as u16);
        assert_eq!(small.evaluate(&frame).and_then(|(_, i)| i), want);
    }
}

#[test]
fn superset_tables_deliver_exactly_and_drop_the_rest() {
    // 60 scattered standard identifiers: more than 14 + 18 elements.
    let f: Vec<Filter> = (0..60u16)
        .map(|i| Filter::standard(i * 33 % 0x800))
        .collect();
    assert!(plan(&f, PlanOptions::default()).is_err());
    let t = check(&f, PlanOptions::default().superset(true));
    assert!(t.superset_extra() > 0);
    let data: Vec<Frame> = (0..0x800u16)
        .map(|id| Frame::standard(id, &[]).unwrap())
        .collect();
    let (delivered, dropped) = run(&t, &data);
    assert_eq!(delivered.len(), 60);
    assert_eq!(dropped, t.superset_extra());
    // With every identifier equally likely, the drop weight is the extra identifiers.
    let (accepted, weight) = t.drop_weight(data.iter().map(|f| (f, 1)));
    assert_eq!((accepted, weight), (60 + dropped, dropped));
}
