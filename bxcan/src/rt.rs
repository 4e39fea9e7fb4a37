//! Interrupts wired by the library (feature `rt`): the bxCAN interrupt entry points of
//! each instance, the place their handlers live ([`IrqState`]), and the way in
//! ([`IrqState::start_on`]: handlers installed, then priorities, then the lines
//! unmasked) and back ([`IrqState::stop_on`]: lines masked, handlers and halves taken
//! back, the controller returned).
//!
//! # Lines and entry points
//!
//! A bxCAN instance has four interrupt lines (RM0410 §40.8 "bxCAN interrupts", RM0090
//! §32.8, RM0008 §24.8), each with its own handler ([`Line`]): **TX** (mailbox
//! requests completed: [`twocan_core::split::TxIrq`]), **RX0** and **RX1** (FIFO 0 and
//! FIFO 1 pending, full, overrun: [`twocan_core::split::Rx0Irq`],
//! [`twocan_core::split::Rx1Irq`]) and **SCE** (status change, error, wake-up:
//! [`twocan_core::split::StatusIrq`]). Which interrupt number each line of each instance
//! has is chip data (the reference manuals' vector tables); the NVIC calls take it from
//! the chip's PAC as its `Interrupt` enum (`lines` for the STM32F7, with `hal-stm32f7`), any other line
//! type through the [`Nvic`] seam (the host tests' recorder, another PAC).
//!
//! The entry points are exported under the vector names of the chip's PAC
//! (`CAN1_TX`, `CAN1_RX0`, `CAN1_RX1`, `CAN1_SCE`, `CAN2_…`, and with
//! `hal-stm32f7-can3` `CAN3_…`), each checked against the PAC's `Interrupt` enum at
//! compile time; the PAC's vector table (its `rt` feature, as cortex-m-rt's
//! `#[interrupt]` handlers are found) takes them from this crate, so the application
//! defines none of them (the linker refuses a second definition). They are exported
//! with a chip feature (`hal-stm32f7`: module `vectors`); every
//! entry point is one call of [`dispatch`] with its instance and line, so another
//! family's table (F1's `USB_HP_CAN_TX` ... or F4's `CAN1_TX` ...) is one more list of
//! names for the same macro, not a copy of the code.
//!
//! # Order
//!
//! [`IrqState::start_on`] splits the controller, puts the four handlers where the entry
//! points find them, and only then gives each line its priority and unmasks it: an
//! interrupt that fires at once (a frame already in a FIFO) finds its handler, whereas a
//! line unmasked first would run an empty entry point and, its level-triggered cause
//! never cleared, stay asserted for ever. The NVIC is reached through [`Nvic`],
//! implemented for `cortex_m::peripheral::NVIC`, so the host tests check the order with
//! a recording one (`tests/rt_start.rs`).
//!
//! # Priorities
//!
//! Each line runs a cell of its own, so the four lines may have four priorities
//! ([`Priorities`]); the RX0 and RX1 handlers may preempt each other (each writes only
//! its own queue's counters). The STM32F1/F4/F7 NVIC implements the upper 4 bits of each
//! priority byte (PM0214/PM0253 "NVIC_IPRx": 16 levels); 0 is the highest.
//!
//! # The way back
//!
//! [`IrqState::stop_on`] masks the four lines, takes the handlers back out of their
//! cells (no entry point runs one from then on), gives them and the halves to
//! [`twocan_core::split::State::unsplit`] and returns the controller ([`BxCan`]); from
//! it, [`BxCan::into_can`] then [`crate::Can::master_reset`] (or
//! [`crate::Can::release`]) give the register handles back, which the HAL hand-over
//! exchanges for the PAC singleton (`hal::Parked::free`). The same state may be started
//! again with a controller configured anew; the entry points of an instance stay
//! wired to the first state started on it.
//!
//! ```ignore
//! use twocan_bxcan::rt::{self, IrqState, Priorities};
//! type Q = twocan_core::FifoQueue<16>;
//! static CAN1: IrqState<twocan_bxcan::regs::CanRegs, twocan_bxcan::regs::CanRegs, 32, Q, 32, 8> =
//!     IrqState::new();
//! let (mut tx, mut rx) = CAN1.start(can.into_split(), Priorities::all(0x80), &mut core.NVIC)
//!     .map_err(|(e, _)| e)?;
//! // ... traffic ...
//! let (can, _leftovers) = CAN1.stop(tx, rx, &mut core.NVIC).map_err(|(e, _)| e)?;
//! let (regs, _) = can.into_can().master_reset().map_err(|f| f.error)?;
//! ```

use core::cell::UnsafeCell;
use core::fmt;
use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicU8, Ordering};

use twocan_core::irq_cell::IrqCell;
use twocan_core::split::{Rx, Rx0Irq, Rx1Irq, State, StatusIrq, Tx, TxIrq};
use twocan_core::txqueue::TxQueue;
use twocan_core::{Error, Features, Leftovers, Parts, Registers, UnsplitError};

use crate::filters::{FmiMap, LOOKUP_KEYS, MAX_FMI};
use crate::instance::Instance;
use crate::split::BxCan;

/// The interrupt lines of one bxCAN instance (RM0410 §40.8), in the order of the
/// `[L; 4]` arrays this module takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Line {
    /// Transmit mailbox empty (`CAN_IER.TMEIE`).
    Tx,
    /// FIFO 0 message pending, full, overrun (`FMPIE0`, `FFIE0`, `FOVIE0`).
    Rx0,
    /// FIFO 1 message pending, full, overrun (`FMPIE1`, `FFIE1`, `FOVIE1`).
    Rx1,
    /// Status change, error, wake-up, sleep (`ERRIE` ..., `WKUIE`, `SLKIE`).
    Sce,
}

impl Line {
    /// The four lines, in array order.
    pub const ALL: [Line; 4] = [Line::Tx, Line::Rx0, Line::Rx1, Line::Sce];
}

/// The NVIC operations `start_on` and `stop_on` need, over the line type `L` (a PAC's
/// `Interrupt`; a recorder's numbers on the host).
pub trait Nvic<L: Copy> {
    /// Sets the priority byte of `line` (0 highest).
    fn set_priority(&mut self, line: L, priority: u8);
    /// Unmasks (enables) `line`.
    fn unmask(&mut self, line: L);
    /// Masks (disables) `line`: its vector is not entered from now on.
    fn mask(&mut self, line: L);
}

/// Firmware's NVIC, for any PAC's `Interrupt`. Meant for applications whose critical
/// sections mask all interrupts (`cortex-m`'s `critical-section-single-core`, PRIMASK);
/// a framework that builds critical sections from NVIC masks or priorities (RTIC) owns
/// the NVIC and runs the handlers of [`State::split`] from its own tasks, without `rt`.
impl<L: cortex_m::interrupt::InterruptNumber> Nvic<L> for cortex_m::peripheral::NVIC {
    fn set_priority(&mut self, line: L, priority: u8) {
        // SAFETY: changing a priority can only break priority-based critical sections,
        // which the applications this is for do not use (see the impl's documentation);
        // `start_on` sets it while the line is still masked.
        unsafe { cortex_m::peripheral::NVIC::set_priority(self, line, priority) };
    }

    fn unmask(&mut self, line: L) {
        // SAFETY: unmasking can only break mask-based critical sections, which the
        // applications this is for do not use; `start_on` calls it after the handler
        // the entry point runs is in place.
        unsafe { cortex_m::peripheral::NVIC::unmask(line) };
    }

    fn mask(&mut self, line: L) {
        cortex_m::peripheral::NVIC::mask(line);
    }
}

/// The priority of each line (0 highest; the NVIC keeps the upper 4 bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Priorities {
    /// TX line.
    pub tx: u8,
    /// RX0 line.
    pub rx0: u8,
    /// RX1 line.
    pub rx1: u8,
    /// SCE line.
    pub sce: u8,
}

impl Priorities {
    /// One priority for the four lines (no CAN handler of the instance preempts
    /// another).
    pub const fn all(priority: u8) -> Self {
        Priorities {
            tx: priority,
            rx0: priority,
            rx1: priority,
            sce: priority,
        }
    }

    /// The priority of `line`.
    pub const fn of(&self, line: Line) -> u8 {
        match line {
            Line::Tx => self.tx,
            Line::Rx0 => self.rx0,
            Line::Rx1 => self.rx1,
            Line::Sce => self.sce,
        }
    }
}

/// What an instance's entry points run (implemented by [`IrqState`]).
pub trait Handlers: Sync {
    /// Runs `line`'s handler; `false` when none is in place (or it is running in
    /// another context).
    fn run(&self, line: Line) -> bool;
}

const EMPTY: u8 = 0;
const CLAIMED: u8 = 1;
const READY: u8 = 2;

/// Where an instance's entry points find its handlers: wired once to one state, read
/// from then on (a stopped state keeps the wiring; its cells are empty).
struct Slot {
    state: AtomicU8,
    handlers: UnsafeCell<MaybeUninit<&'static dyn Handlers>>,
}

// SAFETY: `handlers` is written only by the one context that moved `state` from EMPTY
// to CLAIMED, and read only after `state` is READY (release/acquire), which it never
// leaves; a `&'static dyn Handlers` is `Send + Sync` (`Handlers: Sync`).
unsafe impl Sync for Slot {}

impl Slot {
    const fn new() -> Self {
        Slot {
            state: AtomicU8::new(EMPTY),
            handlers: UnsafeCell::new(MaybeUninit::uninit()),
        }
    }

    /// Wires the slot to `handlers`, or checks that it is wired to them already.
    fn wire(&self, handlers: &'static dyn Handlers) -> bool {
        match self
            .state
            .compare_exchange(EMPTY, CLAIMED, Ordering::Acquire, Ordering::Acquire)
        {
            Ok(_) => {
                // SAFETY: CLAIMED by this call: no other writer, and no reader before
                // READY.
                unsafe { (*self.handlers.get()).write(handlers) };
                self.state.store(READY, Ordering::Release);
                true
            }
            Err(_) => self
                .get()
                .is_some_and(|h| core::ptr::addr_eq(h as *const dyn Handlers, handlers)),
        }
    }

    #[inline]
    fn get(&self) -> Option<&'static dyn Handlers> {
        if self.state.load(Ordering::Acquire) == READY {
            // SAFETY: READY is stored after the write and never left.
            Some(unsafe { (*self.handlers.get()).assume_init() })
        } else {
            None
        }
    }
}

static SLOTS: [Slot; 3] = [Slot::new(), Slot::new(), Slot::new()];

const fn slot(instance: Instance) -> &'static Slot {
    match instance {
        Instance::Can1 => &SLOTS[0],
        Instance::Can2 => &SLOTS[1],
        Instance::Can3 => &SLOTS[2],
    }
}

/// Runs `line` of `instance`: what the exported entry points do. `false` when no
/// handler is in place for it (the line should be masked then).
#[inline]
pub fn dispatch(instance: Instance, line: Line) -> bool {
    match slot(instance).get() {
        Some(h) => h.run(line),
        None => false,
    }
}

/// Whether an [`IrqState`] was started on `instance` (the entry points run its cells).
pub fn is_wired(instance: Instance) -> bool {
    slot(instance).get().is_some()
}

type Hw<R, F, const K: usize, const M: usize, const SWITCH: bool> = BxCan<R, F, K, M, SWITCH>;

/// The split driver's state of one bxCAN instance together with its four interrupt
/// handlers, for a `static` (all zeros: `.bss`). `RX`/`RX1`: the FIFO 0 and FIFO 1
/// receive rings (frames); `Q`: the transmit queue; `DONE`: the completion ring; `K`:
/// the controller's lookup capacity; `M`: the match indices its filter map holds per
/// FIFO; `SWITCH`: whether the filters may be replaced while running; `Fe`: the split
/// driver's compile-time feature set (`twocan_core::Full` by default,
/// `twocan_core::Lean`: no statistics, no time stamps).
pub struct IrqState<
    R: Registers + 'static,
    F: Registers + 'static,
    const RX: usize,
    Q: TxQueue + 'static,
    const RX1: usize,
    const DONE: usize,
    const K: usize = LOOKUP_KEYS,
    const M: usize = MAX_FMI,
    const SWITCH: bool = true,
    Fe: Features = twocan_core::Full,
> {
    state: State<Hw<R, F, K, M, SWITCH>, RX, Q, RX1, DONE, Fe>,
    tx: IrqCell<TxIrq<'static, Hw<R, F, K, M, SWITCH>, RX, Q, RX1, DONE, Fe>>,
    rx0: IrqCell<Rx0Irq<'static, Hw<R, F, K, M, SWITCH>, RX, Q, RX1, DONE, Fe>>,
    rx1: IrqCell<Rx1Irq<'static, Hw<R, F, K, M, SWITCH>, RX, Q, RX1, DONE, Fe>>,
    sce: IrqCell<StatusIrq<'static, Hw<R, F, K, M, SWITCH>, RX, Q, RX1, DONE, Fe>>,
}

/// The transmit and receive halves [`IrqState::start_on`] gives the thread side.
pub type Halves<
    R,
    F,
    const RX: usize,
    Q,
    const RX1: usize,
    const DONE: usize,
    const K: usize,
    const M: usize,
    const SWITCH: bool,
    Fe,
> = (
    Tx<'static, Hw<R, F, K, M, SWITCH>, RX, Q, RX1, DONE, Fe>,
    Rx<'static, Hw<R, F, K, M, SWITCH>, RX, Q, RX1, DONE, Fe>,
);

/// Why [`IrqState::start_on`] did not start; the controller comes back with it, and
/// nothing was unmasked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StartError {
    /// The chip of the build has no interrupt lines for the controller's instance
    /// (CAN3 without `hal-stm32f7-can3`).
    NoInterrupts,
    /// The instance's entry points run another state's handlers.
    AlreadyWired,
    /// This state holds a controller already (started, not stopped).
    AlreadySplit,
    /// The controller's transmit order is not the queue's (`State::split`:
    /// [`Error::InvalidArgument`]).
    Split(Error),
}

impl fmt::Display for StartError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StartError::NoInterrupts => f.write_str("the instance has no interrupt lines"),
            StartError::AlreadyWired => {
                f.write_str("the instance's interrupt entry points run another state")
            }
            StartError::AlreadySplit => f.write_str("the state holds a controller already"),
            StartError::Split(e) => write!(f, "split refused the controller: {e}"),
        }
    }
}

impl core::error::Error for StartError {}

/// Why [`IrqState::stop_on`] did not stop; the halves come back with it. The lines are
/// unmasked again (each after its handler was put back), except with
/// [`StopError::Running`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StopError {
    /// The halves are not this state's (or it holds no controller).
    Foreign,
    /// A handler was running in a context the caller preempted (stop called from an
    /// interrupt of lower priority): the lines stay masked, the handlers in place;
    /// call again from thread mode.
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

impl<
        R,
        F,
        const RX: usize,
        Q,
        const RX1: usize,
        const DONE: usize,
        const K: usize,
        const M: usize,
        const SWITCH: bool,
        Fe,
    > Default for IrqState<R, F, RX, Q, RX1, DONE, K, M, SWITCH, Fe>
where
    R: Registers + 'static,
    F: Registers + 'static,
    Q: TxQueue + 'static,
    Fe: Features,
{
    fn default() -> Self {
        Self::new()
    }
}

impl<
        R,
        F,
        const RX: usize,
        Q,
        const RX1: usize,
        const DONE: usize,
        const K: usize,
        const M: usize,
        const SWITCH: bool,
        Fe,
    > IrqState<R, F, RX, Q, RX1, DONE, K, M, SWITCH, Fe>
where
    R: Registers + 'static,
    F: Registers + 'static,
    Q: TxQueue + 'static,
    Fe: Features,
{
    /// Empty (all zeros: `.bss`).
    pub const fn new() -> Self {
        IrqState {
            state: State::new(),
            tx: IrqCell::new(),
            rx0: IrqCell::new(),
            rx1: IrqCell::new(),
            sce: IrqCell::new(),
        }
    }

    /// The split driver's shared state (statistics, error state).
    pub fn state(&self) -> &State<Hw<R, F, K, M, SWITCH>, RX, Q, RX1, DONE, Fe> {
        &self.state
    }

    /// Whether each line's handler is in place, in [`Line::ALL`] order.
    pub fn installed(&self) -> [bool; 4] {
        [
            self.tx.is_ready(),
            self.rx0.is_ready(),
            self.rx1.is_ready(),
            self.sce.is_ready(),
        ]
    }
}

impl<
        R,
        F,
        const RX: usize,
        Q,
        const RX1: usize,
        const DONE: usize,
        const K: usize,
        const M: usize,
        const SWITCH: bool,
        Fe,
    > Handlers for IrqState<R, F, RX, Q, RX1, DONE, K, M, SWITCH, Fe>
where
    R: Registers + 'static,
    F: Registers + 'static,
    Q: TxQueue + 'static,
    Fe: Features,
    Self: Sync,
{
    #[inline]
    fn run(&self, line: Line) -> bool {
        match line {
            Line::Tx => self.tx.run(|h| h.on_interrupt()),
            Line::Rx0 => self.rx0.run(|h| h.on_interrupt()),
            Line::Rx1 => self.rx1.run(|h| h.on_interrupt()),
            Line::Sce => self.sce.run(|h| h.on_interrupt()),
        }
    }
}

impl<
        R,
        F,
        const RX: usize,
        Q,
        const RX1: usize,
        const DONE: usize,
        const K: usize,
        const M: usize,
        const SWITCH: bool,
        Fe,
    > IrqState<R, F, RX, Q, RX1, DONE, K, M, SWITCH, Fe>
where
    R: Registers + 'static,
    F: Registers + 'static,
    Q: TxQueue + 'static,
    Fe: Features,
    FmiMap<K, M>: Send,
    Self: Sync,
{
    /// Splits `hw` into this state, installs the four handlers behind the instance's
    /// entry points, **then** gives each of `lines` (the instance's TX, RX0, RX1, SCE
    /// interrupts, in [`Line::ALL`] order) its priority and unmasks it (module docs,
    /// "Order"). Returns the thread-side halves. On error nothing was unmasked and the
    /// controller comes back.
    ///
    /// A state stopped with [`IrqState::stop_on`] starts again; the entry points of an
    /// instance run the first state started on it for good
    /// ([`StartError::AlreadyWired`] for another one).
    // The controller comes back by value on error (no allocator to box it in).
    #[allow(clippy::type_complexity, clippy::result_large_err)]
    pub fn start_on<L: Copy>(
        &'static self,
        hw: Hw<R, F, K, M, SWITCH>,
        lines: [L; 4],
        priorities: Priorities,
        nvic: &mut impl Nvic<L>,
    ) -> Result<
        Halves<R, F, RX, Q, RX1, DONE, K, M, SWITCH, Fe>,
        (StartError, Hw<R, F, K, M, SWITCH>),
    > {
        if self.state.hardware().is_some() {
            return Err((StartError::AlreadySplit, hw));
        }
        if !slot(hw.instance()).wire(self) {
            return Err((StartError::AlreadyWired, hw));
        }
        let parts = match self.state.split(hw) {
            Ok(parts) => parts,
            Err((e, hw)) => {
                let e = match e {
                    Error::WrongMode => StartError::AlreadySplit,
                    e => StartError::Split(e),
                };
                return Err((e, hw));
            }
        };
        // The cells are empty: only a successful split fills them, and `stop_on`
        // empties them before it gives the controller back.
        let filled = self.tx.put(parts.tx_irq).is_ok()
            && self.rx0.put(parts.rx0_irq).is_ok()
            && self.rx1.put(parts.rx1_irq).is_ok()
            && self.sce.put(parts.status_irq).is_ok();
        debug_assert!(filled, "split succeeds once per start");
        enable(nvic, &lines, priorities);
        Ok((parts.tx, parts.rx))
    }

    /// [`IrqState::start_on`] with the controller **configured in place** in this state
    /// (issue 21: no controller, plan or filter map moves through the configuration,
    /// whose stack stays a few hundred bytes): `init` is an in-place constructor of
    /// `instance`'s controller, e.g. `|slot| BxCan::can1_in(slot, regs, &config,
    /// plan).map_err(|f| f.error)` ([`State::split_with`]). The handlers are installed
    /// and `lines` unmasked as by `start_on`.
    ///
    /// Errors: [`StartError::AlreadySplit`], [`StartError::AlreadyWired`] (then `init`
    /// is not called); [`StartError::Split`] with `init`'s error, or
    /// [`Error::InvalidArgument`] when the controller `init` built is not `instance`'s
    /// or its transmit order is not the queue's (nothing is unmasked; a controller
    /// configured by `init` stays as it is, off the driver).
    #[allow(clippy::type_complexity)]
    pub fn start_in_place_on<L: Copy>(
        &'static self,
        instance: Instance,
        init: impl FnOnce(
            &mut MaybeUninit<Hw<R, F, K, M, SWITCH>>,
        ) -> Result<&mut Hw<R, F, K, M, SWITCH>, Error>,
        lines: [L; 4],
        priorities: Priorities,
        nvic: &mut impl Nvic<L>,
    ) -> Result<Halves<R, F, RX, Q, RX1, DONE, K, M, SWITCH, Fe>, StartError> {
        if self.state.hardware().is_some() {
            return Err(StartError::AlreadySplit);
        }
        if !slot(instance).wire(self) {
            return Err(StartError::AlreadyWired);
        }
        let parts = self
            .state
            .split_with(|slot| {
                let hw = init(slot)?;
                if hw.instance() == instance {
                    Ok(hw)
                } else {
                    Err(Error::InvalidArgument)
                }
            })
            .map_err(|e| match e {
                Error::WrongMode => StartError::AlreadySplit,
                e => StartError::Split(e),
            })?;
        let filled = self.tx.put(parts.tx_irq).is_ok()
            && self.rx0.put(parts.rx0_irq).is_ok()
            && self.rx1.put(parts.rx1_irq).is_ok()
            && self.sce.put(parts.status_irq).is_ok();
        debug_assert!(filled, "split succeeds once per start");
        enable(nvic, &lines, priorities);
        Ok((parts.tx, parts.rx))
    }

    /// The way back: masks `lines` (the instance's TX, RX0, RX1, SCE, as given to
    /// [`IrqState::start_on`]), takes the four handlers back out of their cells (no
    /// entry point runs them from now on), and gives them with the halves to
    /// [`State::unsplit`]. Returns the controller, still on the bus (end it with
    /// [`BxCan::into_can`] then [`crate::Can::master_reset`]), and what was discarded.
    ///
    /// On error the halves come back (see [`StopError`] for the lines).
    #[allow(clippy::type_complexity, clippy::result_large_err)]
    pub fn stop_on<L: Copy>(
        &'static self,
        tx: Tx<'static, Hw<R, F, K, M, SWITCH>, RX, Q, RX1, DONE, Fe>,
        rx: Rx<'static, Hw<R, F, K, M, SWITCH>, RX, Q, RX1, DONE, Fe>,
        lines: [L; 4],
        nvic: &mut impl Nvic<L>,
    ) -> Result<
        (Hw<R, F, K, M, SWITCH>, Leftovers),
        (StopError, Halves<R, F, RX, Q, RX1, DONE, K, M, SWITCH, Fe>),
    > {
        if !core::ptr::eq(tx.state(), &self.state) || !core::ptr::eq(rx.state(), &self.state) {
            return Err((StopError::Foreign, (tx, rx)));
        }
        for &line in &lines {
            nvic.mask(line);
        }
        let (tx_irq, rx0_irq, rx1_irq, status_irq) = match (
            self.tx.take(),
            self.rx0.take(),
            self.rx1.take(),
            self.sce.take(),
        ) {
            (Some(a), Some(b), Some(c), Some(d)) => (a, b, c, d),
            (a, b, c, d) => {
                // A cell being run by a preempted context: put back what was taken
                // (the cells are empty again), lines left masked.
                let _ = a.map(|h| self.tx.put(h).is_ok());
                let _ = b.map(|h| self.rx0.put(h).is_ok());
                let _ = c.map(|h| self.rx1.put(h).is_ok());
                let _ = d.map(|h| self.sce.put(h).is_ok());
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
            Err((e, parts)) => {
                let filled = self.tx.put(parts.tx_irq).is_ok()
                    && self.rx0.put(parts.rx0_irq).is_ok()
                    && self.rx1.put(parts.rx1_irq).is_ok()
                    && self.sce.put(parts.status_irq).is_ok();
                debug_assert!(filled, "emptied above");
                for &line in &lines {
                    nvic.unmask(line);
                }
                let e = match e {
                    UnsplitError::Foreign => StopError::Foreign,
                    UnsplitError::Leased => StopError::Leased,
                };
                Err((e, (parts.tx, parts.rx)))
            }
        }
    }
}

/// Priority, then unmask, for each line (after the handlers were put in place).
fn enable<L: Copy>(nvic: &mut impl Nvic<L>, lines: &[L; 4], priorities: Priorities) {
    for (line, &irq) in Line::ALL.iter().zip(lines) {
        nvic.set_priority(irq, priorities.of(*line));
    }
    for &irq in lines {
        nvic.unmask(irq);
    }
}

/// Exports one entry point per `(vector, instance, line)`, each name checked against
/// the PAC's `Interrupt` enum at compile time; `$pac` is the chip's PAC path.
#[allow(unused_macros)]
macro_rules! entry_points {
    ($pac:path; $($(#[$m:meta])* $vector:ident => $instance:ident, $line:ident;)*) => {
        $(
            $(#[$m])*
            #[doc = concat!("Entry point `", stringify!($vector), "`: ", stringify!($instance), " ", stringify!($line), " line.")]
            #[export_name = stringify!($vector)]
            #[allow(non_snake_case)]
            pub extern "C" fn $vector() {
                use $pac as pac;
                // The vector exists on this chip.
                const _: pac::Interrupt = pac::Interrupt::$vector;
                dispatch(Instance::$instance, Line::$line);
            }
        )*
    };
}

/// The STM32F7 (`stm32f7xx-hal`'s PAC: RM0410 table 40 "STM32F76xxx and STM32F77xxx
/// vector table"): lines per instance, the entry points, and `start`/`stop` with them.
#[cfg(feature = "hal-stm32f7")]
mod f7 {
    use super::*;
    use stm32f7xx_hal::pac::Interrupt;

    /// The TX, RX0, RX1 and SCE interrupts of `instance` on the chip of the build
    /// (`None` for CAN3 without `hal-stm32f7-can3`).
    pub const fn lines(instance: Instance) -> Option<[Interrupt; 4]> {
        match instance {
            Instance::Can1 => Some([
                Interrupt::CAN1_TX,
                Interrupt::CAN1_RX0,
                Interrupt::CAN1_RX1,
                Interrupt::CAN1_SCE,
            ]),
            Instance::Can2 => Some([
                Interrupt::CAN2_TX,
                Interrupt::CAN2_RX0,
                Interrupt::CAN2_RX1,
                Interrupt::CAN2_SCE,
            ]),
            #[cfg(feature = "hal-stm32f7-can3")]
            Instance::Can3 => Some([
                Interrupt::CAN3_TX,
                Interrupt::CAN3_RX0,
                Interrupt::CAN3_RX1,
                Interrupt::CAN3_SCE,
            ]),
            #[cfg(not(feature = "hal-stm32f7-can3"))]
            Instance::Can3 => None,
        }
    }

    impl<
            R,
            F,
            const RX: usize,
            Q,
            const RX1: usize,
            const DONE: usize,
            const K: usize,
            const M: usize,
            const SWITCH: bool,
            Fe,
        > IrqState<R, F, RX, Q, RX1, DONE, K, M, SWITCH, Fe>
    where
        R: Registers + 'static,
        F: Registers + 'static,
        Q: TxQueue + 'static,
        Fe: Features,
        FmiMap<K, M>: Send,
        Self: Sync,
    {
        /// [`IrqState::start_on`] with the controller's instance's [`lines`] on the
        /// STM32F7.
        #[allow(clippy::type_complexity, clippy::result_large_err)]
        pub fn start(
            &'static self,
            hw: Hw<R, F, K, M, SWITCH>,
            priorities: Priorities,
            nvic: &mut impl Nvic<Interrupt>,
        ) -> Result<
            Halves<R, F, RX, Q, RX1, DONE, K, M, SWITCH, Fe>,
            (StartError, Hw<R, F, K, M, SWITCH>),
        > {
            match lines(hw.instance()) {
                Some(l) => self.start_on(hw, l, priorities, nvic),
                None => Err((StartError::NoInterrupts, hw)),
            }
        }

        /// [`IrqState::start_in_place_on`] with `instance`'s [`lines`] on the STM32F7.
        #[allow(clippy::type_complexity)]
        pub fn start_in_place(
            &'static self,
            instance: Instance,
            init: impl FnOnce(
                &mut MaybeUninit<Hw<R, F, K, M, SWITCH>>,
            ) -> Result<&mut Hw<R, F, K, M, SWITCH>, Error>,
            priorities: Priorities,
            nvic: &mut impl Nvic<Interrupt>,
        ) -> Result<Halves<R, F, RX, Q, RX1, DONE, K, M, SWITCH, Fe>, StartError> {
            match lines(instance) {
                Some(l) => self.start_in_place_on(instance, init, l, priorities, nvic),
                None => Err(StartError::NoInterrupts),
            }
        }

        /// [`IrqState::stop_on`] with the instance's [`lines`] on the STM32F7.
        #[allow(clippy::type_complexity, clippy::result_large_err)]
        pub fn stop(
            &'static self,
            tx: Tx<'static, Hw<R, F, K, M, SWITCH>, RX, Q, RX1, DONE, Fe>,
            rx: Rx<'static, Hw<R, F, K, M, SWITCH>, RX, Q, RX1, DONE, Fe>,
            nvic: &mut impl Nvic<Interrupt>,
        ) -> Result<
            (Hw<R, F, K, M, SWITCH>, Leftovers),
            (StopError, Halves<R, F, RX, Q, RX1, DONE, K, M, SWITCH, Fe>),
        > {
            let instance = tx.hardware().instance();
            match lines(instance) {
                Some(l) => self.stop_on(tx, rx, l, nvic),
                None => Err((StopError::Foreign, (tx, rx))),
            }
        }
    }

    /// The entry points (exported under the vector names; callable from Rust for
    /// tests on the host, where no vector table names them).
    pub mod vectors {
        use super::super::{dispatch, Line};
        use crate::instance::Instance;

        entry_points!(stm32f7xx_hal::pac;
            CAN1_TX => Can1, Tx;
            CAN1_RX0 => Can1, Rx0;
            CAN1_RX1 => Can1, Rx1;
            CAN1_SCE => Can1, Sce;
            CAN2_TX => Can2, Tx;
            CAN2_RX0 => Can2, Rx0;
            CAN2_RX1 => Can2, Rx1;
            CAN2_SCE => Can2, Sce;
            #[cfg(feature = "hal-stm32f7-can3")]
            CAN3_TX => Can3, Tx;
            #[cfg(feature = "hal-stm32f7-can3")]
            CAN3_RX0 => Can3, Rx0;
            #[cfg(feature = "hal-stm32f7-can3")]
            CAN3_RX1 => Can3, Rx1;
            #[cfg(feature = "hal-stm32f7-can3")]
            CAN3_SCE => Can3, Sce;
        );
    }
}

#[cfg(feature = "hal-stm32f7")]
pub use f7::{lines, vectors};
