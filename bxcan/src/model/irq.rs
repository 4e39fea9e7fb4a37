//! The four interrupt lines of a bxCAN instance (RM0410 40.8 "bxCAN interrupts", figure
//! "Event flags and interrupt generation").
//!
//! - transmit: `TMEIE` and any of `RQCP0`, `RQCP1`, `RQCP2`;
//! - FIFO 0: `FMPIE0` and `FMP0 ≠ 0`, or `FFIE0` and `FULL0`, or `FOVIE0` and `FOVR0`;
//! - FIFO 1: likewise with the FIFO 1 bits;
//! - status change / error: `ERRIE` and `ERRI`, or `WKUIE` and `WKUI`, or `SLKIE` and
//!   `SLAKI`. `ERRI` itself is set on error detection when an error flag (`EWGF`,
//!   `EPVF`, `BOFF`, `LEC ≠ 0`) is set with its enable (`EWGIE`, `EPVIE`, `BOFIE`,
//!   `LECIE`).
//!
//! The lines are levels: they stay asserted until software clears the flag or the enable.

use crate::regs::{ier, msr, rfxr, tsr};

/// The levels of the four interrupt request lines of one instance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct IrqLines {
    /// Transmit interrupt (CANx_TX).
    pub tx: bool,
    /// FIFO 0 interrupt (CANx_RX0).
    pub rx0: bool,
    /// FIFO 1 interrupt (CANx_RX1).
    pub rx1: bool,
    /// Status change and error interrupt (CANx_SCE).
    pub sce: bool,
}

impl IrqLines {
    /// The lines given `CAN_IER`, `CAN_MSR`, `CAN_TSR` and `CAN_RFxR` as read.
    pub fn from_registers(ier_v: u32, msr_v: u32, tsr_v: u32, rfr: [u32; 2]) -> Self {
        let any_rqcp = tsr_v & (tsr::RQCP0 | tsr::RQCP1 | tsr::RQCP2) != 0;
        let fifo = |x: usize| {
            let r = rfr[x];
            (ier_v & ier::fmpie(x) != 0 && rfxr::FMP.get(r) != 0)
                || (ier_v & ier::ffie(x) != 0 && r & rfxr::FULL != 0)
                || (ier_v & ier::fovie(x) != 0 && r & rfxr::FOVR != 0)
        };
        IrqLines {
            tx: ier_v & ier::TMEIE != 0 && any_rqcp,
            rx0: fifo(0),
            rx1: fifo(1),
            sce: (ier_v & ier::ERRIE != 0 && msr_v & msr::ERRI != 0)
                || (ier_v & ier::WKUIE != 0 && msr_v & msr::WKUI != 0)
                || (ier_v & ier::SLKIE != 0 && msr_v & msr::SLAKI != 0),
        }
    }

    /// Whether any line is asserted.
    pub fn any(&self) -> bool {
        self.tx || self.rx0 || self.rx1 || self.sce
    }
}
