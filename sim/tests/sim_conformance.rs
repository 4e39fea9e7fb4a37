//! The fault-confinement conformance table (`conformance/mod.rs`) on the simulated node.

#[path = "conformance/mod.rs"]
mod conformance;

use std::cell::RefCell;
use std::rc::Rc;

use conformance::Dut;
use twocan_core::{ErrorCounters, ErrorState, Frame};
use twocan_sim::{Bus, NodeId, SimNode};

/// A [`SimNode`] kept by the test while the bus drives a clone.
struct Sim(Rc<RefCell<SimNode>>);

impl Dut for Sim {
    fn join(bus: &mut Bus) -> (Self, NodeId) {
        let n = SimNode::new().shared();
        let id = bus.attach("dut", n.clone());
        (Sim(n), id)
    }
    fn send(&mut self, frame: &Frame) {
        self.0.borrow_mut().send(*frame);
    }
    fn counters(&self) -> ErrorCounters {
        self.0.borrow().counters()
    }
    fn state(&self) -> ErrorState {
        self.0.borrow().state()
    }
    /// ISO 11898-1 §12.1.4.2 rule 8 allows 119..=127; the simulated node takes 127
    /// (written as a literal, not taken from the code under test).
    const REC_AFTER_PASSIVE_RECEPTION: u16 = 127;
}

conformance_tests!(Sim);
