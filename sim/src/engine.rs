//! One frame attempt played bit by bit: who detects which error when, the error flags and
//! their echoes, the delimiters, and so the exact length of the attempt.
//!
//! Every participant runs a small ISO 11898-1 state machine. The wire value of each bit is
//! the wired-AND of what the participants drive (dominant wins):
//!
//! - a transmitter drives its stuffed frame bits, then recessive delimiters, ACK slot and EOF;
//!   it detects a bit error when it reads another value than it sent (except in the ACK slot,
//!   where it detects an acknowledge error if it reads recessive and does not self-acknowledge);
//! - a receiver drives a dominant ACK slot if it acknowledges and its CRC matched; it detects a
//!   stuff error at six equal bits in the stuffed region, a form error at a dominant CRC
//!   delimiter, ACK delimiter or EOF bit 1..6 (a dominant last EOF bit is an overload
//!   condition, not an error: the frame is already valid), and a CRC error — signalled from the
//!   bit after the ACK delimiter — when what it read differs from the frame it follows or an
//!   injected fault says so;
//! - a node that detects an error sends an active error flag (6 dominant bits) if it is
//!   error-active and able to drive the bus, otherwise a passive one (it drives nothing and
//!   waits for 6 equal consecutive bits); then it waits for a recessive bit (ISO rule 2: a
//!   receiver that reads dominant as the first bit after its flag reports it) and counts the
//!   8-bit error delimiter.
//!
//! The attempt ends when every node that can drive the bus — the transmitters and the
//! error-active receivers — has finished its EOF or error delimiter. A node sending a passive
//! error flag drives nothing, so it does not lengthen the attempt: when a single active flag
//! (6 dominant bits, no echo) meets a passive receiver that detected it at its first bit, ISO
//! 11898-1 would keep that receiver waiting for six equal bits a few bits longer than the
//! others; here it is taken to be done with the others (it would resynchronise on the next
//! idle bits anyway). Its detected error and rule-2 flag are still reported.
//!
//! Fault-confinement details the engine records for each node that sends an error flag:
//!
//! - reading a dominant bit during its own passive error flag (rule 3, exception 1 does
//!   not apply then);
//! - a bit error during its own active error flag or overload flag (rules 4 and 5:
//!   injected with `Fault::FlagBit`): +8, and the node starts a new flag at the next bit;
//! - the dominant-bit tolerance after a flag (rule 6): counting consecutive dominant bits
//!   from the start of an active error flag, or after the end of a passive one, the 14th
//!   (active) or 8th (passive) and every 8th after it add 8 (a bus held dominant:
//!   `Fault::StuckDominant`);
//! - a transmitter's stuff error on a recessive stuff bit of the arbitration field read
//!   dominant (rule 3, exception 2: TEC unchanged).
//!
//! Overload frames (§10.4.5): a receiver that reads a dominant last EOF bit (the frame is
//! valid for it), and a node that reads a dominant bit in the first two bits of the
//! intermission after its end of frame or delimiter, sends an overload flag (6 dominant
//! bits, also when error-passive; not a silent node) and an overload delimiter; counters do
//! not move, except by rule 6. The intermission is played only while something may drive it
//! (an overload frame in progress, a stuck-dominant bus).
//!
//! Delimiters (§10.4.4.3 error delimiter, §10.4.5.3 overload delimiter: 8 recessive bits,
//! a fixed-form field, §10.11.4): a node that reads a dominant bit at delimiter bits 1..=6
//! (bit 0 is the recessive bit it waited for after its flag) detects a form error and
//! starts a new error flag at the next bit — a second error of the attempt, reported per
//! receiver in `Resolution::rx_more_errors` (rule 1, and rule 2 for the new flag) and per
//! transmitter as one more +8 in `Resolution::tx_penalties` (rule 3; its exceptions concern
//! acknowledge and arbitration stuff errors only). A dominant last (8th) delimiter bit is
//! an overload condition (§10.4.5.2): an overload frame, no counter change. Injected
//! misreads (`Fault::DelimiterBit`, `Fault::IntermissionBit` for one node) and bus-wide
//! dominant bits ([`WireFaults`]) aim at the first delimiter of each node; a fault whose bit
//! never comes is listed in `Resolution::missed` (the bus refuses it). A bus-wide one lands
//! where the transmitters and error-active receivers are, or, if none of them is in an
//! error frame, at a passive receiver's delimiter up to their second intermission bit (a
//! dominant bit after it would be their start of frame). A pending delimiter fault keeps
//! the attempt played (past the end that the driving nodes give it) until that delimiter
//! is over.
//!
//! Not modelled (what the engine does instead):
//! - a dominant third intermission bit: a start of frame for every node (§10.4.6.2), a new
//!   attempt one bit early; the injector refuses `Fault::IntermissionBit` there, and a
//!   stuck-dominant period over it is ignored (the intermission ends and the next attempt
//!   starts at its own time);
//! - hard synchronisation effects.

use super::bits::FrameBits;
use super::inject::{is_stuff_bit, RxFault, TxFault};
use twocan_core::error::LastErrorCode;

/// A transmitter of the frame attempt.
#[derive(Debug, Clone)]
pub(crate) struct TxSpec<'a> {
    /// Its stuffed bits, SOF through CRC.
    pub stream: &'a [bool],
    /// Its frame layout.
    pub bits: FrameBits,
    /// It ignores the ACK slot.
    pub self_ack: bool,
    /// It sends active error flags.
    pub active: bool,
    /// Injected faults.
    pub faults: Vec<TxFault>,
}

/// A receiver of the frame attempt.
#[derive(Debug, Clone, Default)]
pub(crate) struct RxSpec {
    /// It drives a dominant ACK bit for a frame it received correctly.
    pub acks: bool,
    /// It sends active error flags.
    pub active: bool,
    /// Injected faults.
    pub faults: Vec<RxFault>,
}

/// How the attempt ended for one participant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PartOutcome {
    /// Transmitted / received without error; `done` bits after SOF (end of its EOF).
    Ok {
        /// One past the node's last EOF bit.
        done: u32,
    },
    /// Detected an error at wire bit `at`.
    Error {
        /// The error.
        code: LastErrorCode,
        /// Wire-bit index from SOF.
        at: u32,
        /// A receiver read a dominant bit right after its error flag (ISO rule 2).
        dominant_after_flag: bool,
        /// It sent a passive error flag and read a dominant bit during it (rule 3,
        /// exception 1 does not apply then).
        dominant_in_passive_flag: bool,
        /// A transmitter's stuff error on a recessive stuff bit in arbitration (rule 3,
        /// exception 2: TEC unchanged).
        arbitration_stuff_exception: bool,
    },
}

/// The result of one frame attempt.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Resolution {
    /// Per transmitter, in input order.
    pub tx: Vec<PartOutcome>,
    /// Per receiver, in input order.
    pub rx: Vec<PartOutcome>,
    /// A fault-free, non-driving listener would have accepted the frame.
    pub observer_ok: bool,
    /// Some receiver drove the ACK slot dominant.
    pub acked: bool,
    /// Bits from SOF to the end of EOF or of the last error delimiter (no intermission).
    pub end: u32,
    /// One past the index of the last dominant bit on the wire.
    pub last_dominant_end: u32,
    /// The wire, bit by bit, from SOF for `end` bits (`true` = recessive).
    pub wire: Vec<bool>,
    /// Index into the transmitters of the frame the receivers followed.
    pub reference: usize,
    /// Per transmitter, extra +8 penalties: bit errors during its own active error flag
    /// (rules 4, 5) and dominant sequences after its error or overload flag (rule 6).
    /// Empty when there are none (the common case: no allocation).
    pub tx_penalties: Vec<u8>,
    /// Per receiver, the same.
    pub rx_penalties: Vec<u8>,
    /// Per receiver, errors it detected after its first one (a form error in an error or
    /// overload delimiter): code, wire bit, and rule 2 for the flag that followed. Empty
    /// when there are none. A transmitter's such errors are in `tx_penalties` (+8 each).
    pub rx_more_errors: Vec<Vec<(LastErrorCode, u32, bool)>>,
    /// Delimiter / intermission faults that found no such bit.
    pub missed: Vec<Missed>,
}

/// A delimiter or intermission fault the attempt never reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Missed {
    /// Of transmitter `n` (input order).
    Tx(usize, Aim),
    /// Of receiver `n` (input order).
    Rx(usize, Aim),
    /// Of the bus.
    Bus(Aim),
}

/// Which bit a delimiter or intermission fault aims at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Aim {
    /// Delimiter bit n.
    Delimiter(u8),
    /// Intermission bit n.
    Intermission(u8),
}

/// Dominant bits the wire carries whatever the nodes drive.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct WireFaults {
    /// Held dominant over these bits.
    pub stuck: Option<(u32, u32)>,
    /// Dominant at this bit of the first error or overload delimiter.
    pub delimiter: Option<u8>,
    /// Dominant at this intermission bit.
    pub intermission: Option<u8>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Frame,
    ActiveFlag(u8),
    PassiveFlag {
        last: bool,
        run: u8,
    },
    /// Overload flag bit n (6 dominant bits).
    Overload(u8),
    AfterFlag {
        first: bool,
    },
    Delimiter(u8),
    /// Intermission bit n after its end of frame or delimiter: a dominant bit at bit 0 or
    /// 1 starts an overload frame.
    Intermission(u8),
    Done,
}

impl Phase {
    /// Finished with the attempt (the intermission counts as finished).
    fn finished(self) -> bool {
        matches!(self, Phase::Done | Phase::Intermission(_))
    }
}

#[derive(Debug, Clone)]
struct Part {
    phase: Phase,
    can_flag: bool,
    /// It can drive the bus (a silent node cannot send overload flags).
    can_drive: bool,
    /// It is sending an overload frame (flag or delimiter).
    overloading: bool,
    error: Option<(LastErrorCode, u32)>,
    dominant_after_flag: bool,
    dominant_in_passive_flag: bool,
    /// The flag it sent (or sends) is active.
    active_flag: bool,
    /// Injected: it misreads this bit of its active error flag (once).
    flag_fault: Option<u8>,
    /// Injected: it reads dominant at this bit of its first delimiter (once).
    delim_fault: Option<u8>,
    /// Injected: it reads dominant at this intermission bit (once).
    inter_fault: Option<u8>,
    /// Errors after the first one (form errors in a delimiter): code, bit, rule 2.
    more_errors: Vec<(LastErrorCode, u32, bool)>,
    /// It has finished one delimiter (a delimiter fault aims at the first one only).
    delimited: bool,
    /// Consecutive dominant bits counted for rule 6.
    dominant_run: u32,
    penalties: u8,
    arbitration_stuff_exception: bool,
    ok: Option<u32>,
    // receiver bookkeeping
    run_last: bool,
    run: u8,
    mismatch: bool,
    crc_bad: bool,
}

impl Part {
    fn new(can_flag: bool) -> Self {
        Part {
            phase: Phase::Frame,
            can_flag,
            can_drive: true,
            overloading: false,
            error: None,
            dominant_after_flag: false,
            dominant_in_passive_flag: false,
            active_flag: false,
            flag_fault: None,
            delim_fault: None,
            inter_fault: None,
            more_errors: Vec::new(),
            delimited: false,
            dominant_run: 0,
            penalties: 0,
            arbitration_stuff_exception: false,
            ok: None,
            run_last: true,
            run: 0,
            mismatch: false,
            crc_bad: false,
        }
    }

    fn detect(&mut self, code: LastErrorCode, at: u32) {
        self.error = Some((code, at));
        self.active_flag = self.can_flag;
        self.dominant_run = 0;
        self.phase = if self.can_flag {
            Phase::ActiveFlag(0)
        } else {
            Phase::PassiveFlag { last: true, run: 0 }
        };
    }

    /// A form error in an error or overload delimiter (ISO 11898-1 §10.11.4): a second
    /// error in the attempt, with a new error flag from the next bit.
    fn detect_again(&mut self, code: LastErrorCode, at: u32) {
        self.more_errors.push((code, at, false));
        self.overloading = false;
        self.active_flag = self.can_flag;
        self.dominant_run = 0;
        self.phase = if self.can_flag {
            Phase::ActiveFlag(0)
        } else {
            Phase::PassiveFlag { last: true, run: 0 }
        };
    }

    /// In an error or overload frame (flag, the bits after it, delimiter).
    fn in_error_frame(&self) -> bool {
        matches!(
            self.phase,
            Phase::ActiveFlag(_)
                | Phase::PassiveFlag { .. }
                | Phase::Overload(_)
                | Phase::AfterFlag { .. }
                | Phase::Delimiter(_)
        )
    }

    fn drives_flag(&self) -> bool {
        matches!(self.phase, Phase::ActiveFlag(_) | Phase::Overload(_))
    }

    /// An overload condition (ISO 11898-1 §10.4.5): a dominant last EOF bit seen by a
    /// receiver, or a dominant bit in the first two intermission bits. A node able to
    /// drive the bus sends an overload flag from the next bit; counters do not move
    /// (rule 6 still counts dominant bits from the start of the flag).
    fn overload(&mut self) {
        if self.can_drive {
            self.overloading = true;
            self.active_flag = true;
            self.dominant_run = 0;
            self.phase = Phase::Overload(0);
        } else {
            self.phase = Phase::Done;
        }
    }

    /// Reads one intermission bit.
    fn intermission(&mut self, wire: bool) {
        if let Phase::Intermission(k) = self.phase {
            let misread = self.inter_fault == Some(k);
            if misread {
                self.inter_fault = None;
            }
            if (!wire || misread) && k < 2 {
                self.overload();
            } else if k + 1 >= 3 {
                self.phase = Phase::Done;
            } else {
                self.phase = Phase::Intermission(k + 1);
            }
        }
    }

    fn add_penalty(&mut self) {
        self.penalties = self.penalties.saturating_add(1);
    }

    /// Rule 6: one more consecutive dominant bit after (or, active, including) the flag.
    fn count_dominant(&mut self) {
        self.dominant_run += 1;
        let first = if self.active_flag { 14 } else { 8 };
        if self.dominant_run >= first && (self.dominant_run - first).is_multiple_of(8) {
            self.add_penalty();
        }
    }

    /// Reads wire bit `i` while in an error phase.
    fn error_phase(&mut self, wire: bool, i: u32) {
        self.phase = match self.phase {
            Phase::ActiveFlag(n) if self.flag_fault == Some(n) => {
                // Rules 4 / 5: a bit error during its own active error flag; a new flag
                // starts at the next bit.
                self.flag_fault = None;
                self.add_penalty();
                self.dominant_run = 0;
                Phase::ActiveFlag(0)
            }
            Phase::ActiveFlag(n) => {
                if !wire {
                    self.count_dominant();
                }
                if n + 1 >= 6 {
                    Phase::AfterFlag { first: true }
                } else {
                    Phase::ActiveFlag(n + 1)
                }
            }
            Phase::Overload(n) if self.flag_fault == Some(n) => {
                // Rules 4 / 5 apply to overload flags too; a new overload flag starts.
                self.flag_fault = None;
                self.add_penalty();
                self.dominant_run = 0;
                Phase::Overload(0)
            }
            Phase::Overload(n) => {
                if !wire {
                    self.count_dominant();
                }
                if n + 1 >= 6 {
                    Phase::AfterFlag { first: true }
                } else {
                    Phase::Overload(n + 1)
                }
            }
            Phase::PassiveFlag { last, run } => {
                // Rule 3 exception 1 is about the flag sent for the acknowledge error.
                if !wire && self.more_errors.is_empty() {
                    self.dominant_in_passive_flag = true;
                }
                let run = if run == 0 || wire == last { run + 1 } else { 1 };
                if run >= 6 {
                    self.dominant_run = 0;
                    Phase::AfterFlag { first: true }
                } else {
                    Phase::PassiveFlag { last: wire, run }
                }
            }
            Phase::AfterFlag { first } => {
                if wire {
                    Phase::Delimiter(1)
                } else {
                    // Rule 2 is about error flags only.
                    if first && !self.overloading {
                        match self.more_errors.last_mut() {
                            Some(e) => e.2 = true,
                            None => self.dominant_after_flag = true,
                        }
                    }
                    self.count_dominant();
                    Phase::AfterFlag { first: false }
                }
            }
            Phase::Delimiter(n) => {
                let misread = !self.delimited && self.delim_fault == Some(n);
                if misread {
                    self.delim_fault = None;
                }
                if wire && !misread {
                    if n + 1 >= 8 {
                        self.overloading = false;
                        self.delimited = true;
                        Phase::Intermission(0)
                    } else {
                        Phase::Delimiter(n + 1)
                    }
                } else if n >= 7 {
                    // A dominant last delimiter bit: an overload condition (§10.4.5.2).
                    self.delimited = true;
                    self.overload();
                    self.phase
                } else {
                    // Any other delimiter bit: a form error (§10.11.4), a new error flag.
                    self.delimited = true;
                    self.detect_again(LastErrorCode::Form, i);
                    self.phase
                }
            }
            other => other,
        };
    }

    /// The faults aimed at delimiter / intermission bits this node never read.
    fn missed(&self) -> impl Iterator<Item = Aim> {
        self.delim_fault
            .map(Aim::Delimiter)
            .into_iter()
            .chain(self.inter_fault.map(Aim::Intermission))
    }

    fn outcome(&self, end: u32) -> PartOutcome {
        match self.error {
            Some((code, at)) => PartOutcome::Error {
                code,
                at,
                dominant_after_flag: self.dominant_after_flag,
                dominant_in_passive_flag: self.dominant_in_passive_flag,
                arbitration_stuff_exception: self.arbitration_stuff_exception,
            },
            None => match self.ok {
                Some(done) => PartOutcome::Ok { done },
                // Cut off by the safety limit (cannot happen with the rules above).
                None => PartOutcome::Error {
                    code: LastErrorCode::Form,
                    at: end,
                    dominant_after_flag: false,
                    dominant_in_passive_flag: false,
                    arbitration_stuff_exception: false,
                },
            },
        }
    }
}

fn tx_bit(tx: &TxSpec<'_>, i: u32) -> bool {
    if i < tx.bits.crc_end {
        tx.stream.get(i as usize).copied().unwrap_or(true)
    } else {
        true
    }
}

fn tx_read(tx: &TxSpec<'_>, p: &mut Part, wire: bool, i: u32) {
    let sent = tx_bit(tx, i);
    let mismatch_code = if sent {
        LastErrorCode::BitRecessive
    } else {
        LastErrorCode::BitDominant
    };
    let code = if tx.faults.contains(&TxFault::Bit(i)) {
        if i < tx.bits.arbitration_end && sent && is_stuff_bit(tx.stream, i) {
            // A recessive stuff bit read dominant in arbitration: a stuff error, and rule 3
            // exception 2 leaves TEC unchanged.
            p.arbitration_stuff_exception = true;
            Some(LastErrorCode::Stuff)
        } else {
            Some(mismatch_code)
        }
    } else if i == tx.bits.crc_end + 1 {
        let read_recessive = wire || tx.faults.contains(&TxFault::Ack);
        (read_recessive && !tx.self_ack).then_some(LastErrorCode::Acknowledge)
    } else if wire != sent {
        Some(mismatch_code)
    } else {
        None
    };
    match code {
        Some(c) => p.detect(c, i),
        None if i >= tx.bits.crc_end + 9 => {
            p.ok = Some(i + 1);
            p.phase = Phase::Intermission(0);
        }
        None => {}
    }
}

fn rx_read(rx: &RxSpec, p: &mut Part, wire: bool, i: u32, reference: &[bool], ce: u32) {
    let form_forced = rx.faults.contains(&RxFault::Form(i));
    let mut code = None;
    if i < ce {
        if wire == p.run_last {
            p.run = p.run.saturating_add(1);
        } else {
            p.run_last = wire;
            p.run = 1;
        }
        if p.run >= 6 || rx.faults.contains(&RxFault::Stuff(i)) {
            code = Some(LastErrorCode::Stuff);
        }
        if reference.get(i as usize).copied() != Some(wire) {
            p.mismatch = true;
        }
    } else if i == ce {
        if !wire || form_forced {
            code = Some(LastErrorCode::Form);
        }
        p.crc_bad = p.mismatch || rx.faults.contains(&RxFault::Crc);
    } else if i == ce + 1 {
        // ACK slot: anything goes.
    } else if i == ce + 2 {
        if !wire || form_forced {
            code = Some(LastErrorCode::Form);
        } else if p.crc_bad {
            code = Some(LastErrorCode::Crc);
        }
    } else if i <= ce + 8 {
        if !wire || form_forced {
            code = Some(LastErrorCode::Form);
        }
    } else {
        // Last EOF bit: the frame is valid for a receiver; a dominant bit here is an
        // overload condition.
        p.ok = Some(i + 1);
        if wire {
            p.phase = Phase::Intermission(0);
        } else {
            p.overload();
        }
    }
    if let Some(c) = code {
        p.detect(c, i);
    }
}

/// The parts' penalties, or an empty vector when all are 0. `transmitters`: a form error
/// in a delimiter is one more error flag sent, TEC + 8 (rule 3) — counted here.
fn penalties(parts: &[Part], transmitters: bool) -> Vec<u8> {
    let of = |p: &Part| {
        let more = if transmitters {
            p.more_errors.len().min(255) as u8
        } else {
            0
        };
        p.penalties.saturating_add(more)
    };
    if parts.iter().all(|p| of(p) == 0) {
        Vec::new()
    } else {
        parts.iter().map(of).collect()
    }
}

/// Plays one frame attempt. `txs` must not be empty (an empty slice gives an empty result).
#[cfg(test)]
pub(crate) fn resolve(txs: &[TxSpec<'_>], rxs: &[RxSpec]) -> Resolution {
    resolve_with(txs, rxs, WireFaults::default())
}

/// [`resolve`] with the wire faults `wf`: held dominant over bits `stuck.0..stuck.1`,
/// dominant at a delimiter or intermission bit.
pub(crate) fn resolve_with(txs: &[TxSpec<'_>], rxs: &[RxSpec], wf: WireFaults) -> Resolution {
    let stuck = wf.stuck;
    let mut bus_delim = wf.delimiter;
    let mut bus_inter = wf.intermission;
    let reference = (0..txs.len())
        .min_by(|&a, &b| txs[a].stream.cmp(txs[b].stream))
        .unwrap_or(0);
    let Some(ref_tx) = txs.get(reference) else {
        return Resolution {
            tx: Vec::new(),
            rx: Vec::new(),
            observer_ok: false,
            acked: false,
            end: 0,
            last_dominant_end: 0,
            wire: Vec::new(),
            reference: 0,
            tx_penalties: Vec::new(),
            rx_penalties: Vec::new(),
            rx_more_errors: Vec::new(),
            missed: Vec::new(),
        };
    };
    let ce = ref_tx.bits.crc_end;
    let ref_stream = ref_tx.stream;

    let observer = RxSpec::default();
    let flag_fault = |tx: Option<&[TxFault]>, rx: Option<&[RxFault]>| {
        tx.into_iter()
            .flatten()
            .find_map(|f| match f {
                TxFault::FlagBit(b) => Some(*b),
                _ => None,
            })
            .or_else(|| {
                rx.into_iter().flatten().find_map(|f| match f {
                    RxFault::FlagBit(b) => Some(*b),
                    _ => None,
                })
            })
    };
    let mut tx_parts: Vec<Part> = txs
        .iter()
        .map(|t| Part {
            flag_fault: flag_fault(Some(&t.faults), None),
            delim_fault: t.faults.iter().find_map(|f| match f {
                TxFault::Delimiter(b) => Some(*b),
                _ => None,
            }),
            inter_fault: t.faults.iter().find_map(|f| match f {
                TxFault::Intermission(b) => Some(*b),
                _ => None,
            }),
            ..Part::new(t.active)
        })
        .collect();
    let mut rx_parts: Vec<Part> = rxs
        .iter()
        .map(|r| Part {
            flag_fault: flag_fault(None, Some(&r.faults)),
            delim_fault: r.faults.iter().find_map(|f| match f {
                RxFault::Delimiter(b) => Some(*b),
                _ => None,
            }),
            inter_fault: r.faults.iter().find_map(|f| match f {
                RxFault::Intermission(b) => Some(*b),
                _ => None,
            }),
            can_drive: r.acks,
            ..Part::new(r.active)
        })
        .collect();
    let mut obs_part = Part {
        can_drive: false,
        ..Part::new(false)
    };

    let longest = txs.iter().map(|t| t.bits.crc_end).max().unwrap_or(ce);
    let stuck_len = stuck.map_or(0, |(a, b)| b.saturating_sub(a));
    // Each delimiter / intermission fault may add an error or overload frame (at most 6 +
    // 6 echo + 8 delimiter + 3 bits, and its own chain of echoes): a generous margin.
    let aimed = (txs.iter().map(|t| t.faults.len()).sum::<usize>()
        + rxs.iter().map(|r| r.faults.len()).sum::<usize>()
        + 2)
    .min(64) as u32;
    let limit = longest + 10 + 64 + stuck_len.min(4096) + 32 + 32 * aimed;
    let mut acked = false;
    let mut last_dominant_end = 0;
    let mut i = 0u32;
    let mut drivers_end = None;
    let mut bus = Vec::with_capacity(limit as usize);
    let end = loop {
        // What the participants drive.
        let mut wire = true;
        for (t, p) in txs.iter().zip(&tx_parts) {
            let drives_dominant = match p.phase {
                Phase::Frame => !tx_bit(t, i),
                _ => p.drives_flag(),
            };
            wire &= !drives_dominant;
        }
        for (r, p) in rxs.iter().zip(&rx_parts) {
            let drives_dominant = match p.phase {
                Phase::Frame => i == ce + 1 && r.acks && !p.crc_bad,
                _ => p.drives_flag(),
            };
            if drives_dominant && p.phase == Phase::Frame {
                acked = true;
            }
            wire &= !drives_dominant;
        }
        if stuck.is_some_and(|(a, b)| (a..b).contains(&i)) {
            wire = false;
        }
        // A bus-wide delimiter / intermission fault lands where the transmitters and the
        // error-active receivers (whose flags end together) are at that bit; only when
        // none of them is in an error or overload frame, where any other node is.
        if bus_delim.is_some() || bus_inter.is_some() {
            let leads = || {
                tx_parts.iter().chain(
                    rx_parts
                        .iter()
                        .zip(rxs)
                        .filter(|(_, r)| r.active)
                        .map(|(p, _)| p),
                )
            };
            let others = || rx_parts.iter().chain(core::iter::once(&obs_part));
            // Not past the leads' second intermission bit: a dominant bit there would be a
            // start of frame for them, which is not played.
            let early =
                || leads().all(|p| !matches!(p.phase, Phase::Intermission(2) | Phase::Done));
            let at = |hit: &dyn Fn(&Part) -> bool, busy: &dyn Fn(&Part) -> bool| {
                if leads().any(busy) {
                    leads().any(hit)
                } else {
                    early() && others().any(hit)
                }
            };
            if let Some(k) = bus_delim {
                let hit = |p: &Part| !p.delimited && p.phase == Phase::Delimiter(k);
                if at(&hit, &|p: &Part| p.in_error_frame()) {
                    wire = false;
                    bus_delim = None;
                }
            }
            if let Some(k) = bus_inter {
                let hit = |p: &Part| p.phase == Phase::Intermission(k);
                let busy = |p: &Part| matches!(p.phase, Phase::Intermission(_));
                if at(&hit, &busy) {
                    wire = false;
                    bus_inter = None;
                }
            }
        }
        if !wire {
            last_dominant_end = i + 1;
        }
        bus.push(wire);

        // What they read.
        for (t, p) in txs.iter().zip(tx_parts.iter_mut()) {
            match p.phase {
                Phase::Frame => tx_read(t, p, wire, i),
                Phase::Done => {}
                Phase::Intermission(_) => p.intermission(wire),
                _ => p.error_phase(wire, i),
            }
        }
        for (r, p) in rxs
            .iter()
            .chain(core::iter::once(&observer))
            .zip(rx_parts.iter_mut().chain(core::iter::once(&mut obs_part)))
        {
            match p.phase {
                Phase::Frame => rx_read(r, p, wire, i, ref_stream, ce),
                Phase::Done => {}
                Phase::Intermission(_) => p.intermission(wire),
                _ => p.error_phase(wire, i),
            }
        }

        i += 1;
        let drivers_done = tx_parts.iter().all(|p| p.phase.finished())
            && rx_parts
                .iter()
                .zip(rxs)
                .all(|(p, r)| (!r.active && !p.overloading) || p.phase.finished());
        if !drivers_done {
            // An overload frame (or anything still driving) moves the end.
            drivers_end = None;
        } else if drivers_end.is_none() {
            drivers_end = Some(i);
        }
        let decided = rx_parts
            .iter()
            .chain(core::iter::once(&obs_part))
            .all(|p| p.phase != Phase::Frame);
        let stuck_over = stuck.is_none_or(|(_, b)| i >= b);
        // An intermission fault keeps the intermission played while it may still hit.
        let in_intermission = |p: &Part| matches!(p.phase, Phase::Intermission(_));
        let parts = || {
            tx_parts
                .iter()
                .chain(&rx_parts)
                .chain(core::iter::once(&obs_part))
        };
        let inter_pending = || {
            (bus_inter.is_some() && parts().any(in_intermission))
                || parts().any(|p| p.inter_fault.is_some() && in_intermission(p))
        };
        // A node's own delimiter fault keeps its delimiter played, also for a node that
        // drives nothing (a passive flag) and so does not hold the end of the attempt.
        let delim_pending = || {
            parts().any(|p| {
                (p.delim_fault.is_some() || bus_delim.is_some())
                    && !p.delimited
                    && p.in_error_frame()
            })
        };
        if (drivers_done && decided && stuck_over && !inter_pending() && !delim_pending())
            || i >= limit
        {
            break drivers_end.unwrap_or(i);
        }
    };

    Resolution {
        tx: tx_parts.iter().map(|p| p.outcome(end)).collect(),
        rx: rx_parts.iter().map(|p| p.outcome(end)).collect(),
        observer_ok: obs_part.error.is_none() && obs_part.ok.is_some(),
        acked,
        end,
        last_dominant_end,
        wire: {
            bus.truncate(end as usize);
            bus
        },
        reference,
        tx_penalties: penalties(&tx_parts, true),
        rx_penalties: penalties(&rx_parts, false),
        rx_more_errors: if rx_parts.iter().all(|p| p.more_errors.is_empty()) {
            Vec::new()
        } else {
            rx_parts.iter().map(|p| p.more_errors.clone()).collect()
        },
        missed: {
            let mut m: Vec<Missed> = Vec::new();
            for (n, p) in tx_parts.iter().enumerate() {
                m.extend(p.missed().map(|a| Missed::Tx(n, a)));
            }
            for (n, p) in rx_parts.iter().enumerate() {
                m.extend(p.missed().map(|a| Missed::Rx(n, a)));
            }
            m.extend(bus_delim.map(|b| Missed::Bus(Aim::Delimiter(b))));
            m.extend(bus_inter.map(|b| Missed::Bus(Aim::Intermission(b))));
            m
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bits::wire_bits;
    use twocan_core::frame::Frame;
    use LastErrorCode as L;

    fn tx<'a>(w: &'a (Vec<bool>, FrameBits), active: bool) -> TxSpec<'a> {
        TxSpec {
            stream: &w.0,
            bits: w.1,
            self_ack: false,
            active,
            faults: Vec::new(),
        }
    }
    fn rx(acks: bool, active: bool) -> RxSpec {
        RxSpec {
            acks,
            active,
            faults: Vec::new(),
        }
    }
    fn err(code: L, at: u32, dom: bool) -> PartOutcome {
        PartOutcome::Error {
            code,
            at,
            dominant_after_flag: dom,
            dominant_in_passive_flag: false,
            arbitration_stuff_exception: false,
        }
    }

    #[test]
    fn good_frame() {
        let w = wire_bits(&Frame::standard(0x123, &[1, 2, 3]).unwrap());
        let r = resolve(&[tx(&w, true)], &[rx(true, true), rx(false, false)]);
        let t = w.1.total;
        assert_eq!(r.tx, vec![PartOutcome::Ok { done: t }]);
        assert_eq!(
            r.rx,
            vec![PartOutcome::Ok { done: t }, PartOutcome::Ok { done: t }]
        );
        assert_eq!(r.wire.len() as u32, t);
        assert_eq!(&r.wire[..w.1.crc_end as usize], &w.0[..]);
        assert!(r.acked && r.observer_ok);
        assert_eq!(r.end, w.1.total);
        assert_eq!(
            r.last_dominant_end,
            w.1.crc_end + 2,
            "the ACK slot is the last dominant bit"
        );
    }

    #[test]
    fn lone_active_transmitter_ack_error() {
        let w = wire_bits(&Frame::standard(0x123, &[]).unwrap());
        let ce = w.1.crc_end;
        // A listen-only receiver sees the active error flag as a form error at the ACK delimiter.
        let r = resolve(&[tx(&w, true)], &[rx(false, false)]);
        assert_eq!(r.tx, vec![err(L::Acknowledge, ce + 1, false)]);
        // Its own passive flag overlaps the transmitter's active flag.
        assert_eq!(
            r.rx,
            vec![PartOutcome::Error {
                code: L::Form,
                at: ce + 2,
                dominant_after_flag: false,
                dominant_in_passive_flag: true,
                arbitration_stuff_exception: false,
            }]
        );
        assert!(!r.observer_ok && !r.acked);
        // Flag ce+2..=ce+7, delimiter ce+8..=ce+15.
        assert_eq!(r.end, ce + 16);
        assert_eq!(r.last_dominant_end, ce + 8);
    }

    #[test]
    fn lone_passive_transmitter_ack_error_frame_still_valid_for_listeners() {
        let w = wire_bits(&Frame::standard(0x123, &[]).unwrap());
        let ce = w.1.crc_end;
        let r = resolve(&[tx(&w, false)], &[rx(false, false)]);
        assert_eq!(r.tx, vec![err(L::Acknowledge, ce + 1, false)]);
        assert_eq!(r.rx, vec![PartOutcome::Ok { done: ce + 10 }]);
        assert!(r.observer_ok);
        // Passive flag ce+2..=ce+7 (recessive), delimiter ce+8..=ce+15.
        assert_eq!(r.end, ce + 16);
    }

    #[test]
    fn crc_error_at_one_receiver() {
        let w = wire_bits(&Frame::standard(0x321, &[0xAA]).unwrap());
        let ce = w.1.crc_end;
        let mut bad = rx(true, true);
        bad.faults.push(RxFault::Crc);
        let r = resolve(&[tx(&w, true)], &[bad, rx(true, true)]);
        // The other receiver acknowledged; the bad one flags from EOF bit 1 (ce+3).
        assert!(r.acked);
        assert_eq!(
            r.rx[0],
            err(L::Crc, ce + 2, true),
            "others' echo flags follow its own"
        );
        assert_eq!(r.rx[1], err(L::Form, ce + 3, false));
        assert_eq!(r.tx[0], err(L::BitRecessive, ce + 3, false));
        // Flags ce+3..=ce+9 (6 + 1 echo), delimiter ce+10..=ce+17.
        assert_eq!(r.last_dominant_end, ce + 10);
        assert_eq!(r.end, ce + 18);
    }

    #[test]
    fn transmitter_bit_error_gives_receivers_a_stuff_error() {
        let w = wire_bits(&Frame::standard(0x7F0, &[0x0F, 0xF0]).unwrap());
        let mut t = tx(&w, true);
        let at = w.1.arbitration_end + 2;
        t.faults.push(TxFault::Bit(at));
        let r = resolve(&[t], &[rx(true, true)]);
        assert!(matches!(r.tx[0], PartOutcome::Error { at: a, .. } if a == at));
        match r.rx[0] {
            PartOutcome::Error {
                code: L::Stuff,
                at: a,
                ..
            } => assert!(a > at && a <= at + 6),
            other => panic!("{other:?}"),
        }
        assert!(r.end <= at + 1 + 12 + 8);
    }

    #[test]
    fn collision_with_same_arbitration_field() {
        // Same identifier, different data: the one sending recessive first gets a bit error.
        let a = wire_bits(&Frame::standard(0x100, &[0x01]).unwrap());
        let b = wire_bits(&Frame::standard(0x100, &[0x00]).unwrap());
        let r = resolve(&[tx(&a, true), tx(&b, true)], &[rx(true, true)]);
        assert_eq!(r.reference, 1);
        assert!(matches!(
            r.tx[0],
            PartOutcome::Error {
                code: L::BitRecessive,
                ..
            }
        ));
        assert!(matches!(
            r.tx[1],
            PartOutcome::Error {
                code: L::BitRecessive,
                ..
            }
        ));
        // If the loser is error-passive, the other frame survives.
        let r = resolve(&[tx(&a, false), tx(&b, true)], &[rx(true, true)]);
        assert!(matches!(
            r.tx[0],
            PartOutcome::Error {
                code: L::BitRecessive,
                ..
            }
        ));
        assert!(matches!(r.tx[1], PartOutcome::Ok { .. }));
        assert!(matches!(r.rx[0], PartOutcome::Ok { .. }));
        // Identical frames: both succeed.
        let c = wire_bits(&Frame::standard(0x100, &[0x01]).unwrap());
        let r = resolve(&[tx(&a, true), tx(&c, true)], &[rx(true, true)]);
        assert!(r.tx.iter().all(|o| matches!(o, PartOutcome::Ok { .. })));
    }

    #[test]
    fn form_error_in_last_but_one_eof_bit_leaves_other_receivers_with_the_frame() {
        let w = wire_bits(&Frame::standard(0x55, &[1]).unwrap());
        let ce = w.1.crc_end;
        let mut bad = rx(true, true);
        bad.faults.push(RxFault::Form(ce + 8));
        let r = resolve(&[tx(&w, true)], &[bad, rx(true, true)]);
        assert_eq!(
            r.rx[1],
            PartOutcome::Ok { done: ce + 10 },
            "a dominant last EOF bit is an overload condition"
        );
        assert!(
            matches!(r.tx[0], PartOutcome::Error { code: L::BitRecessive, at, .. } if at == ce + 9)
        );
    }

    /// A lone active transmitter with a listen-only receiver: acknowledge error at ce+1,
    /// flag ce+2..=ce+7, delimiter bit n at ce+8+n.
    #[test]
    fn dominant_error_delimiter_bit_is_a_form_error_and_a_new_flag() {
        let w = wire_bits(&Frame::standard(0x123, &[]).unwrap());
        let ce = w.1.crc_end;
        let wf = WireFaults {
            delimiter: Some(2),
            ..WireFaults::default()
        };
        let r = resolve_with(&[tx(&w, true)], &[rx(false, false)], wf);
        assert_eq!(r.tx, vec![err(L::Acknowledge, ce + 1, false)]);
        // The wire is dominant at ce+10; the transmitter's new flag is ce+11..=ce+16, its
        // delimiter ce+17..=ce+24.
        assert!(!r.wire[(ce + 10) as usize]);
        assert!(r.wire[(ce + 8) as usize] && r.wire[(ce + 9) as usize]);
        assert!(r.wire[(ce + 11) as usize..=(ce + 16) as usize]
            .iter()
            .all(|&b| !b));
        assert_eq!(r.last_dominant_end, ce + 17);
        assert_eq!(r.end, ce + 25);
        assert_eq!(r.tx_penalties, vec![1], "rule 3: one more error flag");
        // The listen-only receiver: form error at ce+2, passive flag from ce+3 waiting for
        // 6 equal bits (5 dominant to ce+7, then recessive from ce+8): at ce+10 it is still
        // in its passive flag, not in a delimiter — no second error for it.
        assert!(r.rx_more_errors.is_empty());
        assert!(r.missed.is_empty());
    }

    #[test]
    fn dominant_last_delimiter_bit_is_an_overload_frame() {
        let w = wire_bits(&Frame::standard(0x123, &[]).unwrap());
        let ce = w.1.crc_end;
        let mut t = tx(&w, true);
        t.faults.push(TxFault::Delimiter(7));
        let r = resolve(&[t], &[rx(false, false)]);
        // Delimiter bit 7 misread at ce+15: overload flag ce+16..=ce+21, delimiter
        // ce+22..=ce+29; no counter change for the transmitter.
        assert_eq!(r.end, ce + 30);
        assert_eq!(r.last_dominant_end, ce + 22);
        assert!(r.tx_penalties.is_empty());
        // The listen-only receiver lags: its passive flag (form error at ce+2) ends with
        // six recessive bits ce+8..=ce+13, its delimiter starts at ce+14, so the overload
        // flag at ce+16 is at its delimiter bit 2: a form error (rule 1).
        assert_eq!(r.rx_more_errors, vec![vec![(L::Form, ce + 16, false)]]);
    }

    #[test]
    fn a_delimiter_fault_without_a_delimiter_is_missed() {
        let w = wire_bits(&Frame::standard(0x123, &[4]).unwrap());
        let mut t = tx(&w, true);
        t.faults.push(TxFault::Delimiter(3));
        let wf = WireFaults {
            delimiter: Some(5),
            ..WireFaults::default()
        };
        let r = resolve_with(&[t], &[rx(true, true)], wf);
        assert_eq!(r.tx, vec![PartOutcome::Ok { done: w.1.total }]);
        assert_eq!(
            r.missed,
            vec![
                Missed::Tx(0, Aim::Delimiter(3)),
                Missed::Bus(Aim::Delimiter(5))
            ]
        );
    }

    #[test]
    fn a_receiver_misreading_intermission_bit_1_starts_an_overload_frame() {
        let w = wire_bits(&Frame::standard(0x123, &[4]).unwrap());
        let ce = w.1.crc_end;
        let mut r0 = rx(true, true);
        r0.faults.push(RxFault::Intermission(1));
        let r = resolve(&[tx(&w, true)], &[r0, rx(true, true)]);
        // EOF ends at ce+9; intermission bit 1 is ce+11: overload flag ce+12..=ce+17, the
        // others read it at their intermission bit 2 (no overload: a start of frame, not
        // played) — they are done; delimiter ce+18..=ce+25.
        assert!(r
            .tx
            .iter()
            .chain(&r.rx)
            .all(|o| matches!(o, PartOutcome::Ok { .. })));
        assert_eq!(r.last_dominant_end, ce + 18);
        assert_eq!(r.end, ce + 26);
        assert!(r.missed.is_empty());
    }
}
