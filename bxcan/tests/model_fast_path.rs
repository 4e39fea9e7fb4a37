//! The simulator's fast path (fault-free attempts resolved in one step) against the
//! bit-level path with a bxCAN model node on the bus: on random seeded scenarios (plain
//! nodes, random traffic, random faults, the model transmitting from its three mailboxes
//! and receiving into FIFO 0), `Bus::set_fast_path(true)` and `(false)` give the same
//! trace, statistics, bus time, plain-node counters and reports, and the same model
//! registers and received frames.
#![cfg(feature = "model")]

#[path = "model_bus.rs"]
mod tiny;

use std::cell::RefCell;
use std::rc::Rc;

use tiny::{enter_init, load, receive, Received};
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{self, esr, fa1r, fmr, fs1r, msr, tsr};
use twocan_core::{Frame, Registers};
use twocan_sim::{Bus, RandomFaults, SimNode};

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

/// CAN1 accepting everything into FIFO 0 (bank 0, 32-bit mask 0), `mcr_bits`, on `bus`.
fn model(bus: &mut Bus, mcr_bits: u32) -> BxCanModel {
    let mut m = BxCanModel::can1();
    bus.attach("bx", m.clone());
    enter_init(&mut m);
    m.modify32(regs::FMR, |v| v | fmr::FINIT);
    m.modify32(regs::FS1R, |v| v | fs1r::fsc(0));
    m.write32(regs::fir1(0), 0);
    m.write32(regs::fir2(0), 0);
    m.modify32(regs::FA1R, |v| v | fa1r::fact(0));
    m.modify32(regs::FMR, |v| v & !fmr::FINIT);
    m.write32(regs::MCR, mcr_bits);
    bus.run_until_idle(100).unwrap();
    assert_eq!(m.read32(regs::MSR) & msr::INAK, 0);
    m
}

struct Outcome {
    bus: Bus,
    nodes: Vec<Rc<RefCell<SimNode>>>,
    regs: Vec<u32>,
    received: Vec<Received>,
    loaded: usize,
}

fn run(seed: u64, fast: bool) -> Outcome {
    let mut rng = Lcg(seed);
    let mut bus = Bus::new(500_000).unwrap();
    bus.set_fast_path(fast);
    // NART on one scenario in four; automatic bus-off recovery.
    let nart = if rng.next().is_multiple_of(4) {
        regs::mcr::NART
    } else {
        0
    };
    let mut m = model(&mut bus, nart | regs::mcr::ABOM);
    let count = (rng.next() % 3) as usize; // 0..=2 plain nodes: 0 = the model alone
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
    // Chunks of bus time; between them the test plays the firmware: refills empty
    // mailboxes and reads FIFO 0 out.
    let mut loaded = 0;
    let mut received = Vec::new();
    for chunk in 1..=200u64 {
        for x in 0..3 {
            if loaded < mine.len() && m.read32(regs::TSR) & tsr::tme(x) != 0 {
                load(&mut m, x, &mine[loaded]);
                loaded += 1;
            }
        }
        bus.run_until(chunk * 500);
        while let Some(r) = receive(&mut m, 0) {
            received.push(r);
        }
    }
    let regs = [regs::MSR, regs::TSR, regs::RF0R, regs::ESR]
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
fn fast_and_bit_level_paths_agree_with_a_bxcan_model_on_the_bus() {
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
        assert_eq!(f.regs, s.regs, "seed {seed}: MSR TSR RF0R ESR");
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
        errors += esr::TEC.get(f.regs[3]) + esr::REC.get(f.regs[3]);
        received += f.received.len();
        sent_by_model += f
            .bus
            .trace()
            .records()
            .iter()
            .filter(|r| r.is_error_free() && r.transmitters.first().map(|t| t.index()) == Some(0))
            .count();
    }
    // Both paths were exercised, and the model saw errors in some scenarios.
    assert!(fast_attempts > 100, "{fast_attempts}");
    assert!(total > fast_attempts + 100, "{total} {fast_attempts}");
    assert!(errors > 0);
    eprintln!("fast {fast_attempts}/{total}, model received {received}, sent {sent_by_model}");
    assert!(received > 100, "{received}");
    assert!(sent_by_model > 100, "{sent_by_model}");
}
