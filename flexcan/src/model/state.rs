//! The model's state: the register file, the message-buffer RAM and the internal state
//! machines, with the configuration bits read the way the hardware uses them.

use crate::regs::{ctrl1, ctrl2, mcr};

use super::errors::Errors;
use super::mailboxes::Mailboxes;
use super::rx_fifo::RxFifo;
use super::timer::Timer;
use super::variant::{self, Variant};
use super::Chip;

/// The most message buffers a variant has (the RT1062's 64); smaller modules use the
/// first part of the arrays.
pub(crate) const MAX_MBS: usize = 64;
/// Words of message-buffer RAM (64 MBs × 4 words).
pub(crate) const RAM_WORDS: usize = MAX_MBS * 4;

/// Everything the peripheral holds.
#[derive(Debug)]
pub(crate) struct State {
    pub chip: Chip,
    /// The module's differences from the other variants.
    pub variant: &'static Variant,
    /// MCR bits software writes (status bits FRZACK, LPMACK, NOTRDY, SOFTRST are derived).
    pub mcr: u32,
    pub ctrl1: u32,
    pub ctrl2: u32,
    pub rxmgmask: u32,
    pub rx14mask: u32,
    pub rx15mask: u32,
    pub rxfgmask: u32,
    /// IMASK2:IMASK1 (bit n: MB n).
    pub imask: u64,
    /// IFLAG2:IFLAG1 as stored (bit n: MB n); with the Rx FIFO on, bit 5 is derived from
    /// the FIFO occupancy.
    pub iflag: u64,
    /// RXIMR0..63 (RAM: not affected by reset).
    pub rximr: [u32; MAX_MBS],
    /// GFWR (RT1062 CAN1/CAN2; stored, the wake-up filter is not modelled).
    pub gfwr: u32,
    /// CBT (RT1062 CAN3; stored, the model has no bit timing).
    pub cbt: u32,
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
        let v = chip.variant();
        let status = mcr::FRZACK | mcr::LPMACK | mcr::NOTRDY | mcr::SOFTRST;
        State {
            chip,
            variant: v,
            mcr: v.reset_mcr & !status,
            ctrl1: ctrl1::RESET,
            ctrl2: v.reset_ctrl2,
            rxmgmask: v.reset_masks,
            rx14mask: v.reset_masks,
            rx15mask: v.reset_masks,
            rxfgmask: v.reset_masks,
            imask: 0,
            iflag: 0,
            rximr: [0; MAX_MBS],
            gfwr: variant::GFWR_RESET,
            cbt: 0,
            ram: [0; RAM_WORDS],
            // Kinetis: Disable mode out of reset (LPMACK); RT1062: Freeze mode (FRZACK).
            lpmack: v.reset_mcr & mcr::LPMACK != 0,
            frzack: v.reset_mcr & mcr::FRZACK != 0,
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

    /// Number of message buffers of this module.
    pub fn mbs(&self) -> usize {
        self.variant.message_buffers
    }

    /// The last message buffer taking part in matching and arbitration: MCR\[MAXMB\], limited
    /// to the MBs that exist ("MAXMB must be programmed with a value smaller than the
    /// number of available MBs": 16 on the Kinetis parts, 64 on the RT1062).
    pub fn last_mb(&self) -> usize {
        (mcr::MAXMB.get(self.mcr) as usize).min(self.mbs() - 1)
    }

    /// The first message buffer usable as a mailbox: MB0, or the first one after the Rx
    /// FIFO and its ID filter table (table "Rx FIFO filter: possible structures").
    pub fn first_mb(&self) -> usize {
        if self.rfen() {
            Variant::rx_fifo_occupied_mbs(self.rffn()).min(self.mbs())
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
