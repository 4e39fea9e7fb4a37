//! The record of everything that happened on the simulated bus, and its candump form.
//!
//! Every frame attempt on the wire and every internal (loop-back) frame gives one
//! [`TraceRecord`]: time at SOF, frame, transmitters, injected faults, first error and what
//! each node saw. [`Trace::write_candump`] writes it in the `candump -l` log format
//! (`(seconds.micros) can0 123#DEADBEEF`), which python-can's `CanutilsLogReader` and
//! can-utils' `canplayer` read:
//!
//! - standard identifiers as 3 hex digits, extended ones as 8 (`1ABCDEF0#...`), data as
//!   upper-case hex pairs without separators (`123#` for DLC 0);
//! - a remote frame as `123#R`, followed by its DLC as one digit when it is not zero
//!   (`123#R4`), as can-utils prints it; python-can reads the digit after `R` as the DLC;
//! - the timestamp is the frame's SOF time since the bus started, seconds padded to 10
//!   digits like `candump -l` does;
//! - only frames that a listener would have accepted are written (a frame destroyed by an
//!   error frame never reaches a candump), and internal frames never are (they are not on
//!   the wire).
//!
//! Error frames are kept out of [`Trace::write_candump`], so that the output replays as plain
//! traffic. [`Trace::write_candump_with_errors`] adds one SocketCAN error frame per errored
//! attempt, as `candump -l` logs error frames of an interface with error reporting on:
//! identifier `CAN_ERR_FLAG | CAN_ERR_PROT | CAN_ERR_BUSERROR` (plus `CAN_ERR_ACK` for an
//! acknowledge error) as 8 hex digits, 8 data bytes with the protocol error type in byte 2
//! and its location in byte 3 (`linux/can/error.h`), e.g. `200000A8#0000801900000000`.

use std::io::{self, Write};

use super::bits::FrameBits;
use super::bus::NodeId;
use super::inject::{Fault, FaultError};
use super::node::TxResult;
use twocan_core::error::LastErrorCode;
use twocan_core::frame::Frame;

/// What one node saw of a frame attempt.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeOutcome {
    /// The node was a transmitter (or lost arbitration); how its attempt ended.
    Transmitted(TxResult),
    /// The node received the frame correctly.
    Received,
    /// The node detected an error while receiving.
    ReceiveError {
        /// The error it detected.
        code: LastErrorCode,
        /// It read a dominant bit right after its error flag (ISO 11898-1 rule 2).
        dominant_after_flag: bool,
    },
}

/// One node's part in a frame attempt.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NodeReport {
    /// The node.
    pub node: NodeId,
    /// What it saw.
    pub outcome: NodeOutcome,
    /// The wire bit (from SOF) at which it detected its error, if it did.
    pub error_bit: Option<u32>,
}

/// The first error of a frame attempt.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ErrorInfo {
    /// The node that detected it (if several did at the same bit: a transmitter before
    /// receivers, then attach order).
    pub node: NodeId,
    /// Whether that node was a transmitter of the frame.
    pub transmitter: bool,
    /// The error.
    pub code: LastErrorCode,
    /// The wire bit (from SOF) at which it was detected.
    pub bit: u32,
}

/// One frame attempt (or internal frame) in the trace.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceRecord {
    /// Number of the attempt among wire frame attempts (0 = first SOF on the bus); for an
    /// internal frame, the number of wire attempts that came before it.
    pub seq: u64,
    /// `true` for an internal frame that never reached the wire.
    pub internal: bool,
    /// Bus time of the SOF bit, in bit times.
    pub sof: u64,
    /// Bus time after the intermission: the earliest next SOF.
    pub end: u64,
    /// The frame on the wire (with several transmitters of the same identifier, the one the
    /// receivers followed: the first to send a dominant bit where the others differ).
    pub frame: Frame,
    /// The frame's layout on the wire (for an internal frame, the layout it would have had).
    pub bits: FrameBits,
    /// The node(s) that sent it after winning arbitration.
    pub transmitters: Vec<NodeId>,
    /// Nodes that wanted to send and lost arbitration.
    pub arbitration_losers: Vec<NodeId>,
    /// Faults injected into this attempt.
    pub faults: Vec<Fault>,
    /// Faults meant for this attempt and refused: they cannot happen in this frame (see
    /// [`Fault`]); none of them was applied.
    pub refused: Vec<(Fault, FaultError)>,
    /// The first error detected, if any.
    pub first_error: Option<ErrorInfo>,
    /// Some receiver drove the ACK slot dominant.
    pub acked: bool,
    /// A fault-free listener would have accepted the frame (it appears in a candump).
    pub delivered: bool,
    /// What each involved node saw, transmitters first, then receivers, in attach order.
    pub reports: Vec<NodeReport>,
}

impl TraceRecord {
    /// Bit times the attempt occupied, intermission included.
    pub fn duration(&self) -> u64 {
        self.end - self.sof
    }

    /// No node detected an error.
    pub fn is_error_free(&self) -> bool {
        self.first_error.is_none()
    }

    /// What `node` saw, if it took part.
    pub fn outcome_of(&self, node: NodeId) -> Option<NodeOutcome> {
        self.reports
            .iter()
            .find(|r| r.node == node)
            .map(|r| r.outcome)
    }
}

/// The list of everything that happened on a bus (see the [module docs](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    bit_rate: u32,
    records: Vec<TraceRecord>,
}

/// SocketCAN error-frame flag in the identifier.
pub const CAN_ERR_FLAG: u32 = 0x2000_0000;
/// SocketCAN error class: protocol violation (details in data bytes 2 and 3).
pub const CAN_ERR_PROT: u32 = 0x0000_0008;
/// SocketCAN error class: no acknowledge on transmission.
pub const CAN_ERR_ACK: u32 = 0x0000_0020;
/// SocketCAN error class: bus error.
pub const CAN_ERR_BUSERROR: u32 = 0x0000_0080;

impl Trace {
    /// An empty trace for a bus running at `bit_rate` bit/s (used for microseconds).
    pub fn new(bit_rate: u32) -> Self {
        Trace {
            bit_rate: bit_rate.max(1),
            records: Vec::new(),
        }
    }

    /// The records, in time order.
    pub fn records(&self) -> &[TraceRecord] {
        &self.records
    }

    /// Number of records.
    pub fn len(&self) -> usize {
        self.records.len()
    }

    /// Whether there is no record.
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// Forgets all records.
    pub fn clear(&mut self) {
        self.records.clear();
    }

    pub(crate) fn push(&mut self, record: TraceRecord) {
        self.records.push(record);
    }

    /// Microseconds for `bits` bit times at this trace's bit rate (rounded down).
    pub fn micros(&self, bits: u64) -> u64 {
        bits_to_micros(bits, self.bit_rate)
    }

    /// Writes the delivered wire frames in `candump -l` format (see the [module docs](self)).
    pub fn write_candump(&self, w: &mut impl Write, interface: &str) -> io::Result<()> {
        self.write(w, interface, false)
    }

    /// Like [`Trace::write_candump`], plus one SocketCAN error frame per errored attempt at
    /// the time its first error was detected.
    pub fn write_candump_with_errors(&self, w: &mut impl Write, interface: &str) -> io::Result<()> {
        self.write(w, interface, true)
    }

    /// The candump text as a `String` (frames only).
    pub fn candump_string(&self, interface: &str) -> String {
        let mut out = Vec::new();
        // Writing into a Vec cannot fail.
        let _ = self.write_candump(&mut out, interface);
        String::from_utf8_lossy(&out).into_owned()
    }

    fn write(&self, w: &mut impl Write, interface: &str, errors: bool) -> io::Result<()> {
        let mut sink = CandumpWriter::new(w, interface, self.bit_rate);
        sink.error_frames = errors;
        for r in &self.records {
            sink.write_record(r)?;
        }
        Ok(())
    }
}

/// Streams trace records to any [`Write`] target in `candump -l` form, so that a long run
/// keeps only the records not yet written: call [`CandumpWriter::drain`] now and then (it
/// writes the bus's records so far and clears them) instead of writing the whole
/// [`Trace`] at the end.
///
/// ```
/// use twocan_sim::{trace::CandumpWriter, Bus, SimNode};
/// use twocan_core::Frame;
///
/// let mut bus = Bus::new(500_000).unwrap();
/// let a = SimNode::new().shared();
/// bus.attach("a", a.clone());
/// bus.attach("b", SimNode::new().shared());
/// let mut log = Vec::new();
/// let mut sink = CandumpWriter::new(&mut log, "can0", bus.bit_rate());
/// for i in 0..3u8 {
///     a.borrow_mut().send(Frame::standard(0x100 + u16::from(i), &[i]).unwrap());
///     bus.run_for(1_000);
///     sink.drain(bus.trace_mut()).unwrap(); // the trace is empty again
///     assert!(bus.trace().is_empty());
/// }
/// assert_eq!(sink.frames_written(), 3);
/// let text = String::from_utf8(log).unwrap();
/// assert!(text.lines().nth(2).unwrap().ends_with(" can0 102#02"));
/// ```
#[derive(Debug)]
pub struct CandumpWriter<'a, W: Write> {
    out: W,
    interface: &'a str,
    bit_rate: u32,
    /// Also write one SocketCAN error frame per errored attempt (as
    /// [`Trace::write_candump_with_errors`]); off by default.
    pub error_frames: bool,
    frames: u64,
}

impl<'a, W: Write> CandumpWriter<'a, W> {
    /// A writer of `interface` lines for a bus running at `bit_rate` bit/s.
    pub fn new(out: W, interface: &'a str, bit_rate: u32) -> Self {
        CandumpWriter {
            out,
            interface,
            bit_rate: bit_rate.max(1),
            error_frames: false,
            frames: 0,
        }
    }

    /// Writes one record: a line if it was delivered on the wire (none for an internal
    /// frame), and its error frame when [`CandumpWriter::error_frames`] is on.
    pub fn write_record(&mut self, r: &TraceRecord) -> io::Result<()> {
        if r.internal {
            return Ok(());
        }
        if r.delivered {
            let us = bits_to_micros(r.sof, self.bit_rate);
            writeln!(
                self.out,
                "{} {} {}",
                timestamp(us),
                self.interface,
                candump_frame(&r.frame)
            )?;
            self.frames += 1;
        }
        if self.error_frames {
            if let Some(e) = r.first_error {
                let us = bits_to_micros(r.sof + u64::from(e.bit), self.bit_rate);
                writeln!(
                    self.out,
                    "{} {} {}",
                    timestamp(us),
                    self.interface,
                    candump_error(&e, &r.bits)
                )?;
            }
        }
        Ok(())
    }

    /// Writes every record of `trace` and clears it, so that its memory stays bounded by
    /// what happened since the last call. On a write error the trace is left as it was
    /// (a retry may write again the lines that did get out).
    pub fn drain(&mut self, trace: &mut Trace) -> io::Result<()> {
        for r in &trace.records {
            self.write_record(r)?;
        }
        trace.clear();
        Ok(())
    }

    /// Frame lines written so far (error frames not counted).
    pub fn frames_written(&self) -> u64 {
        self.frames
    }

    /// Flushes the target.
    pub fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    /// The target, flushed or not.
    pub fn into_inner(self) -> W {
        self.out
    }
}

/// Microseconds for `bits` bit times at `bit_rate` bit/s (rounded down; 0 bit/s counts as 1).
pub fn bits_to_micros(bits: u64, bit_rate: u32) -> u64 {
    let us = u128::from(bits) * 1_000_000 / u128::from(bit_rate.max(1));
    u64::try_from(us).unwrap_or(u64::MAX)
}

fn timestamp(us: u64) -> String {
    format!("({:010}.{:06})", us / 1_000_000, us % 1_000_000)
}

/// A frame in candump's compact form: `123#DEADBEEF`, `1ABCDEF0#00`, `123#R`, `123#R4`.
/// A DLC code of 9..=15 (eight bytes) follows as `_` and one hex digit, candump's
/// form for a classical frame's raw DLC: `123#0102030405060708_C`, `123#R8_F`.
pub fn candump_frame(frame: &Frame) -> String {
    let mut s = if frame.is_extended() {
        format!("{:08X}#", frame.raw_id())
    } else {
        format!("{:03X}#", frame.raw_id())
    };
    if frame.is_remote() {
        s.push('R');
        if frame.len_from_dlc() != 0 {
            s.push_str(&frame.len_from_dlc().to_string());
        }
    } else {
        for b in frame.data() {
            s.push_str(&format!("{b:02X}"));
        }
    }
    if frame.dlc() > twocan_core::frame::MAX_DLC {
        s.push_str(&format!("_{:X}", frame.dlc()));
    }
    s
}

/// Protocol error type bits of SocketCAN error-frame data byte 2.
const PROT_FORM: u8 = 0x02;
const PROT_STUFF: u8 = 0x04;
const PROT_BIT0: u8 = 0x08;
const PROT_BIT1: u8 = 0x10;
const PROT_TX: u8 = 0x80;

/// SocketCAN location (data byte 3) of wire bit `bit` of a frame laid out as `b`.
fn location(bit: u32, b: &FrameBits) -> u8 {
    match bit {
        0 => 0x03,                          // SOF
        x if x < b.arbitration_end => 0x02, // identifier
        x if x < b.control_end => 0x0B,     // control field (DLC)
        x if x < b.data_end => 0x0A,        // data
        x if x < b.crc_end => 0x08,         // CRC sequence
        x if x == b.crc_end => 0x18,        // CRC delimiter
        x if x == b.crc_end + 1 => 0x19,    // ACK slot
        x if x == b.crc_end + 2 => 0x1B,    // ACK delimiter
        x if x <= b.crc_end + 9 => 0x1A,    // EOF
        _ => 0x12,                          // intermission
    }
}

fn candump_error(e: &ErrorInfo, bits: &FrameBits) -> String {
    let mut id = CAN_ERR_FLAG | CAN_ERR_PROT | CAN_ERR_BUSERROR;
    let mut data = [0u8; 8];
    data[2] = match e.code {
        LastErrorCode::Form => PROT_FORM,
        LastErrorCode::Stuff => PROT_STUFF,
        LastErrorCode::BitDominant => PROT_BIT0,
        LastErrorCode::BitRecessive => PROT_BIT1,
        LastErrorCode::Acknowledge => {
            id |= CAN_ERR_ACK;
            0
        }
        LastErrorCode::Crc | LastErrorCode::None => 0,
    };
    if e.transmitter {
        data[2] |= PROT_TX;
    }
    data[3] = if e.code == LastErrorCode::Crc {
        0x08
    } else {
        location(e.bit, bits)
    };
    let mut s = format!("{id:08X}#");
    for b in data {
        s.push_str(&format!("{b:02X}"));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_forms() {
        assert_eq!(
            candump_frame(&Frame::standard(0x123, &[0xDE, 0xAD, 0xBE, 0xEF]).unwrap()),
            "123#DEADBEEF"
        );
        assert_eq!(candump_frame(&Frame::standard(0x7, &[]).unwrap()), "007#");
        assert_eq!(
            candump_frame(&Frame::extended(0x1ABC_DEF0, &[0]).unwrap()),
            "1ABCDEF0#00"
        );
        assert_eq!(
            candump_frame(&Frame::extended(0x5, &[]).unwrap()),
            "00000005#"
        );
        assert_eq!(
            candump_frame(&Frame::remote(0x123, false, 0).unwrap()),
            "123#R"
        );
        assert_eq!(
            candump_frame(&Frame::remote(0x123, false, 4).unwrap()),
            "123#R4"
        );
        assert_eq!(
            candump_frame(&Frame::remote(0x1234, true, 8).unwrap()),
            "00001234#R8"
        );
        let id = twocan_core::frame::standard_id(0x123).unwrap();
        let f = Frame::with_dlc(id, &[1, 2, 3, 4, 5, 6, 7, 8], 12).unwrap();
        assert_eq!(candump_frame(&f), "123#0102030405060708_C");
        let mut r = Frame::remote(0x123, false, 8).unwrap();
        r.set_dlc(15).unwrap();
        assert_eq!(candump_frame(&r), "123#R8_F");
    }

    #[test]
    fn timestamps() {
        assert_eq!(timestamp(0), "(0000000000.000000)");
        assert_eq!(timestamp(1_234_567), "(0000000001.234567)");
        assert_eq!(bits_to_micros(3, 500_000), 6);
        assert_eq!(bits_to_micros(1, 3), 333_333);
        assert_eq!(bits_to_micros(u64::MAX, 1), u64::MAX);
    }

    #[test]
    fn error_frame_form() {
        let b = super::super::bits::frame_bits(&Frame::standard(1, &[]).unwrap());
        let ack = ErrorInfo {
            node: NodeId::from_index(0),
            transmitter: true,
            code: LastErrorCode::Acknowledge,
            bit: b.crc_end + 1,
        };
        assert_eq!(candump_error(&ack, &b), "200000A8#0000801900000000");
        let crc = ErrorInfo {
            node: NodeId::from_index(1),
            transmitter: false,
            code: LastErrorCode::Crc,
            bit: b.crc_end + 2,
        };
        assert_eq!(candump_error(&crc, &b), "20000088#0000000800000000");
    }
}
