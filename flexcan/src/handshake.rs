//! Mode changes and their bounded acknowledge waits (Kinetis reference manuals,
//! FlexCAN "Modes of operation": freeze, module disable, soft reset).
//!
//! | request | acknowledge |
//! |---|---|
//! | `MCR.MDIS = 1` (disable) | `MCR.LPMACK` becomes 1 |
//! | `MCR.MDIS = 0` (enable) | `MCR.LPMACK` becomes 0 |
//! | `MCR.SOFTRST = 1` | `MCR.SOFTRST` returns to 0 |
//! | `MCR.FRZ = HALT = 1` (freeze) | `MCR.FRZACK` becomes 1 |
//! | `MCR.FRZ = HALT = 0` (leave freeze) | `MCR.FRZACK` becomes 0, then `MCR.NOTRDY` 0 |
//!
//! Every wait polls `MCR` at most `polls` times (at least once) and ends in
//! [`Error::Timeout`]: a module with no clock or no transceiver never hangs the
//! firmware.

use twocan_core::{Error, Registers};

use crate::regs::{mcr, MCR};

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
pub fn disable<R: Registers>(regs: &mut R, polls: u32) -> Result<(), Error> {
    regs.modify32(MCR, |v| v | mcr::MDIS);
    wait_mcr(regs, mcr::LPMACK, true, polls)
}

/// Enables the module (clears `MDIS`, waits for `LPMACK` to clear).
pub fn enable<R: Registers>(regs: &mut R, polls: u32) -> Result<(), Error> {
    regs.modify32(MCR, |v| v & !mcr::MDIS);
    wait_mcr(regs, mcr::LPMACK, false, polls)
}

/// Soft reset (`SOFTRST`, waits until it clears itself).
pub fn soft_reset<R: Registers>(regs: &mut R, polls: u32) -> Result<(), Error> {
    regs.modify32(MCR, |v| v | mcr::SOFTRST);
    wait_mcr(regs, mcr::SOFTRST, false, polls)
}

/// Enters freeze mode (`FRZ` and `HALT`, waits for `FRZACK`).
pub fn freeze<R: Registers>(regs: &mut R, polls: u32) -> Result<(), Error> {
    regs.modify32(MCR, |v| v | mcr::FRZ | mcr::HALT);
    wait_mcr(regs, mcr::FRZACK, true, polls)
}

/// Leaves freeze mode (clears `FRZ` and `HALT`, waits for `FRZACK` and then `NOTRDY`
/// to clear).
pub fn unfreeze<R: Registers>(regs: &mut R, polls: u32) -> Result<(), Error> {
    regs.modify32(MCR, |v| v & !(mcr::FRZ | mcr::HALT));
    wait_mcr(regs, mcr::FRZACK, false, polls)?;
    wait_mcr(regs, mcr::NOTRDY, false, polls)
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
        fn write32(&mut self, _: usize, _: u32) {}
    }

    #[test]
    fn waits_are_bounded() {
        let mut r = Deaf(0);
        assert_eq!(freeze(&mut r, 10), Err(Error::Timeout));
        assert_eq!(disable(&mut r, 0), Err(Error::Timeout));
        let mut r = Deaf(mcr::LPMACK | mcr::SOFTRST | mcr::FRZACK);
        assert_eq!(enable(&mut r, 3), Err(Error::Timeout));
        assert_eq!(soft_reset(&mut r, 3), Err(Error::Timeout));
        assert_eq!(unfreeze(&mut r, 3), Err(Error::Timeout));
        assert_eq!(freeze(&mut r, 1), Ok(()));
    }
}
