//! The split driver of a FlexCAN instance as the examples use it: its shared state and
//! interrupt handlers in one `static` ([`CanState`], `twocan_flexcan::rt::IrqState`
//! with ACAN's buffer sizes), its filter table in another ([`TableSlot`]: the token's
//! `begin_in` compiles the lists straight into it, so no table-sized value moves
//! through `main`, issue 21). `CAN0.start(controller, &mut nvic)` puts the handlers
//! behind the library's entry points **before** it unmasks the interrupt lines at the
//! settings' `message_irq_priority` — so an interrupt never finds an entry point with
//! nothing to run (the line would stay asserted).
//!
//! Interrupt lines (Kinetis RM, FlexCAN "Interrupts"): the ORed message-buffer vector
//! runs the transmit handler and the Rx FIFO's receive handler; the bus-off, error and
//! Tx/Rx-warning vectors run the status handler.

use twocan_core::split::{Rx, Tx};
use twocan_flexcan::options::{FullInSlot, Lean as LeanOptions};
use twocan_flexcan::regs::{Can0At, FlexCanRegs};
use twocan_flexcan::rt::IrqState;
use twocan_flexcan::{FlexCanHw, RECEIVE_BUFFER_SIZE};

pub use twocan_flexcan::filters::TableSlot;

/// Completions kept for the thread side.
pub const COMPLETIONS: usize = twocan_flexcan::types::COMPLETIONS;

/// The controller on target registers, its table in a `static` [`TableSlot`] (every
/// feature: time stamps, filter switches).
pub type Hw = FlexCanHw<FlexCanRegs, FullInSlot>;
/// ACAN's buffer sizes: receive 32, transmit 16 (ACAN table 7).
pub type Queue = twocan_flexcan::types::Queue;
/// The shared state and interrupt handlers a `static` holds.
pub type CanState = IrqState<FlexCanRegs, RECEIVE_BUFFER_SIZE, Queue, COMPLETIONS, FullInSlot>;
/// The transmit half.
pub type CanTxHalf = Tx<'static, Hw, RECEIVE_BUFFER_SIZE, Queue, 0, COMPLETIONS>;
/// The receive half.
pub type CanRxHalf = Rx<'static, Hw, RECEIVE_BUFFER_SIZE, Queue, 0, COMPLETIONS>;

/// The lean choice (issue 21), one line away from [`CanState`]: fire-and-forget
/// transmit (no completion ring, `DONE` = 0), no traffic statistics and no time stamps
/// (`twocan_core::Lean`), the filter table planned at compile time and read from flash
/// (`twocan_flexcan::options::Lean`: no filter switch while running), and FlexCAN0's
/// registers at their fixed address ([`Can0At`]: the per-frame code loads no base; `R`
/// = [`FlexCanRegs`] for the run-time base). Configured with the token's
/// `begin_planned_in_place` (which gives the state's register type, from the consumed
/// token) and a `const` [`twocan_flexcan::BeginPlan`] (`teensy-loopback-lean`).
pub type LeanState<R = Can0At> =
    IrqState<R, RECEIVE_BUFFER_SIZE, Queue, 0, LeanOptions, twocan_core::Lean>;
/// The lean controller on target registers.
pub type LeanHw<R = Can0At> = FlexCanHw<R, LeanOptions>;
/// The lean transmit half.
pub type LeanTxHalf<R = Can0At> =
    Tx<'static, LeanHw<R>, RECEIVE_BUFFER_SIZE, Queue, 0, 0, twocan_core::Lean>;
/// The lean receive half.
pub type LeanRxHalf<R = Can0At> =
    Rx<'static, LeanHw<R>, RECEIVE_BUFFER_SIZE, Queue, 0, 0, twocan_core::Lean>;
