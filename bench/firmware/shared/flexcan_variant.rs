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
//!   `FlexCan::begin_in` straight into a `static` `TableSlot`
//!   (`twocan_flexcan::options::FullInSlot`: filter switches too);
//! - **lean**: no completion ring ([`DONE`] = 0) and the controller's lean choices
//!   (`twocan_flexcan::options::Lean`: no time stamps, no filter switch while running,
//!   the filter table planned at compile time by `const_plan!` and the settings checked
//!   at compile time (`BeginPlan`), written by `FlexCan::begin_checked`, which keeps a
//!   few words pointing into the plan) and the split driver's `Lean` feature set (no
//!   traffic statistics, no time stamps read), which with the request-order queue is
//!   its quiet transmit mode (`State::QUIET_TX`: MB15's interrupt enabled only while
//!   frames wait in the queue, so a frame sent directly costs no transmit handler).

// Each firmware that includes this module uses a part of it.
#![allow(dead_code)]

#[cfg(all(feature = "lean", feature = "full"))]
compile_error!("features `lean` and `full` are exclusive");
#[cfg(not(any(feature = "lean", feature = "full")))]
compile_error!("enable feature `lean` or `full`");

use twocan_core::split::{Parts, Rx, Rx0Irq, State, Tx, TxIrq};
use twocan_core::{Error, FifoQueue, Filter, Registers};
use twocan_flexcan::{
    BeginError, Board, Configuration, FlexCan, FlexCanHw, Instance, Settings, Target,
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

#[cfg(feature = "lean")]
pub const VARIANT: &str = "lean";
/// Completion ring capacity (0: completions off).
#[cfg(feature = "lean")]
pub const DONE: usize = 0;
/// The controller's compile-time choices: no time stamps, no filter switch.
#[cfg(feature = "lean")]
pub type Opts = twocan_flexcan::options::Lean;
/// The split driver's features: no statistics, no time stamps (the quiet transmit mode).
#[cfg(feature = "lean")]
pub type Fe = twocan_core::Lean;

// ------------------------------------------------------------------ full

#[cfg(feature = "full")]
pub const VARIANT: &str = "full";
#[cfg(feature = "full")]
pub const DONE: usize = 8;
/// The controller's compile-time choices: time stamps, filter switches, the table in a
/// `static` slot that `begin_in` compiles into.
#[cfg(feature = "full")]
pub type Opts = twocan_flexcan::options::FullInSlot;
/// The split driver's features: statistics and time stamps.
#[cfg(feature = "full")]
pub type Fe = twocan_core::Full;

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

/// `begin` with [`SETTINGS`] and [`FILTERS`] on the registers `regs()` gives and the
/// SIM/PORT registers `sys`, then the controller for the split driver. `RETRIES` more
/// attempts, each on a fresh register handle, after a handshake that timed out (the QEMU
/// stand-in acknowledges from an interrupt whose rate follows host time; 0 on hardware).
#[inline(always)]
pub fn configure<const RETRIES: u32, R: Registers, S: Registers>(
    regs: impl Fn() -> R,
    sys: &mut S,
) -> Result<Hw<R>, BeginError> {
    #[cfg(feature = "lean")]
    {
        // The filter table planned and the settings checked at compile time, written
        // by `begin_checked` (no check links into the firmware).
        use twocan_flexcan::planner::PlanOptions;
        use twocan_flexcan::{const_plan, BeginPlan};
        const CHECKED: BeginPlan =
            BeginPlan::new_or_panic(TARGET, &SETTINGS, Configuration::Filters8_0);
        let plan = const_plan!(FILTERS, PlanOptions::new(Configuration::Filters8_0)).planned();
        let mut retries = 0;
        loop {
            match FlexCan::begin_checked(regs(), sys, &CHECKED, plan) {
                Err(BeginError::Hardware(Error::Timeout)) if retries < RETRIES => retries += 1,
                attempt => return attempt,
            }
        }
    }
    #[cfg(feature = "full")]
    {
        // `begin` compiles the list at run time straight into the table's `static`.
        let Some(mut slot) = TABLE.take() else {
            return Err(BeginError::Hardware(Error::InvalidArgument));
        };
        let mut retries = 0;
        loop {
            match FlexCan::begin_in(regs(), sys, TARGET, &SETTINGS, &FILTERS, &[], slot) {
                Err((BeginError::Hardware(Error::Timeout), back)) if retries < RETRIES => {
                    retries += 1;
                    slot = back;
                }
                Err((e, _)) => return Err(e),
                Ok(hw) => return Ok(hw),
            }
        }
    }
}

/// The full variant's filter table (`begin_in` compiles into it).
#[cfg(feature = "full")]
static TABLE: twocan_flexcan::filters::TableSlot = twocan_flexcan::filters::TableSlot::new();
