//! Issue 6, item 4: full load. Minimum-length frames (standard identifier, DLC 0) back to
//! back at 1 Mbit/s from a plain node into each controller, the interrupt serviced after a
//! seeded random latency (see `twocan_tests::load` for how, and for what is predicted).
//!
//! Issue 21: for every combination of the compile-time choices a firmware example uses.
//! Five instances run, each with the same assertions:
//!
//! - the unsplit driver (`Driver`, every feature: statistics, time stamps, completions)
//!   on FlexCAN (Teensy 3.6 can0, ACAN's 12/12 partition) and on bxCAN (STM32F767 CAN1,
//!   run-time plan): `Driver::on_interrupt` at the drawn latency, then `receive`;
//! - the lean split driver (`twocan_tests::lean`: `DONE` = 0 and the quiet transmit
//!   mode, `twocan_core::Lean` features, a `const` filter plan) on each of:
//!   - bxCAN in place with the map sized to the plan and the filters fixed (the bench's
//!     lean bxCAN firmware) — `LeanBxCan`;
//!   - FlexCAN Teensy 3.6 can0, `options::Lean` begun with `begin_checked` in the
//!     8-filter partition (the bench's lean FlexCAN firmware, `teensy-loopback-lean`) —
//!     `LeanFlexCan`;
//!   - FlexCAN Teensy 4.1 CAN1 over the RT1062 model, `options::Lean<Imxrt1062>` (the
//!     ERR005829 reserved mailbox), `const_plan_large!` and a `const`
//!     `BeginPlan<Imxrt1062>` in ACAN's 12/12 partition (`teensy4-loopback-lean`) —
//!     `LeanRt1062`;
//!
//!   the line's receive handler (`Rx0Irq::on_interrupt`, with the other handlers of the
//!   raised lines) at the drawn latency, then the receive half drains its ring (8
//!   frames).
//!
//! Assertions:
//!
//! - Within the FIFO budget (latency ≤ depth × minimum frame time: bxCAN one FIFO of 3,
//!   FlexCAN's Rx FIFO of 6 on the Kinetis parts and on the RT1062): zero lost, order
//!   kept.
//! - Beyond it (latency up to 4 × the budget): frames are lost, and every loss is counted
//!   — sent = received + counted lost, with the lost frames, their number and the
//!   overrun events the driver sees all as predicted from the FIFO depth and overrun rule.
//!   The lean driver counts what the full one counts of losses: hardware overruns
//!   (`ErrorStatistics::hardware_overruns`) and receive ring overflows are counted
//!   whatever the feature set; only the per-frame traffic statistics are off (checked: 0).
//!   Neither controller counts the frames an overrun loses (bxCAN sets `FOVR`, FlexCAN
//!   the Rx FIFO overflow flag), so the lost frames are the model's count.
//!
//! 100,000 frames per instance in the default (debug) run; the 1,000,000-frame runs are
//! `#[ignore]`d: `cargo test --release -p twocan-tests --test full_load -- --ignored`.

use twocan_tests::backend::{BxCanBackend, FlexCanBackend};
use twocan_tests::load::{
    budget_bits, full_load, LeanBxCan, LeanFlexCan, LeanRt1062, LoadInstance, LoadReport,
    FULL_LOAD_BIT_RATE, MIN_FRAME_BITS,
};

use twocan_flexcan::layout::{Imxrt1062, Kinetis, Layout};
use twocan_flexcan::regs::{self, code, cs, mcr};
use twocan_flexcan::Configuration;
use twocan_host::Harness;

const DEFAULT_FRAMES: u64 = 100_000;
const FULL_FRAMES: u64 = 1_000_000;

/// What both runs check beyond `LoadReport::assert_accounted`: the traffic statistics
/// count every frame taken from the hardware where the instance counts, and stay 0 where
/// it does not (`Lean`).
fn assert_statistics<B: LoadInstance>(r: &LoadReport) {
    let counted = if B::COUNTS { r.received } else { 0 };
    assert_eq!(
        r.counted_received,
        counted,
        "{}: traffic statistics",
        B::NAME
    );
}

fn within_budget<B: LoadInstance>(frames: u64, seed: u64) -> LoadReport {
    let budget = budget_bits(B::RX_FIFO_DEPTH);
    let r = full_load::<B>(frames, budget, seed);
    println!("{} within budget ({budget} bits): {r:?}", B::NAME);
    r.assert_accounted(B::NAME);
    assert_statistics::<B>(&r);
    assert_eq!(r.sent, frames, "{}: every frame sent", B::NAME);
    assert_eq!(r.hw_lost, 0, "{}: nothing lost within the budget", B::NAME);
    assert_eq!(r.received, frames, "{}", B::NAME);
    assert_eq!(r.overrun_events, 0);
    // The draw covered the budget and the FIFO was really used to its depth: the test
    // would fail with a FIFO one frame shallower.
    assert!(r.max_latency_drawn > budget - MIN_FRAME_BITS, "{r:?}");
    assert_eq!(r.max_interval_arrivals, B::RX_FIFO_DEPTH as u64, "{r:?}");
    // Back to back: the bus carried nothing but these frames.
    assert!(r.bus_bits < frames * (MIN_FRAME_BITS + 6) + 10_000, "{r:?}");
    r
}

fn beyond_budget<B: LoadInstance>(frames: u64, seed: u64) -> LoadReport {
    let budget = budget_bits(B::RX_FIFO_DEPTH);
    let r = full_load::<B>(frames, 4 * budget, seed);
    println!("{} beyond budget ({} bits): {r:?}", B::NAME, 4 * budget);
    r.assert_accounted(B::NAME);
    assert_statistics::<B>(&r);
    assert_eq!(r.sent, frames);
    assert!(
        r.hw_lost > 0,
        "{}: latencies beyond the budget lose frames",
        B::NAME
    );
    assert!(r.overrun_events > 0 && r.overrun_events <= r.hw_lost);
    r
}

#[test]
fn flexcan_full_load_within_budget_loses_nothing() {
    within_budget::<FlexCanBackend>(DEFAULT_FRAMES, 0xF1E7_CA01);
}

#[test]
fn bxcan_full_load_within_budget_loses_nothing() {
    within_budget::<BxCanBackend>(DEFAULT_FRAMES, 0xB7CA_0001);
}

#[test]
fn flexcan_full_load_beyond_budget_counts_every_loss() {
    beyond_budget::<FlexCanBackend>(DEFAULT_FRAMES / 2, 0xF1E7_CA02);
}

#[test]
fn bxcan_full_load_beyond_budget_counts_every_loss() {
    beyond_budget::<BxCanBackend>(DEFAULT_FRAMES / 2, 0xB7CA_0002);
}

#[test]
fn lean_flexcan_full_load_within_budget_loses_nothing() {
    within_budget::<LeanFlexCan>(DEFAULT_FRAMES, 0xF1E7_CA11);
}

#[test]
fn lean_bxcan_full_load_within_budget_loses_nothing() {
    within_budget::<LeanBxCan>(DEFAULT_FRAMES, 0xB7CA_0011);
}

#[test]
fn lean_flexcan_full_load_beyond_budget_counts_every_loss() {
    beyond_budget::<LeanFlexCan>(DEFAULT_FRAMES / 2, 0xF1E7_CA12);
}

#[test]
fn lean_bxcan_full_load_beyond_budget_counts_every_loss() {
    beyond_budget::<LeanBxCan>(DEFAULT_FRAMES / 2, 0xB7CA_0012);
}

#[test]
fn lean_rt1062_full_load_within_budget_loses_nothing() {
    within_budget::<LeanRt1062>(DEFAULT_FRAMES, 0xF1E7_CA21);
}

/// The RT1062 lean instance is the module `teensy4-loopback-lean` begins, in its layout:
/// the RT1062 model (64 message buffers), `MCR[MAXMB]` at the RT1062 layout's data
/// mailbox for the 12/12 partition (MB16: ACAN's layout stops at MB15), the ERR005829
/// reserved mailbox after the Rx FIFO area INACTIVE with its interrupt masked (i.MX
/// RT1060 chip errata, ERR005829; `twocan_flexcan::layout::Layout::E5829`).
#[test]
fn lean_rt1062_node_is_begun_in_the_rt1062_layout() {
    let mut h = Harness::new(FULL_LOAD_BIT_RATE).expect("bus");
    let node = LeanRt1062::attach_via(&mut h, |bus, name, n| bus.attach_boxed(name, n));
    let c = Configuration::Filters12_12;
    assert_eq!(node.model.message_buffers(), 64);
    let maxmb = mcr::MAXMB.get(node.model.peek32(regs::MCR)) as usize;
    assert_eq!(maxmb, Imxrt1062::data_mailbox(c) as usize);
    assert_ne!(maxmb, Kinetis::data_mailbox(c) as usize);
    let reserved = usize::from(Imxrt1062::reserved_mailbox(c).expect("ERR005829 mailbox"));
    assert!(reserved < maxmb);
    let reserved_cs = node.model.peek32(regs::mb_cs(reserved));
    assert_eq!(cs::CODE.get(reserved_cs), code::TX_INACTIVE);
    assert_eq!(node.model.peek32(regs::IMASK1) & (1 << reserved), 0);
}

#[test]
fn lean_rt1062_full_load_beyond_budget_counts_every_loss() {
    beyond_budget::<LeanRt1062>(DEFAULT_FRAMES / 2, 0xF1E7_CA22);
}

#[test]
#[ignore = "full load: run with --release -- --ignored"]
fn flexcan_full_load_1m_frames() {
    within_budget::<FlexCanBackend>(FULL_FRAMES, 0xF1E7_CA03);
    beyond_budget::<FlexCanBackend>(FULL_FRAMES, 0xF1E7_CA04);
}

#[test]
#[ignore = "full load: run with --release -- --ignored"]
fn bxcan_full_load_1m_frames() {
    within_budget::<BxCanBackend>(FULL_FRAMES, 0xB7CA_0003);
    beyond_budget::<BxCanBackend>(FULL_FRAMES, 0xB7CA_0004);
}

#[test]
#[ignore = "full load: run with --release -- --ignored"]
fn lean_flexcan_full_load_1m_frames() {
    within_budget::<LeanFlexCan>(FULL_FRAMES, 0xF1E7_CA13);
    beyond_budget::<LeanFlexCan>(FULL_FRAMES, 0xF1E7_CA14);
}

#[test]
#[ignore = "full load: run with --release -- --ignored"]
fn lean_bxcan_full_load_1m_frames() {
    within_budget::<LeanBxCan>(FULL_FRAMES, 0xB7CA_0013);
    beyond_budget::<LeanBxCan>(FULL_FRAMES, 0xB7CA_0014);
}

#[test]
#[ignore = "full load: run with --release -- --ignored"]
fn lean_rt1062_full_load_1m_frames() {
    within_budget::<LeanRt1062>(FULL_FRAMES, 0xF1E7_CA23);
    beyond_budget::<LeanRt1062>(FULL_FRAMES, 0xF1E7_CA24);
}
