//! FlexCAN registers as plain memory for the `rt` entry-point tests (included with
//! `#[path]`, so that it needs neither the model nor `common/mod.rs`): the mode
//! handshakes acknowledged at once (`MCR`: `LPMACK`/`NOTRDY` in Disable mode,
//! `FRZACK`/`NOTRDY` in Freeze mode; `ESR1.SYNCH` always set), and the write-1-to-clear
//! registers cleared as the manual says (`IFLAG1`, `IFLAG2`, `ESR1`). Atomic words, so
//! that a `&'static` reaches them from the handlers' context.

// Each test binary builds the block it needs (`new` or `imxrt`).
#![allow(dead_code)]

use std::sync::atomic::{AtomicU32, Ordering};

use twocan_core::Registers;
use twocan_flexcan::regs::{self, esr1, mcr, ESR1, IFLAG1, IFLAG2, MCR};

/// FlexCAN registers as plain memory, with the handshakes acknowledged at once.
pub struct SyncRegs {
    words: Vec<AtomicU32>,
}

impl SyncRegs {
    /// A Kinetis module's register block (16 message buffers, `regs::BLOCK_END`).
    pub fn new() -> Self {
        Self::with_end(regs::BLOCK_END)
    }

    /// The i.MX RT1062 module's block: 64 message buffers, `RXIMR0–63`
    /// (`regs::IMXRT_BLOCK_END`).
    pub fn imxrt() -> Self {
        Self::with_end(regs::IMXRT_BLOCK_END)
    }

    fn with_end(end: usize) -> Self {
        SyncRegs {
            words: (0..end / 4).map(|_| AtomicU32::new(0)).collect(),
        }
    }

    /// Sets bits as the hardware would (an interrupt cause).
    pub fn raise(&self, offset: usize, bits: u32) {
        self.words[offset / 4].fetch_or(bits, Ordering::SeqCst);
    }
}

impl Registers for SyncRegs {
    fn read32(&self, offset: usize) -> u32 {
        let v = self.words[offset / 4].load(Ordering::SeqCst);
        match offset {
            MCR if v & mcr::MDIS != 0 => v | mcr::LPMACK | mcr::NOTRDY,
            MCR if v & mcr::FRZ != 0 && v & mcr::HALT != 0 => v | mcr::FRZACK | mcr::NOTRDY,
            ESR1 => v | esr1::SYNCH,
            _ => v,
        }
    }

    fn write32(&self, offset: usize, value: u32) {
        let w = &self.words[offset / 4];
        match offset {
            MCR => w.store(
                value & !(mcr::FRZACK | mcr::LPMACK | mcr::NOTRDY | mcr::SOFTRST),
                Ordering::SeqCst,
            ),
            IFLAG1 | IFLAG2 | ESR1 => {
                w.fetch_and(!value, Ordering::SeqCst);
            }
            _ => w.store(value, Ordering::SeqCst),
        }
    }
}
