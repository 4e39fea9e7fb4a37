//! Operating-mode requests and their bounded acknowledge waits (RM0410 §40.4 "bxCAN
//! operating modes": `CAN_MCR.INRQ`/`SLEEP` request, `CAN_MSR.INAK`/`SLAK` acknowledge).
//!
//! - initialization: set INRQ (clear SLEEP), wait for INAK = 1, SLAK = 0 (§40.4.1);
//! - normal: clear INRQ and SLEEP, wait for INAK = 0, SLAK = 0 — the hardware first
//!   waits for 11 recessive bits on CANRX (§40.4.2);
//! - sleep: set SLEEP (clear INRQ), wait for SLAK = 1, INAK = 0 (§40.4.3).
//!
//! Every wait reads `CAN_MSR` at most `bound` times and then gives up with
//! [`Error::Timeout`] (see [`crate::config::DEFAULT_WAIT_ITERATIONS`]).

use twocan_core::{Error, Mode, Registers};

use crate::regs::{mcr, msr, MCR, MSR};

/// Reads `CAN_MSR` until `(msr & mask) == want`, at most `bound` times.
pub(crate) fn wait_msr<R: Registers>(
    regs: &R,
    mask: u32,
    want: u32,
    bound: u32,
) -> Result<(), Error> {
    for _ in 0..bound {
        if regs.read32(MSR) & mask == want {
            return Ok(());
        }
    }
    Err(Error::Timeout)
}

/// Requests `mode` and waits (bounded) for the acknowledge.
pub(crate) fn request<R: Registers>(regs: &R, mode: Mode, bound: u32) -> Result<(), Error> {
    let both = msr::INAK | msr::SLAK;
    match mode {
        Mode::Stopped => {
            regs.modify32(MCR, |v| (v & !mcr::SLEEP) | mcr::INRQ);
            wait_msr(regs, both, msr::INAK, bound)
        }
        Mode::Normal => {
            regs.modify32(MCR, |v| v & !(mcr::SLEEP | mcr::INRQ));
            wait_msr(regs, both, 0, bound)
        }
        Mode::Sleep => {
            regs.modify32(MCR, |v| (v & !mcr::INRQ) | mcr::SLEEP);
            wait_msr(regs, both, msr::SLAK, bound)
        }
    }
}

/// The mode the acknowledge bits show.
pub(crate) fn current<R: Registers>(regs: &R) -> Mode {
    let s = regs.read32(MSR);
    if s & msr::SLAK != 0 {
        Mode::Sleep
    } else if s & msr::INAK != 0 {
        Mode::Stopped
    } else {
        Mode::Normal
    }
}
