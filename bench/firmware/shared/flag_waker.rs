//! A waker that only raises a flag: enough for a hand-rolled poll loop (no executor) in
//! the async bench firmwares (`insn-count-async`, `loopback-async`), included with
//! `#[path]`.

use core::sync::atomic::{AtomicBool, Ordering};
use core::task::{RawWaker, RawWakerVTable, Waker};

/// Set by a wake, cleared by [`take`].
static WOKEN: AtomicBool = AtomicBool::new(false);

fn clone(_: *const ()) -> RawWaker {
    RawWaker::new(core::ptr::null(), &VTABLE)
}

fn wake(_: *const ()) {
    WOKEN.store(true, Ordering::Relaxed);
}

fn drop_waker(_: *const ()) {}

static VTABLE: RawWakerVTable = RawWakerVTable::new(clone, wake, wake, drop_waker);

/// The waker.
pub fn waker() -> Waker {
    // SAFETY: the vtable's functions ignore the data pointer (null), own no resource,
    // and are safe to call from any context: the `RawWaker` contract holds.
    unsafe { Waker::from_raw(RawWaker::new(core::ptr::null(), &VTABLE)) }
}

/// Whether a wake came since the last call.
pub fn take() -> bool {
    WOKEN.swap(false, Ordering::Relaxed)
}
