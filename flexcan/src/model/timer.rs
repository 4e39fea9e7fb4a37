//! The free-running timer ("Free Running Timer (CANx_TIMER)"; "Time stamp").
//!
//! A 16-bit counter clocked by the bit clock: it counts one per nominal bit time while the
//! module runs (not in Disable or Freeze mode) and wraps around. Time stamps are the
//! timer's value when the start of the identifier field (the bit after SOF) is on the bus.

/// The timer, kept as its value at the last bus time the model saw.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Timer {
    value: u16,
    /// Bus time (bit times) at which `value` holds.
    at: u64,
}

impl Timer {
    /// Reset value 0 at time 0.
    pub const fn new() -> Self {
        Timer { value: 0, at: 0 }
    }

    /// The current value.
    pub const fn value(&self) -> u16 {
        self.value
    }

    /// The bus time of the last update.
    pub const fn at(&self) -> u64 {
        self.at
    }

    /// Lets time run to `now`; the value moves only if the module `running`.
    pub fn advance_to(&mut self, now: u64, running: bool) {
        if now > self.at {
            if running {
                self.value = self.value.wrapping_add(((now - self.at) & 0xFFFF) as u16);
            }
            self.at = now;
        }
    }

    /// Software write (allowed at any time) or TSYN reset.
    pub fn set(&mut self, value: u16) {
        self.value = value;
    }

    /// The timer's value at bus time `t` (not later than the last update): the time stamp
    /// of a frame whose identifier started at `t`.
    pub fn value_at(&self, t: u64) -> u16 {
        let back = self.at.saturating_sub(t);
        self.value.wrapping_sub((back & 0xFFFF) as u16)
    }
}
