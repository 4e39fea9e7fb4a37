//! Mode changes and their bounded acknowledge waits (Kinetis reference manuals,
//! FlexCAN "Modes of operation": freeze, module disable, soft reset).
//!
//! | request | acknowledge |
//! |---|---|
//! | `MCR.MDIS = 1` (disable) | `MCR.LPMACK` becomes 1 |
//! | `MCR.MDIS = 0` (enable) | `MCR.LPMACK` becomes 0 |
//! | `MCR.SOFTRST = 1` | `MCR.SOFTRST` returns to 0 |
//! | `MCR.FRZ = HALT = 1` (freeze) | `MCR.FRZACK` becomes 1 |
//! | `MCR.FRZ = HALT = 0` (leave freeze) | `MCR.FRZACK` becomes 0, then `MCR.NOTRDY` 0, then `ESR1.SYNCH` 1 |
//!
//! Leaving freeze is only complete once the module is synchronised to the bus
//! (`ESR1.SYNCH`: 11 consecutive recessive bits seen after Freeze or Disable mode).
//! Before that the module does not take part in bus traffic, so a frame starting in
//! that window would be missed without any trace. In loop-back mode (`CTRL1.LPB`) the
//! receiver sees the module's own, recessive, Tx output instead of the bus ("Loop-back
//! mode": the Rx pin is ignored), so the module synchronises internally after 11 bit
//! times whatever the bus does; in listen-only mode (`CTRL1.LOM`) it synchronises to the
//! bus like in normal mode.
//!
//! Every wait polls its register (`MCR`, or `ESR1` for `SYNCH`) at most `polls` times
//! (at least once) and ends in [`Error::Timeout`]: a module with no clock, no
//! transceiver or a bus stuck dominant never hangs the firmware.

use twocan_core::{Error, Registers};

use crate::regs::{esr1, mcr, ESR1, MCR};

/// Polls `MCR` until `bit` reads `set`, at most `polls` times (at least once).
pub fn wait_mcr<R: Registers>(regs: &R, bit: u32, set: bool, polls: u32) -> Result<(), Error> {
    for _ in 0..polls.max(1) {
        if (regs.read32(MCR) & bit != 0) == set {
            return Ok(());
        }
    }
    Err(Error::Timeout)
}

/// Disables the module (`MDIS`, waits for `LPMACK`).
pub fn disable<R: Registers>(regs: &R, polls: u32) -> Result<(), Error> {
    regs.modify32(MCR, |v| v | mcr::MDIS);
    wait_mcr(regs, mcr::LPMACK, true, polls)
}

/// Enables the module (clears `MDIS`, waits for `LPMACK` to clear).
pub fn enable<R: Registers>(regs: &R, polls: u32) -> Result<(), Error> {
    regs.modify32(MCR, |v| v & !mcr::MDIS);
    wait_mcr(regs, mcr::LPMACK, false, polls)
}

/// Soft reset (`SOFTRST`, waits until it clears itself).
pub fn soft_reset<R: Registers>(regs: &R, polls: u32) -> Result<(), Error> {
    regs.modify32(MCR, |v| v | mcr::SOFTRST);
    wait_mcr(regs, mcr::SOFTRST, false, polls)
}

/// Enters freeze mode (`FRZ` and `HALT`, waits for `FRZACK`).
pub fn freeze<R: Registers>(regs: &R, polls: u32) -> Result<(), Error> {
    regs.modify32(MCR, |v| v | mcr::FRZ | mcr::HALT);
    wait_mcr(regs, mcr::FRZACK, true, polls)
}

/// Leaves freeze mode (clears `FRZ` and `HALT`, waits for `FRZACK` and then `NOTRDY`
/// to clear). The module is then running but maybe not yet synchronised: see
/// [`wait_synch`], or [`unfreeze`] for both steps.
pub fn leave_freeze<R: Registers>(regs: &R, polls: u32) -> Result<(), Error> {
    regs.modify32(MCR, |v| v & !(mcr::FRZ | mcr::HALT));
    wait_mcr(regs, mcr::FRZACK, false, polls)?;
    wait_mcr(regs, mcr::NOTRDY, false, polls)
}

/// Polls `ESR1` until `SYNCH` is set, at most `polls` times (at least once).
///
/// Reading `ESR1` clears its error bits (`BIT1ERR` … `STFERR`): every value read is
/// handed to `seen`, so that a caller keeping the last error loses none.
pub fn wait_synch<R: Registers>(
    regs: &R,
    polls: u32,
    mut seen: impl FnMut(u32),
) -> Result<(), Error> {
    for _ in 0..polls.max(1) {
        let value = regs.read32(ESR1);
        seen(value);
        if value & esr1::SYNCH != 0 {
            return Ok(());
        }
    }
    Err(Error::Timeout)
}

/// Leaves freeze mode ([`leave_freeze`]) and waits until the module is synchronised to
/// the bus ([`wait_synch`]): when it returns `Ok`, a frame starting on the bus is
/// received.
pub fn unfreeze<R: Registers>(regs: &R, polls: u32) -> Result<(), Error> {
    leave_freeze(regs, polls)?;
    wait_synch(regs, polls, |_| {})
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A register file that never acknowledges anything.
    struct Deaf(u32);
    impl Registers for Deaf {
        fn read32(&self, _: usize) -> u32 {
            self.0
        }
        fn write32(&self, _: usize, _: u32) {}
    }

    #[test]
    fn waits_are_bounded() {
        let r = Deaf(0);
        assert_eq!(freeze(&r, 10), Err(Error::Timeout));
        assert_eq!(disable(&r, 0), Err(Error::Timeout));
        let r = Deaf(mcr::LPMACK | mcr::SOFTRST | mcr::FRZACK);
        assert_eq!(enable(&r, 3), Err(Error::Timeout));
        assert_eq!(soft_reset(&r, 3), Err(Error::Timeout));
        assert_eq!(unfreeze(&r, 3), Err(Error::Timeout));
        assert_eq!(freeze(&r, 1), Ok(()));
    }

    /// Out of freeze at once, but never synchronised (a bus stuck dominant).
    struct NeverSynch;
    impl Registers for NeverSynch {
        fn read32(&self, offset: usize) -> u32 {
            if offset == ESR1 {
                esr1::BIT0ERR
            } else {
                0
            }
        }
        fn write32(&self, _: usize, _: u32) {}
    }

    #[test]
    fn synch_wait_is_bounded_and_reports_every_read() {
        let r = NeverSynch;
        assert_eq!(leave_freeze(&r, 3), Ok(()));
        assert_eq!(unfreeze(&r, 3), Err(Error::Timeout));
        let mut reads = 0;
        assert_eq!(
            wait_synch(&r, 5, |v| {
                assert_eq!(v, esr1::BIT0ERR);
                reads += 1;
            }),
            Err(Error::Timeout)
        );
        assert_eq!(reads, 5);
        assert_eq!(wait_synch(&Deaf(esr1::SYNCH), 0, |_| {}), Ok(()));
    }
}
