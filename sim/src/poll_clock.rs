//! [`PollClock`]: register access to a peripheral model that lets bus time pass while
//! a driver spins on a register — as real time passes while firmware waits for an
//! acknowledge bit. Only back-to-back reads of the same poll register count as a spin:
//! a single read (in an interrupt handler) does not move time.
//!
//! A watchdog bounds the code under test: [`SPIN_LIMIT`] register accesses in a row
//! with no bus time passing (a handler that loops on a register the model never
//! changes, as a receive handler that never releases its FIFO would) panic with the
//! register last accessed, so that a test fails instead of hanging.

use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::vec::Vec;

use crate::{Bus, BusClock};
use twocan_core::registers::Registers;

/// Register accesses in a row, through one [`PollClock`], with the bus time unchanged
/// after which the code under test is taken to spin for ever (see the
/// [module docs](self)). Far above any real sequence: a FlexCAN or bxCAN handler makes
/// a few dozen accesses per frame.
pub const SPIN_LIMIT: u64 = 2_000_000;

/// The simulated bus, shared with the register wrappers that let time pass.
pub type SharedBus = Rc<RefCell<Bus>>;

/// A register handle whose back-to-back reads of a poll register advance the bus by
/// one bit time (see the [module docs](self)).
#[derive(Clone)]
pub struct PollClock<R> {
    regs: R,
    bus: SharedBus,
    /// The bus time, read without borrowing the bus (the watchdog's clock).
    clock: BusClock,
    poll_registers: Vec<usize>,
    /// The poll register read last, if the last access was such a read.
    spinning: Cell<Option<usize>>,
    watchdog: SpinWatchdog,
}

/// The watchdog of [`PollClock`], for other register wrappers of the test suites: counts
/// register accesses made with the bus time unchanged and panics after [`SPIN_LIMIT`]
/// of them, naming the access (see the [module docs](self)).
#[derive(Clone, Debug, Default)]
pub struct SpinWatchdog {
    /// The bus time last seen and the accesses made since it changed.
    seen: Cell<(u64, u64)>,
}

impl SpinWatchdog {
    /// No access seen yet.
    pub const fn new() -> Self {
        SpinWatchdog {
            seen: Cell::new((0, 0)),
        }
    }

    /// Counts one access (`what`, e.g. "read", of register `offset`) at bus time `now`
    /// (`None` when the caller cannot look at the bus: its time cannot move then, so the
    /// access counts against the time last seen). Panics after [`SPIN_LIMIT`] accesses
    /// in a row at one bus time.
    #[track_caller]
    pub fn access(&self, now: Option<u64>, what: &str, offset: usize) {
        let (seen, count) = self.seen.get();
        let now = now.unwrap_or(seen);
        let count = if seen == now { count + 1 } else { 0 };
        self.seen.set((now, count));
        if count >= SPIN_LIMIT {
            panic!(
                "watchdog: {count} register accesses with no bus time passing \
                 (at bit time {now}, last a {what} of offset 0x{offset:03X}): the code \
                 under test waits for a register that never changes"
            );
        }
    }
}

impl<R> core::fmt::Debug for PollClock<R> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("PollClock")
            .field("poll_registers", &self.poll_registers)
            .finish_non_exhaustive()
    }
}

impl<R> PollClock<R> {
    /// Wraps `regs`; back-to-back reads of `poll_register` advance `bus` by one bit time.
    pub fn new(regs: R, bus: &SharedBus, poll_register: usize) -> Self {
        Self::with_poll_registers(regs, bus, &[poll_register])
    }

    /// Wraps `regs`; back-to-back reads of any one of `poll_registers` advance `bus` by
    /// one bit time (FlexCAN: `MCR` for the mode acknowledges, `ESR1` for `SYNCH`).
    pub fn with_poll_registers(regs: R, bus: &SharedBus, poll_registers: &[usize]) -> Self {
        PollClock {
            regs,
            bus: bus.clone(),
            clock: bus.borrow().clock(),
            poll_registers: poll_registers.to_vec(),
            spinning: Cell::new(None),
            watchdog: SpinWatchdog::new(),
        }
    }

    /// The wrapped register access (the model handle).
    pub fn inner(&self) -> &R {
        &self.regs
    }

    /// Lets time pass on `bus` from now on: for a model moved to another bus (a new bus
    /// at another bit rate, brought to the same time, with the model attached to it).
    pub fn set_bus(&mut self, bus: &SharedBus) {
        self.bus = bus.clone();
        self.clock = bus.borrow().clock();
        self.spinning.set(None);
    }
}

impl<R> PollClock<R> {
    /// Counts one access ([`SpinWatchdog::access`]) at the bus time, read through the
    /// bus's [`BusClock`]: also while the bus is borrowed (an access from inside a bus
    /// step, a handler run from a node's hook, where the time moves from one hook to the
    /// next but not within one).
    fn watch(&self, what: &str, offset: usize) {
        self.watchdog.access(Some(self.clock.now()), what, offset);
    }
}

impl<R: Registers> Registers for PollClock<R> {
    fn read32(&self, offset: usize) -> u32 {
        self.watch("read", offset);
        if self.poll_registers.contains(&offset) {
            if self.spinning.replace(Some(offset)) == Some(offset) {
                if let Ok(mut bus) = self.bus.try_borrow_mut() {
                    bus.run_for(1);
                }
            }
        } else {
            self.spinning.set(None);
        }
        self.regs.read32(offset)
    }

    fn write32(&self, offset: usize, value: u32) {
        self.watch("write", offset);
        self.spinning.set(None);
        self.regs.write32(offset, value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One register that never changes.
    struct Constant;
    impl Registers for Constant {
        fn read32(&self, _offset: usize) -> u32 {
            1
        }
        fn write32(&self, _offset: usize, _value: u32) {}
    }

    fn clock() -> PollClock<Constant> {
        let bus: SharedBus = Rc::new(RefCell::new(Bus::new(500_000).expect("bus")));
        PollClock::new(Constant, &bus, 0x04)
    }

    #[test]
    #[should_panic(expected = "watchdog: ")]
    fn a_spin_on_a_register_that_never_changes_fails() {
        let c = clock();
        for _ in 0..=SPIN_LIMIT {
            c.read32(0x0C);
        }
    }

    /// A handler run from inside a bus step (the bus borrowed, as a node's hook runs it)
    /// that spins is caught too: the bus time cannot move while it is borrowed.
    #[test]
    #[should_panic(expected = "watchdog: ")]
    fn a_spin_inside_a_bus_step_fails() {
        let c = clock();
        let _step = c.bus.borrow_mut();
        for _ in 0..=SPIN_LIMIT {
            c.read32(0x0C);
        }
    }

    #[test]
    fn accesses_with_time_passing_are_not_a_spin() {
        let c = clock();
        for _ in 0..3 {
            for _ in 0..SPIN_LIMIT / 2 {
                c.read32(0x0C);
            }
            c.bus.borrow_mut().run_for(1);
        }
    }
}
