//! The simulated bus: arbitration, acknowledgement, time, statistics, internal frames.

use std::cell::RefCell;
use std::rc::Rc;

use twocan_core::{ErrorState, Frame, LastErrorCode};
use twocan_sim::{
    frame_bits, Bus, BusEvent, BusNode, BusTime, NodeOutcome, SimNode, TxRequest, TxResult,
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
fn arbitration_between_three_nodes() {
    let mut bus = Bus::new(500_000).unwrap();
    let (a, b, c, d) = (node(), node(), node(), node());
    let ia = bus.attach("a", a.clone());
    let ib = bus.attach("b", b.clone());
    let ic = bus.attach("c", c.clone());
    bus.attach("listener", d.clone());
    a.borrow_mut().send(std_frame(0x300, &[3]));
    b.borrow_mut().send(std_frame(0x100, &[1]));
    c.borrow_mut().send(std_frame(0x200, &[2]));

    let Some(BusEvent::Frame(first)) = bus.step() else {
        panic!("a frame")
    };
    assert_eq!(first.frame, std_frame(0x100, &[1]));
    assert_eq!(first.transmitters, vec![ib]);
    assert_eq!(first.arbitration_losers, vec![ia, ic]);
    assert_eq!(
        first.outcome_of(ia),
        Some(NodeOutcome::Received),
        "losers receive the winner"
    );
    assert_eq!(tx_results(&a), vec![TxResult::ArbitrationLost]);
    assert_eq!(a.borrow().received_frames(), vec![std_frame(0x100, &[1])]);

    // The losers retry at the next idle point.
    assert!(bus.run_until_idle(10_000).is_ok());
    let order: Vec<u32> = bus
        .trace()
        .records()
        .iter()
        .map(|r| r.frame.raw_id())
        .collect();
    assert_eq!(order, vec![0x100, 0x200, 0x300]);
    assert_eq!(
        tx_results(&a),
        vec![
            TxResult::ArbitrationLost,
            TxResult::ArbitrationLost,
            TxResult::Acked
        ]
    );
    assert_eq!(d.borrow().received().len(), 3);
    let stats = bus.node_stats(ia).unwrap();
    assert_eq!(
        (stats.sent, stats.received, stats.arbitration_lost),
        (1, 2, 2)
    );
}

#[test]
fn arbitration_standard_before_extended_and_data_before_remote() {
    let mut bus = Bus::new(250_000).unwrap();
    let nodes: Vec<_> = (0..5).map(|_| node()).collect();
    for (i, n) in nodes.iter().enumerate() {
        bus.attach(&format!("n{i}"), n.clone());
    }
    let ext_same_base = Frame::extended(0x100 << 18, &[]).unwrap();
    let std_remote = Frame::remote(0x100, false, 0).unwrap();
    let std_data = std_frame(0x100, &[]);
    let ext_data = Frame::extended(0x00AB_CDEF, &[]).unwrap();
    let ext_remote = Frame::remote(0x00AB_CDEF, true, 2).unwrap();
    nodes[0].borrow_mut().send(ext_same_base);
    nodes[1].borrow_mut().send(std_remote);
    nodes[2].borrow_mut().send(std_data);
    nodes[3].borrow_mut().send(ext_remote);
    nodes[4].borrow_mut().send(ext_data);
    bus.run_until_idle(100_000).unwrap();
    let order: Vec<Frame> = bus.trace().records().iter().map(|r| r.frame).collect();
    // 0x00ABCDEF has base identifier 0x02A: it beats every 0x100 frame.
    assert_eq!(
        order,
        vec![ext_data, ext_remote, std_data, std_remote, ext_same_base]
    );
    for w in order.windows(2) {
        assert!(w[0].priority() < w[1].priority());
    }
}

#[test]
fn same_identifier_different_data_collide_until_one_goes_passive() {
    let mut bus = Bus::new(500_000).unwrap();
    let (a, b, c) = (node(), node(), node());
    bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    bus.attach("c", c.clone());
    a.borrow_mut().send(std_frame(0x100, &[0x01]));
    b.borrow_mut().send(std_frame(0x100, &[0x00]));
    bus.run_until_idle(1_000_000).unwrap();
    // Both error-active: each collision destroys the frame for both (TEC + 8 each) until
    // both are error-passive; then the recessive sender's passive flag lets the other win.
    let ra = tx_results(&a);
    assert!(ra
        .iter()
        .take(16)
        .all(|r| *r == TxResult::Error(LastErrorCode::BitRecessive)));
    assert_eq!(tx_results(&b)[16], TxResult::Acked);
    assert_eq!(
        c.borrow().received_frames(),
        vec![std_frame(0x100, &[0x00]), std_frame(0x100, &[0x01])]
    );
}

#[test]
fn identical_frames_from_two_nodes_both_succeed() {
    let mut bus = Bus::new(500_000).unwrap();
    let (a, b, c) = (node(), node(), node());
    let ia = bus.attach("a", a.clone());
    let ib = bus.attach("b", b.clone());
    bus.attach("c", c.clone());
    let f = std_frame(0x42, &[1, 2, 3]);
    a.borrow_mut().send(f);
    b.borrow_mut().send(f);
    let Some(BusEvent::Frame(r)) = bus.step() else {
        panic!()
    };
    assert_eq!(r.transmitters, vec![ia, ib]);
    assert!(r.is_error_free());
    assert_eq!(tx_results(&a), vec![TxResult::Acked]);
    assert_eq!(tx_results(&b), vec![TxResult::Acked]);
    assert_eq!(c.borrow().received_frames(), vec![f]);
    assert_eq!(
        r.duration(),
        u64::from(frame_bits(&f).total_with_intermission)
    );
}

#[test]
fn lone_node_gets_ack_errors_and_stops_at_error_passive() {
    let mut bus = Bus::new(500_000).unwrap();
    let a = node();
    let sniffer = SimNode::new().with_listen_only(true).shared();
    bus.attach("a", a.clone());
    bus.attach("sniffer", sniffer.clone());
    a.borrow_mut().send(std_frame(0x7, &[7]));
    assert!(
        bus.run_until_idle(50_000).is_err(),
        "nobody acknowledges: it retries forever"
    );
    let a = a.borrow();
    assert_eq!(a.counters().tec, 128);
    assert_eq!(a.state(), ErrorState::Passive);
    assert_eq!(a.bus_off_count(), 0);
    assert!(a
        .tx_reports()
        .iter()
        .all(|r| r.result == TxResult::Error(LastErrorCode::Acknowledge)));
    assert!(a.tx_reports().len() > 100);
    // While error-active its error flag destroyed the frame for the sniffer (16 times);
    // error-passive, its flag is recessive and the sniffer accepts every repetition.
    let s = sniffer.borrow();
    assert_eq!(s.rx_errors().len(), 16);
    assert!(s.rx_errors().iter().all(|e| e.code == LastErrorCode::Form));
    assert_eq!(s.received().len(), a.tx_reports().len() - 16);
    assert_eq!(
        s.counters().rec,
        0,
        "a listen-only node's REC went up 16 and down again"
    );
}

#[test]
fn lone_node_with_self_ack_succeeds() {
    let mut bus = Bus::new(500_000).unwrap();
    let a = SimNode::new()
        .with_self_ack(true)
        .with_receive_own(true)
        .shared();
    bus.attach("a", a.clone());
    a.borrow_mut().send(std_frame(0x7, &[7]));
    bus.run_until_idle(1_000).unwrap();
    assert_eq!(tx_results(&a), vec![TxResult::Acked]);
    let own = a.borrow().received()[0];
    assert!(own.own);
    assert!(!bus.trace().records()[0].acked);
}

#[test]
fn time_is_the_sum_of_frame_lengths() {
    let mut bus = Bus::new(125_000).unwrap();
    let (a, b) = (node(), node());
    bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    let frames = [
        std_frame(0, &[]),
        std_frame(0, &[0; 8]),
        Frame::extended(0x1FFF_FFFF, &[0xFF; 8]).unwrap(),
        Frame::remote(0x555, false, 3).unwrap(),
    ];
    for f in frames {
        a.borrow_mut().send(f);
    }
    let events = bus.run_for(1);
    assert_eq!(
        events.len(),
        1,
        "a frame is never cut: it runs past the deadline"
    );
    bus.run_until_idle(10_000).unwrap();
    let expected: u64 = frames
        .iter()
        .map(|f| u64::from(frame_bits(f).total_with_intermission))
        .sum();
    assert_eq!(bus.now(), expected);
    assert_eq!(bus.now_micros(), expected * 8);
    assert_eq!(bus.load(), 1.0);
    // Idle time passes exactly as asked.
    let events = bus.run_for(1000);
    assert_eq!(
        events,
        vec![BusEvent::Idle {
            from: expected,
            to: expected + 1000
        }]
    );
    let stats = bus.stats();
    assert_eq!(stats.busy_bits, expected);
    assert_eq!(stats.elapsed_bits, expected + 1000);
    assert!((bus.load() - expected as f64 / (expected + 1000) as f64).abs() < 1e-12);
    assert_eq!(stats.frames_error_free, 4);
    assert_eq!(b.borrow().received_frames(), frames.to_vec());
}

/// Checks that the bus hands every bit time to every node, in order.
#[derive(Default)]
struct Probe {
    deaf: bool,
    now: u64,
    chunks: Vec<(u64, bool)>,
    results: Vec<(TxResult, BusTime)>,
    queue: Vec<Frame>,
}

impl BusNode for Probe {
    fn poll_tx(&mut self, _now: u64) -> Option<TxRequest> {
        self.queue.first().map(|&frame| TxRequest {
            frame,
            self_ack: false,
            internal: false,
        })
    }
    fn acknowledges(&self) -> bool {
        !self.deaf
    }
    fn listens(&self) -> bool {
        !self.deaf
    }
    fn error_active(&self) -> bool {
        true
    }
    fn tx_result(&mut self, _frame: &Frame, result: TxResult, time: BusTime) {
        assert_eq!(time.now, self.now, "results come at the current time");
        self.results.push((result, time));
        if result == TxResult::Acked {
            self.queue.remove(0);
        }
    }
    fn rx(&mut self, _frame: &Frame, _own: bool, time: BusTime) {
        assert_eq!(time.now, self.now);
    }
    fn rx_error(&mut self, _code: LastErrorCode, _dominant_after_flag: bool, time: BusTime) {
        assert_eq!(time.now, self.now);
    }
    fn advance(&mut self, bits: u64, idle: bool, now: u64) {
        assert!(bits > 0);
        assert_eq!(now, self.now + bits);
        self.now = now;
        self.chunks.push((bits, idle));
    }
}

/// Recessive bits reported at the end of the chunks up to bus time `until`.
fn trailing_idle(chunks: &[(u64, bool)], until: u64) -> u64 {
    let mut t = 0;
    let upto: Vec<_> = chunks
        .iter()
        .take_while(|c| {
            t += c.0;
            t <= until
        })
        .collect();
    upto.iter().rev().take_while(|c| c.1).map(|c| c.0).sum()
}

#[test]
fn every_node_gets_every_bit_time() {
    let mut bus = Bus::new(1_000_000).unwrap();
    let p = Rc::new(RefCell::new(Probe::default()));
    let q = Rc::new(RefCell::new(Probe::default()));
    let deaf = Rc::new(RefCell::new(Probe {
        deaf: true,
        ..Probe::default()
    }));
    bus.attach("p", p.clone());
    bus.attach("q", q.clone());
    bus.attach("deaf", deaf.clone());
    let f = std_frame(0x10, &[1, 2]);
    p.borrow_mut().queue.push(f);
    bus.run_for(500);
    for n in [&p, &q, &deaf] {
        let n = n.borrow();
        assert_eq!(n.now, 500);
        assert_eq!(n.chunks.iter().map(|c| c.0).sum::<u64>(), 500);
    }
    let total = u64::from(frame_bits(&f).total);
    assert_eq!(
        p.borrow().results,
        vec![(TxResult::Acked, BusTime { sof: 0, now: total })]
    );
    // Nodes in the frame see it as busy until they are told the outcome; then the
    // intermission is idle.
    for n in [&p, &q] {
        let n = n.borrow();
        assert_eq!(
            n.chunks
                .iter()
                .take_while(|c| !c.1)
                .map(|c| c.0)
                .sum::<u64>(),
            total
        );
        assert_eq!(trailing_idle(&n.chunks, total + 3), 3);
    }
    // A node outside the frame sees the wire: ACK delimiter + EOF + intermission recessive.
    assert_eq!(trailing_idle(&deaf.borrow().chunks, total + 3), 8 + 3);
}

#[test]
fn harness_services_nodes_between_events() {
    // A responder that answers each request: the "interrupt handler" runs between steps.
    let mut bus = Bus::new(500_000).unwrap();
    let (client, server) = (node(), node());
    bus.attach("client", client.clone());
    bus.attach("server", server.clone());
    client.borrow_mut().send(std_frame(0x600, &[1]));
    client.borrow_mut().send(std_frame(0x600, &[2]));
    let mut answered = 0;
    while let Some(event) = bus.step_until(2_000) {
        let got = server.borrow().received().len();
        while answered < got {
            answered += 1;
            server
                .borrow_mut()
                .send(std_frame(0x580, &[answered as u8]));
        }
        if let BusEvent::Idle { .. } = event {
            assert_eq!(bus.now(), 2_000);
        }
    }
    // Request 1, then the answer (higher priority) wins over request 2.
    let ids: Vec<(u32, u8)> = bus
        .trace()
        .records()
        .iter()
        .map(|r| (r.frame.raw_id(), r.frame.data()[0]))
        .collect();
    assert_eq!(ids, vec![(0x600, 1), (0x580, 1), (0x600, 2), (0x580, 2)]);
}

#[test]
fn internal_frames_take_no_time_and_stay_private() {
    let mut bus = Bus::new(500_000).unwrap();
    let a = SimNode::new()
        .with_internal(true)
        .with_receive_own(true)
        .shared();
    let b = node();
    let ia = bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    a.borrow_mut().send(std_frame(0x1, &[1]));
    a.borrow_mut().send(std_frame(0x2, &[2]));
    let Some(BusEvent::Internal(r)) = bus.step() else {
        panic!()
    };
    assert!(r.internal && r.duration() == 0);
    assert_eq!(bus.run_until_idle(100), Ok(0));
    assert_eq!(bus.now(), 0);
    assert_eq!(a.borrow().received().len(), 2);
    assert!(b.borrow().received().is_empty());
    assert_eq!(bus.node_stats(ia).unwrap().sent_internal, 2);
    assert_eq!(bus.trace().len(), 2);
    assert_eq!(bus.trace().candump_string("can0"), "");
}

#[test]
fn zero_bit_rate_is_refused() {
    assert!(Bus::new(0).is_err());
    let bus = Bus::new(83_333).unwrap();
    assert_eq!(bus.bits_to_micros(1), 12);
    assert_eq!(bus.micros_to_bits(12), 1);
    assert_eq!(bus.micros_to_bits(1_000_000), 83_333);
}
