//! The two receive FIFOs of three messages and their output mailboxes (RM0410 40.7.3
//! "Reception handling", 40.7.5 "Message storage"; notes "The bxCAN Reception Handling").
//!
//! Rules modelled:
//! - `FMP` is the number of messages in the FIFO; the output mailbox (`RIxR`, `RDTxR`,
//!   `RDLxR`, `RDHxR`) shows the oldest one.
//! - `RFOM` (set by software) releases the output mailbox; it has no effect on an empty
//!   FIFO and reads 0 (the release is immediate).
//! - `FULL` is set when a third message is stored; `FOVR` when a valid message arrives
//!   while three are pending. Both are cleared by software writing 1 (`rc_w1`), not by
//!   releasing a message.
//! - Overrun with `MCR.RFLM = 0`: the last (newest) stored message is overwritten by the
//!   new one; with `RFLM = 1` the new message is discarded.
//! - An empty FIFO's output mailbox reads 0 (RM0410 leaves it undefined).

use super::std::collections::VecDeque;

use twocan_core::Frame;

use crate::regs::{rdtxr, rfxr, rixr, RX_FIFO_DEPTH};

/// A message as stored in a FIFO: the four output mailbox registers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct RxMessage {
    regs: [u32; 4],
}

impl RxMessage {
    /// Encodes a received frame with its filter match index and time stamp.
    pub(crate) fn new(frame: &Frame, fmi: u8, time: u16) -> Self {
        let raw = frame.raw_id();
        let mut rir = if frame.is_extended() {
            rixr::STID.val(raw >> 18) | rixr::EXID.val(raw) | rixr::IDE
        } else {
            rixr::STID.val(raw)
        };
        if frame.is_remote() {
            rir |= rixr::RTR;
        }
        let rdtr = rdtxr::DLC.val(frame.dlc() as u32)
            | rdtxr::FMI.val(fmi as u32)
            | rdtxr::TIME.val(time as u32);
        let d = frame.data_padded();
        RxMessage {
            regs: [
                rir,
                rdtr,
                u32::from_le_bytes([d[0], d[1], d[2], d[3]]),
                u32::from_le_bytes([d[4], d[5], d[6], d[7]]),
            ],
        }
    }

    /// The frame, filter match index and time stamp held by the message.
    pub(crate) fn decode(&self) -> Option<(Frame, u8, u16)> {
        let [rir, rdtr, rdlr, rdhr] = self.regs;
        let ide = rir & rixr::IDE != 0;
        let raw = if ide {
            (rixr::STID.get(rir) << 18) | rixr::EXID.get(rir)
        } else {
            rixr::STID.get(rir)
        };
        let mut data = [0u8; 8];
        data[..4].copy_from_slice(&rdlr.to_le_bytes());
        data[4..].copy_from_slice(&rdhr.to_le_bytes());
        let dlc = rdtxr::DLC.get(rdtr) as u8;
        let frame = Frame::from_registers(raw, ide, rir & rixr::RTR != 0, dlc, data).ok()?;
        Some((
            frame,
            rdtxr::FMI.get(rdtr) as u8,
            rdtxr::TIME.get(rdtr) as u16,
        ))
    }
}

/// What happened to a message offered to a FIFO.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum StoreOutcome {
    /// Stored in a free place.
    Stored,
    /// Overrun, FIFO not locked: replaced the newest stored message.
    OverwroteNewest,
    /// Overrun, FIFO locked: discarded.
    Discarded,
}

/// One receive FIFO.
#[derive(Debug, Clone, Default)]
pub(crate) struct RxFifo {
    messages: VecDeque<RxMessage>,
    full: bool,
    fovr: bool,
    overruns: u64,
}

impl RxFifo {
    /// An empty FIFO (`RFxR` = 0).
    pub(crate) fn new() -> Self {
        Self::default()
    }

    /// Number of pending messages (`FMP`).
    pub(crate) fn depth(&self) -> usize {
        self.messages.len()
    }

    /// Messages lost by overrun since reset.
    pub(crate) fn overruns(&self) -> u64 {
        self.overruns
    }

    /// The pending messages, oldest first.
    pub(crate) fn messages(&self) -> impl Iterator<Item = &RxMessage> {
        self.messages.iter()
    }

    /// Stores a valid message (`locked` = `MCR.RFLM`).
    pub(crate) fn store(&mut self, msg: RxMessage, locked: bool) -> StoreOutcome {
        if self.messages.len() < RX_FIFO_DEPTH {
            self.messages.push_back(msg);
            if self.messages.len() == RX_FIFO_DEPTH {
                self.full = true;
            }
            return StoreOutcome::Stored;
        }
        self.fovr = true;
        self.overruns = self.overruns.saturating_add(1);
        if locked {
            StoreOutcome::Discarded
        } else {
            if let Some(newest) = self.messages.back_mut() {
                *newest = msg;
            }
            StoreOutcome::OverwroteNewest
        }
    }

    /// `CAN_RFxR` as read.
    pub(crate) fn rfr(&self) -> u32 {
        let mut v = rfxr::FMP.val(self.messages.len() as u32);
        if self.full {
            v |= rfxr::FULL;
        }
        if self.fovr {
            v |= rfxr::FOVR;
        }
        v
    }

    /// A software write to `CAN_RFxR`.
    pub(crate) fn write_rfr(&mut self, value: u32) {
        if value & rfxr::FULL != 0 {
            self.full = false;
        }
        if value & rfxr::FOVR != 0 {
            self.fovr = false;
        }
        if value & rfxr::RFOM != 0 {
            self.messages.pop_front();
        }
    }

    /// Register `reg` (0 = RIxR, 1 = RDTxR, 2 = RDLxR, 3 = RDHxR) of the output mailbox.
    pub(crate) fn output(&self, reg: usize) -> u32 {
        match self.messages.front() {
            Some(m) if reg < 4 => m.regs[reg],
            _ => 0,
        }
    }
}
