//! The simulator's fast path (attempts that cannot fail, resolved in one step) against the
//! bit-level path: same traces, statistics and node counters on random seeded traffic with
//! random faults, lone transmitters (acknowledge errors) and error-passive nodes.

use std::cell::RefCell;
use std::rc::Rc;

use twocan_core::Frame;
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
}

type Nodes = Vec<Rc<RefCell<SimNode>>>;

fn run(seed: u64, fast: bool) -> (Bus, Nodes) {
    let mut rng = Lcg(seed);
    let mut bus = Bus::new(500_000).unwrap();
    bus.set_fast_path(fast);
    let count = 1 + (rng.next() % 4) as usize;
    let nodes: Nodes = (0..count)
        .map(|k| {
            SimNode::new()
                .with_listen_only(k > 0 && rng.next().is_multiple_of(3))
                .with_one_shot(rng.next().is_multiple_of(4))
                .with_self_ack(rng.next().is_multiple_of(5))
                .shared()
        })
        .collect();
    for (k, n) in nodes.iter().enumerate() {
        bus.attach(&format!("n{k}"), n.clone());
    }
    for i in 0..30u64 {
        let k = (rng.next() as usize) % count;
        let len = (rng.next() % 9) as usize;
        let data: Vec<u8> = (0..len)
            .map(|j| (i as u8) ^ (j as u8).wrapping_mul(37))
            .collect();
        let f = if rng.next().is_multiple_of(3) {
            Frame::extended((rng.next() % 0x2000_0000) as u32, &data).unwrap()
        } else {
            Frame::standard((rng.next() % 0x800) as u16, &data).unwrap()
        };
        nodes[k].borrow_mut().send(f);
    }
    let p = [0.0, 0.05, 0.3][(rng.next() % 3) as usize];
    bus.set_random_faults(Some(RandomFaults::new(seed, p)));
    // Lone transmitters never stop: a fixed span of bus time.
    bus.run_until(200_000);
    (bus, nodes)
}

#[test]
fn fast_and_bit_level_paths_agree_on_random_seeded_scenarios() {
    let (mut fast_attempts, mut total) = (0, 0);
    for seed in 0..60u64 {
        let (fast, nodes_f) = run(seed, true);
        let (slow, nodes_s) = run(seed, false);
        assert_eq!(slow.fast_path_attempts(), 0);
        assert_eq!(
            fast.trace().records(),
            slow.trace().records(),
            "seed {seed}"
        );
        assert_eq!(fast.stats(), slow.stats(), "seed {seed}");
        assert_eq!(fast.now(), slow.now(), "seed {seed}");
        for (a, b) in nodes_f.iter().zip(&nodes_s) {
            let (a, b) = (a.borrow(), b.borrow());
            assert_eq!(a.counters(), b.counters(), "seed {seed}");
            assert_eq!(a.state(), b.state(), "seed {seed}");
            assert_eq!(a.received(), b.received(), "seed {seed}");
            assert_eq!(a.tx_reports(), b.tx_reports(), "seed {seed}");
            assert_eq!(a.rx_errors(), b.rx_errors(), "seed {seed}");
        }
        fast_attempts += fast.fast_path_attempts();
        total += fast.frames_started();
    }
    // Both paths were exercised.
    assert!(fast_attempts > 100, "{fast_attempts}");
    assert!(total > fast_attempts + 100, "{total} {fast_attempts}");
}
