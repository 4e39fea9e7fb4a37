//! Modes of operation and their handshakes ("Modes of operation", "Freeze mode",
//! "Module disable mode", MCR field descriptions).
//!
//! - Reset leaves the module in Disable mode (MCR = 0xD890_000F: MDIS, LPMACK, NOTRDY,
//!   with FRZ and HALT already set). Negating MDIS enables the clocks (LPMACK negated);
//!   with FRZ and HALT set the module then enters Freeze mode (FRZACK asserted).
//! - Freeze mode is requested by FRZ = 1 and HALT = 1 and acknowledged by FRZACK; it is left
//!   when either is negated (FRZACK negated). Out of freeze (or disable) the module must
//!   see 11 consecutive recessive bits to synchronise (ESR1\[SYNCH\]) before it takes part in
//!   bus traffic.
//! - NOTRDY "indicates that FlexCAN is either in Disable mode, Stop mode or Freeze mode.
//!   It is negated once FlexCAN has exited these modes."
//! - SOFTRST resets MCR (except MDIS), TIMER, ECR, ESR1, ESR2, IMASK1, IFLAG1, CRCR and the
//!   internal state machines; CTRL1, CTRL2, the masks, RXFIR and the message buffers are
//!   not affected. It reads 1 until the reset is done, which needs the module clocked:
//!   requested in Disable mode, it completes when the module is enabled.
//! - Entering Freeze or Disable mode while a frame is on the wire (ESR1\[TX\] or \[RX\])
//!   waits for the end of that frame ("Freeze mode": FlexCAN "waits to be in either
//!   Intermission, Passive Error, Bus Off or Idle state").
//! - Fault injection: with no module clock no handshake completes (FRZACK, LPMACK and
//!   SOFTRST keep their values).

use crate::regs::mcr;

use super::errors::Errors;
use super::state::State;

/// The MCR bits that hold state software wrote (the rest are status or reserved).
pub(crate) const MCR_STORED: u32 = mcr::MDIS
    | mcr::FRZ
    | mcr::RFEN
    | mcr::HALT
    | mcr::WAKMSK
    | mcr::SUPV
    | mcr::SLFWAK
    | mcr::WRNEN
    | mcr::WAKSRC
    | mcr::SRXDIS
    | mcr::IRMQ
    | mcr::LPRIOEN
    | mcr::AEN
    | mcr::IDAM.mask()
    | mcr::MAXMB.mask();

impl State {
    /// Brings the acknowledge bits in line with the requests in MCR.
    pub fn settle_modes(&mut self) {
        if self.clock_stuck {
            return;
        }
        // "When Freeze mode is requested during transmission or reception, FlexCAN ...
        // waits to be in either Intermission, Passive Error, Bus Off or Idle state"; the
        // same holds for Disable mode: the frame on the wire is finished first.
        let busy = self.transmitting || self.receiving;
        if self.mcr_bit(mcr::MDIS) {
            if !self.lpmack && !busy {
                self.lpmack = true;
                self.frzack = false;
                self.lose_sync();
            }
            return;
        }
        if self.lpmack {
            self.lpmack = false;
            self.lose_sync();
        }
        if self.softrst_pending {
            self.soft_reset();
        }
        let freeze_requested = self.mcr_bit(mcr::FRZ) && self.mcr_bit(mcr::HALT);
        if freeze_requested && !self.frzack && busy {
            return;
        }
        if freeze_requested != self.frzack {
            self.frzack = freeze_requested;
            self.lose_sync();
        }
    }

    /// Synchronisation is lost (mode change): 11 recessive bits are needed again.
    pub fn lose_sync(&mut self) {
        self.synched = false;
        self.sync_run = 0;
    }

    /// `bits` bit times of bus passed: synchronisation needs 11 consecutive recessive bits
    /// while the module runs. In loop-back mode the receiver sees the module's own
    /// (recessive) Tx output, not the bus.
    pub fn sync_bits(&mut self, bits: u64, idle: bool) {
        if !self.running() || self.synched {
            return;
        }
        if idle || self.lpb() {
            self.sync_run = self.sync_run.saturating_add(bits);
            if self.sync_run >= 11 {
                self.synched = true;
            }
        } else {
            self.sync_run = 0;
        }
    }

    /// The soft reset itself (see the module documentation for what it touches).
    fn soft_reset(&mut self) {
        let mdis = self.mcr & mcr::MDIS;
        self.mcr = (self.variant.reset_mcr & MCR_STORED & !mcr::MDIS) | mdis;
        self.timer.set(0);
        self.errors = Errors::new();
        self.imask = 0;
        self.iflag = 0;
        self.fifo.clear();
        self.mbx.reset_locks();
        self.softrst_pending = false;
        self.lose_sync();
    }

    /// MCR as read: stored bits plus the status bits.
    pub fn mcr_value(&self) -> u32 {
        let mut v = self.mcr;
        if self.frzack {
            v |= mcr::FRZACK;
        }
        if self.lpmack {
            v |= mcr::LPMACK;
        }
        if self.frzack || self.lpmack {
            v |= mcr::NOTRDY;
        }
        if self.softrst_pending {
            v |= mcr::SOFTRST;
        }
        v
    }
}
