//! The filter block: `FMR`, `FM1R`, `FS1R`, `FFA1R`, `FA1R`, the banks `FiR1`/`FiR2`,
//! and acceptance filtering with the filter match index (RM0410 40.7.4 "Identifier
//! filtering", 40.9.4 "CAN filter registers"; notes "The bxCAN Identifier Filtering").
//!
//! Rules modelled:
//! - `FM1R`, `FS1R`, `FFA1R` are written only while `FMR.FINIT = 1`; a bank's `FiR1`/`FiR2`
//!   only while `FINIT = 1` or the bank is inactive (`FACTi = 0`); `FA1R` at any time.
//! - While `FINIT = 1` reception is deactivated: no frame is accepted (RM0410 40.4.1
//!   note "When FINIT=1, CAN reception is deactivated").
//! - The dual-CAN block (CAN1) splits its 28 banks at `CAN2SB`: CAN1 uses `0..CAN2SB`,
//!   CAN2 `CAN2SB..28` (28 gives every bank to CAN1, 0 every bank to CAN2; values above
//!   28 are taken as 28). A single-CAN block — CAN3's, or CAN1's on a single-CAN part
//!   such as the STM32F103 ([`super::part`]) — has 14 banks and no `CAN2SB` (reserved:
//!   writes ignored, reads its reset value 14; RM0008 §24.9.4).
//! - The block has as many banks as its part gives it: `FM1R`, `FS1R`, `FFA1R`, `FA1R`
//!   keep only the bits of existing banks (the others are reserved and read 0), and the
//!   bank registers `FiR1`/`FiR2` of a bank beyond the count read 0 and ignore writes.
//!   RM0008 §24.9.4 and RM0410 §40.9.4 list them only for `i < banks`; what silicon
//!   answers there is an assumption (docs/models.md).
//! - Filter numbers (FMI): each FIFO has its own numbering; the banks assigned to that
//!   FIFO contribute, in bank order, 1 (32-bit mask), 2 (32-bit list or 16-bit mask) or 4
//!   (16-bit list) numbers each, whether active or not. Numbering starts at the first
//!   bank of the controller (for CAN2 at `CAN2SB`) — an assumption: RM0410 does not
//!   say how CAN2 numbers its filters.
//! - When several filters match: a 32-bit filter before a 16-bit one, then identifier
//!   list before identifier mask, then the lower filter number. Matches in different
//!   FIFOs with equal scale and mode are ordered by bank number (RM0410 is silent).
//! - A frame that matches no active filter is dropped.
//! - 32-bit scale: the frame's side of the comparison is the identifier register layout
//!   `STID[10:0] EXID[17:0] IDE RTR 0` (RM0410 Figure "Filter bank scale configuration -
//!   register organization": bit 0 is shown as "0"), and all 32 bits are compared: a list
//!   entry with bit 0 set never matches, a mask filter that sets bit 0 in its mask
//!   matches only if its identifier has bit 0 clear (docs/models.md lists this as an
//!   assumption to check on silicon).

use core::ops::Range;

use twocan_core::Frame;

use crate::regs::{self, firx, fmr, FILTER_BANKS};

/// The reserved bits of `FMR` read as in its reset value.
const FMR_RESERVED: u32 = regs::fmr::RESET_VALUE & !(fmr::FINIT | fmr::CAN2SB.mask());

/// Which filter block a controller has, and which banks of it it uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Owner {
    /// CAN1 of a dual-CAN part: master of the dual block, banks `0..CAN2SB`.
    Master,
    /// CAN2: slave, banks `CAN2SB..28` of CAN1's block.
    Slave,
    /// The only user of its block: CAN3, or CAN1 of a single-CAN part (every bank).
    Single,
}

/// A frame accepted by a filter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Accepted {
    /// The FIFO the filter's bank is assigned to.
    pub fifo: usize,
    /// The filter match index within that FIFO's numbering.
    pub fmi: u8,
}

/// One filter bank block (CAN1's shared dual-CAN block, or CAN3's own).
#[derive(Debug, Clone)]
pub(crate) struct FilterBlock {
    /// `CAN2SB` exists (the block is shared by CAN1 and CAN2).
    dual: bool,
    /// Banks that exist: 14 or 28.
    nbanks: usize,
    finit: bool,
    can2sb: u32,
    fm1r: u32,
    fs1r: u32,
    ffa1r: u32,
    fa1r: u32,
    banks: [[u32; 2]; FILTER_BANKS],
    hits: [u64; FILTER_BANKS],
}

impl FilterBlock {
    /// The block at reset (`FMR` = 0x2A1C_0E01: FINIT = 1, CAN2SB = 14; all banks
    /// inactive, mask mode, 16-bit, FIFO 0). Bank registers reset to undefined values in
    /// RM0410; the model starts them at 0. `nbanks` (at most 28) banks exist; `dual`: the
    /// block has `CAN2SB` and is shared with CAN2.
    pub(crate) fn new(nbanks: usize, dual: bool) -> Self {
        FilterBlock {
            dual,
            nbanks: nbanks.min(FILTER_BANKS),
            finit: true,
            can2sb: fmr::CAN2SB.get(fmr::RESET_VALUE),
            fm1r: 0,
            fs1r: 0,
            ffa1r: 0,
            fa1r: 0,
            banks: [[0; 2]; FILTER_BANKS],
            hits: [0; FILTER_BANKS],
        }
    }

    fn nbanks(&self) -> usize {
        self.nbanks
    }

    fn bank_mask(&self) -> u32 {
        (1u32 << self.nbanks()) - 1
    }

    /// Matches counted per bank (the bank whose filter was selected).
    pub(crate) fn hits(&self) -> [u64; FILTER_BANKS] {
        self.hits
    }

    /// The banks `owner` uses.
    pub(crate) fn range(&self, owner: Owner) -> Range<usize> {
        let n = self.nbanks();
        let split = (self.can2sb as usize).min(n);
        match owner {
            Owner::Master => 0..split,
            Owner::Slave => split..n,
            Owner::Single => 0..n,
        }
    }

    /// Reads a filter register (`offset` in `FMR ..= FiR2(27)`); other offsets read 0.
    pub(crate) fn read(&self, offset: usize) -> u32 {
        match offset {
            regs::FMR => FMR_RESERVED | fmr::CAN2SB.val(self.can2sb) | self.finit as u32,
            regs::FM1R => self.fm1r,
            regs::FS1R => self.fs1r,
            regs::FFA1R => self.ffa1r,
            regs::FA1R => self.fa1r,
            _ => match bank_register(offset) {
                Some((bank, reg)) if bank < self.nbanks() => self.banks[bank][reg],
                _ => 0,
            },
        }
    }

    /// Writes a filter register under the rules of 40.9.4; writes that the hardware
    /// would not accept are ignored.
    pub(crate) fn write(&mut self, offset: usize, value: u32) {
        let mask = self.bank_mask();
        match offset {
            regs::FMR => {
                self.finit = value & fmr::FINIT != 0;
                if self.dual {
                    self.can2sb = fmr::CAN2SB.get(value);
                }
            }
            regs::FM1R if self.finit => self.fm1r = value & mask,
            regs::FS1R if self.finit => self.fs1r = value & mask,
            regs::FFA1R if self.finit => self.ffa1r = value & mask,
            regs::FA1R => self.fa1r = value & mask,
            _ => {
                if let Some((bank, reg)) = bank_register(offset) {
                    let active = self.fa1r & (1 << bank) != 0;
                    if bank < self.nbanks() && (self.finit || !active) {
                        self.banks[bank][reg] = value;
                    }
                }
            }
        }
    }

    /// Runs acceptance filtering for a frame received by `owner`: the selected filter's
    /// FIFO and match index, or `None` (dropped: no match, or `FINIT = 1`).
    pub(crate) fn accept(&mut self, owner: Owner, frame: &Frame) -> Option<Accepted> {
        if self.finit {
            return None;
        }
        let w32 = word32(frame);
        let w16 = word16(frame);
        let mut next_number = [0u32; 2];
        let mut best: Option<(Key, usize, Accepted)> = None;
        for bank in self.range(owner) {
            let bit = 1u32 << bank;
            let fifo = (self.ffa1r & bit != 0) as usize;
            let list = self.fm1r & bit != 0;
            let scale32 = self.fs1r & bit != 0;
            let [r1, r2] = self.banks[bank];
            let first = next_number[fifo];
            next_number[fifo] += filters_in_bank(scale32, list);
            if self.fa1r & bit == 0 {
                continue;
            }
            for k in 0..filters_in_bank(scale32, list) as usize {
                let hit = match (scale32, list) {
                    (true, false) => (w32 ^ r1) & r2 == 0,
                    (true, true) => w32 == [r1, r2][k],
                    (false, false) => {
                        let r = [r1, r2][k];
                        let id = firx::LOW_HALF.get(r);
                        let m = firx::HIGH_HALF.get(r);
                        (w16 ^ id) & m == 0
                    }
                    (false, true) => {
                        let r = [r1, r2][k / 2];
                        let half = if k % 2 == 0 {
                            firx::LOW_HALF
                        } else {
                            firx::HIGH_HALF
                        };
                        half.get(r) == w16
                    }
                };
                if !hit {
                    continue;
                }
                // Smaller key wins: 32-bit first, list first, lower bank / position.
                let key = (!scale32, !list, bank, k);
                let fmi = (first as usize + k).min(u8::MAX as usize) as u8;
                if best.as_ref().is_none_or(|(b, _, _)| key < *b) {
                    best = Some((key, bank, Accepted { fifo, fmi }));
                }
            }
        }
        let (_, bank, accepted) = best?;
        self.hits[bank] = self.hits[bank].saturating_add(1);
        Some(accepted)
    }
}

/// Priority of a matching filter, smaller first: (16-bit, mask mode, bank, position).
type Key = (bool, bool, usize, usize);

/// Numbers a bank contributes to its FIFO's numbering (notes: "Filter Match Index").
fn filters_in_bank(scale32: bool, list: bool) -> u32 {
    match (scale32, list) {
        (true, false) => 1,
        (true, true) | (false, false) => 2,
        (false, true) => 4,
    }
}

/// `(bank, 0 for FiR1 / 1 for FiR2)` of a filter bank register offset.
fn bank_register(offset: usize) -> Option<(usize, usize)> {
    if offset < regs::fir1(0) || offset > regs::fir2(FILTER_BANKS - 1) || !offset.is_multiple_of(4)
    {
        return None;
    }
    let rel = (offset - regs::fir1(0)) / 4;
    Some((rel / 2, rel % 2))
}

/// The frame's identifier in the 32-bit filter layout `STID[10:0] EXID[17:0] IDE RTR 0`.
pub(crate) fn word32(frame: &Frame) -> u32 {
    let (stid, exid) = split_id(frame);
    let mut w = firx::STID.val(stid) | firx::EXID.val(exid);
    if frame.is_extended() {
        w |= firx::IDE;
    }
    if frame.is_remote() {
        w |= firx::RTR;
    }
    w
}

/// The frame's identifier in the 16-bit filter layout `STID[10:0] RTR IDE EXID[17:15]`.
pub(crate) fn word16(frame: &Frame) -> u32 {
    let (stid, exid) = split_id(frame);
    let mut w = firx::STID16.val(stid) | firx::EXID16.val(exid >> 15);
    if frame.is_extended() {
        w |= firx::IDE16;
    }
    if frame.is_remote() {
        w |= firx::RTR16;
    }
    w
}

/// `(STID[10:0] or EXID[28:18], EXID[17:0])` of a frame's identifier.
fn split_id(frame: &Frame) -> (u32, u32) {
    let raw = frame.raw_id();
    if frame.is_extended() {
        (raw >> 18, raw & 0x3_FFFF)
    } else {
        (raw & 0x7FF, 0)
    }
}
