//! The atomics and the cell of the lock-free structures that the loom models check
//! ([`crate::spsc::SpscRing`], [`crate::once::OnceSlot`], [`crate::irq_cell::IrqCell`]):
//! `core`'s, or loom's in the crate's own tests built with `--cfg twocan_loom`
//! (`src/loom_tests.rs`, run by `.ci/run`). No other build sees loom.
//!
//! [`UnsafeCell`] has loom's access API (`with`, `with_mut`: the raw pointer is valid
//! inside the closure), so that loom can see every access; with `core`'s cell the
//! closures compile to the plain pointer access.

#[cfg(not(all(test, twocan_loom)))]
pub(crate) use core::sync::atomic::{AtomicU32, AtomicU8};
#[cfg(all(test, twocan_loom))]
pub(crate) use loom::sync::atomic::{AtomicU32, AtomicU8};

#[cfg(all(test, twocan_loom))]
pub(crate) use loom::cell::UnsafeCell;

/// `core::cell::UnsafeCell` with loom's access API.
#[cfg(not(all(test, twocan_loom)))]
#[repr(transparent)]
pub(crate) struct UnsafeCell<T>(core::cell::UnsafeCell<T>);

#[cfg(not(all(test, twocan_loom)))]
impl<T> UnsafeCell<T> {
    #[inline(always)]
    pub(crate) const fn new(value: T) -> Self {
        UnsafeCell(core::cell::UnsafeCell::new(value))
    }

    /// Runs `f` with a pointer for reading.
    #[inline(always)]
    pub(crate) fn with<R>(&self, f: impl FnOnce(*const T) -> R) -> R {
        f(self.0.get())
    }

    /// Runs `f` with a pointer for writing.
    #[inline(always)]
    pub(crate) fn with_mut<R>(&self, f: impl FnOnce(*mut T) -> R) -> R {
        f(self.0.get())
    }
}

/// Declares a `const fn`, which loom's types (not `const`-constructible) turn into a
/// plain `fn` in the loom build.
macro_rules! const_fn {
    ($(#[$m:meta])* $vis:vis fn $name:ident() -> $ret:ty $body:block) => {
        #[cfg(not(all(test, twocan_loom)))]
        $(#[$m])*
        $vis const fn $name() -> $ret $body
        #[cfg(all(test, twocan_loom))]
        $(#[$m])*
        $vis fn $name() -> $ret $body
    };
}
pub(crate) use const_fn;
