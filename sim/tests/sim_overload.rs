//! Overload frames (ISO 11898-1 §10.4.5): a dominant bit in the first two intermission bits,
//! or a receiver's dominant last EOF bit, starts an overload flag; the frame stays valid,
//! the counters do not move (except by rule 6).

use twocan_core::{ErrorCounters, Frame, LastErrorCode};
use twocan_sim::{frame_bits, Bus, Fault, FormField, Receivers, SimNode};

#[test]
fn dominant_first_intermission_bit_gives_an_overload_frame() {
    let mut bus = Bus::new(500_000).unwrap();
    let a = SimNode::new().shared();
    let b = SimNode::new().shared();
    bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    let f = Frame::standard(0x2F0, &[1, 2]).unwrap();
    let ce = frame_bits(&f).crc_end;
    a.borrow_mut().send(f);
    // The first intermission bit (ce + 10) is dominant.
    bus.try_inject_next(Fault::StuckDominant {
        at: ce + 10,
        bits: 1,
    })
    .unwrap();
    let r = bus.step().unwrap().record().unwrap().clone();
    assert!(r.is_error_free());
    // Both nodes send an overload flag ce+11..=ce+16 and an overload delimiter
    // ce+17..=ce+24; then the intermission: the attempt lasts ce + 25 + 3 bits instead of
    // ce + 10 + 3.
    assert_eq!(r.end - r.sof, u64::from(ce) + 28);
    assert_eq!(b.borrow().received_frames(), vec![f]);
    assert_eq!(a.borrow().counters(), ErrorCounters { tec: 0, rec: 0 });
    assert_eq!(b.borrow().counters(), ErrorCounters { tec: 0, rec: 0 });
    assert!(b.borrow().rx_errors().is_empty());
}

#[test]
fn overload_flag_counts_toward_rule_6() {
    let mut bus = Bus::new(500_000).unwrap();
    let a = SimNode::new().shared();
    let b = SimNode::new().shared();
    bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    let f = Frame::standard(0x2F1, &[3]).unwrap();
    let ce = frame_bits(&f).crc_end;
    a.borrow_mut().send(f);
    // Dominant from the first intermission bit for 15 bits (ce+10..=ce+24): the overload
    // flags start at ce+11, so ce+24 is the 14th consecutive dominant bit from the start
    // of each node's flag: +8 for both.
    bus.try_inject_next(Fault::StuckDominant {
        at: ce + 10,
        bits: 15,
    })
    .unwrap();
    bus.step().unwrap();
    assert_eq!(a.borrow().counters(), ErrorCounters { tec: 8, rec: 0 });
    assert_eq!(b.borrow().counters(), ErrorCounters { tec: 0, rec: 8 });
    assert_eq!(b.borrow().received_frames(), vec![f]);
}

#[test]
fn dominant_last_eof_bit_is_an_overload_condition_for_the_other_receivers() {
    let mut bus = Bus::new(500_000).unwrap();
    let a = SimNode::new().shared();
    let b = SimNode::new().shared();
    let c = SimNode::new().shared();
    bus.attach("a", a.clone());
    let ib = bus.attach("b", b.clone());
    bus.attach("c", c.clone());
    let f = Frame::standard(0x2F2, &[4]).unwrap();
    a.borrow_mut().send(f);
    // b reads a dominant EOF bit 6 (form error, flag from the last EOF bit): c reads the
    // last EOF bit dominant — the frame is valid for it and it sends an overload flag; the
    // transmitter reads it dominant too — a bit error — and sends the frame again.
    bus.inject_next(Fault::Form {
        who: Receivers::Node(ib),
        field: FormField::Eof(5),
    });
    bus.run_until_idle(10_000).unwrap();
    assert_eq!(c.borrow().received_frames(), vec![f, f]);
    assert!(c.borrow().rx_errors().is_empty());
    assert_eq!(b.borrow().received_frames(), vec![f]);
    assert_eq!(
        a.borrow().tx_reports()[0].result,
        twocan_sim::TxResult::Error(LastErrorCode::BitRecessive)
    );
}

#[test]
fn bit_error_in_an_overload_flag_counts_rule_4_and_5() {
    let mut bus = Bus::new(500_000).unwrap();
    let a = SimNode::new().shared();
    let b = SimNode::new().shared();
    let ia = bus.attach("a", a.clone());
    let ib = bus.attach("b", b.clone());
    let f = Frame::standard(0x2F3, &[5]).unwrap();
    let ce = frame_bits(&f).crc_end;
    a.borrow_mut().send(f);
    bus.try_inject_next(Fault::StuckDominant {
        at: ce + 10,
        bits: 1,
    })
    .unwrap();
    // Each node misreads bit 3 of its overload flag: +8 each (transmitter TEC, receiver
    // REC), and a new overload flag: ce+11..=ce+14, then ce+15..=ce+20 (the flag
    // restarts at the bit after the misread one), delimiter ce+21..=ce+28.
    bus.try_inject_next(Fault::FlagBit { who: ia, bit: 3 })
        .unwrap();
    bus.try_inject_next(Fault::FlagBit { who: ib, bit: 3 })
        .unwrap();
    let r = bus.step().unwrap().record().unwrap().clone();
    assert!(r.is_error_free());
    assert_eq!(a.borrow().counters(), ErrorCounters { tec: 8, rec: 0 });
    assert_eq!(b.borrow().counters(), ErrorCounters { tec: 0, rec: 8 });
    assert_eq!(r.end - r.sof, u64::from(ce) + 29 + 3);
}
