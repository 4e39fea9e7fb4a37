//! Error injection: faults at chosen frames, on a node's frames, or at random with a seed.
//!
//! A [`Fault`] says which node detects which error where; the bus then plays the rest of
//! the frame bit by bit (error flags, echoes, delimiters), so what every other node sees
//! follows from ISO 11898-1 rather than from a table (see [`crate::sim::bus`]).
//!
//! Random injection uses [`SplitMix64`], a small self-contained generator (no `rand`
//! dependency), so that the same seed gives the same faults and the same trace.

use super::bits::FrameBits;
use super::bus::NodeId;

/// Which receivers detect an injected receive-side error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Receivers {
    /// Every node receiving the frame.
    All,
    /// One node (no effect if it is not a receiver of the frame).
    Node(NodeId),
}

impl Receivers {
    pub(crate) fn includes(self, node: NodeId) -> bool {
        match self {
            Receivers::All => true,
            Receivers::Node(n) => n == node,
        }
    }
}

/// A fixed-form bit where a form error can be injected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FormField {
    /// The CRC delimiter.
    CrcDelimiter,
    /// The ACK delimiter.
    AckDelimiter,
    /// End-of-frame bit `0..=5` (a dominant last EOF bit is an overload condition for a
    /// receiver, not an error; larger values are clamped to 5).
    Eof(u8),
}

/// The kind of a fault, for random injection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FaultKind {
    /// [`Fault::Bit`].
    Bit,
    /// [`Fault::Stuff`].
    Stuff,
    /// [`Fault::Crc`].
    Crc,
    /// [`Fault::Form`].
    Form,
    /// [`Fault::Ack`].
    Ack,
}

/// An error injected into one frame attempt.
///
/// Bit positions are wire-bit indices from SOF (0 = SOF), as in
/// [`FrameBits`]. Positions inside the arbitration field are moved
/// to the first bit after it: the simulation does not inject errors during arbitration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Fault {
    /// Every transmitter of the frame reads the opposite of the bit it sends at `at`
    /// (default: the first bit after the arbitration field) and detects a bit error
    /// (`BitDominant` if it sent dominant, `BitRecessive` otherwise). Allowed up to the
    /// last EOF bit; the ACK slot (where a dominant bit is normal) is moved to the ACK
    /// delimiter.
    Bit {
        /// Wire-bit index, `None` for the first bit after arbitration.
        at: Option<u32>,
    },
    /// Every transmitter reads a recessive ACK slot (an acknowledge error unless it
    /// acknowledges its own frames).
    Ack,
    /// The chosen receivers detect a stuff error at `at` (clamped to the stuffed region
    /// after arbitration; default: the first bit after arbitration).
    Stuff {
        /// Who detects it.
        who: Receivers,
        /// Wire-bit index, `None` for the first bit after arbitration.
        at: Option<u32>,
    },
    /// The chosen receivers compute a CRC that does not match (they do not acknowledge;
    /// their error flag starts after the ACK delimiter).
    Crc {
        /// Who detects it.
        who: Receivers,
    },
    /// The chosen receivers read a dominant bit in a fixed-form field.
    Form {
        /// Who detects it.
        who: Receivers,
        /// Where.
        field: FormField,
    },
}

impl Fault {
    /// The kind of this fault.
    pub const fn kind(&self) -> FaultKind {
        match self {
            Fault::Bit { .. } => FaultKind::Bit,
            Fault::Ack => FaultKind::Ack,
            Fault::Stuff { .. } => FaultKind::Stuff,
            Fault::Crc { .. } => FaultKind::Crc,
            Fault::Form { .. } => FaultKind::Form,
        }
    }
}

/// A fault resolved against one frame's layout: absolute wire-bit positions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TxFault {
    /// The transmitter reads the opposite bit at this position.
    Bit(u32),
    /// The transmitter reads a recessive ACK slot.
    Ack,
}

/// A receive-side fault at absolute wire-bit positions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum RxFault {
    /// Stuff error detected at this position.
    Stuff(u32),
    /// CRC mismatch.
    Crc,
    /// Form error detected at this position (a fixed-form bit).
    Form(u32),
}

impl Fault {
    /// The transmitter-side part of this fault for a frame laid out as `bits`.
    pub(crate) fn tx_part(&self, bits: &FrameBits) -> Option<TxFault> {
        match *self {
            Fault::Bit { at } => {
                let last_eof = bits.crc_end + 9;
                let mut pos = at
                    .unwrap_or(bits.arbitration_end)
                    .clamp(bits.arbitration_end, last_eof);
                if pos == bits.crc_end + 1 {
                    pos += 1;
                }
                Some(TxFault::Bit(pos))
            }
            Fault::Ack => Some(TxFault::Ack),
            _ => None,
        }
    }

    /// The receive-side part of this fault for `node`, a receiver of a frame laid out as `bits`.
    pub(crate) fn rx_part(&self, node: NodeId, bits: &FrameBits) -> Option<RxFault> {
        match *self {
            Fault::Stuff { who, at } if who.includes(node) => {
                let hi = bits.crc_end.saturating_sub(1).max(bits.arbitration_end);
                Some(RxFault::Stuff(
                    at.unwrap_or(bits.arbitration_end)
                        .clamp(bits.arbitration_end, hi),
                ))
            }
            Fault::Crc { who } if who.includes(node) => Some(RxFault::Crc),
            Fault::Form { who, field } if who.includes(node) => Some(RxFault::Form(match field {
                FormField::CrcDelimiter => bits.crc_end,
                FormField::AckDelimiter => bits.crc_end + 2,
                FormField::Eof(n) => bits.crc_end + 3 + u32::from(n.min(5)),
            })),
            _ => None,
        }
    }
}

/// SplitMix64 (Steele, Lea and Flood, 2014): a tiny, well-distributed 64-bit generator,
/// written here so that random injection needs no external crate.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator seeded with `seed` (any value, zero included).
    pub const fn new(seed: u64) -> Self {
        SplitMix64 { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A value in `0..n` (0 when `n` is 0), by multiply-and-shift.
    pub fn below(&mut self, n: u64) -> u64 {
        ((u128::from(self.next_u64()) * u128::from(n)) >> 64) as u64
    }
}

/// Random fault injection: each frame attempt gets a fault with probability `probability`.
#[derive(Debug, Clone, PartialEq)]
pub struct RandomFaults {
    /// The seed of the generator.
    pub seed: u64,
    /// Probability per frame attempt, `0.0..=1.0` (clamped; NaN counts as 0).
    pub probability: f64,
    /// The kinds to choose from, uniformly (empty: all five).
    pub kinds: Vec<FaultKind>,
}

impl RandomFaults {
    /// All fault kinds with probability `probability` per frame.
    pub fn new(seed: u64, probability: f64) -> Self {
        RandomFaults {
            seed,
            probability,
            kinds: Vec::new(),
        }
    }

    /// Restricts the kinds of fault drawn.
    pub fn with_kinds(mut self, kinds: &[FaultKind]) -> Self {
        self.kinds = kinds.to_vec();
        self
    }
}

const ALL_KINDS: [FaultKind; 5] = [
    FaultKind::Bit,
    FaultKind::Stuff,
    FaultKind::Crc,
    FaultKind::Form,
    FaultKind::Ack,
];

/// The running state of random injection.
#[derive(Debug, Clone)]
struct RandomState {
    rng: SplitMix64,
    /// Probability as a threshold on 64 random bits.
    threshold: u64,
    /// `true` when the probability is 1 (always inject).
    always: bool,
    kinds: Vec<FaultKind>,
}

impl RandomState {
    fn new(cfg: &RandomFaults) -> Self {
        let p = if cfg.probability.is_nan() {
            0.0
        } else {
            cfg.probability.clamp(0.0, 1.0)
        };
        // 2^64 as f64 is exact; the product is below it unless p == 1.
        let threshold = (p * 18_446_744_073_709_551_616.0) as u64;
        let kinds = if cfg.kinds.is_empty() {
            ALL_KINDS.to_vec()
        } else {
            cfg.kinds.clone()
        };
        RandomState {
            rng: SplitMix64::new(cfg.seed),
            threshold,
            always: p >= 1.0,
            kinds,
        }
    }

    fn draw(&mut self, bits: &FrameBits, receivers: &[NodeId]) -> Option<Fault> {
        let roll = self.rng.next_u64();
        if !(self.always || roll < self.threshold) {
            return None;
        }
        let kind = self.kinds[self.rng.below(self.kinds.len() as u64) as usize];
        let mut who = || {
            let pick = self.rng.below(receivers.len() as u64 + 1) as usize;
            match receivers.get(pick) {
                Some(&n) => Receivers::Node(n),
                None => Receivers::All,
            }
        };
        let fault = match kind {
            FaultKind::Bit => {
                let span = u64::from(bits.crc_end + 1 - bits.arbitration_end);
                let at = bits.arbitration_end + self.rng.below(span) as u32;
                Fault::Bit { at: Some(at) }
            }
            FaultKind::Ack => Fault::Ack,
            FaultKind::Crc => Fault::Crc { who: who() },
            FaultKind::Stuff => {
                let who = who();
                let span = u64::from(bits.crc_end.saturating_sub(bits.arbitration_end).max(1));
                let at = bits.arbitration_end + self.rng.below(span) as u32;
                Fault::Stuff { who, at: Some(at) }
            }
            FaultKind::Form => {
                let who = who();
                let field = match self.rng.below(8) {
                    0 => FormField::CrcDelimiter,
                    1 => FormField::AckDelimiter,
                    n => FormField::Eof((n - 2) as u8),
                };
                Fault::Form { who, field }
            }
        };
        Some(fault)
    }
}

/// The schedule of faults the bus consults at every frame attempt.
#[derive(Debug, Clone, Default)]
pub(crate) struct Injector {
    /// Faults for the frame attempt with a given sequence number.
    at_frame: Vec<(u64, Fault)>,
    /// Faults for the next `count` frame attempts of a node.
    from_node: Vec<(NodeId, u32, Fault)>,
    random: Option<RandomState>,
}

impl Injector {
    pub(crate) fn at_frame(&mut self, seq: u64, fault: Fault) {
        self.at_frame.push((seq, fault));
    }

    pub(crate) fn on_node(&mut self, node: NodeId, count: u32, fault: Fault) {
        if count > 0 {
            self.from_node.push((node, count, fault));
        }
    }

    pub(crate) fn set_random(&mut self, cfg: Option<&RandomFaults>) {
        self.random = cfg.map(RandomState::new);
    }

    pub(crate) fn clear(&mut self) {
        *self = Injector::default();
    }

    /// The faults for frame attempt `seq` sent by `transmitters`, received by `receivers`.
    pub(crate) fn faults_for(
        &mut self,
        seq: u64,
        transmitters: &[NodeId],
        receivers: &[NodeId],
        bits: &FrameBits,
    ) -> Vec<Fault> {
        let mut out = Vec::new();
        self.at_frame.retain(|&(s, f)| {
            if s == seq {
                out.push(f);
                false
            } else {
                s > seq
            }
        });
        for entry in self.from_node.iter_mut() {
            if transmitters.contains(&entry.0) && entry.1 > 0 {
                entry.1 -= 1;
                out.push(entry.2);
            }
        }
        self.from_node.retain(|e| e.1 > 0);
        if let Some(random) = self.random.as_mut() {
            if let Some(f) = random.draw(bits, receivers) {
                out.push(f);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix_is_deterministic_and_spread() {
        let mut a = SplitMix64::new(42);
        let mut b = SplitMix64::new(42);
        let xs: Vec<u64> = (0..8).map(|_| a.next_u64()).collect();
        let ys: Vec<u64> = (0..8).map(|_| b.next_u64()).collect();
        assert_eq!(xs, ys);
        assert_ne!(xs[0], xs[1]);
        let mut c = SplitMix64::new(1);
        let mut hist = [0u32; 4];
        for _ in 0..4000 {
            hist[c.below(4) as usize] += 1;
        }
        assert!(hist.iter().all(|&h| (800..1200).contains(&h)), "{hist:?}");
        assert_eq!(c.below(0), 0);
    }

    #[test]
    fn probability_extremes() {
        let bits = super::super::bits::frame_bits(&crate::frame::Frame::standard(1, &[]).unwrap());
        let mut never = RandomState::new(&RandomFaults::new(7, 0.0));
        let mut nan = RandomState::new(&RandomFaults::new(7, f64::NAN));
        let mut always = RandomState::new(&RandomFaults::new(7, 1.0).with_kinds(&[FaultKind::Ack]));
        for _ in 0..100 {
            assert!(never.draw(&bits, &[]).is_none());
            assert!(nan.draw(&bits, &[]).is_none());
            assert_eq!(always.draw(&bits, &[]), Some(Fault::Ack));
        }
    }
}
