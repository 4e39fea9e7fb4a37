//! The register file as software sees it: what each offset reads, what a write changes,
//! which fields are writable only in Freeze mode (FRZACK = 1) or only in Disable mode, and
//! the read side effects ("Memory map/register definition" field descriptions).
//!
//! Write protection, from the field descriptions:
//! - MCR: MDIS, FRZ, HALT, SOFTRST, WAKMSK, SLFWAK at any time; RFEN, SRXDIS, IRMQ,
//!   LPRIOEN, AEN, IDAM, MAXMB, WRNEN, SUPV (and WAKSRC on K66) in Freeze mode only;
//!   FRZACK, LPMACK, NOTRDY read-only.
//! - CTRL1: BOFFMSK, ERRMSK, TWRNMSK, RWRNMSK, BOFFREC at any time; CLKSRC in Disable mode
//!   only; the bit timing fields, SMP, LPB, TSYN, LBUF, LOM in Freeze mode only.
//! - CTRL2, RXMGMASK, RX14MASK, RX15MASK, RXFGMASK, RXIMRn, ECR: Freeze mode only.
//! - IMASK1, TIMER: any time. ESR1, IFLAG1: write 1 to clear. ESR2, CRCR, RXFIR: read-only.
//! - Message buffers are RAM, writable at any time; with the Rx FIFO enabled the FIFO
//!   engine's area (0x80–0xDF) ignores writes.
//!
//! Read side effects: ESR1 clears its error bits; a C/S word read locks that mailbox;
//! TIMER read unlocks. Unaligned, reserved and unimplemented offsets read 0 and ignore
//! writes; reserved bits read 0.
//!
//! What the variants add ([`super::variant`]; IMXRT1060RM FlexCAN memory map and field
//! descriptions):
//! - RT1062: 64 message buffers (0x80–0x47F), RXIMR0–63 (0x880–0x97F), IMASK2 (any time)
//!   and IFLAG2 (write 1 to clear) for MB32–MB63; IMASK1/IFLAG1 have 32 bits.
//! - CAN1/CAN2: DBG1/DBG2 read-only (their reset values: the protocol engine's debug
//!   state is not modelled), GFWR (8 bits, Freeze mode only), no CTRL1\[CLKSRC\] (reads 0).
//! - CAN3: CBT (Freeze mode only, stored), FDCTRL/FDCBT/FDCRC read their reset values and
//!   ignore writes, MCR\[FDEN\] stays 0 (classic CAN only).

use crate::regs::{self, ctrl1, ctrl2, iflag1, mcr, timer};

use super::layout::{self, MB0, MB_BYTES, RXIMR0};
use super::modes::MCR_STORED;
use super::state::State;
use super::variant;

/// MCR bits writable at any time.
const MCR_ANY_TIME: u32 = mcr::MDIS | mcr::FRZ | mcr::HALT | mcr::WAKMSK | mcr::SLFWAK;

/// CTRL1 bits writable at any time.
const CTRL1_ANY_TIME: u32 =
    ctrl1::BOFFMSK | ctrl1::ERRMSK | ctrl1::TWRNMSK | ctrl1::RWRNMSK | ctrl1::BOFFREC;
/// CTRL1 bits writable in Freeze mode only.
const CTRL1_FREEZE: u32 = ctrl1::PRESDIV.mask()
    | ctrl1::RJW.mask()
    | ctrl1::PSEG1.mask()
    | ctrl1::PSEG2.mask()
    | ctrl1::LPB
    | ctrl1::SMP
    | ctrl1::TSYN
    | ctrl1::LBUF
    | ctrl1::LOM
    | ctrl1::PROPSEG.mask();
/// CTRL2 bits (all writable in Freeze mode only).
const CTRL2_BITS: u32 = ctrl2::WRMFRZ
    | ctrl2::RFFN.mask()
    | ctrl2::TASD.mask()
    | ctrl2::MRP
    | ctrl2::RRS
    | ctrl2::EACEN;
/// GFWR's field (bits 7–0).
const GFWR_BITS: u32 = 0xFF;
/// The Rx FIFO engine's area: MB0–MB5 (0x80–0xDF); the ID filter table starts after it.
pub(crate) const RX_FIFO_FILTER_BASE: usize = MB0 + 6 * MB_BYTES;

impl State {
    /// MCR bits writable in Freeze mode only, for this chip.
    fn mcr_freeze_bits(&self) -> u32 {
        let waksrc = if self.variant.waksrc { 0 } else { mcr::WAKSRC };
        MCR_STORED & !MCR_ANY_TIME & !waksrc
    }

    /// End of the message buffer RAM.
    fn mb_end(&self) -> usize {
        MB0 + self.mbs() * MB_BYTES
    }

    /// End of the RXIMR registers.
    fn rximr_end(&self) -> usize {
        RXIMR0 + 4 * self.mbs()
    }

    /// Registers only some variants have; `None` if `offset` is not one of them here.
    fn extra_read(&self, offset: usize) -> Option<u32> {
        let x = &self.variant.extras;
        let flags2 = self.variant.flags2_implemented() != 0;
        Some(match offset {
            layout::IMASK2 if flags2 => (self.imask >> 32) as u32,
            layout::IFLAG2 if flags2 => (self.iflag >> 32) as u32,
            layout::DBG1 if x.debug => variant::DBG1_RESET,
            layout::DBG2 if x.debug => 0,
            layout::GFWR if x.gfwr => self.gfwr,
            layout::CBT if x.cbt => self.cbt,
            layout::FDCTRL if x.can_fd => variant::FDCTRL_RESET,
            layout::FDCBT | layout::FDCRC if x.can_fd => 0,
            _ => return None,
        })
    }

    /// Writes to registers only some variants have; false if `offset` is not one of them.
    fn extra_write(&mut self, offset: usize, value: u32, freeze: bool) -> bool {
        let x = self.variant.extras;
        let flags2 = self.variant.flags2_implemented();
        match offset {
            layout::IMASK2 if flags2 != 0 => {
                self.imask = (self.imask & 0xFFFF_FFFF) | (u64::from(value & flags2) << 32);
            }
            layout::IFLAG2 if flags2 != 0 => self.iflag &= !(u64::from(value & flags2) << 32),
            layout::GFWR if x.gfwr => {
                if freeze {
                    self.gfwr = value & GFWR_BITS;
                }
            }
            layout::CBT if x.cbt => {
                if freeze {
                    self.cbt = value;
                }
            }
            // DBG1/DBG2 and FDCRC are read-only; FDCTRL and FDCBT keep their reset values
            // (classic CAN only).
            layout::DBG1 | layout::DBG2 if x.debug => {}
            layout::FDCTRL | layout::FDCBT | layout::FDCRC if x.can_fd => {}
            _ => return false,
        }
        true
    }

    /// Reads the register at `offset`; `side_effects` false peeks without them.
    pub fn read(&mut self, offset: usize, side_effects: bool) -> u32 {
        if !offset.is_multiple_of(4) {
            return 0;
        }
        if let Some(v) = self.extra_read(offset) {
            return v;
        }
        let (mb_end, rximr_end) = (self.mb_end(), self.rximr_end());
        match offset {
            regs::MCR => self.mcr_value(),
            regs::CTRL1 => self.ctrl1,
            regs::TIMER => {
                if side_effects {
                    self.unlock();
                }
                timer::TIMER.val(u32::from(self.timer.value()))
            }
            regs::RXMGMASK => self.rxmgmask,
            regs::RX14MASK => self.rx14mask,
            regs::RX15MASK => self.rx15mask,
            regs::ECR => self.ecr_value(),
            regs::ESR1 => {
                if side_effects {
                    self.esr1_read()
                } else {
                    self.esr1_value()
                }
            }
            regs::IMASK1 => self.imask as u32,
            regs::IFLAG1 => self.iflag1_value(),
            regs::CTRL2 => self.ctrl2,
            regs::RXFGMASK => self.rxfgmask,
            regs::RXFIR => self.rxfir_value(),
            o if (MB0..mb_end).contains(&o) => self.mb_area_read(o, side_effects),
            o if (RXIMR0..rximr_end).contains(&o) => self.rximr[(o - RXIMR0) / 4],
            // ESR2 and CRCR are not modelled; everything else is reserved.
            _ => 0,
        }
    }

    /// Writes `value` to the register at `offset`.
    pub fn write(&mut self, offset: usize, value: u32) {
        if !offset.is_multiple_of(4) {
            return;
        }
        let freeze = self.frozen();
        if self.extra_write(offset, value, freeze) {
            return;
        }
        let (mb_end, rximr_end) = (self.mb_end(), self.rximr_end());
        match offset {
            regs::MCR => self.mcr_write(value),
            regs::CTRL1 => {
                let mut writable = CTRL1_ANY_TIME;
                if freeze {
                    writable |= CTRL1_FREEZE;
                }
                if self.disabled() && self.variant.clksrc {
                    writable |= ctrl1::CLKSRC;
                }
                self.ctrl1 = (self.ctrl1 & !writable) | (value & writable);
                self.boffrec_written();
            }
            regs::TIMER => self.timer.set(timer::TIMER.get(value) as u16),
            regs::RXMGMASK if freeze => self.rxmgmask = value,
            regs::RX14MASK if freeze => self.rx14mask = value,
            regs::RX15MASK if freeze => self.rx15mask = value,
            regs::ECR if freeze => self.ecr_write(value),
            regs::ESR1 => self.esr1_write(value),
            regs::IMASK1 => {
                let bits = self.variant.flags1_implemented();
                self.imask = (self.imask & !0xFFFF_FFFF) | u64::from(value & bits);
            }
            regs::IFLAG1 => self.iflag1_write(value),
            regs::CTRL2 if freeze => self.ctrl2 = value & CTRL2_BITS,
            regs::RXFGMASK if freeze => self.rxfgmask = value,
            o if (MB0..mb_end).contains(&o) => self.mb_area_write(o, value),
            o if (RXIMR0..rximr_end).contains(&o) && freeze => {
                self.rximr[(o - RXIMR0) / 4] = value;
            }
            _ => {}
        }
    }

    fn mcr_write(&mut self, value: u32) {
        let mut writable = MCR_ANY_TIME;
        if self.frozen() {
            writable |= self.mcr_freeze_bits();
        }
        let new = (self.mcr & !writable) | (value & writable);
        if (new ^ self.mcr) & mcr::RFEN != 0 {
            // The FIFO engine starts empty; IFLAG1 bits 0–7 change meaning.
            self.fifo.clear();
            self.iflag &= !0xFF;
        }
        self.mcr = new;
        if value & mcr::SOFTRST != 0 {
            self.softrst_pending = true;
        }
        self.settle_modes();
    }

    /// IFLAG1 as read: with the Rx FIFO on, bit 5 is "frames available", bits 0–4 unused.
    fn iflag1_value(&self) -> u32 {
        let low = self.iflag as u32;
        if self.rfen() {
            let mut v = low & !0x3F;
            if self.fifo.len() > 0 {
                v |= iflag1::BUF5I;
            }
            v
        } else {
            low
        }
    }

    /// IFLAG1 write: write 1 to clear; with the Rx FIFO on, 1 in bit 5 releases the output.
    fn iflag1_write(&mut self, value: u32) {
        let value = value & self.variant.flags1_implemented();
        if self.rfen() {
            if value & iflag1::BUF5I != 0 {
                self.fifo_pop();
            }
            self.iflag &= !u64::from(value & !0x3F);
        } else {
            self.iflag &= !u64::from(value);
        }
    }

    /// Whether `n` is a mailbox (not FIFO engine or filter table storage).
    fn is_mailbox(&self, n: usize) -> bool {
        n >= self.first_mb()
    }

    fn mb_area_read(&mut self, offset: usize, side_effects: bool) -> u32 {
        let word = (offset - MB0) / 4;
        let (n, w) = (word / 4, word % 4);
        if self.rfen() && offset < RX_FIFO_FILTER_BASE {
            return if n == 0 { self.fifo_output_word(w) } else { 0 };
        }
        if side_effects && w == 0 && self.is_mailbox(n) {
            self.lock(n);
        }
        self.ram[word]
    }

    fn mb_area_write(&mut self, offset: usize, value: u32) {
        let word = (offset - MB0) / 4;
        let (n, w) = (word / 4, word % 4);
        if self.rfen() && offset < RX_FIFO_FILTER_BASE {
            return;
        }
        if w == 0 && self.is_mailbox(n) {
            self.cs_write(n, value);
        } else {
            self.ram[word] = value;
        }
    }
}
