//! [`IrqCell`]: a place in a `static` where thread code puts an interrupt handler's
//! handle (once) and the interrupt vector runs it, without a critical section and
//! without `unsafe` in the application.
//!
//! The split driver's interrupt handles ([`crate::split::TxIrq`], ...) need `&mut`
//! access from their vector. With RTIC they are task-local resources; with plain
//! `cortex-m-rt` vectors, put them in an `IrqCell` before enabling the interrupt line:
//!
//! ```
//! use twocan_core::irq_cell::IrqCell;
//!
//! static COUNTER: IrqCell<u32> = IrqCell::new();
//! // In the vector (here: called by hand): nothing runs before `put`.
//! assert!(!COUNTER.run(|c| *c += 1));
//! COUNTER.put(41).unwrap();
//! assert!(COUNTER.run(|c| *c += 1));
//! assert!(COUNTER.put(7).is_err(), "once only");
//! COUNTER.run(|c| assert_eq!(*c, 42));
//! ```
//!
//! Soundness: [`IrqCell::run`] takes a busy flag with one atomic swap before it hands
//! out `&mut`; a second context that tries while the first runs (a preempting
//! interrupt routed to the same cell, a host thread) is turned away (`false`) rather
//! than given an aliasing reference. With one vector per cell that never happens.

use core::cell::UnsafeCell;
use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicU8, Ordering};

const EMPTY: u8 = 0;
const WRITING: u8 = 1;
const READY: u8 = 2;
const BUSY: u8 = 3;

/// A value that one interrupt vector runs (see the [module docs](self)).
pub struct IrqCell<T> {
    state: AtomicU8,
    value: UnsafeCell<MaybeUninit<T>>,
}

// SAFETY: the value is written once by the context whose `put` moved the state from
// EMPTY to WRITING, and reached afterwards only through `run`, which gives `&mut T` to
// one context at a time (the BUSY state, taken by compare-and-swap; release/acquire
// orders each context's accesses after the previous one's). Like `Mutex<T>`, sharing
// the cell hands the value itself (not `&T`) from context to context: `T: Send`, and no
// `T: Sync` is needed because no two contexts hold a reference at once.
unsafe impl<T: Send> Sync for IrqCell<T> {}

impl<T> Drop for IrqCell<T> {
    fn drop(&mut self) {
        if matches!(*self.state.get_mut(), READY | BUSY) {
            // SAFETY: READY (or BUSY, left by a `run` that panicked) is stored only
            // after the value was written; `&mut self` excludes every other access,
            // and the value is dropped once, here.
            unsafe { self.value.get_mut().assume_init_drop() };
        }
    }
}

impl<T> Default for IrqCell<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T> IrqCell<T> {
    /// Empty (all zeros, `.bss`).
    pub const fn new() -> Self {
        IrqCell {
            state: AtomicU8::new(EMPTY),
            value: UnsafeCell::new(MaybeUninit::uninit()),
        }
    }

    /// Puts the handle in place (once); gives it back if the cell is not empty.
    pub fn put(&self, value: T) -> Result<(), T> {
        if self
            .state
            .compare_exchange(EMPTY, WRITING, Ordering::Acquire, Ordering::Relaxed)
            .is_err()
        {
            return Err(value);
        }
        // SAFETY: the WRITING state excludes every other access to `value`.
        unsafe { (*self.value.get()).write(value) };
        self.state.store(READY, Ordering::Release);
        Ok(())
    }

    /// Runs `f` on the handle; `false` (and `f` not run) when the cell is empty or
    /// another context is running it.
    #[inline]
    pub fn run(&self, f: impl FnOnce(&mut T)) -> bool {
        if self
            .state
            .compare_exchange(READY, BUSY, Ordering::Acquire, Ordering::Relaxed)
            .is_err()
        {
            return false;
        }
        // SAFETY: the BUSY state makes this the only reference to the value, which
        // READY guarantees is initialised.
        f(unsafe { (*self.value.get()).assume_init_mut() });
        self.state.store(READY, Ordering::Release);
        true
    }

    /// Whether a handle was put in place.
    pub fn is_ready(&self) -> bool {
        matches!(self.state.load(Ordering::Acquire), READY | BUSY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_context_is_turned_away_while_the_first_runs() {
        let cell: IrqCell<u32> = IrqCell::new();
        cell.put(1).unwrap();
        assert!(cell.run(|v| {
            assert!(!cell.run(|_| unreachable!("aliasing")));
            *v += 1;
        }));
        assert!(cell.run(|v| assert_eq!(*v, 2)));
    }
}
