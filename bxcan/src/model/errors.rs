//! Error management: `CAN_ESR` and bus-off recovery (RM0410 40.7.6 "Error management",
//! 40.9.2 "CAN error status register"; notes "The bxCAN Error Management",
//! "Bus-Off Recovery").
//!
//! The counters follow ISO 11898-1 through [`FaultConfinement`] (shared with the other
//! models and the simulated bus). Rules modelled:
//! - `EWGF`: TEC or REC ≥ 96; `EPVF`: TEC or REC > 127; `BOFF`: bus-off (TEC > 255).
//!   `TEC` shows the low byte of the 9-bit counter.
//! - `LEC` holds the code of the last error; a transfer without error clears it to 0;
//!   software may write it (RM0410: "can be set to value 0b111 by software") — the
//!   model stores whatever value software writes in the field.
//! - Bus-off recovery needs 128 occurrences of 11 consecutive recessive bits monitored
//!   in normal mode (in initialization mode CANRX is not monitored). With `MCR.ABOM = 1`
//!   counting starts when bus-off is entered; with `ABOM = 0` only after software has
//!   set and then cleared `INRQ` (entered and left initialization mode) — RM0410
//!   `CAN_MCR.ABOM`: "left on software request, once 128 occurrences of 11 recessive bits
//!   have been monitored and the software has first set and cleared the INRQ bit".

use twocan_core::{ErrorCounters, LastErrorCode};
use twocan_sim::fault::FaultConfinement;

use crate::regs::esr;

/// The `LEC` code of a bus error.
pub(crate) fn lec_code(code: LastErrorCode) -> u32 {
    match code {
        LastErrorCode::None => esr::LEC_NO_ERROR,
        LastErrorCode::Stuff => esr::LEC_STUFF,
        LastErrorCode::Form => esr::LEC_FORM,
        LastErrorCode::Acknowledge => esr::LEC_ACK,
        LastErrorCode::BitRecessive => esr::LEC_BIT_RECESSIVE,
        LastErrorCode::BitDominant => esr::LEC_BIT_DOMINANT,
        LastErrorCode::Crc => esr::LEC_CRC,
    }
}

/// REC after a successful reception while above 127: RM0410 40.9.2 (`CAN_ESR.REC`):
/// "After every successful reception, the counter is decremented by 1 or reset to 120 if
/// its value was higher than 128". ISO 11898-1 rule 8 allows 119..=127. The model applies
/// 120 to every REC above 127 (the standard's condition; RM0410's "higher than 128" would
/// take REC = 128 to 127, docs/models.md says how silicon can tell).
pub const REC_AFTER_PASSIVE_RECEPTION: u8 = 120;

const FRESH_COUNTERS: FaultConfinement =
    match FaultConfinement::with_rec_after_passive_reception(REC_AFTER_PASSIVE_RECEPTION) {
        Ok(f) => f,
        Err(_) => panic!("REC_AFTER_PASSIVE_RECEPTION outside 119..=127"),
    };

/// The error counters, last error code and bus-off recovery state of a controller.
#[derive(Debug, Clone)]
pub(crate) struct ErrorUnit {
    fc: FaultConfinement,
    lec: u32,
    /// Bus-off with `ABOM = 0`: software has entered initialization mode since.
    init_entered: bool,
    /// Bus-off with `ABOM = 0`: software has entered and left initialization mode.
    manual_armed: bool,
    /// Recessive bits of the current (incomplete) run of 11 fed to the recovery, mirrored
    /// from `fc` for [`ErrorUnit::recovery_bits_to_next_sequence`].
    run: u64,
}

impl ErrorUnit {
    /// Error-active, counters zero, `LEC` = 0.
    pub(crate) fn new() -> Self {
        ErrorUnit {
            fc: FRESH_COUNTERS,
            lec: 0,
            init_entered: false,
            manual_armed: false,
            run: 0,
        }
    }

    /// The shared fault-confinement state.
    pub(crate) fn fault_confinement(&self) -> &FaultConfinement {
        &self.fc
    }

    /// `CAN_ESR` as read.
    pub(crate) fn esr(&self) -> u32 {
        let c = self.fc.counters();
        let mut v = esr::LEC.val(self.lec)
            | esr::TEC.val(self.fc.tec_register() as u32)
            | esr::REC.val(self.fc.rec_register() as u32);
        if c.tec >= 96 || c.rec >= 96 {
            v |= esr::EWGF;
        }
        if c.tec > 127 || c.rec > 127 {
            v |= esr::EPVF;
        }
        if self.fc.is_bus_off() {
            v |= esr::BOFF;
        }
        v
    }

    /// A software write to `CAN_ESR`: only `LEC` is writable.
    pub(crate) fn write_esr(&mut self, value: u32) {
        self.lec = esr::LEC.get(value);
    }

    /// The counters (TEC = 256 while bus-off).
    pub(crate) fn counters(&self) -> ErrorCounters {
        self.fc.counters()
    }

    /// Whether the controller is bus-off.
    pub(crate) fn is_bus_off(&self) -> bool {
        self.fc.is_bus_off()
    }

    /// Whether the controller is error-passive.
    pub(crate) fn is_passive(&self) -> bool {
        self.fc.is_passive()
    }

    /// Whether an error flag is set whose interrupt is enabled in `ier` (the condition
    /// that sets `MSR.ERRI` on error detection).
    pub(crate) fn erri_condition(&self, ier: u32) -> bool {
        use crate::regs::ier as e;
        let v = self.esr();
        (v & esr::EWGF != 0 && ier & e::EWGIE != 0)
            || (v & esr::EPVF != 0 && ier & e::EPVIE != 0)
            || (v & esr::BOFF != 0 && ier & e::BOFIE != 0)
            || (esr::LEC.get(v) != esr::LEC_NO_ERROR && ier & e::LECIE != 0)
    }

    /// A frame sent without error.
    pub(crate) fn transmit_ok(&mut self) {
        self.fc.transmit_succeeded();
        self.lec = esr::LEC_NO_ERROR;
    }

    /// An error while transmitting.
    pub(crate) fn transmit_error(&mut self, code: LastErrorCode) {
        self.lec = lec_code(code);
        if self.fc.transmit_error(code) {
            self.entered_bus_off();
        }
    }

    fn entered_bus_off(&mut self) {
        self.init_entered = false;
        self.manual_armed = false;
        self.run = 0;
    }

    /// The end of an attempt the controller transmitted (`end`: end of its EOF or error
    /// delimiter): rule 3 exception 1 settled, suspend transmission armed. Returns whether
    /// bus-off was entered.
    pub(crate) fn transmission_ended(&mut self, end: u64, dominant_in_passive_flag: bool) -> bool {
        let off = self.fc.transmission_ended(end, dominant_in_passive_flag);
        if off {
            self.entered_bus_off();
        }
        off
    }

    /// Rule 3 exception 2 for the transmit error that follows.
    pub(crate) fn arbitration_stuff_exception(&mut self) {
        self.fc.arbitration_stuff_exception();
    }

    /// `count` flag penalties (rules 4 to 6); returns whether bus-off was entered.
    pub(crate) fn flag_penalties(&mut self, transmitter: bool, count: u8) -> bool {
        let off = self.fc.confinement_penalties(transmitter, count);
        if off {
            self.entered_bus_off();
        }
        off
    }

    /// A frame received without error.
    pub(crate) fn receive_ok(&mut self) {
        self.fc.receive_succeeded();
        self.lec = esr::LEC_NO_ERROR;
    }

    /// An error while receiving.
    pub(crate) fn receive_error(&mut self, code: LastErrorCode, dominant_after_flag: bool) {
        self.lec = lec_code(code);
        self.fc.receive_error(dominant_after_flag);
    }

    /// Initialization mode was entered.
    pub(crate) fn entered_init(&mut self) {
        if self.fc.is_bus_off() {
            self.init_entered = true;
        }
    }

    /// Initialization mode was left (normal mode reached).
    pub(crate) fn left_init(&mut self) {
        if self.fc.is_bus_off() && self.init_entered {
            self.manual_armed = true;
        }
    }

    /// Whether bus-off recovery counts recessive bits now (given `MCR.ABOM`).
    pub(crate) fn recovery_under_way(&self, abom: bool) -> bool {
        self.fc.is_bus_off() && (abom || self.manual_armed)
    }

    /// Recessive bits until the current run of 11 completes a recovery sequence.
    pub(crate) fn recovery_bits_to_next_sequence(&self) -> u64 {
        11 - self.run % 11
    }

    /// Recessive bits monitored in normal mode; returns whether bus-off was just left.
    pub(crate) fn recessive_bits(&mut self, bits: u64, abom: bool) -> bool {
        if !self.recovery_under_way(abom) {
            return false;
        }
        self.run = (self.run + bits % 11) % 11;
        // More than 129 runs of 11 complete the recovery anyway.
        if self.fc.idle_bits(bits.min(11 * 129)) || self.fc.recovery_condition_met() {
            self.fc.recover();
            self.init_entered = false;
            self.manual_armed = false;
            return true;
        }
        false
    }

    /// A dominant bit (bus activity): restarts the current run of recessive bits.
    pub(crate) fn dominant(&mut self) {
        self.fc.dominant_bit();
        self.run = 0;
    }
}
