//! Interrupts preempting the thread at every register access, on both controllers.
//!
//! [`Preempted`] wraps a peripheral model's registers (the `Registers` seam). While a
//! scenario runs, it counts the accesses made from the thread side and, at the chosen
//! one, lets the hardware move on and runs the interrupt handlers **before** the access
//! is performed — as an interrupt taken between two instructions of `try_send` or
//! `abort` would. Looping the chosen access over every access of a scenario tries every
//! preemption point in turn ([`sweep`]).
//!
//! What may happen at a preemption point follows what the chip allows:
//!
//! - [`Progress::Handlers`]: the handlers of the lines the model raises run (nothing new
//!   happens on the bus); a line raised by an earlier bus event and not yet serviced is
//!   taken here.
//! - [`Progress::FrameEnds`]: the frame on the wire ends first (its outcome reaches the
//!   controllers), then the handlers run. Outside a critical section, with the bus idle,
//!   the next frame (if a node offers one) is sent whole: the thread may be held up for
//!   a frame time. Inside one, only a frame already on the wire may end: a critical
//!   section lasts a few instructions, never a frame.
//! - Inside a critical section no handler runs: the handlers run at the thread's first
//!   access outside it, or when the scenario ends (the interrupt taken when the section
//!   is left; memory-only steps between the end of the section and the next access are
//!   not separated).
//!
//! Accesses made by the handlers themselves are not counted and never preempted.
//!
//! [`Rig`] is one controller over its model on a simulated bus with an acknowledging
//! peer, driven through the split driver (a `static`-like [`State`] leaked per rig): the
//! thread-side [`Tx`] half, and the interrupt handlers in a closure the preemption runs.
//! [`bxcan_rig`] and [`flexcan_rig`] build one; [`run_script`] plays a [`Step`] list and
//! checks the outcome ([`Outcome::check`]): every accepted frame gets exactly one
//! completion, `sent + failed + aborted == queued`, the queue count is back to 0, a frame
//! completed as sent is on the wire exactly once and an aborted one not at all, and the
//! wire order keeps the submission order (the request order: all frames; identifier
//! priority: frames of equal priority).

use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::rc::Rc;

use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::{BxCan, Can, Config as BxConfig, PlanOptions};
use twocan_core::split::{Rx, Tx};
use twocan_core::txqueue::TxQueue;
use twocan_core::{
    AbortRequest, Completion, Features, Filter, Frame, Full, Hardware, Priority, Registers, State,
    Token, TxOutcome, TxPolicy,
};
use twocan_flexcan::layout::{Imxrt1062, Kinetis, Layout};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::options::Full as FullOptions;
use twocan_flexcan::{Board, CanClock, FlexCan, FlexCanHw, HostSystem, Instance, Settings, Target};
use twocan_sim::{Bus, PollClock, SharedBus, SimNode};

/// Receive ring capacity (both queues) of the rigs.
pub const RX: usize = 16;
/// Completion ring capacity of the rigs.
pub const DONE: usize = 64;
/// Bit rate of the rigs' bus.
pub const BIT_RATE: u32 = 500_000;

/// What happens at the preemption point (see the [module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// The handlers of the raised lines run.
    Handlers,
    /// The frame on the wire ends (or, outside a critical section, the next frame is
    /// sent), then the handlers run.
    FrameEnds,
}

/// Both kinds of preemption point.
pub const PROGRESS: [Progress; 2] = [Progress::Handlers, Progress::FrameEnds];

/// The preemption control shared by a rig's register wrapper and its test.
pub struct Preemption {
    bus: SharedBus,
    counting: Cell<bool>,
    seen: Cell<usize>,
    at: Cell<Option<(usize, Progress)>>,
    fired: Cell<bool>,
    in_handler: Cell<bool>,
    deferred: Cell<bool>,
    /// Whether a handler had a raised line to service at the preemption point (or when
    /// it was deferred to).
    worked: Cell<bool>,
    handlers: RefCell<Option<Box<dyn FnMut() -> bool>>>,
}

impl Preemption {
    /// A control for models on `bus`; no handlers yet, not counting.
    pub fn new(bus: &SharedBus) -> Rc<Self> {
        Rc::new(Preemption {
            bus: bus.clone(),
            counting: Cell::new(false),
            seen: Cell::new(0),
            at: Cell::new(None),
            fired: Cell::new(false),
            in_handler: Cell::new(false),
            deferred: Cell::new(false),
            worked: Cell::new(false),
            handlers: RefCell::new(None),
        })
    }

    /// The interrupt side: runs the handlers of the lines the model raises; says
    /// whether any line was raised.
    pub fn set_handlers(&self, handlers: impl FnMut() -> bool + 'static) {
        *self.handlers.borrow_mut() = Some(Box::new(handlers));
    }

    /// Counts thread-side accesses from 0, preempting at `at` (none: count only).
    pub fn start(&self, at: Option<(usize, Progress)>) {
        self.seen.set(0);
        self.at.set(at);
        self.fired.set(false);
        self.worked.set(false);
        self.counting.set(true);
    }

    /// Stops counting (deferred handlers run now); the accesses counted.
    pub fn stop(&self) -> usize {
        self.counting.set(false);
        if self.deferred.replace(false) {
            let worked = self.run_handlers();
            self.worked.set(worked);
        }
        self.seen.get()
    }

    /// Whether the preempting handlers found a raised line to service.
    pub fn worked(&self) -> bool {
        self.worked.get()
    }

    /// Runs `f` with counting paused (hardware progress the script itself makes).
    pub fn paused<T>(&self, f: impl FnOnce() -> T) -> T {
        let was = self.counting.replace(false);
        let r = f();
        self.counting.set(was);
        r
    }

    /// Whether the preemption point was reached.
    pub fn fired(&self) -> bool {
        self.fired.get()
    }

    /// Runs the handlers (interrupt side: their accesses are not counted); whether a
    /// line was raised.
    pub fn run_handlers(&self) -> bool {
        if self.in_handler.replace(true) {
            return false;
        }
        let worked = match self.handlers.borrow_mut().as_mut() {
            Some(h) => h(),
            None => false,
        };
        self.in_handler.set(false);
        worked
    }

    fn before_access(&self) {
        if self.in_handler.get() || !self.counting.get() {
            return;
        }
        let n = self.seen.get();
        self.seen.set(n + 1);
        let in_cs = in_critical_section();
        if !in_cs && self.deferred.replace(false) {
            let worked = self.run_handlers();
            self.worked.set(worked);
        }
        let Some((k, progress)) = self.at.get() else {
            return;
        };
        if k != n {
            return;
        }
        self.fired.set(true);
        if progress == Progress::FrameEnds {
            let mut bus = self.bus.borrow_mut();
            if bus.in_frame() || !in_cs {
                bus.step();
            }
        }
        if in_cs {
            self.deferred.set(true);
        } else {
            let worked = self.run_handlers();
            self.worked.set(worked);
        }
    }
}

/// Whether this thread holds the critical section (the `critical-section` crate's `std`
/// implementation: an acquire while held reports a nested section).
pub fn in_critical_section() -> bool {
    // SAFETY: acquired and released in a pair on this thread, nothing in between.
    let state = unsafe { critical_section::acquire() };
    let text = format!("{state:?}");
    // SAFETY: the state the acquire above returned.
    unsafe { critical_section::release(state) };
    match text.as_str() {
        "RestoreState(true)" => true,
        "RestoreState(false)" => false,
        other => panic!("unexpected critical-section restore state {other}"),
    }
}

/// A model's registers with a preemption point before each access.
#[derive(Clone)]
pub struct Preempted<R> {
    inner: R,
    preemption: Rc<Preemption>,
}

impl<R> Preempted<R> {
    /// Wraps `inner`.
    pub fn new(inner: R, preemption: &Rc<Preemption>) -> Self {
        Preempted {
            inner,
            preemption: preemption.clone(),
        }
    }
}

impl<R: Registers> Registers for Preempted<R> {
    fn read32(&self, offset: usize) -> u32 {
        self.preemption.before_access();
        self.inner.read32(offset)
    }

    fn write32(&self, offset: usize, value: u32) {
        self.preemption.before_access();
        self.inner.write32(offset, value)
    }
}

/// One controller on a bus with a peer, through the split driver.
///
/// `D`: the completion ring's capacity ([`DONE`]; 0: completions off), `Fe`: the
/// driver's feature set ([`Full`]; [`twocan_core::Lean`] with `D` = 0 and a
/// request-order queue is the quiet transmit mode on bxCAN).
pub struct Rig<
    H: Hardware + 'static,
    Q: TxQueue + 'static,
    const D: usize = DONE,
    Fe: Features = Full,
> {
    /// The shared state (leaked: the handles borrow it for the rig's life).
    pub state: &'static State<H, RX, Q, RX, D, Fe>,
    /// The transmit half.
    pub tx: Tx<'static, H, RX, Q, RX, D, Fe>,
    /// The receive half.
    pub rx: Rx<'static, H, RX, Q, RX, D, Fe>,
    /// The preemption control.
    pub preemption: Rc<Preemption>,
    /// The bus.
    pub bus: SharedBus,
    /// The acknowledging peer.
    pub peer: Rc<RefCell<SimNode>>,
    /// For messages.
    pub name: &'static str,
    /// Whether the controller's transmit interrupt is enabled now (bxCAN
    /// `CAN_IER.TMEIE`; FlexCAN: the data mailbox's `IMASK1`/`IMASK2` bit, the one the
    /// quiet mode switches), read from the model without going through the preemption.
    pub tx_interrupt_on: Option<Box<dyn Fn() -> bool>>,
}

/// The bxCAN controller of a rig.
pub type BxHw = BxCan<Preempted<PollClock<BxCanModel>>>;
/// The FlexCAN controller of a rig.
pub type FlexHw = FlexCanHw<Preempted<PollClock<FlexCanModel>>>;
/// The FlexCAN controller of a rig in the layout `L`.
pub type FlexHwIn<L> = FlexCanHw<Preempted<PollClock<FlexCanModel>>, FullOptions<L>>;
/// The FlexCAN controller of a rig in the RT1062 layout (a Teensy 4.1's CAN3).
pub type FlexRtHw = FlexHwIn<Imxrt1062>;

fn bus_and_peer() -> (SharedBus, Rc<RefCell<SimNode>>) {
    let bus = Rc::new(RefCell::new(Bus::new(BIT_RATE).expect("bus")));
    let peer = SimNode::new().shared();
    (bus, peer)
}

/// bxCAN CAN1 of an STM32F767 (receive everything, every interrupt) in transmit order
/// `policy`, with queue `Q` (whose order must be `policy`).
pub fn bxcan_rig<Q: TxQueue + 'static>(policy: TxPolicy) -> Rig<BxHw, Q> {
    bxcan_rig_with(policy)
}

/// [`bxcan_rig`] with the completion ring `D` and feature set `Fe` chosen.
pub fn bxcan_rig_with<Q: TxQueue + 'static, const D: usize, Fe: Features>(
    policy: TxPolicy,
) -> Rig<BxHw, Q, D, Fe> {
    let (bus, peer) = bus_and_peer();
    let model = BxCanModel::can1();
    bus.borrow_mut().attach("can1", model.clone());
    bus.borrow_mut().attach("peer", peer.clone());
    let preemption = Preemption::new(&bus);
    let regs = Preempted::new(
        PollClock::new(model.clone(), &bus, twocan_bxcan::regs::MSR),
        &preemption,
    );
    let config = BxConfig::from_bitrate(twocan_host::STM32F767_APB1_HZ, BIT_RATE)
        .expect("timing")
        .tx_policy(policy)
        .interrupts(twocan_bxcan::config::DEFAULT_INTERRUPTS);
    let mut init = Can::can1(regs, &config).map_err(|f| f.error).expect("init");
    let plan = twocan_bxcan::plan(&[Filter::pass_all()], PlanOptions::new(14)).expect("plan");
    init.set_filters(&plan).expect("filters");
    let can = init.enable().map_err(|f| f.error).expect("enable");
    let state: &'static State<BxHw, RX, Q, RX, D, Fe> = Box::leak(Box::new(State::new()));
    let parts = state
        .split(can.into_split())
        .map_err(|(e, _)| e)
        .expect("split");
    let (mut tx_irq, mut rx0, mut rx1, mut status) =
        (parts.tx_irq, parts.rx0_irq, parts.rx1_irq, parts.status_irq);
    let ier = model.clone();
    let tx_interrupt_on = move || {
        twocan_core::Registers::read32(&ier, twocan_bxcan::regs::IER)
            & twocan_bxcan::regs::ier::TMEIE
            != 0
    };
    preemption.set_handlers(move || {
        // One handler per line, as the chip's four vectors run them.
        let l = model.irq_lines();
        if l.tx {
            tx_irq.on_interrupt();
        }
        if l.rx0 {
            rx0.on_interrupt();
        }
        if l.rx1 {
            rx1.on_interrupt();
        }
        if l.sce {
            status.on_interrupt();
        }
        l.tx || l.rx0 || l.rx1 || l.sce
    });
    Rig {
        state,
        tx: parts.tx,
        rx: parts.rx,
        preemption,
        bus,
        peer,
        tx_interrupt_on: Some(Box::new(tx_interrupt_on)),
        name: if policy == TxPolicy::Fifo {
            "bxCAN, request order"
        } else {
            "bxCAN, identifier priority"
        },
    }
}

/// FlexCAN can0 of a Teensy 3.6 (ACAN's defaults, receive everything), request order.
pub fn flexcan_rig<Q: TxQueue + 'static>() -> Rig<FlexHw, Q> {
    flexcan_rig_with(SimNode::new())
}

/// [`flexcan_rig`] with another peer (a listen-only one acknowledges nothing).
pub fn flexcan_rig_with<Q: TxQueue + 'static>(peer: SimNode) -> Rig<FlexHw, Q> {
    flexcan_rig_in::<Kinetis, Q, DONE, Full>(peer, crate::backend::teensy36_can0(), 0)
}

/// FlexCAN can0 of a Teensy 3.6 with the completion ring `D` and feature set `Fe`
/// chosen (`D` = 0 with [`twocan_core::Lean`] and a request-order queue: the quiet
/// transmit mode).
pub fn flexcan_rig_quiet<Q: TxQueue + 'static, const D: usize, Fe: Features>(
) -> Rig<FlexHw, Q, D, Fe> {
    flexcan_rig_quiet_with(SimNode::new())
}

/// [`flexcan_rig_quiet`] with another peer (a listen-only one acknowledges nothing).
pub fn flexcan_rig_quiet_with<Q: TxQueue + 'static, const D: usize, Fe: Features>(
    peer: SimNode,
) -> Rig<FlexHw, Q, D, Fe> {
    flexcan_rig_in::<Kinetis, Q, D, Fe>(peer, crate::backend::teensy36_can0(), 0)
}

/// CAN3 of a Teensy 4.1 in the RT1062 layout (the ERR005829 reserved mailbox after the
/// Rx FIFO area, the transmit mailboxes after it; `configuration` 0 is ACAN's
/// `Filters8_0`, others per [`twocan_flexcan::Configuration::EVERY`]: from RFFN 8 the
/// transmit mailboxes lie above MB31, in `IFLAG2`/`IMASK2`), with the completion ring
/// `D` and the feature set `Fe` chosen.
pub fn flexcan_rt_rig<Q: TxQueue + 'static, const D: usize, Fe: Features>(
    configuration: twocan_flexcan::Configuration,
) -> Rig<FlexRtHw, Q, D, Fe> {
    let index = twocan_flexcan::Configuration::EVERY
        .iter()
        .position(|c| *c == configuration)
        .expect("a configuration");
    flexcan_rig_in::<Imxrt1062, Q, D, Fe>(
        SimNode::new(),
        Target::new(Board::Teensy41, Instance::Can3),
        index,
    )
}

/// A FlexCAN rig of layout `L` on `target`, its settings ACAN's defaults at
/// [`BIT_RATE`] (on a Teensy 4, the 24 MHz oscillator and the configuration
/// `Configuration::EVERY[configuration]`), receiving everything.
fn flexcan_rig_in<L: Layout, Q: TxQueue + 'static, const D: usize, Fe: Features>(
    peer: SimNode,
    target: Target,
    configuration: usize,
) -> Rig<FlexHwIn<L>, Q, D, Fe>
where
    FullOptions<L>: twocan_flexcan::options::Options<Layout = L, Table = L::Table>,
{
    let bus = Rc::new(RefCell::new(Bus::new(BIT_RATE).expect("bus")));
    let peer = peer.shared();
    let model = FlexCanModel::new(target.model_chip());
    bus.borrow_mut().attach("can", model.clone());
    bus.borrow_mut().attach("peer", peer.clone());
    let preemption = Preemption::new(&bus);
    let regs = Preempted::new(
        PollClock::with_poll_registers(
            model.clone(),
            &bus,
            &[twocan_flexcan::regs::MCR, twocan_flexcan::regs::ESR1],
        ),
        &preemption,
    );
    let rt = L::IFLAG2;
    let settings = if rt {
        let mut s = Settings::with_clock(BIT_RATE, CanClock::IMXRT_24MHZ);
        s.configuration = twocan_flexcan::Configuration::EVERY[configuration];
        s
    } else {
        Settings::new(BIT_RATE)
    };
    let controller = FlexCan::<_, L>::begin_with_layout(
        regs,
        &mut HostSystem::new(),
        target,
        &settings,
        &[Filter::pass_all()],
        &[],
    )
    .expect("begin");
    let state: &'static State<FlexHwIn<L>, RX, Q, RX, D, Fe> = Box::leak(Box::new(State::new()));
    let parts = state
        .split(controller.into_split())
        .map_err(|(e, _)| e)
        .expect("split");
    let configuration = settings.configuration;
    let data = usize::from(L::data_mailbox(configuration));
    let (mask, bit) = if data < 32 {
        (twocan_flexcan::regs::IMASK1, data)
    } else {
        (twocan_flexcan::regs::IMASK2, data - 32)
    };
    let imask = model.clone();
    let tx_interrupt_on = move || twocan_core::Registers::read32(&imask, mask) & 1 << bit != 0;
    let (mut tx_irq, mut rx0, mut status) = (parts.tx_irq, parts.rx0_irq, parts.status_irq);
    preemption.set_handlers(move || {
        let l = model.irq();
        // The ORed message-buffer line runs the transmit and the receive handler.
        if l.message_buffer {
            tx_irq.on_interrupt();
            rx0.on_interrupt();
        }
        if l.error || l.bus_off || l.warning {
            status.on_interrupt();
        }
        l.any()
    });
    Rig {
        state,
        tx: parts.tx,
        rx: parts.rx,
        preemption,
        bus,
        peer,
        name: if rt {
            "FlexCAN RT1062 layout, request order"
        } else {
            "FlexCAN, request order"
        },
        tx_interrupt_on: Some(Box::new(tx_interrupt_on)),
    }
}

/// One step of a scenario, run from the thread side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Step {
    /// `try_send`, with the bus moving on one frame (handlers not run) while it says
    /// `WouldBlock`.
    Send(Frame),
    /// `abort` of the frame of the `n`-th `Send`.
    Abort(usize),
    /// `abort_all`.
    AbortAll,
    /// `try_send_now`, with the bus moving on one frame while it says `WouldBlock`.
    SendNow(Frame),
    /// `Tx::poll` (the transmit interrupt's work from the thread).
    Poll,
    /// The bus runs this many bit times (stopping inside a frame), no handler runs.
    Bus(u64),
    /// The peer queues a frame (it goes when the bus next runs).
    Peer(Frame),
}

/// What a scenario ended with.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The frames submitted, in order, with their tokens.
    pub accepted: Vec<(Token, Frame)>,
    /// The completions, in the order delivered.
    pub completions: Vec<Completion>,
    /// What the peer received, in bus order.
    pub wire: Vec<Frame>,
    /// `queued`, `sent`, `failed`, `aborted` of the traffic counters.
    pub counters: (u32, u32, u32, u32),
    /// The transmit queue's count at the end.
    pub queue_count: usize,
    /// What each `abort` returned.
    pub aborts: Vec<AbortRequest>,
    /// Thread-side register accesses the scenario made.
    pub accesses: usize,
    /// Whether the preempting handlers had a raised line to service.
    pub preempted_with_work: bool,
    /// Whether the driver reports completions (a completion ring); without, the
    /// checks are on the wire alone.
    pub completions_on: bool,
    /// Whether the scenario ran `abort_all`.
    pub aborted_all: bool,
    /// Whether the driver ran in the quiet transmit mode (`State::QUIET_TX`).
    pub quiet: bool,
    /// Indices into `accepted` of the frames sent with `try_send_now`, which may
    /// overtake frames queued before them (by design).
    pub overtaking: Vec<usize>,
    /// Whether the transmit interrupt was enabled at the end, where the rig can tell.
    pub tx_interrupt_on: Option<bool>,
}

/// Retries `send` while it says `WouldBlock`, running `wait` in between (the 100th
/// `WouldBlock` fails the test: "no `what` comes"); the token it gives.
fn until_accepted(
    name: &str,
    what: &str,
    mut send: impl FnMut() -> nb::Result<Token, twocan_core::Error>,
    mut wait: impl FnMut(),
) -> Token {
    for tries in 1.. {
        match send() {
            Ok(token) => return token,
            Err(nb::Error::WouldBlock) => {
                assert!(tries < 100, "{name}: no {what} comes");
                wait();
            }
            Err(nb::Error::Other(e)) => panic!("{name}: {e:?}"),
        }
    }
    unreachable!("the loop returns or panics")
}

/// Plays `steps` on a fresh `rig`, preempting at `at`, then runs the bus with the
/// handlers serviced until nothing is left to do.
pub fn run_script<H: Hardware + 'static, Q: TxQueue + 'static, const D: usize, Fe: Features>(
    mut rig: Rig<H, Q, D, Fe>,
    steps: &[Step],
    at: Option<(usize, Progress)>,
) -> Outcome {
    let p = rig.preemption.clone();
    let bus = rig.bus.clone();
    let mut accepted = Vec::new();
    let mut aborts = Vec::new();
    let mut aborted_all = false;
    let mut overtaking = Vec::new();
    p.start(at);
    for step in steps {
        match *step {
            Step::Send(frame) => {
                let token = until_accepted(
                    rig.name,
                    "room",
                    || rig.tx.try_send(&frame),
                    || {
                        p.paused(|| bus.borrow_mut().step());
                    },
                );
                accepted.push((token, frame));
            }
            Step::Abort(n) => aborts.push(rig.tx.abort(accepted[n].0)),
            Step::AbortAll => {
                rig.tx.abort_all();
                aborted_all = true;
            }
            Step::SendNow(frame) => {
                // No mailbox free and settled: the bus moves on and the handlers settle
                // what ended.
                let token = until_accepted(
                    rig.name,
                    "mailbox",
                    || rig.tx.try_send_now(&frame),
                    || {
                        p.paused(|| bus.borrow_mut().step());
                        p.run_handlers();
                    },
                );
                accepted.push((token, frame));
                overtaking.push(accepted.len() - 1);
            }
            Step::Poll => rig.tx.poll(),
            Step::Bus(bits) => {
                p.paused(|| bus.borrow_mut().run_bits(bits));
            }
            Step::Peer(frame) => rig.peer.borrow_mut().send(frame),
        }
    }
    let accesses = p.stop();
    let preempted_with_work = p.fired() && p.worked();
    // The bus runs on, each line serviced after each event.
    for _ in 0..10_000 {
        p.run_handlers();
        if bus.borrow_mut().step().is_none() {
            p.run_handlers();
            if bus.borrow_mut().step().is_none() {
                break;
            }
        }
    }
    let completions: Vec<Completion> = std::iter::from_fn(|| rig.tx.take_completion()).collect();
    let t = rig.state.traffic();
    Outcome {
        accepted,
        completions,
        wire: rig.peer.borrow().received_frames(),
        counters: (t.queued, t.sent, t.failed, t.aborted),
        queue_count: rig.tx.stats().count,
        aborts,
        accesses,
        preempted_with_work,
        completions_on: D != 0,
        aborted_all,
        quiet: State::<H, RX, Q, RX, D, Fe>::QUIET_TX,
        overtaking,
        tx_interrupt_on: rig.tx_interrupt_on.as_ref().map(|on| on()),
    }
}

impl Outcome {
    /// The checks every scenario must pass (see the [module docs](self)); `what` names
    /// the run in the messages. Frames must be distinct (a tag in data or DLC).
    pub fn check(&self, policy: TxPolicy, what: &str) {
        if !self.completions_on {
            return self.check_quiet(policy, what);
        }
        let (queued, sent, failed, aborted) = self.counters;
        assert_eq!(queued as usize, self.accepted.len(), "{what}: queued");
        assert_eq!(sent + failed + aborted, queued, "{what}: counters");
        assert_eq!(self.queue_count, 0, "{what}: queue count at the end");
        assert_eq!(
            self.completions.len(),
            self.accepted.len(),
            "{what}: completions {:?}",
            self.completions
        );
        let mut outcome: HashMap<Token, TxOutcome> = HashMap::new();
        for c in &self.completions {
            assert!(
                outcome.insert(c.token, c.outcome).is_none(),
                "{what}: two completions for {:?}",
                c.token
            );
        }
        // Each of our frames on the wire once if sent, never if aborted; the wire shows
        // them in an order the transmit order allows.
        let ours = self.ours_on_the_wire(what);
        for (i, (token, frame)) in self.accepted.iter().enumerate() {
            let times = ours.iter().filter(|&&k| k == i).count();
            let Some(o) = outcome.get(token) else {
                panic!("{what}: no completion for {token:?} ({frame:?})");
            };
            let want = match o {
                TxOutcome::Sent => 1,
                TxOutcome::Aborted | TxOutcome::Failed => 0,
            };
            assert_eq!(
                times, want,
                "{what}: {frame:?} completed {o:?}, on the wire {times} times; wire {:?}",
                self.wire
            );
        }
        self.check_order(&ours, policy, what);
    }

    /// The checks without completions (fire and forget): the queue count back to 0, the
    /// quiet mode's transmit interrupt off, each frame on the wire exactly once (at
    /// most once when the scenario aborts), in an order the transmit order allows.
    fn check_quiet(&self, policy: TxPolicy, what: &str) {
        assert_eq!(self.queue_count, 0, "{what}: queue count at the end");
        if self.quiet {
            // Nothing queued: the quiet mode's transmit interrupt must be off.
            assert_ne!(
                self.tx_interrupt_on,
                Some(true),
                "{what}: transmit interrupt on with an empty queue"
            );
        }
        let ours = self.ours_on_the_wire(what);
        for (i, (_, frame)) in self.accepted.iter().enumerate() {
            let times = ours.iter().filter(|&&k| k == i).count();
            if self.aborts.is_empty() && !self.aborted_all {
                assert_eq!(
                    times, 1,
                    "{what}: {frame:?} on the wire {times} times; wire {:?}",
                    self.wire
                );
            } else {
                assert!(times <= 1, "{what}: {frame:?} on the wire {times} times");
            }
        }
        self.check_order(&ours, policy, what);
    }

    /// Our frames on the wire, as indices into `accepted` in wire order (the frames
    /// must be distinct).
    fn ours_on_the_wire(&self, what: &str) -> Vec<usize> {
        let mut index = HashMap::new();
        for (i, (_, f)) in self.accepted.iter().enumerate() {
            assert!(
                index.insert(*f, i).is_none(),
                "{what}: frames must be distinct"
            );
        }
        self.wire
            .iter()
            .filter_map(|f| index.get(f).copied())
            .collect()
    }

    /// Our frames (indices into `accepted`, in wire order) left in an order `policy`
    /// allows. A frame of `try_send_now` is ordered with no other: it may leave before
    /// frames accepted earlier (FlexCAN: a remote frame's mailbox beside the loaded data
    /// mailbox, the module picking by identifier), and where the order is by priority a
    /// later frame may leave before it.
    fn check_order(&self, ours: &[usize], policy: TxPolicy, what: &str) {
        for (a, &i) in ours.iter().enumerate() {
            for &j in &ours[a + 1..] {
                let (fi, fj) = (self.accepted[i].1, self.accepted[j].1);
                let ordered = !self.overtaking.contains(&i)
                    && !self.overtaking.contains(&j)
                    && match policy {
                        TxPolicy::Fifo => true,
                        TxPolicy::Priority => Priority::of(&fi) == Priority::of(&fj),
                    };
                assert!(
                    !ordered || i < j,
                    "{what}: frame {i} ({fi:?}) left before frame {j} ({fj:?}); wire {:?}",
                    self.wire
                );
            }
        }
    }
}

/// What a [`sweep`] tried.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Swept {
    /// Thread-side register accesses of the scenario without preemption.
    pub accesses: usize,
    /// Preemption points tried (each access with each [`Progress`]; a preempted run may
    /// make a different number of accesses, the points are those of the plain run).
    pub points: usize,
    /// Points where a preempting handler had a raised line to service.
    pub with_work: usize,
    /// Frames sent and aborted in the plain run.
    pub sent_aborted: (u32, u32),
}

/// Runs `steps` once without preemption to count the thread's accesses, then once per
/// access and kind of preemption point, each on a fresh rig from `rig`, checking every
/// outcome.
pub fn sweep<H: Hardware + 'static, Q: TxQueue + 'static, const D: usize, Fe: Features>(
    rig: impl Fn() -> Rig<H, Q, D, Fe>,
    policy: TxPolicy,
    steps: &[Step],
    what: &str,
) -> Swept {
    let base = run_script(rig(), steps, None);
    base.check(policy, &format!("{what}, no preemption"));
    let n = base.accesses;
    assert!(n > 0, "{what}: the scenario touches no register");
    let mut swept = Swept {
        accesses: n,
        points: 0,
        with_work: 0,
        sent_aborted: (base.counters.1, base.counters.3),
    };
    for k in 0..n {
        for progress in PROGRESS {
            let o = run_script(rig(), steps, Some((k, progress)));
            o.check(
                policy,
                &format!("{what}, {progress:?} at access {k} of {n}"),
            );
            swept.points += 1;
            swept.with_work += o.preempted_with_work as usize;
        }
    }
    swept
}
