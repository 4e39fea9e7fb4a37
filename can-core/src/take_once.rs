//! [`TakeOnce`]: a `static` value lent once as `&'static mut` — working memory that
//! firmware keeps out of the stack (the bxCAN and FlexCAN planners' scratch, about
//! 90 KB, planned into at run time: issue 21), without `static mut` and without a
//! critical section around its use.
//!
//! ```
//! use twocan_core::TakeOnce;
//!
//! static BUFFER: TakeOnce<[u32; 1024]> = TakeOnce::new([0; 1024]);
//!
//! let buf: &'static mut [u32; 1024] = BUFFER.take().expect("first take");
//! buf[0] = 7;
//! assert!(BUFFER.take().is_none(), "lent once only");
//! ```

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, Ordering};

/// A value in a `static`, lent once as `&'static mut` by [`TakeOnce::take`] (one
/// compare-and-swap: of several contexts racing, one gets it). A `const` initial value
/// of zeros puts it in `.bss` (RAM, no flash image).
pub struct TakeOnce<T> {
    taken: AtomicBool,
    value: UnsafeCell<T>,
}

// SAFETY: the value is reached only through the one `&mut T` that `take` hands out (the
// compare-and-swap lets one caller through), which may go to another thread: `T: Send`.
unsafe impl<T: Send> Sync for TakeOnce<T> {}

impl<T> TakeOnce<T> {
    /// Holding `value`, not lent yet.
    pub const fn new(value: T) -> Self {
        TakeOnce {
            taken: AtomicBool::new(false),
            value: UnsafeCell::new(value),
        }
    }

    /// The value, the first time (`None` ever after).
    // `&'static self` lends `&'static mut T`: the compare-and-swap makes it unique.
    #[allow(clippy::mut_from_ref)]
    pub fn take(&'static self) -> Option<&'static mut T> {
        self.taken
            .compare_exchange(false, true, Ordering::Acquire, Ordering::Relaxed)
            .ok()?;
        // SAFETY: the compare-and-swap succeeded for this caller only, once: no other
        // reference to the value exists or will be made, and it lives in a `static`.
        Some(unsafe { &mut *self.value.get() })
    }
}

#[cfg(test)]
mod tests {
    use super::TakeOnce;

    #[test]
    fn lends_once() {
        static V: TakeOnce<[u8; 4]> = TakeOnce::new([0; 4]);
        let v = V.take().unwrap();
        v[1] = 9;
        assert!(V.take().is_none());
        assert_eq!(v, &[0, 9, 0, 0]);
    }
}
