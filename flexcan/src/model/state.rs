//! The model's state: the register file, the message-buffer RAM and the internal state
//! machines, with the configuration bits read the way the hardware uses them.

use crate::regs::{self, ctrl1, ctrl2, mcr, NUM_MB};

use super::errors::Errors;
use super::mailboxes::Mailboxes;
use super::rx_fifo::RxFifo;
use super::timer::Timer;
use super::Chip;

/// Words of message-buffer RAM (16 MBs × 4 words).
pub(crate) const RAM_WORDS: usize = NUM_MB * 4;

/// Everything the peripheral holds.
#[derive(Debug)]
pub(crate) struct State {
    pub chip: Chip,
    /// MCR bits software writes (status bits FRZACK, LPMACK, NOTRDY, SOFTRST are derived).
    pub mcr: u32,
    pub ctrl1: u32,
    pub ctrl2: u32,
    pub rxmgmask: u32,
    pub rx14mask: u32,
    pub rx15mask: u32,
    pub rxfgmask: u32,
    pub imask1: u32,
    /// IFLAG1 as stored; with the Rx FIFO on, bit 5 is derived from the FIFO occupancy.
    pub iflag1: u32,
    /// RXIMR0..15 (RAM: not affected by reset).
    pub rximr: [u32; NUM_MB],
    /// Message buffer RAM (not affected by reset).
    pub ram: [u32; RAM_WORDS],
    /// Low-power (disable) mode acknowledged.
    pub lpmack: bool,
    /// Freeze mode acknowledged.
    pub frzack: bool,
    /// SOFTRST written, reset not yet done (needs a clocked, enabled module).
    pub softrst_pending: bool,
    /// Fault injection: the module has no clock, no mode handshake completes.
    pub clock_stuck: bool,
    /// Synchronised to the bus (ESR1\[SYNCH\]).
    pub synched: bool,
    /// Consecutive recessive bits seen while waiting for synchronisation.
    pub sync_run: u64,
    pub errors: Errors,
    pub timer: Timer,
    pub fifo: RxFifo,
    pub mbx: Mailboxes,
    /// Frames that matched no filter and no mailbox.
    pub discarded: u64,
    /// Transmitting a frame (ESR1\[TX\]): from its start of frame to the end of the attempt.
    pub transmitting: bool,
    /// Receiving a frame (ESR1\[RX\]): from its start of frame to its outcome.
    pub receiving: bool,
}

impl State {
    /// A module fresh from power-on reset.
    pub fn new(chip: Chip) -> Self {
        State {
            chip,
            mcr: mcr::RESET & !(mcr::FRZACK | mcr::LPMACK | mcr::NOTRDY | mcr::SOFTRST),
            ctrl1: ctrl1::RESET,
            ctrl2: ctrl2::RESET,
            rxmgmask: u32::MAX,
            rx14mask: u32::MAX,
            rx15mask: u32::MAX,
            rxfgmask: u32::MAX,
            imask1: 0,
            iflag1: 0,
            rximr: [0; NUM_MB],
            ram: [0; RAM_WORDS],
            lpmack: true,
            frzack: false,
            softrst_pending: false,
            clock_stuck: false,
            synched: false,
            sync_run: 0,
            errors: Errors::new(),
            timer: Timer::new(),
            fifo: RxFifo::new(),
            mbx: Mailboxes::new(),
            discarded: 0,
            transmitting: false,
            receiving: false,
        }
    }

    // --- modes -------------------------------------------------------------------------

    /// Module Disable mode (LPMACK).
    pub fn disabled(&self) -> bool {
        self.lpmack
    }

    /// Freeze mode (FRZACK).
    pub fn frozen(&self) -> bool {
        self.frzack
    }

    /// Enabled and out of freeze: the protocol engine runs (the TIMER counts).
    pub fn running(&self) -> bool {
        !self.lpmack && !self.frzack
    }

    /// Running and synchronised to the bus: takes part in bus traffic (unless bus-off).
    pub fn on_bus(&self) -> bool {
        self.running() && self.synched
    }

    // --- configuration bits --------------------------------------------------------------

    pub fn mcr_bit(&self, bit: u32) -> bool {
        self.mcr & bit != 0
    }
    pub fn ctrl1_bit(&self, bit: u32) -> bool {
        self.ctrl1 & bit != 0
    }
    pub fn ctrl2_bit(&self, bit: u32) -> bool {
        self.ctrl2 & bit != 0
    }
    pub fn rfen(&self) -> bool {
        self.mcr_bit(mcr::RFEN)
    }
    pub fn irmq(&self) -> bool {
        self.mcr_bit(mcr::IRMQ)
    }
    pub fn lpb(&self) -> bool {
        self.ctrl1_bit(ctrl1::LPB)
    }
    pub fn lom(&self) -> bool {
        self.ctrl1_bit(ctrl1::LOM)
    }
    pub fn rffn(&self) -> u32 {
        ctrl2::RFFN.get(self.ctrl2)
    }

    /// The last message buffer taking part in matching and arbitration: MCR\[MAXMB\], limited
    /// to the 16 MBs that exist ("MAXMB must be programmed with a value smaller than the
    /// number of available MBs").
    pub fn last_mb(&self) -> usize {
        (mcr::MAXMB.get(self.mcr) as usize).min(NUM_MB - 1)
    }

    /// The first message buffer usable as a mailbox: MB0, or the first one after the Rx
    /// FIFO and its ID filter table (table "Rx FIFO filter: possible structures").
    pub fn first_mb(&self) -> usize {
        if self.rfen() {
            regs::rx_fifo_occupied_mbs(self.rffn()).min(NUM_MB)
        } else {
            0
        }
    }

    /// The mailboxes taking part in matching and arbitration.
    pub fn active_mbs(&self) -> core::ops::RangeInclusive<usize> {
        self.first_mb()..=self.last_mb()
    }

    /// Word `w` of message buffer `n`.
    pub fn mb_word(&self, n: usize, w: usize) -> u32 {
        self.ram[4 * n + w]
    }

    /// The four words of message buffer `n`.
    pub fn mb_words(&self, n: usize) -> [u32; 4] {
        [
            self.ram[4 * n],
            self.ram[4 * n + 1],
            self.ram[4 * n + 2],
            self.ram[4 * n + 3],
        ]
    }

    /// Writes the four words of message buffer `n`.
    pub fn set_mb_words(&mut self, n: usize, words: [u32; 4]) {
        self.ram[4 * n..4 * n + 4].copy_from_slice(&words);
    }
}
