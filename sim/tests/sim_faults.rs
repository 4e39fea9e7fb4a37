//! Error injection on the simulated bus: error frames, fault confinement, bus-off, recovery,
//! reproducible random faults.

use std::cell::RefCell;
use std::rc::Rc;

use twocan_core::{ErrorCounters, ErrorState, Frame, LastErrorCode};
use twocan_sim::fault::BUS_OFF_RECOVERY_SEQUENCES;
use twocan_sim::{
    frame_bits, Bus, BusEvent, Fault, FaultKind, FormField, NodeOutcome, RandomFaults, Receivers,
    SimNode, TxResult,
};

fn std_frame(id: u16, data: &[u8]) -> Frame {
    Frame::standard(id, data).unwrap()
}

fn node() -> Rc<RefCell<SimNode>> {
    SimNode::new().shared()
}

fn tx_results(n: &Rc<RefCell<SimNode>>) -> Vec<TxResult> {
    n.borrow().tx_reports().iter().map(|r| r.result).collect()
}

#[test]
fn crc_error_seen_by_one_receiver() {
    let mut bus = Bus::new(500_000).unwrap();
    let (a, b, c) = (node(), node(), node());
    let ia = bus.attach("a", a.clone());
    let ib = bus.attach("b", b.clone());
    let ic = bus.attach("c", c.clone());
    let f = std_frame(0x123, &[1, 2, 3]);
    a.borrow_mut().send(f);
    bus.inject_next(Fault::Crc {
        who: Receivers::Node(ic),
    });

    let Some(BusEvent::Frame(r)) = bus.step() else {
        panic!()
    };
    let bits = frame_bits(&f);
    let ce = bits.crc_end;
    // C flags after the ACK delimiter; A and B see that flag in EOF and echo it, so C reads
    // dominant after its own flag (rule 2).
    assert_eq!(
        r.first_error.map(|e| (e.node, e.code, e.bit)),
        Some((ic, LastErrorCode::Crc, ce + 2))
    );
    assert_eq!(
        r.outcome_of(ic),
        Some(NodeOutcome::ReceiveError {
            code: LastErrorCode::Crc,
            dominant_after_flag: true
        })
    );
    assert_eq!(
        r.outcome_of(ib),
        Some(NodeOutcome::ReceiveError {
            code: LastErrorCode::Form,
            dominant_after_flag: false
        })
    );
    assert_eq!(
        r.outcome_of(ia),
        Some(NodeOutcome::Transmitted(TxResult::Error(
            LastErrorCode::BitRecessive
        )))
    );
    assert!(r.acked && !r.delivered);
    // Up to the error, 6 flag bits + 1 echo bit, 8 delimiter bits, intermission.
    assert_eq!(r.duration(), u64::from(ce + 3 + 7 + 8 + 3));

    // The retransmission goes through.
    bus.run_until_idle(10_000).unwrap();
    assert_eq!(b.borrow().received_frames(), vec![f]);
    assert_eq!(c.borrow().received_frames(), vec![f]);
    assert_eq!(a.borrow().counters(), ErrorCounters { tec: 7, rec: 0 });
    assert_eq!(b.borrow().counters().rec, 0);
    assert!(c.borrow().counters().rec >= 7, "REC + 8 (rule 2) then - 1");
    let stats = bus.node_stats(ic).unwrap();
    assert_eq!((stats.received, stats.rx_errors), (1, 1));
}

#[test]
fn crc_error_at_every_receiver_means_no_acknowledge() {
    let mut bus = Bus::new(500_000).unwrap();
    let (a, b, c) = (node(), node(), node());
    bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    bus.attach("c", c.clone());
    a.borrow_mut().send(std_frame(0x10, &[]));
    bus.inject(
        0,
        Fault::Crc {
            who: Receivers::All,
        },
    );
    bus.run_until_idle(10_000).unwrap();
    assert_eq!(
        tx_results(&a),
        vec![TxResult::Error(LastErrorCode::Acknowledge), TxResult::Acked]
    );
    // The transmitter's flag starts in the ACK delimiter, before their CRC flags would.
    assert_eq!(b.borrow().rx_errors()[0].code, LastErrorCode::Form);
}

#[test]
fn form_error_in_last_but_one_eof_bit_gives_double_reception() {
    let mut bus = Bus::new(500_000).unwrap();
    let (a, b, c) = (node(), node(), node());
    bus.attach("a", a.clone());
    let ib = bus.attach("b", b.clone());
    bus.attach("c", c.clone());
    let f = std_frame(0x55, &[5]);
    a.borrow_mut().send(f);
    bus.inject_next(Fault::Form {
        who: Receivers::Node(ib),
        field: FormField::Eof(5),
    });
    bus.run_until_idle(10_000).unwrap();
    // B's flag hits the last EOF bit: C already accepted the frame (overload condition),
    // A has not (error), so A sends it again and C gets it twice.
    assert_eq!(
        tx_results(&a)[0],
        TxResult::Error(LastErrorCode::BitRecessive)
    );
    assert_eq!(c.borrow().received_frames(), vec![f, f]);
    assert_eq!(b.borrow().received_frames(), vec![f]);
    assert!(bus.trace().records()[0].delivered);
}

#[test]
fn stuff_error_at_a_receiver_and_transmitter_bit_error() {
    let mut bus = Bus::new(500_000).unwrap();
    let (a, b) = (node(), node());
    bus.attach("a", a.clone());
    let ib = bus.attach("b", b.clone());
    let f = std_frame(0x321, &[0xAA, 0x55]);
    a.borrow_mut().send(f);
    let arb = frame_bits(&f).arbitration_end;
    bus.inject(
        0,
        Fault::Stuff {
            who: Receivers::Node(ib),
            at: Some(arb + 3),
        },
    );
    bus.inject(1, Fault::Bit { at: None });
    bus.run_until_idle(10_000).unwrap();
    let recs = bus.trace().records();
    assert_eq!(recs.len(), 3);
    let e0 = recs[0].first_error.unwrap();
    assert_eq!(
        (e0.node, e0.code, e0.bit),
        (ib, LastErrorCode::Stuff, arb + 3)
    );
    let e1 = recs[1].first_error.unwrap();
    assert!(e1.transmitter && e1.bit == arb);
    assert!(matches!(
        e1.code,
        LastErrorCode::BitDominant | LastErrorCode::BitRecessive
    ));
    assert!(recs[2].is_error_free());
    // An error frame is at most: error bit + 12 flag bits + 8 delimiter + 3 intermission.
    for r in &recs[..2] {
        let e = r.first_error.unwrap();
        assert!(r.duration() <= u64::from(e.bit) + 1 + 12 + 8 + 3);
        assert!(r.duration() >= u64::from(e.bit) + 1 + 6 + 8 + 3);
    }
    assert_eq!(a.borrow().counters().tec, 15);
}

#[test]
fn injected_errors_drive_a_node_bus_off_and_it_recovers_after_128_x_11_bits() {
    let mut bus = Bus::new(500_000).unwrap();
    let (a, b) = (node(), node());
    let ia = bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    let f = std_frame(0x100, &[0xC0, 0xFF, 0xEE]);
    a.borrow_mut().send(f);
    bus.inject_from(ia, 32, Fault::Bit { at: None });

    // 32 bit errors: TEC 8, 16, ... 256 > 255. From TEC 128 on, suspend transmission keeps
    // the node idle for 8 bits after each intermission.
    for i in 0..32 {
        let r = loop {
            match bus.step_until(u64::MAX) {
                Some(BusEvent::Frame(r)) => break r,
                Some(BusEvent::Idle { from, to }) => {
                    assert!(i >= 16 && to - from == 8, "attempt {i}: idle {from}..{to}")
                }
                other => panic!("attempt {i}: {other:?}"),
            }
        };
        assert!(!r.is_error_free());
        let expected = if i < 31 { (i + 1) * 8 } else { 256 };
        assert_eq!(a.borrow().counters().tec, expected);
    }
    assert_eq!(a.borrow().state(), ErrorState::BusOff);
    assert_eq!(a.borrow().bus_off_count(), 1);
    let off_end = bus.now();
    // Bus-off: no attempt while the 128 x 11 recessive bits have not passed.
    assert!(bus.step().is_none());
    let events = bus.run_for(1000);
    assert!(events.iter().all(|e| matches!(e, BusEvent::Idle { .. })));
    assert_eq!(a.borrow().state(), ErrorState::BusOff);

    // The recessive tail of the last error frame (8 delimiter + 3 intermission bits) is the
    // first sequence; the node wakes the bus exactly when the 128th completes.
    bus.run_until_idle(10_000).unwrap();
    let last = bus.trace().records().last().unwrap().clone();
    assert!(last.is_error_free());
    assert_eq!(
        last.sof,
        off_end - 11 + 11 * u64::from(BUS_OFF_RECOVERY_SEQUENCES)
    );
    assert_eq!(a.borrow().counters(), ErrorCounters { tec: 0, rec: 0 });
    assert_eq!(b.borrow().received_frames(), vec![f]);
    assert_eq!(bus.node_stats(ia).unwrap().tx_errors, 32);
}

#[test]
fn bus_off_node_does_not_take_part_and_recovers_by_hand() {
    let mut bus = Bus::new(500_000).unwrap();
    let a = SimNode::new().with_manual_recovery(true).shared();
    let (b, c) = (node(), node());
    let ia = bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    bus.attach("c", c.clone());
    a.borrow_mut().send(std_frame(0x1, &[]));
    bus.inject_from(ia, 32, Fault::Bit { at: None });
    // Idle with a bus-off node: nothing to do without recovery.
    bus.run_until_idle(100_000).unwrap();
    assert_eq!(a.borrow().state(), ErrorState::BusOff);
    assert_eq!(a.borrow().pending(), 1);
    // Traffic of others goes on without it; busy frames count toward recovery too
    // (their ACK delimiter + EOF + intermission are 11 recessive bits).
    for i in 0..127u8 {
        b.borrow_mut().send(std_frame(0x200, &[i]));
    }
    bus.run_until_idle(100_000).unwrap();
    assert!(a.borrow().received().is_empty());
    assert!(
        a.borrow().fault().recovery_condition_met(),
        "127 frames + the error frame's tail"
    );
    assert!(a.borrow_mut().recover());
    bus.run_until_idle(1_000).unwrap();
    assert_eq!(
        c.borrow().received().last().unwrap().frame,
        std_frame(0x1, &[])
    );
}

#[test]
fn error_passive_receiver_does_not_destroy_the_frame() {
    let mut bus = Bus::new(500_000).unwrap();
    let (a, b, c) = (node(), node(), node());
    bus.attach("a", a.clone());
    let ib = bus.attach("b", b.clone());
    bus.attach("c", c.clone());
    // Make B error-passive with CRC errors only it sees (rule 2 applies: the others echo its
    // flag). A good reception brings a REC above 127 back to 127, so B is error-passive
    // only between an error and the next good frame.
    for i in 0..40u8 {
        a.borrow_mut().send(std_frame(0x300, &[i]));
        bus.inject_next(Fault::Crc {
            who: Receivers::Node(ib),
        });
        assert!(bus.step().is_some());
        if b.borrow().state() == ErrorState::Passive {
            break;
        }
        bus.run_until_idle(10_000).unwrap();
    }
    assert_eq!(b.borrow().state(), ErrorState::Passive);
    let before = c.borrow().received().len();
    // A retransmits; B sees a CRC error again, but its passive flag is recessive: A and C
    // never notice.
    bus.inject_next(Fault::Crc {
        who: Receivers::Node(ib),
    });
    let Some(BusEvent::Frame(r)) = bus.step() else {
        panic!()
    };
    assert_eq!(r.first_error.map(|e| e.node), Some(ib));
    assert!(r.delivered);
    assert_eq!(tx_results(&a).last(), Some(&TxResult::Acked));
    assert_eq!(c.borrow().received().len(), before + 1);
    assert_eq!(
        b.borrow().rx_errors().last().map(|e| e.dominant_after_flag),
        Some(false)
    );
}

fn random_run(seed: u64) -> (String, Vec<twocan_sim::TraceRecord>) {
    let mut bus = Bus::new(500_000).unwrap();
    let nodes: Vec<_> = (0..3).map(|_| node()).collect();
    for (i, n) in nodes.iter().enumerate() {
        bus.attach(&format!("n{i}"), n.clone());
        for k in 0..20u8 {
            n.borrow_mut()
                .send(std_frame(0x100 + i as u16, &[k, i as u8]));
        }
    }
    bus.set_random_faults(Some(RandomFaults::new(seed, 0.3)));
    bus.run_until_idle(1_000_000).unwrap();
    let mut log = Vec::new();
    bus.trace()
        .write_candump_with_errors(&mut log, "vcan0")
        .unwrap();
    (
        String::from_utf8(log).unwrap(),
        bus.trace().records().to_vec(),
    )
}

#[test]
fn random_faults_are_reproducible() {
    let (log1, trace1) = random_run(0xC0FFEE);
    let (log2, trace2) = random_run(0xC0FFEE);
    assert_eq!(log1, log2);
    assert_eq!(trace1, trace2);
    let errored = trace1.iter().filter(|r| !r.faults.is_empty()).count();
    assert!(errored > 5, "{errored} faulty attempts");
    assert_eq!(
        trace1.iter().filter(|r| r.delivered).count(),
        60,
        "every frame gets through"
    );
    let (log3, _) = random_run(1);
    assert_ne!(log1, log3);
}

#[test]
fn random_faults_of_chosen_kinds_only() {
    let mut bus = Bus::new(500_000).unwrap();
    let (a, b) = (node(), node());
    bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    for k in 0..10u8 {
        a.borrow_mut().send(std_frame(0x10, &[k]));
    }
    bus.set_random_faults(Some(
        RandomFaults::new(5, 1.0).with_kinds(&[FaultKind::Crc]),
    ));
    // Every attempt fails: stop after a while.
    assert!(bus.run_until_idle(20_000).is_err());
    assert!(bus
        .trace()
        .records()
        .iter()
        .all(|r| r.faults.iter().all(|f| f.kind() == FaultKind::Crc)));
    bus.set_random_faults(None);
    bus.run_until_idle(20_000).unwrap();
    assert_eq!(b.borrow().received().len(), 10);
}
