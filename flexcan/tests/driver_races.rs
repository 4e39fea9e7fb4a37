//! The abort and ESR1 acknowledge races through the real driver over the model (the
//! model is not atomic: `Bus::run_bits` stops inside a frame, so driver register
//! accesses interleave with the frame on the wire).
//!
//! - Abort (Kinetis RM "Transmission abort mechanism", MCR\[AEN\] = 1): an ABORT written
//!   while the mailbox transmits waits for the frame's outcome; the driver must take the
//!   outcome from the mailbox CODE after IFLAG (INACTIVE = sent, ABORT = aborted), not
//!   from having written ABORT.
//! - ESR1 (Kinetis RM "Error and Status 1 register"): ERRINT/BOFFINT are
//!   write-1-to-clear and the error bits clear on read. The driver writes back exactly
//!   the flags it read; an error raised between its read and its write-back whose flag
//!   was already set loses that flag to the write-back, but its error bits stay in ESR1
//!   and the driver must still count it.
#![cfg(feature = "model")]

mod common;

use std::cell::RefCell;
use std::rc::Rc;

use common::*;
use twocan_core::registers::Registers;
use twocan_core::{AbortRequest, Driver, TxOutcome};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::regs;
use twocan_flexcan::{Board, FlexCan, FlexCanHw, HostSystem, Instance, Settings, Target};
use twocan_sim::{Bus, Fault, SimNode};

/// Runs bit by bit until the bus is inside a frame (bounded).
fn until_in_frame(bus: &mut Bus) {
    for _ in 0..200 {
        if bus.in_frame() {
            return;
        }
        bus.run_bits(1);
    }
    panic!("no frame started");
}

#[test]
fn abort_while_the_frame_is_on_the_wire_completes_as_sent() {
    let (model, mut can) = begin::<32, 16>(&Settings::new(500_000), &[], &[]).unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    let peer = SimNode::new().shared();
    bus.attach("peer", peer.clone());
    let f = std_data(0x123, &[1, 2, 3]);
    let t = can.try_send(&f).unwrap();
    until_in_frame(&mut bus);
    // Some bits into the frame (past arbitration): the mailbox is transmitting.
    bus.run_bits(20);
    assert!(bus.in_frame(), "still on the wire");
    assert_eq!(can.abort(t), AbortRequest::Requested);
    bus.run_until_idle(10_000).unwrap();
    can.on_interrupt();
    let c = can.take_completion().expect("one completion");
    assert_eq!((c.token, c.outcome), (t, TxOutcome::Sent));
    assert!(can.take_completion().is_none(), "exactly one completion");
    let tr = can.traffic();
    assert_eq!((tr.sent, tr.aborted, tr.failed), (1, 0, 0));
    assert_eq!(peer.borrow().received_frames(), vec![f], "one copy");
    // Nothing more goes out later (no retransmission of a frame counted aborted).
    run1(&mut bus, &mut can, 1_000);
    assert_eq!(peer.borrow().received_frames().len(), 1);
}

#[test]
fn abort_before_start_of_frame_completes_as_aborted() {
    let (model, mut can) = begin::<32, 16>(&Settings::new(500_000), &[], &[]).unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    let peer = SimNode::new().shared();
    bus.attach("peer", peer.clone());
    let t = can.try_send(&std_data(0x124, &[4])).unwrap();
    assert!(!bus.in_frame());
    assert_eq!(can.abort(t), AbortRequest::Requested);
    bus.run_until_idle(10_000).unwrap();
    run1(&mut bus, &mut can, 1_000);
    let c = can.take_completion().expect("one completion");
    assert_eq!((c.token, c.outcome), (t, TxOutcome::Aborted));
    let tr = can.traffic();
    assert_eq!((tr.sent, tr.aborted), (0, 1));
    assert!(peer.borrow().received_frames().is_empty(), "no copy");
    assert!(bus.trace().records().is_empty(), "nothing on the wire");
}

/// An event run once between the driver's read of a register and its write-back.
type Hook = Rc<RefCell<Option<Box<dyn FnMut()>>>>;

/// Register access to the model that runs `hook` just before a write to `ESR1`, i.e.
/// between the driver's read of `ESR1` and its write-back.
#[derive(Clone)]
struct InjectBeforeEsr1Write {
    inner: Ticking,
    hook: Hook,
}

impl std::fmt::Debug for InjectBeforeEsr1Write {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("InjectBeforeEsr1Write")
            .finish_non_exhaustive()
    }
}

impl Registers for InjectBeforeEsr1Write {
    fn read32(&self, offset: usize) -> u32 {
        self.inner.read32(offset)
    }
    fn write32(&self, offset: usize, value: u32) {
        if offset == regs::ESR1 {
            let hook = self.hook.borrow_mut().take();
            if let Some(mut h) = hook {
                h();
            }
        }
        self.inner.write32(offset, value)
    }
}

#[test]
fn an_error_raised_between_the_esr1_read_and_its_write_back_is_counted() {
    let model = FlexCanModel::mk20dx256();
    let hook: Hook = Rc::new(RefCell::new(None));
    let regs = InjectBeforeEsr1Write {
        inner: Ticking::new(model.clone()),
        hook: hook.clone(),
    };
    let controller = FlexCan::begin(
        regs,
        &mut HostSystem::new(),
        Target::new(Board::Teensy32, Instance::Can0),
        &Settings::new(500_000),
        &[],
        &[],
    )
    .unwrap();
    let mut can: Driver<FlexCanHw<InjectBeforeEsr1Write>, 32, 16> =
        Driver::new(controller.into_split());
    let bus = Rc::new(RefCell::new(bus_with(500_000, &[&model])));
    let peer = SimNode::new().shared();
    bus.borrow_mut().attach("peer", peer.clone());

    // First attempt: a bit error (ERRINT, BIT0/BIT1ERR).
    bus.borrow_mut().inject_next(Fault::Bit { at: None });
    can.try_send(&std_data(0x126, &[6])).unwrap();
    let first = bus.borrow_mut().step().unwrap();
    assert!(!first.record().unwrap().is_error_free());
    // (The test does not read ESR1 itself: the read clears its error bits.)
    assert!(model.irq_pending());

    // While the driver handles it, the retransmission fails too: the second error
    // latches ERRINT again after the driver's read of ESR1 and before its write-back.
    let b = bus.clone();
    *hook.borrow_mut() = Some(Box::new(move || {
        b.borrow_mut().inject_next(Fault::Bit { at: None });
        let second = b.borrow_mut().step().unwrap();
        assert!(!second.record().unwrap().is_error_free());
    }));
    can.on_interrupt();
    assert!(hook.borrow().is_none(), "the event was injected");
    // The write-back cleared the second ERRINT (it was set when read: one flag for two
    // events), so no interrupt is left for it; its error bits are still in ESR1 and
    // the same service counts them. Before the fix the count stayed at 1.
    assert_eq!(can.error_stats().bit, 2, "{:?}", can.error_stats());
    assert!(!model.irq_pending(), "nothing left to service");
    assert_eq!(can.counters().tec, 16);

    // The third attempt succeeds: one copy at the peer, counters back from 16.
    bus.borrow_mut().run_until_idle(10_000).unwrap();
    can.on_interrupt();
    assert_eq!(peer.borrow().received_frames(), vec![std_data(0x126, &[6])]);
    assert_eq!(can.traffic().sent, 1);
    assert_eq!(can.counters().tec, 15);
}
