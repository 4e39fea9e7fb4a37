//! The split driver of an RT1062 FlexCAN module as the Teensy 4 examples use it: its
//! shared state and interrupt handlers in one `static` ([`CanState`],
//! `twocan_flexcan::rt::IrqState` with ACAN's buffer sizes), its filter table in another
//! ([`TableSlot`]: the token's `begin_in_place` compiles the lists straight into it, so
//! no table-sized value moves through `main`, issue 21). `CAN1.start_in_place(...)`
//! puts the handlers behind the library's `CAN1` entry point **before** it unmasks the
//! module's line at the settings' `message_irq_priority`.
//!
//! Every type here is in the RT1062 message-buffer layout
//! ([`twocan_flexcan::layout::Imxrt1062`]), as the one calls of `twocan_flexcan::acan`
//! and the tokens' `begin`: the workaround of erratum ERR005829 (i.MX RT1060 chip
//! errata: the first mailbox after the Rx FIFO area kept INACTIVE, two INACTIVE writes
//! after each transmit activation) and Rx FIFO tables up to RFFN 0xF, in a 128-element
//! table ([`twocan_flexcan::layout::LargeFilterTable`]). The Teensy 3 examples' module
//! of the same name keeps ACAN's layout (MB0–MB15). The settings are planned for this
//! layout with `BeginPlan::<Imxrt1062>::new_with_layout_or_panic`.
//!
//! Interrupt line (IMXRT1060RM, "ARM Cortex M7 domain interrupt summary"): one per
//! module, which runs the transmit and Rx FIFO handlers, then the status handler.

use twocan_core::split::{Rx, Tx};
use twocan_flexcan::imxrt::Can1At;
use twocan_flexcan::layout::{Imxrt1062, LargeFilterTable};
use twocan_flexcan::options::{FullInSlot, Lean as LeanOptions};
use twocan_flexcan::regs::FlexCanRegs;
use twocan_flexcan::rt::IrqState;
use twocan_flexcan::{FlexCanHw, RECEIVE_BUFFER_SIZE};

/// Room for one module's filter table in a `static` (the RT1062 layout's, 128 elements;
/// `TableSlot::new_sized()`).
pub type TableSlot = twocan_flexcan::filters::TableSlot<LargeFilterTable>;

/// Completions kept for the thread side.
pub const COMPLETIONS: usize = twocan_flexcan::types::COMPLETIONS;

/// The controller on target registers, in the RT1062 layout, its table in a `static`
/// [`TableSlot`] (every feature: time stamps, filter switches).
pub type Hw = FlexCanHw<FlexCanRegs, FullInSlot<Imxrt1062>>;
/// ACAN's buffer sizes: receive 32, transmit 16 (ACAN table 7).
pub type Queue = twocan_flexcan::types::Queue;
/// The shared state and interrupt handlers a `static` holds.
pub type CanState =
    IrqState<FlexCanRegs, RECEIVE_BUFFER_SIZE, Queue, COMPLETIONS, FullInSlot<Imxrt1062>>;
/// The transmit half.
pub type CanTxHalf = Tx<'static, Hw, RECEIVE_BUFFER_SIZE, Queue, 0, COMPLETIONS>;
/// The receive half.
pub type CanRxHalf = Rx<'static, Hw, RECEIVE_BUFFER_SIZE, Queue, 0, COMPLETIONS>;

/// The lean choice (issue 21), one line away from [`CanState`], in the RT1062 layout:
/// fire-and-forget transmit (no completion ring, `DONE` = 0), no traffic statistics and
/// no time stamps (`twocan_core::Lean`), the filter table planned at compile time
/// (`twocan_flexcan::const_plan_large!`) and read from flash
/// (`twocan_flexcan::options::Lean`: no filter switch while running), and CAN1's
/// registers at their fixed address ([`Can1At`]: the per-frame code loads no base; `R`
/// = [`FlexCanRegs`] for the run-time base), configured with the token's
/// `begin_planned_in_place` (which gives the state's register type, from the consumed
/// token) and a `const` `twocan_flexcan::BeginPlan<Imxrt1062>`.
pub type LeanState<R = Can1At> =
    IrqState<R, RECEIVE_BUFFER_SIZE, Queue, 0, LeanOptions<Imxrt1062>, twocan_core::Lean>;
/// The lean controller on target registers.
pub type LeanHw<R = Can1At> = FlexCanHw<R, LeanOptions<Imxrt1062>>;
/// The lean transmit half.
pub type LeanTxHalf<R = Can1At> =
    Tx<'static, LeanHw<R>, RECEIVE_BUFFER_SIZE, Queue, 0, 0, twocan_core::Lean>;
/// The lean receive half.
pub type LeanRxHalf<R = Can1At> =
    Rx<'static, LeanHw<R>, RECEIVE_BUFFER_SIZE, Queue, 0, 0, twocan_core::Lean>;
