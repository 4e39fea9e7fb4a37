//! Planner v2 through the bxCAN model at register level: plans (merged, superset) are
//! written to the filter banks as a driver would, frames are sent on the simulated bus,
//! and each received frame's `RDTxR.FMI` is resolved on the "thread side" with
//! `FmiMap::resolve`. Every standard identifier (data and remote) and a sample of
//! extended ones are sent; exactly the requested frames must be delivered, each with
//! the index of the first user filter that matches it (reference:
//! `Filter::matches` in list order).

#[path = "model_bus.rs"]
mod bus;

use bus::*;
use twocan_bxcan::filters::MAX_LOOKUP_KEYS;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::planner::plan_for;
use twocan_bxcan::regs::{self, fa1r, ffa1r, fm1r, fmr, fs1r};
use twocan_bxcan::{plan, Fifo, FifoPolicy, PlanError, PlanOptions};
use twocan_core::{Filter, Format, Frame, FrameKind, Registers};

/// Plans with room for every lookup key (the driver's capacity is the subject of
/// `driver_lookup.rs`).
type FilterPlan = twocan_bxcan::FilterPlan<MAX_LOOKUP_KEYS>;

/// Programs the plan's banks (FINIT, deactivate, configure, activate).
fn install(m: &mut BxCanModel, p: &FilterPlan) {
    m.modify32(regs::FMR, |v| v | fmr::FINIT);
    m.write32(regs::FA1R, 0);
    let set = |v: u32, bit: u32, on: bool| if on { v | bit } else { v & !bit };
    for (i, b) in p.banks().iter().enumerate() {
        m.modify32(regs::FS1R, |v| set(v, fs1r::fsc(i), b.kind.is_32bit()));
        m.modify32(regs::FM1R, |v| set(v, fm1r::fbm(i), b.kind.is_list()));
        m.modify32(regs::FFA1R, |v| {
            set(v, ffa1r::ffa(i), b.fifo == Fifo::Fifo1)
        });
        m.write32(regs::fir1(i), b.fr1);
        m.write32(regs::fir2(i), b.fr2);
        m.modify32(regs::FA1R, |v| set(v, fa1r::fact(i), b.active));
    }
    m.modify32(regs::FMR, |v| v & !fmr::FINIT);
}

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> u32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 33) as u32
    }
}

/// Every standard identifier in both kinds, the extended identifiers of the filters and
/// their neighbours, and random extended identifiers.
fn frames(filters: &[Filter], r: &mut Lcg) -> Vec<Frame> {
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
        for d in 0..4 {
            ext(f.id ^ d);
            ext(f.id.wrapping_add(16 + d));
        }
    }
    for _ in 0..1500 {
        ext(r.next());
    }
    out
}

/// What the application sees: `(frame, user index)` for every delivered frame, and the
/// number of frames the hardware accepted that the resolver dropped.
fn run(p: &FilterPlan, frames: &[Frame]) -> (Vec<(Frame, u16)>, usize) {
    let mut m = BxCanModel::can1();
    let mut bus = TinyBus::new(&[&m]);
    enter_init(&mut m);
    install(&mut m, p);
    leave_init(&mut m, &mut bus);
    let map = p
        .fmi_map::<{ twocan_core::filter_set::MAX_KEYS }>()
        .unwrap();
    let mut delivered = Vec::new();
    let mut dropped = 0;
    for f in frames {
        bus.inject(f);
        for x in 0..2 {
            while let Some(r) = receive(&mut m, x) {
                assert_eq!(r.frame, *f);
                let fifo = if x == 0 { Fifo::Fifo0 } else { Fifo::Fifo1 };
                let (id, ext, rtr) = (f.raw_id(), f.is_extended(), f.is_remote());
                match map.resolve(fifo, r.fmi as u8, id, ext, rtr) {
                    Some(i) => delivered.push((*f, i)),
                    None => dropped += 1,
                }
            }
        }
    }
    (delivered, dropped)
}

fn check(filters: &[Filter], options: PlanOptions, r: &mut Lcg) -> FilterPlan {
    let p = plan_for::<MAX_LOOKUP_KEYS>(filters, options).unwrap();
    let frames = frames(filters, r);
    let (delivered, dropped) = run(&p, &frames);
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
    if !p.is_superset() {
        assert_eq!(dropped, 0);
    }
    p
}

fn std_ids(ids: impl IntoIterator<Item = u32>) -> Vec<Filter> {
    ids.into_iter()
        .map(|i| Filter::standard(i as u16))
        .collect()
}

#[test]
fn merged_plan_delivers_exactly_through_the_model() {
    let mut r = Lcg(1);
    // A DBC-like set: a block of 64, a block of 16 with holes, scattered ids, extended
    // J1939-like ids, and a mask filter and a kind-any filter in the list.
    let mut f = std_ids((0x500..0x540).chain([0x4E0, 0x4E1, 0x4E2, 0x4E3, 0x5D0, 0x5D1]));
    f.extend(std_ids((0x120..0x130).filter(|i| i % 5 != 0)));
    f.extend(std_ids([0x21, 0x22, 0x76C, 0x7FF, 0x000]));
    for pgn in [0xF004u32, 0xF005, 0xF006, 0xF007, 0xFEF1, 0xFEEE] {
        f.push(Filter::extended(0x18 << 24 | pgn << 8));
    }
    f.push(Filter::masked(
        FrameKind::Data,
        Format::Standard,
        0x7F0,
        0x600,
    ));
    f.push(Filter::exact(FrameKind::Any, Format::Standard, 0x123));
    // Shadowed by the mask filter above: index of the mask.
    f.push(Filter::standard(0x605));
    let p = check(&f, PlanOptions::new(28).merge(true), &mut r);
    assert!(p.bank_count() < p.list_only_banks() as usize, "{p:?}");
    // Both FIFOs: the resolver works per FIFO.
    let both = PlanOptions::new(28).merge(true).fifo(FifoPolicy::Balanced);
    let p = check(&f, both, &mut r);
    assert!(p.uses_fifo(Fifo::Fifo0) && p.uses_fifo(Fifo::Fifo1));
}

#[test]
fn superset_plan_delivers_exactly_and_drops_the_rest() {
    let mut r = Lcg(2);
    // 120 scattered standard ids need 30 16-bit list banks: more than CAN1's 14.
    let ids: Vec<u32> = (0..120).map(|i| (i * 17 + 3) % 0x800).collect();
    let f = std_ids(ids);
    assert!(plan(&f, PlanOptions::new(14)).is_err());
    let p = check(&f, PlanOptions::new(14).merge(true).superset(true), &mut r);
    // Every identifier of a superset slot is looked up: more keys than the default
    // driver keeps, refused at planning time with both counts.
    assert_eq!(
        plan(&f, PlanOptions::new(14).superset(true)),
        Err(PlanError::TooManyLookupKeys {
            needed: p.key_table().len() as u16,
            max: 64
        })
    );
    assert!(p.is_superset());
    assert!(p.bank_count() <= 14);
    // The drops the model saw are the plan's superset identifiers (data frames only:
    // the filters are data-frame filters, remote frames are not accepted).
    let frames: Vec<Frame> = (0..0x800u32)
        .map(|id| Frame::standard(id as u16, &[]).unwrap())
        .collect();
    let (_, dropped) = run(&p, &frames);
    assert_eq!(dropped as u64, p.superset_extra());
    let (accepted, weight_dropped) = p.drop_weight(frames.iter().map(|f| (f, 1)));
    assert_eq!(weight_dropped, dropped as u64);
    assert_eq!(accepted, 120 + dropped as u64);
}
