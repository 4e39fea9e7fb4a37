//! The split driver of a bxCAN instance as the examples use it: its shared state and
//! its four interrupt handlers in one `static` ([`CanState`], or the lean choice
//! [`LeanState`]: the library's `twocan_bxcan::rt::IrqState`), run by the library's own entry points `CAN1_TX`,
//! `CAN1_RX0`, `CAN1_RX1`, `CAN1_SCE` (and `CAN2_…`; one handler per line, RM0410
//! §40.8): the examples define no CAN vector. `start` configures the controller **in
//! place** in the state (an in-place constructor such as `BxCan::can1_in`: no
//! controller, plan or filter map moves through the configuration, issue 21) and puts
//! the handlers in place **before** it unmasks the lines. Filter lists known at compile
//! time are planned at compile time (`const_plan!`); lists known at run time use the
//! planner with its working memory in [`PLANNER`].

use twocan_bxcan::planner::Scratch;
use twocan_bxcan::regs::{Can1At, CanRegs};
use twocan_bxcan::rt::IrqState;
use twocan_bxcan::types::{BxRx, BxTx};
use twocan_core::TakeOnce;

/// Receive ring per FIFO, transmit queue and completion ring sizes of the examples.
pub const RX: usize = twocan_bxcan::types::RX_RING;
/// See [`RX`].
pub const TX: usize = twocan_bxcan::types::TX_QUEUE;
/// See [`RX`].
pub const COMPLETIONS: usize = twocan_bxcan::types::COMPLETIONS;

/// The planner's working memory for filter lists known only at run time (about 90 KB
/// of `.bss`, never on the stack), lent once: plan into it with
/// `twocan_bxcan::planner::plan_in`, install the plan, plan the next list into it.
pub static PLANNER: TakeOnce<Scratch> = TakeOnce::new(Scratch::new());

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
/// loads no base). `stm32f7-loopback-lean`.
pub type LeanState<const M: usize, R = Can1At, F = R> =
    IrqState<R, F, RX, Queue, 0, 0, 0, M, false, twocan_core::Lean>;

/// Configures `instance`'s controller in place in `state` (`init`: an in-place
/// constructor, e.g. `BxCan::can1_in`) and starts it (`IrqState::start_in_place`: the
/// four handlers installed, then each line of the instance given
/// [`crate::rt::CAN_PRIORITY`] and unmasked). Returns the thread-side halves; `None`
/// when the configuration failed or the state runs a controller already. For
/// [`CanState`] and [`LeanState`] alike.
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
    state.start_in_place(instance, init, priorities, nvic).ok()
}
