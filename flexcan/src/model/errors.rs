//! Error counters, ESR1 and bus-off recovery ("Error Counter (CANx_ECR)", "Error and
//! Status 1 register (CANx_ESR1)", CTRL1\[BOFFREC\]).
//!
//! The counter rules are ISO 11898-1's, implemented once in
//! [`twocan_sim::fault::FaultConfinement`]; this file adds what FlexCAN shows of them:
//! - ESR1 error bits STFERR..BIT1ERR record errors since ESR1 was last read and are
//!   cleared by the read; ERRINT (set with any of them), BOFFINT (bus-off entered),
//!   RWRNINT/TWRNINT (RXWRN/TXWRN went 0 → 1, only with MCR\[WRNEN\]) are write-1-to-clear;
//! - while bus-off, ECR\[TXERRCNT\] counts the sequences of 11 recessive bits toward the
//!   128 needed for recovery ("If FlexCAN is in Bus Off state, then TXERRCNT is cascaded
//!   together with another internal counter to count the 128th occurrences of 11
//!   consecutive recessive bits");
//! - CTRL1\[BOFFREC\] = 0 recovers automatically once the 128 × 11 bits are seen; with
//!   BOFFREC = 1 (as it was when bus-off was entered) the module stays bus-off until
//!   software negates BOFFREC: before the condition is met recovery then proceeds as if
//!   automatic, after it the module recovers at once and re-synchronises (11 recessive
//!   bits) before joining the bus.

use twocan_core::error::{ErrorState, LastErrorCode};
use twocan_sim::fault::{FaultConfinement, BUS_OFF_RECOVERY_SEQUENCES};

use crate::regs::{ctrl1, ecr, esr1, mcr};

use super::state::State;

/// RXERRCNT after a successful reception while above 127. The Kinetis reference manuals
/// ("Error Counter (CANx_ECR)") say only "set to a value between 119 and 127", as ISO
/// 11898-1 rule 8 does; the model takes 127 (docs/models.md says how silicon can tell:
/// ECR is writable in Freeze mode).
pub const REC_AFTER_PASSIVE_RECEPTION: u8 = 127;

/// A fresh counter pair with FlexCAN's REC rule.
pub(crate) const FRESH_COUNTERS: FaultConfinement =
    match FaultConfinement::with_rec_after_passive_reception(REC_AFTER_PASSIVE_RECEPTION) {
        Ok(f) => f,
        Err(_) => panic!("REC_AFTER_PASSIVE_RECEPTION outside 119..=127"),
    };

/// FlexCAN's view of fault confinement.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Errors {
    pub fc: FaultConfinement,
    /// ESR1 error bits and write-1-to-clear interrupt flags.
    pub flags: u32,
    /// CTRL1\[BOFFREC\] as it was when bus-off was entered (manual recovery requested).
    pub boffrec_latched: bool,
    rxwrn: bool,
    txwrn: bool,
}

/// The ESR1 error bit of an error code.
pub(crate) fn error_bit(code: LastErrorCode) -> u32 {
    match code {
        LastErrorCode::None => 0,
        LastErrorCode::Stuff => esr1::STFERR,
        LastErrorCode::Form => esr1::FRMERR,
        LastErrorCode::Crc => esr1::CRCERR,
        LastErrorCode::Acknowledge => esr1::ACKERR,
        // Sent dominant, read recessive.
        LastErrorCode::BitDominant => esr1::BIT0ERR,
        // Sent recessive, read dominant.
        LastErrorCode::BitRecessive => esr1::BIT1ERR,
    }
}

impl Errors {
    /// Reset state: error active, counters zero, no flags.
    pub const fn new() -> Self {
        Errors {
            fc: FRESH_COUNTERS,
            flags: 0,
            boffrec_latched: false,
            rxwrn: false,
            txwrn: false,
        }
    }

    fn bus_off_entered(&mut self, boffrec: bool) {
        self.flags |= esr1::BOFFINT;
        self.boffrec_latched = boffrec;
    }

    /// Completed sequences of 11 recessive bits since bus-off was entered (0..=128).
    fn recovery_sequences(&self) -> u64 {
        let total = u64::from(BUS_OFF_RECOVERY_SEQUENCES) * 11;
        (total - self.fc.recovery_remaining_bits().min(total)) / 11
    }
}

impl State {
    /// Records an error event in ESR1 (error bit and ERRINT).
    fn note_error(&mut self, code: LastErrorCode) {
        let bit = error_bit(code);
        if bit != 0 {
            self.errors.flags |= bit | esr1::ERRINT;
        }
    }

    /// Re-evaluates RXWRN/TXWRN and raises RWRNINT/TWRNINT on a 0 → 1 transition when
    /// MCR\[WRNEN\] is set.
    pub fn update_warnings(&mut self) {
        let c = self.errors.fc.counters();
        let rxwrn = c.rec >= 96;
        let txwrn = c.tec >= 96;
        if self.mcr_bit(mcr::WRNEN) {
            if rxwrn && !self.errors.rxwrn {
                self.errors.flags |= esr1::RWRNINT;
            }
            if txwrn && !self.errors.txwrn {
                self.errors.flags |= esr1::TWRNINT;
            }
        }
        self.errors.rxwrn = rxwrn;
        self.errors.txwrn = txwrn;
    }

    /// The transmitter detected `code` (ISO 11898-1 rule 3 and its exception).
    pub fn transmit_error(&mut self, code: LastErrorCode) {
        self.note_error(code);
        if self.errors.fc.transmit_error(code) {
            let boffrec = self.ctrl1_bit(ctrl1::BOFFREC);
            self.errors.bus_off_entered(boffrec);
        }
        self.update_warnings();
    }

    /// The end of a frame attempt the module transmitted (`end`: end of its EOF or error
    /// delimiter): rule 3 exception 1 settled, suspend transmission armed.
    pub fn transmission_ended(&mut self, end: u64, dominant_in_passive_flag: bool) {
        if self
            .errors
            .fc
            .transmission_ended(end, dominant_in_passive_flag)
        {
            let boffrec = self.ctrl1_bit(ctrl1::BOFFREC);
            self.errors.bus_off_entered(boffrec);
        }
        self.update_warnings();
    }

    /// Rule 3 exception 2 for the transmit error that follows.
    pub fn arbitration_stuff_exception(&mut self) {
        self.errors.fc.arbitration_stuff_exception();
    }

    /// `count` flag penalties (rules 4 to 6).
    pub fn flag_penalties(&mut self, transmitter: bool, count: u8) {
        if self.errors.fc.confinement_penalties(transmitter, count) {
            let boffrec = self.ctrl1_bit(ctrl1::BOFFREC);
            self.errors.bus_off_entered(boffrec);
        }
        self.update_warnings();
    }

    /// A transmission completed (rule 7).
    pub fn transmit_ok(&mut self) {
        self.errors.fc.transmit_succeeded();
        self.update_warnings();
    }

    /// A receiver detected `code` (rules 1 and 2).
    pub fn receive_error(&mut self, code: LastErrorCode, dominant_after_flag: bool) {
        self.note_error(code);
        self.errors.fc.receive_error(dominant_after_flag);
        self.update_warnings();
    }

    /// A frame was received correctly (rule 8).
    pub fn receive_ok(&mut self) {
        self.errors.fc.receive_succeeded();
        self.update_warnings();
    }

    /// Whether the module is bus-off.
    pub fn bus_off(&self) -> bool {
        self.errors.fc.is_bus_off()
    }

    /// Bus activity (a dominant bit) seen while bus-off restarts the run of 11.
    pub fn bus_off_dominant(&mut self) {
        if self.bus_off() {
            self.errors.fc.dominant_bit();
        }
    }

    /// `bits` recessive bits seen while bus-off: counts toward recovery, and recovers when
    /// the condition is met unless manual recovery (BOFFREC latched) holds the module.
    pub fn bus_off_idle(&mut self, bits: u64) {
        if !self.bus_off() {
            return;
        }
        self.errors.fc.idle_bits(bits);
        if self.errors.fc.recovery_condition_met() && !self.errors.boffrec_latched {
            self.recover_from_bus_off();
        }
    }

    fn recover_from_bus_off(&mut self) {
        self.errors.fc.recover();
        self.errors.boffrec_latched = false;
        self.update_warnings();
    }

    /// Software wrote CTRL1: negating BOFFREC releases a module held in bus-off.
    pub fn boffrec_written(&mut self) {
        if self.bus_off() && self.errors.boffrec_latched && !self.ctrl1_bit(ctrl1::BOFFREC) {
            self.errors.boffrec_latched = false;
            if self.errors.fc.recovery_condition_met() {
                self.recover_from_bus_off();
                // "FlexCAN will re-synchronize to the bus by waiting for 11 recessive bits".
                self.lose_sync();
            }
        }
    }

    /// Bit times of recessive bus still needed before bus-off recovery can complete.
    pub fn bus_off_bits_left(&self) -> Option<u64> {
        self.bus_off()
            .then(|| self.errors.fc.recovery_remaining_bits())
    }

    /// ECR as read: the 8-bit counters; while bus-off TXERRCNT counts recovery sequences.
    pub fn ecr_value(&self) -> u32 {
        let fc = &self.errors.fc;
        let tx = if fc.is_bus_off() {
            self.errors.recovery_sequences() as u32
        } else {
            u32::from(fc.tec_register())
        };
        ecr::TXERRCNT.val(tx) | ecr::RXERRCNT.val(u32::from(fc.rec_register()))
    }

    /// Software write of ECR (Freeze mode only: "both counters are read-only except in
    /// Freeze mode, where they can be written by the CPU"). The counters are rebuilt by
    /// replaying the standard's rules; a TEC above 248 cannot be reached that way without
    /// going bus-off and is stored as 248.
    pub fn ecr_write(&mut self, value: u32) {
        let tec = ecr::TXERRCNT.get(value).min(248);
        let rec = ecr::RXERRCNT.get(value);
        let mut fc = FRESH_COUNTERS;
        for _ in 0..rec {
            fc.receive_error(false);
        }
        let errors = tec.div_ceil(8);
        for _ in 0..errors {
            fc.transmit_error(LastErrorCode::BitDominant);
        }
        for _ in 0..(errors * 8 - tec) {
            fc.transmit_succeeded();
        }
        self.errors.fc = fc;
        self.update_warnings();
    }

    /// ESR1 as read (without the read's side effect).
    pub fn esr1_value(&self) -> u32 {
        let fc = &self.errors.fc;
        // Listen-only mode: "If the LOM bit in CTRL1 is asserted, after some delay that
        // depends on the CAN bit timing the FLTCONF field will indicate 'Error Passive'"
        // (ESR1[FLTCONF]); the model shows it at once.
        let fltconf = match fc.state() {
            ErrorState::BusOff => esr1::FLTCONF_BUS_OFF,
            ErrorState::Passive => esr1::FLTCONF_ERROR_PASSIVE,
            _ if self.lom() => esr1::FLTCONF_ERROR_PASSIVE,
            _ => esr1::FLTCONF_ERROR_ACTIVE,
        };
        let mut v = self.errors.flags | esr1::FLTCONF.val(fltconf);
        if self.errors.rxwrn {
            v |= esr1::RXWRN;
        }
        if self.errors.txwrn {
            v |= esr1::TXWRN;
        }
        if self.on_bus() {
            v |= esr1::SYNCH;
            if self.transmitting {
                v |= esr1::TX;
            }
            if self.receiving {
                v |= esr1::RX;
            }
            if !self.transmitting && !self.receiving {
                v |= esr1::IDLE;
            }
        }
        v
    }

    /// The read of ESR1: the error bits are cleared by it.
    pub fn esr1_read(&mut self) -> u32 {
        let v = self.esr1_value();
        self.errors.flags &= !esr1::ERROR_BITS;
        v
    }

    /// Write of ESR1: write-1-to-clear of the interrupt flags; other bits are read-only.
    pub fn esr1_write(&mut self, value: u32) {
        self.errors.flags &= !(value & esr1::W1C_BITS);
    }
}
