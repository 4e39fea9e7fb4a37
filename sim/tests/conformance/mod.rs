//! The fault-confinement conformance table, shared by the three node kinds: the simulated
//! node (`sim/tests/sim_conformance.rs`), the bxCAN model
//! (`bxcan/tests/model_conformance.rs`) and the FlexCAN model
//! (`flexcan/tests/model_conformance.rs`).
//!
//! Each case is one rule or exception of ISO 11898-1 §12.1.4.2 (Bosch CAN 2.0 part B §8)
//! or §10.4.6.4 (suspend transmission), played on the simulated bus with the node under
//! test ("dut") and plain [`SimNode`] peers. The expected counters, states and bit times
//! are worked out by hand in each case's comment from the frame layout
//! (`ce` = end of the CRC sequence = index of the CRC delimiter, from
//! [`twocan_sim::frame_bits`]) and the rules, not read back from a run.
//!
//! A node kind plugs in through [`Dut`]; [`conformance_tests!`] makes one `#[test]` per case.

#![allow(dead_code)]

use std::cell::RefCell;
use std::rc::Rc;

use twocan_core::{ErrorCounters, ErrorState, Frame, LastErrorCode};
use twocan_sim::fault::BUS_OFF_RECOVERY_SEQUENCES;
use twocan_sim::{
    frame_bits, Bus, BusEvent, Fault, FaultError, FormField, NodeId, Receivers, Sees, SimNode,
    TraceRecord,
};

/// A node kind under test, driven as its users drive it (registers for the models).
pub trait Dut: Sized {
    /// Builds the node with automatic retransmission and automatic bus-off recovery,
    /// attaches it to `bus` and lets it join the bus (synchronisation).
    fn join(bus: &mut Bus) -> (Self, NodeId);
    /// Queues one frame for transmission (at most one pending at a time in this table).
    fn send(&mut self, frame: &Frame);
    /// TEC and REC (TEC reads 256 while bus-off).
    fn counters(&self) -> ErrorCounters;
    /// The fault-confinement state as the controller reports it.
    fn state(&self) -> ErrorState;
    /// REC after a successful reception above 127, from the controller's manual.
    const REC_AFTER_PASSIVE_RECEPTION: u16;
}

/// What every case starts from: a bus at 500 kbit/s with the dut on it (it joins
/// first), then `N` plain nodes attached in order, each kept by the case (the bus drives
/// a clone).
struct Case<D, const N: usize> {
    bus: Bus,
    dut: D,
    /// The dut's place on the bus.
    id: NodeId,
    peers: [Rc<RefCell<SimNode>>; N],
    /// The plain nodes' places on the bus.
    ids: [NodeId; N],
}

impl<D: Dut, const N: usize> Case<D, N> {
    fn new(peers: [(&str, SimNode); N]) -> Self {
        let mut bus = Bus::new(500_000).unwrap();
        let (dut, id) = D::join(&mut bus);
        let peers = peers.map(|(name, node)| (name, node.shared()));
        let ids = peers
            .each_ref()
            .map(|(name, node)| bus.attach(name, node.clone()));
        Case {
            bus,
            dut,
            id,
            peers: peers.map(|(_, node)| node),
            ids,
        }
    }
}

/// The most common start: the dut and one plain peer `p` ([`Case`]).
fn with_peer<D: Dut>() -> (Bus, D, NodeId, Rc<RefCell<SimNode>>) {
    let Case {
        bus,
        dut,
        id,
        peers: [p],
        ..
    } = Case::<D, 1>::new([("p", SimNode::new())]);
    (bus, dut, id, p)
}

fn frame(id: u16) -> Frame {
    Frame::standard(id, &[0x5A, id as u8]).unwrap()
}

/// Runs until the next frame attempt on the wire and returns it.
fn next_frame(bus: &mut Bus) -> Box<TraceRecord> {
    for _ in 0..10_000 {
        match bus.step_until(u64::MAX) {
            Some(BusEvent::Frame(r)) => return r,
            Some(_) => continue,
            None => break,
        }
    }
    panic!("no frame attempt");
}

fn ce_of(f: &Frame) -> u64 {
    u64::from(frame_bits(f).crc_end)
}

/// Rule 1: a receiver that detects an error adds 1 to REC.
///
/// The dut is the only receiver and computes a wrong CRC: it does not acknowledge, so the
/// transmitter detects an acknowledge error at the ACK slot (ce+1) and flags ce+2..=ce+7.
/// The dut reads that dominant ACK delimiter (ce+2): form error, flag ce+3..=ce+8. Its first
/// bit after the flag (ce+9) is recessive (the transmitter's delimiter): rule 2 does not
/// apply. REC = 1. Wire: error delimiter ce+9..=ce+16, end ce+17, intermission: the record
/// lasts ce+20 bits.
pub fn rule_1_receiver_error<D: Dut>() {
    let Case {
        mut bus,
        dut,
        id,
        peers: [t],
        ..
    } = Case::<D, 1>::new([("t", SimNode::new().with_one_shot(true))]);
    let f = frame(0x123);
    t.borrow_mut().send(f);
    bus.inject_next(Fault::Crc {
        who: Receivers::Node(id),
    });
    let r = next_frame(&mut bus);
    assert_eq!(dut.counters(), ErrorCounters { tec: 0, rec: 1 });
    assert_eq!(dut.state(), ErrorState::Active);
    assert_eq!(
        t.borrow().counters().tec,
        8,
        "transmitter: acknowledge error"
    );
    assert_eq!(r.end - r.sof, ce_of(&f) + 20);
}

/// Rule 2: a receiver that reads a dominant bit as the first bit after its own error flag
/// adds 8 more (REC = 9).
///
/// Another receiver acknowledges, so only the dut's CRC is wrong: it flags from ce+3 (after
/// the ACK delimiter) to ce+8; the other receiver (form error at EOF bit 1, ce+3) and the
/// transmitter (bit error at ce+3) flag ce+4..=ce+9, so the dut's first bit after its flag,
/// ce+9, is dominant. Wire: last dominant ce+9, delimiter ce+10..=ce+17, end ce+18, +3.
pub fn rule_2_dominant_after_own_flag<D: Dut>() {
    let Case {
        mut bus,
        dut,
        id,
        peers: [t, other],
        ..
    } = Case::<D, 2>::new([
        ("t", SimNode::new().with_one_shot(true)),
        ("other", SimNode::new()),
    ]);
    let f = frame(0x321);
    t.borrow_mut().send(f);
    bus.inject_next(Fault::Crc {
        who: Receivers::Node(id),
    });
    let r = next_frame(&mut bus);
    assert_eq!(dut.counters(), ErrorCounters { tec: 0, rec: 9 });
    assert_eq!(other.borrow().counters().rec, 1);
    assert_eq!(r.end - r.sof, ce_of(&f) + 21);
}

/// Rule 3 then rule 7: a transmitter that sends an error flag adds 8 to TEC; a successful
/// transmission subtracts 1. One injected bit error then a clean retransmission: TEC 8
/// then 7. An error-active transmitter is not suspended: the retransmission starts right
/// after the intermission of the error frame.
pub fn rule_3_and_7_transmitter<D: Dut>() {
    let (mut bus, mut dut, id, p) = with_peer::<D>();
    let f = frame(0x0F0);
    bus.inject_from(id, 1, Fault::Bit { at: None });
    dut.send(&f);
    let first = next_frame(&mut bus);
    assert_eq!(dut.counters(), ErrorCounters { tec: 8, rec: 0 });
    let second = next_frame(&mut bus);
    assert_eq!(
        second.sof, first.end,
        "no suspend transmission while active"
    );
    assert!(second.is_error_free());
    assert_eq!(dut.counters(), ErrorCounters { tec: 7, rec: 0 });
    assert_eq!(p.borrow().received_frames(), vec![f]);
}

/// Drives the dut to TEC = 128 (error-passive) with 16 injected bit errors on its frame,
/// the peer acknowledging; returns the last error record. Attempt k (0-based) starts at
/// the end of attempt k-1 while active; the 16th error makes it passive.
fn make_passive<D: Dut>(bus: &mut Bus, dut: &mut D, id: NodeId, f: &Frame) -> Box<TraceRecord> {
    bus.inject_from(id, 16, Fault::Bit { at: None });
    dut.send(f);
    let mut last = next_frame(bus);
    for _ in 1..16 {
        let r = next_frame(bus);
        assert_eq!(r.sof, last.end);
        last = r;
    }
    assert_eq!(dut.counters(), ErrorCounters { tec: 128, rec: 0 });
    assert_eq!(dut.state(), ErrorState::Passive);
    last
}

/// Rule 3 exception 1, condition met: an error-passive transmitter that detects an
/// acknowledge error and no dominant bit during its passive error flag keeps its TEC.
/// The dut reads a recessive ACK slot (the peer did acknowledge): its passive flag
/// ce+2..=ce+7 is recessive and so is everything else: TEC stays 128.
///
/// Suspend transmission (§10.4.6.4): after the 16th error (passive), the next attempt
/// starts 8 bits after the intermission. After the ACK-error attempt (delimiter
/// ce+8..=ce+15, end ce+16, intermission to ce+19), the retry starts at ce+19+8.
pub fn rule_3_exception_1_ack_error_when_passive<D: Dut>() {
    let (mut bus, mut dut, id, p) = with_peer::<D>();
    let f = frame(0x0F1);
    let last = make_passive(&mut bus, &mut dut, id, &f);
    bus.inject_next(Fault::Ack);
    let ack = next_frame(&mut bus);
    assert_eq!(
        ack.sof,
        last.end + 8,
        "suspend transmission after the error frame"
    );
    assert_eq!(ack.end - ack.sof, ce_of(&f) + 19);
    assert_eq!(dut.counters(), ErrorCounters { tec: 128, rec: 0 });
    let retry = next_frame(&mut bus);
    assert_eq!(retry.sof, ack.end + 8);
    assert!(retry.is_error_free());
    assert_eq!(dut.counters(), ErrorCounters { tec: 127, rec: 0 });
    // The peer accepted the frame of the ACK-error attempt (its last EOF bit passed) and
    // the retry: the known double reception.
    assert_eq!(p.borrow().received_frames(), vec![f, f]);
}

/// Rule 3 exception 1, condition not met: the only receiver computes a wrong CRC, so it
/// does not acknowledge (acknowledge error for the passive dut at ce+1, passive flag from
/// ce+2) and flags ce+3..=ce+8 after its ACK delimiter (CRC error at ce+2): the dut reads
/// dominant bits during its passive flag, so TEC += 8 after all: 136.
pub fn rule_3_exception_1_not_met_dominant_during_passive_flag<D: Dut>() {
    let Case {
        mut bus,
        mut dut,
        id,
        peers: [p],
        ids: [pid],
    } = Case::<D, 1>::new([("p", SimNode::new())]);
    let f = frame(0x0F2);
    make_passive(&mut bus, &mut dut, id, &f);
    let rec_before = p.borrow().counters().rec;
    bus.inject_next(Fault::Crc {
        who: Receivers::Node(pid),
    });
    let r = next_frame(&mut bus);
    assert_eq!(dut.counters(), ErrorCounters { tec: 136, rec: 0 });
    assert_eq!(p.borrow().counters().rec, rec_before + 1);
    // Wire: the receiver's flag ce+3..=ce+8 is the last dominant stretch; the dut's passive
    // flag needs six equal bits: ce+3..=ce+8, then delimiters ce+9..=ce+16, end ce+17.
    assert_eq!(r.end - r.sof, ce_of(&f) + 20);
}

/// Rule 8: a successful reception with REC above 127 sets REC to the controller's value in
/// 119..=127. 15 rule-2 errors (9 each, the dut still error-active at the start of each:
/// 14 × 9 = 126 < 128) bring REC to 135; one good frame then sets it to the value its
/// manual names (the node is then error-warning: REC ≥ 96).
pub fn rule_8_reception_above_127<D: Dut>() {
    let Case {
        mut bus,
        dut,
        id,
        peers: [t, _],
        ..
    } = Case::<D, 2>::new([
        ("t", SimNode::new().with_one_shot(true)),
        ("other", SimNode::new()),
    ]);
    for k in 0..15u64 {
        t.borrow_mut().send(frame(0x200 + k as u16));
        bus.inject_next(Fault::Crc {
            who: Receivers::Node(id),
        });
        next_frame(&mut bus);
    }
    assert_eq!(dut.counters(), ErrorCounters { tec: 0, rec: 135 });
    assert_eq!(dut.state(), ErrorState::Passive);
    t.borrow_mut().send(frame(0x300));
    let r = next_frame(&mut bus);
    assert!(r.is_error_free());
    assert_eq!(
        dut.counters(),
        ErrorCounters {
            tec: 0,
            rec: D::REC_AFTER_PASSIVE_RECEPTION
        }
    );
    assert_eq!(dut.state(), ErrorState::Warning);
}

/// Suspend transmission, other node first: an error-passive dut that was transmitter must
/// wait 8 bits after the intermission, but a node that starts in that window wins the bus
/// and the dut receives its frame; the dut's frame follows right after (no new suspension:
/// it was a receiver).
pub fn suspend_transmission_other_node_starts_first<D: Dut>() {
    let (mut bus, mut dut, id, p) = with_peer::<D>();
    let f = frame(0x0F3);
    let last = make_passive(&mut bus, &mut dut, id, &f);
    let g = frame(0x7FF);
    p.borrow_mut().send(g);
    let other = next_frame(&mut bus);
    assert_eq!(other.sof, last.end, "the peer starts at once");
    assert_eq!(other.frame, g);
    let mine = next_frame(&mut bus);
    assert_eq!(mine.sof, other.end, "the dut was a receiver: no suspension");
    assert_eq!(mine.frame, f);
    assert!(mine.is_error_free());
    assert_eq!(dut.counters(), ErrorCounters { tec: 127, rec: 0 });
}

/// Rule 3 exception 2: a transmitter that reads dominant on a recessive stuff bit of the
/// arbitration field detects a stuff error and leaves TEC unchanged. Identifier 0x000:
/// SOF and the first four identifier bits are dominant, so wire bit 5 is a recessive stuff
/// bit inside the arbitration field. The retry succeeds; TEC stays 0 throughout.
pub fn rule_3_exception_2_stuff_error_in_arbitration<D: Dut>() {
    let (mut bus, mut dut, id, _) = with_peer::<D>();
    let f = Frame::standard(0x000, &[1]).unwrap();
    assert!(frame_bits(&f).arbitration_end > 5);
    bus.try_inject_from(id, 1, Fault::Bit { at: Some(5) })
        .unwrap();
    dut.send(&f);
    let r = next_frame(&mut bus);
    let e = r.first_error.unwrap();
    assert_eq!((e.node, e.code, e.bit), (id, LastErrorCode::Stuff, 5));
    assert!(r.refused.is_empty());
    assert_eq!(dut.counters(), ErrorCounters { tec: 0, rec: 0 });
    let retry = next_frame(&mut bus);
    assert!(retry.is_error_free());
    assert_eq!(dut.counters(), ErrorCounters { tec: 0, rec: 0 });
}

/// Rule 4: a transmitter that detects a bit error while sending its active error flag adds
/// 8 (and starts a new flag). One bit error (rule 3: +8) whose error flag is hit at its
/// third bit (rule 4: +8): TEC 16; the retry succeeds: 15.
pub fn rule_4_bit_error_in_own_active_flag_transmitter<D: Dut>() {
    let (mut bus, mut dut, id, _) = with_peer::<D>();
    let f = frame(0x0F5);
    bus.inject_from(id, 1, Fault::Bit { at: None });
    bus.try_inject_next(Fault::FlagBit { who: id, bit: 2 })
        .unwrap();
    dut.send(&f);
    next_frame(&mut bus);
    assert_eq!(dut.counters(), ErrorCounters { tec: 16, rec: 0 });
    assert!(next_frame(&mut bus).is_error_free());
    assert_eq!(dut.counters(), ErrorCounters { tec: 15, rec: 0 });
}

/// Rule 5: a receiver that detects a bit error while sending its active error flag adds 8.
/// As in rule 2, the dut alone computes a wrong CRC and flags from ce+3, but it misreads
/// the first bit of its flag: +8, and its new flag runs ce+4..=ce+9, together with the
/// others' flags (their errors are at ce+3): its first bit after the flag (ce+10) is
/// recessive, so rule 2 does not apply: REC = 1 + 8 = 9. Wire: last dominant ce+9, end
/// ce+18, +3.
pub fn rule_5_bit_error_in_own_active_flag_receiver<D: Dut>() {
    let Case {
        mut bus,
        dut,
        id,
        peers: [t, _],
        ..
    } = Case::<D, 2>::new([
        ("t", SimNode::new().with_one_shot(true)),
        ("other", SimNode::new()),
    ]);
    let f = frame(0x322);
    t.borrow_mut().send(f);
    bus.inject_next(Fault::Crc {
        who: Receivers::Node(id),
    });
    bus.try_inject_next(Fault::FlagBit { who: id, bit: 0 })
        .unwrap();
    let r = next_frame(&mut bus);
    assert_eq!(dut.counters(), ErrorCounters { tec: 0, rec: 9 });
    assert_eq!(r.end - r.sof, ce_of(&f) + 21);
}

/// Rule 6, active flag: the 14th consecutive dominant bit counted from the start of the
/// flag, and each 8 more, add 8. A lone error-active dut (a listen-only sniffer does not
/// acknowledge): acknowledge error at ce+1 (+8), flag ce+2..=ce+7, then the bus is held
/// dominant from ce+8 for 16 bits: dominant bits 14 (ce+15) and 22 (ce+23) add 8 each:
/// TEC 24.
pub fn rule_6_dominant_bits_after_active_flag<D: Dut>() {
    let Case {
        mut bus,
        mut dut,
        peers: [_],
        ..
    } = Case::<D, 1>::new([("sniffer", SimNode::new().with_listen_only(true))]);
    let f = frame(0x0F6);
    let ce = frame_bits(&f).crc_end;
    bus.try_inject_next(Fault::StuckDominant {
        at: ce + 8,
        bits: 16,
    })
    .unwrap();
    dut.send(&f);
    let r = next_frame(&mut bus);
    assert_eq!(r.first_error.unwrap().code, LastErrorCode::Acknowledge);
    assert_eq!(dut.counters(), ErrorCounters { tec: 24, rec: 0 });
    // Held dominant to ce+23, delimiter ce+24..=ce+31, end ce+32, +3.
    assert_eq!(r.end - r.sof, u64::from(ce) + 35);
}

/// Rule 6, passive flag: the 8th consecutive dominant bit after a passive error flag adds
/// 8. An error-passive dut reads a recessive ACK slot (acknowledge error, rule 3 exception
/// 1 applies: its passive flag ce+2..=ce+7 is all recessive), then the bus is held dominant
/// from ce+8 for 8 bits: TEC 128 + 8 = 136.
pub fn rule_6_dominant_bits_after_passive_flag<D: Dut>() {
    let (mut bus, mut dut, id, _) = with_peer::<D>();
    let f = frame(0x0F7);
    let ce = frame_bits(&f).crc_end;
    make_passive(&mut bus, &mut dut, id, &f);
    bus.inject_next(Fault::Ack);
    bus.try_inject_next(Fault::StuckDominant {
        at: ce + 8,
        bits: 8,
    })
    .unwrap();
    next_frame(&mut bus);
    assert_eq!(dut.counters(), ErrorCounters { tec: 136, rec: 0 });
}

/// Overload frame (§10.4.5): a dominant first intermission bit makes every node send an
/// overload flag (ce+11..=ce+16) and delimiter (ce+17..=ce+24); the frame stays valid and
/// the counters move only by the success (rule 7): a TEC of 8 becomes 7. The attempt lasts
/// ce + 25 bits and the intermission.
pub fn overload_frame_leaves_the_counters<D: Dut>() {
    let (mut bus, mut dut, id, p) = with_peer::<D>();
    let f = frame(0x0F8);
    let ce = frame_bits(&f).crc_end;
    bus.inject_from(id, 1, Fault::Bit { at: None });
    dut.send(&f);
    next_frame(&mut bus);
    assert_eq!(dut.counters(), ErrorCounters { tec: 8, rec: 0 });
    bus.try_inject_next(Fault::StuckDominant {
        at: ce + 10,
        bits: 1,
    })
    .unwrap();
    let r = next_frame(&mut bus);
    assert!(r.is_error_free());
    assert_eq!(r.end - r.sof, u64::from(ce) + 28);
    assert_eq!(dut.counters(), ErrorCounters { tec: 7, rec: 0 });
    assert_eq!(p.borrow().received_frames(), vec![f]);
}

/// Rule 6 after an overload flag (§12.1.4.2 rule 6 counts the 14th consecutive dominant
/// bit after an active error flag **or an overload flag**, and each 8 more). The bus is
/// held dominant from the first intermission bit (ce+10) for 15 bits (ce+10..=ce+24):
/// every node sends its overload flag ce+11..=ce+16 and reads dominant up to ce+24, the
/// 14th consecutive dominant bit counted from the start of its flag: +8. The frame was
/// valid before (at the end of EOF): the success takes the counter from 0 (stays 0).
/// Played twice: dut transmitter (TEC 0 → 8, the peer's REC 8), dut receiver (REC 8).
pub fn overload_rule_6_after_overload_flag<D: Dut>() {
    for dut_sends in [true, false] {
        let (mut bus, mut dut, _, p) = with_peer::<D>();
        let f = frame(0x0F9);
        let ce = frame_bits(&f).crc_end;
        bus.try_inject_next(Fault::StuckDominant {
            at: ce + 10,
            bits: 15,
        })
        .unwrap();
        if dut_sends {
            dut.send(&f);
        } else {
            p.borrow_mut().send(f);
        }
        let r = next_frame(&mut bus);
        assert!(r.is_error_free(), "the frame itself was valid");
        if dut_sends {
            assert_eq!(dut.counters(), ErrorCounters { tec: 8, rec: 0 });
            assert_eq!(p.borrow().counters(), ErrorCounters { tec: 0, rec: 8 });
            assert_eq!(p.borrow().received_frames(), vec![f]);
        } else {
            assert_eq!(dut.counters(), ErrorCounters { tec: 0, rec: 8 });
            assert_eq!(p.borrow().counters(), ErrorCounters { tec: 8, rec: 0 });
        }
        assert_eq!(dut.state(), ErrorState::Active);
    }
}

/// Rules 4 and 5 during an overload flag (§12.1.4.2: a bit error while sending an active
/// error flag **or an overload flag** adds 8 to TEC for a transmitter, to REC for a
/// receiver). A dominant first intermission bit (ce+10) starts the overload flags at
/// ce+11; the dut misreads bit 3 of its flag (ce+14, the fourth bit, counted from 0): +8,
/// and a new flag. The peer misreads its bit 3 too (so both flags restart together):
/// new flags ce+15..=ce+20, delimiter ce+21..=ce+28, intermission: the record lasts
/// ce + 29 + 3 bits. Played twice: dut transmitter (TEC 8), dut receiver (REC 8).
pub fn overload_rules_4_and_5_bit_error_in_overload_flag<D: Dut>() {
    for dut_sends in [true, false] {
        let Case {
            mut bus,
            mut dut,
            id,
            peers: [p],
            ids: [ip],
        } = Case::<D, 1>::new([("p", SimNode::new())]);
        let f = frame(0x0FA);
        let ce = u64::from(frame_bits(&f).crc_end);
        bus.try_inject_next(Fault::StuckDominant {
            at: ce as u32 + 10,
            bits: 1,
        })
        .unwrap();
        bus.try_inject_next(Fault::FlagBit { who: id, bit: 3 })
            .unwrap();
        bus.try_inject_next(Fault::FlagBit { who: ip, bit: 3 })
            .unwrap();
        if dut_sends {
            dut.send(&f);
        } else {
            p.borrow_mut().send(f);
        }
        let r = next_frame(&mut bus);
        assert!(r.is_error_free());
        assert_eq!(r.end - r.sof, ce + 29 + 3);
        if dut_sends {
            assert_eq!(dut.counters(), ErrorCounters { tec: 8, rec: 0 });
            assert_eq!(p.borrow().counters(), ErrorCounters { tec: 0, rec: 8 });
        } else {
            assert_eq!(dut.counters(), ErrorCounters { tec: 0, rec: 8 });
            assert_eq!(p.borrow().counters(), ErrorCounters { tec: 8, rec: 0 });
        }
    }
}

/// A dominant last EOF bit (§10.4.5 overload condition 3 / §10.4.4.2): the dut is a
/// receiver that reads the last EOF bit (EOF bit 7, index 6) dominant because another
/// receiver `b` flags a form error from there (it misread EOF bit 6). For the dut the
/// frame is already valid (a receiver's frame is valid after the next-to-last EOF bit):
/// REC stays 0 and it sends an overload flag, not an error flag (no counter moves). `b`:
/// rule 1 (+1), and its first bit after its flag is dominant (the others' flags): rule 2
/// (+8): REC 9. The transmitter reads its recessive last EOF bit dominant: bit error,
/// TEC 8; it sends the frame again, which every node receives: TEC 7, b's REC 8, the
/// dut's REC still 0.
pub fn overload_dominant_last_eof_bit<D: Dut>() {
    let Case {
        mut bus,
        dut,
        peers: [t, b],
        ids: [_, ib],
        ..
    } = Case::<D, 2>::new([("t", SimNode::new()), ("b", SimNode::new())]);
    let f = frame(0x0FB);
    t.borrow_mut().send(f);
    bus.inject_next(Fault::Form {
        who: Receivers::Node(ib),
        field: FormField::Eof(5),
    });
    let first = next_frame(&mut bus);
    assert!(!first.is_error_free(), "the transmitter's bit error");
    assert_eq!(dut.counters(), ErrorCounters { tec: 0, rec: 0 });
    assert_eq!(b.borrow().counters(), ErrorCounters { tec: 0, rec: 9 });
    assert_eq!(t.borrow().counters(), ErrorCounters { tec: 8, rec: 0 });
    let retry = next_frame(&mut bus);
    assert!(retry.is_error_free());
    assert_eq!(dut.counters(), ErrorCounters { tec: 0, rec: 0 });
    assert_eq!(b.borrow().counters(), ErrorCounters { tec: 0, rec: 8 });
    assert_eq!(t.borrow().counters(), ErrorCounters { tec: 7, rec: 0 });
    assert_eq!(dut.state(), ErrorState::Active);
}

/// The setting of rule 1 with the dut as receiver (`dut_sends` false: a one-shot [`SimNode`]
/// transmitter `o`) or as transmitter (`dut_sends` true: `o` is the one receiver): the
/// receiver computes a wrong CRC and does not acknowledge, so the transmitter detects an
/// acknowledge error at ce+1 (TEC 8) and flags ce+2..=ce+7; the receiver reads the dominant
/// ACK delimiter (ce+2): form error (REC 1), flag ce+3..=ce+8. Both read ce+9 recessive:
/// the error delimiter is ce+9..=ce+16, its bit n is ce+9+n. `extra` is injected on the
/// same attempt. Returns the record, the dut and the other node.
fn error_delimiter_setting<D: Dut>(
    dut_sends: bool,
    extra: impl FnOnce(NodeId, NodeId) -> Fault,
) -> (Box<TraceRecord>, D, Rc<RefCell<SimNode>>, Frame) {
    let Case {
        mut bus,
        mut dut,
        id,
        peers: [o],
        ids: [io],
    } = Case::<D, 1>::new([("o", SimNode::new().with_one_shot(true))]);
    let f = frame(0x124);
    let receiver = if dut_sends { io } else { id };
    bus.inject_next(Fault::Crc {
        who: Receivers::Node(receiver),
    });
    bus.try_inject_next(extra(id, io)).unwrap();
    if dut_sends {
        dut.send(&f);
    } else {
        o.borrow_mut().send(f);
    }
    (next_frame(&mut bus), dut, o, f)
}

/// The counters of the dut and the other node of [`error_delimiter_setting`]: `(tec, rec)`
/// as the transmitter and the receiver have them.
fn tx_rx_counters<D: Dut>(
    dut_sends: bool,
    dut: &D,
    o: &Rc<RefCell<SimNode>>,
) -> (ErrorCounters, ErrorCounters) {
    let (d, o) = (dut.counters(), o.borrow().counters());
    if dut_sends {
        (d, o)
    } else {
        (o, d)
    }
}

/// A fault in the error delimiter of [`error_delimiter_setting`] at delimiter bit `bit`,
/// seen by the bus or (`dut_alone`) by the dut alone,
/// played with the dut as transmitter and then as receiver: the transmitter ends with
/// TEC `tec`, the receiver with REC `rec[0]` when the dut receives and `rec[1]` when it
/// sends, the record lasts `ce + len` bits, and the dut stays error-active.
fn delimiter_case<D: Dut>(dut_alone: bool, bit: u8, tec: u16, rec: [u16; 2], len: u64) {
    for dut_sends in [true, false] {
        let (r, dut, o, f) = error_delimiter_setting::<D>(dut_sends, |id, _| {
            let who = if dut_alone { Sees::Node(id) } else { Sees::Bus };
            Fault::DelimiterBit { who, bit }
        });
        assert!(r.refused.is_empty(), "{:?}", r.refused);
        let (t, rx) = tx_rx_counters(dut_sends, &dut, &o);
        let rec = rec[usize::from(dut_sends)];
        assert_eq!(t, ErrorCounters { tec, rec: 0 }, "dut sends: {dut_sends}");
        assert_eq!(rx, ErrorCounters { tec: 0, rec }, "dut sends: {dut_sends}");
        assert_eq!(r.end - r.sof, ce_of(&f) + len, "dut sends: {dut_sends}");
        assert_eq!(dut.state(), ErrorState::Active, "dut sends: {dut_sends}");
    }
}

/// A dominant bit inside an error delimiter, on the bus (ISO 11898-1 §10.4.4.3: the error
/// delimiter is 8 recessive bits; a dominant bit in it is a form error, §10.11.4; Bosch
/// CAN 2.0B §3.2.3 / §7). In [`error_delimiter_setting`], delimiter bit 3 (ce+12) is
/// dominant: both nodes detect a form error there and send a new error flag ce+13..=ce+18:
/// the transmitter adds 8 (rule 3: it sends an error flag; exception 1 is about acknowledge
/// errors, exception 2 about arbitration), TEC 8 + 8 = 16; the receiver adds 1 (rule 1;
/// the dominant bit is not the first bit after its flag, so not rule 2), REC 1 + 1 = 2.
/// Both read ce+19 recessive after their flags (no rule 2); delimiter ce+19..=ce+26, end
/// ce+27, intermission: the record lasts ce+30 bits. Played with the dut as transmitter
/// and as receiver.
pub fn delimiter_form_error_on_the_bus<D: Dut>() {
    delimiter_case::<D>(false, 3, 16, [2, 2], 30);
}

/// One node alone misreads an error delimiter bit as dominant (`Sees::Node`).
///
/// Dut receiver in [`error_delimiter_setting`]: it misreads delimiter bit 3 (ce+12): form
/// error, REC 1 + 1 (rule 1), active flag ce+13..=ce+18. The transmitter reads that flag at
/// its delimiter bit 4 (ce+13): form error, TEC 8 + 8 (rule 3), flag ce+14..=ce+19. The
/// first bit after the dut's new flag (ce+19) is dominant: rule 2, REC + 8: 10.
///
/// Dut transmitter: it misreads its bit 3 (ce+12): TEC 16, flag ce+13..=ce+18; the
/// receiver reads that flag at its bit 4 (ce+13): form error, REC 2, flag ce+14..=ce+19,
/// and the first bit after it (ce+20) is recessive: no rule 2, REC 2.
///
/// Either way: delimiter ce+20..=ce+27, end ce+28, +3: ce+31.
pub fn delimiter_form_error_seen_by_one_node<D: Dut>() {
    delimiter_case::<D>(true, 3, 16, [10, 2], 31);
}

/// A dominant last bit of an error delimiter (ISO 11898-1 §10.4.5.2: "detection of a
/// dominant bit at the last bit of an error delimiter or overload delimiter" starts an
/// overload frame). In [`error_delimiter_setting`], delimiter bit 7 (ce+16) is dominant:
/// both nodes send an overload flag ce+17..=ce+22 and delimiter ce+23..=ce+30; no counter
/// moves (TEC 8, REC 1 as after the error alone). End ce+31, +3: ce+34.
pub fn dominant_last_error_delimiter_bit_is_overload<D: Dut>() {
    delimiter_case::<D>(false, 7, 8, [1, 1], 34);
}

/// An overload frame from a dominant first intermission bit (`Fault::IntermissionBit`,
/// bit 0 = ce+10; §10.4.5.2): overload flags ce+11..=ce+16, overload delimiter
/// ce+17..=ce+24 (bit n at ce+17+n). Then:
///
/// - its last bit (ce+24) dominant: a second overload frame (§10.4.5.2), flags
///   ce+25..=ce+30, delimiter ce+31..=ce+38, end ce+39, +3: ce+42; no counter moves and
///   the frame (valid at its end of frame) is received;
/// - its bit 2 (ce+19) dominant: a form error (§10.11.4) for both nodes, error flags
///   ce+20..=ce+25, delimiter ce+26..=ce+33, end ce+34, +3: ce+37. The transmitter had
///   succeeded (rule 7: TEC 0 stays 0) and adds 8 (rule 3, still the transmitter until
///   the bus is idle); the receiver had received the frame (REC 0) and adds 1 (rule 1;
///   ce+26 is recessive: no rule 2). Played with the dut as transmitter and as receiver.
pub fn faults_in_an_overload_delimiter<D: Dut>() {
    for (bit, tec, rec, len) in [(7u8, 0u16, 0u16, 42u64), (2, 8, 1, 37)] {
        for dut_sends in [true, false] {
            let (mut bus, mut dut, _, p) = with_peer::<D>();
            let f = frame(0x0FC);
            bus.try_inject_next(Fault::IntermissionBit {
                who: Sees::Bus,
                bit: 0,
            })
            .unwrap();
            bus.try_inject_next(Fault::DelimiterBit {
                who: Sees::Bus,
                bit,
            })
            .unwrap();
            if dut_sends {
                dut.send(&f);
            } else {
                p.borrow_mut().send(f);
            }
            let r = next_frame(&mut bus);
            assert!(r.refused.is_empty(), "{:?}", r.refused);
            assert_eq!(r.end - r.sof, ce_of(&f) + len, "bit {bit}");
            let (t, rx) = tx_rx_counters(dut_sends, &dut, &p);
            assert_eq!(
                t,
                ErrorCounters { tec, rec: 0 },
                "bit {bit}, dut sends {dut_sends}"
            );
            assert_eq!(
                rx,
                ErrorCounters { tec: 0, rec },
                "bit {bit}, dut sends {dut_sends}"
            );
            if dut_sends {
                assert_eq!(p.borrow().received_frames(), vec![f]);
            }
        }
    }
}

/// Rule 3 exception 1 does not cover a later form error. An error-passive dut reads a
/// recessive ACK slot (acknowledge error at ce+1, exception 1 applies: its passive flag
/// ce+2..=ce+7 is all recessive, TEC stays 128); its delimiter starts at ce+8 and it
/// misreads bit 3 (ce+11): form error, rule 3: TEC 136, a new passive flag ce+12..=ce+17,
/// delimiter ce+18..=ce+25, end ce+26, +3: ce+29 (the peer received the frame at ce+9,
/// REC - 1 by rule 8, and drives nothing after it).
pub fn delimiter_form_error_after_passive_ack_error<D: Dut>() {
    let (mut bus, mut dut, id, p) = with_peer::<D>();
    let f = frame(0x0FD);
    make_passive(&mut bus, &mut dut, id, &f);
    let rec_before = p.borrow().counters().rec;
    bus.inject_next(Fault::Ack);
    bus.try_inject_next(Fault::DelimiterBit {
        who: Sees::Node(id),
        bit: 3,
    })
    .unwrap();
    let r = next_frame(&mut bus);
    assert!(r.refused.is_empty(), "{:?}", r.refused);
    assert_eq!(dut.counters(), ErrorCounters { tec: 136, rec: 0 });
    assert_eq!(r.end - r.sof, ce_of(&f) + 29);
    // The peer received the frame (rule 8) and saw no error: the dut's flag is passive.
    assert_eq!(p.borrow().counters().rec, rec_before - 1);
}

/// Faults that cannot happen are refused, never moved: delimiter bit 0 (the recessive bit
/// that ends the flag) and 8 (a delimiter has 8 bits), a dominant third intermission bit
/// (a start of frame, §10.4.6.2, not simulated), and — once the attempt is played — a
/// delimiter bit in an attempt without error or overload frame (the frame is then sent
/// as if no fault had been injected: 0 errors, TEC 0, length ce+10+3).
pub fn delimiter_and_intermission_refusals<D: Dut>() {
    let (mut bus, mut dut, id, p) = with_peer::<D>();
    for (fault, error) in [
        (
            Fault::DelimiterBit {
                who: Sees::Bus,
                bit: 0,
            },
            FaultError::DelimiterBitOutOfRange(0),
        ),
        (
            Fault::DelimiterBit {
                who: Sees::Node(id),
                bit: 8,
            },
            FaultError::DelimiterBitOutOfRange(8),
        ),
        (
            Fault::IntermissionBit {
                who: Sees::Bus,
                bit: 2,
            },
            FaultError::IntermissionStartOfFrame,
        ),
        (
            Fault::IntermissionBit {
                who: Sees::Node(id),
                bit: 3,
            },
            FaultError::IntermissionBitOutOfRange(3),
        ),
    ] {
        assert_eq!(bus.try_inject_next(fault), Err(error));
    }
    let f = frame(0x0FE);
    let fault = Fault::DelimiterBit {
        who: Sees::Node(id),
        bit: 3,
    };
    bus.try_inject_next(fault).unwrap();
    dut.send(&f);
    let r = next_frame(&mut bus);
    assert!(r.is_error_free());
    assert_eq!(r.refused, vec![(fault, FaultError::DelimiterNotReached(3))]);
    assert_eq!(r.end - r.sof, ce_of(&f) + 13);
    assert_eq!(dut.counters(), ErrorCounters { tec: 0, rec: 0 });
    assert_eq!(p.borrow().received_frames(), vec![f]);
}

/// Bus-off at TEC > 255 (32 bit errors) and recovery after 128 occurrences of 11
/// consecutive recessive bits (§12.1.4.2, "bus-off"). The error delimiter and intermission
/// of the last error frame (8 + 3 recessive bits) are the first sequence, so the retry
/// starts 127 × 11 bits after that error frame ends.
pub fn bus_off_and_recovery<D: Dut>() {
    let (mut bus, mut dut, id, p) = with_peer::<D>();
    let f = frame(0x0F4);
    bus.inject_from(id, 32, Fault::Bit { at: None });
    dut.send(&f);
    let mut last = next_frame(&mut bus);
    for _ in 1..32 {
        last = next_frame(&mut bus);
    }
    assert_eq!(dut.state(), ErrorState::BusOff);
    assert_eq!(dut.counters().tec, 256);
    let retry = next_frame(&mut bus);
    assert_eq!(
        retry.sof,
        last.end + 11 * u64::from(BUS_OFF_RECOVERY_SEQUENCES - 1)
    );
    assert!(retry.is_error_free());
    assert_eq!(dut.state(), ErrorState::Active);
    assert_eq!(dut.counters(), ErrorCounters { tec: 0, rec: 0 });
    assert_eq!(p.borrow().received_frames(), vec![f]);
}

/// Issue 22, item 10 (one DLC rule): a remote frame carries its DLC code as written, 8
/// to 15 (ISO 11898-1: four DLC bits; 9..=15 ask for eight bytes), built by
/// `Frame::remote` like any other code; the node under test sends each with that code in
/// the DLC field (the wire layout is the one that code gives, with no data field) and a
/// plain receiver gets the same frame.
pub fn remote_dlc_codes_on_the_wire<D: Dut>() {
    let (mut bus, mut dut, id, p) = with_peer::<D>();
    let built: Vec<Frame> = (8..=15u8)
        .map(|code| Frame::remote(0x2A0 + u32::from(code), false, code).unwrap())
        .collect();
    for f in &built {
        dut.send(f);
        let r = next_frame(&mut bus);
        assert!(r.is_error_free(), "{f:?}");
        assert_eq!(r.transmitters, vec![id]);
        assert_eq!(r.frame, *f);
        assert_eq!(r.frame.dlc(), f.dlc());
        assert_eq!(r.bits, frame_bits(f), "{f:?}");
    }
    assert_eq!(p.borrow().received_frames(), built);
    assert_eq!(dut.counters(), ErrorCounters { tec: 0, rec: 0 });
}

/// One `#[test]` per case of the table for the node kind `$dut`.
#[macro_export]
macro_rules! conformance_tests {
    ($dut:ty) => {
        #[test]
        fn rule_1_receiver_error() {
            conformance::rule_1_receiver_error::<$dut>();
        }
        #[test]
        fn rule_2_dominant_after_own_flag() {
            conformance::rule_2_dominant_after_own_flag::<$dut>();
        }
        #[test]
        fn rule_3_and_7_transmitter() {
            conformance::rule_3_and_7_transmitter::<$dut>();
        }
        #[test]
        fn rule_3_exception_1_ack_error_when_passive() {
            conformance::rule_3_exception_1_ack_error_when_passive::<$dut>();
        }
        #[test]
        fn rule_3_exception_1_not_met_dominant_during_passive_flag() {
            conformance::rule_3_exception_1_not_met_dominant_during_passive_flag::<$dut>();
        }
        #[test]
        fn rule_8_reception_above_127() {
            conformance::rule_8_reception_above_127::<$dut>();
        }
        #[test]
        fn suspend_transmission_other_node_starts_first() {
            conformance::suspend_transmission_other_node_starts_first::<$dut>();
        }
        #[test]
        fn rule_3_exception_2_stuff_error_in_arbitration() {
            conformance::rule_3_exception_2_stuff_error_in_arbitration::<$dut>();
        }
        #[test]
        fn rule_4_bit_error_in_own_active_flag_transmitter() {
            conformance::rule_4_bit_error_in_own_active_flag_transmitter::<$dut>();
        }
        #[test]
        fn rule_5_bit_error_in_own_active_flag_receiver() {
            conformance::rule_5_bit_error_in_own_active_flag_receiver::<$dut>();
        }
        #[test]
        fn rule_6_dominant_bits_after_active_flag() {
            conformance::rule_6_dominant_bits_after_active_flag::<$dut>();
        }
        #[test]
        fn rule_6_dominant_bits_after_passive_flag() {
            conformance::rule_6_dominant_bits_after_passive_flag::<$dut>();
        }
        #[test]
        fn overload_frame_leaves_the_counters() {
            conformance::overload_frame_leaves_the_counters::<$dut>();
        }
        #[test]
        fn overload_rule_6_after_overload_flag() {
            conformance::overload_rule_6_after_overload_flag::<$dut>();
        }
        #[test]
        fn overload_rules_4_and_5_bit_error_in_overload_flag() {
            conformance::overload_rules_4_and_5_bit_error_in_overload_flag::<$dut>();
        }
        #[test]
        fn overload_dominant_last_eof_bit() {
            conformance::overload_dominant_last_eof_bit::<$dut>();
        }
        #[test]
        fn delimiter_form_error_on_the_bus() {
            conformance::delimiter_form_error_on_the_bus::<$dut>();
        }
        #[test]
        fn delimiter_form_error_seen_by_one_node() {
            conformance::delimiter_form_error_seen_by_one_node::<$dut>();
        }
        #[test]
        fn dominant_last_error_delimiter_bit_is_overload() {
            conformance::dominant_last_error_delimiter_bit_is_overload::<$dut>();
        }
        #[test]
        fn faults_in_an_overload_delimiter() {
            conformance::faults_in_an_overload_delimiter::<$dut>();
        }
        #[test]
        fn delimiter_form_error_after_passive_ack_error() {
            conformance::delimiter_form_error_after_passive_ack_error::<$dut>();
        }
        #[test]
        fn delimiter_and_intermission_refusals() {
            conformance::delimiter_and_intermission_refusals::<$dut>();
        }
        #[test]
        fn bus_off_and_recovery() {
            conformance::bus_off_and_recovery::<$dut>();
        }
        #[test]
        fn remote_dlc_codes_on_the_wire() {
            conformance::remote_dlc_codes_on_the_wire::<$dut>();
        }
    };
}
