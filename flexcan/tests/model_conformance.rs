//! The fault-confinement conformance table (`sim/tests/conformance/mod.rs`) on the
//! FlexCAN model, driven through its registers (automatic bus-off recovery:
//! CTRL1\[BOFFREC\] = 0): as the Kinetis K20 module and as the i.MX RT1062's CAN1
//! (module `rt1062`; same register procedure, the RT1062 leaves reset in Freeze mode).

#[path = "../../sim/tests/conformance/mod.rs"]
mod conformance;
#[path = "model_support.rs"]
mod support;

use conformance::Dut;
use support::Rig;
use twocan_core::registers::Registers;
use twocan_core::{ErrorCounters, ErrorState, Frame};
use twocan_flexcan::model::{FlexCanModel, Rt1062Can};
use twocan_flexcan::regs::{self, code, cs, ecr, esr1, mcr};
use twocan_sim::{Bus, NodeId};

/// The model as the K20's FlexCAN0 (`RT1062 = false`) or the RT1062's CAN1.
struct FlexCan<const RT1062: bool>(FlexCanModel);

impl<const RT1062: bool> Dut for FlexCan<RT1062> {
    fn join(bus: &mut Bus) -> (Self, NodeId) {
        let m = if RT1062 {
            FlexCanModel::imxrt1062(Rt1062Can::Can1)
        } else {
            FlexCanModel::mk20dx256()
        };
        support::accept_all_into_fifo(&m, mcr::SRXDIS);
        let id = bus.attach("dut", m.clone());
        m.modify32(regs::MCR, |v| v & !mcr::HALT);
        // Synchronisation: 11 recessive bits ("FlexCAN ... waits for 11 consecutive
        // recessive bits to synchronize to the CAN bus").
        bus.run_for(11);
        assert!(m.is_synchronised());
        (FlexCan(m), id)
    }
    fn send(&mut self, frame: &Frame) {
        let n = (8..16)
            .find(|&n| {
                let c = cs::CODE.get(self.0.read32(regs::mb_cs(n)));
                c == code::TX_INACTIVE || c == 0
            })
            .unwrap();
        let mut rig = Rig {
            m: self.0.clone(),
            now: 0,
        };
        rig.load_mb(n, frame, code::TX_DATA);
    }
    fn counters(&self) -> ErrorCounters {
        let e = self.0.read32(regs::ECR);
        let tec = if self.state() == ErrorState::BusOff {
            256
        } else {
            ecr::TXERRCNT.get(e) as u16
        };
        ErrorCounters {
            tec,
            rec: ecr::RXERRCNT.get(e) as u16,
        }
    }
    fn state(&self) -> ErrorState {
        // Reading ESR1 clears its error bits; the table does not use them.
        let e = self.0.read32(regs::ESR1);
        match esr1::FLTCONF.get(e) {
            esr1::FLTCONF_ERROR_ACTIVE if e & (esr1::RXWRN | esr1::TXWRN) != 0 => {
                ErrorState::Warning
            }
            esr1::FLTCONF_ERROR_ACTIVE => ErrorState::Active,
            esr1::FLTCONF_ERROR_PASSIVE => ErrorState::Passive,
            _ => ErrorState::BusOff,
        }
    }
    /// Written as a literal, not taken from the model: the Kinetis RM ("Error Counter (CANx_ECR)") allows 119..=127 as ISO 11898-1 §12.1.4.2 rule 8; the model takes 127.
    const REC_AFTER_PASSIVE_RECEPTION: u16 = 127;
}

conformance_tests!(FlexCan<false>);

mod rt1062 {
    use super::{conformance, FlexCan};

    crate::conformance_tests!(FlexCan<true>);
}
