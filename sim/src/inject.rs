//! Error injection: faults at chosen frames, on a node's frames, or at random with a seed.
//!
//! A [`Fault`] says which node detects which error where; the bus then plays the rest of
//! the frame bit by bit (error flags, echoes, delimiters), so what every other node sees
//! follows from ISO 11898-1 rather than from a table (see [`crate::bus`]).
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
    /// receiver, not an error: larger values are refused, [`FaultError::EofBitOutOfRange`]).
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
    /// [`Fault::FlagBit`] (not among the default random kinds).
    FlagBit,
    /// [`Fault::StuckDominant`] (not among the default random kinds).
    StuckDominant,
    /// [`Fault::DelimiterBit`] (not among the default random kinds).
    DelimiterBit,
    /// [`Fault::IntermissionBit`] (not among the default random kinds).
    IntermissionBit,
}

/// Who reads a dominant bit injected into a delimiter or the intermission.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Sees {
    /// The bus itself is dominant at that bit (a disturbance on the wire): every node
    /// reads it.
    Bus,
    /// One node (transmitter or receiver of the frame) misreads the bit as dominant; the
    /// wire stays recessive for the others (no effect if the node takes no part in the
    /// attempt).
    Node(NodeId),
}

/// An error injected into one frame attempt.
///
/// Bit positions are wire-bit indices from SOF (0 = SOF), as in [`FrameBits`]. A fault
/// is placed at the exact bit it names, or refused with a [`FaultError`] if it cannot
/// happen there ([`Fault::validate`] at injection, the frame's layout when the attempt
/// starts: [`crate::TraceRecord::refused`], [`crate::Bus::refused_faults`]); it
/// is never moved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Fault {
    /// Every transmitter of the frame reads the opposite of the bit it sends at `at`
    /// (default: the first bit after the arbitration field) and detects a bit error
    /// (`BitDominant` if it sent dominant, `BitRecessive` otherwise), up to the last EOF
    /// bit. Inside the arbitration field a recessive bit read dominant is lost arbitration,
    /// not an error — refused — except on a stuff bit, where it is a stuff error that
    /// leaves TEC unchanged (ISO 11898-1 §12.1.4.2 rule 3, exception 2). The ACK slot
    /// (where reading dominant is normal) is refused.
    Bit {
        /// Wire-bit index, `None` for the first bit after arbitration.
        at: Option<u32>,
    },
    /// Every transmitter reads a recessive ACK slot (an acknowledge error unless it
    /// acknowledges its own frames).
    Ack,
    /// The chosen receivers detect a stuff error at `at` (default: the first bit after
    /// arbitration); refused outside the stuffed region (SOF to the end of the CRC).
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
    /// Rules 4 and 5: node `who` (transmitter or receiver) reads a recessive bit at bit
    /// `bit` (0..=5) of the first active error flag or overload flag it sends in the
    /// attempt: a bit error during its flag. Its counter rises by 8 and it starts a new
    /// flag. No effect on a node that sends no such flag in that attempt.
    FlagBit {
        /// The node.
        who: NodeId,
        /// The bit of its active error flag, 0..=5.
        bit: u8,
    },
    /// The bus is held dominant (by a faulty node or transceiver) for `bits` bits from
    /// wire bit `at`: after an error flag this is ISO 11898-1 rule 6 (every node adds 8
    /// at its 14th consecutive dominant bit after an active flag, 8th after a passive one,
    /// and at each 8 more). Refused inside the arbitration field (it would decide
    /// arbitration, which the simulation resolves before the bits).
    StuckDominant {
        /// First wire bit held dominant.
        at: u32,
        /// How many bits.
        bits: u32,
    },
    /// A dominant bit at bit `bit` (1..=7) of the first error or overload delimiter of
    /// the attempt (ISO 11898-1 §10.4.4.3 / §10.4.5.3: 8 recessive bits; bit 0 is the
    /// first recessive bit after the flag, which a node waits for, so a dominant bit there
    /// only prolongs the flag: refused, [`FaultError::DelimiterBitOutOfRange`]). For
    /// [`Sees::Bus`] the wire is dominant at the bit where the nodes are at that delimiter
    /// bit; for [`Sees::Node`] that node alone misreads it.
    ///
    /// - bits 1..=6: a form error (the delimiter is a fixed-form field, §10.11.4 / Bosch
    ///   §3.2.3): the node starts a new error flag at the next bit; a receiver adds 1 to
    ///   REC (rule 1, and rule 2 if the first bit after that new flag is dominant), a
    ///   transmitter adds 8 to TEC (rule 3; neither exception concerns a form error);
    /// - bit 7 (the last): an overload condition (§10.4.5.2 c: "detection of a dominant bit
    ///   at the last bit of an error delimiter or overload delimiter"): an overload frame,
    ///   no counter moves (except by rules 4 to 6 during it).
    ///
    /// A fault whose delimiter never comes (no error or overload frame in the attempt, or
    /// the node leaves before that bit) is refused once the attempt is played
    /// ([`FaultError::DelimiterNotReached`]), never moved to another bit.
    DelimiterBit {
        /// Who reads the dominant bit.
        who: Sees,
        /// The delimiter bit, 1..=7.
        bit: u8,
    },
    /// A dominant bit at intermission bit `bit` after the end of frame or after the first
    /// error / overload delimiter of the attempt (§10.4.6.2: 3 recessive bits). Bits 0
    /// and 1: an overload condition (§10.4.5.2 b), every node that reads it sends an
    /// overload frame; no counter moves. Bit 2 is refused
    /// ([`FaultError::IntermissionStartOfFrame`]): a node reads a dominant third
    /// intermission bit as the start of frame of the next frame (§10.4.6.2), which the
    /// simulator does not play (each attempt starts with its own SOF after the whole
    /// intermission). Refused as [`FaultError::IntermissionNotReached`] once the attempt
    /// is played if the bit is never read.
    IntermissionBit {
        /// Who reads the dominant bit.
        who: Sees,
        /// The intermission bit, 0..=1.
        bit: u8,
    },
}

/// Why a fault was refused (see [`Fault`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FaultError {
    /// [`Fault::FlagBit`] names a bit beyond the 6-bit error flag.
    FlagBitOutOfRange(u8),
    /// [`FormField::Eof`] beyond bit 5: a dominant last EOF bit is an overload condition
    /// for a receiver, not a form error.
    EofBitOutOfRange(u8),
    /// [`Fault::StuckDominant`] of 0 bits.
    EmptyStuckDominant,
    /// A bit fault in the ACK slot, where a transmitter reading dominant is normal.
    AckSlot,
    /// A bit fault on a recessive arbitration bit that is not a stuff bit: reading it
    /// dominant is lost arbitration, not an error.
    ArbitrationRecessiveBit(u32),
    /// A bit fault after the last EOF bit of the frame.
    AfterEndOfFrame(u32),
    /// A stuff error outside the stuffed region.
    OutsideStuffedRegion(u32),
    /// A stuck-dominant bus inside the arbitration field.
    StuckDuringArbitration(u32),
    /// [`Fault::DelimiterBit`] outside 1..=7 (bit 0 ends the flag; a delimiter has 8 bits).
    DelimiterBitOutOfRange(u8),
    /// [`Fault::IntermissionBit`] beyond bit 2 (the intermission has 3 bits).
    IntermissionBitOutOfRange(u8),
    /// [`Fault::IntermissionBit`] at bit 2: a dominant third intermission bit is a start
    /// of frame (§10.4.6.2), which the simulator does not play.
    IntermissionStartOfFrame,
    /// The attempt had no such delimiter bit for the node(s) named (no error or overload
    /// frame, or the node was not there at that bit).
    DelimiterNotReached(u8),
    /// The attempt played no such intermission bit for the node(s) named.
    IntermissionNotReached(u8),
}

impl core::fmt::Display for FaultError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FaultError::FlagBitOutOfRange(b) => write!(f, "error flag bit {b} (0..=5)"),
            FaultError::EofBitOutOfRange(b) => {
                write!(f, "EOF bit {b}: only bits 0..=5 give a form error")
            }
            FaultError::EmptyStuckDominant => f.write_str("stuck-dominant period of 0 bits"),
            FaultError::AckSlot => f.write_str("bit fault in the ACK slot"),
            FaultError::ArbitrationRecessiveBit(i) => {
                write!(f, "bit {i}: recessive arbitration bit (lost arbitration)")
            }
            FaultError::AfterEndOfFrame(i) => write!(f, "bit {i} is after the end of frame"),
            FaultError::OutsideStuffedRegion(i) => {
                write!(f, "bit {i} is outside the stuffed region")
            }
            FaultError::StuckDuringArbitration(i) => {
                write!(f, "stuck-dominant bus from bit {i}, inside arbitration")
            }
            FaultError::DelimiterBitOutOfRange(b) => {
                write!(f, "delimiter bit {b} (1..=7; bit 0 ends the flag)")
            }
            FaultError::IntermissionBitOutOfRange(b) => {
                write!(f, "intermission bit {b} (the intermission has bits 0..=2)")
            }
            FaultError::IntermissionStartOfFrame => {
                f.write_str("a dominant third intermission bit is a start of frame, not simulated")
            }
            FaultError::DelimiterNotReached(b) => {
                write!(f, "no error or overload delimiter reached bit {b}")
            }
            FaultError::IntermissionNotReached(b) => {
                write!(f, "intermission bit {b} was not played")
            }
        }
    }
}

impl std::error::Error for FaultError {}

impl Fault {
    /// The kind of this fault.
    pub const fn kind(&self) -> FaultKind {
        match self {
            Fault::Bit { .. } => FaultKind::Bit,
            Fault::Ack => FaultKind::Ack,
            Fault::Stuff { .. } => FaultKind::Stuff,
            Fault::Crc { .. } => FaultKind::Crc,
            Fault::Form { .. } => FaultKind::Form,
            Fault::FlagBit { .. } => FaultKind::FlagBit,
            Fault::StuckDominant { .. } => FaultKind::StuckDominant,
            Fault::DelimiterBit { .. } => FaultKind::DelimiterBit,
            Fault::IntermissionBit { .. } => FaultKind::IntermissionBit,
        }
    }

    /// Refuses a fault that cannot happen whatever the frame.
    pub const fn validate(&self) -> Result<(), FaultError> {
        match *self {
            Fault::FlagBit { bit, .. } if bit > 5 => Err(FaultError::FlagBitOutOfRange(bit)),
            Fault::Form {
                field: FormField::Eof(n),
                ..
            } if n > 5 => Err(FaultError::EofBitOutOfRange(n)),
            Fault::StuckDominant { bits: 0, .. } => Err(FaultError::EmptyStuckDominant),
            Fault::DelimiterBit { bit, .. } if bit == 0 || bit > 7 => {
                Err(FaultError::DelimiterBitOutOfRange(bit))
            }
            Fault::IntermissionBit { bit: 2, .. } => Err(FaultError::IntermissionStartOfFrame),
            Fault::IntermissionBit { bit, .. } if bit > 2 => {
                Err(FaultError::IntermissionBitOutOfRange(bit))
            }
            _ => Ok(()),
        }
    }

    /// Refuses a fault that cannot happen in a frame laid out as `bits` with the stuffed
    /// bits `stream` (SOF to the end of the CRC).
    pub(crate) fn check_layout(&self, bits: &FrameBits, stream: &[bool]) -> Result<(), FaultError> {
        self.validate()?;
        match *self {
            Fault::Bit { at } => {
                let pos = at.unwrap_or(bits.arbitration_end);
                if pos == bits.crc_end + 1 {
                    return Err(FaultError::AckSlot);
                }
                if pos > bits.crc_end + 9 {
                    return Err(FaultError::AfterEndOfFrame(pos));
                }
                let recessive = stream.get(pos as usize).copied().unwrap_or(true);
                if pos < bits.arbitration_end && recessive && !is_stuff_bit(stream, pos) {
                    return Err(FaultError::ArbitrationRecessiveBit(pos));
                }
                Ok(())
            }
            Fault::Stuff { at: Some(pos), .. } if pos >= bits.crc_end => {
                Err(FaultError::OutsideStuffedRegion(pos))
            }
            Fault::StuckDominant { at, .. } if at < bits.arbitration_end => {
                Err(FaultError::StuckDuringArbitration(at))
            }
            _ => Ok(()),
        }
    }

    /// The wire bits `at..at + bits` a [`Fault::StuckDominant`] holds dominant.
    pub(crate) fn stuck_range(&self) -> Option<(u32, u32)> {
        match *self {
            Fault::StuckDominant { at, bits } => Some((at, at.saturating_add(bits))),
            _ => None,
        }
    }

    /// The bus-wide delimiter bit of a [`Fault::DelimiterBit`] seen by the bus.
    pub(crate) fn bus_delimiter(&self) -> Option<u8> {
        match *self {
            Fault::DelimiterBit {
                who: Sees::Bus,
                bit,
            } => Some(bit),
            _ => None,
        }
    }

    /// The bus-wide intermission bit of a [`Fault::IntermissionBit`] seen by the bus.
    pub(crate) fn bus_intermission(&self) -> Option<u8> {
        match *self {
            Fault::IntermissionBit {
                who: Sees::Bus,
                bit,
            } => Some(bit),
            _ => None,
        }
    }
}

/// Whether wire bit `pos` of a stuffed stream is a stuff bit: the five bits before it are
/// equal (a stuff bit starts the next run, so this holds for stuff bits only).
pub(crate) fn is_stuff_bit(stream: &[bool], pos: u32) -> bool {
    let pos = pos as usize;
    pos >= 5 && pos <= stream.len() && stream[pos - 5..pos].iter().all(|&b| b == stream[pos - 1])
}

/// A fault resolved against one frame's layout: absolute wire-bit positions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TxFault {
    /// The transmitter reads the opposite bit at this position.
    Bit(u32),
    /// The transmitter reads a recessive ACK slot.
    Ack,
    /// It reads recessive at this bit of its own active error flag.
    FlagBit(u8),
    /// It reads dominant at this bit of its first error or overload delimiter.
    Delimiter(u8),
    /// It reads dominant at this intermission bit.
    Intermission(u8),
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
    /// It reads recessive at this bit of its own active error flag.
    FlagBit(u8),
    /// It reads dominant at this bit of its first error or overload delimiter.
    Delimiter(u8),
    /// It reads dominant at this intermission bit.
    Intermission(u8),
}

impl Fault {
    /// The transmitter-side part of this fault for transmitter `node` of a frame laid out
    /// as `bits` (the fault has passed [`Fault::check_layout`]).
    pub(crate) fn tx_part(&self, node: NodeId, bits: &FrameBits) -> Option<TxFault> {
        match *self {
            Fault::Bit { at } => Some(TxFault::Bit(at.unwrap_or(bits.arbitration_end))),
            Fault::Ack => Some(TxFault::Ack),
            Fault::FlagBit { who, bit } if who == node => Some(TxFault::FlagBit(bit)),
            Fault::DelimiterBit {
                who: Sees::Node(n),
                bit,
            } if n == node => Some(TxFault::Delimiter(bit)),
            Fault::IntermissionBit {
                who: Sees::Node(n),
                bit,
            } if n == node => Some(TxFault::Intermission(bit)),
            _ => None,
        }
    }

    /// The receive-side part of this fault for `node`, a receiver of a frame laid out as `bits`.
    pub(crate) fn rx_part(&self, node: NodeId, bits: &FrameBits) -> Option<RxFault> {
        match *self {
            Fault::Stuff { who, at } if who.includes(node) => {
                Some(RxFault::Stuff(at.unwrap_or(bits.arbitration_end)))
            }
            Fault::Crc { who } if who.includes(node) => Some(RxFault::Crc),
            Fault::Form { who, field } if who.includes(node) => Some(RxFault::Form(match field {
                FormField::CrcDelimiter => bits.crc_end,
                FormField::AckDelimiter => bits.crc_end + 2,
                FormField::Eof(n) => bits.crc_end + 3 + u32::from(n),
            })),
            Fault::FlagBit { who, bit } if who == node => Some(RxFault::FlagBit(bit)),
            Fault::DelimiterBit {
                who: Sees::Node(n),
                bit,
            } if n == node => Some(RxFault::Delimiter(bit)),
            Fault::IntermissionBit {
                who: Sees::Node(n),
                bit,
            } if n == node => Some(RxFault::Intermission(bit)),
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
            FaultKind::FlagBit => Fault::FlagBit {
                who: *receivers.get(self.rng.below(receivers.len().max(1) as u64) as usize)?,
                bit: self.rng.below(6) as u8,
            },
            FaultKind::StuckDominant => Fault::StuckDominant {
                at: bits.arbitration_end + self.rng.below(u64::from(bits.total)) as u32,
                bits: 1 + self.rng.below(24) as u32,
            },
            FaultKind::DelimiterBit => Fault::DelimiterBit {
                who: match who() {
                    Receivers::Node(n) => Sees::Node(n),
                    Receivers::All => Sees::Bus,
                },
                bit: 1 + self.rng.below(7) as u8,
            },
            FaultKind::IntermissionBit => Fault::IntermissionBit {
                who: match who() {
                    Receivers::Node(n) => Sees::Node(n),
                    Receivers::All => Sees::Bus,
                },
                bit: self.rng.below(2) as u8,
            },
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

    /// Nothing scheduled and no random injection: every attempt gets no fault.
    pub(crate) fn is_idle(&self) -> bool {
        self.at_frame.is_empty() && self.from_node.is_empty() && self.random.is_none()
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
        let bits =
            super::super::bits::frame_bits(&twocan_core::frame::Frame::standard(1, &[]).unwrap());
        let mut never = RandomState::new(&RandomFaults::new(7, 0.0));
        let mut nan = RandomState::new(&RandomFaults::new(7, f64::NAN));
        let mut always = RandomState::new(&RandomFaults::new(7, 1.0).with_kinds(&[FaultKind::Ack]));
        for _ in 0..100 {
            assert!(never.draw(&bits, &[]).is_none());
            assert!(nan.draw(&bits, &[]).is_none());
            assert_eq!(always.draw(&bits, &[]), Some(Fault::Ack));
        }
    }

    #[test]
    fn delimiter_and_intermission_faults_are_checked() {
        let mut bus = crate::Bus::new(500_000).unwrap();
        let node = bus.attach("a", crate::SimNode::new().shared());
        let other = bus.attach("b", crate::SimNode::new().shared());
        for bit in 1..=7 {
            for who in [Sees::Bus, Sees::Node(node)] {
                assert_eq!(Fault::DelimiterBit { who, bit }.validate(), Ok(()));
            }
        }
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
                    who: Sees::Bus,
                    bit: 8,
                },
                FaultError::DelimiterBitOutOfRange(8),
            ),
            (
                Fault::IntermissionBit {
                    who: Sees::Node(node),
                    bit: 2,
                },
                FaultError::IntermissionStartOfFrame,
            ),
            (
                Fault::IntermissionBit {
                    who: Sees::Bus,
                    bit: 3,
                },
                FaultError::IntermissionBitOutOfRange(3),
            ),
        ] {
            assert_eq!(fault.validate(), Err(error));
            let e: &dyn std::error::Error = &error;
            assert!(!std::format!("{e}").is_empty());
        }
        assert_eq!(
            std::format!("{}", FaultError::IntermissionStartOfFrame),
            "a dominant third intermission bit is a start of frame, not simulated"
        );
        // Node faults go to that node only; bus faults to nobody's own list.
        let bits =
            super::super::bits::frame_bits(&twocan_core::frame::Frame::standard(1, &[]).unwrap());
        let f = Fault::DelimiterBit {
            who: Sees::Node(node),
            bit: 4,
        };
        assert_eq!(f.tx_part(node, &bits), Some(TxFault::Delimiter(4)));
        assert_eq!(f.rx_part(other, &bits), None);
        let f = Fault::IntermissionBit {
            who: Sees::Bus,
            bit: 1,
        };
        assert_eq!(f.bus_intermission(), Some(1));
        assert_eq!(f.tx_part(node, &bits), None);
    }
}
