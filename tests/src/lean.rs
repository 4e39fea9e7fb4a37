//! The lean split driver as the firmware examples build it (issue 21), one definition
//! for every host test that runs it (`split_threads`, `full_load`), over any register
//! handle (a harness model's, or the threaded test's shared world). Three instances:
//!
//! - every one: the split driver with no completion ring (`DONE` = 0, fire-and-forget
//!   transmit) and the [`twocan_core::Lean`] feature set (no traffic statistics, no time
//!   stamps read): with a request-order queue, the quiet transmit mode on both backends;
//! - bxCAN (STM32F767 CAN1): configured in place in the state (`State::split_with`,
//!   `BxCan::can1_in`) from a `const` plan (`const_plan!`, the planner not used), the
//!   filter map sized to that plan (no lookup key, [`BX_LEAN_FMIS`] match indices) and
//!   the filters fixed (`SWITCH` = false), time stamps off (`CAN_MCR.TTCM` = 0) — the
//!   bench's lean bxCAN firmware (`bench/firmware/shared/bxcan_variant.rs`);
//! - FlexCAN, Teensy 3.6 can0 ([`Teensy36Can0`], ACAN's layout): `options::Lean` (no
//!   time stamps, no filter switch, the table planned at compile time by `const_plan!`),
//!   the settings checked at compile time (a `const` [`BeginPlan`]) and written by
//!   `FlexCan::begin_checked`, the 8-filter Rx FIFO partition — the bench's lean FlexCAN
//!   firmware (`bench/firmware/shared/flexcan_variant.rs`) and `teensy-loopback-lean`;
//! - FlexCAN, Teensy 4.1 CAN1 ([`Teensy41Can1`], the RT1062 model): `options::Lean` in
//!   the RT1062 layout (`Lean<Imxrt1062>`: the ERR005829 reserved mailbox after the Rx
//!   FIFO area), the table planned at compile time by `const_plan_large!`, a `const`
//!   `BeginPlan<Imxrt1062>`, ACAN's default 12/12 partition from the 24 MHz oscillator —
//!   `teensy4-loopback-lean` (`examples/teensy4/src/can.rs`, `LeanState`), begun by
//!   `begin_checked` as the token's `begin_planned_in_place` begins it (the fixed-base
//!   registers are the target's; the host uses the model's).
//!
//! Each FlexCAN instance is a [`LeanFlexPart`]: its module, clock and layout (the
//! [`FlexPart`] the conformance suite knows), its partition and its compile-time table.
//! All accept every frame into their one receive FIFO (bxCAN FIFO 0, FlexCAN's Rx FIFO)
//! with user filter 0.

use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::{const_plan as bx_const_plan, BxCan, Config, PlanOptions as BxPlanOptions};
use twocan_core::split::{Parts, State};
use twocan_core::txqueue::TxQueue;
use twocan_core::{Error, Features, FifoQueue, Filter, Hardware, Registers, TxPolicy};
use twocan_flexcan::installed::PlannedTable;
use twocan_flexcan::layout::{Imxrt1062, Kinetis};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::options::Lean;
use twocan_flexcan::planner::PlanOptions as FlexPlanOptions;
use twocan_flexcan::{
    const_plan as flex_const_plan, const_plan_large as flex_const_plan_large, BeginError,
    BeginPlan, Configuration, FlexCan, FlexCanHw, HostSystem, Settings,
};
use twocan_host::{Clocked, Harness, SetupError};
use twocan_sim::{Bus, BusNode, NodeId};

use crate::backend::{FlexPart, Teensy36Can0, Teensy41Can1};

/// The filter list of both lean controllers: user filter 0 accepts every frame.
pub const LEAN_FILTERS: [Filter; 1] = [Filter::pass_all()];

/// The APB1 clock of the STM32F767 the lean bxCAN node runs from (216 MHz core, /4).
pub const BX_APB1_HZ: u32 = 54_000_000;

/// The bxCAN planner's options: CAN1's banks at reset (`CAN_FMR.CAN2SB` = 14, RM0410
/// §40.9.4; the lean configuration leaves it), FIFO 0.
pub const BX_LEAN_PLAN_OPTIONS: BxPlanOptions = BxPlanOptions::new(14);

/// Match indices the lean bxCAN filter map holds per FIFO: exactly what the `const`
/// plan of [`LEAN_FILTERS`] numbers.
pub const BX_LEAN_FMIS: usize = bx_const_plan!(LEAN_FILTERS, BX_LEAN_PLAN_OPTIONS).match_indices();

/// The lean bxCAN controller over registers `R`: no lookup key, the map sized to the
/// plan, the filters fixed.
pub type BxLeanHw<R> = BxCan<R, R, 0, BX_LEAN_FMIS, false>;

/// The lean FlexCAN controller over registers `R` in the layout `L` (`options::Lean`;
/// ACAN's layout by default).
pub type FlexLeanHw<R, L = Kinetis> = FlexCanHw<R, Lean<L>>;

/// The lean bxCAN configuration at `bit_rate`: request-order transmit (the quiet mode's
/// condition and `FifoQueue`'s order), automatic bus-off recovery, time stamps off,
/// receive FIFOs not locked (`CAN_MCR.RFLM` = 0: a full FIFO's newest frame is
/// overwritten, RM0410 §40.7.5), the default interrupts (`FOVIE0` among them).
pub fn bx_lean_config(bit_rate: u32) -> Result<Config, twocan_bxcan::ConfigError> {
    Ok(Config::from_bitrate(BX_APB1_HZ, bit_rate)?
        .tx_policy(TxPolicy::Fifo)
        .recovery(twocan_bxcan::Recovery::Automatic)
        .timestamps(false)
        .rx_fifo_lock(false))
}

/// Configures CAN1 over `regs` with `config` and the `const` plan of [`LEAN_FILTERS`]
/// in place in `state`, and splits it.
#[allow(clippy::type_complexity)]
pub fn split_bx_lean<
    'a,
    R: Registers,
    const RX: usize,
    Q: TxQueue,
    const RX1: usize,
    const DONE: usize,
    Fe: Features,
>(
    state: &'a State<BxLeanHw<R>, RX, Q, RX1, DONE, Fe>,
    regs: R,
    config: &Config,
) -> Result<Parts<'a, BxLeanHw<R>, RX, Q, RX1, DONE, Fe>, Error> {
    let plan = bx_const_plan!(LEAN_FILTERS, BX_LEAN_PLAN_OPTIONS);
    state.split_with(|slot| BxCan::can1_in(slot, regs, config, plan).map_err(|f| f.error))
}

/// A FlexCAN module a lean split driver runs on, as a firmware example begins it: the
/// module, its CAN clock and layout ([`FlexPart`]), the Rx FIFO partition and the
/// pass-all table planned for it at compile time.
pub trait LeanFlexPart: FlexPart {
    /// The instance in messages.
    const LEAN_NAME: &'static str;
    /// The model's name on the bus.
    const BUS_NAME: &'static str;
    /// The Rx FIFO partition the example begins the module in.
    const CONFIGURATION: Configuration;
    /// [`LEAN_FILTERS`] planned at compile time for [`LeanFlexPart::CONFIGURATION`] in
    /// the part's layout, as the example plans it.
    fn table() -> PlannedTable;
}

/// The bench's lean FlexCAN firmware and `teensy-loopback-lean`: `const_plan!` in the
/// 8-filter partition, ACAN's layout.
impl LeanFlexPart for Teensy36Can0 {
    const LEAN_NAME: &'static str = "FlexCAN (Teensy 3.6 can0), lean split";
    const BUS_NAME: &'static str = "teensy36-can0-lean";
    const CONFIGURATION: Configuration = Configuration::Filters8_0;
    fn table() -> PlannedTable {
        flex_const_plan!(
            LEAN_FILTERS,
            FlexPlanOptions::new(<Teensy36Can0 as LeanFlexPart>::CONFIGURATION)
        )
        .planned()
    }
}

/// `teensy4-loopback-lean`: `const_plan_large!` (the RT1062 layout's planner) in the
/// settings' partition, ACAN's default 12/12 (`Settings::with_clock`).
impl LeanFlexPart for Teensy41Can1 {
    const LEAN_NAME: &'static str = "FlexCAN (Teensy 4.1 CAN1, RT1062 layout), lean split";
    const BUS_NAME: &'static str = "teensy41-can1-lean";
    const CONFIGURATION: Configuration = Configuration::Filters12_12;
    fn table() -> PlannedTable {
        flex_const_plan_large!(
            LEAN_FILTERS,
            FlexPlanOptions::new(<Teensy41Can1 as LeanFlexPart>::CONFIGURATION)
        )
        .planned()
    }
}

/// The lean FlexCAN settings of `P` at `RATE` (ACAN's defaults otherwise, from the
/// part's CAN clock) in the part's partition.
pub const fn flex_lean_settings<P: LeanFlexPart, const RATE: u32>() -> Settings {
    let mut s = Settings::with_clock(RATE, P::CLOCK);
    s.configuration = P::CONFIGURATION;
    s
}

/// Begins the lean FlexCAN controller of `P` over `regs` at `RATE`: the settings checked
/// (a `const` [`BeginPlan`] in the part's layout) and the pass-all table planned at
/// compile time ([`LeanFlexPart::table`]), written by `begin_checked`.
pub fn begin_flex_lean<P: LeanFlexPart, const RATE: u32, R: Registers>(
    regs: R,
) -> Result<FlexLeanHw<R, P::Layout>, BeginError> {
    let checked: BeginPlan<P::Layout> = const {
        BeginPlan::new_with_layout_or_panic(
            P::TARGET,
            &flex_lean_settings::<P, RATE>(),
            P::CONFIGURATION,
        )
    };
    FlexCan::begin_checked(regs, &mut HostSystem::new(), &checked, P::table())
}

// ---------------------------------------------------------------------------------------
// The lean nodes on the host harness's bus.

/// Receive ring of the lean host nodes (frames): the bench's lean firmware's.
pub const LEAN_RX: usize = 8;
/// Transmit queue of the lean host nodes: the bench's lean firmware's, request order.
pub type LeanQueue = FifoQueue<8>;

/// The lean bxCAN controller over its model.
pub type BxLeanModelHw = BxLeanHw<Clocked<BxCanModel>>;
/// The lean FlexCAN controller over its model, in the layout `L`.
pub type FlexLeanModelHw<L = Kinetis> = FlexLeanHw<Clocked<FlexCanModel>, L>;
/// The lean bxCAN node's state: FIFO 0's ring only (`RX1` = 0), no completions, `Lean`.
pub type BxLeanState = State<BxLeanModelHw, LEAN_RX, LeanQueue, 0, 0, twocan_core::Lean>;
/// The lean FlexCAN node's state in the layout `L`: no completions, `Lean`.
pub type FlexLeanState<L = Kinetis> =
    State<FlexLeanModelHw<L>, LEAN_RX, LeanQueue, 0, 0, twocan_core::Lean>;

// The lean choices are the quiet transmit mode on both backends, in both layouts.
const _: () = assert!(
    BxLeanState::QUIET_TX
        && FlexLeanState::<Kinetis>::QUIET_TX
        && FlexLeanState::<Imxrt1062>::QUIET_TX
);

/// A node of a lean split driver on the harness bus: its model, its place on the bus,
/// the state (leaked: a firmware keeps it in a `static`, and the handles borrow it) and
/// every handle `split` gave.
pub struct LeanNode<H: Hardware + 'static, M> {
    /// The peripheral model (its interrupt lines, its counters).
    pub model: M,
    /// Its place on the bus.
    pub id: NodeId,
    /// The shared state.
    pub state: &'static State<H, LEAN_RX, LeanQueue, 0, 0, twocan_core::Lean>,
    /// The halves and interrupt handlers.
    pub parts: Parts<'static, H, LEAN_RX, LeanQueue, 0, 0, twocan_core::Lean>,
}

/// A lean bxCAN node (STM32F767 CAN1).
pub type LeanBxNode = LeanNode<BxLeanModelHw, BxCanModel>;
/// A lean FlexCAN node of the part `P`.
pub type LeanFlexNode<P> = LeanNode<FlexLeanModelHw<<P as FlexPart>::Layout>, FlexCanModel>;

/// Brings a lean bxCAN node up on `h`'s bus at its bit rate; `attach` puts the model on
/// the bus (to wrap it, see `twocan_host::BxNode::with_config_via`).
pub fn attach_bx_lean(
    h: &mut Harness,
    attach: impl FnOnce(&mut Bus, &str, Box<dyn BusNode>) -> NodeId,
) -> Result<LeanBxNode, SetupError> {
    let model = BxCanModel::can1();
    let id = attach(
        &mut h.bus().borrow_mut(),
        "stm32f767-can1-lean",
        Box::new(model.clone()),
    );
    let regs = Clocked::new(model.clone(), h.bus(), twocan_bxcan::regs::MSR);
    let config = bx_lean_config(h.bus().borrow().bit_rate()).map_err(SetupError::BxCanConfig)?;
    let state: &'static BxLeanState = Box::leak(Box::new(State::new()));
    let parts = split_bx_lean(state, regs, &config).map_err(SetupError::Driver)?;
    Ok(LeanNode {
        model,
        id,
        state,
        parts,
    })
}

/// Brings a lean FlexCAN node of `P` up on `h`'s bus at `RATE` (the bus's bit rate,
/// checked) over the model of its chip; `attach` puts the model on the bus.
pub fn attach_flex_lean<P: LeanFlexPart, const RATE: u32>(
    h: &mut Harness,
    attach: impl FnOnce(&mut Bus, &str, Box<dyn BusNode>) -> NodeId,
) -> Result<LeanFlexNode<P>, SetupError> {
    if h.bus().borrow().bit_rate() != RATE {
        return Err(SetupError::Driver(Error::InvalidArgument));
    }
    let model = FlexCanModel::new(P::TARGET.model_chip());
    let id = attach(
        &mut h.bus().borrow_mut(),
        P::BUS_NAME,
        Box::new(model.clone()),
    );
    let regs = Clocked::with_poll_registers(
        model.clone(),
        h.bus(),
        &[twocan_flexcan::regs::MCR, twocan_flexcan::regs::ESR1],
    );
    let hw = begin_flex_lean::<P, RATE, _>(regs).map_err(SetupError::FlexCan)?;
    let state: &'static FlexLeanState<P::Layout> = Box::leak(Box::new(State::new()));
    let parts = state.split(hw).map_err(|(e, _)| SetupError::Driver(e))?;
    Ok(LeanNode {
        model,
        id,
        state,
        parts,
    })
}
