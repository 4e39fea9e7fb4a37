//! Our FlexCAN driver as the **lean** and the **full** bench firmware configure it,
//! selected by the firmware crate's cargo feature (`lean` or `full`, exactly one).
//! Included with `#[path]` by `insn-count-flexcan` (QEMU, RAM stand-in) and
//! `loopback-flexcan` (Teensy 3.6), generic over the register handle `R` (the stand-in
//! or FlexCAN0's `FlexCanRegs`).
//!
//! Both: FlexCAN0 of a Teensy 3.6 at 500 kbit/s from the 16 MHz oscillator clock,
//! loop-back with self reception, the 8-filter Rx FIFO partition (`Filters8_0`), one
//! pass-all filter, request-order transmit through MB15.
//!
//! - **full**: transmit completions (a completion ring of [`DONE`] = 8), receive and
//!   transmit time stamps, traffic statistics, the filter list compiled by `begin`'s
//!   runtime planner;
//! - **lean**: no completion ring ([`DONE`] = 0) and the controller's lean choices
//!   (`twocan_flexcan::options::Lean`: no time stamps, no filter switch while running,
//!   the filter table planned at compile time by `const_plan!` and the settings checked
//!   at compile time (`BeginPlan`), written by `FlexCan::begin_checked`, which keeps a
//!   few words pointing into the plan).
//!   Statistics stay on (twocan-core's counters).

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

// ------------------------------------------------------------------ full

#[cfg(feature = "full")]
pub const VARIANT: &str = "full";
#[cfg(feature = "full")]
pub const DONE: usize = 8;
/// The controller's compile-time choices: time stamps, filter switches.
#[cfg(feature = "full")]
pub type Opts = twocan_flexcan::options::Full;

// ------------------------------------------------------------------ both

/// The controller the split driver holds.
pub type Hw<R> = FlexCanHw<R, Opts>;
/// The transmit queue.
pub type Q = FifoQueue<TXQ>;
/// The shared state a `static` holds.
pub type OurState<R> = State<Hw<R>, RX, Q, 0, DONE>;
pub type OurParts<R> = Parts<'static, Hw<R>, RX, Q, 0, DONE>;
pub type OurTx<R> = Tx<'static, Hw<R>, RX, Q, 0, DONE>;
pub type OurRx<R> = Rx<'static, Hw<R>, RX, Q, 0, DONE>;
pub type OurTxIrq<R> = TxIrq<'static, Hw<R>, RX, Q, 0, DONE>;
pub type OurRxIrq<R> = Rx0Irq<'static, Hw<R>, RX, Q, 0, DONE>;

/// `begin` with [`SETTINGS`] and [`FILTERS`] on the registers `regs()` gives and the
/// SIM/PORT registers `sys`, then the controller for the split driver. `RETRIES` more
/// attempts, each on a fresh register handle, after a handshake that timed out (the QEMU
/// stand-in acknowledges from an interrupt whose rate follows host time; 0 on hardware).
#[inline(always)]
pub fn configure<const RETRIES: u32, R: Registers, S: Registers>(
    regs: impl Fn() -> R,
    sys: &mut S,
) -> Result<Hw<R>, BeginError> {
    // One call site of `begin`: its result goes straight into the split controller.
    let mut retries = 0;
    loop {
        match begin(regs(), sys) {
            Err(BeginError::Hardware(Error::Timeout)) if retries < RETRIES => retries += 1,
            attempt => return attempt,
        }
    }
}

/// Lean: the filter table planned and the settings checked at compile time, written by
/// `begin_checked` (no check links into the firmware).
#[cfg(feature = "lean")]
#[inline(always)]
fn begin<R: Registers, S: Registers>(regs: R, sys: &mut S) -> Result<Hw<R>, BeginError> {
    use twocan_flexcan::planner::PlanOptions;
    use twocan_flexcan::{const_plan, BeginPlan};
    const CHECKED: BeginPlan =
        BeginPlan::new_or_panic(TARGET, &SETTINGS, Configuration::Filters8_0);
    let plan = const_plan!(FILTERS, PlanOptions::new(Configuration::Filters8_0)).planned();
    FlexCan::begin_checked(regs, sys, &CHECKED, plan)
}

/// Full: `begin` compiles the list at run time; the controller keeps the table.
#[cfg(feature = "full")]
#[inline(always)]
fn begin<R: Registers, S: Registers>(regs: R, sys: &mut S) -> Result<Hw<R>, BeginError> {
    Ok(FlexCan::begin(regs, sys, TARGET, &SETTINGS, &FILTERS, &[])?.into_split_with::<Opts>())
}
