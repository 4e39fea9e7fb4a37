//! `IrqState::start_in_place_on` (feature `rt`, issue 21): the controller configured in
//! place in the state's slot by an in-place constructor, the four handlers installed
//! before any line is unmasked, frames moved through the library's entry points
//! (`rt::dispatch`), and a constructor of another instance refused.
//!
//! One test function per binary: the entry points' slots are process-wide.
#![cfg(all(feature = "model", feature = "rt"))]

mod common;

use common::*;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::rt::{self, IrqState, Line, Nvic, Priorities, StartError};
use twocan_bxcan::{const_plan, BxCan, Instance, PlanOptions};
use twocan_core::{Error, FifoQueue, Filter, Frame, Registers, TxPolicy};

/// The model's registers, declared shareable between "contexts" that are all this
/// test's one thread.
#[derive(Debug)]
struct OneThread(Clocked);

// SAFETY: the registers (an `Rc` model) are reached only from the thread that runs the
// one test of this binary: the "interrupts" are this test's `rt::dispatch` calls.
unsafe impl Send for OneThread {}
// SAFETY: as above.
unsafe impl Sync for OneThread {}

impl Registers for OneThread {
    fn read32(&self, offset: usize) -> u32 {
        self.0.read32(offset)
    }
    fn write32(&self, offset: usize, value: u32) {
        self.0.write32(offset, value)
    }
}

type Wired = IrqState<OneThread, OneThread, 8, FifoQueue<4>, 8, 8>;

/// An NVIC that records, at each unmask, whether every handler was in place.
struct Recorder {
    state: &'static Wired,
    unmasked: Vec<(u16, [bool; 4])>,
}

impl Nvic<u16> for Recorder {
    fn set_priority(&mut self, _: u16, _: u8) {}
    fn unmask(&mut self, line: u16) {
        self.unmasked.push((line, self.state.installed()));
    }
    fn mask(&mut self, _: u16) {}
}

#[test]
fn start_in_place_configures_in_the_state_installs_then_unmasks() {
    static CAN1: Wired = Wired::new();
    let bus = new_bus();
    let model = BxCanModel::can1();
    bus.borrow_mut().attach("can1", model.clone());
    let regs = OneThread(Clocked::new(model, &bus));
    let config = loopback_config(TxPolicy::Fifo);
    let plan = const_plan!([Filter::pass_all()], PlanOptions::new(14));
    let mut nvic = Recorder {
        state: &CAN1,
        unmasked: Vec::new(),
    };

    // A constructor of another instance than the one named is refused.
    let mut regs = Some(regs);
    let wrong = CAN1.start_in_place_on(
        Instance::Can1,
        |slot| {
            BxCan::can3_in(slot, regs.take().unwrap(), &config, plan).map_err(|f| {
                regs = Some(f.value.regs);
                f.error
            })
        },
        [19, 20, 21, 22],
        Priorities::all(0x80),
        &mut nvic,
    );
    assert_eq!(wrong.err(), Some(StartError::Split(Error::InvalidArgument)));
    assert!(nvic.unmasked.is_empty(), "nothing unmasked on error");
    assert!(CAN1.state().hardware().is_none());

    // The same registers again (the refused controller was configured: CAN1's block).
    let bus = new_bus();
    let model = BxCanModel::can1();
    bus.borrow_mut().attach("can1", model.clone());
    let regs = OneThread(Clocked::new(model, &bus));
    let (mut tx, mut rx) = CAN1
        .start_in_place_on(
            Instance::Can1,
            |slot| BxCan::can1_in(slot, regs, &config, plan).map_err(|f| f.error),
            [19, 20, 21, 22],
            Priorities::all(0x80),
            &mut nvic,
        )
        .ok()
        .unwrap();
    assert_eq!(nvic.unmasked.len(), 4);
    assert!(
        nvic.unmasked
            .iter()
            .all(|(_, installed)| *installed == [true; 4]),
        "every handler in place before any line is unmasked: {:?}",
        nvic.unmasked
    );
    let frame = Frame::standard(0x123, &[1, 2, 3]).unwrap();
    tx.try_send(&frame).unwrap();
    run(&bus, 300);
    assert!(rt::dispatch(Instance::Can1, Line::Tx));
    assert!(rt::dispatch(Instance::Can1, Line::Rx0));
    let got = rx.receive().unwrap();
    assert_eq!((got.frame, got.filter), (frame, 0));
    assert!(tx.take_completion().is_some());
}
