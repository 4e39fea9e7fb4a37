//! [`OnceSlot`]: a value written once by whichever context claims the slot first, and
//! read by every context only after it is written — how [`crate::State`] holds its
//! controller.
//!
//! Three stages in one atomic byte (all zeros is empty, so a `static` of it is `.bss`):
//! EMPTY → CLAIMED (one compare-and-swap: the claimer is the only writer, nobody
//! reads) → READY (a release store after the write; readers load it with acquire
//! ordering, so the write happens before their reads). A claim dropped without
//! publishing goes back to EMPTY. The loom model (`src/loom_tests.rs`) checks this.
//!
//! The way back ([`OnceSlot::take_shared`], `State::unsplit`): a fourth stage, TAKING,
//! and a count of the [`Lease`]s alive (references handed out by [`OnceSlot::lease`],
//! which `State::hardware` gives any context). A lease counts itself first, then checks
//! READY; the taker moves READY → TAKING first, then checks that no lease is counted.
//! Both in sequentially consistent order: either the taker sees the lease (and gives
//! up, the value stays) or the lease sees TAKING (and gives up, `None`). So no
//! reference handed out by `lease` outlives the value.

use core::mem::MaybeUninit;
use core::sync::atomic::Ordering;

use crate::sync::{const_fn, AtomicU32, AtomicU8, UnsafeCell};

/// No value (0: all zeros).
const EMPTY: u8 = 0;
/// One context claimed the slot and is writing the value; nobody may read it yet.
const CLAIMED: u8 = 1;
/// The value is written (release store after the write).
const READY: u8 = 2;
/// The value is being moved out by [`OnceSlot::take_shared`]; nobody may read it.
const TAKING: u8 = 3;

/// A value published once (see the [module docs](self)).
pub(crate) struct OnceSlot<T> {
    stage: AtomicU8,
    /// Leases alive ([`OnceSlot::lease`]), plus leases being attempted.
    leases: AtomicU32,
    value: UnsafeCell<MaybeUninit<T>>,
}

// SAFETY: the value is written only by the one context whose `claim` moved the stage
// from EMPTY to CLAIMED, before the release store of READY, and from then on only read
// through `&T` by every context (`T: Sync`) until `take` (or the drop) moves it out
// with `&mut self`, or `take_shared` moves it out when no lease is alive (module docs),
// possibly on another thread than the one that wrote it (`T: Send`): as `OnceLock<T>`.
unsafe impl<T: Send + Sync> Sync for OnceSlot<T> {}

impl<T> OnceSlot<T> {
    const_fn! {
        /// Empty.
        pub(crate) fn new() -> Self {
            OnceSlot {
                stage: AtomicU8::new(EMPTY),
                leases: AtomicU32::new(0),
                value: UnsafeCell::new(MaybeUninit::uninit()),
            }
        }
    }

    /// Claims the empty slot for this context: `None` when another context claimed it
    /// (or it holds a value).
    pub(crate) fn claim(&self) -> Option<Claim<'_, T>> {
        self.stage
            .compare_exchange(EMPTY, CLAIMED, Ordering::Acquire, Ordering::Relaxed)
            .ok()
            .map(|_| Claim { slot: self })
    }

    /// The value, once published (any context).
    #[inline]
    pub(crate) fn get(&self) -> Option<&T> {
        if self.stage.load(Ordering::Acquire) == READY {
            // SAFETY: READY was stored (release) after the value was written, and this
            // load is acquire; nothing writes the value while `&self` lives.
            Some(unsafe { self.get_unchecked() })
        } else {
            None
        }
    }

    /// The value, for any context, counted as a [`Lease`] while the reference lives so
    /// that [`OnceSlot::take_shared`] does not move it out meanwhile.
    pub(crate) fn lease(&self) -> Option<Lease<'_, T>> {
        // Count first, then look (module docs): SeqCst pairs with `take_shared`.
        self.leases.fetch_add(1, Ordering::SeqCst);
        if self.stage.load(Ordering::SeqCst) == READY {
            // SAFETY: READY was stored (release) after the value was written (this
            // SeqCst load acquires it), and the counted lease keeps `take_shared` from
            // moving it out until the lease is dropped.
            Some(Lease {
                slot: self,
                value: unsafe { self.get_unchecked() },
            })
        } else {
            self.leases.fetch_sub(1, Ordering::Release);
            None
        }
    }

    /// Moves the value out through `&self`: `Err(true)` while a [`Lease`] is alive (the
    /// value stays), `Err(false)` when there is no value.
    ///
    /// # Safety
    /// No reference to the value other than the leases exists or will be made from the
    /// value being published: every user of [`OnceSlot::get_unchecked`] is gone (the
    /// split driver's handles, given back to `State::unsplit`), and no `get` reference
    /// is alive.
    pub(crate) unsafe fn take_shared(&self) -> Result<T, bool> {
        if self
            .stage
            .compare_exchange(READY, TAKING, Ordering::SeqCst, Ordering::Relaxed)
            .is_err()
        {
            return Err(false);
        }
        // After TAKING (SeqCst): a lease counted before is seen here; one counted after
        // sees TAKING and gives up. The SeqCst load also acquires the release
        // decrements of leases dropped before it.
        if self.leases.load(Ordering::SeqCst) != 0 {
            self.stage.store(READY, Ordering::Release);
            return Err(true);
        }
        // SAFETY: TAKING excludes new leases and every other taker, no lease is alive,
        // and the caller promises no other reference: the value is moved out once.
        let value = self.value.with(|p| unsafe { (*p).assume_init_read() });
        self.stage.store(EMPTY, Ordering::Release);
        Ok(value)
    }

    /// The value, without looking at the stage.
    ///
    /// # Safety
    /// The value was published, and the publication happens before this call (the
    /// caller was made after it in the publishing thread, and reached its context
    /// through something that synchronises, or loaded READY with acquire ordering).
    #[inline(always)]
    pub(crate) unsafe fn get_unchecked(&self) -> &T {
        // SAFETY: the caller's contract: the value is initialised and not written
        // again while `&self` lives.
        self.value.with(|p| unsafe { &*(*p).as_ptr() })
    }

    /// Puts `value` in a slot owned exclusively (`&mut self`: no other context can
    /// look); a value there before is dropped.
    pub(crate) fn set(&mut self, value: T) -> &T {
        drop(self.take());
        // SAFETY: `&mut self`: no other access; the stage is EMPTY (after `take`).
        self.value.with_mut(|p| unsafe { (*p).write(value) });
        self.stage.store(READY, Ordering::Relaxed);
        // SAFETY: written just above.
        unsafe { self.get_unchecked() }
    }

    /// Moves the value out of a slot owned exclusively; the slot is empty again.
    pub(crate) fn take(&mut self) -> Option<T> {
        if self.stage.load(Ordering::Relaxed) != READY {
            return None;
        }
        self.stage.store(EMPTY, Ordering::Relaxed);
        // SAFETY: the stage was READY: the value is initialised; it is moved out once
        // (the stage is EMPTY now) and `&mut self` excludes every other access.
        Some(self.value.with(|p| unsafe { (*p).assume_init_read() }))
    }
}

impl<T> Drop for OnceSlot<T> {
    fn drop(&mut self) {
        drop(self.take());
    }
}

/// A reference to the controller of a `State` (`State::hardware`), counted while it
/// lives: `State::unsplit` does not take the controller out meanwhile (it refuses with
/// `UnsplitError::Leased`). Dereferences to the controller.
pub struct Lease<'a, T> {
    slot: &'a OnceSlot<T>,
    value: &'a T,
}

impl<T> core::ops::Deref for Lease<'_, T> {
    type Target = T;

    #[inline]
    fn deref(&self) -> &T {
        self.value
    }
}

impl<T> Drop for Lease<'_, T> {
    fn drop(&mut self) {
        // Release: this lease's reads happen before the taker's SeqCst load.
        self.slot.leases.fetch_sub(1, Ordering::Release);
    }
}

impl<T: core::fmt::Debug> core::fmt::Debug for Lease<'_, T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.value.fmt(f)
    }
}

/// The right to write the value of a claimed [`OnceSlot`]; dropped unpublished, it
/// gives the slot back (EMPTY).
pub(crate) struct Claim<'a, T> {
    slot: &'a OnceSlot<T>,
}

impl<'a, T> Claim<'a, T> {
    /// Writes `value`, runs `before` on it while no other context can see it yet, then
    /// publishes it (release). Returns the published value and `before`'s result.
    pub(crate) fn publish<R>(self, value: T, before: impl FnOnce(&T) -> R) -> (&'a T, R) {
        let slot = self.slot;
        core::mem::forget(self);
        // SAFETY: this claim moved the stage from EMPTY to CLAIMED: this is the only
        // writer, and nobody reads before READY.
        slot.value.with_mut(|p| unsafe { (*p).write(value) });
        // SAFETY: written just above, by this context.
        let value = unsafe { slot.get_unchecked() };
        let r = before(value);
        slot.stage.store(READY, Ordering::Release);
        (value, r)
    }
}

impl<T> Drop for Claim<'_, T> {
    fn drop(&mut self) {
        // Nothing was written.
        self.slot.stage.store(EMPTY, Ordering::Release);
    }
}
