//! The one call of the Teensy 4 (`acan::can1` ..., ACAN_T4's `begin`/`end`; features `rt`
//! and `teensy40` or `teensy41`) over the behavioural model of CAN1: what `acan::start`
//! and `acan::end` do with a module's token, its spare slot and its state — the board's
//! one calls are these two over the target's tokens, which on the host reach no
//! registers.
//!
//! The token here is the test's own [`acan::Module`]: taken once, it begins CAN1 of a
//! Teensy 4.1 over the RT1062 model (64 message buffers) in the RT1062 layout, as the
//! board's `Can1` does, and ends back into a token. The NVIC records its calls; the
//! "interrupt" is the exported `CAN1` entry point, run whenever the model raises its
//! line. The registers record every write, so that the ERR005829 workaround of the
//! RT1062 layout shows (`driver_rt1062_e5829.rs` tests it for every configuration): the
//! reserved mailbox after the Rx FIFO area reads INACTIVE and is masked, and each
//! transmit activation is followed by two INACTIVE writes into it. The board's one
//! calls are checked to be typed in that layout (a one call back on the Kinetis layout
//! does not compile here).
//!
//! One test function: the entry points' slots are process-wide, and the model (`Rc`, one
//! thread) is shared with the "interrupt" side only on this thread.
#![cfg(all(feature = "rt", any(feature = "teensy40", feature = "teensy41")))]

use std::cell::RefCell;
use std::mem::MaybeUninit;
use std::sync::atomic::{AtomicBool, Ordering};

use twocan_core::{Error, Filter, Frame, Registers, TxOutcome};
use twocan_flexcan::acan::{self, Module, OneCallError, Spare};
use twocan_flexcan::filters::TableSlot;
use twocan_flexcan::layout::{BoardLayout, Imxrt1062, LargeFilterTable, Layout};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::options::{Full, FullInSlot};
use twocan_flexcan::regs::{self, code, cs, mcr, FlexCanRegs};
use twocan_flexcan::rt::{self, IrqNumber, Nvic, StartError};
use twocan_flexcan::{
    rt_imxrt, BeginError, BeginPlan, Board, ConfigErrors, Configuration, FlexCan, FlexCanHw,
    HostSystem, IdleClocked, Instance, Settings, Target,
};
use twocan_sim::Bus;

/// The model's registers, declared shareable between "contexts" that are all this
/// test's one thread; every write is recorded in [`WRITES`].
struct OneThread(IdleClocked);

// SAFETY: the registers (an `Rc` model) are reached only from the thread that runs the
// one test of this binary: the "interrupts" are the entry-point calls it makes.
unsafe impl Send for OneThread {}
// SAFETY: as above.
unsafe impl Sync for OneThread {}

impl Registers for OneThread {
    fn read32(&self, offset: usize) -> u32 {
        self.0.read32(offset)
    }
    fn write32(&self, offset: usize, value: u32) {
        WRITES.with(|w| w.borrow_mut().push((offset, value)));
        self.0.write32(offset, value)
    }
}

const TARGET: Target = Target::new(Board::Teensy41, Instance::Can1);

thread_local! {
    /// The module the test's token owns.
    static MODEL: RefCell<Option<FlexCanModel>> = const { RefCell::new(None) };
    /// The register writes of the module, in order (offset, value).
    static WRITES: RefCell<Vec<(usize, u32)>> = const { RefCell::new(Vec::new()) };
}
static TAKEN: AtomicBool = AtomicBool::new(false);

/// The test's CAN1 token: `take` gives it once, as the target's `Can1::take`.
struct HostCan1(FlexCanModel);

impl Module for HostCan1 {
    type Regs = OneThread;
    // As the board's `Can1`.
    type Layout = Imxrt1062;
    const TARGET: Target = TARGET;

    fn take() -> Option<Self> {
        if TAKEN.swap(true, Ordering::AcqRel) {
            return None;
        }
        MODEL.with(|m| m.borrow().clone()).map(HostCan1)
    }

    fn begin_in_place<'h>(
        self,
        hw: &'h mut MaybeUninit<FlexCanHw<OneThread, FullInSlot<Imxrt1062>>>,
        checked: &BeginPlan<Imxrt1062>,
        primary: &[Filter],
        secondary: &[Filter],
        slot: &'static mut LargeFilterTable,
    ) -> Result<
        &'h mut FlexCanHw<OneThread, FullInSlot<Imxrt1062>>,
        (Self, BeginError, &'static mut LargeFilterTable),
    > {
        let regs = OneThread(IdleClocked::new(self.0.clone()));
        FlexCan::begin_in_place(
            hw,
            regs,
            &mut HostSystem::new(),
            checked,
            primary,
            secondary,
            slot,
        )
        .map_err(|(e, slot)| (self, e, slot))
    }

    #[allow(clippy::type_complexity)]
    fn end_split(
        hw: FlexCanHw<OneThread, FullInSlot<Imxrt1062>>,
    ) -> Result<
        (Self, &'static mut LargeFilterTable),
        (FlexCanHw<OneThread, FullInSlot<Imxrt1062>>, Error),
    > {
        if hw.target() != TARGET {
            return Err((hw, Error::InvalidArgument));
        }
        hw.end(&mut HostSystem::new())
            .map(|(regs, table)| (HostCan1(regs.0.model().clone()), table))
    }
}

/// CAN1's filter table, which the one call's `begin` compiles into (the RT1062
/// layout's, 128 elements).
static TABLE: TableSlot<LargeFilterTable> = TableSlot::new_sized();

/// The one call with `settings` checked first, as the board's `can1_with` does.
fn start(
    spare: &Spare<HostCan1>,
    state: &'static State,
    settings: &Settings,
    primary: &[Filter],
    secondary: &[Filter],
    nvic: &mut Recorder,
) -> Result<acan::AcanHalves<OneThread>, OneCallError> {
    let checked = BeginPlan::<Imxrt1062>::new_with_layout(TARGET, settings, settings.configuration)
        .map_err(OneCallError::Begin)?;
    acan::start(spare, &TABLE, state, &checked, primary, secondary, nvic)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Call {
    Priority(u16, u8),
    Unmask(u16),
    Mask(u16),
}

#[derive(Default)]
struct Recorder(Vec<Call>);

impl Nvic for Recorder {
    fn set_priority(&mut self, irq: IrqNumber, priority: u8) {
        self.0.push(Call::Priority(irq.number(), priority));
    }
    fn unmask(&mut self, irq: IrqNumber) {
        self.0.push(Call::Unmask(irq.number()));
    }
    fn mask(&mut self, irq: IrqNumber) {
        self.0.push(Call::Mask(irq.number()));
    }
}

/// The one call's state over the test's registers, in the board's layout (the
/// default of `OneCallState`), which the first test checks is the RT1062's.
type State = acan::OneCallState<OneThread>;

/// Runs the bus for `bits`, entering `CAN1` whenever the model raises its line.
fn run(bus: &mut Bus, model: &FlexCanModel, bits: u64) -> u32 {
    let until = bus.now() + bits;
    let mut entered = 0;
    loop {
        while model.irq_pending() {
            rt_imxrt::can1();
            entered += 1;
            assert!(entered < 10_000, "the line stays asserted");
        }
        if bus.step_until(until).is_none() {
            break;
        }
    }
    entered
}

/// The one call's loop-back settings: the board's defaults at 500 kbit/s.
fn loop_back() -> Settings {
    let mut s = acan::default_settings(500_000);
    s.loop_back = true;
    s.self_reception = true;
    s
}

fn disabled(model: &FlexCanModel) -> bool {
    model.read32(regs::MCR) & mcr::MDIS != 0
}

/// The message buffer and word (0 = C/S) a register offset belongs to.
fn mb_word(offset: usize) -> Option<(usize, usize)> {
    let first = regs::mb_cs(0);
    (first..regs::mb_cs(64))
        .contains(&offset)
        .then(|| ((offset - first) / 16, (offset - first) % 16 / 4))
}

/// ERR005829 with the RT1062 layout, right after the one call's `begin`: the first
/// mailbox after the Rx FIFO area of the settings' configuration reads INACTIVE (over
/// the garbage the RAM held), has no interrupt mask bit, and lies inside `MCR[MAXMB]`,
/// whose value is the data mailbox after it (the Kinetis layout: that mailbox is a
/// remote-frame one, unmasked, and `MAXMB` 15).
fn assert_reserved_mailbox(model: &FlexCanModel, settings: &Settings) -> usize {
    let c = settings.configuration;
    let reserved = usize::from(c.reserved_mailbox());
    assert_eq!(reserved, regs::rx_fifo_occupied_mbs(u32::from(c.rffn())));
    assert_eq!(Imxrt1062::reserved_mailbox(c), Some(c.reserved_mailbox()));
    assert_eq!(
        cs::CODE.get(model.read32(regs::mb_cs(reserved))),
        code::TX_INACTIVE,
        "MB{reserved} INACTIVE"
    );
    assert_eq!(
        model.read32(regs::IMASK1) & 1 << reserved,
        0,
        "MB{reserved} masked"
    );
    let data = usize::from(Imxrt1062::data_mailbox(c));
    assert_eq!(mcr::MAXMB.get(model.read32(regs::MCR)) as usize, data);
    assert!(reserved < data);
    reserved
}

/// ERR005829 with the RT1062 layout, over the writes since `WRITES` was cleared: each
/// write of code DATA into a transmit mailbox's C/S word (`tx`) is followed at once by
/// exactly two INACTIVE writes into the reserved mailbox's C/S word, and nothing else
/// reaches the reserved mailbox. Returns the number of activations.
fn assert_two_inactive_writes(reserved: usize, tx: core::ops::RangeInclusive<usize>) -> usize {
    let log = WRITES.with(|w| w.borrow().clone());
    let inactive = (regs::mb_cs(reserved), cs::CODE.val(code::TX_INACTIVE));
    let mut activations = 0;
    for (i, &(offset, value)) in log.iter().enumerate() {
        if matches!(mb_word(offset), Some((mb, 0)) if tx.contains(&mb))
            && cs::CODE.get(value) == code::TX_DATA
        {
            activations += 1;
            assert_eq!(
                log.get(i + 1..i + 3),
                Some(&[inactive, inactive][..]),
                "two INACTIVE writes after write {i}"
            );
            assert_ne!(log.get(i + 3).map(|w| w.0), Some(inactive.0), "exactly two");
        }
    }
    let to_reserved = log
        .iter()
        .filter(|(o, _)| mb_word(*o).map(|w| w.0) == Some(reserved))
        .inspect(|w| assert_eq!(**w, inactive, "only INACTIVE reaches MB{reserved}"))
        .count();
    assert_eq!(to_reserved, 2 * activations);
    activations
}

/// The board's one calls, their states and `rt::AcanState` are typed in the RT1062
/// layout: these bindings do not compile if any of them is back on `Kinetis`. On the
/// host the calls touch nothing.
#[test]
fn the_board_s_one_calls_are_in_the_rt1062_layout() {
    let _: &'static acan::OneCallState<FlexCanRegs, Imxrt1062> = &acan::CAN1;
    let _: &'static acan::OneCallState<FlexCanRegs, Imxrt1062> = &acan::CAN2;
    let _: &'static acan::OneCallState<FlexCanRegs, Imxrt1062> = &acan::CAN3;
    type Checked = fn(
        &BeginPlan<Imxrt1062>,
        &[Filter],
        &[Filter],
        &mut Recorder,
    ) -> Result<acan::AcanHalves<FlexCanRegs, Imxrt1062>, OneCallError>;
    let checked: [Checked; 3] = [acan::can1_checked, acan::can2_checked, acan::can3_checked];
    let state = rt::AcanState::new();
    let _: &rt::IrqState<FlexCanRegs, 32, twocan_core::FifoQueue<16>, 8, Full<Imxrt1062>> = &state;
    // The board's layout is the RT1062's: the workaround and the larger tables.
    let (e5829, max_rffn) = (BoardLayout::E5829, BoardLayout::MAX_RFFN);
    assert_eq!((e5829, max_rffn), (true, 0xF));
    // A configuration only the RT1062 layout takes: the plan the `*_checked` calls
    // take is made, and on the host the call returns before touching anything.
    let mut large = loop_back();
    large.configuration = Configuration::Filters32_96;
    for (call, instance) in
        checked
            .into_iter()
            .zip([Instance::Can1, Instance::Can2, Instance::Can3])
    {
        let target = Target::new(Board::DEFAULT, instance);
        let plan = BeginPlan::<Imxrt1062>::new_with_layout(target, &large, large.configuration)
            .unwrap_or_else(|e| panic!("{e:?}"));
        assert_eq!(
            call(&plan, &[], &[], &mut Recorder::default()).map(|_| ()),
            Err(OneCallError::NotOnTarget)
        );
    }
}

#[test]
fn the_one_call_starts_runs_ends_and_starts_again() {
    let model = FlexCanModel::new(TARGET.model_chip());
    // Garbage in the message-buffer RAM: what reads INACTIVE below, `begin` wrote.
    model.scramble_ram(0x000E_5829);
    MODEL.with(|m| *m.borrow_mut() = Some(model.clone()));
    let mut bus = Bus::new(500_000).unwrap();
    bus.attach("can1", model.clone());
    let spare: Spare<HostCan1> = Spare::new();
    let state: &'static State = Box::leak(Box::new(State::new()));
    let mut nvic = Recorder::default();

    // The board's defaults: the RT1062's 24 MHz clock root, ACAN's priority 64.
    let defaults = acan::default_settings(500_000);
    assert_eq!(defaults.can_clock.hz(), 24_000_000);
    assert_eq!(defaults.actual_bit_rate(), 500_000);
    assert_eq!(defaults.message_irq_priority, 64);

    // Start: CAN1's one line (36) at the settings' priority, after the handlers.
    let (mut tx, mut rx) = start(
        &spare,
        state,
        &loop_back(),
        &[Filter::pass_all()],
        &[],
        &mut nvic,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(nvic.0, [Call::Priority(36, 64), Call::Unmask(36)]);
    assert!(rt::is_wired(Instance::Can1));
    assert_eq!(state.installed(), [true, true]);
    assert!(!spare.holds());

    // The RT1062 layout's ERR005829 reservation (RFFN 2 of the default settings:
    // MB12 reserved, MB13–MB15 for remote frames, data MB16).
    let c = loop_back().configuration;
    let reserved = assert_reserved_mailbox(&model, &loop_back());
    assert_eq!((reserved, Imxrt1062::data_mailbox(c)), (12, 16));
    let tx_mailboxes =
        usize::from(Imxrt1062::first_remote_mailbox(c))..=usize::from(Imxrt1062::data_mailbox(c));

    // Frames go round through the model and come back, in order, with their
    // completions in order.
    WRITES.with(|w| w.borrow_mut().clear());
    let frames: Vec<Frame> = (0..5u8)
        .map(|i| Frame::standard(0x100 + u16::from(i), &[i; 3]).unwrap())
        .collect();
    let tokens: Vec<_> = frames.iter().map(|f| tx.try_send(f).unwrap()).collect();
    let entered = run(&mut bus, &model, 2_000);
    assert!(entered >= 5, "{entered} entries of CAN1");
    // Each of the five frames activated a transmit mailbox once, each activation
    // followed by the workaround's two INACTIVE writes.
    assert_eq!(
        assert_two_inactive_writes(reserved, tx_mailboxes.clone()),
        5
    );
    assert_eq!(
        cs::CODE.get(model.read32(regs::mb_cs(reserved))),
        code::TX_INACTIVE
    );
    let got: Vec<Frame> = std::iter::from_fn(|| rx.receive().ok())
        .map(|r| r.frame)
        .collect();
    assert_eq!(got, frames);
    let done: Vec<_> = std::iter::from_fn(|| tx.take_completion()).collect();
    assert_eq!(
        done.iter().map(|c| c.token).collect::<Vec<_>>(),
        tokens,
        "completions in request order"
    );
    assert!(done.iter().all(|c| c.outcome == TxOutcome::Sent));

    // While it runs, its token is nowhere: a second one call is `Taken`.
    assert_eq!(
        start(&spare, state, &loop_back(), &[], &[], &mut nvic).map(|_| ()),
        Err(OneCallError::Taken)
    );

    // The way back: the line masked, the module disabled, the token spare.
    nvic.0.clear();
    let left = acan::end(&spare, state, (tx, rx), &mut nvic)
        .map_err(|(e, _)| e)
        .unwrap();
    assert_eq!((left.queued, left.received, left.completions), (0, 0, 0));
    assert_eq!(nvic.0, [Call::Mask(36)]);
    assert!(disabled(&model));
    assert!(spare.holds());
    assert_eq!(state.installed(), [false, false]);

    // Again, on the same state (its entry point stays wired to it).
    nvic.0.clear();
    let (mut tx, mut rx) = start(
        &spare,
        state,
        &loop_back(),
        &[Filter::pass_all()],
        &[],
        &mut nvic,
    )
    .unwrap();
    assert_eq!(nvic.0, [Call::Priority(36, 64), Call::Unmask(36)]);
    assert!(!disabled(&model));
    // Begun again: the reservation again, the two writes again.
    assert_eq!(assert_reserved_mailbox(&model, &loop_back()), reserved);
    WRITES.with(|w| w.borrow_mut().clear());
    tx.try_send(&frames[0]).unwrap();
    run(&mut bus, &model, 500);
    assert_eq!(rx.receive().unwrap().frame, frames[0]);
    assert_eq!(assert_two_inactive_writes(reserved, tx_mailboxes), 1);
    acan::end(&spare, state, (tx, rx), &mut nvic)
        .map_err(|(e, _)| e)
        .unwrap();

    // A refused `begin` (a Kinetis clock on the RT1062) keeps the token.
    let kinetis = Settings::new(500_000);
    match start(&spare, state, &kinetis, &[], &[], &mut nvic) {
        Err(OneCallError::Begin(BeginError::Config(c))) => {
            assert!(c.contains(ConfigErrors::CLOCK_NOT_ON_CHIP), "{c:?}")
        }
        other => panic!("{:?}", other.map(|_| ())),
    }
    assert!(spare.holds());

    // A refused start (CAN1's entry point runs another state) ends the module again and
    // keeps the token.
    let other: &'static State = Box::leak(Box::new(State::new()));
    nvic.0.clear();
    assert_eq!(
        start(&spare, other, &loop_back(), &[], &[], &mut nvic).map(|_| ()),
        Err(OneCallError::Start(StartError::AlreadyWired))
    );
    assert!(nvic.0.is_empty(), "nothing unmasked: {:?}", nvic.0);
    assert!(disabled(&model));
    assert!(spare.holds());

    // And the first state starts once more from the spare token.
    let halves = start(&spare, state, &loop_back(), &[], &[], &mut nvic).unwrap();
    assert!(!spare.holds());
    acan::end(&spare, state, halves, &mut nvic)
        .map_err(|(e, _)| e)
        .unwrap();
}
