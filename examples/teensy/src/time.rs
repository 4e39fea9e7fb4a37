//! A millisecond time base from SysTick (ARMv7-M ARM B3.3 "The system timer, SysTick";
//! the handler is in `rt.rs`), and periodic deadlines over it.

use core::sync::atomic::{AtomicU32, Ordering};

static MILLIS: AtomicU32 = AtomicU32::new(0);

/// Milliseconds since `start` (wraps after 49.7 days).
pub fn millis() -> u32 {
    MILLIS.load(Ordering::Relaxed)
}

/// Called by the SysTick handler every millisecond.
pub fn tick() {
    MILLIS.fetch_add(1, Ordering::Relaxed);
}

/// The SysTick reload value for a 1 ms period at `core_hz` (SysTick counts the processor
/// clock, `CSR.CLKSOURCE = 1`; the reload register is 24 bits wide).
pub const fn reload_for_1ms(core_hz: u32) -> u32 {
    let r = core_hz / 1000 - 1;
    assert!(r > 0 && r < (1 << 24));
    r
}

/// Starts SysTick: processor clock, 1 ms period, interrupt enabled.
#[cfg(target_os = "none")]
pub fn start(syst: &mut cortex_m::peripheral::SYST, core_hz: u32) {
    use cortex_m::peripheral::syst::SystClkSource;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(reload_for_1ms(core_hz));
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// A periodic deadline: `due(now)` is true once per `period` milliseconds; wrap-safe.
#[derive(Debug, Clone, Copy)]
pub struct Every {
    period: u32,
    next: u32,
}

impl Every {
    /// First due `period` ms after `now`.
    pub const fn new(now: u32, period: u32) -> Self {
        Every {
            period,
            next: now.wrapping_add(period),
        }
    }

    /// Whether the deadline passed; if so the next one is set (missed periods are skipped,
    /// not caught up).
    pub fn due(&mut self, now: u32) -> bool {
        if (now.wrapping_sub(self.next) as i32) < 0 {
            return false;
        }
        self.next = self.next.wrapping_add(self.period);
        if (now.wrapping_sub(self.next) as i32) >= 0 {
            self.next = now.wrapping_add(self.period);
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reload() {
        assert_eq!(reload_for_1ms(16_000_000), 15_999);
    }

    #[test]
    fn every_is_wrap_safe_and_skips_missed_periods() {
        let start = u32::MAX - 1500;
        let at = |ms: u32| start.wrapping_add(ms);
        let mut e = Every::new(start, 1000);
        assert!(!e.due(at(999)));
        assert!(e.due(at(1000)));
        assert!(!e.due(at(1999)));
        assert!(e.due(at(2000)));
        // A long stall: one `due`, then the next period starts from now.
        assert!(e.due(at(10_500)));
        assert!(!e.due(at(11_000)));
        assert!(e.due(at(11_500)));
    }
}
