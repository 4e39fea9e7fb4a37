//! The fault-confinement conformance table (`sim/tests/conformance/mod.rs`) on the
//! bxCAN model, driven through its registers (automatic bus-off recovery: `MCR.ABOM`).

#[path = "../../sim/tests/conformance/mod.rs"]
mod conformance;
#[path = "model_bus.rs"]
mod tiny;

use conformance::Dut;
use tiny::{accept_all, enter_init, load};
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{self, esr, mcr, tsr};
use twocan_core::{ErrorCounters, ErrorState, Frame, Registers};
use twocan_sim::{Bus, NodeId};

struct BxCan(BxCanModel);

impl Dut for BxCan {
    fn join(bus: &mut Bus) -> (Self, NodeId) {
        let mut m = BxCanModel::can1();
        let id = bus.attach("dut", m.clone());
        enter_init(&mut m);
        accept_all(&mut m, 0, 0);
        m.write32(regs::MCR, mcr::ABOM);
        bus.run_until_idle(100).unwrap();
        assert_eq!(m.read32(regs::MSR) & regs::msr::INAK, 0, "normal mode");
        (BxCan(m), id)
    }
    fn send(&mut self, frame: &Frame) {
        let t = self.0.read32(regs::TSR);
        let x = (0..3).find(|&x| t & (tsr::TME0 << x) != 0).unwrap();
        load(&mut self.0, x, frame);
    }
    fn counters(&self) -> ErrorCounters {
        let e = self.0.read32(regs::ESR);
        let tec = if e & esr::BOFF != 0 {
            256
        } else {
            esr::TEC.get(e) as u16
        };
        ErrorCounters {
            tec,
            rec: esr::REC.get(e) as u16,
        }
    }
    fn state(&self) -> ErrorState {
        let e = self.0.read32(regs::ESR);
        if e & esr::BOFF != 0 {
            ErrorState::BusOff
        } else if e & esr::EPVF != 0 {
            ErrorState::Passive
        } else if e & esr::EWGF != 0 {
            ErrorState::Warning
        } else {
            ErrorState::Active
        }
    }
    /// Written as a literal, not taken from the model: the bxCAN notes (after RM0410 §40.7.6 "Error management"): "reset to 120".
    const REC_AFTER_PASSIVE_RECEPTION: u16 = 120;
}

conformance_tests!(BxCan);
