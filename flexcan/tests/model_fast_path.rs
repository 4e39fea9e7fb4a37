//! The simulator's fast path (fault-free attempts resolved in one step) against the
//! bit-level path with a FlexCAN model node on the bus: on random seeded scenarios (plain
//! nodes, random traffic, random faults, the model transmitting from MB8 and receiving
//! into its Rx FIFO), `Bus::set_fast_path(true)` and `(false)` give the same trace,
//! statistics, bus time, plain-node counters and reports, and the same model registers
//! and received frames (with their time stamps).
#![cfg(feature = "model")]

#[path = "model_support.rs"]
mod support;

use std::cell::RefCell;
use std::rc::Rc;

use support::Rig;
use twocan_core::registers::Registers;
use twocan_core::Frame;
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::regs::{self, code, ecr, mcr};
use twocan_sim::{Bus, RandomFaults, SimNode};

const MB: usize = 8;

struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        self.0 >> 33
    }
    fn frame(&mut self, i: u64) -> Frame {
        let len = (self.next() % 9) as usize;
        let data: Vec<u8> = (0..len)
            .map(|j| (i as u8) ^ (j as u8).wrapping_mul(37))
            .collect();
        if self.next().is_multiple_of(3) {
            Frame::extended((self.next() % 0x2000_0000) as u32, &data).unwrap()
        } else {
            Frame::standard((self.next() % 0x800) as u16, &data).unwrap()
        }
    }
}

/// A module with the Rx FIFO accepting everything and MB8..15 inactive, on `bus`,
/// synchronised.
fn module(bus: &mut Bus) -> FlexCanModel {
    let m = FlexCanModel::mk20dx256();
    m.modify32(regs::MCR, |v| v & !mcr::MDIS);
    m.modify32(regs::MCR, |v| v | mcr::RFEN | mcr::IRMQ | mcr::SRXDIS);
    for n in 0..8 {
        m.write32(regs::rx_fifo_filter(n), 0);
        m.write32(regs::rximr(n), 0);
    }
    for n in 8..16 {
        m.write32(regs::mb_cs(n), 0);
        m.write32(regs::rximr(n), u32::MAX);
    }
    bus.attach("fc", m.clone());
    m.modify32(regs::MCR, |v| v & !mcr::HALT);
    bus.run_for(11);
    assert!(m.is_synchronised());
    m
}

struct Outcome {
    bus: Bus,
    nodes: Vec<Rc<RefCell<SimNode>>>,
    regs: Vec<u32>,
    received: Vec<(Frame, u32, u16)>,
    loaded: usize,
}

fn run(seed: u64, fast: bool) -> Outcome {
    let mut rng = Lcg(seed);
    let mut bus = Bus::new(500_000).unwrap();
    bus.set_fast_path(fast);
    let m = module(&mut bus);
    let mut rig = Rig {
        m: m.clone(),
        now: 0,
    };
    let count = (rng.next() % 3) as usize; // 0..=2 plain nodes: 0 = the module alone
    let nodes: Vec<_> = (0..count)
        .map(|k| {
            SimNode::new()
                .with_listen_only(k > 0 && rng.next().is_multiple_of(3))
                .with_one_shot(rng.next().is_multiple_of(4))
                .shared()
        })
        .collect();
    for (k, n) in nodes.iter().enumerate() {
        bus.attach(&format!("n{k}"), n.clone());
    }
    for i in 0..20u64 {
        if count > 0 {
            let k = (rng.next() as usize) % count;
            let f = rng.frame(i);
            nodes[k].borrow_mut().send(f);
        }
    }
    let mine: Vec<Frame> = (100..112u64).map(|i| rng.frame(i)).collect();
    let p = [0.0, 0.05, 0.3][(rng.next() % 3) as usize];
    bus.set_random_faults(Some(RandomFaults::new(seed, p)));
    // Chunks of bus time; between them the test plays the firmware: reloads MB8 when
    // its frame went (IFLAG1 bit 8, acknowledged) and reads the Rx FIFO out.
    let mut loaded = 0;
    let mut received = Vec::new();
    for chunk in 1..=200u64 {
        let done = m.read32(regs::IFLAG1) & (1 << MB) != 0;
        if done {
            m.write32(regs::IFLAG1, 1 << MB);
        }
        if loaded < mine.len() && (loaded == 0 || done) {
            rig.load_mb(MB, &mine[loaded], code::TX_DATA);
            loaded += 1;
        }
        bus.run_until(chunk * 500);
        while let Some(r) = rig.pop_fifo() {
            received.push(r);
        }
    }
    let regs = [regs::ECR, regs::IFLAG1, regs::mb_cs(MB)]
        .iter()
        .map(|&r| m.read32(r))
        .collect();
    Outcome {
        bus,
        nodes,
        regs,
        received,
        loaded,
    }
}

#[test]
fn fast_and_bit_level_paths_agree_with_a_flexcan_model_on_the_bus() {
    let (mut fast_attempts, mut total, mut errors) = (0, 0, 0);
    let (mut received, mut sent_by_model) = (0, 0);
    for seed in 0..40u64 {
        let f = run(seed, true);
        let s = run(seed, false);
        assert_eq!(s.bus.fast_path_attempts(), 0);
        assert_eq!(
            f.bus.trace().records(),
            s.bus.trace().records(),
            "seed {seed}"
        );
        assert_eq!(f.bus.stats(), s.bus.stats(), "seed {seed}");
        assert_eq!(f.bus.now(), s.bus.now(), "seed {seed}");
        assert_eq!(f.regs, s.regs, "seed {seed}: ECR IFLAG1 MB8.CS");
        assert_eq!(f.received, s.received, "seed {seed}");
        assert_eq!(f.loaded, s.loaded, "seed {seed}");
        for (a, b) in f.nodes.iter().zip(&s.nodes) {
            let (a, b) = (a.borrow(), b.borrow());
            assert_eq!(a.counters(), b.counters(), "seed {seed}");
            assert_eq!(a.state(), b.state(), "seed {seed}");
            assert_eq!(a.received(), b.received(), "seed {seed}");
            assert_eq!(a.tx_reports(), b.tx_reports(), "seed {seed}");
            assert_eq!(a.rx_errors(), b.rx_errors(), "seed {seed}");
        }
        fast_attempts += f.bus.fast_path_attempts();
        total += f.bus.frames_started();
        errors += ecr::TXERRCNT.get(f.regs[0]) + ecr::RXERRCNT.get(f.regs[0]);
        received += f.received.len();
        sent_by_model += f
            .bus
            .trace()
            .records()
            .iter()
            .filter(|r| r.is_error_free() && r.transmitters.first().map(|t| t.index()) == Some(0))
            .count();
    }
    eprintln!("fast {fast_attempts}/{total}, model received {received}, sent {sent_by_model}");
    // Both paths were exercised; the model received, sent and saw errors.
    assert!(fast_attempts > 100, "{fast_attempts}");
    assert!(total > fast_attempts + 100, "{total} {fast_attempts}");
    assert!(errors > 0);
    assert!(received > 100, "{received}");
    assert!(sent_by_model > 100, "{sent_by_model}");
}
