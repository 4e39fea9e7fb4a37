//! Issue 26 item 5: a filter switch through the split driver's receive half, with a
//! frame that the new list accepts arriving right after `CAN_FMR.FINIT` is cleared and
//! read by the receive interrupt at once (on the chip: the interrupt taken as soon as the
//! switch's critical section ends). The frame must be delivered with the new list's
//! index, not dropped as a frame of the old list.
#![cfg(feature = "model")]

mod common;

use std::cell::RefCell;
use std::rc::Rc;

use common::*;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{fmr, FMR};
use twocan_bxcan::{BxCan, Can, PlanOptions};
use twocan_core::{FifoQueue, Filter, Frame, Registers, State};
use twocan_sim::SimNode;

type Hook = Rc<RefCell<Option<Box<dyn FnMut()>>>>;

/// The model's registers; the hook runs once, right after a write that clears `FINIT`.
#[derive(Clone)]
struct AfterFinit {
    inner: Clocked,
    hook: Hook,
}

impl Registers for AfterFinit {
    fn read32(&self, offset: usize) -> u32 {
        self.inner.read32(offset)
    }
    fn write32(&self, offset: usize, value: u32) {
        self.inner.write32(offset, value);
        if offset == FMR && value & fmr::FINIT == 0 {
            let hook = self.hook.borrow_mut().take();
            if let Some(mut h) = hook {
                h();
            }
        }
    }
}

type Hw = BxCan<AfterFinit>;

#[test]
fn a_frame_of_the_new_list_read_right_after_the_switch_is_delivered() {
    let bus = new_bus();
    let model = BxCanModel::can1();
    bus.borrow_mut().attach("can1", model.clone());
    let peer = SimNode::new().shared();
    bus.borrow_mut().attach("peer", peer.clone());
    let hook: Hook = Rc::new(RefCell::new(None));
    let regs = AfterFinit {
        inner: Clocked::new(model, &bus),
        hook: hook.clone(),
    };
    let old = twocan_bxcan::plan(&[Filter::standard(0x100)], PlanOptions::new(14)).unwrap();
    let new = twocan_bxcan::plan(&[Filter::standard(0x200)], PlanOptions::new(14)).unwrap();
    let mut init = Can::can1(regs.clone(), &config())
        .map_err(|f| f.error)
        .unwrap();
    init.set_filters(&old).unwrap();
    let can = init.enable().map_err(|f| f.error).unwrap();
    regs.inner.ticking.set(false);
    let state: &'static State<Hw, 8, FifoQueue<4>, 8> = Box::leak(Box::new(State::new()));
    let parts = state.split(can.into_split()).map_err(|(e, _)| e).unwrap();
    let mut rx = parts.rx;
    let mut rx0_irq = parts.rx0_irq;
    let frame = Frame::standard(0x200, &[2]).unwrap();
    {
        let (peer, bus) = (peer.clone(), bus.clone());
        *hook.borrow_mut() = Some(Box::new(move || {
            peer.borrow_mut().send(frame);
            bus.borrow_mut().run_until_idle(2_000).unwrap();
            rx0_irq.on_interrupt();
        }));
    }
    let plan = new;
    rx.set_filters(&plan).unwrap();
    assert!(hook.borrow().is_none(), "the hook ran");
    assert_eq!(state.traffic().received, 1, "read by the receive interrupt");
    let got = rx.receive().expect("delivered");
    assert_eq!((got.frame, got.filter), (frame, 0));
    assert_eq!(state.traffic().rx_dropped, 0);
}
