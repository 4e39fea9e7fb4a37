//! The split driver: one shared [`State`] that a `static` holds, and handles taken from
//! it once — the transmit half [`Tx`], the receive half [`Rx`] (thread or task
//! context) and one handler per interrupt line ([`TxIrq`], [`RxIrq`], [`StatusIrq`]).
//!
//! ```text
//!  thread / tasks                         interrupt lines
//!  Tx::try_send ─ queue empty & mailbox free ──► mailbox (no lock)
//!      └─ otherwise ─► [transmit queue] ◄── critical section ──► TxIrq::on_interrupt
//!  Tx::take_completion ◄────── completion ring (lock-free) ◄───────┘ (settles, refills)
//!  Rx::receive (decode, user index) ◄─ raw ring per FIFO (lock-free) ◄─ RxIrq::on_interrupt
//!  Rx::take_state_change ◄──── state-change ring (lock-free) ◄──────── StatusIrq::on_interrupt
//! ```
//!
//! Who owns what: each ring has one producer handle and one consumer handle, so the
//! per-frame path needs no critical section. The transmit queue is the only structure
//! two contexts modify; it is touched inside a critical section only when a frame cannot
//! go straight into a free mailbox, and by the transmit interrupt (settling ended
//! mailboxes and refilling them: a bounded loop over the mailboxes). The interrupt
//! handlers can only exist once [`State::split`] has stored the controller: an
//! interrupt that fires before its handler is installed must stay masked (enable the
//! interrupt lines after the split).
//!
//! ```
//! use twocan_core::mock::{block, MockHardware};
//! use twocan_core::split::State;
//! use twocan_core::{FifoQueue, Frame, TxOutcome};
//!
//! static CAN: State<MockHardware, 8, FifoQueue<4>> = State::new();
//!
//! let mut parts = CAN.split(MockHardware::new(3)).expect("taken once");
//! assert!(CAN.split(MockHardware::new(3)).is_err(), "a second split is refused");
//! let frame = Frame::standard(0x123, &[1, 2])?;
//! let token = block("room to send", || parts.tx.try_send(&frame))?; // nb::block! in firmware
//! CAN.hardware().unwrap().complete_all();   // the mock "sends" its mailboxes
//! parts.tx_irq.on_interrupt();              // in the transmit interrupt handler
//! let done = parts.tx.take_completion().unwrap();
//! assert_eq!((done.token, done.outcome), (token, TxOutcome::Sent));
//! # Ok::<(), twocan_core::Error>(())
//! ```

use core::cell::{Cell, UnsafeCell};
#[cfg(feature = "async")]
use core::sync::atomic::AtomicBool;
use core::sync::atomic::{AtomicU32, AtomicU8, Ordering};

use crate::controller::{ErrorStatus, Mode};
use crate::dispatch::Dispatcher;
use crate::error::{Error, ErrorCounters, ErrorState, ErrorStatistics, LastErrorCode};
use crate::features::StampClock;
use crate::features::{Features, Full, Tally};
use crate::frame::{Frame, RxFrame};
use crate::hardware::{Completion, FifoEvents, Hardware, Settled, Token};
use crate::mailbox::{TxOutcome, TxPolicy};
use crate::once::{Lease, OnceSlot};
use crate::spsc::{BufferStats, Counter, SpscRing};
use crate::timestamp::Timestamp;
use crate::txqueue::{FifoQueue, Queued, TxQueue};

/// Capacity of the error-state change ring. Changes the thread side has not taken when
/// the ring is full are counted in [`TrafficStats::state_change_overflows`], not lost
/// silently.
pub const STATE_CHANGES: usize = 8;

/// One error-state change, with the counters read at the change.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StateChange {
    /// The new state.
    pub state: ErrorState,
    /// TEC (256 while bus-off) and REC when the change was seen.
    pub counters: ErrorCounters,
}

/// Traffic counters (wrapping: compare readings with wrapping differences), each
/// written by one context; 0 under a feature set without statistics
/// ([`crate::Lean`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TrafficStats {
    /// Frames accepted by `try_send` (each has a token and gets one completion).
    pub queued: u32,
    /// Completions: sent.
    pub sent: u32,
    /// Completions: failed (one-shot mode).
    pub failed: u32,
    /// Completions: aborted (queued frames dropped, mailboxes aborted).
    pub aborted: u32,
    /// Frames taken from the hardware by the receive handlers.
    pub received: u32,
    /// Frames lost because a receive ring was full.
    pub rx_ring_overflows: u32,
    /// Frames the hardware accepted that no user filter claims (dropped on the thread
    /// side, e.g. the extra identifiers of a superset filter plan), and frames the old
    /// list had accepted that a filter switch discarded (from the hardware FIFO,
    /// [`Hardware::take_filter_switch_discards`], or from the ring).
    pub rx_dropped: u32,
    /// Completions lost because the completion ring was full.
    pub completion_overflows: u32,
    /// Error-state transitions observed.
    pub state_changes: u32,
    /// Error-state transitions lost because the state-change ring
    /// ([`STATE_CHANGES`] entries) was full: the thread side did not take them
    /// ([`Rx::take_state_change`]) before more arrived. Every transition is in
    /// [`TrafficStats::state_changes`]; the ring keeps the oldest ones not yet taken and
    /// counts each newer one it could not hold here.
    pub state_change_overflows: u32,
}

/// One raw frame in a receive ring, with the wraps of its time stamp counted by the
/// receive interrupt (0 when the hardware records no stamp) as the feature set's clock
/// keeps them (`W`: `u32`, or zero-sized without time stamps).
#[derive(Clone, Copy)]
pub(crate) struct Stamped<R, W> {
    raw: R,
    wraps: W,
}

/// How a receive ring slot of feature set `Fe` keeps a stamp's wraps.
type Wraps<Fe> = <<Fe as Features>::Clock as StampClock>::Wraps;

/// What a [`State`] of one type spends its bytes on ([`State::FOOTPRINT`]), on the
/// target it is built for: `size_of` of each part's type, [`Footprint::padding`] the
/// rest. The slots are what the capacities buy; everything else is the driver's own
/// state, and each compile-time choice shows here as the bytes it adds.
///
/// ```
/// use twocan_core::mock::MockHardware;
/// use twocan_core::split::State;
/// use twocan_core::{FifoQueue, Full, Lean};
///
/// type LeanState = State<MockHardware, 8, FifoQueue<4>, 0, 0, Lean>;
/// type FullState = State<MockHardware, 8, FifoQueue<4>, 0, 8, Full>;
/// let (lean, full) = (LeanState::FOOTPRINT, FullState::FOOTPRINT);
/// assert_eq!(lean.total, core::mem::size_of::<LeanState>());
/// assert_eq!((lean.clock, lean.statistics, lean.completion_slots), (0, 0, 0));
/// assert!(full.clock > 0 && full.statistics > 0 && full.completion_slots > 0);
/// assert!(lean.driver_state() < full.driver_state());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Footprint {
    /// The whole `State`.
    pub total: usize,
    /// The controller value, with its publication stage and lease count.
    pub controller: usize,
    /// Receive ring slots of both queues (`RX` + `RX1`): a raw frame each, with the
    /// wraps of its time stamp when the feature set widens them.
    pub receive_slots: usize,
    /// Transmit queue slots (`Q::CAPACITY` entries).
    pub transmit_slots: usize,
    /// Completion ring slots (`DONE`).
    pub completion_slots: usize,
    /// State-change ring slots ([`STATE_CHANGES`]).
    pub state_change_slots: usize,
    /// The four rings' indices, peaks and overflow counts (kept by a ring of capacity
    /// 0 as well).
    pub ring_bookkeeping: usize,
    /// The transmit queue's own indices, its length, peak and overflow count.
    pub queue_bookkeeping: usize,
    /// The time-stamp widening reference ([`Features::Clock`]).
    pub clock: usize,
    /// The traffic statistics ([`Features::Counter`]: queued, sent, failed, aborted,
    /// received per queue, dropped).
    pub statistics: usize,
    /// The rare events, counted in every feature set: overruns and warnings per
    /// queue, error counts, state changes, and the current error state.
    pub errors: usize,
    /// The wakers of the async API (feature `async`; 0 without).
    pub wakers: usize,
    /// Alignment padding: the total less every part above.
    pub padding: usize,
}

impl Footprint {
    /// The slots the capacities buy (receive, transmit, completion, state-change).
    pub const fn slots(&self) -> usize {
        self.receive_slots + self.transmit_slots + self.completion_slots + self.state_change_slots
    }

    /// Everything but the slots: the driver's own state.
    pub const fn driver_state(&self) -> usize {
        self.total - self.slots()
    }
}

/// No state recorded yet (0, so that a `static State` is all zeros and lives in `.bss`).
const STATE_UNKNOWN: u8 = 0;

fn state_code(s: ErrorState) -> u8 {
    match s {
        ErrorState::Active => 1,
        ErrorState::Warning => 2,
        ErrorState::Passive => 3,
        ErrorState::BusOff => 4,
        ErrorState::Stopped => 5,
        ErrorState::Sleeping => 6,
    }
}

/// Error statistics as atomics, written by the status handler only.
struct ErrorCounts {
    stuff: Counter,
    form: Counter,
    ack: Counter,
    bit: Counter,
    crc: Counter,
    bus_off: Counter,
    wakeups: Counter,
}

/// The counters of one hardware receive queue, written by its receive handler only.
///
/// One writer per counter, rather than a read-modify-write shared by both handlers:
/// an atomic `fetch_add` would need LDREX/STREX (ARMv7-M has them, ARMv6-M does not)
/// and costs a retry loop on the per-frame path; a plain load and store per queue
/// works on every core and the readers add the two.
struct QueueCounts<C> {
    received: C,
    overruns: Counter,
    warnings: Counter,
}

impl<C: Tally> QueueCounts<C> {
    const fn new() -> Self {
        QueueCounts {
            received: C::NEW,
            overruns: Counter::new(),
            warnings: Counter::new(),
        }
    }
}

impl ErrorCounts {
    const fn new() -> Self {
        ErrorCounts {
            stuff: Counter::new(),
            form: Counter::new(),
            ack: Counter::new(),
            bit: Counter::new(),
            crc: Counter::new(),
            bus_off: Counter::new(),
            wakeups: Counter::new(),
        }
    }

    fn record(&self, code: LastErrorCode) {
        match code {
            LastErrorCode::None => {}
            LastErrorCode::Stuff => self.stuff.inc(),
            LastErrorCode::Form => self.form.inc(),
            LastErrorCode::Acknowledge => self.ack.inc(),
            LastErrorCode::BitRecessive | LastErrorCode::BitDominant => self.bit.inc(),
            LastErrorCode::Crc => self.crc.inc(),
        }
    }
}

/// Everything the halves and handlers share. A `static` holds it (`State::new` is a
/// `const fn` of zeros: no flash image); [`State::split`] stores the controller and
/// hands out the handles once.
///
/// - `H`: the controller ([`Hardware`]).
/// - `RX`: receive ring capacity (frames) of the first receive queue (bxCAN FIFO 0,
///   FlexCAN Rx FIFO).
/// - `Q`: the transmit queue, which fixes the transmit order and its capacity
///   ([`FifoQueue`] or [`crate::PriorityQueue`]); the completion ring has the same
///   capacity.
/// - `RX1`: receive ring capacity of the second queue (bxCAN FIFO 1; 0 when unused —
///   frames arriving there are then counted as ring overflows).
/// - `DONE`: completion ring capacity (a completion that finds it full is counted in
///   [`TrafficStats::completion_overflows`]; 0 turns completions off).
pub struct State<
    H: Hardware,
    const RX: usize,
    Q: TxQueue = FifoQueue<8>,
    const RX1: usize = 0,
    const DONE: usize = 8,
    Fe: Features = Full,
> {
    /// The controller, published once by `split` (see [`OnceSlot`]).
    hw: OnceSlot<H>,
    rx0: SpscRing<Stamped<H::Raw, Wraps<Fe>>, RX>,
    rx1: SpscRing<Stamped<H::Raw, Wraps<Fe>>, RX1>,
    /// The time stamp extender shared by the receive and transmit interrupt sides (and
    /// `refresh_timestamps`), touched inside a critical section only.
    clock: critical_section::Mutex<Cell<Fe::Clock>>,
    queue: critical_section::Mutex<UnsafeCell<Q>>,
    /// Entries in `queue` plus displaced frames on their way back into it.
    queue_len: AtomicU32,
    queue_peak: AtomicU32,
    queue_overflows: Counter,
    done: SpscRing<Completion, DONE>,
    changes: SpscRing<StateChange, STATE_CHANGES>,
    state: AtomicU8,
    queued: Fe::Counter,
    sent: Fe::Counter,
    failed: Fe::Counter,
    aborted: Fe::Counter,
    /// Per hardware receive queue: each queue's handler is the one writer of its
    /// counters (bxCAN's RX0 and RX1 handlers may preempt each other); read as sums.
    per_queue: [QueueCounts<Fe::Counter>; 2],
    dropped: Fe::Counter,
    state_changes: Counter,
    errors: ErrorCounts,
    #[cfg(feature = "async")]
    pub(crate) wakers: crate::wakers::Wakers,
    /// A completion was recorded since the transmit handler last looked: the event that
    /// wakes the transmit half's waits. Written and cleared only inside the critical
    /// section (plain load and store, no read-modify-write).
    #[cfg(feature = "async")]
    tx_event: AtomicBool,
    _q: core::marker::PhantomData<Q>,
}

// SAFETY: what each field needs to be shared between contexts:
// - `hw`: a `OnceSlot<H>`, `Sync` when `H: Send + Sync` (as `OnceLock<T>`): written
//   once by the one `split` that claimed it and published (release; readers acquire),
//   then only read through `&H` from every context (`H: Sync`); a controller moved in
//   through `&State` by one thread is dropped (or taken back by `uninstall`) by
//   whichever thread owns the state later (`H: Send`).
// - the rings: one producer handle and one consumer handle each (`SpscRing`'s
//   contract, upheld by the handles `split` makes once); their entries move between
//   contexts: `H::Raw: Send` (raw frames), and completions and state changes are plain
//   data.
// - `queue`: only touched inside a critical section (`critical_section::Mutex`), and its
//   entries move between contexts: `Q: Send`.
// - `clock`: inside a `critical_section::Mutex`; the counters, `stage` and `state` are
//   atomics; the wakers are `AtomicWaker`s (`Sync`).
unsafe impl<
        H: Hardware + Send + Sync,
        const RX: usize,
        Q: TxQueue + Send,
        const RX1: usize,
        const DONE: usize,
        Fe: Features,
    > Sync for State<H, RX, Q, RX1, DONE, Fe>
where
    H::Raw: Send,
{
}

impl<
        H: Hardware,
        const RX: usize,
        Q: TxQueue,
        const RX1: usize,
        const DONE: usize,
        Fe: Features,
    > Default for State<H, RX, Q, RX1, DONE, Fe>
{
    fn default() -> Self {
        Self::new()
    }
}

/// The handles [`State::split`] hands out, each for one context.
pub struct Parts<
    'a,
    H: Hardware,
    const RX: usize,
    Q: TxQueue,
    const RX1: usize,
    const DONE: usize,
    Fe: Features = Full,
> {
    /// Transmit half (thread/task).
    pub tx: Tx<'a, H, RX, Q, RX1, DONE, Fe>,
    /// Receive half (thread/task).
    pub rx: Rx<'a, H, RX, Q, RX1, DONE, Fe>,
    /// Transmit interrupt handler (bxCAN TX line; FlexCAN message-buffer line).
    pub tx_irq: TxIrq<'a, H, RX, Q, RX1, DONE, Fe>,
    /// Receive interrupt handler of queue 0 (bxCAN RX0; FlexCAN message-buffer line).
    pub rx0_irq: Rx0Irq<'a, H, RX, Q, RX1, DONE, Fe>,
    /// Receive interrupt handler of queue 1 (bxCAN RX1; unused on FlexCAN). A type of
    /// its own: it cannot be put where queue 0's handler belongs.
    pub rx1_irq: Rx1Irq<'a, H, RX, Q, RX1, DONE, Fe>,
    /// Status interrupt handler (bxCAN SCE; FlexCAN bus-off, error, warning, wake-up).
    pub status_irq: StatusIrq<'a, H, RX, Q, RX1, DONE, Fe>,
}

impl<
        H: Hardware,
        const RX: usize,
        Q: TxQueue,
        const RX1: usize,
        const DONE: usize,
        Fe: Features,
    > State<H, RX, Q, RX1, DONE, Fe>
{
    /// The quiet transmit mode ([`Hardware::QUIET_TX`]), settled at compile time: no
    /// completion ring (`DONE` = 0), no statistics or time stamps to record, a queue
    /// in request order (nothing is ever displaced), on a controller that offers it.
    /// The transmit interrupt then runs only while frames wait in the queue, and
    /// acknowledges ended mailboxes without reporting them. (The async halves exist for
    /// [`crate::Full`] only, so no async waiter depends on it.) `split` refuses a
    /// controller whose transmit order is not the request order in this mode.
    pub const QUIET_TX: bool =
        H::QUIET_TX && DONE == 0 && !Fe::COUNTS && !Fe::TIMESTAMPS && Q::ALWAYS_FIFO;

    /// What this `State` type spends its bytes on ([`Footprint`]).
    pub const FOOTPRINT: Footprint = {
        use core::mem::size_of;
        let total = size_of::<Self>();
        let controller = size_of::<OnceSlot<H>>();
        let slot = size_of::<Stamped<H::Raw, Wraps<Fe>>>();
        let receive_slots = (RX + RX1) * slot;
        let transmit_slots = Q::CAPACITY * size_of::<Queued>();
        let completion_slots = DONE * size_of::<Completion>();
        let state_change_slots = STATE_CHANGES * size_of::<StateChange>();
        let ring_bookkeeping = size_of::<SpscRing<Stamped<H::Raw, Wraps<Fe>>, RX>>()
            + size_of::<SpscRing<Stamped<H::Raw, Wraps<Fe>>, RX1>>()
            + size_of::<SpscRing<Completion, DONE>>()
            + size_of::<SpscRing<StateChange, STATE_CHANGES>>()
            - receive_slots
            - completion_slots
            - state_change_slots;
        // (Saturating: a queue type of its own may store its entries otherwise.)
        let queue_bookkeeping = size_of::<critical_section::Mutex<UnsafeCell<Q>>>()
            .saturating_sub(transmit_slots)
            + 2 * size_of::<AtomicU32>()
            + size_of::<Counter>();
        let clock = size_of::<critical_section::Mutex<Cell<Fe::Clock>>>();
        let statistics = 5 * size_of::<Fe::Counter>() + 2 * size_of::<Fe::Counter>();
        let errors = 2 * 2 * size_of::<Counter>()
            + size_of::<Counter>()
            + size_of::<ErrorCounts>()
            + size_of::<AtomicU8>();
        #[cfg(feature = "async")]
        let wakers = size_of::<crate::wakers::Wakers>() + size_of::<AtomicBool>();
        #[cfg(not(feature = "async"))]
        let wakers = 0;
        let parts = controller
            + receive_slots
            + transmit_slots
            + completion_slots
            + state_change_slots
            + ring_bookkeeping
            + queue_bookkeeping
            + clock
            + statistics
            + errors
            + wakers;
        Footprint {
            total,
            controller,
            receive_slots,
            transmit_slots,
            completion_slots,
            state_change_slots,
            ring_bookkeeping,
            queue_bookkeeping,
            clock,
            statistics,
            errors,
            wakers,
            padding: total.saturating_sub(parts),
        }
    };

    /// The feature set's clock widens stamps exactly when its time stamps are on
    /// ([`Features::Clock`]): a `State` of a feature set that disagrees does not build.
    const CLOCK_AGREES: () = assert!(
        Fe::TIMESTAMPS == <Fe::Clock as StampClock>::WIDENS,
        "Features::Clock must be Extender with TIMESTAMPS and NoClock without"
    );

    crate::sync::const_fn! {
        /// Empty, with no controller yet: all zeros.
        pub fn new() -> Self {
            let () = Self::CLOCK_AGREES;
            State {
                hw: OnceSlot::new(),
                rx0: SpscRing::new(),
                rx1: SpscRing::new(),
                clock: critical_section::Mutex::new(Cell::new(<Fe::Clock as StampClock>::NEW)),
                queue: critical_section::Mutex::new(UnsafeCell::new(Q::EMPTY)),
                queue_len: AtomicU32::new(0),
                queue_peak: AtomicU32::new(0),
                queue_overflows: Counter::new(),
                done: SpscRing::new(),
                changes: SpscRing::new(),
                state: AtomicU8::new(STATE_UNKNOWN),
                queued: Fe::Counter::NEW,
                sent: Fe::Counter::NEW,
                failed: Fe::Counter::NEW,
                aborted: Fe::Counter::NEW,
                per_queue: [QueueCounts::new(), QueueCounts::new()],
                dropped: Fe::Counter::NEW,
                state_changes: Counter::new(),
                errors: ErrorCounts::new(),
                #[cfg(feature = "async")]
                wakers: crate::wakers::Wakers::new(),
                #[cfg(feature = "async")]
                tx_event: AtomicBool::new(false),
                _q: core::marker::PhantomData,
            }
        }
    }

    /// Stores `hardware` and hands out the handles; once only. A second call gives
    /// `hardware` back. The controller's transmit order must be `Q`'s
    /// ([`Error::InvalidArgument`] otherwise, with the controller given back).
    ///
    /// Any context may call it, and several may race: the first to claim the state
    /// (one compare-and-swap) is the only one that touches the queue and writes the
    /// controller; the controller becomes visible to [`State::hardware`] (and to every
    /// reader in other contexts) only once it is written, through a release store that
    /// those readers load with acquire ordering.
    #[allow(clippy::type_complexity)]
    pub fn split(&self, hardware: H) -> Result<Parts<'_, H, RX, Q, RX1, DONE, Fe>, (Error, H)> {
        // Claim first: a losing `split` must not touch the winner's queue.
        let Some(claim) = self.hw.claim() else {
            return Err((Error::WrongMode, hardware));
        };
        if !self.adopt_order(&hardware) {
            // Nothing was written: dropping the claim frees the state again.
            drop(claim);
            return Err((Error::InvalidArgument, hardware));
        }
        // Written, read while only this context can see it, then published (release):
        // every reader (`hardware()`, acquire) sees the controller whole.
        let (_, (map, status)) = claim.publish(hardware, |hw| self.first_look(hw));
        self.refresh_timestamps();
        Ok(self.parts(map, status))
    }

    /// [`State::split`] with the controller **built in place** in the state (no move of
    /// the controller through the configuration path, so the configuration's stack
    /// stays small whatever the controller's size): `init` gets the state's empty
    /// controller storage, configures the controller there and returns it
    /// (`Ok(slot.write(..))`, or a backend's in-place constructor such as
    /// `twocan_bxcan::BxCan::can1_in`). Once only, as `split`.
    ///
    /// Errors: `init`'s error (the state stays unsplit; the backend's constructor says
    /// what it gives back); [`Error::WrongMode`] when the state was split already (then
    /// `init` is not called); [`Error::InvalidArgument`] when the controller's transmit
    /// order is not `Q`'s (the controller is dropped in place, the state stays
    /// unsplit) or when `init` returns a controller that is not the slot's.
    #[allow(clippy::type_complexity)]
    pub fn split_with(
        &self,
        init: impl FnOnce(&mut core::mem::MaybeUninit<H>) -> Result<&mut H, Error>,
    ) -> Result<Parts<'_, H, RX, Q, RX1, DONE, Fe>, Error> {
        let Some(claim) = self.hw.claim() else {
            return Err(Error::WrongMode);
        };
        let adopt = |hw: &H| {
            if self.adopt_order(hw) {
                Ok(())
            } else {
                Err(Error::InvalidArgument)
            }
        };
        let (_, (map, status)) = claim
            .publish_in_place(init, adopt, |hw| self.first_look(hw))
            .map_err(|e| e.unwrap_or(Error::InvalidArgument))?;
        self.refresh_timestamps();
        Ok(self.parts(map, status))
    }

    /// Makes the queue take the controller's transmit order (the claimer only);
    /// whether the orders agree.
    fn adopt_order(&self, hw: &H) -> bool {
        if Self::QUIET_TX && hw.tx_policy() != TxPolicy::Fifo {
            // The quiet mode loads any empty mailbox: only request order keeps the
            // order then (a user queue claiming `ALWAYS_FIFO` may adopt another).
            return false;
        }
        critical_section::with(|cs| {
            // SAFETY: the queue is only touched inside a critical section.
            unsafe { &mut *self.queue.borrow(cs).get() }.adopt(hw.tx_policy())
        })
    }

    /// The filter map and error status of a controller not yet published, the state
    /// recorded from it.
    fn first_look(&self, hw: &H) -> (H::FilterMap, ErrorStatus) {
        // SAFETY: not published yet: this is the only context that sees it.
        let map = unsafe { hw.filter_map() };
        if Self::QUIET_TX {
            // Nothing queued yet: the transmit interrupt waits for the first queued
            // frame. SAFETY: not published yet, so no other context runs the driver.
            unsafe { hw.set_tx_interrupt(false) };
        }
        let status = hw.error_status();
        self.state
            .store(state_code(status.state), Ordering::Relaxed);
        (map, status)
    }

    /// The handles over a published controller (made once, by the one splitter).
    #[allow(clippy::type_complexity)]
    fn parts(&self, map: H::FilterMap, status: ErrorStatus) -> Parts<'_, H, RX, Q, RX1, DONE, Fe> {
        Parts {
            tx: Tx { s: self, next: 0 },
            rx: Rx { s: self, map },
            tx_irq: TxIrq { s: self },
            rx0_irq: RxIrq { s: self },
            rx1_irq: RxIrq { s: self },
            status_irq: StatusIrq {
                s: self,
                last: status.state,
            },
        }
    }

    /// Stores `hardware` in a state owned exclusively (the one-struct
    /// [`crate::Driver`]); returns the filter map and status for its handles.
    pub(crate) fn install(&mut self, hardware: H) -> (H::FilterMap, ErrorStatus) {
        let policy = hardware.tx_policy();
        self.queue.get_mut().get_mut().adopt(policy);
        // `&mut self`: no other context can look.
        let hw = self.hw.set(hardware);
        let status = hw.error_status();
        // SAFETY: `&mut self`: the controller is not shared.
        let map = unsafe { hw.filter_map() };
        self.state
            .store(state_code(status.state), Ordering::Relaxed);
        self.refresh_timestamps();
        (map, status)
    }

    /// Takes the controller back out of a state owned exclusively.
    pub(crate) fn uninstall(&mut self) -> Option<H> {
        self.hw.take()
    }

    /// Gives the controller back once no handle borrows the state any more (it takes
    /// the state by value, so the handles are gone; a `static` state gives it back
    /// with [`State::unsplit`]). Frames and completions still in the rings and the
    /// queue go with the state; the controller keeps its configuration and its
    /// mailboxes. `None` when the state was never split.
    pub fn into_hardware(mut self) -> Option<H> {
        self.uninstall()
    }

    /// The controller, once [`State::split`] stored it (any context). The reference is
    /// a [`Lease`]: while it lives, [`State::unsplit`] refuses to take the controller
    /// out ([`UnsplitError::Leased`]); drop it before ending the controller.
    pub fn hardware(&self) -> Option<Lease<'_, H>> {
        self.hw.lease()
    }

    /// The controller of a state owned exclusively ([`crate::Driver`]): no `unsplit`
    /// can run while `&self` lives there.
    pub(crate) fn owned_hardware(&self) -> Option<&H> {
        self.hw.get()
    }

    #[inline(always)]
    fn hw(&self) -> &H {
        // SAFETY: only the handles call this. A handle is made by `split` after it
        // published the controller, in the same thread, and reaches another context
        // only through something that synchronises (a thread spawn, an `IrqCell`'s
        // release/acquire, a channel): the publication happens before this read.
        unsafe { self.hw.get_unchecked() }
    }

    /// Traffic counters.
    pub fn traffic(&self) -> TrafficStats {
        TrafficStats {
            queued: self.queued.get(),
            sent: self.sent.get(),
            failed: self.failed.get(),
            aborted: self.aborted.get(),
            received: self.per_queue[0]
                .received
                .get()
                .wrapping_add(self.per_queue[1].received.get()),
            rx_ring_overflows: self.rx0.stats().overflows + self.rx1.stats().overflows,
            rx_dropped: self.dropped.get(),
            completion_overflows: self.done.stats().overflows,
            state_changes: self.state_changes.get(),
            state_change_overflows: self.changes.stats().overflows,
        }
    }

    /// Error statistics (bus errors by kind, bus-off count, hardware overruns).
    pub fn error_stats(&self) -> ErrorStatistics {
        let e = &self.errors;
        ErrorStatistics {
            stuff: e.stuff.get(),
            form: e.form.get(),
            acknowledge: e.ack.get(),
            bit: e.bit.get(),
            crc: e.crc.get(),
            bus_off: e.bus_off.get(),
            hardware_overruns: self.per_queue[0]
                .overruns
                .get()
                .wrapping_add(self.per_queue[1].overruns.get()),
            hardware_fifo_warnings: self.per_queue[0]
                .warnings
                .get()
                .wrapping_add(self.per_queue[1].warnings.get()),
        }
    }

    /// Wake-up events seen by the status handler.
    pub fn wakeups(&self) -> u32 {
        self.errors.wakeups.get()
    }

    /// Reads the controller's free-running time stamp counter, where software can
    /// ([`Hardware::timer_now`]: FlexCAN), so that time stamps stay exact across a quiet
    /// bus. The interrupt handlers read it whenever they widen a stamp, and the status
    /// handler on each interrupt and [`StatusIrq::poll_state`]: call this (any context)
    /// at intervals shorter than 65,536 bit times (131 ms at 500 kbit/s) when the bus
    /// may carry no frame for that long. Nothing to do without a readable counter (bxCAN):
    /// see `docs/architecture.md`, "Time stamps".
    pub fn refresh_timestamps(&self) {
        let Some(hw) = self.hardware() else {
            return;
        };
        critical_section::with(|cs| {
            if let Some(now) = hw.timer_now() {
                let c = self.clock.borrow(cs);
                let mut e = c.get();
                e.observe(now);
                c.set(e);
            }
        });
    }

    /// Widens the 16-bit stamp of a completion read from the hardware before this call
    /// (transmit interrupt side).
    #[inline]
    fn widen(&self, stamp: u16) -> Timestamp {
        self.widen_from(None, stamp)
    }

    /// Widens the 16-bit stamp of a frame just read from receive queue `queue` (its
    /// receive interrupt).
    #[inline]
    fn widen_received(&self, queue: usize, stamp: u16) -> Timestamp {
        self.widen_from(Some(queue), stamp)
    }

    #[inline]
    fn widen_from(&self, queue: Option<usize>, stamp: u16) -> Timestamp {
        let hw = self.hw();
        let pending = |q: usize| q < H::RX_QUEUES && hw.rx_pending(q);
        critical_section::with(|cs| {
            let c = self.clock.borrow(cs);
            let mut e = c.get();
            // The counter is read after the stamp, inside the section: every stamp
            // widened is at or before the reading, whichever context read it. Without a
            // readable counter, the queues' "frame pending" flags are read inside the
            // section too, so that they are current for the reference it leaves.
            let t = match hw.timer_now() {
                Some(now) => {
                    e.observe(now);
                    e.extend_before(stamp)
                }
                None => match queue {
                    Some(q) => e.extend_received(q, stamp, pending),
                    None => e.extend_sent(stamp, pending),
                },
            };
            c.set(e);
            t
        })
    }

    /// The receive rings as one buffer: `size` and `peak` are those of the rings the
    /// installed filters feed ([`Hardware::fed_rx_queues`]: bxCAN FIFO 0, FIFO 1 or
    /// both, as the plan assigns the banks; FlexCAN its one FIFO), added where both are
    /// fed, so that `size` frames arrive before an overflow; `count` and `overflows` are
    /// over every ring (a frame still waiting in a ring no longer fed is counted, and
    /// taken by `receive`). Each ring: [`State::rx_ring_stats`].
    pub fn rx_stats(&self) -> BufferStats {
        let all = ((1u16 << H::RX_QUEUES) - 1) as u8;
        let fed = self.hardware().map_or(all, |h| h.fed_rx_queues()) & all;
        let rings = [self.rx_ring_stats(0), self.rx_ring_stats(1)];
        let mut total = BufferStats::default();
        for (q, ring) in rings.into_iter().enumerate() {
            let Some(r) = ring else { continue };
            total.count += r.count;
            total.overflows += r.overflows;
            // A ring of no room (`RX1` = 0) holds nothing: its frames are overflows.
            if fed & (1 << q) != 0 && r.size > 0 {
                total.size += r.size;
                total.peak += r.peak;
            }
        }
        total
    }

    /// The figures of receive ring `queue` (0: the `RX` ring, bxCAN FIFO 0 or the
    /// FlexCAN Rx FIFO; 1: the `RX1` ring, bxCAN FIFO 1), whether the installed filters
    /// feed it or not; `None` for a queue the controller does not have.
    pub fn rx_ring_stats(&self, queue: usize) -> Option<BufferStats> {
        match queue {
            _ if queue >= H::RX_QUEUES => None,
            0 => Some(self.rx0.stats()),
            _ => Some(self.rx1.stats()),
        }
    }

    /// Transmit queue figures.
    pub fn tx_stats(&self) -> BufferStats {
        BufferStats {
            size: Q::CAPACITY,
            count: self.queue_len.load(Ordering::Relaxed) as usize,
            peak: self.queue_peak.load(Ordering::Relaxed) as usize,
            overflows: self.queue_overflows.get(),
        }
    }

    /// Sets both rings' peaks back to their counts.
    pub fn reset_peaks(&self) {
        self.rx0.reset_peak();
        self.rx1.reset_peak();
        self.queue_peak
            .store(self.queue_len.load(Ordering::Relaxed), Ordering::Relaxed);
    }

    /// The raw frame's 16-bit time stamp, when the feature set reads them
    /// ([`Features::TIMESTAMPS`]) and the hardware records one.
    #[inline(always)]
    fn raw_stamp(&self, raw: &H::Raw) -> Option<u16> {
        if Fe::TIMESTAMPS {
            self.hw().raw_timestamp(raw)
        } else {
            None
        }
    }

    #[inline]
    fn record(&self, mut done: Completion) {
        if !Fe::TIMESTAMPS {
            done.timestamp = None;
        } else if let Some(t) = done.timestamp {
            done.timestamp = Some(self.widen(t.counter()));
        }
        match done.outcome {
            TxOutcome::Sent => self.sent.inc(),
            TxOutcome::Failed => self.failed.inc(),
            TxOutcome::Aborted => self.aborted.inc(),
        }
        // With `DONE` = 0 completions are off: nothing is kept, nothing counted (the
        // branch is settled at compile time).
        if DONE != 0 {
            // SAFETY: completions are produced only inside the critical section
            // (transmit interrupt, transmit half's slow path), so producers never
            // overlap.
            let _ = unsafe { self.done.push(done) };
        }
        // The event the transmit handler wakes on (inside the critical section, as
        // every `record`).
        #[cfg(feature = "async")]
        self.tx_event.store(true, Ordering::Relaxed);
    }

    /// Whether a completion was recorded since the last call (cleared). Called inside
    /// the critical section, where `record` sets the flag: a load and a store suffice.
    /// Always `false` without the `async` feature (nothing waits).
    #[inline(always)]
    fn take_tx_event(&self) -> bool {
        #[cfg(feature = "async")]
        {
            let event = self.tx_event.load(Ordering::Relaxed);
            self.tx_event.store(false, Ordering::Relaxed);
            event
        }
        #[cfg(not(feature = "async"))]
        false
    }

    /// Moves `queue_len` one up (`up`) or down and returns the new length, with a load
    /// and a store instead of a read-modify-write: every change happens inside the
    /// driver's critical section (one writer at a time), and the transmit half's direct
    /// path only loads it. `store`: the ordering of the store (release where the
    /// direct path must see what came before).
    #[inline(always)]
    fn queue_len_step(&self, up: bool, store: Ordering) -> u32 {
        let len = self.queue_len.load(Ordering::Relaxed);
        let len = if up {
            len.wrapping_add(1)
        } else {
            len.wrapping_sub(1)
        };
        self.queue_len.store(len, store);
        len
    }

    /// The transmit interrupt's work, inside the critical section `cs`: settle ended
    /// mailboxes, put displaced frames back, refill free mailboxes from the queue.
    fn service_tx(&self, q: &mut Q) {
        let hw = self.hw();
        // SAFETY (every block below): the caller holds the critical section, the
        // transmit interrupt's context for `settle`/`load`/`displace`.
        if Self::QUIET_TX {
            unsafe { hw.acknowledge_ended() };
        } else {
            unsafe { self.settle_into(q) };
        }
        let mut displaced = false;
        while let Some(next) = q.peek() {
            match self.free_mailbox(&next.frame) {
                Ok(Some(m)) => {
                    let e = *next;
                    q.pop();
                    unsafe { hw.load(m, &e.frame, e.token) };
                    // Only now may the transmit half see an empty queue and take its
                    // direct path: a core running it beside this one (host threads)
                    // must not pick the mailbox being loaded here (release: the load's
                    // register writes come first).
                    self.queue_len_step(false, Ordering::Release);
                }
                Ok(None) => {
                    // The displaced frame comes back through `settle` while `next` still
                    // waits in the queue, so a displacement needs one free place: never
                    // displace into a full queue (the frame then waits for the next
                    // mailbox that ends; nothing accepted is dropped).
                    if displaced
                        || q.policy() != TxPolicy::Priority
                        || self.queue_len.load(Ordering::Relaxed) as usize >= Q::CAPACITY
                        || !unsafe { hw.displace(&next.frame) }
                    {
                        break;
                    }
                    // That place is kept from now on (counted in `queue_len`, so that the
                    // transmit half cannot take it). An abort of a pending mailbox ends at
                    // once: settle again so the frame takes the mailbox now; otherwise
                    // the abort's completion interrupt does it.
                    self.queue_len_step(true, Ordering::Relaxed);
                    displaced = true;
                    unsafe { self.settle_into(q) };
                }
                Err(_) => break,
            }
        }
        self.quiet_if_empty(q);
    }

    /// The controller's mailbox for `frame` in the request order this state keeps:
    /// [`Hardware::free_mailbox_quiet`] in the quiet mode (ends need no acknowledgement),
    /// else [`Hardware::free_mailbox`] (settled mailboxes only).
    #[inline(always)]
    fn free_mailbox(&self, frame: &Frame) -> Result<Option<u8>, Error> {
        if Self::QUIET_TX {
            self.hw().free_mailbox_quiet(frame)
        } else {
            self.hw().free_mailbox(frame)
        }
    }

    /// The quiet mode: with nothing left to refill, no transmit interrupt until a frame
    /// is queued again. Called inside the critical section (`q` is borrowed from it).
    #[inline(always)]
    fn quiet_if_empty(&self, q: &Q) {
        if Self::QUIET_TX && q.is_empty() {
            // SAFETY: inside the critical section, the transmit interrupt's context.
            unsafe { self.hw().set_tx_interrupt(false) };
        }
    }

    /// Settles ended mailboxes into the completion ring and the queue.
    ///
    /// # Safety
    /// Called inside the critical section (the transmit interrupt's context).
    unsafe fn settle_into(&self, q: &mut Q) {
        // SAFETY: the caller's contract.
        unsafe { self.hw().settle(|s| self.on_settled(q, s)) }
    }

    /// One settled mailbox (inlined into each of the backend's call sites, so that each
    /// handles the one variant it builds).
    #[inline(always)]
    fn on_settled(&self, q: &mut Q, s: Settled) {
        match s {
            Settled::Done(c) => self.record(c),
            Settled::Displaced(token, frame) => {
                // Room was reserved when the displacement was requested (and stays
                // counted in `queue_len`, now by the frame itself), so the push succeeds.
                // Were it refused, the frame would still get its one completion.
                if q.push(Queued { token, frame }).is_err() {
                    debug_assert!(false, "no room kept for a displaced frame");
                    self.queue_len_step(false, Ordering::Relaxed);
                    self.record(Completion {
                        token,
                        outcome: TxOutcome::Aborted,
                        cause: None,
                        timestamp: None,
                    });
                }
            }
            Settled::DoneDisplacing(c) => {
                self.queue_len_step(false, Ordering::Relaxed);
                self.record(c);
            }
        }
    }

    /// The consumer side of the receive rings: the oldest frame across both queues
    /// (by time stamp when the hardware records one, else queue 0 first), decoded.
    ///
    /// # Safety
    /// Called from the receive rings' one consumer context.
    pub(crate) unsafe fn receive_with(&self, map: &H::FilterMap) -> nb::Result<RxFrame, Error> {
        loop {
            // SAFETY: the caller is the rings' only consumer.
            let raw = unsafe { self.pop_raw() }.ok_or(nb::Error::WouldBlock)?;
            // SAFETY: the caller is the receive half's context.
            match unsafe { self.hw().decode(&raw.raw, map) } {
                Some(mut frame) => {
                    frame.timestamp = self
                        .raw_stamp(&raw.raw)
                        .map(|t| Timestamp::from_parts(Fe::Clock::wraps(raw.wraps), t));
                    return Ok(frame);
                }
                None => self.dropped.inc(),
            }
        }
    }

    /// # Safety
    /// Called from the receive rings' one consumer context.
    unsafe fn pop_raw(&self) -> Option<Stamped<H::Raw, Wraps<Fe>>> {
        // SAFETY: the caller is the rings' only consumer.
        unsafe {
            if RX1 == 0 {
                return self.rx0.pop();
            }
            match (self.rx0.peek(), self.rx1.peek()) {
                (Some(a), Some(b)) => {
                    let first = match (self.raw_stamp(&a.raw), self.raw_stamp(&b.raw)) {
                        (Some(ta), Some(tb)) => {
                            (Fe::Clock::wraps(a.wraps), ta) <= (Fe::Clock::wraps(b.wraps), tb)
                        }
                        _ => true,
                    };
                    if first {
                        self.rx0.pop()
                    } else {
                        self.rx1.pop()
                    }
                }
                (Some(_), None) => self.rx0.pop(),
                (None, Some(_)) => self.rx1.pop(),
                (None, None) => None,
            }
        }
    }

    /// Adds the frames the last filter switch discarded from the hardware FIFO to
    /// [`TrafficStats::rx_dropped`] (the receive half's context, the counter's writer).
    ///
    /// # Safety
    /// Called from the receive half's context.
    pub(crate) unsafe fn count_filter_switch_discards(&self) {
        if let Some(hw) = self.hardware() {
            // SAFETY: the caller's contract.
            self.dropped
                .add(unsafe { hw.take_filter_switch_discards() });
        }
    }

    /// # Safety
    /// Called from the state-change ring's one consumer context.
    pub(crate) unsafe fn pop_change(&self) -> Option<StateChange> {
        // SAFETY: the caller is the ring's only consumer.
        unsafe { self.changes.pop() }
    }

    /// Whether the controller is bus-off now (read when the status handler last saw
    /// bus-off: it may have recovered since). Out of line: the transmit path's rare case.
    #[cold]
    #[inline(never)]
    fn bus_off_now(&self) -> bool {
        self.hw().error_status().state == ErrorState::BusOff
    }

    fn note_queue_peak(&self, len: u32) {
        if len > self.queue_peak.load(Ordering::Relaxed) {
            self.queue_peak.store(len, Ordering::Relaxed);
        }
    }
}

/// The transmit half: send frames, take their completions, abort them.
///
/// ```
/// use twocan_core::mock::{block, MockHardware};
/// use twocan_core::split::AbortRequest;
/// use twocan_core::{FifoQueue, Frame, State, TxOutcome};
///
/// static CAN: State<MockHardware, 8, FifoQueue<4>> = State::new();
/// let mut p = CAN.split(MockHardware::new(1)).map_err(|(e, _)| e)?;
/// // One mailbox: the first frame goes straight in, the second waits in the queue.
/// let (fa, fb) = (Frame::standard(0x100, &[1])?, Frame::standard(0x101, &[2])?);
/// let a = block("a mailbox", || p.tx.try_send(&fa))?;
/// let b = block("room in the queue", || p.tx.try_send(&fb))?;
/// assert_eq!(p.tx.stats().count, 1);
/// // A queued frame can be taken back; its `Aborted` completion follows at once.
/// assert_eq!(p.tx.abort(b), AbortRequest::Dequeued);
/// let done = p.tx.take_completion().unwrap();
/// assert_eq!((done.token, done.outcome), (b, TxOutcome::Aborted));
///
/// CAN.hardware().unwrap().complete_all(); // the mock sends its mailbox
/// p.tx_irq.on_interrupt();
/// let done = p.tx.take_completion().unwrap();
/// assert_eq!((done.token, done.outcome), (a, TxOutcome::Sent));
/// assert_eq!(p.tx.take_completion(), None); // exactly one completion per token
/// assert_eq!(p.tx.abort(a), AbortRequest::NotFound);
/// # Ok::<(), twocan_core::Error>(())
/// ```
pub struct Tx<
    'a,
    H: Hardware,
    const RX: usize,
    Q: TxQueue,
    const RX1: usize,
    const DONE: usize,
    Fe: Features = Full,
> {
    pub(crate) s: &'a State<H, RX, Q, RX1, DONE, Fe>,
    pub(crate) next: u32,
}

/// What [`Tx::abort`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AbortRequest {
    /// The frame was still queued: it was removed; its `Aborted` completion is in the
    /// completion ring already (with one: `DONE` > 0).
    Dequeued,
    /// The frame is in a mailbox: its abort was requested; the completion (aborted, or
    /// sent if the abort came too late) follows (with a completion ring).
    Requested,
    /// Nothing was aborted: no frame with this token is queued or waiting in a mailbox
    /// now. That does not mean its completion was delivered: a frame whose mailbox
    /// ended (sent, or failed) but was not settled yet still gets its one completion
    /// when the transmit interrupt settles it, possibly after this call returns. A
    /// token never handed out is not found either.
    NotFound,
}

impl<
        'a,
        H: Hardware,
        const RX: usize,
        Q: TxQueue,
        const RX1: usize,
        const DONE: usize,
        Fe: Features,
    > Tx<'a, H, RX, Q, RX1, DONE, Fe>
{
    /// Accepts `frame` for transmission and returns its token; with a completion ring
    /// (`DONE` > 0) exactly one [`Completion`] with that token follows (with `DONE` = 0
    /// none: fire and forget).
    ///
    /// When nothing is queued and a mailbox is free, the frame goes straight into it
    /// (no lock). Otherwise it joins the queue (a short critical section, in which the
    /// transmit interrupt's refill also runs, so a mailbox freed meanwhile is used at
    /// once). `WouldBlock` when the queue is full (counted in [`Tx::stats`]). An error
    /// means the frame was **not** accepted: [`Error::BusOff`] while bus-off,
    /// [`Error::WrongMode`] when the controller cannot send in its mode.
    #[inline]
    pub fn try_send(&mut self, frame: &Frame) -> nb::Result<Token, Error> {
        let s = self.s;
        let hw = s.hw();
        if s.state.load(Ordering::Relaxed) == state_code(ErrorState::BusOff) && s.bus_off_now() {
            return Err(nb::Error::Other(Error::BusOff));
        }
        let token = Token(self.next);
        // Relaxed: on the direct path this half reads no memory that the transmit
        // interrupt writes, only the hardware's mailbox status (`free_mailbox`).
        if s.queue_len.load(Ordering::Relaxed) == 0 {
            match s.free_mailbox(frame) {
                Ok(Some(m)) => {
                    // SAFETY: the transmit half's direct path: the queue is empty and only
                    // this half fills it, so the interrupt's refill loads nothing and
                    // `m` (empty, and settled unless in the quiet mode, where the end of
                    // its last frame is not reported) is this call's alone.
                    unsafe { hw.load(m, frame, token) };
                    return Ok(self.accept(token));
                }
                Ok(None) => {}
                Err(e) => return Err(nb::Error::Other(e)),
            }
        }
        self.send_queued(frame, token)
    }

    /// The slow path of [`Tx::try_send`]: the frame joins the queue (in the critical
    /// section shared with the transmit interrupt). Out of line so that the direct path
    /// stays a short leaf.
    #[cold]
    #[inline(never)]
    fn send_queued(&mut self, frame: &Frame, token: Token) -> nb::Result<Token, Error> {
        let s = self.s;
        let hw = s.hw();
        critical_section::with(|cs| {
            // SAFETY: the queue is only touched inside a critical section.
            let q = unsafe { &mut *s.queue.borrow(cs).get() };
            let len = s.queue_len.load(Ordering::Relaxed);
            if len as usize >= Q::CAPACITY {
                // Make what progress the hardware allows (useful when polled with the
                // interrupt masked), then try once more.
                s.service_tx(q);
                if s.queue_len.load(Ordering::Relaxed) as usize >= Q::CAPACITY {
                    s.queue_overflows.inc();
                    s.queue_peak
                        .store(Q::CAPACITY as u32 + 1, Ordering::Relaxed);
                    return Err(nb::Error::WouldBlock);
                }
            }
            if let Err(e) = s.free_mailbox(frame) {
                return Err(nb::Error::Other(e));
            }
            if q.push(Queued {
                token,
                frame: *frame,
            })
            .is_err()
            {
                s.queue_overflows.inc();
                return Err(nb::Error::WouldBlock);
            }
            let len = s.queue_len_step(true, Ordering::Relaxed);
            s.note_queue_peak(len);
            if State::<H, RX, Q, RX1, DONE, Fe>::QUIET_TX {
                // SAFETY: inside the critical section. A frame waits: the interrupt
                // refills (`service_tx` turns it off again if the queue empties now).
                unsafe { hw.set_tx_interrupt(true) };
            }
            s.service_tx(q);
            Ok(self.accept(token))
        })
    }

    /// Loads `frame` into a free mailbox now, or `WouldBlock`: never queued. Unlike
    /// [`Tx::try_send`] it does not wait behind queued frames, so it may overtake them
    /// when it needs another kind of mailbox — ACAN's remote frames, which go straight
    /// to FlexCAN's remote-frame mailboxes while [`Tx::try_send`] loads one frame at a
    /// time ([`Hardware::free_mailbox_now`]). (On bxCAN all mailboxes are alike: it
    /// overtakes the queue whenever a mailbox is free.)
    pub fn try_send_now(&mut self, frame: &Frame) -> nb::Result<Token, Error> {
        let s = self.s;
        let hw = s.hw();
        if s.state.load(Ordering::Relaxed) == state_code(ErrorState::BusOff) && s.bus_off_now() {
            return Err(nb::Error::Other(Error::BusOff));
        }
        let token = Token(self.next);
        let free = || {
            if State::<H, RX, Q, RX1, DONE, Fe>::QUIET_TX {
                hw.free_mailbox_now_quiet(frame)
            } else {
                hw.free_mailbox_now(frame)
            }
        };
        let load = || match free() {
            Ok(Some(m)) => {
                // SAFETY: either the queue is empty (the direct path of `try_send`), or
                // the caller holds the critical section, which keeps the interrupt's
                // refill from taking `m` meanwhile.
                unsafe { hw.load(m, frame, token) };
                Ok(())
            }
            Ok(None) => Err(nb::Error::WouldBlock),
            Err(e) => Err(nb::Error::Other(e)),
        };
        let r = if s.queue_len.load(Ordering::Acquire) == 0 {
            load()
        } else {
            critical_section::with(|_| load())
        };
        r.map(|()| self.accept(token))
    }

    #[inline(always)]
    fn accept(&mut self, token: Token) -> Token {
        self.next = self.next.wrapping_add(1);
        self.s.queued.inc();
        token
    }

    /// The next completion, in the order the controller reported them.
    pub fn take_completion(&mut self) -> Option<Completion> {
        // SAFETY: the transmit half is the completion ring's only consumer.
        unsafe { self.s.done.pop() }
    }

    /// Aborts the frame of `token`, queued or in a mailbox. On FlexCAN, the abort of a
    /// frame in a mailbox while the module transmits is written when that transmission
    /// ends: the call waits for it, bounded ([`Hardware::prepare_abort`]).
    pub fn abort(&mut self, token: Token) -> AbortRequest {
        let s = self.s;
        s.hw().prepare_abort(Some(token));
        critical_section::with(|cs| {
            // SAFETY: the queue is only touched inside a critical section.
            let q = unsafe { &mut *s.queue.borrow(cs).get() };
            if q.remove(token) {
                s.queue_len_step(false, Ordering::Relaxed);
                s.record(Completion {
                    token,
                    outcome: TxOutcome::Aborted,
                    cause: None,
                    timestamp: None,
                });
                s.quiet_if_empty(q);
                AbortRequest::Dequeued
            } else {
                // SAFETY: inside the critical section, exclusive with the interrupt's
                // settle, as `request_abort` needs.
                if unsafe { s.hw().request_abort(token) } {
                    AbortRequest::Requested
                } else {
                    AbortRequest::NotFound
                }
            }
        })
    }

    /// Drops every queued frame (each gets an `Aborted` completion) and requests the
    /// abort of every mailbox (waiting as [`Tx::abort`] does). Returns the number of
    /// queued frames dropped.
    pub fn abort_all(&mut self) -> usize {
        let s = self.s;
        s.hw().prepare_abort(None);
        critical_section::with(|cs| {
            // SAFETY: the queue is only touched inside a critical section.
            let q = unsafe { &mut *s.queue.borrow(cs).get() };
            let mut dropped = 0;
            while let Some(e) = q.pop() {
                s.queue_len_step(false, Ordering::Relaxed);
                s.record(Completion {
                    token: e.token,
                    outcome: TxOutcome::Aborted,
                    cause: None,
                    timestamp: None,
                });
                dropped += 1;
            }
            s.quiet_if_empty(q);
            // SAFETY: inside the critical section, as `abort_all_mailboxes` needs.
            unsafe { s.hw().abort_all_mailboxes() };
            dropped
        })
    }

    /// Runs the transmit interrupt's work from here (for polling code with the transmit
    /// interrupt off).
    pub fn poll(&mut self) {
        let s = self.s;
        critical_section::with(|cs| {
            // SAFETY: the queue is only touched inside a critical section.
            s.service_tx(unsafe { &mut *s.queue.borrow(cs).get() })
        })
    }

    /// Transmit queue figures.
    pub fn stats(&self) -> BufferStats {
        self.s.tx_stats()
    }

    /// The token the next accepted frame will get.
    pub fn next_token(&self) -> Token {
        Token(self.next)
    }

    /// The shared state (statistics, the controller).
    pub fn state(&self) -> &'a State<H, RX, Q, RX1, DONE, Fe> {
        self.s
    }

    /// The controller.
    pub fn hardware(&self) -> &H {
        self.s.hw()
    }
}

/// The receive half: take frames with their user filter index, dispatch them, follow
/// the error state.
///
/// ```
/// use twocan_core::mock::{block, MockHardware};
/// use twocan_core::{ErrorState, FifoQueue, Filter, Frame, LastErrorCode, State};
///
/// static CAN: State<MockHardware, 8, FifoQueue<4>> = State::new();
/// let hw = MockHardware::new(3).with_filters(&[Filter::standard(0x100), Filter::extended(0x100)]);
/// let mut p = CAN.split(hw).map_err(|(e, _)| e)?;
/// assert!(matches!(p.rx.receive(), Err(nb::Error::WouldBlock))); // nothing yet
///
/// CAN.hardware().unwrap().deliver(Frame::extended(0x100, &[7])?);
/// CAN.hardware().unwrap().deliver(Frame::standard(0x100, &[8])?);
/// p.rx0_irq.on_interrupt();
/// assert_eq!(p.rx.available(), 2);
/// // Frames in arrival order, each with the index of the user's filter that took it.
/// let first = block("the first frame", || p.rx.receive())?;
/// assert_eq!((first.frame.data(), first.filter), (&[7][..], 1));
/// let second = block("the second frame", || p.rx.receive())?;
/// assert_eq!((second.frame.data(), second.filter), (&[8][..], 0));
///
/// // Error-state changes arrive through the status handler.
/// CAN.hardware().unwrap().set_status(ErrorState::Warning, 100, 0, LastErrorCode::BitDominant);
/// p.status_irq.on_interrupt();
/// let change = p.rx.take_state_change().unwrap();
/// assert_eq!((change.state, change.counters.tec), (ErrorState::Warning, 100));
/// # Ok::<(), twocan_core::Error>(())
/// ```
pub struct Rx<
    'a,
    H: Hardware,
    const RX: usize,
    Q: TxQueue,
    const RX1: usize,
    const DONE: usize,
    Fe: Features = Full,
> {
    pub(crate) s: &'a State<H, RX, Q, RX1, DONE, Fe>,
    pub(crate) map: H::FilterMap,
}

impl<
        'a,
        H: Hardware,
        const RX: usize,
        Q: TxQueue,
        const RX1: usize,
        const DONE: usize,
        Fe: Features,
    > Rx<'a, H, RX, Q, RX1, DONE, Fe>
{
    /// Takes the oldest received frame, decoded, with the index of the user's filter
    /// that accepted it and its time stamp. `WouldBlock` when none is waiting.
    #[inline]
    pub fn receive(&mut self) -> nb::Result<RxFrame, Error> {
        // SAFETY: the receive half is the receive rings' only consumer.
        unsafe { self.s.receive_with(&self.map) }
    }

    /// Frames waiting in the receive ring(s) (ACAN `available()`).
    pub fn available(&self) -> usize {
        self.s.rx0.len() + self.s.rx1.len()
    }

    /// Takes one frame and hands it to its filter's call-back (ACAN
    /// `dispatchReceivedMessage`). Returns whether a frame was taken.
    pub fn dispatch<Ctx, const N: usize>(
        &mut self,
        dispatcher: &mut Dispatcher<Ctx, N>,
        ctx: &mut Ctx,
    ) -> bool {
        match self.receive() {
            Ok(frame) => {
                dispatcher.dispatch(ctx, &frame);
                true
            }
            Err(_) => false,
        }
    }

    /// The next error-state change, in order, with the counters at the change.
    pub fn take_state_change(&mut self) -> Option<StateChange> {
        // SAFETY: the receive half is the state-change ring's only consumer.
        unsafe { self.s.pop_change() }
    }

    /// Installs a new compiled filter list, atomically: once it returns, no frame is
    /// reported with an index of the old list (frames the old list accepted are
    /// discarded from the hardware FIFO or dropped from the ring, and counted in
    /// [`TrafficStats::rx_dropped`] either way; see [`crate::hardware`]).
    pub fn set_filters(&mut self, filters: &H::Filters) -> Result<(), Error> {
        // SAFETY: the receive half is the context of `install_filters` (and of the
        // control methods, so no mode change runs meanwhile); `&mut self` keeps this
        // half's other calls (`decode`, a `ReceiveContext`) out while it runs.
        self.map = unsafe { self.s.hw().install_filters(filters)? };
        // SAFETY: as above, the receive half's context.
        unsafe { self.s.count_filter_switch_discards() };
        Ok(())
    }

    /// The controller seen from this half's context, for a backend's receive-side
    /// methods (FlexCAN's installed filter table): no filter switch runs while it is
    /// borrowed.
    pub fn receive_context(&mut self) -> crate::hardware::ReceiveContext<'_, H> {
        // SAFETY: the receive half, borrowed exclusively for the context's lifetime.
        unsafe { crate::hardware::ReceiveContext::new(self.s.hw()) }
    }

    /// Changes the operating mode. The receive half is the controller's control
    /// context: mode, timing, bus mode and recovery changes never race a filter switch
    /// or each other (see [`crate::hardware`]).
    pub fn set_mode(&mut self, mode: Mode) -> Result<(), Error> {
        // SAFETY: the control context (this half, `&mut self`).
        unsafe { self.s.hw().set_mode(mode) }
    }

    /// Starts bus-off recovery by software (refused with [`Error::WrongMode`] where
    /// recovery is automatic).
    pub fn recover(&mut self) -> Result<(), Error> {
        // SAFETY: the control context (this half, `&mut self`).
        unsafe { self.s.hw().recover() }
    }

    /// Stopped controller only: a new bit timing, the filters kept.
    pub fn set_timing(&mut self, timing: &crate::timing::Timing) -> Result<(), Error> {
        // SAFETY: the control context (this half, `&mut self`).
        unsafe { self.s.hw().set_timing(timing) }
    }

    /// Stopped controller only: the bus mode used from the next start, the filters kept.
    pub fn set_bus_mode(&mut self, mode: crate::capabilities::BusMode) -> Result<(), Error> {
        // SAFETY: the control context (this half, `&mut self`).
        unsafe { self.s.hw().set_bus_mode(mode) }
    }

    /// Receive ring figures ([`State::rx_stats`]).
    pub fn stats(&self) -> BufferStats {
        self.s.rx_stats()
    }

    /// The figures of one receive ring ([`State::rx_ring_stats`]).
    pub fn ring_stats(&self, queue: usize) -> Option<BufferStats> {
        self.s.rx_ring_stats(queue)
    }

    /// The shared state (statistics, the controller).
    pub fn state(&self) -> &'a State<H, RX, Q, RX1, DONE, Fe> {
        self.s
    }

    /// The controller.
    pub fn hardware(&self) -> &H {
        self.s.hw()
    }

    /// The map from hardware match index to user filter index in force.
    pub fn filter_map(&self) -> &H::FilterMap {
        &self.map
    }
}

/// The transmit interrupt handler.
///
/// Its [`TxIrq::on_interrupt`] runs in the transmit interrupt (bxCAN `CANx_TX`, FlexCAN
/// message-buffer line) or, on a host, wherever the bus is serviced.
///
/// ```
/// use twocan_core::mock::{block, MockHardware};
/// use twocan_core::{FifoQueue, Frame, State};
///
/// static CAN: State<MockHardware, 8, FifoQueue<4>> = State::new();
/// let mut p = CAN.split(MockHardware::new(1)).map_err(|(e, _)| e)?;
/// for id in [0x10, 0x11, 0x12] {
///     let f = Frame::standard(id, &[])?;
///     block("room to send", || p.tx.try_send(&f))?;
/// }
/// assert_eq!(p.tx.stats().count, 2); // one mailbox: two frames queued
/// for _ in 0..3 {
///     CAN.hardware().unwrap().complete(); // the mailbox's frame goes out
///     p.tx_irq.on_interrupt(); // settles it and refills the mailbox from the queue
/// }
/// assert_eq!(CAN.traffic().sent, 3);
/// let ids: Vec<u32> = CAN.hardware().unwrap().sent().iter().map(|f| f.raw_id()).collect();
/// assert_eq!(ids, [0x10, 0x11, 0x12]);
/// # Ok::<(), twocan_core::Error>(())
/// ```
pub struct TxIrq<
    'a,
    H: Hardware,
    const RX: usize,
    Q: TxQueue,
    const RX1: usize,
    const DONE: usize,
    Fe: Features = Full,
> {
    pub(crate) s: &'a State<H, RX, Q, RX1, DONE, Fe>,
}

impl<
        H: Hardware,
        const RX: usize,
        Q: TxQueue,
        const RX1: usize,
        const DONE: usize,
        Fe: Features,
    > TxIrq<'_, H, RX, Q, RX1, DONE, Fe>
{
    /// Settles ended mailboxes (completions in order, with their tokens) and refills
    /// free mailboxes from the queue, in one critical section. In the quiet transmit
    /// mode ([`State::QUIET_TX`]) it acknowledges the ended mailboxes without a report,
    /// refills, and turns itself off once the queue is empty.
    pub fn on_interrupt(&mut self) {
        let s = self.s;
        let completed = critical_section::with(|cs| {
            // SAFETY: the queue is only touched inside a critical section.
            s.service_tx(unsafe { &mut *s.queue.borrow(cs).get() });
            s.take_tx_event()
        });
        // Woken on the event (a completion recorded here, or since the last interrupt by
        // the transmit half's own slow path), never on a difference of the saturating
        // counters: those stop moving after 2^32 frames.
        #[cfg(feature = "async")]
        if completed {
            // Completions came, so mailboxes (and queue room) were freed.
            s.wakers.tx_done.wake();
            s.wakers.tx_room.wake();
        }
        #[cfg(not(feature = "async"))]
        let _ = completed;
    }
}

/// The receive interrupt handler of one hardware receive queue.
///
/// ```
/// use twocan_core::mock::MockHardware;
/// use twocan_core::{FifoQueue, Frame, State};
///
/// // A receive ring of 2 frames: the handler moves what the hardware holds, and a frame
/// // the full ring cannot take is counted, not lost silently.
/// static CAN: State<MockHardware, 2, FifoQueue<4>> = State::new();
/// let mut p = CAN.split(MockHardware::new(3)).map_err(|(e, _)| e)?;
/// assert_eq!(p.rx0_irq.queue(), 0);
/// for id in 1..=3 {
///     CAN.hardware().unwrap().deliver(Frame::standard(id, &[])?);
/// }
/// p.rx0_irq.on_interrupt();
/// assert_eq!(CAN.hardware().unwrap().fifo_len(), 0); // hardware queue released
/// assert_eq!(p.rx.available(), 2);
/// assert_eq!(CAN.rx_stats().overflows, 1);
/// # Ok::<(), twocan_core::Error>(())
/// ```
pub struct RxIrq<
    'a,
    H: Hardware,
    const RX: usize,
    Q: TxQueue,
    const RX1: usize,
    const DONE: usize,
    const QUEUE: usize,
    Fe: Features = Full,
> {
    pub(crate) s: &'a State<H, RX, Q, RX1, DONE, Fe>,
}

/// The receive interrupt handler of hardware queue 0 (bxCAN RX0 / FIFO 0, FlexCAN's Rx
/// FIFO on the ORed message-buffer line).
pub type Rx0Irq<'a, H, const RX: usize, Q, const RX1: usize, const DONE: usize, Fe = Full> =
    RxIrq<'a, H, RX, Q, RX1, DONE, 0, Fe>;

/// The receive interrupt handler of hardware queue 1 (bxCAN RX1 / FIFO 1; a FlexCAN
/// controller has no second queue: its handler finds nothing).
///
/// Each queue's handler has a type of its own, so that one cannot be put where the
/// other belongs (run from the other line's vector, it would leave that line's level
/// triggered cause set for ever):
///
/// ```compile_fail,E0308
/// use twocan_core::irq_cell::IrqCell;
/// use twocan_core::mock::MockHardware;
/// use twocan_core::split::Rx0Irq;
/// use twocan_core::{FifoQueue, State};
///
/// type Q = FifoQueue<4>;
/// static CAN: State<MockHardware, 8, Q, 8> = State::new();
/// static RX0: IrqCell<Rx0Irq<'static, MockHardware, 8, Q, 8, 8>> = IrqCell::new();
/// let p = CAN.split(MockHardware::new(3)).ok().unwrap();
/// let _ = RX0.put(p.rx1_irq); // queue 1's handler where queue 0's belongs: refused
/// ```
pub type Rx1Irq<'a, H, const RX: usize, Q, const RX1: usize, const DONE: usize, Fe = Full> =
    RxIrq<'a, H, RX, Q, RX1, DONE, 1, Fe>;

impl<
        H: Hardware,
        const RX: usize,
        Q: TxQueue,
        const RX1: usize,
        const DONE: usize,
        const QUEUE: usize,
        Fe: Features,
    > RxIrq<'_, H, RX, Q, RX1, DONE, QUEUE, Fe>
{
    /// Moves every frame of the hardware queue into its ring as raw words and releases
    /// the hardware; a full ring counts the frame as an overflow. No decoding here.
    #[inline]
    pub fn on_interrupt(&mut self) {
        const { assert!(QUEUE < 2, "a controller has at most two receive queues") };
        let s = self.s;
        // The queue number is a constant, so that the backend's register offsets fold
        // into the loop.
        // SAFETY (both): this handle (one per queue, made once by `split`, its type
        // naming its queue) is the only caller of `read_rx` for its queue and the only
        // producer of its ring.
        if QUEUE == 0 {
            unsafe { drain(s, 0, &s.rx0) }
        } else {
            unsafe { drain(s, 1, &s.rx1) }
        }
    }

    /// Which hardware queue this handler drains.
    pub const fn queue(&self) -> usize {
        QUEUE
    }
}

/// The receive handler's loop for hardware queue `q` into `ring`.
///
/// # Safety
/// Called from queue `q`'s receive interrupt handle only (the one caller of `read_rx`
/// for `q`, the one producer of `ring` and the one writer of queue `q`'s counters).
#[inline(always)]
unsafe fn drain<
    H: Hardware,
    const RX: usize,
    Q: TxQueue,
    const RX1: usize,
    const DONE: usize,
    Fe: Features,
    const N: usize,
>(
    s: &State<H, RX, Q, RX1, DONE, Fe>,
    q: usize,
    ring: &SpscRing<Stamped<H::Raw, Wraps<Fe>>, N>,
) {
    let hw = s.hw();
    let counts = &s.per_queue[q];
    let mut events = FifoEvents::default();
    let mut any = false;
    // SAFETY: the caller's contract.
    unsafe {
        while let Some(raw) = hw.read_rx(q, &mut events) {
            any = true;
            counts.received.inc();
            // Widened here, on the interrupt side: the counter's wraps are only known
            // while the frame is fresh.
            let wraps = match s.raw_stamp(&raw) {
                Some(t) => s.widen_received(q, t).wraps(),
                None => 0,
            };
            let _ = ring.push(Stamped {
                raw,
                wraps: Fe::Clock::keep(wraps),
            });
        }
    }
    if events != FifoEvents::default() {
        fifo_events(counts, events);
    }
    #[cfg(feature = "async")]
    if any {
        s.wakers.rx.wake();
    }
    let _ = any;
}

/// Counts a drain's rare FIFO events, out of the per-frame path.
#[cold]
#[inline(never)]
fn fifo_events<C>(counts: &QueueCounts<C>, events: FifoEvents) {
    if events.overrun {
        counts.overruns.inc();
    }
    if events.warning {
        counts.warnings.inc();
    }
}

/// The status (error, bus-off, wake-up) interrupt handler.
///
/// ```
/// use twocan_core::mock::MockHardware;
/// use twocan_core::{ErrorState, FifoQueue, LastErrorCode, State};
///
/// static CAN: State<MockHardware, 8, FifoQueue<4>> = State::new();
/// let mut p = CAN.split(MockHardware::new(3)).map_err(|(e, _)| e)?;
/// let hw = CAN.hardware().unwrap();
///
/// hw.set_status(ErrorState::Passive, 128, 0, LastErrorCode::Acknowledge);
/// p.status_irq.on_interrupt(); // counts the bus error, records the change
/// hw.set_status(ErrorState::BusOff, 256, 0, LastErrorCode::BitRecessive);
/// p.status_irq.on_interrupt();
/// assert_eq!(p.status_irq.last_state(), ErrorState::BusOff);
///
/// let stats = CAN.error_stats();
/// assert_eq!((stats.acknowledge, stats.bit, stats.bus_off), (1, 1, 1));
/// let states: Vec<ErrorState> =
///     core::iter::from_fn(|| p.rx.take_state_change()).map(|c| c.state).collect();
/// assert_eq!(states, [ErrorState::Passive, ErrorState::BusOff]);
/// # Ok::<(), twocan_core::Error>(())
/// ```
pub struct StatusIrq<
    'a,
    H: Hardware,
    const RX: usize,
    Q: TxQueue,
    const RX1: usize,
    const DONE: usize,
    Fe: Features = Full,
> {
    pub(crate) s: &'a State<H, RX, Q, RX1, DONE, Fe>,
    pub(crate) last: ErrorState,
}

/// Calls of `Hardware::take_status` per status interrupt at most (each after one that
/// reported an error).
const MAX_STATUS_ROUNDS: u32 = 4;

impl<
        H: Hardware,
        const RX: usize,
        Q: TxQueue,
        const RX1: usize,
        const DONE: usize,
        Fe: Features,
    > StatusIrq<'_, H, RX, Q, RX1, DONE, Fe>
{
    /// Reads and acknowledges the error and wake-up causes: counts the bus error by
    /// kind, records a state change (with the counters) when the state moved.
    pub fn on_interrupt(&mut self) {
        let s = self.s;
        // SAFETY: this handle is the only caller of `take_status`.
        let mut ev = unsafe { s.hw().take_status() };
        s.refresh_timestamps();
        let mut wakeup = ev.wakeup;
        // While a call reports an error, call again (bounded): a controller may hold an
        // error that one call could not report (FlexCAN: one raised between its read
        // of ESR1 and the write-back, see `Hardware::take_status`).
        let mut rounds = 0;
        while let Some(code) = ev.bus_error {
            s.errors.record(code);
            rounds += 1;
            if rounds == MAX_STATUS_ROUNDS {
                break;
            }
            // SAFETY: as above.
            ev = unsafe { s.hw().take_status() };
            wakeup |= ev.wakeup;
        }
        if wakeup {
            s.errors.wakeups.inc();
        }
        self.note(ev.status);
    }

    fn note(&mut self, now: ErrorStatus) {
        let s = self.s;
        if now.state != self.last {
            if now.state == ErrorState::BusOff {
                s.errors.bus_off.inc();
            }
            self.last = now.state;
            s.state.store(state_code(now.state), Ordering::Relaxed);
            s.state_changes.inc();
            // A full ring keeps the older changes; the ring counts this one as lost
            // (`TrafficStats::state_change_overflows`).
            // SAFETY: this handle is the state-change ring's only producer.
            let _ = unsafe {
                s.changes.push(StateChange {
                    state: now.state,
                    counters: now.counters,
                })
            };
            #[cfg(feature = "async")]
            s.wakers.state.wake();
        }
    }

    /// Reads the error state without an interrupt (controllers that recover from
    /// bus-off raise none) and records a change.
    pub fn poll_state(&mut self) {
        let now = self.s.hw().error_status();
        self.s.refresh_timestamps();
        self.note(now);
    }

    /// The state last recorded.
    pub fn last_state(&self) -> ErrorState {
        self.last
    }
}

// The handles need no `unsafe impl Send`: each is a shared reference to the state
// (`Send` exactly when the state is `Sync`, see above) plus data owned by its context.

/// Reads any context may make.
impl<
        H: Hardware,
        const RX: usize,
        Q: TxQueue,
        const RX1: usize,
        const DONE: usize,
        Fe: Features,
    > State<H, RX, Q, RX1, DONE, Fe>
{
    /// The controller's error status, read now.
    pub fn error_status(&self) -> Option<ErrorStatus> {
        self.hardware().map(|h| h.error_status())
    }

    /// What the controller can do, as configured now.
    pub fn capabilities(&self) -> Option<crate::capabilities::Capabilities> {
        self.hardware().map(|h| h.capabilities())
    }
}

/// What [`State::unsplit`] found still in the state and discarded (the controller is
/// about to be ended: ACAN's `end` drops its buffers the same way). Take what matters
/// before (`receive`, `take_completion`, `abort_all` then the transmit handler).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Leftovers {
    /// Frames accepted by `try_send` and still in the software queue: never loaded
    /// into a mailbox, they get no completion. (Frames in mailboxes are the
    /// controller's: ending it stops them.)
    pub queued: usize,
    /// Received frames not taken from the receive rings.
    pub received: usize,
    /// Completions not taken.
    pub completions: usize,
    /// Error-state changes not taken.
    pub state_changes: usize,
}

/// Why [`State::unsplit`] gave the handles back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum UnsplitError {
    /// A handle came from another state.
    Foreign,
    /// A reference from [`State::hardware`] is alive (in some context), or was being
    /// made at that very moment: drop it and try again.
    Leased,
}

impl core::fmt::Display for UnsplitError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            UnsplitError::Foreign => "a handle belongs to another state",
            UnsplitError::Leased => "a reference to the controller is alive",
        })
    }
}

impl core::error::Error for UnsplitError {}

/// The way back (issue 22 item 11).
impl<
        H: Hardware,
        const RX: usize,
        Q: TxQueue,
        const RX1: usize,
        const DONE: usize,
        Fe: Features,
    > State<H, RX, Q, RX1, DONE, Fe>
{
    /// Takes the controller back out of the state, given every handle [`State::split`]
    /// made: the halves, and the interrupt handlers taken back out of their vectors'
    /// cells (`IrqCell::take`) **after** the lines that run them were masked. With all
    /// six handles here, no context can reach the controller through a handle any
    /// more; a reference from [`State::hardware`] still alive refuses
    /// ([`UnsplitError::Leased`]). What the rings and the queue still hold is discarded
    /// and counted ([`Leftovers`]); the statistics stay. The state is empty again:
    /// [`State::split`] may store a controller anew (after `end` and `begin`, say).
    ///
    /// On error every handle comes back, untouched.
    #[allow(clippy::type_complexity, clippy::result_large_err)]
    pub fn unsplit<'a>(
        &'a self,
        parts: Parts<'a, H, RX, Q, RX1, DONE, Fe>,
    ) -> Result<(H, Leftovers), (UnsplitError, Parts<'a, H, RX, Q, RX1, DONE, Fe>)> {
        let ours = [
            parts.tx.s,
            parts.rx.s,
            parts.tx_irq.s,
            parts.rx0_irq.s,
            parts.rx1_irq.s,
            parts.status_irq.s,
        ]
        .iter()
        .all(|s| core::ptr::eq(*s, self));
        if !ours {
            return Err((UnsplitError::Foreign, parts));
        }
        // SAFETY: the six handles, the only users of `hw()` (`get_unchecked`), are
        // here and are dropped below without being used again; `get` is used only by
        // the one-struct driver, whose state is never split; references from
        // `hardware()` are leases, which `take_shared` counts.
        let hw = match unsafe { self.hw.take_shared() } {
            Ok(hw) => hw,
            // Not published: impossible with handles of this state (`split` made them
            // after publishing, and only `unsplit` empties the slot, consuming them).
            Err(false) => return Err((UnsplitError::Foreign, parts)),
            Err(true) => return Err((UnsplitError::Leased, parts)),
        };
        if Self::QUIET_TX {
            // Ends never acknowledged are acknowledged now (a driver split next with
            // completions must not report this one's frames), then the transmit
            // interrupt goes back as configured. SAFETY: every handle is here, so no
            // other context runs the driver; the critical section keeps the interrupt's
            // own handler out.
            critical_section::with(|_| unsafe {
                hw.acknowledge_ended();
                hw.set_tx_interrupt(true);
            });
        }
        let mut left = Leftovers::default();
        // SAFETY: the consumer handles of the rings (`Rx`, `Tx`) and the producer
        // handles (the interrupt handlers, `Tx`'s slow path inside the critical
        // section) are all here: no other context pops or pushes.
        unsafe {
            while self.rx0.pop().is_some() {
                left.received += 1;
            }
            while self.rx1.pop().is_some() {
                left.received += 1;
            }
            while self.done.pop().is_some() {
                left.completions += 1;
            }
            while self.changes.pop().is_some() {
                left.state_changes += 1;
            }
        }
        critical_section::with(|cs| {
            // SAFETY: the queue is only touched inside a critical section.
            let queue = unsafe { &mut *self.queue.borrow(cs).get() };
            while queue.pop().is_some() {
                left.queued += 1;
            }
        });
        self.queue_len.store(0, Ordering::Relaxed);
        self.state.store(STATE_UNKNOWN, Ordering::Relaxed);
        drop(parts);
        Ok((hw, left))
    }
}

#[cfg(all(test, feature = "mock", feature = "async"))]
mod tests {
    use core::future::Future;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Arc;
    use std::task::{Context, Poll, Wake, Waker};

    use super::State;
    use crate::mock::MockHardware;
    use crate::{FifoQueue, Frame, TxOutcome};

    /// Counts its wake-ups.
    struct Count(AtomicUsize);
    impl Wake for Count {
        fn wake(self: Arc<Self>) {
            self.0.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// Issue 21: the footprint accounts for every byte of the state, and a feature set
    /// without time stamps keeps no clock and no wraps per receive ring slot.
    #[test]
    fn the_footprint_accounts_for_the_state_and_lean_keeps_no_clock() {
        use core::mem::size_of;

        use crate::{Full, Lean};

        type L = State<MockHardware, 8, FifoQueue<4>, 2, 0, Lean>;
        type F = State<MockHardware, 8, FifoQueue<4>, 2, 8, Full>;
        for fp in [L::FOOTPRINT, F::FOOTPRINT] {
            let parts = fp.controller
                + fp.slots()
                + fp.ring_bookkeeping
                + fp.queue_bookkeeping
                + fp.clock
                + fp.statistics
                + fp.errors
                + fp.wakers;
            assert_eq!(parts + fp.padding, fp.total, "{fp:?}");
            assert!(fp.padding < 16, "{fp:?}");
            assert_eq!(fp.transmit_slots, 4 * size_of::<super::Queued>());
        }
        let (lean, full) = (L::FOOTPRINT, F::FOOTPRINT);
        assert_eq!(lean.total, size_of::<L>());
        assert_eq!(lean.receive_slots, 10 * size_of::<Frame>());
        assert!(
            full.receive_slots >= 10 * (size_of::<Frame>() + 4),
            "{full:?}"
        );
        assert_eq!((lean.clock, lean.statistics), (0, 0));
        assert_eq!(full.clock, size_of::<crate::timestamp::Extender>());
        assert_eq!(full.statistics, 7 * 4);
        assert_eq!(lean.completion_slots, 0);
        assert_eq!(full.completion_slots, 8 * size_of::<crate::Completion>());
        assert_eq!(lean.errors, full.errors);
    }

    /// Item 7 of issue 26: the transmit handler woke the waiting task only when
    /// `sent + failed + aborted` changed, so after the saturating counters reached
    /// `u32::MAX` (about 2^32 frames) nothing was woken any more (and the sum itself
    /// overflowed). It wakes on the event: a completion recorded.
    #[test]
    fn a_saturated_sent_counter_still_wakes_the_waiting_task() {
        let state: State<MockHardware, 8, FifoQueue<4>> = State::new();
        let mut p = state.split(MockHardware::new(1)).ok().unwrap();
        state.sent.add(u32::MAX);
        let count = Arc::new(Count(AtomicUsize::new(0)));
        let waker = Waker::from(count.clone());
        let mut cx = Context::from_waker(&waker);

        let token = p.tx.try_send(&Frame::standard(0x10, &[]).unwrap()).unwrap();
        let mut done = core::pin::pin!(p.tx.completion());
        assert!(done.as_mut().poll(&mut cx).is_pending());
        state.hardware().unwrap().complete_all();
        p.tx_irq.on_interrupt();
        assert_eq!(
            count.0.load(Ordering::Relaxed),
            1,
            "the waiting task was not woken"
        );
        match done.as_mut().poll(&mut cx) {
            Poll::Ready(c) => assert_eq!((c.token, c.outcome), (token, TxOutcome::Sent)),
            Poll::Pending => panic!("woken without a completion"),
        }
        assert_eq!(state.traffic().sent, 0, "the counter wraps");
    }
}

#[cfg(all(test, feature = "mock"))]
mod in_place_tests {
    use super::State;
    use crate::mock::MockHardware;
    use crate::{Error, FifoQueue, Frame, TxOutcome, TxPolicy};

    /// `split_with` builds the controller in the state's slot, publishes it once, and
    /// leaves the state unsplit when the closure fails, returns another controller, or
    /// the transmit order is not the queue's.
    #[test]
    fn split_with_builds_in_place_once() {
        let state: State<MockHardware, 8, FifoQueue<4>> = State::new();
        assert_eq!(
            state.split_with(|_| Err(Error::Timeout)).err(),
            Some(Error::Timeout)
        );
        assert!(state.hardware().is_none());
        let other_ptr = Box::into_raw(Box::new(MockHardware::new(1)));
        // SAFETY: a fresh box, not freed before the end of the test; this is the only
        // reference made from it.
        let other: &'static mut MockHardware = unsafe { &mut *other_ptr };
        assert_eq!(
            state.split_with(move |_| Ok(other)).err(),
            Some(Error::InvalidArgument),
            "a controller outside the slot is refused"
        );
        // SAFETY: `other_ptr` came from `Box::into_raw` above; the refused `&mut` was
        // dropped by `split_with`, nothing refers to the box any more.
        drop(unsafe { Box::from_raw(other_ptr) });
        assert_eq!(
            state
                .split_with(|slot| Ok(
                    slot.write(MockHardware::new(1).with_policy(TxPolicy::Priority))
                ))
                .err(),
            Some(Error::InvalidArgument),
            "a transmit order other than the queue's is refused"
        );
        assert!(state.hardware().is_none());
        let mut p = state
            .split_with(|slot| Ok(slot.write(MockHardware::new(2))))
            .ok()
            .unwrap();
        assert!(state.hardware().is_some());
        assert_eq!(
            state
                .split_with(|slot| Ok(slot.write(MockHardware::new(2))))
                .err(),
            Some(Error::WrongMode)
        );
        let token =
            p.tx.try_send(&Frame::standard(0x10, &[1]).unwrap())
                .unwrap();
        state.hardware().unwrap().complete_all();
        p.tx_irq.on_interrupt();
        let done = p.tx.take_completion().unwrap();
        assert_eq!((done.token, done.outcome), (token, TxOutcome::Sent));
    }

    /// The lean feature set moves the same frames with the same tokens, counts no
    /// traffic and takes no room for it.
    #[test]
    fn lean_moves_frames_and_counts_nothing() {
        use crate::{Full, Lean};
        type LeanState = State<MockHardware, 8, FifoQueue<4>, 0, 0, Lean>;
        type FullState = State<MockHardware, 8, FifoQueue<4>, 0, 0, Full>;
        assert!(core::mem::size_of::<LeanState>() + 7 * 4 <= core::mem::size_of::<FullState>());
        let state: LeanState = State::new();
        let mut p = state
            .split_with(|slot| Ok(slot.write(MockHardware::new(3).with_loopback(true))))
            .ok()
            .unwrap();
        let frame = Frame::standard(0x321, &[1, 2, 3]).unwrap();
        p.tx.try_send(&frame).unwrap();
        state.hardware().unwrap().complete_all();
        p.tx_irq.on_interrupt();
        p.rx0_irq.on_interrupt();
        let rx = p.rx.receive().unwrap();
        assert_eq!(rx.frame, frame);
        assert_eq!(rx.timestamp, None);
        assert!(p.tx.take_completion().is_none(), "no completion ring");
        let t = state.traffic();
        assert_eq!((t.queued, t.sent, t.received), (0, 0, 0));
    }
}
