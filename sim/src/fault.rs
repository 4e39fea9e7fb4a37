//! ISO 11898-1 fault confinement (§12.1.4): the error counters and the rules that move them.
//!
//! Both controllers implement these rules in hardware; the behavioural models and the
//! simulated bus share this one implementation of the standard, so that the rule set is
//! written (and tested) once. The driver never uses it: it reads its controller's counters.

use twocan_core::error::{ErrorCounters, ErrorState, LastErrorCode};

/// Error counters of one node with the standard's update rules.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FaultConfinement {
    tec: u16,
    rec: u16,
    bus_off: bool,
    /// Sequences of 11 consecutive recessive bits seen while bus-off.
    recovery_sequences: u16,
    /// Recessive bits in the current run while bus-off.
    recessive_run: u16,
    /// The value REC takes after a successful reception while above 127 (rule 8 leaves
    /// the choice in 119..=127 to the implementation).
    rec_after_passive_reception: u8,
    /// An error-passive transmitter detected an acknowledge error: whether TEC moves waits
    /// for the end of its passive error flag (rule 3, exception 1).
    ack_exception_pending: bool,
    /// Bus time before which an error-passive node that was transmitter may not start a
    /// transmission (suspend transmission); 0 when not suspended.
    suspend_until: u64,
    /// The next transmit error is a stuff error in arbitration on a recessive stuff bit
    /// (rule 3, exception 2).
    arbitration_stuff_exception: bool,
}

/// The number of 11-recessive-bit sequences after which a bus-off node may recover.
pub const BUS_OFF_RECOVERY_SEQUENCES: u16 = 128;

/// Bits of intermission after an end of frame or an error / overload delimiter
/// (ISO 11898-1 §10.4.6.2 "Intermission").
pub const INTERMISSION_BITS: u64 = 3;

/// Bits an error-passive node that was transmitter waits after the intermission before it
/// may start another transmission (ISO 11898-1 §10.4.6.4 "Suspend transmission").
pub const SUSPEND_TRANSMISSION_BITS: u64 = 8;

/// The implementation-defined REC value after a successful reception above 127 is outside
/// the 119..=127 range that ISO 11898-1 §12.1.4.2 rule 8 allows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecResetOutOfRange(pub u8);

impl core::fmt::Display for RecResetOutOfRange {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "REC after a successful reception above 127 must be in 119..=127, not {}",
            self.0
        )
    }
}

impl core::error::Error for RecResetOutOfRange {}

impl Default for FaultConfinement {
    fn default() -> Self {
        Self::new()
    }
}

impl FaultConfinement {
    /// The REC value [`FaultConfinement::new`] uses after a successful reception above 127.
    pub const DEFAULT_REC_AFTER_PASSIVE_RECEPTION: u8 = 127;

    /// A node fresh from reset: error-active, both counters zero.
    pub const fn new() -> Self {
        FaultConfinement {
            tec: 0,
            rec: 0,
            bus_off: false,
            recovery_sequences: 0,
            recessive_run: 0,
            rec_after_passive_reception: Self::DEFAULT_REC_AFTER_PASSIVE_RECEPTION,
            ack_exception_pending: false,
            suspend_until: 0,
            arbitration_stuff_exception: false,
        }
    }

    /// A node fresh from reset whose REC is set to `value` by a successful reception while
    /// above 127 (rule 8: "a value between 119 and 127"; each controller's reference manual
    /// names its own). Refuses a value outside 119..=127.
    pub const fn with_rec_after_passive_reception(value: u8) -> Result<Self, RecResetOutOfRange> {
        if value < 119 || value > 127 {
            return Err(RecResetOutOfRange(value));
        }
        let mut f = Self::new();
        f.rec_after_passive_reception = value;
        Ok(f)
    }

    /// The REC value after a successful reception above 127.
    pub const fn rec_after_passive_reception(&self) -> u8 {
        self.rec_after_passive_reception
    }

    /// The counters; TEC reads 256 while bus-off (ACAN §17 convention).
    pub const fn counters(&self) -> ErrorCounters {
        ErrorCounters {
            tec: if self.bus_off { 256 } else { self.tec },
            rec: self.rec,
        }
    }

    /// The raw 8-bit transmit counter as the hardware registers show it.
    pub const fn tec_register(&self) -> u8 {
        (self.tec & 0xFF) as u8
    }

    /// The raw 8-bit receive counter as the hardware registers show it.
    pub const fn rec_register(&self) -> u8 {
        if self.rec > 255 {
            255
        } else {
            self.rec as u8
        }
    }

    /// The fault-confinement state.
    pub const fn state(&self) -> ErrorState {
        if self.bus_off {
            ErrorState::BusOff
        } else {
            ErrorState::from_counters(ErrorCounters {
                tec: self.tec,
                rec: self.rec,
            })
        }
    }

    /// Whether the node is error-passive (sends passive error flags).
    pub const fn is_passive(&self) -> bool {
        !self.bus_off && (self.tec >= 128 || self.rec >= 128)
    }

    /// Whether the node is bus-off.
    pub const fn is_bus_off(&self) -> bool {
        self.bus_off
    }

    /// Rule 7: a successful transmission decrements TEC.
    pub fn transmit_succeeded(&mut self) {
        if !self.bus_off {
            self.tec = self.tec.saturating_sub(1);
        }
    }

    /// Rule 8: a successful reception decrements REC (1..=127), or sets it to the
    /// controller's value in 119..=127 when above 127
    /// ([`FaultConfinement::with_rec_after_passive_reception`]).
    pub fn receive_succeeded(&mut self) {
        if self.rec > 127 {
            self.rec = u16::from(self.rec_after_passive_reception);
        } else if self.rec > 0 {
            self.rec -= 1;
        }
    }

    /// Rule 3: the transmitter sends an error flag, TEC += 8. Returns whether bus-off was
    /// entered.
    ///
    /// Exception 1: an error-passive transmitter that detects an acknowledge error and
    /// detects no dominant bit while sending its passive error flag leaves TEC unchanged.
    /// The flag comes after the detection, so for an error-passive transmitter with
    /// `Acknowledge` the decision waits for [`FaultConfinement::transmission_ended`].
    pub fn transmit_error(&mut self, code: LastErrorCode) -> bool {
        if self.bus_off {
            return false;
        }
        let exempt = core::mem::replace(&mut self.arbitration_stuff_exception, false);
        if exempt && code == LastErrorCode::Stuff {
            return false;
        }
        if code == LastErrorCode::Acknowledge && self.is_passive() {
            self.ack_exception_pending = true;
            return false;
        }
        self.add_tec(8)
    }

    fn add_tec(&mut self, n: u16) -> bool {
        self.tec += n;
        if self.tec > 255 {
            self.bus_off = true;
            self.recovery_sequences = 0;
            self.recessive_run = 0;
            self.suspend_until = 0;
            return true;
        }
        false
    }

    /// The end of a frame attempt in which the node was a transmitter (to the end of its
    /// end of frame or of its error delimiter, bus time `end`), after
    /// [`FaultConfinement::transmit_error`] or [`FaultConfinement::transmit_succeeded`].
    ///
    /// - Rule 3 exception 1 settled: an acknowledge error of an error-passive transmitter
    ///   that saw a dominant bit during its passive error flag
    ///   (`dominant_in_passive_flag`) counts TEC += 8 after all.
    /// - Suspend transmission (ISO 11898-1 §10.4.6.4): a node error-passive at this point
    ///   may not start a transmission before `end` + intermission + 8 bits
    ///   ([`FaultConfinement::may_start_transmission`]); it still receives a frame another
    ///   node starts meanwhile.
    ///
    /// Returns whether bus-off was entered.
    pub fn transmission_ended(&mut self, end: u64, dominant_in_passive_flag: bool) -> bool {
        let pending = core::mem::replace(&mut self.ack_exception_pending, false);
        if self.bus_off {
            return false;
        }
        let off = pending && dominant_in_passive_flag && self.add_tec(8);
        if !off && self.is_passive() {
            self.suspend_until = end + INTERMISSION_BITS + SUSPEND_TRANSMISSION_BITS;
        }
        off
    }

    /// Whether suspend transmission lets the node start a frame at bus time `now`.
    pub const fn may_start_transmission(&self, now: u64) -> bool {
        now >= self.suspend_until
    }

    /// The bus time at which suspend transmission ends, if it has not ended by `now`.
    pub const fn suspend_end(&self, now: u64) -> Option<u64> {
        if now < self.suspend_until {
            Some(self.suspend_until)
        } else {
            None
        }
    }

    /// Rule 3, exception 2: the next [`FaultConfinement::transmit_error`], a stuff error
    /// on a recessive stuff bit of the arbitration field that was read dominant, leaves
    /// TEC unchanged.
    pub fn arbitration_stuff_exception(&mut self) {
        self.arbitration_stuff_exception = true;
    }

    /// Rules 4 and 5 (a bit error while sending an active error or overload flag) and rule
    /// 6 (the 14th / 8th consecutive dominant bit after a flag, and each 8 more): TEC + 8
    /// for a transmitter, REC + 8 for a receiver. Returns whether bus-off was entered.
    pub fn flag_penalty(&mut self, transmitter: bool) -> bool {
        if self.bus_off {
            return false;
        }
        if transmitter {
            self.add_tec(8)
        } else {
            self.rec = (self.rec + 8).min(255);
            false
        }
    }

    /// `count` flag penalties at once ([`FaultConfinement::flag_penalty`]). Returns
    /// whether bus-off was entered.
    pub fn confinement_penalties(&mut self, transmitter: bool, count: u8) -> bool {
        let mut off = false;
        for _ in 0..count {
            off |= self.flag_penalty(transmitter);
        }
        off
    }

    /// Rule 1: a receiver detects an error, REC += 1; rule 2, a dominant bit as the first
    /// bit after its own error flag, adds 8 more (both rules apply to the same error:
    /// +9 in all). REC saturates at 255 (a receiver never goes bus-off).
    pub fn receive_error(&mut self, dominant_after_flag: bool) {
        if self.bus_off {
            return;
        }
        let add = if dominant_after_flag { 9 } else { 1 };
        self.rec = (self.rec + add).min(255);
    }

    /// Feeds `bits` bus bits while bus-off: recessive bits count toward the 128 × 11
    /// recessive-bit recovery sequence, a dominant bit restarts the current run of 11.
    /// Returns `true` when the condition for recovery has just been met.
    ///
    /// Whether the node then leaves bus-off at once (bxCAN ABOM, FlexCAN automatic
    /// recovery) or waits for software (bxCAN manual recovery) is the controller's
    /// business: it calls [`FaultConfinement::recover`].
    pub fn idle_bits(&mut self, bits: u64) -> bool {
        if !self.bus_off || self.recovery_sequences >= BUS_OFF_RECOVERY_SEQUENCES {
            return false;
        }
        let total = self.recessive_run as u64 + bits;
        let seqs = total / 11;
        self.recessive_run = (total % 11) as u16;
        let done = self.recovery_sequences as u64 + seqs;
        if done >= BUS_OFF_RECOVERY_SEQUENCES as u64 {
            self.recovery_sequences = BUS_OFF_RECOVERY_SEQUENCES;
            true
        } else {
            self.recovery_sequences = done as u16;
            false
        }
    }

    /// Recessive bits still needed (at best, with no dominant bit in between) before the
    /// bus-off recovery condition is met; 0 when not bus-off or already met.
    pub const fn recovery_remaining_bits(&self) -> u64 {
        if !self.bus_off || self.recovery_sequences >= BUS_OFF_RECOVERY_SEQUENCES {
            return 0;
        }
        (BUS_OFF_RECOVERY_SEQUENCES - self.recovery_sequences) as u64 * 11
            - self.recessive_run as u64
    }

    /// A dominant bit seen while bus-off interrupts the current run of recessive bits.
    pub fn dominant_bit(&mut self) {
        self.recessive_run = 0;
    }

    /// Whether the 128 × 11 recessive-bit condition has been met while bus-off.
    pub const fn recovery_condition_met(&self) -> bool {
        self.bus_off && self.recovery_sequences >= BUS_OFF_RECOVERY_SEQUENCES
    }

    /// Leaves bus-off: error-active with both counters zero (ISO 11898-1 §12.1.4.2).
    pub fn recover(&mut self) {
        *self = FaultConfinement {
            rec_after_passive_reception: self.rec_after_passive_reception,
            ..Self::new()
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rec_reset_out_of_range_is_an_error_with_a_message() {
        let e = FaultConfinement::with_rec_after_passive_reception(118).unwrap_err();
        assert_eq!(e, RecResetOutOfRange(118));
        let e: &dyn core::error::Error = &e;
        assert_eq!(
            std::format!("{e}"),
            "REC after a successful reception above 127 must be in 119..=127, not 118"
        );
    }

    #[test]
    fn lone_transmitter_stops_at_error_passive() {
        let mut f = FaultConfinement::new();
        for _ in 0..100 {
            assert!(!f.transmit_error(LastErrorCode::Acknowledge));
        }
        assert_eq!(f.counters().tec, 128);
        assert_eq!(f.state(), ErrorState::Passive);
    }

    #[test]
    fn bus_off_after_32_errors_and_recovery() {
        let mut f = FaultConfinement::new();
        for i in 0..32 {
            let off = f.transmit_error(LastErrorCode::BitDominant);
            assert_eq!(off, i == 31);
        }
        assert_eq!(f.state(), ErrorState::BusOff);
        assert_eq!(f.counters().tec, 256);
        assert_eq!(f.recovery_remaining_bits(), 128 * 11);
        assert!(!f.idle_bits(11 * 127 + 10));
        assert_eq!(f.recovery_remaining_bits(), 1);
        f.dominant_bit();
        assert_eq!(f.recovery_remaining_bits(), 11);
        assert!(!f.idle_bits(10));
        assert!(f.idle_bits(1));
        assert!(f.recovery_condition_met());
        f.recover();
        assert_eq!(f.state(), ErrorState::Active);
        assert_eq!(f.counters(), ErrorCounters { tec: 0, rec: 0 });
    }

    #[test]
    fn receive_rules() {
        let mut f = FaultConfinement::new();
        f.receive_error(false);
        f.receive_error(true);
        assert_eq!(f.counters().rec, 10);
        f.receive_succeeded();
        assert_eq!(f.counters().rec, 9);
        for _ in 0..40 {
            f.receive_error(true);
        }
        assert_eq!(f.counters().rec, 255);
        assert_eq!(f.state(), ErrorState::Passive);
        f.receive_succeeded();
        assert_eq!(f.counters().rec, 127);
        assert_eq!(f.state(), ErrorState::Warning);
        f.transmit_error(LastErrorCode::Form);
        f.transmit_succeeded();
        assert_eq!(f.counters().tec, 7);
    }
}
