//! The way back from the split driver (issue 22 item 11): `State::unsplit` takes the
//! controller back out of a `static` state given every handle, discards and counts
//! what the rings and the queue still hold, refuses while a `hardware()` reference
//! lives or when a handle is another state's, and leaves the state ready for a new
//! `split`.
#![cfg(feature = "mock")]

use twocan_core::irq_cell::IrqCell;
use twocan_core::mock::MockHardware;
use twocan_core::split::{Rx0Irq, TxIrq};
use twocan_core::{FifoQueue, Frame, Leftovers, State, UnsplitError};

type Q = FifoQueue<4>;
type St = State<MockHardware, 4, Q, 4, 4>;

#[test]
fn unsplit_gives_the_controller_back_and_the_state_splits_again() {
    static CAN: St = State::new();
    static TX_VECTOR: IrqCell<TxIrq<'static, MockHardware, 4, Q, 4, 4>> = IrqCell::new();
    static RX0_VECTOR: IrqCell<Rx0Irq<'static, MockHardware, 4, Q, 4, 4>> = IrqCell::new();

    let mut p = CAN.split(MockHardware::new(1)).ok().unwrap();
    let _ = TX_VECTOR.put(p.tx_irq).ok().unwrap();
    let _ = RX0_VECTOR.put(p.rx0_irq).ok().unwrap();
    // One frame in the mailbox, two in the queue; one sent and completed; one received.
    for id in [0x10, 0x11, 0x12] {
        p.tx.try_send(&Frame::standard(id, &[]).unwrap()).unwrap();
    }
    CAN.hardware().unwrap().complete();
    assert!(TX_VECTOR.run(|h| h.on_interrupt()));
    CAN.hardware()
        .unwrap()
        .deliver(Frame::standard(0x20, &[1]).unwrap());
    assert!(RX0_VECTOR.run(|h| h.on_interrupt()));

    // The handlers come back out of their cells: the vectors do nothing from now on.
    let tx_irq = TX_VECTOR.take().expect("installed");
    let rx0_irq = RX0_VECTOR.take().expect("installed");
    assert!(!TX_VECTOR.run(|_| unreachable!("taken")));
    assert!(!RX0_VECTOR.run(|_| unreachable!("taken")));

    let lease = CAN.hardware().unwrap();
    let parts = twocan_core::Parts {
        tx_irq,
        rx0_irq,
        ..p
    };
    let Err((e, parts)) = CAN.unsplit(parts) else {
        panic!("taken while a lease is alive")
    };
    assert_eq!(e, UnsplitError::Leased);
    assert_eq!(lease.sent().len(), 1, "the controller stayed in place");
    drop(lease);

    let (hw, left) = CAN.unsplit(parts).ok().expect("every handle is here");
    assert_eq!(
        left,
        Leftovers {
            queued: 1,
            received: 1,
            completions: 1,
            state_changes: 0
        }
    );
    assert_eq!(hw.sent().len(), 1);
    assert!(CAN.hardware().is_none(), "the state is empty again");
    assert_eq!(CAN.tx_stats().count, 0);

    // Split again (a controller begun again): a clean state, the counters kept.
    let mut p = CAN.split(MockHardware::new(1)).ok().unwrap();
    assert_eq!(p.rx.available(), 0);
    assert!(p.tx.take_completion().is_none());
    p.tx.try_send(&Frame::standard(0x30, &[]).unwrap()).unwrap();
    CAN.hardware().unwrap().complete();
    p.tx_irq.on_interrupt();
    let c =
        p.tx.take_completion()
            .expect("a completion in the new session");
    assert_eq!(c.outcome, twocan_core::TxOutcome::Sent);
    assert_eq!(CAN.traffic().sent, 2);
}

#[test]
fn handles_of_another_state_are_refused() {
    static A: St = State::new();
    static B: St = State::new();
    let pa = A.split(MockHardware::new(1)).ok().unwrap();
    let pb = B.split(MockHardware::new(1)).ok().unwrap();
    let mixed = twocan_core::Parts { rx: pb.rx, ..pa };
    let Err((e, _)) = A.unsplit(mixed) else {
        panic!("B's receive half accepted")
    };
    assert_eq!(e, UnsplitError::Foreign);
    assert!(A.hardware().is_some(), "A keeps its controller");
}
