//! The i.MX RT1062's FlexCAN entry points (features `rt` and `teensy40` or `teensy41`):
//! one interrupt line per module (IMXRT1060RM, "ARM Cortex M7 domain interrupt summary":
//! CAN1 = 36, CAN2 = 37, CAN3 = 154), exported under the vector names `CAN1`, `CAN2`
//! and `CAN3` (as NXP's SVD and `imxrt-ral`'s `Interrupt` spell them). Each runs the
//! module's message handlers (transmit, Rx FIFO) and then its status handler, since
//! every source of the module shares the line. [`crate::rt::IrqState::start`] wires them
//! as on the Kinetis boards: it unmasks the module's one line ([`crate::Irqs`] gives it
//! in every field).

use crate::instance::Instance;
use crate::rt::{dispatch, Line};

/// Runs both handlers of `instance`.
#[inline]
fn line(instance: Instance) {
    dispatch(instance, Line::Message);
    dispatch(instance, Line::Status);
}

/// Entry point `CAN1` (every source of CAN1).
#[export_name = "CAN1"]
pub extern "C" fn can1() {
    line(Instance::Can1);
}

/// Entry point `CAN2` (every source of CAN2).
#[export_name = "CAN2"]
pub extern "C" fn can2() {
    line(Instance::Can2);
}

/// Entry point `CAN3` (every source of CAN3).
#[export_name = "CAN3"]
pub extern "C" fn can3() {
    line(Instance::Can3);
}
