//! The firmware's `defmt` log: read from its RTT up-channel in emulated RAM, as a debug
//! probe reads it, and decoded with the `.defmt` table of its ELF.
//!
//! RTT (SEGGER's Real-Time Transfer) is a control block in the target's RAM, found by the
//! symbol `_SEGGER_RTT`: a 16-byte identifier (`"SEGGER RTT"`), the number of up and down
//! channels, then one descriptor per up-channel — name pointer, buffer pointer, buffer
//! size, write offset, read offset, flags, six 32-bit words. The firmware (`defmt-rtt`)
//! writes at the write offset; the host reads from the read offset up to it and then
//! stores the new read offset, which frees the space. `defmt-rtt` writes its frames,
//! rzCOBS-encoded, to up-channel 0; in its default non-blocking mode it drops what does
//! not fit, so the harness drains the channel every co-simulation step.

use defmt_decoder::{DecodeError, Table};

/// The control block's identifier.
const RTT_ID: &[u8; 10] = b"SEGGER RTT";
/// Offset of up-channel 0's descriptor in the control block.
const UP0: u32 = 24;
/// Largest buffer the reader accepts (a larger size means a corrupt control block).
const MAX_BUFFER: u32 = 1 << 20;

/// Where the firmware's RTT control block is and what was read from it.
#[derive(Debug, Clone, Default)]
pub struct Rtt {
    /// Address of `_SEGGER_RTT`.
    pub control_block: u32,
    /// Bytes read from up-channel 0, in order.
    pub bytes: Vec<u8>,
    /// Set when the control block was found invalid after the firmware set it up.
    pub error: Option<String>,
}

impl Rtt {
    /// A reader of the control block at `control_block`.
    pub fn new(control_block: u32) -> Self {
        Rtt {
            control_block,
            ..Rtt::default()
        }
    }

    /// Reads what up-channel 0 holds and advances its read offset, through `read` and
    /// `write` (target memory). Before the start-up code has initialised the control
    /// block (no identifier yet) there is nothing to read.
    pub fn drain(
        &mut self,
        read: impl Fn(u32, usize) -> Option<Vec<u8>>,
        mut write: impl FnMut(u32, &[u8]) -> bool,
    ) {
        if self.error.is_some() {
            return;
        }
        let Some(block) = read(self.control_block, (UP0 + 24) as usize) else {
            self.error = Some(format!(
                "_SEGGER_RTT at 0x{:08X} is not readable",
                self.control_block
            ));
            return;
        };
        if &block[..RTT_ID.len()] != RTT_ID {
            return;
        }
        let word =
            |o: u32| u32::from_le_bytes(block[o as usize..o as usize + 4].try_into().unwrap());
        let up_channels = word(16);
        let (buffer, size, wr, rd) = (word(UP0 + 4), word(UP0 + 8), word(UP0 + 12), word(UP0 + 16));
        if up_channels == 0 || size == 0 || size > MAX_BUFFER || wr >= size || rd >= size {
            self.error = Some(format!(
                "RTT up-channel 0 invalid: {up_channels} channels, buffer 0x{buffer:08X} size {size}, write {wr}, read {rd}"
            ));
            return;
        }
        if wr == rd {
            return;
        }
        // The data is [rd, wr) or, wrapped, [rd, size) then [0, wr).
        let mut runs = vec![(rd, if wr > rd { wr } else { size })];
        if wr < rd && wr > 0 {
            runs.push((0, wr));
        }
        for (from, to) in runs {
            match read(buffer + from, (to - from) as usize) {
                Some(b) => self.bytes.extend_from_slice(&b),
                None => {
                    self.error = Some(format!(
                        "RTT buffer 0x{buffer:08X}+{from}..{to} is not readable"
                    ));
                    return;
                }
            }
        }
        if !write(self.control_block + UP0 + 16, &wr.to_le_bytes()) {
            self.error = Some("RTT read offset is not writable".into());
        }
    }
}

/// One decoded `defmt` log line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LogLine {
    /// The firmware's timestamp, as its format shows it (empty without one).
    pub timestamp: String,
    /// `trace`, `debug`, `info`, `warn`, `error`, or empty for `println!`.
    pub level: String,
    /// The message.
    pub message: String,
}

impl std::fmt::Display for LogLine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} {:<5} {}",
            self.timestamp,
            self.level.to_uppercase(),
            self.message
        )
    }
}

/// Decodes `bytes` (the up-channel's stream) with `table`. A malformed frame becomes a
/// line saying so (the decoder skips to the next frame); an incomplete last frame is
/// left out.
pub fn decode(table: &Table, bytes: &[u8]) -> Vec<LogLine> {
    let mut decoder = table.new_stream_decoder();
    decoder.received(bytes);
    let mut lines = Vec::new();
    loop {
        match decoder.decode() {
            Ok(frame) => lines.push(LogLine {
                timestamp: frame
                    .display_timestamp()
                    .map_or(String::new(), |t| t.to_string()),
                level: frame
                    .level()
                    .map_or(String::new(), |l| l.as_str().to_string()),
                message: frame.display_message().to_string(),
            }),
            Err(DecodeError::UnexpectedEof) => break,
            Err(DecodeError::Malformed) => lines.push(LogLine {
                timestamp: String::new(),
                level: "error".into(),
                message: "(malformed defmt frame)".into(),
            }),
        }
    }
    lines
}
