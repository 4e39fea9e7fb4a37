//! The injector places a fault at the exact bit it names or refuses it with a typed error;
//! it never moves it.

use twocan_core::{Frame, LastErrorCode};
use twocan_sim::{frame_bits, Bus, Fault, FaultError, FormField, Receivers, SimNode};

fn bus_with_two() -> (
    Bus,
    std::rc::Rc<std::cell::RefCell<SimNode>>,
    twocan_sim::NodeId,
) {
    let mut bus = Bus::new(500_000).unwrap();
    let a = SimNode::new().shared();
    let id = bus.attach("a", a.clone());
    bus.attach("b", SimNode::new().shared());
    (bus, a, id)
}

#[test]
fn faults_impossible_in_any_frame_are_refused_at_injection() {
    let (mut bus, _, id) = bus_with_two();
    assert_eq!(
        bus.try_inject_next(Fault::Form {
            who: Receivers::All,
            field: FormField::Eof(6)
        }),
        Err(FaultError::EofBitOutOfRange(6))
    );
    assert_eq!(
        bus.try_inject_next(Fault::FlagBit { who: id, bit: 6 }),
        Err(FaultError::FlagBitOutOfRange(6))
    );
    assert_eq!(
        bus.try_inject_next(Fault::StuckDominant { at: 30, bits: 0 }),
        Err(FaultError::EmptyStuckDominant)
    );
    // The infallible form records the refusal instead of dropping it silently.
    bus.inject_next(Fault::FlagBit { who: id, bit: 9 });
    assert_eq!(
        bus.refused_faults(),
        &[(
            Fault::FlagBit { who: id, bit: 9 },
            FaultError::FlagBitOutOfRange(9)
        )]
    );
}

#[test]
fn faults_the_frame_rules_out_are_refused_with_its_attempt_not_moved() {
    let f = Frame::standard(0x7FF, &[0x55]).unwrap();
    let bits = frame_bits(&f);
    let cases = [
        // Identifier 0x7FF: bit 1 is a recessive identifier bit, not a stuff bit.
        (
            Fault::Bit { at: Some(1) },
            FaultError::ArbitrationRecessiveBit(1),
        ),
        (
            Fault::Bit {
                at: Some(bits.crc_end + 1),
            },
            FaultError::AckSlot,
        ),
        (
            Fault::Bit {
                at: Some(bits.crc_end + 10),
            },
            FaultError::AfterEndOfFrame(bits.crc_end + 10),
        ),
        (
            Fault::Stuff {
                who: Receivers::All,
                at: Some(bits.crc_end),
            },
            FaultError::OutsideStuffedRegion(bits.crc_end),
        ),
        (
            Fault::StuckDominant { at: 3, bits: 4 },
            FaultError::StuckDuringArbitration(3),
        ),
    ];
    for (fault, error) in cases {
        let (mut bus, a, _) = bus_with_two();
        a.borrow_mut().send(f);
        bus.try_inject_next(fault).unwrap();
        bus.run_until_idle(10_000).unwrap();
        let recs = bus.trace().records();
        assert_eq!(recs.len(), 1, "{fault:?}: not applied elsewhere");
        assert!(recs[0].is_error_free());
        assert!(recs[0].faults.is_empty());
        assert_eq!(recs[0].refused, vec![(fault, error)]);
        assert_eq!(bus.refused_faults(), &[(fault, error)]);
    }
}

#[test]
fn a_dominant_arbitration_bit_takes_a_bit_error_where_it_is_named() {
    let f = Frame::standard(0x000, &[0x55]).unwrap();
    let (mut bus, a, id) = bus_with_two();
    a.borrow_mut().send(f);
    // Wire bit 3 (identifier bit 2) is dominant: reading it recessive is a bit error.
    bus.try_inject_next(Fault::Bit { at: Some(3) }).unwrap();
    bus.step().unwrap();
    let e = bus.trace().records()[0].first_error.unwrap();
    assert_eq!((e.node, e.code, e.bit), (id, LastErrorCode::BitDominant, 3));
    assert_eq!(a.borrow().counters().tec, 8);
}

#[test]
fn a_receiver_stuff_error_inside_arbitration_stays_there() {
    let f = Frame::standard(0x123, &[1]).unwrap();
    let mut bus = Bus::new(500_000).unwrap();
    let a = SimNode::new().shared();
    let b = SimNode::new().shared();
    bus.attach("a", a.clone());
    let ib = bus.attach("b", b.clone());
    a.borrow_mut().send(f);
    bus.try_inject_next(Fault::Stuff {
        who: Receivers::Node(ib),
        at: Some(4),
    })
    .unwrap();
    bus.step().unwrap();
    let e = bus.trace().records()[0].first_error.unwrap();
    assert_eq!((e.node, e.code, e.bit), (ib, LastErrorCode::Stuff, 4));
}
