//! The Rx FIFO ("Rx FIFO structure", "Rx FIFO" in the functional description, IFLAG1
//! bits 5–7, RXFIR).
//!
//! With MCR\[RFEN\] = 1 the storage of MB0–MB5 is the FIFO engine: six frames deep, the
//! oldest presented at the MB0 window (0x80–0x8F), 0x90–0xDF reserved to the engine.
//! - IFLAG1\[BUF5I\] "frames available" is set while the FIFO holds a frame; writing 1 to it
//!   releases the output, and the next frame (if any) is presented.
//! - IFLAG1\[BUF6I\] "warning" is set when the number of unread frames goes from 4 to 5.
//! - IFLAG1\[BUF7I\] "overflow" is set when a frame that passed the filters is lost because
//!   the FIFO already holds six frames.
//! - RXFIR\[IDHIT\] is the filter that accepted the frame at the output.

use super::std::collections::VecDeque;
use twocan_core::frame::Frame;

use crate::regs::{iflag1, rxfir, RX_FIFO_DEPTH};

use super::codec;
use super::state::State;

/// A frame stored in the FIFO.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct FifoEntry {
    pub frame: Frame,
    pub stamp: u16,
    pub idhit: u16,
}

/// The FIFO engine.
#[derive(Debug, Default)]
pub(crate) struct RxFifo {
    entries: VecDeque<FifoEntry>,
    /// The last frame released: the output window keeps showing it once the FIFO is empty.
    stale: Option<FifoEntry>,
    /// Frames lost to overflow.
    pub overflows: u64,
}

impl RxFifo {
    pub fn new() -> Self {
        RxFifo::default()
    }

    /// Empties the FIFO (RFEN change, soft reset).
    pub fn clear(&mut self) {
        self.entries.clear();
        self.stale = None;
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_full(&self) -> bool {
        self.entries.len() >= RX_FIFO_DEPTH
    }

    /// The frame the output window shows.
    pub fn output(&self) -> Option<&FifoEntry> {
        self.entries.front().or(self.stale.as_ref())
    }
}

impl State {
    /// Stores a frame that passed filter `idhit`, or counts it lost if the FIFO is full.
    pub fn fifo_store(&mut self, frame: &Frame, stamp: u16, idhit: u16) {
        if self.fifo.is_full() {
            self.fifo.overflows += 1;
            self.iflag |= u64::from(iflag1::BUF7I);
            return;
        }
        self.fifo.entries.push_back(FifoEntry {
            frame: *frame,
            stamp,
            idhit,
        });
        if self.fifo.entries.len() == 5 {
            self.iflag |= u64::from(iflag1::BUF6I);
        }
    }

    /// Software wrote 1 to IFLAG1\[BUF5I\]: the output is released.
    pub fn fifo_pop(&mut self) {
        if let Some(e) = self.fifo.entries.pop_front() {
            self.fifo.stale = Some(e);
        }
    }

    /// Word `w` (0..4) of the output window.
    pub fn fifo_output_word(&self, w: usize) -> u32 {
        match self.fifo.output() {
            Some(e) => codec::encode(&e.frame, e.stamp, 0, 0)[w],
            None => 0,
        }
    }

    /// RXFIR as read.
    pub fn rxfir_value(&self) -> u32 {
        self.fifo
            .output()
            .map_or(0, |e| rxfir::IDHIT.val(u32::from(e.idhit)))
    }
}
