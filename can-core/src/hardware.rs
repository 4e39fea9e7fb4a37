//! The seam between the portable split driver ([`crate::split`]) and a controller
//! backend, by execution context.
//!
//! A backend implements [`Hardware`] on one value that every half of the driver shares
//! by reference (it is `Sync`). Each method says which context calls it; the backend
//! guarantees that calls from different contexts touch disjoint registers, or only
//! write-1-to-clear bits of a shared status register, so they never need a lock.
//!
//! **The types say who may call what.** Every method that belongs to one context is
//! `unsafe`: only the driver's handle for that context calls it, and the handle exists
//! once. Every *safe* method — of this trait and of a backend's own type — may be called
//! from any context at any time, and [`crate::State::hardware`], `Tx::hardware` and
//! `Rx::hardware` hand out `&H` for those only. A backend method that needs the receive
//! half's context (FlexCAN's copy of the installed filter table) takes a
//! [`ReceiveContext`], which only the receive half (and the one-struct driver, with
//! `&mut self`) can make.
//!
//! So a context that holds only `&H` cannot change the mode under a filter switch:
//!
//! ```compile_fail,E0133
//! use twocan_core::mock::MockHardware;
//! use twocan_core::{FifoQueue, Hardware, Mode, State};
//!
//! static CAN: State<MockHardware, 8, FifoQueue<4>> = State::new();
//! let _p = CAN.split(MockHardware::new(3)).ok().unwrap();
//! // e.g. a timer interrupt: the control methods are the receive half's.
//! let _ = CAN.hardware().unwrap().set_mode(Mode::Stopped);
//! ```
//!
//! | context | who runs it | methods |
//! |---|---|---|
//! | transmit half | `Tx` (thread/task) | [`Hardware::load`] (queue empty), [`Hardware::request_abort`], [`Hardware::abort_all_mailboxes`] (the last two inside the critical section) |
//! | transmit interrupt | `TxIrq`, and `Tx`'s slow path, inside the driver's one critical section | [`Hardware::settle`], [`Hardware::load`], [`Hardware::displace`] |
//! | receive interrupt of queue `q` | `RxIrq<.., q>` | [`Hardware::read_rx`] |
//! | receive half | `Rx` (thread/task) | [`Hardware::decode`], [`Hardware::install_filters`], [`Hardware::take_filter_switch_discards`], [`Hardware::filter_map`]; a backend's [`ReceiveContext`] methods |
//! | control | `Rx` too (the receive half is the controller's one control context, so that configuration never races a filter switch), or the one-struct driver | [`Hardware::set_mode`], [`Hardware::recover`], [`Hardware::set_timing`], [`Hardware::set_bus_mode`] |
//! | status interrupt | `StatusIrq` | [`Hardware::take_status`] |
//! | any (safe, reads or self-contained) | every handle, [`crate::State`], `&H` | [`Hardware::free_mailbox`], [`Hardware::free_mailbox_now`], [`Hardware::free_mailbox_quiet`], [`Hardware::free_mailbox_now_quiet`], [`Hardware::tx_policy`], [`Hardware::mailbox_count`], [`Hardware::mailbox_state`], [`Hardware::error_status`], [`Hardware::on_bus`], [`Hardware::raw_timestamp`], [`Hardware::timer_now`], [`Hardware::rx_pending`], [`Hardware::capabilities`], [`Hardware::bus_mode`], [`Hardware::bus_off_recovery`] |
//!
//! # Portable semantics every backend keeps
//!
//! - **Filters.** An empty compiled list accepts no frame; accepting every frame is the
//!   explicit filter [`crate::Filter::pass_all`]. [`Hardware::install_filters`] replaces
//!   the list atomically for the receive half: once it returns, [`Hardware::decode`]
//!   reports no frame with an index of the old list: frames the old list accepted that
//!   are still in the hardware FIFO are discarded while the controller is switched (off
//!   the bus for it) and reported by [`Hardware::take_filter_switch_discards`], and
//!   those already in the driver's ring are dropped when taken (`None` from `decode`);
//!   both are counted in [`crate::TrafficStats::rx_dropped`].
//! - **Stop, change, start.** With the controller stopped ([`Mode::Stopped`]),
//!   [`Hardware::set_timing`] and [`Hardware::set_bus_mode`] change the bit timing and the
//!   bus mode; the installed filters and their user indices stay. Either is refused with
//!   [`Error::WrongMode`] while the controller is on the bus.
//! - **Bus-off recovery.** [`BusOffRecovery::Automatic`]: the controller leaves bus-off
//!   after 128 × 11 recessive bits by itself and [`Hardware::recover`] is refused with
//!   [`Error::WrongMode`]. [`BusOffRecovery::Manual`]: the controller stays bus-off until
//!   [`Hardware::recover`] (which succeeds without effect when not bus-off), then leaves
//!   it after the 128 × 11 recessive bits the hardware requires.

use crate::capabilities::{BusMode, BusOffRecovery, Capabilities};
use crate::controller::{ErrorStatus, Mode};
use crate::error::{Error, LastErrorCode};
use crate::frame::{Frame, RxFrame};
use crate::mailbox::{MailboxId, MailboxState, TxOutcome, TxPolicy};
use crate::timestamp::Timestamp;
use crate::timing::Timing;

/// Identifies one frame accepted by [`crate::split::Tx::try_send`]: its sequence number
/// (wrapping at `u32::MAX`), in acceptance order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Token(pub u32);

/// How one accepted frame ended, delivered in order to the transmit half.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Completion {
    /// The frame's token.
    pub token: Token,
    /// Sent, failed (one-shot), or aborted.
    pub outcome: TxOutcome,
    /// Why a one-shot transmission failed, where the hardware says.
    pub cause: Option<TxFailure>,
    /// When the frame was sent, where the hardware records it (`None` for a failed or
    /// aborted frame, and on bxCAN without TTCM): the counter at the frame's start,
    /// extended by the driver on the interrupt side ([`crate::timestamp`]). A backend's
    /// [`Hardware::settle`] fills the hardware's 16-bit value
    /// ([`Timestamp::from_parts`] with 0 wraps); the driver widens it before the
    /// completion is delivered.
    pub timestamp: Option<Timestamp>,
}

/// Why a transmission failed without retry (one-shot mode).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TxFailure {
    /// Arbitration lost (bxCAN `ALSTx`).
    ArbitrationLost,
    /// A transmit error (bxCAN `TERRx`).
    Error,
}

/// What [`Hardware::settle`] found in one mailbox.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Settled {
    /// The mailbox's frame ended: report it.
    Done(Completion),
    /// The mailbox was emptied to make room for a higher-priority frame
    /// ([`Hardware::displace`]): queue this frame again, under its token.
    Displaced(Token, Frame),
    /// A mailbox whose displacement was requested ended otherwise (sent before the
    /// abort took effect, or aborted at the application's request): report it, and the
    /// room kept for the displaced frame is free again.
    DoneDisplacing(Completion),
}

/// Puts `ended` — mailboxes that ended between two transmit interrupts, each with its
/// token — in token (acceptance) order, across the tokens' wrap: the order in which
/// [`Hardware::settle`] reports them. An insertion sort: at most a handful of entries,
/// and no generic sort linked into firmware.
pub fn sort_by_token<T>(ended: &mut [(u32, T)]) {
    let Some(first) = ended.first() else {
        return;
    };
    // The oldest token: the one no other is before (wrapping comparison).
    let base = ended.iter().fold(first.0, |oldest, e| {
        if (e.0.wrapping_sub(oldest) as i32) < 0 {
            e.0
        } else {
            oldest
        }
    });
    for i in 1..ended.len() {
        let mut j = i;
        while j > 0 && ended[j].0.wrapping_sub(base) < ended[j - 1].0.wrapping_sub(base) {
            ended.swap(j, j - 1);
            j -= 1;
        }
    }
}

/// The controller as the receive half's context sees it: made only by
/// `twocan_core::split::Rx::receive_context` and `Driver::receive_context`, each from an
/// exclusive borrow (`&mut`) of the one receive half, so holding one proves that no
/// filter switch ([`Hardware::install_filters`]) runs meanwhile. A backend offers its
/// receive-side methods (those that read what a filter switch writes) on it.
///
/// ```compile_fail
/// // Not made outside the driver.
/// let cx = twocan_core::hardware::ReceiveContext { hw: &() };
/// ```
#[derive(Debug)]
pub struct ReceiveContext<'a, H> {
    hw: &'a H,
}

impl<'a, H> ReceiveContext<'a, H> {
    /// # Safety
    /// The caller is the receive half's context and stays so while the result lives
    /// (it holds the one receive half borrowed exclusively).
    pub(crate) unsafe fn new(hw: &'a H) -> Self {
        ReceiveContext { hw }
    }

    /// The controller (its any-context methods).
    pub fn hardware(&self) -> &'a H {
        self.hw
    }
}

/// What the status interrupt found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StatusEvents {
    /// Bus errors latched, by code (each reported error counted once).
    pub bus_error: Option<LastErrorCode>,
    /// The error status now.
    pub status: ErrorStatus,
    /// The controller woke up from sleep.
    pub wakeup: bool,
}

/// A CAN controller as the split driver uses it. See the [module docs](self) for who
/// calls what.
///
/// # Safety
/// Implementations promise the table of the [module docs](self): calls made from
/// different contexts as listed there may overlap in time (an interrupt preempting the
/// thread, or two host threads) and must stay correct. The methods marked `unsafe` may
/// rely on their context being exclusive, as their `# Safety` sections say.
pub unsafe trait Hardware {
    /// One received frame as the receive interrupt copies it out of the hardware (raw
    /// register words and the hardware match index); decoded on the thread side.
    type Raw: Copy + Send;
    /// The thread side's map from hardware match index to the user's filter index, kept
    /// by the receive half (`()` for a backend that keeps its map in the controller,
    /// read only from the receive half's context).
    type FilterMap: Send;
    /// A compiled filter list for [`Hardware::install_filters`].
    type Filters;
    /// Number of hardware receive queues (1 or 2: bxCAN FIFO 0 and FIFO 1), each with
    /// its own receive line and ring.
    const RX_QUEUES: usize = 1;

    /// Transmit order of the loaded mailboxes (and so of the driver's queue).
    fn tx_policy(&self) -> TxPolicy;

    /// A mailbox that is empty and settled (its last completion taken by
    /// [`Hardware::settle`]) and may carry `frame` **in the transmit order**: loaded
    /// there, `frame` leaves after every frame loaded before it that the order puts
    /// first (request order: all of them; identifier priority: those of higher or
    /// equal priority). `None` when no mailbox allows that now. Reads the status
    /// register once. `Err` when the controller cannot send now or ever in its mode
    /// (listen-only, sleep): the frame is then not accepted.
    fn free_mailbox(&self, frame: &Frame) -> Result<Option<u8>, Error>;

    /// A mailbox for [`crate::split::Tx::try_send_now`], which may overtake frames
    /// loaded or queued before it: any empty and settled mailbox that may carry `frame`
    /// (FlexCAN: any free remote-frame mailbox, ACAN's path). The default is
    /// [`Hardware::free_mailbox`].
    fn free_mailbox_now(&self, frame: &Frame) -> Result<Option<u8>, Error> {
        self.free_mailbox(frame)
    }

    /// Whether the controller supports the quiet transmit mode of a driver with no
    /// completions to report (`DONE` = 0, [`crate::Lean`], a request-order queue): its
    /// transmit interrupt enabled only while frames are queued
    /// ([`Hardware::set_tx_interrupt`]), ended mailboxes acknowledged wholesale
    /// ([`Hardware::acknowledge_ended`]) and reloaded without it
    /// ([`Hardware::free_mailbox_quiet`]). `false` by default: the driver then runs as
    /// with completions.
    const QUIET_TX: bool = false;

    /// Quiet mode ([`Hardware::QUIET_TX`], request order): an empty mailbox for
    /// `frame`, whether or not its last end was acknowledged (the outcome is not
    /// reported), **in the transmit order**, as [`Hardware::free_mailbox`]. In the quiet
    /// mode it replaces [`Hardware::free_mailbox`] (the direct path of
    /// [`crate::split::Tx::try_send`], the queue's refill). The default is
    /// [`Hardware::free_mailbox`].
    fn free_mailbox_quiet(&self, frame: &Frame) -> Result<Option<u8>, Error> {
        self.free_mailbox(frame)
    }

    /// Quiet mode: the mailbox for [`crate::split::Tx::try_send_now`], which may overtake
    /// frames loaded or queued before it, whether or not its last end was acknowledged.
    /// It replaces [`Hardware::free_mailbox_now`], so a backend whose
    /// `free_mailbox_now` differs from its `free_mailbox` keeps that difference here
    /// (FlexCAN: a remote frame takes any free remote-frame mailbox whatever else is
    /// loaded). The default is [`Hardware::free_mailbox_quiet`] (bxCAN: in request order
    /// every mailbox leaves in the order of its request, so any empty one will do).
    fn free_mailbox_now_quiet(&self, frame: &Frame) -> Result<Option<u8>, Error> {
        self.free_mailbox_quiet(frame)
    }

    /// Quiet mode: acknowledges every ended mailbox without reporting it. The default
    /// settles them and drops the reports.
    ///
    /// # Safety
    /// As for [`Hardware::settle`].
    unsafe fn acknowledge_ended(&self) {
        // SAFETY: the caller's contract is `settle`'s.
        unsafe { self.settle(|_| {}) }
    }

    /// Quiet mode: the transmit interrupt on (frames are queued) or off, as far as the
    /// configuration enables it. The default does nothing (the interrupt stays as
    /// configured).
    ///
    /// # Safety
    /// Called inside the driver's critical section (the transmit interrupt's context).
    unsafe fn set_tx_interrupt(&self, on: bool) {
        let _ = on;
    }

    /// Loads `frame` into `mailbox` (returned by [`Hardware::free_mailbox`],
    /// [`Hardware::free_mailbox_now`] or, in the quiet mode,
    /// [`Hardware::free_mailbox_quiet`] or [`Hardware::free_mailbox_now_quiet`]; the
    /// value is the backend's, passed back unchanged), remembers
    /// `token` for its completion, and requests transmission.
    ///
    /// # Safety
    /// Called from this method's one context only (see the [module docs](self)).
    unsafe fn load(&self, mailbox: u8, frame: &Frame, token: Token);

    /// Transmit interrupt: acknowledges every ended mailbox and reports it to `f`.
    ///
    /// # Safety
    /// Called from this method's one context only (see the [module docs](self)).
    unsafe fn settle<F: FnMut(Settled)>(&self, f: F);

    /// Transmit interrupt, [`TxPolicy::Priority`] only: when every mailbox is busy and
    /// `frame` beats the lowest-priority pending one, requests that mailbox's abort so
    /// `frame` can take it; the displaced frame comes back through
    /// [`Settled::Displaced`]. Returns whether an abort was requested.
    ///
    /// # Safety
    /// Called from this method's one context only (see the [module docs](self)).
    unsafe fn displace(&self, frame: &Frame) -> bool {
        let _ = frame;
        false
    }

    /// Number of transmit mailboxes.
    fn mailbox_count(&self) -> u8;

    /// State of one transmit mailbox, read now (any context; an index beyond the
    /// mailboxes reads [`MailboxState::Empty`]).
    fn mailbox_state(&self, mailbox: MailboxId) -> MailboxState;

    /// Transmit half, before [`Hardware::request_abort`] (`token`) or
    /// [`Hardware::abort_all_mailboxes`] (`None`) and outside the critical section they
    /// run in: waits, bounded, until the abort request cannot race the end of a
    /// transmission (FlexCAN: while the module transmits, see its `request_abort`). The
    /// default does nothing.
    fn prepare_abort(&self, token: Option<Token>) {
        let _ = token;
    }

    /// Transmit half: requests the abort of the mailbox holding `token`, if one does.
    /// Returns whether it did; the outcome arrives through [`Hardware::settle`].
    ///
    /// # Safety
    /// Called from this method's one context only (see the [module docs](self)).
    unsafe fn request_abort(&self, token: Token) -> bool;

    /// Transmit half: requests the abort of every loaded mailbox.
    ///
    /// # Safety
    /// Called from this method's one context only (see the [module docs](self)).
    unsafe fn abort_all_mailboxes(&self);

    /// Receive interrupt of queue `queue`: copies the head of that hardware FIFO out and
    /// releases it. The FIFO's overrun and warning flags, when raised, are acknowledged
    /// and recorded in `events` (left as they are otherwise: the caller accumulates them
    /// over a drain).
    ///
    /// # Safety
    /// Called from this method's one context only (see the [module docs](self)).
    unsafe fn read_rx(&self, queue: usize, events: &mut FifoEvents) -> Option<Self::Raw>;

    /// Receive half: the frame, its user filter index and time stamp. `None` when the
    /// frame must be dropped (the filter map has no user filter for it: e.g. the extra
    /// identifiers of a superset filter plan).
    ///
    /// # Safety
    /// Called from the receive half's context only (a backend may keep its filter map
    /// in the controller, written by [`Hardware::install_filters`] in that context).
    unsafe fn decode(&self, raw: &Self::Raw, map: &Self::FilterMap) -> Option<RxFrame>;

    /// The 16-bit receive time stamp of a raw frame, if the hardware records one. The
    /// receive interrupt widens it ([`crate::timestamp`]) and the driver reports it in
    /// [`RxFrame::timestamp`] (whatever [`Hardware::decode`] put there is replaced); it
    /// also keeps arrival order across several receive queues. Any context.
    fn raw_timestamp(&self, raw: &Self::Raw) -> Option<u16> {
        let _ = raw;
        None
    }

    /// Whether hardware receive queue `queue` holds a frame its receive handler has not
    /// read yet, read now. Any context (a read without side effects: the driver reads it
    /// from the other queue's receive interrupt and the transmit interrupt, inside its
    /// critical section, when it widens a time stamp without a readable counter, so
    /// that frames of several queues keep their bus order after a quiet bus; see
    /// [`crate::timestamp::Extender::extend_received`]). The default, `true`, means
    /// "unknown"; a controller whose counter software can read
    /// ([`Hardware::timer_now`]) never needs it.
    fn rx_pending(&self, queue: usize) -> bool {
        let _ = queue;
        true
    }

    /// The free-running time stamp counter read now, where software can read it
    /// (FlexCAN `TIMER`; `None` on bxCAN, whose TTCM counter is internal, and whenever
    /// the counter cannot be read). The driver reads it inside its critical section,
    /// after the stamps it widens were read, and at [`crate::State::refresh_timestamps`].
    /// Any context (a read without side effects on the frames).
    fn timer_now(&self) -> Option<u16> {
        None
    }

    /// Receive half: writes `filters` into the hardware and returns their map.
    ///
    /// # Safety
    /// Called from this method's one context only (see the [module docs](self)).
    unsafe fn install_filters(&self, filters: &Self::Filters) -> Result<Self::FilterMap, Error>;

    /// Receive half: the frames the last [`Hardware::install_filters`] calls discarded
    /// from the hardware FIFO during the switch (accepted by the old list, never read),
    /// since the previous call; the call resets the count. The driver adds them to
    /// [`crate::TrafficStats::rx_dropped`], so that a filter switch loses no frame
    /// silently. The default, 0, is for a controller whose switch discards nothing.
    ///
    /// # Safety
    /// Called from the receive half's context only (another context would take the
    /// count from it).
    unsafe fn take_filter_switch_discards(&self) -> u32 {
        0
    }

    /// Any context: which receive queues the installed filters can feed, bit `q` for
    /// queue `q` (bxCAN: the FIFOs the active banks are assigned to, `CAN_FFA1R`). The
    /// driver reports the rings of these queues as the receive buffer
    /// ([`crate::State::rx_stats`]). The default is every queue the controller has.
    fn fed_rx_queues(&self) -> u8 {
        ((1u16 << Self::RX_QUEUES) - 1) as u8
    }

    /// The map of the filters installed now.
    ///
    /// # Safety
    /// Called from the receive half's context, or before the controller is shared
    /// (`split` and the one-struct driver read it before any other context can call in).
    unsafe fn filter_map(&self) -> Self::FilterMap;

    /// Status interrupt: reads and acknowledges error and wake-up causes.
    ///
    /// The driver calls it again (a few times at most) while it reports a bus error, so
    /// an implementation that found a further error it could not report in the same
    /// call (or whose acknowledge may have cleared the flag of an error raised during
    /// it) reports that one on the next call; a call with nothing new reports `None`.
    ///
    /// # Safety
    /// Called from this method's one context only (see the [module docs](self)).
    unsafe fn take_status(&self) -> StatusEvents;

    /// The error status, read now.
    fn error_status(&self) -> ErrorStatus;

    /// Whether the controller is on the bus (not stopped, not asleep).
    fn on_bus(&self) -> bool;

    /// Changes the operating mode (bounded wait on the acknowledge bit).
    ///
    /// # Safety
    /// Called from the control context only (see the [module docs](self)): never at the
    /// same time as another control method or [`Hardware::install_filters`].
    unsafe fn set_mode(&self, mode: Mode) -> Result<(), Error>;

    /// Starts bus-off recovery by software ([`BusOffRecovery::Manual`]); refused with
    /// [`Error::WrongMode`] when the controller recovers by itself.
    ///
    /// # Safety
    /// As for [`Hardware::set_mode`].
    unsafe fn recover(&self) -> Result<(), Error>;

    /// What this instance can do, as configured now (clock, bit-rate range, modes,
    /// filter capacity of the current partition, mailboxes, FIFO depth, time stamps).
    fn capabilities(&self) -> Capabilities;

    /// The bus mode in force (or to be used at the next start).
    fn bus_mode(&self) -> BusMode;

    /// How the controller leaves bus-off.
    fn bus_off_recovery(&self) -> BusOffRecovery;

    /// Stopped controller only: writes a new bit timing (computed for
    /// [`Capabilities::clock_hz`] within [`Capabilities::timing_limits`]); the filters
    /// stay. [`Error::WrongMode`] while on the bus; [`Error::Timing`] for a timing the
    /// controller's rule refuses ([`Capabilities::check_timing`]: made for another clock
    /// or register layout, inconsistent, or forbidden by the controller's manual,
    /// [`crate::timing::TimingError::ForbiddenByManual`]).
    ///
    /// # Safety
    /// As for [`Hardware::set_mode`].
    unsafe fn set_timing(&self, timing: &Timing) -> Result<(), Error>;

    /// Stopped controller only: selects the bus mode used from the next start; the
    /// filters stay. [`Error::WrongMode`] while on the bus, [`Error::Unsupported`] for a
    /// mode [`Capabilities::modes`] does not offer.
    ///
    /// # Safety
    /// As for [`Hardware::set_mode`].
    unsafe fn set_bus_mode(&self, mode: BusMode) -> Result<(), Error>;
}

/// The checks [`Hardware::set_timing`] applies before any register is written: the
/// controller is stopped (`stopped`), and it accepts the timing
/// ([`Capabilities::check_timing`], the controller's one rule: made for its clock and
/// register layout, consistent, allowed by its manual). The wished rate the timing
/// carries is not judged: the counts are written as given.
pub fn check_timing_for(caps: &Capabilities, timing: &Timing, stopped: bool) -> Result<(), Error> {
    if !stopped {
        return Err(Error::WrongMode);
    }
    caps.check_timing(timing).map_err(Error::Timing)?;
    if timing.triple_sampling && !caps.modes.triple_sampling {
        return Err(Error::Unsupported);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn tokens_sort_in_acceptance_order_across_the_wrap() {
        let mut e = [(1u32, 'c'), (u32::MAX, 'a'), (0, 'b')];
        super::sort_by_token(&mut e);
        assert_eq!(e.map(|x| x.1), ['a', 'b', 'c']);
        let mut one = [(7u32, ())];
        super::sort_by_token(&mut one);
        super::sort_by_token::<()>(&mut []);
    }
}

/// What a hardware receive FIFO reported while [`Hardware::read_rx`] read it (its flags
/// acknowledged by the backend). Both are rare: the per-frame path only tests the flag
/// register, and the receive handler counts them in
/// [`ErrorStatistics`](crate::ErrorStatistics) once per drain in which they were seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FifoEvents {
    /// Frames were lost in hardware (FlexCAN `IFLAG1.BUF7I`, bxCAN `FOVRx`).
    pub overrun: bool,
    /// The FIFO reached its warning level: FlexCAN `IFLAG1.BUF6I` (the number of unread
    /// frames rose from 4 to 5 of 6), bxCAN `FULLx` (3 of 3 frames, RM0410 §40.7.5).
    pub warning: bool,
}
