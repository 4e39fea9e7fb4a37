//! The 16-bit time-triggered communication timer (RM0410 40.7.2 "Time triggered
//! communication mode"; notes "The bxCAN Time Triggered Communication Mode").
//!
//! The internal counter is activated by `MCR.TTCM`, incremented once per CAN bit time,
//! and captured at the start-of-frame of received and transmitted frames into
//! `RDTxR.TIME` / `TDTxR.TIME`. The model derives the count from the bus time (bit
//! times), so a capture at any past start-of-frame is exact. It stops while the
//! controller is asleep (the bxCAN clock is stopped) and while `TTCM = 0`, and keeps its
//! value meanwhile; it wraps at 2^16.

/// The free-running bit-time counter.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Timer {
    /// Counter value at `base_time`.
    base_value: u16,
    /// Bus time (bit times) at which `base_value` was taken.
    base_time: u64,
    running: bool,
}

impl Timer {
    /// A stopped counter at 0.
    pub(crate) fn new() -> Self {
        Self::default()
    }

    /// The counter value at bus time `t` (not before the last start or stop).
    pub(crate) fn at(&self, t: u64) -> u16 {
        if self.running {
            let elapsed = t.saturating_sub(self.base_time);
            self.base_value.wrapping_add(elapsed as u16)
        } else {
            self.base_value
        }
    }

    /// Starts or stops the counter at bus time `now`.
    pub(crate) fn set_running(&mut self, running: bool, now: u64) {
        if running != self.running {
            self.base_value = self.at(now);
            self.base_time = now;
            self.running = running;
        }
    }
}
