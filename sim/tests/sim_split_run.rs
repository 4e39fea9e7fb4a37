//! `Bus::run_bits` can stop inside a frame attempt; the attempt then continues where it
//! stopped. Cutting the run at arbitrary bits must not change anything the nodes see:
//! same trace, same counters, same frames, as with the atomic run methods.

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

fn scenario(seed: u64) -> (Bus, Nodes) {
    let mut bus = Bus::new(250_000).unwrap();
    let nodes: Nodes = (0..4).map(|_| SimNode::new().shared()).collect();
    for (k, n) in nodes.iter().enumerate() {
        bus.attach(&format!("n{k}"), n.clone());
    }
    let mut rng = Lcg(seed);
    for i in 0..40u64 {
        let k = (rng.next() % 4) as usize;
        let id = (rng.next() % 0x7FF) as u16;
        let len = (rng.next() % 9) as usize;
        let data: Vec<u8> = (0..len).map(|j| (i as u8).wrapping_add(j as u8)).collect();
        nodes[k]
            .borrow_mut()
            .send(Frame::standard(id, &data).unwrap());
    }
    bus.set_random_faults(Some(RandomFaults::new(seed, 0.2)));
    (bus, nodes)
}

#[test]
fn cutting_the_run_at_random_bits_changes_nothing() {
    for seed in 1..=8u64 {
        let (mut whole, nodes_a) = scenario(seed);
        whole.run_until_idle(1_000_000).unwrap();

        let (mut cut, nodes_b) = scenario(seed);
        let mut rng = Lcg(seed ^ 0xABCD);
        let mut paused_inside = 0;
        while cut.now() < whole.now() {
            cut.run_bits(1 + rng.next() % 40);
            if cut.in_frame() {
                paused_inside += 1;
                assert!(cut.frame_offset().is_some());
            }
        }
        cut.run_until_idle(1_000_000).unwrap();
        assert!(
            paused_inside > 10,
            "seed {seed}: the runs did stop inside frames"
        );
        // The cut run may let a few more idle bits pass at the end.
        assert!(cut.now() >= whole.now(), "seed {seed}");
        assert_eq!(
            cut.trace().records(),
            whole.trace().records(),
            "seed {seed}"
        );
        let (mut sc, sw) = (cut.stats(), whole.stats());
        sc.elapsed_bits = sw.elapsed_bits;
        assert_eq!(sc, sw, "seed {seed}");
        for (a, b) in nodes_a.iter().zip(&nodes_b) {
            let (a, b) = (a.borrow(), b.borrow());
            assert_eq!(a.counters(), b.counters(), "seed {seed}");
            assert_eq!(a.received(), b.received(), "seed {seed}");
            assert_eq!(a.tx_reports(), b.tx_reports(), "seed {seed}");
            assert_eq!(a.rx_errors(), b.rx_errors(), "seed {seed}");
        }
    }
}
