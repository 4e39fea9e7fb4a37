//! Seeded scenarios for the simulated bus's fast path (fault-free attempts resolved in
//! one step) against its bit-level path, with a peripheral model on the bus.
//!
//! One scenario, drawn from a seed: the model under test (first on the bus), 0..=2 plain
//! [`SimNode`]s (some listen-only, some one-shot) with 20 random frames to send, 12
//! random frames for the model, and random faults at a probability of 0, 5 % or 30 %.
//! Bus time runs in 200 chunks of 500 bit times; between chunks the test plays the
//! model's firmware ([`Model::refill`], [`Model::drain`]). [`run`] plays it with the fast
//! path on or off; [`compare_paths`] plays seeds both ways and reports the first
//! difference in the trace, the bus statistics and time, the plain nodes' counters,
//! states and reports, and the model's registers and received frames.

use std::cell::RefCell;
use std::fmt::Debug;
use std::ops::Range;
use std::rc::Rc;

use twocan_core::Frame;
use twocan_sim::{Bus, RandomFaults, SimNode};

/// The scenarios' random numbers: a 64-bit linear congruential generator (Knuth's MMIX
/// constants), its high 31 bits per draw.
pub struct Lcg(pub u64);

impl Lcg {
    /// The next draw.
    pub fn draw(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        self.0 >> 33
    }

    /// A random data frame (a third extended), 0..=8 data bytes derived from `i`.
    pub fn frame(&mut self, i: u64) -> Frame {
        let len = (self.draw() % 9) as usize;
        let data: Vec<u8> = (0..len)
            .map(|j| (i as u8) ^ (j as u8).wrapping_mul(37))
            .collect();
        if self.draw().is_multiple_of(3) {
            Frame::extended((self.draw() % 0x2000_0000) as u32, &data)
                .expect("identifier drawn below 2^29, at most 8 bytes")
        } else {
            Frame::standard((self.draw() % 0x800) as u16, &data)
                .expect("identifier drawn below 2^11, at most 8 bytes")
        }
    }
}

/// A peripheral model under test, as the scenario's firmware drives it.
pub trait Model: Sized {
    /// A received frame as the test reads it (with what the model records beside it).
    type Received: PartialEq + Debug;
    /// The registers [`Model::registers`] reads, for messages.
    const REGISTERS: &'static str;
    /// Makes the model, attaches it to `bus` (the first node) and brings it on the bus;
    /// it may draw its options from `rng` (before the scenario draws the rest).
    fn start(bus: &mut Bus, rng: &mut Lcg) -> Self;
    /// Between chunks: loads frames of `mine` from index `*loaded` on into the free
    /// transmit buffers, advancing `*loaded`.
    fn refill(&mut self, mine: &[Frame], loaded: &mut usize);
    /// After a chunk: takes every received frame out, in order.
    fn drain(&mut self, out: &mut Vec<Self::Received>);
    /// The registers compared at the end ([`Model::REGISTERS`]).
    fn registers(&self) -> Vec<u32>;
    /// TEC + REC from those registers.
    fn error_count(registers: &[u32]) -> u32;
}

/// What one run left.
pub struct Outcome<R> {
    /// The bus (trace, statistics, time).
    pub bus: Bus,
    /// The plain nodes.
    pub nodes: Vec<Rc<RefCell<SimNode>>>,
    /// The model's registers ([`Model::registers`]).
    pub registers: Vec<u32>,
    /// The frames the model received.
    pub received: Vec<R>,
    /// How many of its 12 frames the model was given to send.
    pub loaded: usize,
}

/// Plays the scenario of `seed` with the fast path on (`fast`) or off.
pub fn run<M: Model>(seed: u64, fast: bool) -> Outcome<M::Received> {
    let mut rng = Lcg(seed);
    let mut bus = Bus::new(500_000).expect("500 kbit/s is a valid bus rate");
    bus.set_fast_path(fast);
    let mut model = M::start(&mut bus, &mut rng);
    let count = (rng.draw() % 3) as usize; // 0..=2 plain nodes: 0 = the model alone
    let nodes: Vec<_> = (0..count)
        .map(|k| {
            SimNode::new()
                .with_listen_only(k > 0 && rng.draw().is_multiple_of(3))
                .with_one_shot(rng.draw().is_multiple_of(4))
                .shared()
        })
        .collect();
    for (k, n) in nodes.iter().enumerate() {
        bus.attach(&format!("n{k}"), n.clone());
    }
    for i in 0..20u64 {
        if count > 0 {
            let k = (rng.draw() as usize) % count;
            let f = rng.frame(i);
            nodes[k].borrow_mut().send(f);
        }
    }
    let mine: Vec<Frame> = (100..112u64).map(|i| rng.frame(i)).collect();
    let p = [0.0, 0.05, 0.3][(rng.draw() % 3) as usize];
    bus.set_random_faults(Some(RandomFaults::new(seed, p)));
    let mut loaded = 0;
    let mut received = Vec::new();
    for chunk in 1..=200u64 {
        model.refill(&mine, &mut loaded);
        bus.run_until(chunk * 500);
        model.drain(&mut received);
    }
    Outcome {
        registers: model.registers(),
        bus,
        nodes,
        received,
        loaded,
    }
}

/// The first difference between two runs of one scenario, `None` when they agree.
pub fn difference<R: PartialEq + Debug>(
    a: &Outcome<R>,
    b: &Outcome<R>,
    registers: &str,
) -> Option<String> {
    fn differ<T: PartialEq + Debug>(what: &str, a: T, b: T) -> Option<String> {
        (a != b).then(|| format!("{what}: {a:?} != {b:?}"))
    }
    differ("trace", a.bus.trace().records(), b.bus.trace().records())
        .or_else(|| differ("bus statistics", a.bus.stats(), b.bus.stats()))
        .or_else(|| differ("bus time", a.bus.now(), b.bus.now()))
        .or_else(|| differ(registers, &a.registers, &b.registers))
        .or_else(|| differ("model received", &a.received, &b.received))
        .or_else(|| differ("model loaded", a.loaded, b.loaded))
        .or_else(|| differ("plain nodes", a.nodes.len(), b.nodes.len()))
        .or_else(|| {
            a.nodes.iter().zip(&b.nodes).find_map(|(a, b)| {
                let (a, b) = (a.borrow(), b.borrow());
                differ("node counters", a.counters(), b.counters())
                    .or_else(|| differ("node state", a.state(), b.state()))
                    .or_else(|| differ("node received", a.received(), b.received()))
                    .or_else(|| differ("node reports", a.tx_reports(), b.tx_reports()))
                    .or_else(|| differ("node receive errors", a.rx_errors(), b.rx_errors()))
            })
        })
}

/// What the seeds of [`compare_paths`] exercised (of the fast-path runs).
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Totals {
    /// Attempts the fast path resolved.
    pub fast_attempts: u64,
    /// Frame attempts started.
    pub frames_started: u64,
    /// TEC + REC of the model at the end, summed.
    pub errors: u32,
    /// Frames the model received.
    pub received: usize,
    /// Frames the model sent without error.
    pub sent_by_model: usize,
}

/// Plays every seed with the fast path on and off; the first difference (with its seed),
/// or what the runs exercised. A run with the fast path off that used it is a difference
/// too.
pub fn compare_paths<M: Model>(seeds: Range<u64>) -> Result<Totals, String> {
    let mut t = Totals::default();
    for seed in seeds {
        let f = run::<M>(seed, true);
        let s = run::<M>(seed, false);
        if s.bus.fast_path_attempts() != 0 {
            return Err(format!("seed {seed}: the bit-level run used the fast path"));
        }
        if let Some(d) = difference(&f, &s, M::REGISTERS) {
            return Err(format!("seed {seed}: {d}"));
        }
        t.fast_attempts += f.bus.fast_path_attempts();
        t.frames_started += f.bus.frames_started();
        t.errors += M::error_count(&f.registers);
        t.received += f.received.len();
        t.sent_by_model += f
            .bus
            .trace()
            .records()
            .iter()
            .filter(|r| r.is_error_free() && r.transmitters.first().map(|t| t.index()) == Some(0))
            .count();
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_generator_is_deterministic_and_frames_are_valid() {
        let (mut a, mut b) = (Lcg(7), Lcg(7));
        let fa: Vec<Frame> = (0..50).map(|i| a.frame(i)).collect();
        let fb: Vec<Frame> = (0..50).map(|i| b.frame(i)).collect();
        assert_eq!(fa, fb);
        assert!(fa.iter().any(|f| f.is_extended()) && fa.iter().any(|f| !f.is_extended()));
        assert!(fa.iter().all(|f| f.data().len() <= 8));
        assert_ne!(Lcg(8).draw(), Lcg(7).draw());
    }

    /// A plain node in the model's place: the scenario machinery alone.
    struct Plain(Rc<RefCell<SimNode>>, usize);

    impl Model for Plain {
        type Received = Frame;
        const REGISTERS: &'static str = "TEC REC";
        fn start(bus: &mut Bus, _rng: &mut Lcg) -> Self {
            let n = SimNode::new().shared();
            bus.attach("dut", n.clone());
            Plain(n, 0)
        }
        fn refill(&mut self, mine: &[Frame], loaded: &mut usize) {
            if *loaded < mine.len() && self.0.borrow().pending() == 0 {
                self.0.borrow_mut().send(mine[*loaded]);
                *loaded += 1;
            }
        }
        fn drain(&mut self, out: &mut Vec<Frame>) {
            let got = self.0.borrow().received_frames();
            out.extend_from_slice(&got[self.1..]);
            self.1 = got.len();
        }
        fn registers(&self) -> Vec<u32> {
            let c = self.0.borrow().counters();
            vec![u32::from(c.tec), u32::from(c.rec)]
        }
        fn error_count(r: &[u32]) -> u32 {
            r[0] + r[1]
        }
    }

    #[test]
    fn both_paths_agree_with_a_plain_node_in_the_models_place() {
        let t = compare_paths::<Plain>(0..8).unwrap();
        assert!(
            t.fast_attempts > 0 && t.frames_started > t.fast_attempts,
            "{t:?}"
        );
        assert!(t.sent_by_model > 0 && t.received > 0, "{t:?}");
    }

    #[test]
    fn a_difference_is_reported_with_its_seed() {
        let a = run::<Plain>(3, true);
        let mut b = run::<Plain>(3, true);
        assert_eq!(difference(&a, &b, "TEC REC"), None);
        b.loaded += 1;
        assert_eq!(
            difference(&a, &b, "TEC REC").as_deref(),
            Some(format!("model loaded: {} != {}", a.loaded, b.loaded).as_str())
        );
    }
}
