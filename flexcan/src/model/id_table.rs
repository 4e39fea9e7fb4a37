//! Rx FIFO ID filter table matching ("Rx FIFO structure", MCR\[IDAM\], CTRL2\[RFFN\], RXIMR,
//! RXMGMASK and RXFGMASK field descriptions, table "Rx FIFO filter: possible structures").
//!
//! - The table holds 8 × (RFFN + 1) elements from MB6 on (element n at 0xE0 + 4·n); on
//!   the 16-MB Kinetis parts only 40 elements fit, elements beyond never match; on the
//!   64-MB RT1062 all 128 (RFFN = 0xF) fit, up to MB37.
//! - The first elements, as many as the message buffers the FIFO and table occupy
//!   (RFFN 0 → 8, 1 → 10, 2 → 12, 3 → 14, …, at most the module's MBs and at most 32:
//!   RFFN ≥ 0xC gives "elements 0–31"), are masked by the individual masks RXIMR\[n\]
//!   when MCR\[IRMQ\] = 1, by RXMGMASK when IRMQ = 0; the remaining elements are masked
//!   by RXFGMASK. Masks align bit for bit with the element ("in a perfect
//!   alignment"); a mask bit 1 means the bit is checked.
//! - Format A (IDAM = 0): RTR bit 31, IDE bit 30, RXIDA bits 29–1 (standard ID in 29–19;
//!   for a standard frame only bits 31–19 are compared). One filter per element.
//! - Format B (IDAM = 1): two filters per element, RTR/IDE/14-bit ID in each half
//!   (standard: the 11-bit ID in the top of the 14 bits; extended: the 14 MSBs of the ID).
//! - Format C (IDAM = 2): four filters per element, each 8 bits compared with the 8 MSBs
//!   of the identifier; remote frames are always accepted.
//! - Format D (IDAM = 3): all frames rejected.
//! - "If multiple filters match the incoming message ID, then the first matching IDAF found
//!   (lowest number) by the matching process is indicated" in RXFIR\[IDHIT\]; IDAF numbers
//!   count filters, so format B element n holds filters 2n, 2n+1 and format C 4n..4n+3.

use twocan_core::frame::Frame;

use crate::regs::mcr;

use super::access::RX_FIFO_FILTER_BASE;
use super::layout::{MB0, MB_BYTES};
use super::state::State;
use super::variant::Variant;

/// Word index of filter element 0 in the message-buffer RAM.
const TABLE_START_WORD: usize = (RX_FIFO_FILTER_BASE - MB0) / 4;

impl State {
    /// Elements that fit in this module's message-buffer RAM after MB5 (40 with 16 MBs,
    /// 232 with 64: every table size fits).
    fn table_capacity(&self) -> usize {
        (self.mbs() * MB_BYTES - (RX_FIFO_FILTER_BASE - MB0)) / 4
    }

    /// Number of filter elements in use.
    pub fn filter_elements(&self) -> usize {
        Variant::rx_fifo_filters(self.rffn()).min(self.table_capacity())
    }

    /// Number of leading elements under individual (or, with IRMQ = 0, RXMGMASK) masks.
    pub fn individually_masked_elements(&self) -> usize {
        self.variant.rx_fifo_individually_masked(self.rffn())
    }

    /// The value of filter element `n`.
    pub fn filter_element(&self, n: usize) -> u32 {
        self.ram[TABLE_START_WORD + n]
    }

    /// The mask applying to filter element `n`.
    pub fn filter_mask(&self, n: usize) -> u32 {
        if n < self.individually_masked_elements() {
            if self.irmq() {
                self.rximr[n]
            } else {
                self.rxmgmask
            }
        } else {
            self.rxfgmask
        }
    }

    /// The filter (IDAF number) that accepts `frame` into the FIFO, if any.
    pub fn fifo_match(&self, frame: &Frame) -> Option<u16> {
        let idam = mcr::IDAM.get(self.mcr);
        for n in 0..self.filter_elements() {
            let elem = self.filter_element(n);
            let mask = self.filter_mask(n);
            let hit = match idam {
                mcr::IDAM_FORMAT_A => match_a(frame, elem, mask).then_some(n),
                mcr::IDAM_FORMAT_B => (0..2)
                    .find(|&h| match_b(frame, elem, mask, h))
                    .map(|h| 2 * n + h),
                mcr::IDAM_FORMAT_C => (0..4)
                    .find(|&q| match_c(frame, elem, mask, q))
                    .map(|q| 4 * n + q),
                _ => return None,
            };
            if let Some(idaf) = hit {
                return Some(idaf as u16);
            }
        }
        None
    }
}

/// Compares under a mask: every bit the mask checks must be equal.
fn masked_equal(a: u32, b: u32, mask: u32) -> bool {
    (a ^ b) & mask == 0
}

fn match_a(frame: &Frame, elem: u32, mask: u32) -> bool {
    let ext = frame.is_extended();
    let mut word = if ext {
        frame.raw_id() << 1
    } else {
        frame.raw_id() << 19
    };
    if frame.is_remote() {
        word |= 1 << 31;
    }
    if ext {
        word |= 1 << 30;
    }
    let compared = if ext { 0xFFFF_FFFE } else { 0xFFF8_0000 };
    masked_equal(word, elem, mask & compared)
}

/// Half `h` (0: bits 31–16, 1: bits 15–0) of a format B element.
fn match_b(frame: &Frame, elem: u32, mask: u32, h: usize) -> bool {
    let shift = if h == 0 { 16 } else { 0 };
    let e = (elem >> shift) & 0xFFFF;
    let m = (mask >> shift) & 0xFFFF;
    let ext = frame.is_extended();
    let mut word = if ext {
        (frame.raw_id() >> 15) & 0x3FFF
    } else {
        frame.raw_id() << 3
    };
    if frame.is_remote() {
        word |= 1 << 15;
    }
    if ext {
        word |= 1 << 14;
    }
    let compared = if ext { 0xFFFF } else { 0xFFF8 };
    masked_equal(word, e, m & compared)
}

/// Slice `q` (0: bits 31–24 … 3: bits 7–0) of a format C element.
fn match_c(frame: &Frame, elem: u32, mask: u32, q: usize) -> bool {
    let shift = 24 - 8 * q as u32;
    let e = (elem >> shift) & 0xFF;
    let m = (mask >> shift) & 0xFF;
    let msbs = if frame.is_extended() {
        frame.raw_id() >> 21
    } else {
        frame.raw_id() >> 3
    };
    masked_equal(msbs & 0xFF, e, m)
}
