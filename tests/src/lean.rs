//! The lean split driver as a firmware example builds it (issue 21), one definition for
//! every host test that runs it (`split_threads`, `full_load`), over any register handle
//! (a harness model's, or the threaded test's shared world):
//!
//! - the split driver with no completion ring (`DONE` = 0, fire-and-forget transmit) and
//!   the [`twocan_core::Lean`] feature set (no traffic statistics, no time stamps read):
//!   with a request-order queue, the quiet transmit mode on both backends;
//! - bxCAN: CAN1 configured in place in the state (`State::split_with`,
//!   `BxCan::can1_in`) from a `const` plan (`const_plan!`, the planner not used), the
//!   filter map sized to that plan (no lookup key, [`BX_LEAN_FMIS`] match indices) and
//!   the filters fixed (`SWITCH` = false), time stamps off (`CAN_MCR.TTCM` = 0) — the
//!   bench's lean bxCAN firmware (`bench/firmware/shared/bxcan_variant.rs`);
//! - FlexCAN: `options::Lean` (no time stamps, no filter switch, the table planned at
//!   compile time), the settings checked at compile time (a `const` [`BeginPlan`]) and
//!   written by `FlexCan::begin_checked`, the 8-filter Rx FIFO partition — the bench's
//!   lean FlexCAN firmware (`bench/firmware/shared/flexcan_variant.rs`) and
//!   `teensy-loopback-lean`.
//!
//! Both accept every frame into their one receive FIFO (bxCAN FIFO 0, FlexCAN's Rx
//! FIFO) with user filter 0.

use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::{const_plan as bx_const_plan, BxCan, Config, PlanOptions as BxPlanOptions};
use twocan_core::split::{Parts, State};
use twocan_core::txqueue::TxQueue;
use twocan_core::{Error, Features, FifoQueue, Filter, Hardware, Registers, TxPolicy};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::options::Lean;
use twocan_flexcan::planner::PlanOptions as FlexPlanOptions;
use twocan_flexcan::{
    const_plan as flex_const_plan, BeginError, BeginPlan, Board, Configuration, FlexCan, FlexCanHw,
    HostSystem, Instance, Settings, Target,
};
use twocan_host::{Clocked, Harness, SetupError};
use twocan_sim::{Bus, BusNode, NodeId};

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

/// The lean FlexCAN controller over registers `R` (`options::Lean`, ACAN's layout).
pub type FlexLeanHw<R> = FlexCanHw<R, Lean>;

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

/// The lean FlexCAN node: can0 of a Teensy 3.6.
pub const FLEX_LEAN_TARGET: Target = Target::new(Board::Teensy36, Instance::Can0);

/// The lean FlexCAN settings at `RATE` (ACAN's defaults otherwise, 16 MHz oscillator
/// clock) in the 8-filter Rx FIFO partition.
pub const fn flex_lean_settings<const RATE: u32>() -> Settings {
    let mut s = Settings::new(RATE);
    s.configuration = Configuration::Filters8_0;
    s
}

/// Begins the lean FlexCAN controller over `regs` at `RATE`: the settings checked and
/// the pass-all table planned at compile time, written by `begin_checked`.
pub fn begin_flex_lean<const RATE: u32, R: Registers>(
    regs: R,
) -> Result<FlexLeanHw<R>, BeginError> {
    let checked: BeginPlan = const {
        BeginPlan::new_or_panic(
            FLEX_LEAN_TARGET,
            &flex_lean_settings::<RATE>(),
            Configuration::Filters8_0,
        )
    };
    let plan = flex_const_plan!(
        LEAN_FILTERS,
        FlexPlanOptions::new(Configuration::Filters8_0)
    )
    .planned();
    FlexCan::begin_checked(regs, &mut HostSystem::new(), &checked, plan)
}

// ---------------------------------------------------------------------------------------
// The lean nodes on the host harness's bus.

/// Receive ring of the lean host nodes (frames): the bench's lean firmware's.
pub const LEAN_RX: usize = 8;
/// Transmit queue of the lean host nodes: the bench's lean firmware's, request order.
pub type LeanQueue = FifoQueue<8>;

/// The lean bxCAN controller over its model.
pub type BxLeanModelHw = BxLeanHw<Clocked<BxCanModel>>;
/// The lean FlexCAN controller over its model.
pub type FlexLeanModelHw = FlexLeanHw<Clocked<FlexCanModel>>;
/// The lean bxCAN node's state: FIFO 0's ring only (`RX1` = 0), no completions, `Lean`.
pub type BxLeanState = State<BxLeanModelHw, LEAN_RX, LeanQueue, 0, 0, twocan_core::Lean>;
/// The lean FlexCAN node's state: no completions, `Lean`.
pub type FlexLeanState = State<FlexLeanModelHw, LEAN_RX, LeanQueue, 0, 0, twocan_core::Lean>;

// The lean choices are the quiet transmit mode on both backends.
const _: () = assert!(BxLeanState::QUIET_TX && FlexLeanState::QUIET_TX);

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
/// A lean FlexCAN node (Teensy 3.6 can0).
pub type LeanFlexNode = LeanNode<FlexLeanModelHw, FlexCanModel>;

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

/// Brings a lean FlexCAN node up on `h`'s bus at `RATE` (the bus's bit rate, checked);
/// `attach` puts the model on the bus.
pub fn attach_flex_lean<const RATE: u32>(
    h: &mut Harness,
    attach: impl FnOnce(&mut Bus, &str, Box<dyn BusNode>) -> NodeId,
) -> Result<LeanFlexNode, SetupError> {
    if h.bus().borrow().bit_rate() != RATE {
        return Err(SetupError::Driver(Error::InvalidArgument));
    }
    let model = FlexCanModel::new(FLEX_LEAN_TARGET.model_chip());
    let id = attach(
        &mut h.bus().borrow_mut(),
        "teensy36-can0-lean",
        Box::new(model.clone()),
    );
    let regs = Clocked::with_poll_registers(
        model.clone(),
        h.bus(),
        &[twocan_flexcan::regs::MCR, twocan_flexcan::regs::ESR1],
    );
    let hw = begin_flex_lean::<RATE, _>(regs).map_err(SetupError::FlexCan)?;
    let state: &'static FlexLeanState = Box::leak(Box::new(State::new()));
    let parts = state.split(hw).map_err(|(e, _)| SetupError::Driver(e))?;
    Ok(LeanNode {
        model,
        id,
        state,
        parts,
    })
}
