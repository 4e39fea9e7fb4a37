//! [`IrqCell`]: a place in a `static` where thread code puts an interrupt handler's
//! handle (once) and the interrupt vector runs it, without a critical section and
//! without `unsafe` in the application.
//!
//! The split driver's interrupt handles ([`crate::split::TxIrq`], ...) need `&mut`
//! access from their vector. With RTIC they are task-local resources; with plain
//! `cortex-m-rt` vectors, put them in an `IrqCell`, then enable the lines that run it
//! with the [`Installed`] token that [`IrqCell::put`] returns:
//!
//! ```
//! use twocan_core::irq_cell::{IrqCell, Nvic};
//!
//! # #[derive(Default)] struct Recorded(Vec<String>);
//! # impl Nvic<u16> for Recorded {
//! #     fn set_priority(&mut self, line: u16, priority: u8) { self.0.push(format!("priority {line} {priority}")) }
//! #     fn unmask(&mut self, line: u16) { self.0.push(format!("unmask {line}")) }
//! # }
//! static COUNTER: IrqCell<u32> = IrqCell::new();
//! // In the vector (here: called by hand): nothing runs before `put`.
//! assert!(!COUNTER.run(|c| *c += 1));
//! let installed = COUNTER.put(41).unwrap();
//! assert!(COUNTER.put(7).is_err(), "once only");
//! // The lines that run the cell are unmasked only now, all at one priority.
//! let mut nvic = Recorded::default(); // firmware: its NVIC, behind this trait
//! installed.enable(&mut nvic, &[20, 21], 0x40);
//! assert_eq!(nvic.0, ["priority 20 64", "priority 21 64", "unmask 20", "unmask 21"]);
//! assert!(COUNTER.run(|c| *c += 1));
//! COUNTER.run(|c| assert_eq!(*c, 42));
//! ```
//!
//! Soundness: [`IrqCell::run`] takes a busy flag with one atomic compare-and-swap
//! before it hands out `&mut`; a second context that tries while the first runs (a
//! preempting interrupt routed to the same cell, a host thread) is turned away
//! (`false`) rather than given an aliasing reference.
//!
//! **One priority per cell.** A context turned away leaves its interrupt's cause set;
//! a level-triggered line then fires again at once, and if it preempted the context
//! that holds the cell, that context never resumes: a livelock. Lines that run one
//! cell (FlexCAN's four status lines run one status handler) must therefore never
//! preempt each other: give them one priority. [`Installed::enable`], the way this
//! module offers to unmask a cell's lines, sets the one priority on every line before
//! it unmasks any; `twocan-flexcan`'s `rt` entry points do the same. Lines of different
//! cells may have different priorities.

use core::mem::MaybeUninit;
use core::sync::atomic::Ordering;

use crate::sync::{const_fn, AtomicU8, UnsafeCell};

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
        if matches!(self.state.load(Ordering::Relaxed), READY | BUSY) {
            // SAFETY: READY (or BUSY, left by a `run` that panicked) is stored only
            // after the value was written; `&mut self` excludes every other access,
            // and the value is dropped once, here.
            self.value.with_mut(|p| unsafe { (*p).assume_init_drop() });
        }
    }
}

impl<T> Default for IrqCell<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T> IrqCell<T> {
    const_fn! {
        /// Empty (all zeros, `.bss`).
        pub fn new() -> Self {
            IrqCell {
                state: AtomicU8::new(EMPTY),
                value: UnsafeCell::new(MaybeUninit::uninit()),
            }
        }
    }

    /// Puts the handle in place (once); gives it back if the cell is not empty. The
    /// [`Installed`] token it returns is what enables the interrupt lines that run the
    /// cell ([`Installed::enable`]): they can so be unmasked only once the handle is
    /// in place.
    pub fn put(&self, value: T) -> Result<Installed<'_, T>, T> {
        if self
            .state
            .compare_exchange(EMPTY, WRITING, Ordering::Acquire, Ordering::Relaxed)
            .is_err()
        {
            return Err(value);
        }
        // SAFETY: this call moved the state from EMPTY to WRITING: no other `put` writes
        // and no `run` reads the value until READY is stored below (release; `run`
        // acquires it).
        self.value.with_mut(|p| unsafe { (*p).write(value) });
        self.state.store(READY, Ordering::Release);
        Ok(Installed { cell: self })
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
        self.value
            .with_mut(|p| f(unsafe { (*p).assume_init_mut() }));
        self.state.store(READY, Ordering::Release);
        true
    }

    /// Takes the handle back out (the way back of `State::unsplit`): the cell is empty
    /// again, and a vector that runs it from now on does nothing. `None` when the cell
    /// is empty or a context is running it at this moment (a handler preempted by the
    /// caller; try again once it returned). Mask the lines that run the cell first, so
    /// that none of them is left asserted with nobody to clear its cause.
    pub fn take(&self) -> Option<T> {
        // READY -> WRITING: no `run` and no `put` touches the value meanwhile.
        if self
            .state
            .compare_exchange(READY, WRITING, Ordering::Acquire, Ordering::Relaxed)
            .is_err()
        {
            return None;
        }
        // SAFETY: WRITING, taken from READY by this call: the value is initialised and
        // this is the only context that reaches it; it is moved out once (EMPTY next).
        let value = self.value.with(|p| unsafe { (*p).assume_init_read() });
        self.state.store(EMPTY, Ordering::Release);
        Some(value)
    }

    /// Whether a handle was put in place.
    pub fn is_ready(&self) -> bool {
        matches!(self.state.load(Ordering::Acquire), READY | BUSY)
    }
}

/// The interrupt controller, as far as enabling the lines of a cell goes: the priority
/// of a line and its unmasking. Firmware implements it for its NVIC (with
/// `cortex_m::peripheral::NVIC::set_priority` and `NVIC::unmask`, whose safety
/// conditions — no critical section built from NVIC masks or priorities is broken —
/// the implementation states); host tests record the calls. `L` is the line
/// (a device interrupt number, e.g. a PAC's `Interrupt`).
pub trait Nvic<L: Copy> {
    /// Sets the priority of `line` (0 highest on Cortex-M).
    fn set_priority(&mut self, line: L, priority: u8);
    /// Unmasks `line`.
    fn unmask(&mut self, line: L);
}

/// Proof that an [`IrqCell`] holds its handle, returned by [`IrqCell::put`] only: the
/// way to unmask the interrupt lines that run the cell, so that no line is unmasked
/// before the handle its vector runs is in place (a line whose cause nobody clears
/// stays asserted for ever).
#[must_use = "the lines that run the cell stay masked until `Installed::enable`"]
pub struct Installed<'a, T> {
    cell: &'a IrqCell<T>,
}

impl<T> Installed<'_, T> {
    /// Gives every line of `lines` — the lines whose vectors run this cell — the one
    /// `priority`, then unmasks them: lines that share a cell never preempt each
    /// other (see the [module docs](self), "One priority per cell").
    pub fn enable<L: Copy>(self, nvic: &mut impl Nvic<L>, lines: &[L], priority: u8) {
        debug_assert!(self.cell.is_ready());
        for &line in lines {
            nvic.set_priority(line, priority);
        }
        for &line in lines {
            nvic.unmask(line);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn take_empties_the_cell_and_put_fills_it_again() {
        let cell: IrqCell<u32> = IrqCell::new();
        assert_eq!(cell.take(), None);
        let _ = cell.put(5).unwrap();
        assert!(cell.run(|v| {
            assert_eq!(cell.take(), None, "not while it runs");
            *v += 1;
        }));
        assert_eq!(cell.take(), Some(6));
        assert!(!cell.is_ready());
        assert!(!cell.run(|_| unreachable!("taken")));
        let _ = cell.put(7).unwrap();
        assert!(cell.run(|v| assert_eq!(*v, 7)));
    }

    #[test]
    fn a_second_context_is_turned_away_while_the_first_runs() {
        let cell: IrqCell<u32> = IrqCell::new();
        let _ = cell.put(1).unwrap();
        assert!(cell.run(|v| {
            assert!(!cell.run(|_| unreachable!("aliasing")));
            *v += 1;
        }));
        assert!(cell.run(|v| assert_eq!(*v, 2)));
    }

    /// A priority-preemptive interrupt controller with level-triggered lines, enough to
    /// show what two lines that run one cell do (Cortex-M NVIC rules: a pending line
    /// preempts the running handler only at a strictly higher priority, i.e. a lower
    /// number; otherwise it runs when the handler returns, while its cause is set).
    struct Lines {
        priority: [core::cell::Cell<u8>; 2],
        cause: [core::cell::Cell<bool>; 2],
        running: core::cell::RefCell<Vec<u8>>,
        entries: core::cell::Cell<u32>,
    }

    /// Entries into the vectors after which the simulation calls it a livelock.
    const LIVELOCK: u32 = 1_000;

    impl Nvic<usize> for Lines {
        fn set_priority(&mut self, line: usize, priority: u8) {
            self.priority[line].set(priority);
        }
        fn unmask(&mut self, _: usize) {}
    }

    impl Lines {
        fn new() -> Self {
            Lines {
                priority: Default::default(),
                cause: Default::default(),
                running: Default::default(),
                entries: Default::default(),
            }
        }

        /// Line `line`'s cause is raised (by the hardware).
        fn raise(&self, line: usize, cell: &IrqCell<u32>) {
            self.cause[line].set(true);
            let preempts = match self.running.borrow().last() {
                None => true,
                Some(&p) => self.priority[line].get() < p,
            };
            if preempts {
                self.enter(line, cell);
            }
        }

        /// Runs `line`'s vector while its cause is set, then what is pending.
        fn enter(&self, line: usize, cell: &IrqCell<u32>) {
            self.running.borrow_mut().push(self.priority[line].get());
            while self.cause[line].get() && self.entries.get() < LIVELOCK {
                self.entries.set(self.entries.get() + 1);
                // The vector: the shared handler acknowledges both lines' causes; in
                // its first run line 1's cause is raised again (a new event).
                cell.run(|runs| {
                    *runs += 1;
                    if *runs == 1 {
                        self.raise(1, cell);
                    }
                    self.cause[0].set(false);
                    self.cause[1].set(false);
                });
            }
            self.running.borrow_mut().pop();
            if self.running.borrow().is_empty() {
                for l in 0..2 {
                    if self.cause[l].get() {
                        self.enter(l, cell);
                    }
                }
            }
        }
    }

    #[test]
    fn lines_of_one_cell_enabled_together_never_livelock() {
        let cell: IrqCell<u32> = IrqCell::new();
        let mut lines = Lines::new();
        cell.put(0).unwrap().enable(&mut lines, &[0, 1], 0x40);
        lines.raise(0, &cell);
        assert!(lines.entries.get() < LIVELOCK);
        assert!(
            !lines.cause[0].get() && !lines.cause[1].get(),
            "both causes handled"
        );
        assert!(cell.run(|runs| assert_eq!(*runs, 1)));
    }

    #[test]
    fn lines_of_one_cell_at_two_priorities_would_livelock() {
        // What `Installed::enable` rules out: line 1 above line 0 (set around it).
        let cell: IrqCell<u32> = IrqCell::new();
        let mut lines = Lines::new();
        cell.put(0).unwrap().enable(&mut lines, &[0, 1], 0x40);
        lines.set_priority(1, 0x20);
        lines.raise(0, &cell);
        assert_eq!(lines.entries.get(), LIVELOCK, "turned away for ever");
    }
}
