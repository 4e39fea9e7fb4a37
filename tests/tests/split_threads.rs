//! The split halves used from several threads: std threads stand in for the interrupt
//! context (one thread runs the bus and every interrupt handler) and for the thread
//! context (a sender and a receiver per node), with the `critical-section` std
//! implementation. A FlexCAN node and a bxCAN node (STM32F767 CAN1), the real drivers
//! over their models, exchange sequenced frames both ways: nothing lost, duplicated or
//! reordered, and the token/completion accounting is exact. Three pairs run (each with
//! 10,000 frames in the default run and 1,000,000 in its `#[ignore]`d release run):
//!
//! - the default choices (completions, statistics, time stamps), FlexCAN Teensy 3.6
//!   can0 begun with `begin`, bxCAN with the run-time plan;
//! - the lean choices a firmware example uses (no completions, `Lean` features, `const`
//!   filter plans, the quiet transmit mode on both backends; built by
//!   `twocan_tests::lean`, the same definitions `full_load` runs): bxCAN configured in
//!   place with the map sized to its plan and the filters fixed, with
//!   - FlexCAN Teensy 3.6 can0, `options::Lean` begun with `begin_checked` in the
//!     8-filter partition (`teensy-loopback-lean`);
//!   - FlexCAN Teensy 4.1 CAN1 over the RT1062 model, `options::Lean<Imxrt1062>` (the
//!     ERR005829 reserved mailbox), `const_plan_large!`, a `const`
//!     `BeginPlan<Imxrt1062>`, ACAN's 12/12 partition (`teensy4-loopback-lean`).
//!
//! The peripheral models are single-threaded (`Rc` handles, shared with the bus), so the
//! bus and both models live in one [`World`] behind a mutex, and every register access
//! of a driver locks it — as a real bus serialises accesses to one peripheral.

use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Arc, Mutex};

use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::{BxCan, Can, Config, FifoPolicy, Recovery};
use twocan_core::split::{Parts, State};
use twocan_core::{Features, FifoQueue, Filter, Frame, Hardware, Registers, TxOutcome, TxPolicy};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::options::{Full, Lean, Options};
use twocan_flexcan::{FlexCan, FlexCanHw, HostSystem, Settings};
use twocan_sim::Bus;
use twocan_tests::backend::{FlexPart, Teensy36Can0, Teensy41Can1};
use twocan_tests::lean::{bx_lean_config, split_bx_lean, BxLeanHw, LeanFlexPart};

const RATE: u32 = 1_000_000;
const APB1: u32 = 54_000_000;

/// The bus and the two models; only ever touched through the mutex.
struct World {
    bus: Bus,
    bx: BxCanModel,
    flex: FlexCanModel,
}

// SAFETY: the `Rc` handles inside (the models, and their clones attached to the bus)
// never leave `World`: the register handles reach them only while holding the one
// `Mutex<World>`, so no two threads touch them at the same time, and the test drops
// the `World` on one thread at the end.
unsafe impl Send for World {}

#[derive(Clone, Copy)]
enum Which {
    Bx,
    Flex,
}

/// Register access to one model of the world. Back-to-back reads of a poll register
/// let one bit time pass while `setup` is on (the drivers' bounded acknowledge waits).
struct WorldRegs {
    world: Arc<Mutex<World>>,
    which: Which,
    polls: &'static [usize],
    setup: Arc<AtomicBool>,
    spinning: Mutex<Cell<Option<usize>>>,
    /// Fails the run when a driver spins on a register the model never changes (a
    /// receive handler that never releases its FIFO) instead of hanging.
    watchdog: Mutex<twocan_sim::SpinWatchdog>,
}

impl Registers for WorldRegs {
    fn read32(&self, offset: usize) -> u32 {
        let mut w = self.world.lock().unwrap();
        let now = w.bus.now();
        self.watchdog
            .lock()
            .unwrap()
            .access(Some(now), "read", offset);
        if self.setup.load(Ordering::Relaxed) && self.polls.contains(&offset) {
            let spin = self.spinning.lock().unwrap();
            if spin.replace(Some(offset)) == Some(offset) {
                w.bus.run_for(1);
            }
        }
        match self.which {
            Which::Bx => w.bx.read32(offset),
            Which::Flex => w.flex.read32(offset),
        }
    }

    fn write32(&self, offset: usize, value: u32) {
        self.spinning.lock().unwrap().set(None);
        let w = self.world.lock().unwrap();
        let now = w.bus.now();
        self.watchdog
            .lock()
            .unwrap()
            .access(Some(now), "write", offset);
        match self.which {
            Which::Bx => w.bx.write32(offset, value),
            Which::Flex => w.flex.write32(offset, value),
        }
    }
}

type BxHw = BxCan<WorldRegs>;

fn frame(id: u16, seq: u32) -> Frame {
    Frame::standard(id, &seq.to_le_bytes()).unwrap()
}

/// Sets the stop flag when its thread unwinds (a failed assertion).
struct StopOnPanic<'a>(&'a AtomicBool);

impl Drop for StopOnPanic<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(true, Ordering::Release);
        }
    }
}

/// Sends `count` sequenced frames with identifier `id`, then accounts every completion:
/// one per token, in order, all sent (with `DONE` = 0, fire and forget: the tokens
/// alone, and the receiver proves delivery).
fn sender<H: twocan_core::Hardware, const DONE: usize, Fe: Features>(
    tx: &mut twocan_core::split::Tx<'_, H, 256, FifoQueue<32>, 0, DONE, Fe>,
    id: u16,
    count: u32,
    stop: &AtomicBool,
) {
    let mut next = 0u32;
    let mut expected_token = 0u32;
    while (if DONE == 0 { next } else { expected_token }) < count && !stop.load(Ordering::Acquire) {
        if next < count {
            match tx.try_send(&frame(id, next)) {
                Ok(t) => {
                    assert_eq!(t.0, next, "tokens in acceptance order");
                    next += 1;
                }
                Err(nb::Error::WouldBlock) => std::thread::yield_now(),
                Err(e) => panic!("{e:?}"),
            }
        }
        while let Some(c) = tx.take_completion() {
            assert_eq!(c.outcome, TxOutcome::Sent);
            assert_eq!(
                c.token.0, expected_token,
                "completions in order (sender {id:#x}): {c:?}"
            );
            expected_token += 1;
        }
    }
}

/// The FlexCAN node's settings (ACAN's defaults at the test's rate).
const FLEX_SETTINGS: Settings = Settings::new(RATE);

/// How the FlexCAN node is modelled and begun for one set of compile-time choices.
trait FlexBegin {
    /// The split driver's controller options.
    type O: Options + Send + Sync;
    /// The model of the node's chip, and its name on the bus.
    fn model() -> (FlexCanModel, &'static str);
    /// Begins the node over `regs`.
    fn begin(regs: WorldRegs) -> FlexCanHw<WorldRegs, Self::O>;
}

/// Every feature on Teensy 3.6 can0: `begin` with the list at run time.
enum FullFlex {}

impl FlexBegin for FullFlex {
    type O = Full;
    fn model() -> (FlexCanModel, &'static str) {
        (
            FlexCanModel::new(Teensy36Can0::TARGET.model_chip()),
            "teensy36-can0",
        )
    }
    fn begin(regs: WorldRegs) -> FlexCanHw<WorldRegs, Full> {
        FlexCan::begin(
            regs,
            &mut HostSystem::new(),
            Teensy36Can0::TARGET,
            &FLEX_SETTINGS,
            &[Filter::pass_all()],
            &[],
        )
        .unwrap()
        .into_split()
    }
}

/// The lean controller of the part `P` (`twocan_tests::lean`: Teensy 3.6 can0 in ACAN's
/// layout, or Teensy 4.1 CAN1 over the RT1062 model in the RT1062 layout): the plan and
/// the checks settled at compile time (`begin_checked`), no time stamps, no filter
/// switch.
struct LeanFlex<P>(std::marker::PhantomData<P>);

impl<P: LeanFlexPart> FlexBegin for LeanFlex<P> {
    type O = Lean<P::Layout>;
    fn model() -> (FlexCanModel, &'static str) {
        (FlexCanModel::new(P::TARGET.model_chip()), P::BUS_NAME)
    }
    fn begin(regs: WorldRegs) -> FlexCanHw<WorldRegs, Self::O> {
        twocan_tests::lean::begin_flex_lean::<P, RATE, _>(regs).unwrap()
    }
}

/// How the bxCAN node is configured and split for one set of compile-time choices.
trait BxBegin {
    /// The controller the split driver holds.
    type Hw: Hardware + Send + Sync;
    /// Configures CAN1 over `regs` and splits `state` over it.
    #[allow(clippy::type_complexity)]
    fn split<const DONE: usize, Fe: Features>(
        state: &State<Self::Hw, 256, FifoQueue<32>, 0, DONE, Fe>,
        regs: WorldRegs,
    ) -> Parts<'_, Self::Hw, 256, FifoQueue<32>, 0, DONE, Fe>;
}

/// Every feature: `Can::can1`, the run-time plan, `into_split` (the map with every
/// lookup key and match index, the filters replaceable).
enum FullBx {}

impl BxBegin for FullBx {
    type Hw = BxHw;
    fn split<const DONE: usize, Fe: Features>(
        state: &State<BxHw, 256, FifoQueue<32>, 0, DONE, Fe>,
        regs: WorldRegs,
    ) -> Parts<'_, BxHw, 256, FifoQueue<32>, 0, DONE, Fe> {
        let config = Config::from_bitrate(APB1, RATE)
            .unwrap()
            .recovery(Recovery::Automatic)
            .tx_policy(TxPolicy::Fifo);
        let mut init = Can::can1(regs, &config).map_err(|f| f.error).unwrap();
        let plan = init
            .can()
            .plan(&[Filter::pass_all()], FifoPolicy::Fifo0)
            .unwrap();
        init.set_filters(&plan).unwrap();
        let can = init.enable().map_err(|f| f.error).unwrap();
        state.split(can.into_split()).ok().unwrap()
    }
}

/// The lean controller (`twocan_tests::lean`): configured in place from a `const` plan,
/// the map sized to it, the filters fixed, time stamps off.
enum LeanBx {}

impl BxBegin for LeanBx {
    type Hw = BxLeanHw<WorldRegs>;
    fn split<const DONE: usize, Fe: Features>(
        state: &State<Self::Hw, 256, FifoQueue<32>, 0, DONE, Fe>,
        regs: WorldRegs,
    ) -> Parts<'_, Self::Hw, 256, FifoQueue<32>, 0, DONE, Fe> {
        let config = bx_lean_config(RATE).unwrap();
        split_bx_lean(state, regs, &config).unwrap()
    }
}

/// Moves `per_direction` frames each way with the default driver (completions, time
/// stamps, statistics); returns (frames received by the bxCAN node, by the FlexCAN node).
fn exchange(per_direction: u32) -> (u32, u32) {
    exchange_with::<64, twocan_core::Full, FullFlex, FullBx>(per_direction)
}

/// [`exchange`] with the lean choices a firmware example makes (`teensy-loopback-lean`):
/// no completion ring, the split driver's `Lean` features, FlexCAN's `options::Lean`,
/// bxCAN configured in place from a `const` plan with the map sized to it
/// (`twocan_tests::lean`, one definition with `full_load`), both controllers in request
/// order (as in [`exchange`]) — the quiet transmit mode on both backends.
fn exchange_lean(per_direction: u32) -> (u32, u32) {
    exchange_with::<0, twocan_core::Lean, LeanFlex<Teensy36Can0>, LeanBx>(per_direction)
}

/// [`exchange_lean`] with the FlexCAN node of `teensy4-loopback-lean`: Teensy 4.1 CAN1
/// over the RT1062 model, `options::Lean<Imxrt1062>` (the ERR005829 reserved mailbox),
/// the table of `const_plan_large!` in ACAN's 12/12 partition, a `const`
/// `BeginPlan<Imxrt1062>` (`twocan_tests::lean`, one definition with `full_load`).
fn exchange_lean_rt1062(per_direction: u32) -> (u32, u32) {
    exchange_with::<0, twocan_core::Lean, LeanFlex<Teensy41Can1>, LeanBx>(per_direction)
}

/// [`exchange`] for the compile-time choices `DONE`, `Fe`, `F` (FlexCAN), `B` (bxCAN);
/// both controllers send in request order (the quiet mode's condition, and the
/// `FifoQueue`'s order).
fn exchange_with<const DONE: usize, Fe: Features, F: FlexBegin, B: BxBegin>(
    per_direction: u32,
) -> (u32, u32) {
    let bx = BxCanModel::can1();
    let (flex, flex_name) = F::model();
    let mut bus = Bus::new(RATE).unwrap();
    bus.attach("stm32f767-can1", bx.clone());
    bus.attach(flex_name, flex.clone());
    let world = Arc::new(Mutex::new(World { bus, bx, flex }));
    let setup = Arc::new(AtomicBool::new(true));
    let regs = |which, polls| WorldRegs {
        world: world.clone(),
        which,
        polls,
        setup: setup.clone(),
        spinning: Mutex::new(Cell::new(None)),
        watchdog: Mutex::default(),
    };

    const BX_POLLS: &[usize] = &[twocan_bxcan::regs::MSR];
    const FLEX_POLLS: &[usize] = &[twocan_flexcan::regs::MCR, twocan_flexcan::regs::ESR1];
    let bx_state: State<B::Hw, 256, FifoQueue<32>, 0, DONE, Fe> = State::new();
    let flex_state: State<FlexCanHw<WorldRegs, F::O>, 256, FifoQueue<32>, 0, DONE, Fe> =
        State::new();
    assert_eq!(
        State::<B::Hw, 256, FifoQueue<32>, 0, DONE, Fe>::QUIET_TX,
        DONE == 0
    );
    assert_eq!(
        State::<FlexCanHw<WorldRegs, F::O>, 256, FifoQueue<32>, 0, DONE, Fe>::QUIET_TX,
        DONE == 0
    );
    // bxCAN configured (in place, for the lean choices) and split, FlexCAN begun, while
    // the polls let bus time pass.
    let bx_parts = B::split(&bx_state, regs(Which::Bx, BX_POLLS));
    let flex_can = F::begin(regs(Which::Flex, FLEX_POLLS));
    // Both synchronised to the idle bus before traffic.
    world.lock().unwrap().bus.run_for(20);
    setup.store(false, Ordering::Relaxed);

    let flex_parts = flex_state.split(flex_can).ok().unwrap();
    let received = [AtomicU32::new(0), AtomicU32::new(0)];
    let done = AtomicBool::new(false);
    // Set by a thread that panics, so that the others stop instead of spinning on.
    let stop = AtomicBool::new(false);

    std::thread::scope(|s| {
        let (mut bx_tx, mut bx_rx) = (bx_parts.tx, bx_parts.rx);
        let (mut fx_tx, mut fx_rx) = (flex_parts.tx, flex_parts.rx);
        let (mut bx_tx_irq, mut bx_rx_irq, mut bx_status) =
            (bx_parts.tx_irq, bx_parts.rx0_irq, bx_parts.status_irq);
        let (mut fx_tx_irq, mut fx_rx_irq, mut fx_status) =
            (flex_parts.tx_irq, flex_parts.rx0_irq, flex_parts.status_irq);
        let world = &world;
        let done = &done;
        let received = &received;
        let stop = &stop;

        // The interrupt context: the bus runs, the raised lines are serviced.
        let (bx_state, flex_state) = (&bx_state, &flex_state);
        s.spawn(move || {
            let _stop = StopOnPanic(stop);
            // (frames received by both nodes, when that last changed)
            let mut progress = (0u32, std::time::Instant::now());
            while !done.load(Ordering::Acquire) && !stop.load(Ordering::Acquire) {
                // Simulated time is ours to hold: the bus does not run ahead of a
                // receiving thread the scheduler has left behind (its ring would
                // overflow — counted, but this test is about nothing being lost).
                if bx_state.rx_stats().count > 192 || flex_state.rx_stats().count > 192 {
                    std::thread::yield_now();
                    continue;
                }
                let (bx_lines, flex_pending) = {
                    let mut w = world.lock().unwrap();
                    w.bus.run_for(40);
                    // Bounded: the run fails when no frame is received for a minute
                    // of wall time. Bus time is no measure here: the bus runs on while
                    // the scheduler leaves the application threads behind (on a busy
                    // two-core machine, for many simulated seconds).
                    let got =
                        received[0].load(Ordering::Acquire) + received[1].load(Ordering::Acquire);
                    if got != progress.0 {
                        progress = (got, std::time::Instant::now());
                    }
                    assert!(
                        progress.1.elapsed() < std::time::Duration::from_secs(60),
                        "no frame received for a minute: {} of {per_direction} (bxCAN) \
                         and {} (FlexCAN)",
                        received[0].load(Ordering::Acquire),
                        received[1].load(Ordering::Acquire)
                    );
                    (w.bx.irq_lines(), w.flex.irq_pending())
                };
                if bx_lines.tx {
                    bx_tx_irq.on_interrupt();
                }
                if bx_lines.rx0 {
                    bx_rx_irq.on_interrupt();
                }
                if bx_lines.sce {
                    bx_status.on_interrupt();
                }
                if flex_pending {
                    fx_tx_irq.on_interrupt();
                    fx_rx_irq.on_interrupt();
                    fx_status.on_interrupt();
                }
            }
        });

        // A sender per node: sequenced frames, then every completion accounted.
        s.spawn(move || {
            let _stop = StopOnPanic(stop);
            sender(&mut bx_tx, 0x200, per_direction, stop)
        });
        s.spawn(move || {
            let _stop = StopOnPanic(stop);
            sender(&mut fx_tx, 0x100, per_direction, stop)
        });

        // A receiver per node: every frame of the peer, once, in order.
        s.spawn(move || {
            let _stop = StopOnPanic(stop);
            let mut expect = 0u32;
            while expect < per_direction && !stop.load(Ordering::Acquire) {
                match bx_rx.receive() {
                    Ok(rx) => {
                        assert_eq!(rx.frame, frame(0x100, expect), "bxCAN node");
                        expect += 1;
                        received[0].store(expect, Ordering::Release);
                    }
                    Err(_) => std::thread::yield_now(),
                }
            }
        });
        s.spawn(move || {
            let _stop = StopOnPanic(stop);
            let mut expect = 0u32;
            while expect < per_direction && !stop.load(Ordering::Acquire) {
                match fx_rx.receive() {
                    Ok(rx) => {
                        assert_eq!(rx.frame, frame(0x200, expect), "FlexCAN node");
                        expect += 1;
                        received[1].store(expect, Ordering::Release);
                    }
                    Err(_) => std::thread::yield_now(),
                }
            }
            while received[0].load(Ordering::Acquire) < per_direction
                && !stop.load(Ordering::Acquire)
            {
                std::thread::yield_now();
            }
            done.store(true, Ordering::Release);
        });
    });

    for (name, state) in [
        ("bxCAN", bx_state.traffic()),
        ("FlexCAN", flex_state.traffic()),
    ] {
        // Without statistics (`Lean`) the traffic counters stay 0; the receivers above
        // proved every frame arrived once and in order.
        let counted = if Fe::COUNTS { per_direction } else { 0 };
        assert_eq!(state.queued, counted, "{name}");
        assert_eq!(state.sent, counted, "{name}");
        assert_eq!(state.received, counted, "{name}");
        assert_eq!(state.rx_ring_overflows, 0, "{name}");
        assert_eq!(state.completion_overflows, 0, "{name}");
        assert_eq!(state.failed + state.aborted, 0, "{name}");
    }
    assert_eq!(bx_state.rx_stats().overflows, 0);
    assert_eq!(flex_state.rx_stats().overflows, 0);
    assert_eq!(bx_state.error_stats().hardware_overruns, 0);
    assert_eq!(flex_state.error_stats().hardware_overruns, 0);
    (
        received[0].load(Ordering::Relaxed),
        received[1].load(Ordering::Relaxed),
    )
}

#[test]
fn split_halves_on_threads_move_frames_both_ways() {
    assert_eq!(exchange(5_000), (5_000, 5_000));
}

/// 500,000 frames each way: 1,000,000 through the two backends' models. Slow in a
/// debug build: CI runs it in release with `--ignored`.
#[test]
#[ignore]
fn split_halves_on_threads_move_a_million_frames() {
    assert_eq!(exchange(500_000), (500_000, 500_000));
}

/// The lean choices (quiet transmit mode on both backends, no completions, no
/// statistics, FlexCAN's compile-time plan): frames both ways, none lost, duplicated or
/// reordered.
#[test]
fn lean_split_halves_on_threads_move_frames_both_ways() {
    assert_eq!(exchange_lean(5_000), (5_000, 5_000));
}

/// [`lean_split_halves_on_threads_move_frames_both_ways`] with 1,000,000 frames (release,
/// `--ignored` in CI).
#[test]
#[ignore]
fn lean_split_halves_on_threads_move_a_million_frames() {
    assert_eq!(exchange_lean(500_000), (500_000, 500_000));
}

/// The lean choices with the FlexCAN node of `teensy4-loopback-lean` (Teensy 4.1 CAN1,
/// RT1062 model and layout): frames both ways, none lost, duplicated or reordered.
#[test]
fn lean_rt1062_split_halves_on_threads_move_frames_both_ways() {
    assert_eq!(exchange_lean_rt1062(5_000), (5_000, 5_000));
}

/// [`lean_rt1062_split_halves_on_threads_move_frames_both_ways`] with 1,000,000 frames
/// (release, `--ignored` in CI).
#[test]
#[ignore]
fn lean_rt1062_split_halves_on_threads_move_a_million_frames() {
    assert_eq!(exchange_lean_rt1062(500_000), (500_000, 500_000));
}
