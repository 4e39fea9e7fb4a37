//! The split driver of a bxCAN instance as the examples use it: its shared state and its
//! four interrupt handlers in one `static` ([`CanState`], or the lean choice
//! [`LeanState`]: the library's `twocan_bxcan::rt::IrqState`, the same types as
//! `twocan-stm32f7`'s), and `start`,
//! which configures the controller in place in the state and puts the handlers in
//! place **before** it unmasks the part's lines. The vectors
//! (`crate::can1_vectors!`, `crate::can2_vectors!`) call the library's
//! `twocan_bxcan::rt::dispatch` with the instance and line: the library exports entry
//! points for the STM32F7 only (`hal-stm32f7`), these parts' vector names are the board
//! module's.

use twocan_bxcan::regs::{Can1At, CanRegs};
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

/// The lean choice (issue 21), one line away from [`CanState`]: fire-and-forget
/// transmit (no completion ring, `DONE` = 0), no traffic statistics and no time stamps
/// (`twocan_core::Lean`), the filters planned at compile time (`const_plan!`) and fixed
/// (no filter switch while running, no merged-filter lookup), the filter map holding
/// exactly the plan's `M` match indices (`const_plan!(..).match_indices()`), no FIFO 1
/// ring (the plan routes to FIFO 0; a frame a filter sent to FIFO 1 would be taken from
/// the hardware and counted as a ring overflow), and CAN1's registers at their fixed
/// address ([`Can1At`], from the hand-over's `into_registers_at`: the per-frame code
/// loads no base). `stm32-loopback-lean`.
pub type LeanState<const M: usize, R = Can1At, F = R> =
    IrqState<R, F, RX, Queue, 0, 0, 0, M, false, twocan_core::Lean>;

/// Configures `instance`'s controller in place in `state` (`init`: an in-place
/// constructor, e.g. `BxCan::can1_in`: no controller, plan or filter map moves through
/// the configuration, issue 21) and starts it on the instance's four `lines`
/// (`crate::rt::CAN1_IRQS`, …): the handlers installed, then each line given
/// [`crate::rt::CAN_PRIORITY`] and unmasked (`IrqState::start_in_place_on`). Returns
/// the thread-side halves; `None` when the configuration failed or the state runs a
/// controller already. For [`CanState`] and [`LeanState`] alike.
#[cfg(target_os = "none")]
#[allow(clippy::type_complexity)]
pub fn start<
    R,
    F,
    const RX0: usize,
    const RX1: usize,
    const DONE: usize,
    const K: usize,
    const M: usize,
    const SWITCH: bool,
    Fe,
>(
    state: &'static IrqState<R, F, RX0, Queue, RX1, DONE, K, M, SWITCH, Fe>,
    instance: twocan_bxcan::Instance,
    init: impl FnOnce(
        &mut core::mem::MaybeUninit<twocan_bxcan::BxCan<R, F, K, M, SWITCH>>,
    ) -> Result<&mut twocan_bxcan::BxCan<R, F, K, M, SWITCH>, twocan_core::Error>,
    lines: [crate::rt::Interrupt; 4],
    nvic: &mut cortex_m::peripheral::NVIC,
) -> Option<twocan_bxcan::rt::Halves<R, F, RX0, Queue, RX1, DONE, K, M, SWITCH, Fe>>
where
    R: twocan_core::Registers + Send + Sync + 'static,
    F: twocan_core::Registers + Send + Sync + 'static,
    Fe: twocan_core::Features,
    twocan_bxcan::filters::FmiMap<K, M>: Send,
    IrqState<R, F, RX0, Queue, RX1, DONE, K, M, SWITCH, Fe>: Sync,
{
    let priorities = twocan_bxcan::rt::Priorities::all(crate::rt::CAN_PRIORITY);
    state
        .start_in_place_on(instance, init, lines, priorities, nvic)
        .ok()
}
