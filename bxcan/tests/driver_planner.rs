//! Pure tests of the filter planner and the bank numbering (no model): known optima,
//! exact acceptance and reported indices against can-core's `Filter::matches` in list
//! order, the notes' match-index example, direct bank configuration and typed errors.

use twocan_bxcan::filters::{Acceptance, NO_FILTER};
use twocan_bxcan::planner::MAX_FILTERS;
use twocan_bxcan::{
    plan, plan_dual, Bank, BankError, BankKind, Fifo, FifoPolicy, FilterPlan, PlanError,
    PlanOptions,
};
use twocan_core::{Filter, FilterError, Format, Frame, FrameKind};

const ALL: PlanOptions = PlanOptions::new(28);

fn kinds(p: &FilterPlan) -> Vec<BankKind> {
    p.banks().iter().map(|b| b.kind).collect()
}

/// The reference: index of the first filter of the list that matches.
fn first_match(filters: &[Filter], frame: &Frame) -> Option<u16> {
    filters
        .iter()
        .position(|f| f.matches(frame))
        .map(|i| i as u16)
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

/// Frames around every filter's identifier (single and double bit flips, both formats,
/// both kinds) plus every standard identifier and a random sample of extended ones.
fn sweep(filters: &[Filter], r: &mut Lcg) -> Vec<Frame> {
    let mut out = Vec::new();
    let mut push = |id: u32, ext: bool| {
        if ext {
            let id = id & 0x1FFF_FFFF;
            out.push(Frame::extended(id, &[]).unwrap());
            out.push(Frame::remote(id, true, 0).unwrap());
        } else {
            let id = id & 0x7FF;
            out.push(Frame::standard(id as u16, &[]).unwrap());
            out.push(Frame::remote(id, false, 0).unwrap());
        }
    };
    for id in 0..0x800 {
        push(id, false);
    }
    for f in filters {
        for ext in [false, true] {
            push(f.id, ext);
            for b in 0..29 {
                push(f.id ^ (1 << b), ext);
                for c in 0..b {
                    push(f.id ^ (1 << b) ^ (1 << c), ext);
                }
            }
        }
    }
    for _ in 0..5_000 {
        push(r.next(), true);
    }
    out
}

/// Exact acceptance and reported index, frame by frame.
fn check_exact(filters: &[Filter], p: &FilterPlan) {
    let mut r = Lcg(99);
    for frame in sweep(filters, &mut r) {
        let want = first_match(filters, &frame);
        let got = p.evaluate(&frame).map(|a: Acceptance| a.filter);
        assert_eq!(got, want, "frame {frame:?} filters {filters:?} plan {p:?}");
    }
}

#[test]
fn nine_standard_ids_take_three_banks() {
    // Identifiers of even parity: no two differ in one bit only, nothing to merge.
    let f: Vec<Filter> = (0u16..32)
        .filter(|i| i.count_ones() % 2 == 0)
        .take(9)
        .map(|i| Filter::standard(0x100 + i))
        .collect();
    let p = plan(&f, ALL).unwrap();
    assert_eq!(p.bank_count(), 3);
    assert_eq!(kinds(&p), [BankKind::List16; 3]);
    assert!(p.is_proven_optimal());
    check_exact(&f, &p);
    // Without merging, consecutive identifiers take the same three banks.
    let f: Vec<Filter> = (0..9).map(|i| Filter::standard(0x100 + i)).collect();
    let p = plan(&f, ALL.merge(false)).unwrap();
    assert_eq!(kinds(&p), [BankKind::List16; 3]);
    check_exact(&f, &p);
    // Merged: 0x100..=0x107 is one 16-bit mask entry, 0x108 the bank's second entry.
    let p = plan(&f, ALL.merge(true)).unwrap();
    assert_eq!(kinds(&p), [BankKind::Mask16]);
    assert_eq!(p.list_only_banks(), 3);
    check_exact(&f, &p);
}

#[test]
fn two_extended_ids_take_one_bank() {
    let f = [Filter::extended(0x1234_5678), Filter::extended(0x0000_0001)];
    let p = plan(&f, ALL).unwrap();
    assert_eq!(kinds(&p), [BankKind::List32]);
    check_exact(&f, &p);
}

#[test]
fn mixes() {
    // One standard and one extended id share a 32-bit list bank.
    let f = [Filter::standard(0x7FF), Filter::extended(0x1FFF_FFFF)];
    let p = plan(&f, ALL).unwrap();
    assert_eq!(kinds(&p), [BankKind::List32]);
    check_exact(&f, &p);

    // 9 standard + 2 extended: 3 × 16-bit list (the 9th id could also go to the 32-bit
    // list bank: 2 + 1 = 3 entries = 2 banks; either way 4 banks).
    let mut f: Vec<Filter> = (0..9).map(|i| Filter::standard(0x200 + i)).collect();
    f.push(Filter::extended(0x10));
    f.push(Filter::extended(0x11));
    let p = plan(&f, ALL.merge(false)).unwrap();
    assert_eq!(p.bank_count(), 4);
    check_exact(&f, &p);
    // Merged: 0x200..=0x207 and 0x208 in one 16-bit mask bank, the two extended ids in
    // a 32-bit list bank.
    let p = plan(&f, ALL.merge(true)).unwrap();
    assert_eq!(p.bank_count(), 2);
    check_exact(&f, &p);

    // 5 standard + 1 extended: 4 std in a 16-bit list, 1 std + 1 ext in a 32-bit list.
    let mut f: Vec<Filter> = (0..5).map(|i| Filter::standard(0x300 + i)).collect();
    f.push(Filter::extended(0x300));
    let p = plan(&f, ALL).unwrap();
    assert_eq!(p.bank_count(), 2);
    check_exact(&f, &p);

    // Kind "any" on a standard id: two 16-bit list entries; two such filters fill a bank.
    let f = [
        Filter::exact(FrameKind::Any, Format::Standard, 0x10),
        Filter::exact(FrameKind::Any, Format::Standard, 0x20),
    ];
    let p = plan(&f, ALL).unwrap();
    assert_eq!(p.bank_count(), 1);
    check_exact(&f, &p);

    // Ranges: two standard masks share a 16-bit mask bank; an extended mask that
    // compares low bits needs a 32-bit mask bank.
    let f = [
        Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, 0x120),
        Filter::masked(FrameKind::Any, Format::Standard, 0x700, 0x300),
        Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_FF00, 0x0012_3400),
    ];
    let p = plan(&f, ALL).unwrap();
    assert_eq!(p.bank_count(), 2);
    let mut k = kinds(&p);
    k.sort_by_key(|k| k.priority_class());
    assert_eq!(k, [BankKind::Mask32, BankKind::Mask16]);
    check_exact(&f, &p);
}

#[test]
fn extended_prefix_filters_use_16_bit_banks_only_when_exact() {
    // Mask = the 14 bits a 16-bit filter sees: exact in a 16-bit list slot.
    let prefix = Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_8000, 0x0ABC_8000);
    let p = plan(&[prefix], ALL).unwrap();
    assert_eq!(kinds(&p), [BankKind::List16]);
    check_exact(&[prefix], &p);
    // One more compared bit (EXID[14]) is invisible to a 16-bit filter: 32-bit mask.
    let finer = Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_C000, 0x0ABC_C000);
    let p = plan(&[finer], ALL).unwrap();
    assert_eq!(kinds(&p), [BankKind::Mask32]);
    check_exact(&[finer], &p);
}

#[test]
fn pass_all_and_kind_format_filters() {
    let f = [Filter::pass_all()];
    let p = plan(&f, ALL).unwrap();
    assert_eq!(p.bank_count(), 1);
    check_exact(&f, &p);
    let f = [
        Filter::kind_format(FrameKind::Remote, Format::Any),
        Filter::kind_format(FrameKind::Data, Format::Extended),
    ];
    let p = plan(&f, ALL).unwrap();
    assert_eq!(p.bank_count(), 1);
    check_exact(&f, &p);
}

#[test]
fn first_filter_in_list_order_is_reported_when_filters_overlap() {
    // A broad range first, then a narrower one overlapping it, then everything else.
    let f = [
        Filter::masked(FrameKind::Data, Format::Standard, 0x7F1, 0x100), // even 0x100..0x10E
        Filter::masked(FrameKind::Any, Format::Standard, 0x7FC, 0x104),  // 0x104..0x107
        Filter::exact(FrameKind::Data, Format::Standard, 0x105),         // shadowed by [1]
        Filter::kind_format(FrameKind::Data, Format::Any),               // the rest of data
        Filter::extended(0x42),                                          // shadowed by [3]
        Filter::exact(FrameKind::Remote, Format::Extended, 0x42),
    ];
    let p = plan(&f, ALL).unwrap();
    check_exact(&f, &p);
    let idx = |frame: Frame| p.evaluate(&frame).map(|a| a.filter);
    assert_eq!(idx(Frame::standard(0x104, &[]).unwrap()), Some(0));
    assert_eq!(idx(Frame::standard(0x105, &[]).unwrap()), Some(1));
    assert_eq!(idx(Frame::remote(0x104, false, 0).unwrap()), Some(1));
    assert_eq!(idx(Frame::extended(0x42, &[]).unwrap()), Some(3));
    assert_eq!(idx(Frame::remote(0x42, true, 0).unwrap()), Some(5));
    assert_eq!(idx(Frame::remote(0x43, true, 0).unwrap()), None);
}

#[test]
fn random_lists_are_exact_with_both_fifo_policies() {
    let mut r = Lcg(2024);
    for round in 0..60 {
        let n = 1 + (r.next() % 12) as usize;
        let mut f = Vec::new();
        for _ in 0..n {
            let kind =
                [FrameKind::Data, FrameKind::Remote, FrameKind::Any][(r.next() % 3) as usize];
            let base = 0x100 + r.next() % 16;
            let filter = match r.next() % 7 {
                0 | 1 => Filter::exact(kind, Format::Standard, base),
                2 => Filter::exact(kind, Format::Extended, base),
                3 => {
                    let m = 0x7FF & !(r.next() % 16);
                    Filter::masked(kind, Format::Standard, m, base & m)
                }
                4 => {
                    let m = 0x1FFF_FFFF & !(r.next() % 16);
                    Filter::masked(kind, Format::Extended, m, base & m)
                }
                5 => {
                    let m = 0x1FFF_8000 & !((r.next() % 4) << 15);
                    Filter::masked(kind, Format::Extended, m, (base << 15) & m)
                }
                _ => Filter::kind_format(
                    kind,
                    [Format::Standard, Format::Extended, Format::Any][(r.next() % 3) as usize],
                ),
            };
            f.push(filter);
        }
        let policy = if round % 2 == 0 {
            FifoPolicy::Fifo0
        } else {
            FifoPolicy::Balanced
        };
        let p = plan(&f, ALL.fifo(policy)).unwrap();
        check_exact(&f, &p);
        // Balancing never costs a bank.
        let p0 = plan(&f, ALL).unwrap();
        assert_eq!(p.bank_count(), p0.bank_count());
    }
}

#[test]
fn balanced_plan_uses_both_fifos_and_keeps_overlaps_together() {
    let mut f: Vec<Filter> = (0..8).map(|i| Filter::standard(0x100 + i)).collect();
    f.push(Filter::extended(0x1234));
    f.push(Filter::extended(0x1235));
    let p = plan(&f, ALL.fifo(FifoPolicy::Balanced)).unwrap();
    assert!(p.uses_fifo(Fifo::Fifo0) && p.uses_fifo(Fifo::Fifo1));
    check_exact(&f, &p);
    let p1 = plan(&f, ALL.fifo(FifoPolicy::Fifo1)).unwrap();
    assert!(!p1.uses_fifo(Fifo::Fifo0));
    check_exact(&f, &p1);
}

#[test]
fn typed_errors() {
    // 29 extended ranges that compare low bits: one 32-bit mask bank each.
    let f: Vec<Filter> = (0..29)
        .map(|i| Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_FFF0, i << 8))
        .collect();
    assert_eq!(
        plan(&f, ALL),
        Err(PlanError::TooManyBanks {
            needed: 29,
            available: 28
        })
    );
    assert_eq!(
        plan(&f[..14], PlanOptions::new(14)).map(|p| p.bank_count()),
        Ok(14)
    );
    assert_eq!(
        plan(&f[..15], PlanOptions::new(14)),
        Err(PlanError::TooManyBanks {
            needed: 15,
            available: 14
        })
    );
    let bad = [Filter::standard(1), Filter::standard(0x800)];
    assert_eq!(
        plan(&bad, ALL),
        Err(PlanError::Filter {
            index: 1,
            error: FilterError::IdOutOfRange
        })
    );
    let many = vec![Filter::standard(1); MAX_FILTERS + 1];
    assert_eq!(
        plan(&many, ALL),
        Err(PlanError::TooManyFilters {
            given: MAX_FILTERS as u16 + 1,
            max: MAX_FILTERS as u16
        })
    );
    // Duplicates are shadowed: 128 copies of one id need one bank.
    let dup = vec![Filter::standard(1); MAX_FILTERS];
    assert_eq!(plan(&dup, ALL).unwrap().bank_count(), 1);
    let mut m = FilterPlan::manual();
    assert_eq!(
        m.set_bank(28, Bank::unused()),
        Err(PlanError::BankOutOfRange)
    );
    assert_eq!(
        Bank::list32(
            &Filter::standard(1),
            &Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, 0),
            Fifo::Fifo0
        ),
        Err(BankError::NotRepresentable { slot: 1 })
    );
    assert_eq!(
        Bank::mask16(&Filter::pass_all(), &Filter::extended(5), Fifo::Fifo0),
        Err(BankError::NotRepresentable { slot: 1 })
    );
    assert_eq!(
        Bank::mask32(&Filter::standard(0x900), Fifo::Fifo0),
        Err(BankError::Filter {
            slot: 0,
            error: FilterError::IdOutOfRange
        })
    );
}

/// The notes' "Example of filter numbering" table (RM0410 figure "Example of filter
/// numbering"): banks 0..13 with their FIFO, scale/mode and activation.
#[test]
fn match_index_numbering_follows_the_notes_example() {
    use BankKind::*;
    let f0 = Fifo::Fifo0;
    let f1 = Fifo::Fifo1;
    let layout: [(BankKind, Fifo, bool); 14] = [
        (List32, f0, true),  // 0: FIFO0 0, 1
        (Mask32, f0, true),  // 1: FIFO0 2
        (Mask16, f1, true),  // 2: FIFO1 0, 1
        (List16, f0, true),  // 3: FIFO0 3..6
        (List32, f1, true),  // 4: FIFO1 2, 3
        (List32, f0, false), // 5: FIFO0 7, 8 (deactivated)
        (Mask16, f0, true),  // 6: FIFO0 9, 10
        (Mask16, f1, false), // 7: FIFO1 4, 5 (deactivated)
        (Mask16, f1, true),  // 8: FIFO1 6, 7
        (List32, f0, true),  // 9: FIFO0 11, 12
        (List16, f1, false), // 10: FIFO1 8..11 (deactivated)
        (List32, f1, true),  // 11: FIFO1 12, 13
        (Mask32, f1, true),  // 12: FIFO1 14
        (Mask32, f0, true),  // 13: FIFO0 13
    ];
    let mut p = FilterPlan::manual();
    for (i, (kind, fifo, active)) in layout.iter().enumerate() {
        let b = Bank::raw(*kind, *fifo, 0, 0);
        p.set_bank(i, if *active { b } else { b.deactivated() })
            .unwrap();
    }
    let first: [(Fifo, u8); 14] = [
        (f0, 0),
        (f0, 2),
        (f1, 0),
        (f0, 3),
        (f1, 2),
        (f0, 7),
        (f0, 9),
        (f1, 4),
        (f1, 6),
        (f0, 11),
        (f1, 8),
        (f1, 12),
        (f1, 14),
        (f0, 13),
    ];
    for (bank, want) in first.iter().enumerate() {
        assert_eq!(p.fmi_of(bank, 0), Some(*want), "bank {bank}");
    }
    assert_eq!(p.fmi_of(3, 3), Some((f0, 6)));
    assert_eq!(p.fmi_of(10, 3), Some((f1, 11)));
    assert_eq!(p.fmi_of(1, 1), None);
    // Manual plans report 4 × bank + slot.
    assert_eq!(p.user_index(f1, 13), FilterPlan::slot_index(11, 1));
    assert_eq!(p.user_index(f0, 14), NO_FILTER);
}

#[test]
fn hardware_priority_rules() {
    // Bank 0: 16-bit mask accepting 0x123; bank 1: 16-bit list with 0x123; bank 2:
    // 32-bit mask accepting it; bank 3: 32-bit list with it.
    let id = Filter::standard(0x123);
    let range = Filter::masked(FrameKind::Data, Format::Standard, 0x700, 0x100);
    let mut p = FilterPlan::manual();
    p.set_bank(0, Bank::mask16(&range, &range, Fifo::Fifo0).unwrap())
        .unwrap();
    p.set_bank(1, Bank::list16([&id, &id, &id, &id], Fifo::Fifo0).unwrap())
        .unwrap();
    p.set_bank(2, Bank::mask32(&range, Fifo::Fifo0).unwrap())
        .unwrap();
    p.set_bank(3, Bank::list32(&id, &id, Fifo::Fifo0).unwrap())
        .unwrap();
    let frame = Frame::standard(0x123, &[]).unwrap();
    // 32-bit list wins: bank 3 slot 0.
    assert_eq!(
        p.evaluate(&frame).unwrap().filter,
        FilterPlan::slot_index(3, 0)
    );
    p.set_bank(3, Bank::unused()).unwrap();
    assert_eq!(
        p.evaluate(&frame).unwrap().filter,
        FilterPlan::slot_index(2, 0)
    );
    p.set_bank(2, Bank::unused()).unwrap();
    assert_eq!(
        p.evaluate(&frame).unwrap().filter,
        FilterPlan::slot_index(1, 0)
    );
    p.set_bank(1, Bank::unused()).unwrap();
    // Equal scale and mode: the lower number.
    assert_eq!(
        p.evaluate(&frame).unwrap().filter,
        FilterPlan::slot_index(0, 0)
    );
    assert_eq!(p.evaluate(&Frame::standard(0x223, &[]).unwrap()), None);
}

#[test]
fn direct_configuration_of_all_four_modes() {
    let a = Filter::standard(0x10);
    let b = Filter::exact(FrameKind::Remote, Format::Extended, 0x1_0000);
    let c = Filter::masked(FrameKind::Any, Format::Standard, 0x7F0, 0x200);
    let d = Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_8000, 0x1FFF_8000);
    let mut p = FilterPlan::manual();
    p.set_bank(0, Bank::list32(&a, &b, Fifo::Fifo0).unwrap())
        .unwrap();
    p.set_bank(1, Bank::mask32(&c, Fifo::Fifo1).unwrap())
        .unwrap();
    p.set_bank(2, Bank::mask16(&c, &d, Fifo::Fifo0).unwrap())
        .unwrap();
    p.set_bank(3, Bank::list16([&a, &a, &a, &d], Fifo::Fifo1).unwrap())
        .unwrap();
    let ev = |f: Frame| p.evaluate(&f).map(|x| (x.fifo, x.fmi, x.filter));
    assert_eq!(
        ev(Frame::standard(0x10, &[]).unwrap()),
        Some((Fifo::Fifo0, 0, 0))
    );
    assert_eq!(
        ev(Frame::remote(0x1_0000, true, 1).unwrap()),
        Some((Fifo::Fifo0, 1, 1))
    );
    // 32-bit mask (FIFO 1) beats the 16-bit mask (FIFO 0) for 0x205.
    assert_eq!(
        ev(Frame::standard(0x205, &[]).unwrap()),
        Some((Fifo::Fifo1, 0, 4))
    );
    // 16-bit list (FIFO 1, numbers 1..4 after bank 1's 0) beats the 16-bit mask.
    assert_eq!(
        ev(Frame::extended(0x1FFF_8123, &[]).unwrap()),
        Some((Fifo::Fifo1, 4, 15))
    );
    assert_eq!(ev(Frame::extended(0x1FFF_0123, &[]).unwrap()), None);
}

#[test]
fn large_overlapping_lists_are_planned_quickly_and_exactly() {
    let mut r = Lcg(5);
    let mut planned = 0;
    for n in [20, 30, 40, 50] {
        let mut f = Vec::new();
        for _ in 0..n {
            let base = r.next() % 64;
            let filter = match r.next() % 4 {
                0 => Filter::standard(base as u16),
                1 => Filter::extended(base),
                2 => {
                    let m = 0x7FF & !(r.next() % 8);
                    Filter::masked(FrameKind::Data, Format::Standard, m, base & m)
                }
                _ => {
                    let m = 0x1FFF_FFFF & !(r.next() % 2);
                    Filter::masked(FrameKind::Remote, Format::Extended, m, base & m)
                }
            };
            f.push(filter);
        }
        let start = std::time::Instant::now();
        let p = plan(&f, ALL);
        assert!(start.elapsed().as_secs() < 5);
        match p {
            Ok(p) => {
                check_exact(&f, &p);
                planned += 1;
            }
            Err(e) => assert!(matches!(e, PlanError::TooManyBanks { .. }), "{e:?}"),
        }
    }
    assert!(planned >= 2);
}

#[test]
fn evaluate_breaks_cross_fifo_ties_by_bank_number() {
    // Two 32-bit mask banks accepting the same frames, in different FIFOs: equal scale
    // and mode, so the lower bank number wins (RM0410 is silent; the model does so too,
    // see `driver_rx.rs`).
    for (low, high) in [(Fifo::Fifo1, Fifo::Fifo0), (Fifo::Fifo0, Fifo::Fifo1)] {
        let mut p = FilterPlan::manual();
        p.set_bank(0, Bank::mask32(&Filter::pass_all(), low).unwrap())
            .unwrap();
        p.set_bank(1, Bank::mask32(&Filter::pass_all(), high).unwrap())
            .unwrap();
        let frame = Frame::standard(0x123, &[]).unwrap();
        let a = p.evaluate(&frame).unwrap();
        assert_eq!((a.fifo, a.fmi), (low, 0));
        assert_eq!(a.filter, p.user_index(low, 0));
    }
}

#[test]
fn dual_plans_choose_can2sb() {
    // CAN1: 20 scattered standard ids (5 banks); CAN2: 6 extended ids (3 banks).
    let can1: Vec<Filter> = (0..20u16).map(|i| Filter::standard(i * 0x51)).collect();
    let can2: Vec<Filter> = (0..6u32).map(|i| Filter::extended(i * 0x1001)).collect();
    let d = plan_dual(&can1, &can2, ALL).unwrap();
    assert_eq!(d.can2sb as usize, d.can1.bank_count());
    assert_eq!(d.can1.bank_count(), 5);
    assert!(d.can2.bank_count() <= 28 - d.can2sb as usize);
    check_exact(&can1, &d.can1);
    check_exact(&can2, &d.can2);
    // 29 single-bank masks on CAN1 and one on CAN2: says who needs what.
    let big: Vec<Filter> = (0..29)
        .map(|i| Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_FFF0, i << 8))
        .collect();
    assert_eq!(
        plan_dual(&big, &big[..1], ALL),
        Err(PlanError::DualTooManyBanks {
            can1_needed: 29,
            can2_needed: 1,
            available: 28
        })
    );
    assert_eq!(
        twocan_core::Error::from(PlanError::TooManyBanks {
            needed: 40,
            available: 14
        }),
        twocan_core::Error::FilterSpace {
            needed: 40,
            available: 14
        }
    );
}
