//! loom models of the lock-free structures (issue 26): every interleaving (within
//! loom's preemption bound) of their real code, with loom's atomics and cells
//! ([`crate::sync`]). Built and run only with `--cfg twocan_loom`:
//!
//! ```text
//! RUSTFLAGS="--cfg twocan_loom" CARGO_TARGET_DIR=target/loom \
//!     cargo test -p twocan-core --release --lib loom_tests
//! ```

use loom::sync::Arc;
use loom::thread;

use crate::irq_cell::IrqCell;
use crate::once::OnceSlot;
use crate::spsc::SpscRing;

/// A value whose parts are written one after the other: a reader that could see the
/// slot before the write finished would see them differ (and loom reports the access
/// itself as a race).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Marked(u32, u32);

/// The SPSC ring: the producer pushes three values through a ring of two while the
/// consumer pops; every value arrives once, in order, whole; a full ring refuses and
/// counts.
#[test]
fn spsc_ring_moves_values_in_order() {
    loom::model(|| {
        let ring: Arc<SpscRing<Marked, 2>> = Arc::new(SpscRing::new());
        let producer = {
            let ring = ring.clone();
            thread::spawn(move || {
                let mut refused = 0;
                let mut next = 0;
                while next < 3 {
                    // SAFETY: this thread is the ring's only producer.
                    if unsafe { ring.push(Marked(next, next)) }.is_ok() {
                        next += 1;
                    } else {
                        refused += 1;
                        thread::yield_now();
                    }
                }
                refused
            })
        };
        let mut got = Vec::new();
        while got.len() < 3 {
            // SAFETY: this thread is the ring's only consumer.
            match unsafe { ring.pop() } {
                Some(v) => got.push(v),
                None => thread::yield_now(),
            }
        }
        let refused = producer.join().unwrap();
        assert_eq!(got, [Marked(0, 0), Marked(1, 1), Marked(2, 2)]);
        assert_eq!(ring.stats().overflows, refused);
        assert!(ring.is_empty());
    });
}

/// The publication of the controller (`State::split` / `State::hardware`): a reader
/// sees nothing or the whole value, never a value being written; of two claimers
/// exactly one publishes.
#[test]
fn once_slot_publishes_a_whole_value_once() {
    loom::model(|| {
        let slot: Arc<OnceSlot<Marked>> = Arc::new(OnceSlot::new());
        let claimers: Vec<_> = (0..2u32)
            .map(|i| {
                let slot = slot.clone();
                thread::spawn(move || match slot.claim() {
                    Some(claim) => {
                        let (v, ()) = claim.publish(Marked(i, i), |_| ());
                        assert_eq!(*v, Marked(i, i));
                        true
                    }
                    None => false,
                })
            })
            .collect();
        if let Some(v) = slot.get() {
            assert_eq!(v.0, v.1, "a value seen before it was written whole");
        }
        let won: Vec<bool> = claimers.into_iter().map(|t| t.join().unwrap()).collect();
        assert_eq!(won.iter().filter(|&&w| w).count(), 1, "{won:?}");
        let v = slot.get().expect("published");
        assert_eq!(v.0, v.1);
    });
}

/// A claim given back unpublished (a `split` refused for its queue order) leaves the
/// slot free for the next claimer, and a reader sees nothing meanwhile.
#[test]
fn once_slot_claim_given_back_frees_the_slot() {
    loom::model(|| {
        let slot: Arc<OnceSlot<Marked>> = Arc::new(OnceSlot::new());
        let first = {
            let slot = slot.clone();
            thread::spawn(move || drop(slot.claim()))
        };
        let seen = slot.get().copied();
        first.join().unwrap();
        assert_eq!(seen, None);
        let claim = slot.claim().expect("free again");
        claim.publish(Marked(7, 7), |_| ());
        assert_eq!(slot.get(), Some(&Marked(7, 7)));
    });
}

/// `IrqCell`: a vector that runs while the thread puts the handle sees nothing or the
/// whole handle; two vectors never hold it at once (the second is turned away).
#[test]
fn irq_cell_hands_the_handle_to_one_context_at_a_time() {
    loom::model(|| {
        let cell: Arc<IrqCell<Marked>> = Arc::new(IrqCell::new());
        let vectors: Vec<_> = (0..2)
            .map(|_| {
                let cell = cell.clone();
                thread::spawn(move || {
                    cell.run(|m| {
                        assert_eq!(m.0, m.1, "a handle seen before it was written whole");
                        m.0 += 1;
                        m.1 += 1;
                    })
                })
            })
            .collect();
        let installed = cell.put(Marked(0, 0)).ok().expect("empty");
        drop(installed);
        let ran = vectors
            .into_iter()
            .map(|t| t.join().unwrap())
            .filter(|&r| r)
            .count() as u32;
        assert!(cell.run(|m| assert_eq!(*m, Marked(ran, ran))));
    });
}

/// The way back (`State::unsplit` over `OnceSlot::take_shared`) against a reader in
/// another context (`State::hardware`'s lease): either the reader's lease is seen and
/// the value stays, or the reader sees nothing; a reader never holds a value being
/// moved out (loom reports the access as a race, the check below a torn value).
#[test]
fn once_slot_take_waits_for_leases() {
    loom::model(|| {
        let slot: Arc<OnceSlot<Marked>> = Arc::new(OnceSlot::new());
        slot.claim().expect("empty").publish(Marked(3, 3), |_| ());
        let reader = {
            let slot = slot.clone();
            thread::spawn(move || slot.lease().map(|v| assert_eq!(*v, Marked(3, 3))))
        };
        // SAFETY: no handle exists; the only other reference is the reader's lease.
        let taken = unsafe { slot.take_shared() };
        let read = reader.join().unwrap();
        match taken {
            Ok(v) => assert_eq!(v, Marked(3, 3)),
            Err(leased) => {
                assert!(leased, "the value was there");
                // A reader counted while it looked, then gave up (it saw TAKING),
                // refuses too: the taker tries again, as `unsplit`'s caller does.
                let _ = read;
                // SAFETY: as above; the reader is gone.
                assert_eq!(unsafe { slot.take_shared() }, Ok(Marked(3, 3)));
            }
        }
        assert!(slot.lease().is_none(), "empty after the take");
    });
}

/// `IrqCell::take` (the way back) against a vector running the cell: the vector sees
/// the whole handle or nothing, and the thread takes it only when no vector holds it
/// (a take that finds it running gives up and is tried again).
#[test]
fn irq_cell_take_never_overlaps_a_run() {
    loom::model(|| {
        let cell: Arc<IrqCell<Marked>> = Arc::new(IrqCell::new());
        let _ = cell.put(Marked(1, 1)).ok().expect("empty");
        let vector = {
            let cell = cell.clone();
            thread::spawn(move || {
                cell.run(|m| {
                    assert_eq!(m.0, m.1, "a handle seen torn");
                    m.0 += 1;
                    m.1 += 1;
                })
            })
        };
        let taken = loop {
            if let Some(v) = cell.take() {
                break v;
            }
            thread::yield_now();
        };
        let ran = vector.join().unwrap();
        assert_eq!(taken, if ran { Marked(2, 2) } else { Marked(1, 1) });
        assert!(!cell.run(|_| unreachable!("taken")));
    });
}
