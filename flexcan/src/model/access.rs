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

use crate::regs::{
    self, ctrl1, ctrl2, iflag1, imask1, mcr, timer, MB_BASE, MB_STRIDE, NUM_MB, RXIMR_BASE,
    RX_FIFO_FILTER_BASE,
};

use super::modes::MCR_STORED;
use super::state::State;
use super::Chip;

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
/// IFLAG1/IMASK1 bits that exist (one per MB).
const MB_BITS: u32 = imask1::IMPLEMENTED;

/// End of the message buffer RAM.
const MB_END: usize = MB_BASE + NUM_MB * MB_STRIDE;
/// End of the RXIMR registers.
const RXIMR_END: usize = RXIMR_BASE + 4 * NUM_MB;

impl State {
    /// MCR bits writable in Freeze mode only, for this chip.
    fn mcr_freeze_bits(&self) -> u32 {
        let waksrc = if self.chip == Chip::Mk20dx256 {
            mcr::WAKSRC
        } else {
            0
        };
        MCR_STORED & !MCR_ANY_TIME & !waksrc
    }

    /// Reads the register at `offset`; `side_effects` false peeks without them.
    pub fn read(&mut self, offset: usize, side_effects: bool) -> u32 {
        if !offset.is_multiple_of(4) {
            return 0;
        }
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
            regs::IMASK1 => self.imask1,
            regs::IFLAG1 => self.iflag1_value(),
            regs::CTRL2 => self.ctrl2,
            regs::RXFGMASK => self.rxfgmask,
            regs::RXFIR => self.rxfir_value(),
            o if (MB_BASE..MB_END).contains(&o) => self.mb_area_read(o, side_effects),
            o if (RXIMR_BASE..RXIMR_END).contains(&o) => self.rximr[(o - RXIMR_BASE) / 4],
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
        match offset {
            regs::MCR => self.mcr_write(value),
            regs::CTRL1 => {
                let mut writable = CTRL1_ANY_TIME;
                if freeze {
                    writable |= CTRL1_FREEZE;
                }
                if self.disabled() {
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
            regs::IMASK1 => self.imask1 = value & MB_BITS,
            regs::IFLAG1 => self.iflag1_write(value),
            regs::CTRL2 if freeze => self.ctrl2 = value & CTRL2_BITS,
            regs::RXFGMASK if freeze => self.rxfgmask = value,
            o if (MB_BASE..MB_END).contains(&o) => self.mb_area_write(o, value),
            o if (RXIMR_BASE..RXIMR_END).contains(&o) && freeze => {
                self.rximr[(o - RXIMR_BASE) / 4] = value;
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
            self.iflag1 &= !0xFF;
        }
        self.mcr = new;
        if value & mcr::SOFTRST != 0 {
            self.softrst_pending = true;
        }
        self.settle_modes();
    }

    /// IFLAG1 as read: with the Rx FIFO on, bit 5 is "frames available", bits 0–4 unused.
    fn iflag1_value(&self) -> u32 {
        if self.rfen() {
            let mut v = self.iflag1 & !0x3F;
            if self.fifo.len() > 0 {
                v |= iflag1::BUF5I;
            }
            v
        } else {
            self.iflag1
        }
    }

    /// IFLAG1 write: write 1 to clear; with the Rx FIFO on, 1 in bit 5 releases the output.
    fn iflag1_write(&mut self, value: u32) {
        let value = value & MB_BITS;
        if self.rfen() {
            if value & iflag1::BUF5I != 0 {
                self.fifo_pop();
            }
            self.iflag1 &= !(value & !0x3F);
        } else {
            self.iflag1 &= !value;
        }
    }

    /// Whether `n` is a mailbox (not FIFO engine or filter table storage).
    fn is_mailbox(&self, n: usize) -> bool {
        n >= self.first_mb()
    }

    fn mb_area_read(&mut self, offset: usize, side_effects: bool) -> u32 {
        let word = (offset - MB_BASE) / 4;
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
        let word = (offset - MB_BASE) / 4;
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
