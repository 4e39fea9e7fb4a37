//! A driver shared between thread code and its interrupt handler: the handler calls
//! [`SharedDriver::on_interrupt`], the main loop works on the driver inside
//! [`SharedDriver::with`]. The driver sits in a `critical_section::Mutex` (no
//! `static mut`); on the single-core Kinetis the critical section masks interrupts.

use core::cell::RefCell;

use critical_section::Mutex;
use twocan_core::{Controller, Driver};

/// A [`Driver`] that a `static` can hold.
pub struct SharedDriver<C: Controller, const RX: usize, const TX: usize> {
    inner: Mutex<RefCell<Option<Driver<C, RX, TX>>>>,
}

impl<C: Controller, const RX: usize, const TX: usize> SharedDriver<C, RX, TX> {
    /// Empty: the interrupt handler does nothing until [`SharedDriver::install`].
    pub const fn new() -> Self {
        SharedDriver {
            inner: Mutex::new(RefCell::new(None)),
        }
    }

    /// Puts the driver in place; gives it back if one is there already (the error hands
    /// the whole driver back, so it is as large as the driver).
    #[allow(clippy::result_large_err)]
    pub fn install(&self, driver: Driver<C, RX, TX>) -> Result<(), Driver<C, RX, TX>> {
        critical_section::with(|cs| {
            let mut slot = self.inner.borrow_ref_mut(cs);
            if slot.is_some() {
                Err(driver)
            } else {
                *slot = Some(driver);
                Ok(())
            }
        })
    }

    /// Runs `f` on the driver in a critical section; `None` before `install`.
    pub fn with<R>(&self, f: impl FnOnce(&mut Driver<C, RX, TX>) -> R) -> Option<R> {
        critical_section::with(|cs| self.inner.borrow_ref_mut(cs).as_mut().map(f))
    }

    /// The interrupt handler's work ([`Driver::on_interrupt`]); `false` before `install`.
    pub fn on_interrupt(&self) -> bool {
        self.with(|d| d.on_interrupt()).is_some()
    }
}

impl<C: Controller, const RX: usize, const TX: usize> Default for SharedDriver<C, RX, TX> {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use twocan_core::mock::MockController;
    use twocan_core::TxPolicy;

    type Mock = MockController<3, 4>;

    #[test]
    fn install_once_then_use() {
        static SHARED: SharedDriver<Mock, 8, 4> = SharedDriver::new();
        assert!(!SHARED.on_interrupt());
        assert_eq!(SHARED.with(|_| ()), None);
        assert!(SHARED
            .install(Driver::new(Mock::new(TxPolicy::Fifo)))
            .is_ok());
        assert!(SHARED
            .install(Driver::new(Mock::new(TxPolicy::Fifo)))
            .is_err());
        assert!(SHARED.on_interrupt());
        assert_eq!(SHARED.with(|d| d.traffic().sent), Some(0));
    }
}
