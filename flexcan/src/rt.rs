//! Interrupts wired by the library, as ACAN's `begin` does (feature `rt`): the FlexCAN
//! interrupt entry points of each instance, the place their handlers live, and
//! [`IrqState::start`], which installs the split driver's interrupt handlers and then
//! unmasks the lines in the NVIC at `mMessageIRQPriority` (ACAN §16.7.4).
//!
//! # Entry points and the vector table
//!
//! This module exports one `extern "C"` function per interrupt line, under the vector
//! names of the Kinetis reference manuals' "Interrupt channel assignments" (as the
//! vendor SVD files spell them, upper case): `CAN0_ORED_MESSAGE_BUFFER`, `CAN0_BUS_OFF`,
//! `CAN0_ERROR`, `CAN0_TX_WARNING`, `CAN0_RX_WARNING`, and with `teensy36` the same for
//! `CAN1_`. It does not build a vector table and needs no runtime crate: the
//! application's table (with `cortex-m-rt`'s `device` feature, its `__INTERRUPTS`)
//! names these symbols, and the linker takes them from this crate. The wake-up vectors
//! are not among them (`start` never enables wake-up).
//!
//! Which handler each line runs (Kinetis RM, FlexCAN "Interrupts"): the ORed
//! message-buffer line the transmit handler then the Rx FIFO handler
//! ([`twocan_core::split::TxIrq`], [`twocan_core::split::Rx0Irq`]); the bus-off, error
//! and warning lines the status handler ([`twocan_core::split::StatusIrq`]).
//!
//! # Order
//!
//! [`IrqState::start`] splits the controller, puts the handlers where the entry points
//! find them, and only then sets the priorities and unmasks the lines: an interrupt
//! that fires at once (a frame already in the FIFO) finds its handler, whereas a line
//! unmasked first would run an empty entry point and, its cause never cleared, stay
//! asserted for ever (the firmware-in-the-loop harness's negative test shows that
//! failure). The NVIC is reached through the [`Nvic`] trait, implemented for
//! `cortex_m::peripheral::NVIC`, so host tests check the order with a recording one.
//!
//! # The way back
//!
//! [`IrqState::stop`] masks the lines, takes the handlers back out of their cells (the
//! entry points do nothing from then on) and gives them with the halves to
//! [`twocan_core::split::State::unsplit`]: the controller comes back, to
//! [`FlexCanHw::into_controller`] and `Can0::end` (which gives the token back), and
//! the same state starts again over a controller begun anew. The entry points of an
//! instance stay wired to the first state started on it.
//!
//! # Priority
//!
//! Every line of the instance gets `Settings::message_irq_priority` (ACAN's
//! `mMessageIRQPriority`, default 64; 0 is the highest). The Kinetis NVIC implements the
//! upper 4 bits of each priority byte (ARMv7-M "NVIC_IPRn"; K20/K66 RM "Nested Vectored
//! Interrupt Controller": 16 levels), so 64 is level 4. One priority for all lines
//! means no FlexCAN handler preempts another of the same instance.
//!
//! ```ignore
//! use twocan_flexcan::rt::AcanState;
//! use twocan_flexcan::{Can0, Settings};
//! static CAN0: AcanState = AcanState::new();
//! let can = Can0::take().unwrap().begin(&Settings::new(500_000), &[], &[]).map_err(|(_, e)| e)?;
//! let (tx, rx) = CAN0.start(can.into_split(), &mut core.NVIC).map_err(|(e, _)| e)?;
//! // ... traffic; then the way back:
//! let (hw, _leftovers) = CAN0.stop(tx, rx, &mut core.NVIC).map_err(|(e, _)| e)?;
//! let token = Can0::end(hw.into_controller()).map_err(|(_, e)| e)?;
//! ```

use core::cell::UnsafeCell;
use core::fmt;
use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicU8, Ordering};

use twocan_core::irq_cell::IrqCell;
use twocan_core::split::{Rx, Rx0Irq, Rx1Irq, State, StatusIrq, Tx, TxIrq};
use twocan_core::txqueue::TxQueue;
use twocan_core::{Error, Features, FifoQueue, Leftovers, Parts, Registers, UnsplitError};

use crate::instance::{Instance, Irqs, Target};
use crate::options::{Full, Options};
use crate::regs::FlexCanRegs;
use crate::settings::{RECEIVE_BUFFER_SIZE, TRANSMIT_BUFFER_SIZE};
use crate::split::FlexCanHw;

/// A FlexCAN device interrupt number. Only [`IrqState::start`] makes them, from
/// [`Instance::irqs`] of the controller's chip (the reference manuals' "Interrupt
/// channel assignments"), so an [`Nvic`] is never handed a line that does not exist.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct IrqNumber(u16);

impl IrqNumber {
    /// The NVIC interrupt number (vector number − 16).
    pub const fn number(self) -> u16 {
        self.0
    }
}

/// The NVIC operations `start` needs (a seam for host tests).
pub trait Nvic {
    /// Sets the priority byte of device interrupt `irq` (0 highest).
    fn set_priority(&mut self, irq: IrqNumber, priority: u8);
    /// Unmasks (enables) device interrupt `irq`.
    fn unmask(&mut self, irq: IrqNumber);
    /// Masks (disables) device interrupt `irq`: its vector is not entered from now on
    /// ([`IrqState::stop`]).
    fn mask(&mut self, irq: IrqNumber);
}

// SAFETY: an `IrqNumber` is made only from `Instance::irqs` (see its documentation):
// an existing device interrupt of the chip.
unsafe impl cortex_m::interrupt::InterruptNumber for IrqNumber {
    fn number(self) -> u16 {
        self.0
    }
}

/// Firmware's NVIC. `start` is meant for applications whose critical sections mask all
/// interrupts (`cortex-m`'s `critical-section-single-core`, PRIMASK); a framework that
/// builds critical sections from NVIC masks or priorities (RTIC) owns the NVIC and runs
/// the handlers of [`twocan_core::split::State::split`] itself, without `rt`.
impl Nvic for cortex_m::peripheral::NVIC {
    fn set_priority(&mut self, irq: IrqNumber, priority: u8) {
        // SAFETY: changing a priority can only break priority-based critical sections,
        // which the applications this is for do not use (see the impl's documentation);
        // `start` sets the priority while the line is still masked.
        unsafe { cortex_m::peripheral::NVIC::set_priority(self, irq, priority) };
    }

    fn unmask(&mut self, irq: IrqNumber) {
        // SAFETY: unmasking can only break mask-based critical sections, which the
        // applications this is for do not use; `start` calls it after the handler the
        // entry point runs is in place.
        unsafe { cortex_m::peripheral::NVIC::unmask(irq) };
    }

    fn mask(&mut self, irq: IrqNumber) {
        cortex_m::peripheral::NVIC::mask(irq);
    }
}

/// The interrupt lines of one instance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Line {
    /// ORed message buffer (transmit mailboxes, Rx FIFO).
    Message,
    /// Bus off, error, Tx warning, Rx warning.
    Status,
}

/// What an instance's entry points run (implemented by [`IrqState`]).
pub trait Handlers: Sync {
    /// The message-buffer line's work; `false` when no handler is in place.
    fn on_message(&self) -> bool;
    /// The status lines' work; `false` when no handler is in place.
    fn on_status(&self) -> bool;
}

const EMPTY: u8 = 0;
const CLAIMED: u8 = 1;
const READY: u8 = 2;

/// Where an instance's entry points find its handlers: set once, read from then on.
struct Slot {
    state: AtomicU8,
    handlers: UnsafeCell<MaybeUninit<&'static dyn Handlers>>,
}

// SAFETY: `handlers` is written only by the one context that moved `state` from
// CLAIMED (its `claim` succeeded) and read only after `state` is READY (release/
// acquire); a `&'static dyn Handlers` is `Send + Sync` (`Handlers: Sync`).
unsafe impl Sync for Slot {}

impl Slot {
    const fn new() -> Self {
        Slot {
            state: AtomicU8::new(EMPTY),
            handlers: UnsafeCell::new(MaybeUninit::uninit()),
        }
    }

    fn claim(&self) -> bool {
        self.state
            .compare_exchange(EMPTY, CLAIMED, Ordering::Acquire, Ordering::Relaxed)
            .is_ok()
    }

    /// Whether the slot is wired to `handlers` already (a state started again after
    /// [`IrqState::stop`]: the wiring stays).
    fn wired_to(&self, handlers: &'static dyn Handlers) -> bool {
        self.get()
            .is_some_and(|h| core::ptr::addr_eq(h as *const dyn Handlers, handlers))
    }

    fn unclaim(&self) {
        self.state.store(EMPTY, Ordering::Release);
    }

    /// After a successful `claim`.
    fn publish(&self, handlers: &'static dyn Handlers) {
        // SAFETY: CLAIMED by this caller: no other writer, and no reader before READY.
        unsafe { (*self.handlers.get()).write(handlers) };
        self.state.store(READY, Ordering::Release);
    }

    fn get(&self) -> Option<&'static dyn Handlers> {
        if self.state.load(Ordering::Acquire) == READY {
            // SAFETY: READY is stored after the write and never left.
            Some(unsafe { (*self.handlers.get()).assume_init() })
        } else {
            None
        }
    }
}

static SLOTS: [Slot; 4] = [Slot::new(), Slot::new(), Slot::new(), Slot::new()];

const fn slot(instance: Instance) -> &'static Slot {
    match instance {
        Instance::Can0 => &SLOTS[0],
        Instance::Can1 => &SLOTS[1],
        Instance::Can2 => &SLOTS[2],
        Instance::Can3 => &SLOTS[3],
    }
}

/// Runs `line` of `instance`: what the exported entry points do. `false` when no
/// handler was installed for it (the line should not be unmasked then).
#[inline]
pub fn dispatch(instance: Instance, line: Line) -> bool {
    match slot(instance).get() {
        Some(h) => match line {
            Line::Message => h.on_message(),
            Line::Status => h.on_status(),
        },
        None => false,
    }
}

/// Whether [`IrqState::start`] wired `instance`.
pub fn is_wired(instance: Instance) -> bool {
    slot(instance).get().is_some()
}

/// The message line's handlers, and the second receive queue's (none on FlexCAN: kept
/// only to give every handle back to `State::unsplit`).
type Message<R, const RX: usize, Q, const DONE: usize, O, Fe> = (
    TxIrq<'static, FlexCanHw<R, O>, RX, Q, 0, DONE, Fe>,
    Rx0Irq<'static, FlexCanHw<R, O>, RX, Q, 0, DONE, Fe>,
    Rx1Irq<'static, FlexCanHw<R, O>, RX, Q, 0, DONE, Fe>,
);
type Status<R, const RX: usize, Q, const DONE: usize, O, Fe> =
    StatusIrq<'static, FlexCanHw<R, O>, RX, Q, 0, DONE, Fe>;

/// The split driver's state of one FlexCAN instance together with its interrupt
/// handlers, for a `static`. `RX`: receive ring (frames); `Q`: transmit queue
/// ([`FifoQueue`] keeps ACAN's send order); `DONE`: completion ring (0: fire and
/// forget); `O`: the controller's compile-time choices ([`crate::options`]: the
/// owned table of [`crate::FlexCan::into_split`] by default, the `static` table of
/// [`crate::FlexCan::begin_in`] with [`crate::options::FullInSlot`], the plan of
/// [`crate::FlexCan::begin_planned`] with [`crate::options::Lean`]); `Fe`: the portable
/// state's ([`twocan_core::Full`] or [`twocan_core::Lean`]: statistics, time stamps).
///
/// `start` takes the controller by value: with `FullInSlot` or `Lean` it holds a
/// reference to its table, not the table, so no table-sized value moves through the
/// configuration (issue 21).
pub struct IrqState<
    R: Registers + 'static,
    const RX: usize,
    Q: TxQueue + 'static,
    const DONE: usize,
    O: Options = Full,
    Fe: Features = twocan_core::Full,
> {
    state: State<FlexCanHw<R, O>, RX, Q, 0, DONE, Fe>,
    message: IrqCell<Message<R, RX, Q, DONE, O, Fe>>,
    status: IrqCell<Status<R, RX, Q, DONE, O, Fe>>,
}

/// ACAN's buffer sizes (receive 32, transmit 16, table 7) on the target registers, with
/// 8 completions, for the controller of the board's token (`begin(...).into_split()`):
/// its layout is the board's ([`crate::layout::BoardLayout`]: the RT1062 layout, with
/// the ERR005829 workaround, on a Teensy 4; ACAN's MB0–MB15 on a Teensy 3.x).
pub type AcanState = IrqState<
    FlexCanRegs,
    RECEIVE_BUFFER_SIZE,
    FifoQueue<TRANSMIT_BUFFER_SIZE>,
    8,
    Full<crate::layout::BoardLayout>,
>;

/// Why [`IrqState::start`] did not start; the controller comes back with it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StartError {
    /// The controller's board has no interrupt numbers for its instance.
    NoInterrupts,
    /// The instance's entry points already run another state's handlers.
    AlreadyWired,
    /// This state was split before (it holds a controller already).
    AlreadySplit,
    /// The controller's transmit order is not the queue's (`twocan_core` split:
    /// [`Error::InvalidArgument`]).
    Split(Error),
}

impl fmt::Display for StartError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StartError::NoInterrupts => f.write_str("the instance has no interrupt numbers"),
            StartError::AlreadyWired => {
                f.write_str("the instance's interrupt entry points are wired already")
            }
            StartError::AlreadySplit => f.write_str("the state holds a controller already"),
            StartError::Split(e) => write!(f, "split refused the controller: {e}"),
        }
    }
}

impl core::error::Error for StartError {}

impl<
        R: Registers + 'static,
        const RX: usize,
        Q: TxQueue + 'static,
        const DONE: usize,
        O: Options,
        Fe: Features,
    > Default for IrqState<R, RX, Q, DONE, O, Fe>
{
    fn default() -> Self {
        Self::new()
    }
}

impl<
        R: Registers + 'static,
        const RX: usize,
        Q: TxQueue + 'static,
        const DONE: usize,
        O: Options,
        Fe: Features,
    > IrqState<R, RX, Q, DONE, O, Fe>
{
    /// Empty (all zeros: `.bss`).
    pub const fn new() -> Self {
        IrqState {
            state: State::new(),
            message: IrqCell::new(),
            status: IrqCell::new(),
        }
    }

    /// The split driver's shared state (statistics, error state).
    pub fn state(&self) -> &State<FlexCanHw<R, O>, RX, Q, 0, DONE, Fe> {
        &self.state
    }

    /// Whether the message line's and the status lines' handlers are in place.
    pub fn installed(&self) -> [bool; 2] {
        [self.message.is_ready(), self.status.is_ready()]
    }
}

impl<R, const RX: usize, Q, const DONE: usize, O, Fe> Handlers for IrqState<R, RX, Q, DONE, O, Fe>
where
    R: Registers + 'static,
    Q: TxQueue + 'static,
    O: Options,
    Fe: Features,
    Self: Sync,
{
    #[inline]
    fn on_message(&self) -> bool {
        self.message.run(|(tx, rx, _)| {
            tx.on_interrupt();
            rx.on_interrupt();
        })
    }

    #[inline]
    fn on_status(&self) -> bool {
        self.status.run(|s| s.on_interrupt())
    }
}

/// The transmit and receive halves [`IrqState::start`] gives the thread side.
pub type Halves<R, const RX: usize, Q, const DONE: usize, O = Full, Fe = twocan_core::Full> = (
    Tx<'static, FlexCanHw<R, O>, RX, Q, 0, DONE, Fe>,
    Rx<'static, FlexCanHw<R, O>, RX, Q, 0, DONE, Fe>,
);

impl<R, const RX: usize, Q, const DONE: usize, O, Fe> IrqState<R, RX, Q, DONE, O, Fe>
where
    R: Registers + 'static,
    Q: TxQueue + 'static,
    O: Options,
    Fe: Features,
    Self: Sync,
{
    /// ACAN's `begin` interrupt set-up, after [`crate::FlexCan::begin`]: splits `hw`
    /// into this state, installs the interrupt handlers for the instance's entry
    /// points, **then** gives the message, bus-off, error and warning lines the
    /// settings' `message_irq_priority` and unmasks them (module docs, "Order").
    /// Returns the thread-side halves. On error nothing was unmasked and the controller
    /// comes back.
    // The controller comes back by value on error (no allocator to box it in).
    #[allow(clippy::type_complexity, clippy::result_large_err)]
    pub fn start(
        &'static self,
        hw: FlexCanHw<R, O>,
        nvic: &mut impl Nvic,
    ) -> Result<Halves<R, RX, Q, DONE, O, Fe>, (StartError, FlexCanHw<R, O>)> {
        let target = hw.target();
        let Some(irqs) = target.irqs() else {
            return Err((StartError::NoInterrupts, hw));
        };
        let priority = hw.message_irq_priority();
        let slot = slot(target.instance);
        // Wired to this state already (started again after `stop`), or claimed now and
        // published once the handlers are in place.
        let again = slot.wired_to(self);
        if !again && !slot.claim() {
            return Err((StartError::AlreadyWired, hw));
        }
        let parts = match self.state.split(hw) {
            Ok(parts) => parts,
            Err((e, hw)) => {
                if !again {
                    slot.unclaim();
                }
                let e = match e {
                    Error::WrongMode => StartError::AlreadySplit,
                    e => StartError::Split(e),
                };
                return Err((e, hw));
            }
        };
        Ok(self.install(parts, again, slot, irqs, priority, nvic))
    }

    /// [`IrqState::start`] with the controller **configured in place** in this state
    /// (issue 21): `init` gets the state's empty controller storage and writes the
    /// controller there (a token's `begin_in_place` or `begin_planned_in_place`, or
    /// [`crate::FlexCan::begin_in_place`]), so that no controller moves through the
    /// configuration. `target` is the module `init` configures: its entry points are
    /// claimed before `init` runs, and a controller of another module is refused
    /// ([`StartError::Split`] with [`Error::InvalidArgument`]; it stays configured,
    /// unwired). The handlers are installed, then the lines unmasked at the
    /// controller's `message_irq_priority`.
    ///
    /// Errors: [`InPlaceError::Init`] with `init`'s own error (the state stays unsplit,
    /// the entry points unclaimed); [`InPlaceError::Start`] otherwise (`init` not
    /// called, except for a controller of another module).
    #[allow(clippy::type_complexity)]
    pub fn start_in_place<E>(
        &'static self,
        target: Target,
        init: impl FnOnce(&mut MaybeUninit<FlexCanHw<R, O>>) -> Result<&mut FlexCanHw<R, O>, E>,
        nvic: &mut impl Nvic,
    ) -> Result<Halves<R, RX, Q, DONE, O, Fe>, InPlaceError<E>> {
        let Some(irqs) = target.irqs() else {
            return Err(InPlaceError::Start(StartError::NoInterrupts));
        };
        if self.state.hardware().is_some() {
            return Err(InPlaceError::Start(StartError::AlreadySplit));
        }
        let slot = slot(target.instance);
        let again = slot.wired_to(self);
        if !again && !slot.claim() {
            return Err(InPlaceError::Start(StartError::AlreadyWired));
        }
        let mut failed = None;
        let mut priority = 0;
        let split = self.state.split_with(|storage| match init(storage) {
            Ok(hw) if hw.target() == target => {
                priority = hw.message_irq_priority();
                Ok(hw)
            }
            Ok(_) => Err(Error::InvalidArgument),
            Err(e) => {
                failed = Some(e);
                Err(Error::InvalidArgument)
            }
        });
        let parts = match split {
            Ok(parts) => parts,
            Err(e) => {
                if !again {
                    slot.unclaim();
                }
                return Err(match (failed, e) {
                    (Some(e), _) => InPlaceError::Init(e),
                    (None, Error::WrongMode) => InPlaceError::Start(StartError::AlreadySplit),
                    (None, e) => InPlaceError::Start(StartError::Split(e)),
                });
            }
        };
        Ok(self.install(parts, again, slot, irqs, priority, nvic))
    }

    /// The end of [`IrqState::start`] and [`IrqState::start_in_place`]: the split's
    /// handlers into the cells the entry points read, the instance's slot published to
    /// this state (unless it was already), **then** the lines given their priority and
    /// unmasked; the halves.
    fn install(
        &'static self,
        parts: Parts<'static, FlexCanHw<R, O>, RX, Q, 0, DONE, Fe>,
        again: bool,
        slot: &'static Slot,
        irqs: Irqs,
        priority: u8,
        nvic: &mut impl Nvic,
    ) -> Halves<R, RX, Q, DONE, O, Fe> {
        // The cells are empty: only a successful split fills them, and `stop` empties
        // them before the controller leaves the state.
        let filled = self
            .message
            .put((parts.tx_irq, parts.rx0_irq, parts.rx1_irq))
            .is_ok()
            && self.status.put(parts.status_irq).is_ok();
        debug_assert!(filled, "split succeeds once per start");
        if !again {
            slot.publish(self);
        }
        enable(nvic, irqs, priority);
        (parts.tx, parts.rx)
    }

    /// The way back (issue 22 item 11): masks the instance's message, bus-off, error
    /// and warning lines, takes the handlers back out of their cells (no entry point
    /// runs them from now on), and gives them with the halves to
    /// [`State::unsplit`]. Returns the controller, still running (end it with
    /// [`FlexCanHw::into_controller`] then `Can0::end` / `Can1::end`, or
    /// [`crate::FlexCan::end`]), and what the rings and the queue still held
    /// (discarded). The state may be started again with a controller begun anew; the
    /// entry points stay wired to it.
    ///
    /// On error the halves come back; with [`StopError::Leased`] the handlers are put
    /// back and the lines unmasked again, with [`StopError::Running`] the lines stay
    /// masked.
    #[allow(clippy::type_complexity, clippy::result_large_err)]
    pub fn stop(
        &'static self,
        tx: Tx<'static, FlexCanHw<R, O>, RX, Q, 0, DONE, Fe>,
        rx: Rx<'static, FlexCanHw<R, O>, RX, Q, 0, DONE, Fe>,
        nvic: &mut impl Nvic,
    ) -> Result<(FlexCanHw<R, O>, Leftovers), (StopError, Halves<R, RX, Q, DONE, O, Fe>)> {
        if !core::ptr::eq(tx.state(), &self.state) || !core::ptr::eq(rx.state(), &self.state) {
            return Err((StopError::Foreign, (tx, rx)));
        }
        let Some(irqs) = tx.hardware().target().irqs() else {
            return Err((StopError::Foreign, (tx, rx)));
        };
        for irq in distinct_lines(irqs) {
            nvic.mask(IrqNumber(irq));
        }
        let ((tx_irq, rx0_irq, rx1_irq), status_irq) =
            match (self.message.take(), self.status.take()) {
                (Some(m), Some(s)) => (m, s),
                (m, s) => {
                    // A cell being run by a context the caller preempted: put back what was
                    // taken, lines left masked.
                    let _ = m.map(|h| self.message.put(h).is_ok());
                    let _ = s.map(|h| self.status.put(h).is_ok());
                    return Err((StopError::Running, (tx, rx)));
                }
            };
        let parts = Parts {
            tx,
            rx,
            tx_irq,
            rx0_irq,
            rx1_irq,
            status_irq,
        };
        match self.state.unsplit(parts) {
            Ok(done) => Ok(done),
            Err((e, p)) => {
                let filled = self.message.put((p.tx_irq, p.rx0_irq, p.rx1_irq)).is_ok()
                    && self.status.put(p.status_irq).is_ok();
                debug_assert!(filled, "emptied above");
                let priority = p.tx.hardware().message_irq_priority();
                enable(nvic, irqs, priority);
                let e = match e {
                    UnsplitError::Foreign => StopError::Foreign,
                    UnsplitError::Leased => StopError::Leased,
                };
                Err((e, (p.tx, p.rx)))
            }
        }
    }
}

/// Why [`IrqState::start_in_place`] did not start.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum InPlaceError<E> {
    /// The configuration `init` refused (its own error; nothing was wired).
    Init(E),
    /// As [`IrqState::start`].
    Start(StartError),
}

impl<E: fmt::Display> fmt::Display for InPlaceError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            InPlaceError::Init(e) => write!(f, "configuration: {e}"),
            InPlaceError::Start(e) => e.fmt(f),
        }
    }
}

impl<E: fmt::Debug + fmt::Display> core::error::Error for InPlaceError<E> {}

/// Why [`IrqState::stop`] did not stop; the halves come back with it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StopError {
    /// The halves are not this state's.
    Foreign,
    /// A handler was running in a context the caller preempted (`stop` called from an
    /// interrupt of lower priority): the lines stay masked; call again from thread
    /// mode.
    Running,
    /// A reference from `State::hardware` is alive: drop it and call again.
    Leased,
}

impl fmt::Display for StopError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            StopError::Foreign => "the halves belong to another state",
            StopError::Running => "a handler is running in a preempted context",
            StopError::Leased => "a reference to the controller is alive",
        })
    }
}

impl core::error::Error for StopError {}

/// The lines `start` unmasks and `stop` masks (not the wake-up line: `start` never
/// enables wake-up).
fn lines(irqs: Irqs) -> [u16; 5] {
    [
        irqs.message,
        irqs.bus_off,
        irqs.error,
        irqs.tx_warning,
        irqs.rx_warning,
    ]
}

/// [`lines`] with each line once (the i.MX RT1062 has one per module:
/// [`Irqs::is_single_line`]).
fn distinct_lines(irqs: Irqs) -> impl Iterator<Item = u16> + Clone {
    let lines = lines(irqs);
    (0..lines.len())
        .filter(move |&i| !lines[..i].contains(&lines[i]))
        .map(move |i| lines[i])
}

/// The one priority on every line (they run two cells; the four status lines one),
/// then each line unmasked: after the handlers are in place. A line shared by several
/// sources (the i.MX RT1062 has one per module: [`Irqs::is_single_line`]) is set once.
fn enable(nvic: &mut impl Nvic, irqs: Irqs, priority: u8) {
    for irq in distinct_lines(irqs) {
        nvic.set_priority(IrqNumber(irq), priority);
    }
    for irq in distinct_lines(irqs) {
        nvic.unmask(IrqNumber(irq));
    }
}

macro_rules! entry {
    ($(#[$m:meta])* $name:ident = $symbol:literal, $instance:ident, $line:ident) => {
        $(#[$m])*
        #[export_name = $symbol]
        pub extern "C" fn $name() {
            dispatch(Instance::$instance, Line::$line);
        }
    };
}

entry!(
    /// Entry point `CAN0_ORED_MESSAGE_BUFFER` (FlexCAN0 message buffers, Rx FIFO).
    can0_ored_message_buffer = "CAN0_ORED_MESSAGE_BUFFER", Can0, Message
);
entry!(
    /// Entry point `CAN0_BUS_OFF`.
    can0_bus_off = "CAN0_BUS_OFF", Can0, Status
);
entry!(
    /// Entry point `CAN0_ERROR`.
    can0_error = "CAN0_ERROR", Can0, Status
);
entry!(
    /// Entry point `CAN0_TX_WARNING`.
    can0_tx_warning = "CAN0_TX_WARNING", Can0, Status
);
entry!(
    /// Entry point `CAN0_RX_WARNING`.
    can0_rx_warning = "CAN0_RX_WARNING", Can0, Status
);
entry!(
    /// Entry point `CAN1_ORED_MESSAGE_BUFFER` (Teensy 3.6).
    #[cfg(feature = "teensy36")]
    can1_ored_message_buffer = "CAN1_ORED_MESSAGE_BUFFER", Can1, Message
);
entry!(
    /// Entry point `CAN1_BUS_OFF` (Teensy 3.6).
    #[cfg(feature = "teensy36")]
    can1_bus_off = "CAN1_BUS_OFF", Can1, Status
);
entry!(
    /// Entry point `CAN1_ERROR` (Teensy 3.6).
    #[cfg(feature = "teensy36")]
    can1_error = "CAN1_ERROR", Can1, Status
);
entry!(
    /// Entry point `CAN1_TX_WARNING` (Teensy 3.6).
    #[cfg(feature = "teensy36")]
    can1_tx_warning = "CAN1_TX_WARNING", Can1, Status
);
entry!(
    /// Entry point `CAN1_RX_WARNING` (Teensy 3.6).
    #[cfg(feature = "teensy36")]
    can1_rx_warning = "CAN1_RX_WARNING", Can1, Status
);
