//! Our FlexCAN driver as the **lean** and the **full** bench firmware configure it,
//! selected by the firmware crate's cargo feature (`lean` or `full`, exactly one).
//! Included with `#[path]` by `insn-count-flexcan` (QEMU, RAM stand-in) and
//! `loopback-flexcan` (Teensy 3.6), generic over the register handle `R` (the stand-in
//! or FlexCAN0's `Can0At`).
//!
//! Both: FlexCAN0 of a Teensy 3.6 at 500 kbit/s from the 16 MHz oscillator clock,
//! loop-back with self reception, the 8-filter Rx FIFO partition (`Filters8_0`), one
//! pass-all filter, request-order transmit through MB15. The register handle is
//! `FlexCanAt` (the module's address known at compile time).
//!
//! - **full**: transmit completions (a completion ring of [`DONE`] = 8), receive and
//!   transmit time stamps, traffic statistics, the filter list compiled at run time by
//!   `FlexCan::begin_in_place` straight into a `static` `TableSlot`
//!   (`twocan_flexcan::options::FullInSlot`: filter switches too);
//! - **lean**: no completion ring ([`DONE`] = 0) and the controller's lean choices
//!   (`twocan_flexcan::options::Lean`: no time stamps, no filter switch while running,
//!   the filter table planned at compile time by `const_plan!` and the settings checked
//!   at compile time (`BeginPlan`), written by `FlexCan::begin_checked_in_place`, which keeps a
//!   few words pointing into the plan) and the split driver's `Lean` feature set (no
//!   traffic statistics, no time stamps read), which with the request-order queue is
//!   its quiet transmit mode (`State::QUIET_TX`: MB15's interrupt enabled only while
//!   frames wait in the queue, so a frame sent directly costs no transmit handler).
//!
//! Every variant writes the controller in place in the `static` state
//! (`State::split_with`, [`start`]).
//!
//! **One-feature variants** (issue 21: each compile-time choice with its own measured
//! cost, as `shared/bxcan_variant.rs` for bxCAN): `lean` plus exactly one of the
//! additive features below switches that one choice to its full setting and leaves every
//! other as lean (a `compile_error!` says so otherwise):
//!
//! - `done`: transmit completions ([`DONE`] = 8; with a completion ring the quiet
//!   transmit mode is off, so every frame runs the transmit handler);
//! - `stamps`: receive and transmit time stamps (controller options [`LeanStamps`]:
//!   the message buffer's `TIME STAMP` read, and the split driver's `StampsOnly`
//!   feature set of `shared/feature_sets.rs`);
//! - `counts`: traffic statistics (the `CountsOnly` feature set);
//! - `switch`: filter lists replaceable while running (controller options
//!   [`LeanSwitch`]: each raw frame carries the filter generation);
//! - `planner`: the filter list compiled at run time by `FlexCan::begin_in` into a
//!   `static` `TableSlot` (controller options [`LeanInSlot`]) instead of the `const`
//!   plan, with the settings checked at run time too (`begin_in` checks them).

// Each firmware that includes this module uses a part of it.
#![allow(dead_code)]

use twocan_core::split::{Parts, Rx, Rx0Irq, State, Tx, TxIrq};
use twocan_core::{Error, FifoQueue, Filter, Registers};

// (The loop-back firmwares print no variant name: `VARIANT` unused there.)
#[allow(unused_imports)]
pub use crate::feature_sets::{Fe, DONE, VARIANT};
use twocan_flexcan::{
    BeginError, BeginPlan, Board, Configuration, FlexCan, FlexCanHw, Instance, Settings, Target,
};

pub const BITRATE: u32 = 500_000;

/// Receive ring (frames), as the bxCAN bench firmware.
pub const RX: usize = 8;
/// Transmit queue capacity.
pub const TXQ: usize = 8;

/// The filter list (the user's filter 0 accepts every frame).
pub const FILTERS: [Filter; 1] = [Filter::pass_all()];
/// The user's filter index the one frame comes back with.
pub const FILTER_INDEX: u16 = 0;

/// Which module of which board.
pub const TARGET: Target = Target::new(Board::Teensy36, Instance::Can0);

/// The settings `begin` takes.
pub const SETTINGS: Settings = {
    let mut s = Settings::new(BITRATE);
    s.loop_back = true;
    s.self_reception = true;
    s.configuration = Configuration::Filters8_0;
    s
};

// ------------------------------------------------------------------ lean

// `VARIANT`, `DONE` and `Fe`: `crate::feature_sets` (the same for both drivers).
/// The controller's compile-time choices: no time stamps, no filter switch, the
/// table planned at compile time.
#[cfg(all(
    feature = "lean",
    not(any(feature = "stamps", feature = "switch", feature = "planner"))
))]
pub type Opts = twocan_flexcan::options::Lean;
/// `lean+stamps`: time stamps read from the message buffers.
#[cfg(feature = "stamps")]
pub type Opts = LeanStamps;
/// `lean+switch`: filter lists replaceable while running.
#[cfg(feature = "switch")]
pub type Opts = LeanSwitch;
/// `lean+planner`: the table compiled at run time into a `static` slot.
#[cfg(feature = "planner")]
pub type Opts = LeanInSlot;
/// `lean` with the message buffers' time stamps read (`Options::STAMPS`).
#[cfg(feature = "stamps")]
#[derive(Debug, Clone, Copy)]
pub enum LeanStamps {}

#[cfg(feature = "stamps")]
impl twocan_flexcan::options::Options for LeanStamps {
    type Layout = twocan_flexcan::layout::Kinetis;
    type Table = twocan_flexcan::installed::PlannedTable;
    const STAMPS: bool = true;
    const FILTER_SWITCH: bool = false;
}

/// `lean` with filter lists replaceable while running (`Options::FILTER_SWITCH`).
#[cfg(feature = "switch")]
#[derive(Debug, Clone, Copy)]
pub enum LeanSwitch {}

#[cfg(feature = "switch")]
impl twocan_flexcan::options::Options for LeanSwitch {
    type Layout = twocan_flexcan::layout::Kinetis;
    type Table = twocan_flexcan::installed::PlannedTable;
    const STAMPS: bool = false;
    const FILTER_SWITCH: bool = true;
}

/// `lean` with the table compiled at run time into a `static` slot.
#[cfg(feature = "planner")]
#[derive(Debug, Clone, Copy)]
pub enum LeanInSlot {}

#[cfg(feature = "planner")]
impl twocan_flexcan::options::Options for LeanInSlot {
    type Layout = twocan_flexcan::layout::Kinetis;
    type Table = &'static mut <twocan_flexcan::layout::Kinetis as twocan_flexcan::layout::Layout>::Table;
    const STAMPS: bool = false;
    const FILTER_SWITCH: bool = false;
}

// ------------------------------------------------------------------ full

/// The controller's compile-time choices: time stamps, filter switches, the table in a
/// `static` slot that `begin_in` compiles into.
#[cfg(feature = "full")]
pub type Opts = twocan_flexcan::options::FullInSlot;

// ------------------------------------------------------------------ both

/// The controller the split driver holds.
pub type Hw<R> = FlexCanHw<R, Opts>;
/// The transmit queue.
pub type Q = FifoQueue<TXQ>;
/// The shared state a `static` holds.
pub type OurState<R> = State<Hw<R>, RX, Q, 0, DONE, Fe>;
pub type OurParts<R> = Parts<'static, Hw<R>, RX, Q, 0, DONE, Fe>;
pub type OurTx<R> = Tx<'static, Hw<R>, RX, Q, 0, DONE, Fe>;
pub type OurRx<R> = Rx<'static, Hw<R>, RX, Q, 0, DONE, Fe>;
pub type OurTxIrq<R> = TxIrq<'static, Hw<R>, RX, Q, 0, DONE, Fe>;
pub type OurRxIrq<R> = Rx0Irq<'static, Hw<R>, RX, Q, 0, DONE, Fe>;

/// The settings checked at compile time for FlexCAN0 of the Teensy 3.6 (`BeginPlan`:
/// settings `begin` would refuse do not build).
pub const CHECKED: BeginPlan =
    BeginPlan::new_or_panic(TARGET, &SETTINGS, Configuration::Filters8_0);

/// `begin` with [`SETTINGS`] and [`FILTERS`] on the registers `regs()` gives and the
/// SIM/PORT registers `sys`, the controller written **in place** into `state`
/// (`State::split_with`: no controller value moves through the configuration), then
/// split. `RETRIES` more attempts (a failed `split_with` leaves the state empty), each
/// on a fresh register handle, after a handshake that timed out (the QEMU stand-in
/// acknowledges from an interrupt whose rate follows host time; 0 on hardware).
#[inline(always)]
pub fn start<const RETRIES: u32, R: Registers + Send + Sync, S: Registers>(
    state: &'static OurState<R>,
    regs: impl Fn() -> R,
    sys: &mut S,
) -> Result<OurParts<R>, Error> {
    let hardware = |e: BeginError| match e {
        BeginError::Hardware(e) => e,
        _ => Error::InvalidArgument,
    };
    #[cfg(any(feature = "full", feature = "planner"))]
    let mut table = TABLE.take();
    let mut retries = 0;
    loop {
        #[cfg(all(feature = "lean", not(feature = "planner")))]
        let attempt = state.split_with(|slot| {
            // The filter table planned and the settings checked at compile time,
            // written by `begin_checked_in_place` (no check links into the firmware).
            use twocan_flexcan::const_plan;
            use twocan_flexcan::planner::PlanOptions;
            let plan =
                const_plan!(FILTERS, PlanOptions::new(Configuration::Filters8_0)).planned();
            FlexCan::begin_checked_in_place(slot, regs(), sys, &CHECKED, plan).map_err(hardware)
        });
        #[cfg(any(feature = "full", feature = "planner"))]
        let attempt = {
            // `begin` compiles the list at run time straight into the table's `static`;
            // a failed attempt gives the table back for the next.
            state.split_with(|slot| {
                let Some(t) = table.take() else {
                    return Err(Error::InvalidArgument);
                };
                match FlexCan::begin_in_place(slot, regs(), sys, &CHECKED, &FILTERS, &[], t) {
                    Ok(hw) => Ok(hw),
                    Err((e, t)) => {
                        table = Some(t);
                        Err(hardware(e))
                    }
                }
            })
        };
        match attempt {
            Err(Error::Timeout) if retries < RETRIES => retries += 1,
            attempt => return attempt,
        }
    }
}

/// The filter table of the full and `lean+planner` variants (`begin_in` compiles into
/// it).
#[cfg(any(feature = "full", feature = "planner"))]
static TABLE: twocan_flexcan::filters::TableSlot = twocan_flexcan::filters::TableSlot::new();
