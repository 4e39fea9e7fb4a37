//! Our bxCAN driver as the **lean** and the **full** bench firmware configure it, selected
//! by the firmware crate's cargo feature (`lean` or `full`, exactly one). Included with
//! `#[path]` by `insn-count` (QEMU, RAM stand-in) and `loopback-twocan` (STM32F7), so the
//! instruction counts and the flash figures are of the same configuration.
//!
//! Both configure the controller **in place** in the `static` state
//! (`State::split_with` and `BxCan::can1_in`: no controller, plan or filter map moves
//! through the configuration), with the filter map sized to the variant's plan:
//!
//! - **full**: every per-frame feature on — transmit completions (a completion ring of
//!   [`DONE`] = 8), receive time stamps (`CAN_MCR.TTCM`), traffic statistics, and the
//!   filters compiled at run time by the planner (`planner::plan_in`) from a filter
//!   list, its working memory in a `static` ([`TakeOnce`]), and a map with the default
//!   lookup capacity;
//! - **lean**: a `const` filter plan (`const_plan!`, the planner not linked) and a map
//!   with no lookup key (the plan has no merged slot), no completion ring ([`DONE`] =
//!   0), time stamps off (`CAN_MCR.TTCM` = 0) and the split driver's `Lean` feature
//!   set (no traffic statistics, no time stamps read); the filter map holds exactly
//!   the plan's match indices ([`FMIS`]), and the filters fixed ([`SWITCH`] = false: no
//!   filter generation per frame).
//!
//! **One-feature variants** (issue 21: each compile-time choice with its own measured
//! cost): `lean` plus exactly one of the additive features below switches that one
//! choice to its full setting and leaves every other as lean. They are valid only with
//! `lean`, one at a time (a `compile_error!` says so otherwise):
//!
//! - `done`: transmit completions ([`DONE`] = 8; with a completion ring the split
//!   driver's quiet transmit mode is off, so every frame runs the transmit handler);
//! - `stamps`: receive time stamps (`CAN_MCR.TTCM` = 1 and the split driver's
//!   `StampsOnly` feature set (`shared/feature_sets.rs`): time stamps read, nothing counted);
//! - `counts`: traffic statistics (the `CountsOnly` feature set: counted, no time
//!   stamps read);
//! - `switch`: filters replaceable while running ([`SWITCH`] = true: the filter
//!   generation checked per frame; the map sized as lean);
//! - `planner`: the filters compiled at run time by the planner (`planner::plan_in`,
//!   its working memory in a `static`) instead of the `const` plan; the map sized to
//!   the same plan as lean (no lookup key, the plan's match indices).
//!
//! [`TakeOnce`]: twocan_core::TakeOnce

// Each firmware that includes this module uses a part of it.
#![allow(dead_code)]

use twocan_bxcan::{BxCan, Config, PlanOptions, PlanRef};
use twocan_core::split::{Parts, Rx, Rx0Irq, State, Tx, TxIrq};
use twocan_core::{Error, FifoQueue, Filter, Fixed, TxPolicy};

// (The loop-back firmwares print no variant name: `VARIANT` unused there.)
#[allow(unused_imports)]
pub use crate::feature_sets::{Fe, DONE, VARIANT};

pub const APB1_HZ: u32 = 54_000_000;
pub const BITRATE: u32 = 500_000;

/// Receive ring (frames) of FIFO 0.
pub const RX: usize = 8;
/// Transmit queue capacity.
pub const TXQ: usize = 8;

/// The filter list of the full variant (the runtime planner compiles it): everything to
/// FIFO 0, the user's filter 0.
pub const FILTERS: [Filter; 1] = [Filter::pass_all()];

/// Loop-back, request-order transmit (TXFP = 1, the order of `FifoQueue`), time stamps
/// as the variant says.
pub const CONFIG: Config = match Config::from_bitrate(APB1_HZ, BITRATE) {
    Ok(c) => c
        .loopback(true)
        .tx_policy(TxPolicy::Fifo)
        .timestamps(TIMESTAMPS),
    Err(_) => panic!("no bit timing for 500 kbit/s from 54 MHz"),
};

// ------------------------------------------------------------------ lean

// `VARIANT`, `DONE` and `Fe`: `crate::feature_sets` (the same for both drivers).
/// Receive time stamps (`CAN_MCR.TTCM`; on with `stamps`).
#[cfg(feature = "lean")]
pub const TIMESTAMPS: bool = cfg!(feature = "stamps");
/// Identifiers of the filter map's merged-filter lookup.
#[cfg(feature = "lean")]
pub const KEYS: usize = 0;
/// Planner options: CAN1's banks at reset (`CAN2SB` = 14, RM0410 §40.9.4), FIFO 0.
pub const OPTIONS: PlanOptions = PlanOptions::new(14);

/// The filters: [`FILTERS`] planned at compile time (one accept-all mask bank to FIFO 0).
#[cfg(all(feature = "lean", not(feature = "planner")))]
#[inline(always)]
fn with_plan<T>(f: impl FnOnce(PlanRef<'_>) -> Result<T, Error>) -> Result<T, Error> {
    f(twocan_bxcan::const_plan!(FILTERS, OPTIONS).as_ref())
}

/// The user's filter index the one frame comes back with: its index in [`FILTERS`].
#[cfg(feature = "lean")]
pub const FILTER_INDEX: u16 = 0;

/// Match indices the filter map holds per FIFO: exactly what the `const` plan numbers.
#[cfg(feature = "lean")]
pub const FMIS: usize = twocan_bxcan::const_plan!(FILTERS, OPTIONS).match_indices();

/// The filters stay as configured (`set_filters` refused): no filter generation per
/// frame. With `switch`: replaceable while running, each frame carries the generation.
#[cfg(feature = "lean")]
pub const SWITCH: bool = cfg!(feature = "switch");

// ------------------------------------------------------------------ full

#[cfg(feature = "full")]
pub const TIMESTAMPS: bool = true;
#[cfg(feature = "full")]
pub const KEYS: usize = twocan_bxcan::filters::LOOKUP_KEYS;

/// The planner's working memory (about 90 KB of `.bss`), lent once.
#[cfg(any(feature = "full", feature = "planner"))]
static SCRATCH: twocan_core::TakeOnce<twocan_bxcan::planner::Scratch<KEYS>> =
    twocan_core::TakeOnce::new(twocan_bxcan::planner::Scratch::new());

/// The filters: [`FILTERS`] compiled by the run-time planner into [`SCRATCH`].
#[cfg(any(feature = "full", feature = "planner"))]
#[inline(always)]
fn with_plan<T>(f: impl FnOnce(PlanRef<'_>) -> Result<T, Error>) -> Result<T, Error> {
    let scratch = SCRATCH.take().ok_or(Error::WrongMode)?;
    let plan = twocan_bxcan::planner::plan_in(&FILTERS, OPTIONS, scratch)?;
    f(plan.as_ref())
}

/// The user's filter index the one frame comes back with: its index in [`FILTERS`].
#[cfg(feature = "full")]
pub const FILTER_INDEX: u16 = 0;

/// Match indices the filter map holds per FIFO: every bank's (the run-time planner may
/// number any).
#[cfg(feature = "full")]
pub const FMIS: usize = twocan_bxcan::filters::MAX_FMI;

/// Filters may be replaced while running: each frame carries the filter generation.
#[cfg(feature = "full")]
pub const SWITCH: bool = true;

// ------------------------------------------------------------------ both

/// CAN1's registers at the firmware's `CAN_BASE`, a constant: the per-frame code reaches
/// them with no base to load (`twocan_core::Fixed`).
pub type Regs = Fixed<{ crate::CAN_BASE }>;
/// The controller the split driver holds.
pub type Hw = BxCan<Regs, Regs, KEYS, FMIS, SWITCH>;
/// The transmit queue.
pub type Q = FifoQueue<TXQ>;
/// The shared state a `static` holds.
pub type OurState = State<Hw, RX, Q, 0, DONE, Fe>;
/// The handles of `State::split`.
pub type OurParts = Parts<'static, Hw, RX, Q, 0, DONE, Fe>;
pub type OurTx = Tx<'static, Hw, RX, Q, 0, DONE, Fe>;
pub type OurRx = Rx<'static, Hw, RX, Q, 0, DONE, Fe>;
pub type OurTxIrq = TxIrq<'static, Hw, RX, Q, 0, DONE, Fe>;
pub type OurRxIrq = Rx0Irq<'static, Hw, RX, Q, 0, DONE, Fe>;

/// Configures CAN1 at `regs` ([`CONFIG`], the variant's filters) in place in `state`
/// and splits it. `RETRIES` more attempts after a mode request that timed out (the QEMU
/// stand-in acknowledges from an interrupt whose rate follows host time; 0 on
/// hardware).
#[inline(always)]
pub fn start<const RETRIES: u32>(state: &'static OurState, regs: Regs) -> Result<OurParts, Error> {
    with_plan(|plan| {
        state.split_with(|slot| {
            let mut attempt = Hw::can1_in(slot, regs, &CONFIG, plan);
            for _ in 0..RETRIES {
                match attempt {
                    Err(f) if f.error == Error::Timeout => {
                        attempt = Hw::can1_in(f.value.slot, f.value.regs, &CONFIG, plan)
                    }
                    _ => break,
                }
            }
            attempt.map_err(|f| f.error)
        })
    })
}
