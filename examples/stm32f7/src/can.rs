//! The split driver of a bxCAN instance as the examples use it: its shared state and
//! its four interrupt handlers in one `static` ([`CanState`], the library's
//! `twocan_bxcan::rt::IrqState`), run by the library's own entry points `CAN1_TX`,
//! `CAN1_RX0`, `CAN1_RX1`, `CAN1_SCE` (and `CAN2_…`; one handler per line, RM0410
//! §40.8): the examples define no CAN vector. `start` puts the handlers in place
//! **before** it unmasks the lines.

use twocan_bxcan::regs::CanRegs;
use twocan_bxcan::rt::IrqState;
use twocan_bxcan::types::{BxRx, BxTx};

/// Receive ring per FIFO, transmit queue and completion ring sizes of the examples.
pub const RX: usize = twocan_bxcan::types::RX_RING;
/// See [`RX`].
pub const TX: usize = twocan_bxcan::types::TX_QUEUE;
/// See [`RX`].
pub const COMPLETIONS: usize = twocan_bxcan::types::COMPLETIONS;

/// A transmit queue in request order (`TXFP = 1`, the driver's default).
pub type Queue = twocan_bxcan::types::Queue;
/// The shared state and interrupt handlers of an instance with registers `R` and filter
/// registers `F` (a whole block by default; `ControlRegs` and
/// `twocan_bxcan::hal::Can1Filters` for CAN1 and CAN2 sharing CAN1's filters).
pub type CanState<R = CanRegs, F = CanRegs> = IrqState<R, F, RX, Queue, RX, COMPLETIONS>;
/// The transmit half.
pub type CanTxHalf<R = CanRegs, F = CanRegs> = BxTx<'static, R, F>;
/// The receive half.
pub type CanRxHalf<R = CanRegs, F = CanRegs> = BxRx<'static, R, F>;

/// Starts `state` over `hw` (`IrqState::start`: the four handlers installed, then each
/// line of the instance given [`crate::rt::CAN_PRIORITY`] and unmasked). Returns the
/// thread-side halves; `None` when the state runs a controller already.
#[cfg(target_os = "none")]
pub fn start<R, F>(
    state: &'static CanState<R, F>,
    hw: twocan_bxcan::BxCan<R, F>,
    nvic: &mut cortex_m::peripheral::NVIC,
) -> Option<(CanTxHalf<R, F>, CanRxHalf<R, F>)>
where
    R: twocan_core::Registers + Send + Sync + 'static,
    F: twocan_core::Registers + Send + Sync + 'static,
{
    let priorities = twocan_bxcan::rt::Priorities::all(crate::rt::CAN_PRIORITY);
    state.start(hw, priorities, nvic).ok()
}
