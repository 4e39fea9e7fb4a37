//! The bxCAN controller as the portable split driver uses it ([`twocan_core::split`]):
//! [`BxCan`], built from an enabled [`Can`] with [`Can::into_split`].
//!
//! Who touches which register (RM0410 §40.9.2), so that the contexts need no lock:
//! - transmit half (direct path) and transmit interrupt: `CAN_TSR` read, the registers
//!   of one mailbox that is empty and settled (`TMEx` = 1, `RQCPx` = 0) — only one
//!   context loads a given mailbox (see [`twocan_core::hardware`]);
//! - transmit interrupt: `CAN_TSR` write-1-to-clear `RQCPx` and `ABRQx` requests;
//! - receive interrupt x: `CAN_RFxR` (`FOVRx`, `FULLx` write-1-to-clear, `RFOMx`) and the
//!   FIFO x output mailbox;
//! - status interrupt: `CAN_MSR` (`ERRI`, `WKUI`, `SLAKI` write-1-to-clear) and
//!   `CAN_ESR.LEC` (set to 0b111 after reading);
//! - receive half: the filter registers (under `CAN_FMR.FINIT`), and `RFOMx` under it to
//!   discard the old list's frames;
//! - any context, inside the driver's critical section: `CAN_RFxR` read (`FMPx`, no side
//!   effect) when a time stamp is widened ([`Hardware::rx_pending`]);
//! - control (the receive half's context; initialization mode): `CAN_BTR` (timing fields,
//!   `SILM`, `LBKM`), `CAN_MCR` mode requests.
//!
//! A raw received frame is the four output-mailbox words (`CAN_RIxR`, `CAN_RDTxR`,
//! `CAN_RDLxR`, `CAN_RDHxR`) with the FIFO number in the reserved bits 7:4 of the
//! second word; the thread side decodes it and maps `(FIFO, FMI)` to the user's filter.

mod in_place;

pub use in_place::{InPlace, Unconfigured};

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, AtomicU32, AtomicU8, Ordering};

use twocan_core::hardware::{
    sort_by_token, Completion, FifoEvents, Settled, StatusEvents, Token, TxFailure,
};
use twocan_core::timing::frame_time::frame_in_flight_wait;
use twocan_core::timing::{Limits, Timing, BXCAN_BTR_TIMING_MASK};
use twocan_core::{
    AtomicLastError, BusMode, BusOffRecovery, Capabilities, Error, ErrorCounters, ErrorState,
    ErrorStatus, Frame, Hardware, LastErrorCode, Mode, ModeSupport, Priority, Registers, RxFrame,
    Timestamp, TxOutcome, TxPolicy,
};
use twocan_core::{MailboxId, MailboxState};

use crate::config::{Config, Recovery};
use crate::controller::{lec, Can};
use crate::filter_block;
use crate::filters::{Fifo, FilterPlan, FmiMap, LOOKUP_KEYS, MAX_FMI};
use crate::instance::Instance;
use crate::mailbox;
use crate::mode;
use crate::regs::{
    btr, esr, ier, msr, rdhxr, rdlxr, rdtxr, rfxr, rixr, tdtxr, tixr, tsr, BTR, ESR, IER, MSR, TSR,
    TX_MAILBOXES,
};

/// Frames one receive FIFO holds (RM0410 §40.7.5).
const RX_FIFO_DEPTH: usize = 3;

/// `CAN_TSR.TMEx` of the three mailboxes.
const TME_ALL: u32 = tsr::TME0 | tsr::TME1 | tsr::TME2;
/// `CAN_TSR.RQCPx` of the three mailboxes.
const RQCP_ALL: u32 = tsr::RQCP0 | tsr::RQCP1 | tsr::RQCP2;

/// A mailbox empty (`TMEx`) and settled (`RQCPx` = 0) in `CAN_TSR` value `t`, `CODE`'s
/// first: the slow path of `free_mailbox`, when a completion is still pending.
#[cold]
fn free_of(t: u32, code: usize) -> Option<u8> {
    let ok = |x: usize| t & tsr::tme(x) != 0 && t & tsr::rqcp(x) == 0;
    if code < TX_MAILBOXES && ok(code) {
        return Some(code as u8);
    }
    (0..TX_MAILBOXES).find(|&x| ok(x)).map(|x| x as u8)
}

/// Any empty mailbox in `CAN_TSR` value `t`, lowest first, acknowledged or not: the
/// slow path of `free_mailbox_quiet`, when `CODE` names none.
#[cold]
fn free_of_quiet(t: u32) -> Option<u8> {
    (0..TX_MAILBOXES)
        .find(|&x| t & tsr::tme(x) != 0)
        .map(|x| x as u8)
}

/// One received frame as the receive interrupt copies it: `CAN_RIxR`, `CAN_RDTxR` (FIFO
/// number in bits 7:4), `CAN_RDLxR`, `CAN_RDHxR`, and the filter list generation it was
/// read under.
pub type RawFrame = [u32; 5];

/// A bxCAN instance shared by the halves and handlers of the split driver.
///
/// `K`: the capacity of the merged-filter lookup ([`FmiMap`]), as the [`Can`] it came
/// from; `M`: the match indices its map holds per FIFO ([`MAX_FMI`] unless a `const`
/// plan sizes it); `SWITCH`: whether the receive half may replace the filters while the
/// controller runs (each received frame then carries the filter generation, read in
/// the receive interrupt and checked on the thread side; `false`:
/// [`Can::into_split_fixed`], `set_filters` refused, nothing paid per frame).
pub struct BxCan<
    R: Registers,
    F: Registers = R,
    const K: usize = LOOKUP_KEYS,
    const M: usize = MAX_FMI,
    const SWITCH: bool = true,
> {
    regs: R,
    filter_regs: Option<F>,
    instance: Instance,
    config: Config,
    /// The installed filters' map from (FIFO, FMI) to the user's index: touched only
    /// from the receive half's context (`decode`, `install_filters`), so one copy.
    fmi: UnsafeCell<FmiMap<K, M>>,
    /// Token of the frame in each mailbox (written before `TXRQ`).
    tokens: [AtomicU32; TX_MAILBOXES],
    /// When each mailbox was loaded: the count of loads before it (written before
    /// `TXRQ`), for `mailbox_state`.
    loads: [AtomicU32; TX_MAILBOXES],
    /// Loads so far (wrapping).
    load_count: AtomicU32,
    /// Mailboxes whose abort was requested to make room (displacement).
    displacing: AtomicU8,
    /// Mailboxes whose abort the application requested.
    aborting: AtomicU8,
    /// Frames read back from mailboxes being displaced: touched only by the transmit
    /// interrupt's `displace` and `settle` (one context, see `Hardware`).
    displaced: UnsafeCell<[Frame; TX_MAILBOXES]>,
    /// The last error code latched (`LastErrorCode` as its index), kept after LEC is
    /// set to 0b111.
    last_error: AtomicLastError,
    /// Acknowledge wait bound (grows when a slower bit rate is set).
    wait: AtomicU32,
    /// `CAN_BTR.SILM` without `LBKM` (listen-only): transmission refused.
    listen_only: AtomicBool,
    /// Filter list generation, stamped on each raw frame by `read_rx` and compared by
    /// `decode`: frames read before the last `install_filters` are dropped. Written by
    /// `install_filters` only.
    generation: AtomicU32,
    /// FIFO frames released by `install_filters` and not yet taken (receive half only).
    discarded: AtomicU32,
    /// The FIFOs the installed filters feed (`fed_rx_queues`), read from the filter
    /// block when the filters are installed.
    fed: AtomicU8,
}

// SAFETY: what each field needs to be shared between contexts:
// - `regs`, `filter_regs`: every context reads and writes registers through `&R`/`&F`
//   (`R: Sync`, `F: Sync`), each its own registers or write-1-to-clear bits (module
//   docs, the `Hardware` contract);
// - `fmi`: touched only by `decode` and `install_filters`, both `unsafe` and called
//   from the receive half's one context (the `Hardware` contract, upheld by
//   `twocan_core::split::Rx`); that context may move between threads with the receive
//   half, so the map must be `Send` (the `where` clause);
// - `displaced`: touched only by `displace` and `settle`, both `unsafe` and called from
//   the transmit interrupt's context inside the driver's critical section; `Frame` is
//   plain data;
// - `instance`, `config`: read only; everything else is atomic.
// `BxCan` itself is `Send` (moved into the driver's state) exactly when `R` and `F` are.
unsafe impl<
        R: Registers + Sync,
        F: Registers + Sync,
        const K: usize,
        const M: usize,
        const SWITCH: bool,
    > Sync for BxCan<R, F, K, M, SWITCH>
where
    FmiMap<K, M>: Send,
{
}

impl<R: Registers, F: Registers, const K: usize, const M: usize> Can<R, F, K, M> {
    /// The controller for the split driver (`twocan_core::split::State::split`); the
    /// installed filters come along, and the receive half may replace them while it
    /// runs (`set_filters`).
    pub fn into_split(self) -> BxCan<R, F, K, M> {
        self.into_split_with()
    }

    /// [`Can::into_split`] with the filters fixed: the receive half's `set_filters` is
    /// refused ([`Error::Unsupported`]), and in exchange no received frame carries or
    /// checks a filter generation (issue 21: paid only where filters change).
    pub fn into_split_fixed(self) -> BxCan<R, F, K, M, false> {
        self.into_split_with()
    }

    /// [`Can::into_split`] with `SWITCH` (whether the filters may change while the
    /// controller runs) chosen by the caller's type.
    pub fn into_split_with<const SWITCH: bool>(self) -> BxCan<R, F, K, M, SWITCH> {
        let listen_only = self.regs.read32(BTR) & (btr::SILM | btr::LBKM) == btr::SILM;
        let fed = match &self.filter_regs {
            Some(f) => filter_block::fed_fifos(f, self.config.get_chip(), self.instance),
            None => filter_block::fed_fifos(&self.regs, self.config.get_chip(), self.instance),
        };
        BxCan {
            regs: self.regs,
            filter_regs: self.filter_regs,
            instance: self.instance,
            config: self.config,
            fmi: UnsafeCell::new(self.fmi),
            tokens: [const { AtomicU32::new(0) }; TX_MAILBOXES],
            loads: [const { AtomicU32::new(0) }; TX_MAILBOXES],
            load_count: AtomicU32::new(0),
            displacing: AtomicU8::new(0),
            aborting: AtomicU8::new(0),
            displaced: UnsafeCell::new([Frame::default(); TX_MAILBOXES]),
            last_error: AtomicLastError::new(LastErrorCode::None),
            wait: AtomicU32::new(self.config.get_wait_iterations()),
            listen_only: AtomicBool::new(listen_only),
            generation: AtomicU32::new(0),
            discarded: AtomicU32::new(0),
            fed: AtomicU8::new(fed),
        }
    }
}

impl<R: Registers, F: Registers, const K: usize, const M: usize, const SWITCH: bool>
    BxCan<R, F, K, M, SWITCH>
{
    /// Back to the configuration-level controller (for [`Can::reconfigure`]); the
    /// filters installed (and their map) come along. Transmit bookkeeping is dropped:
    /// take it back only when no frame is in flight.
    pub fn into_can(self) -> Can<R, F, K, M> {
        Can {
            regs: self.regs,
            filter_regs: self.filter_regs,
            instance: self.instance,
            config: self.config,
            fmi: self.fmi.into_inner(),
        }
    }

    /// Software master reset of a controller taken back from the driver
    /// ([`Can::master_reset`]: every controller register to its reset value).
    #[allow(clippy::result_large_err, clippy::type_complexity)]
    pub fn master_reset(
        self,
    ) -> Result<(R, Option<F>), crate::controller::Failed<Can<R, F, K, M>>> {
        self.into_can().master_reset()
    }

    /// Clears the last error code by software (`CAN_ESR.LEC = 0b111`, "set by
    /// software": the hardware overwrites it with the next bus event); the sticky copy
    /// the error status reports reads [`LastErrorCode::None`] too.
    pub fn clear_last_error(&self) {
        self.regs.write32(ESR, esr::LEC.val(esr::LEC_SOFTWARE));
        self.last_error.store(LastErrorCode::None);
    }

    /// The operating mode the acknowledge bits (`CAN_MSR.INAK`, `SLAK`) show now.
    pub fn mode(&self) -> Mode {
        mode::current(&self.regs)
    }

    /// The banks (`start..end`, hardware numbering) this instance owns now.
    pub fn bank_range(&self) -> (usize, usize) {
        match &self.filter_regs {
            Some(f) => filter_block::banks_of(f, self.config.get_chip(), self.instance),
            None => filter_block::banks_of(&self.regs, self.config.get_chip(), self.instance),
        }
    }

    /// Compiles `filters` for this instance's banks ([`crate::planner::plan`]), to
    /// install with the receive half's `set_filters`.
    pub fn plan(
        &self,
        filters: &[twocan_core::Filter],
        fifo: crate::planner::FifoPolicy,
    ) -> Result<FilterPlan<K>, crate::filters::PlanError> {
        let (s, e) = self.bank_range();
        crate::planner::plan_for::<K>(
            filters,
            crate::planner::PlanOptions::new((e - s) as u8).fifo(fifo),
        )
    }

    /// The instance.
    pub fn instance(&self) -> Instance {
        self.instance
    }

    /// The configuration in force.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The registers (for inspection).
    pub fn registers(&self) -> &R {
        &self.regs
    }

    /// The registers, mutably (a host harness moving a model to another bus; writing
    /// them behind the driver's back voids its bookkeeping).
    pub fn registers_mut(&mut self) -> &mut R {
        &mut self.regs
    }

    fn read_frame(&self, x: usize) -> Frame {
        mailbox::read_tx(&self.regs, x)
    }

    /// Settles mailbox `x`, whose `RQCPx` is set in `t` (`CAN_TSR` as read): what ended
    /// (RM0410 §40.9.2: `TXOKx` → sent, with `CAN_TDTxR.TIME` when TTCM is on; an abort
    /// the application requested → aborted; a displacement abort → the frame goes back
    /// to the queue; otherwise a one-shot failure, `ALSTx` or `TERRx` saying why), then
    /// acknowledges it (writing `RQCPx` clears `TXOKx`, `ALSTx` and `TERRx`: the flags
    /// were read in `t` before), and reports it to `f` with the mailbox's token.
    ///
    /// # Safety
    /// Transmit interrupt context (the one context of `settle`, which alone touches
    /// `displaced` and clears `aborting`/`displacing` bits, inside the driver's critical
    /// section, as `request_abort` sets them).
    #[inline(always)]
    unsafe fn settle_one(&self, t: u32, x: usize, mut f: impl FnMut(u32, Settled)) {
        let bit = 1u8 << x;
        // Relaxed: see `load`.
        let token = Token(self.tokens[x].load(Ordering::Relaxed));
        // Plain load, then clear only when set: both flags change only inside the
        // driver's critical section (this method's context and `request_abort`).
        let user_abort = self.aborting.load(Ordering::Relaxed) & bit != 0;
        if user_abort {
            self.aborting.fetch_and(!bit, Ordering::Relaxed);
        }
        let displacing = self.displacing.load(Ordering::Relaxed) & bit != 0;
        if displacing {
            self.displacing.fetch_and(!bit, Ordering::Relaxed);
        }
        // The 16-bit TIME of a sent frame (RM0410 §40.9.2 CAN_TDTxR), read before the
        // acknowledge frees the mailbox for the next load; the driver widens it.
        let sent = t & tsr::txok(x) != 0;
        let timestamp = (sent && self.config.get_timestamps())
            .then(|| Timestamp::from_parts(0, rdtxr::TIME.get(self.regs.read32(tdtxr(x))) as u16));
        self.regs.write32(TSR, tsr::rqcp(x));
        // Each outcome calls `f` with its own variant, so that an inlined `f` matches
        // on a known variant instead of copying a generic `Settled` around.
        let mut done = |c: Completion| {
            if displacing {
                f(token.0, Settled::DoneDisplacing(c))
            } else {
                f(token.0, Settled::Done(c))
            }
        };
        if sent {
            done(Completion {
                token,
                outcome: TxOutcome::Sent,
                cause: None,
                timestamp,
            })
        } else if user_abort {
            done(Completion {
                token,
                outcome: TxOutcome::Aborted,
                cause: None,
                timestamp: None,
            })
        } else if displacing {
            // SAFETY: transmit interrupt context, the only one touching `displaced`.
            let frame = unsafe { (*self.displaced.get())[x] };
            f(token.0, Settled::Displaced(token, frame))
        } else {
            let cause = if t & tsr::alst(x) != 0 {
                Some(TxFailure::ArbitrationLost)
            } else if t & tsr::terr(x) != 0 {
                Some(TxFailure::Error)
            } else {
                None
            };
            f(
                token.0,
                Settled::Done(Completion {
                    token,
                    outcome: TxOutcome::Failed,
                    cause,
                    timestamp: None,
                }),
            )
        }
    }

    /// `settle` when several mailboxes ended between two interrupts: reports them in
    /// token (acceptance) order, which is the transmit order under TXFP = 1. Out of line
    /// and not generic (`dyn`), so that the usual single completion needs no sort buffer
    /// in its frame and the caller's `f` has one static call site, inlined there.
    ///
    /// # Safety
    /// As for `settle`.
    #[cold]
    #[inline(never)]
    unsafe fn settle_many(&self, t: u32, f: &mut dyn FnMut(Settled)) {
        let mut ended = [(
            0u32,
            Settled::Done(Completion {
                token: Token(0),
                outcome: TxOutcome::Sent,
                cause: None,
                timestamp: None,
            }),
        ); TX_MAILBOXES];
        let mut n = 0;
        for x in 0..TX_MAILBOXES {
            if t & tsr::rqcp(x) == 0 {
                continue;
            }
            // SAFETY: the caller's contract (transmit interrupt context).
            unsafe { self.settle_one(t, x, |token, settled| ended[n] = (token, settled)) };
            n += 1;
        }
        let ended = &mut ended[..n];
        sort_by_token(ended);
        for (_, s) in ended.iter() {
            f(*s);
        }
    }

    /// Under identifier priority (`TXFP` = 0), the free mailbox `frame` may take
    /// without overtaking a pending frame it ties with: the hardware sends equal
    /// arbitration keys lowest mailbox number first (RM0410 §40.7.3 "Transmit
    /// priority": "If the identifier values are equal, the lower mailbox number will be
    /// scheduled first"), so a tie must go above every pending tie — `first` if it
    /// already is, else the lowest free and settled mailbox above them, else none (the
    /// frame waits for the ties to leave). None either while a tie is being displaced:
    /// its frame may come back to the queue, ahead of `frame`. `t` is `CAN_TSR` as
    /// read. Frames of one identifier (ISO-TP, CANopen SDO blocks, DroneCAN transfers)
    /// so leave in request order.
    #[cold]
    #[inline(never)]
    fn after_ties(&self, t: u32, frame: &Frame, first: u8) -> Option<u8> {
        let key = Priority::of(frame);
        let displacing = self.displacing.load(Ordering::Relaxed);
        let mut above = 0;
        for x in 0..TX_MAILBOXES {
            let pending = t & tsr::tme(x) == 0;
            // Being displaced, pending or ended unsettled (`TIxR` keeps the frame).
            let back = displacing & (1 << x) != 0;
            if (pending || back) && mailbox::priority_of(self.regs.read32(tixr(x))) == key {
                if back {
                    return None;
                }
                above = x + 1;
            }
        }
        if first as usize >= above {
            return Some(first);
        }
        (above..TX_MAILBOXES)
            .find(|&x| t & tsr::tme(x) != 0 && t & tsr::rqcp(x) == 0)
            .map(|x| x as u8)
    }

    /// The rare path of `read_rx`, out of line: acknowledges `FOVRx` and `FULLx` of
    /// FIFO `x` (write 1 to clear, RM0410 §40.9.2 `CAN_RFxR`), `r` as read, and
    /// records them in `events` (`FOVRx`: frames lost; `FULLx`: the FIFO was full).
    #[cold]
    #[inline(never)]
    fn acknowledge_full(&self, x: usize, r: u32, events: &mut FifoEvents) {
        self.regs.write32(rfxr(x), r & (rfxr::FOVR | rfxr::FULL));
        events.overrun |= r & rfxr::FOVR != 0;
        events.warning |= r & rfxr::FULL != 0;
    }

    fn status_now(&self) -> ErrorStatus {
        let m = self.regs.read32(MSR);
        let e = self.regs.read32(ESR);
        let boff = e & esr::BOFF != 0;
        let counters = ErrorCounters {
            tec: if boff { 256 } else { esr::TEC.get(e) as u16 },
            rec: esr::REC.get(e) as u16,
        };
        let state = if m & msr::SLAK != 0 {
            ErrorState::Sleeping
        } else if m & msr::INAK != 0 {
            ErrorState::Stopped
        } else if boff {
            ErrorState::BusOff
        } else if e & esr::EPVF != 0 {
            ErrorState::Passive
        } else if e & esr::EWGF != 0 {
            ErrorState::Warning
        } else {
            ErrorState::from_counters(counters)
        };
        // A code latched since the status handler last ran counts as the last error
        // (the handler reports and clears it; reading it here changes nothing).
        let code = lec(esr::LEC.get(e));
        if code != LastErrorCode::None {
            self.last_error.store(code);
        }
        ErrorStatus {
            state,
            counters,
            last_error: self.last_error.load(),
        }
    }
}

// SAFETY: each method touches the registers its context owns (module docs); `displaced`
// only from `displace`/`settle` (transmit interrupt context).
unsafe impl<R: Registers, F: Registers, const K: usize, const M: usize, const SWITCH: bool> Hardware
    for BxCan<R, F, K, M, SWITCH>
{
    type Raw = RawFrame;
    type FilterMap = ();
    type Filters = FilterPlan<K>;
    const RX_QUEUES: usize = 2;

    fn tx_policy(&self) -> TxPolicy {
        self.config.get_tx_policy()
    }

    /// Refused with [`Error::WrongMode`] in listen-only mode (`SILM` without `LBKM`,
    /// the portable [`BusMode::ListenOnly`]). Reads `CAN_TSR` once: `CODE` names an empty mailbox when any `TMEx` is set (RM0410
    /// §40.9.2); it is taken when its last completion was settled (`RQCPx` = 0). With
    /// no `RQCPx` pending (the usual case) that is `CODE` itself, its `TMEx` checked.
    #[inline(always)]
    fn free_mailbox(&self, frame: &Frame) -> Result<Option<u8>, Error> {
        if self.listen_only.load(Ordering::Relaxed) {
            return Err(Error::WrongMode);
        }
        let t = self.regs.read32(TSR);
        if t & TME_ALL == 0 {
            return Ok(None);
        }
        let code = tsr::CODE.get(t) as usize;
        // `TMEx` of `CODE` is checked too: a wrong `CODE` must not make a pending
        // mailbox look free (its frame would be overwritten).
        let free = if t & RQCP_ALL == 0 && code < TX_MAILBOXES && t & tsr::tme(code) != 0 {
            Some(code as u8)
        } else {
            free_of(t, code)
        };
        if self.config.get_tx_policy() == TxPolicy::Priority
            && (t & TME_ALL != TME_ALL || self.displacing.load(Ordering::Relaxed) != 0)
        {
            // Some mailbox is pending (or being displaced): a tie must not overtake it.
            return Ok(free.and_then(|m| self.after_ties(t, frame, m)));
        }
        Ok(free)
    }

    /// The quiet transmit mode is offered: `CAN_IER.TMEIE` gates the transmit line
    /// (RM0410 §40.8 "Interrupts": the line is `TMEIE` and any `RQCPx`), and a
    /// mailbox may be reloaded before its `RQCPx` is acknowledged (setting `TXRQ`
    /// clears `RQCPx`, RM0410 §40.9.2 `CAN_TSR`).
    const QUIET_TX: bool = true;

    /// Request order only (the quiet mode's queue, adopted only by a controller with
    /// `TXFP` = 1, which sends the mailboxes in the order of their requests, RM0410
    /// §40.7.3; in identifier priority this would break the order): any empty mailbox, `CODE` first,
    /// whether or not its `RQCPx` was acknowledged. Refused in listen-only mode as
    /// [`Hardware::free_mailbox`] is.
    #[inline(always)]
    fn free_mailbox_quiet(&self, frame: &Frame) -> Result<Option<u8>, Error> {
        // The quiet mode's state is split only with a request-order controller, whose
        // order (`config`) never changes while split (`State::split` refuses others).
        let _ = frame;
        if self.listen_only.load(Ordering::Relaxed) {
            return Err(Error::WrongMode);
        }
        let t = self.regs.read32(TSR);
        let code = tsr::CODE.get(t) as usize;
        // `TMEx` of `CODE` is checked: `CODE` names an empty mailbox only when one is.
        if code < TX_MAILBOXES && t & tsr::tme(code) != 0 {
            return Ok(Some(code as u8));
        }
        Ok(free_of_quiet(t))
    }

    /// Writes back the `RQCPx` bits `CAN_TSR` shows (write 1 to clear; RM0410 §40.9.2),
    /// which lowers the transmit line; nothing is reported. The `aborting` marks of
    /// these mailboxes are cleared too (their aborts ended), so that a driver split
    /// later with completions does not take a later frame of theirs for aborted.
    unsafe fn acknowledge_ended(&self) {
        let rq = self.regs.read32(TSR) & RQCP_ALL;
        if rq != 0 {
            self.regs.write32(TSR, rq);
            // Bit x of the mailboxes from `RQCPx` (bits 0, 8, 16). The marks change only
            // inside the driver's critical section (this context and `request_abort`).
            let ended = (rq & tsr::RQCP0) | (rq & tsr::RQCP1) >> 7 | (rq & tsr::RQCP2) >> 14;
            let marks = self.aborting.load(Ordering::Relaxed);
            if marks & ended as u8 != 0 {
                self.aborting
                    .store(marks & !(ended as u8), Ordering::Relaxed);
            }
        }
    }

    /// `CAN_IER` as configured, with `TMEIE` cleared when `on` is false (`CAN_IER` is
    /// written by the configuration and, once split, only here, inside the driver's
    /// critical section).
    unsafe fn set_tx_interrupt(&self, on: bool) {
        let ier = self.config.get_interrupts();
        self.regs
            .write32(IER, if on { ier } else { ier & !ier::TMEIE });
    }

    /// Notes "Transmission handling": DLC, data, then identifier with `TXRQ`.
    #[inline(always)]
    unsafe fn load(&self, mailbox: u8, frame: &Frame, token: Token) {
        let x = mailbox as usize;
        // Relaxed: the token is stored before the `TXRQ` store in program order, and the
        // transmit interrupt reads it only after seeing this mailbox's `RQCPx`, which the
        // hardware sets after acting on `TXRQ` (on the host, the model's lock around each
        // register access orders the two).
        self.tokens[x].store(token.0, Ordering::Relaxed);
        let n = self.load_count.fetch_add(1, Ordering::Relaxed);
        self.loads[x].store(n, Ordering::Relaxed);
        mailbox::load(&self.regs, x, frame);
    }

    /// For each `RQCPx` (RM0410 §40.9.2): `TXOKx` → sent (with `CAN_TDTxR.TIME` when
    /// TTCM is on); an abort the application requested → aborted; a displacement abort
    /// → the frame goes back to the queue; otherwise a one-shot failure, `ALSTx` or
    /// `TERRx` saying why. Writing `RQCPx` clears `TXOKx`, `ALSTx` and `TERRx`.
    unsafe fn settle<G: FnMut(Settled)>(&self, mut f: G) {
        let t = self.regs.read32(TSR);
        let rq = t & RQCP_ALL;
        if rq == 0 {
            return;
        }
        if rq & (rq - 1) == 0 {
            // One mailbox ended (the usual case): no ordering needed.
            let x = if rq == tsr::RQCP0 {
                0
            } else if rq == tsr::RQCP1 {
                1
            } else {
                2
            };
            // SAFETY: the caller's contract (transmit interrupt context).
            unsafe { self.settle_one(t, x, |_, settled| f(settled)) };
            return;
        }
        // SAFETY: the caller's contract (transmit interrupt context).
        unsafe { self.settle_many(t, &mut f) }
    }

    /// With all three mailboxes pending, the one lowest in the hardware's order
    /// (largest arbitration key; ties: higher mailbox number, notes "Transmit
    /// priority") among those `frame` beats and may replace is aborted (`ABRQx`).
    /// `frame` may replace a mailbox above every pending mailbox it ties with (it
    /// leaves after them, see `after_ties`); the victim is the last of its own ties,
    /// so its frame goes back to the queue ahead of none of them.
    unsafe fn displace(&self, frame: &Frame) -> bool {
        let t = self.regs.read32(TSR);
        if t & TME_ALL != 0 || self.displacing.load(Ordering::Relaxed) != 0 {
            return false;
        }
        let key = Priority::of(frame);
        let keys: [Priority; TX_MAILBOXES] =
            core::array::from_fn(|x| mailbox::priority_of(self.regs.read32(tixr(x))));
        let above = match (0..TX_MAILBOXES).rev().find(|&x| keys[x] == key) {
            Some(tie) => tie + 1,
            None => 0,
        };
        let Some(low) = (above..TX_MAILBOXES)
            .filter(|&x| key.beats(keys[x]))
            .max_by_key(|&x| (keys[x], x))
        else {
            return false;
        };
        let low_frame = self.read_frame(low);
        // SAFETY: transmit interrupt context, the only one touching `displaced`.
        unsafe { (*self.displaced.get())[low] = low_frame };
        self.displacing.fetch_or(1 << low, Ordering::Relaxed);
        self.regs.write32(TSR, tsr::abrq(low));
        true
    }

    fn mailbox_count(&self) -> u8 {
        TX_MAILBOXES as u8
    }

    /// `Empty` when `CAN_TSR.TMEx`. Otherwise, from the hardware's transmit order (the
    /// identifier priority, ties lower mailbox number first, under `TXFP = 0`; the
    /// request order under `TXFP = 1`; notes "Transmit priority", "Transmit mailbox
    /// states"): while `CAN_MSR.TXM` is clear, the first mailbox is `Scheduled` and the
    /// others `Pending`. While it is set, one mailbox is on the bus: the first in the
    /// hardware's order among those pending when its frame started. No register names
    /// it, so the driver uses the order of its loads: the mailbox on the bus is the first
    /// of some earliest-loaded part of the pending ones. When every such part has the
    /// same first mailbox (always under `TXFP = 1`; under `TXFP = 0` unless a frame of
    /// higher priority was loaded after an earlier one), that mailbox is
    /// `Transmitting`, the first of the others `Scheduled`, the rest `Pending`. When
    /// they differ (a higher-priority frame loaded while an earlier one may have
    /// started), no mailbox is named `Transmitting`: each one that may be on the bus or
    /// next to go reads `Scheduled`, the others `Pending`.
    fn mailbox_state(&self, mailbox: MailboxId) -> MailboxState {
        let x = mailbox.0 as usize;
        let t = self.regs.read32(TSR);
        if x >= TX_MAILBOXES || t & tsr::tme(x) != 0 {
            return MailboxState::Empty;
        }
        let priority = self.config.get_tx_policy() == TxPolicy::Priority;
        let seq: [u32; TX_MAILBOXES] =
            core::array::from_fn(|y| self.loads[y].load(Ordering::Relaxed));
        let keys: [Priority; TX_MAILBOXES] = core::array::from_fn(|y| {
            if priority && t & tsr::tme(y) == 0 {
                mailbox::priority_of(self.regs.read32(tixr(y)))
            } else {
                Priority::from_raw(0, false, false)
            }
        });
        let loaded_before = |a: usize, b: usize| (seq[a].wrapping_sub(seq[b]) as i32) < 0;
        // Whether mailbox `a` goes before `b` in the hardware's order.
        let before = |a: usize, b: usize| {
            if priority {
                (keys[a], a) < (keys[b], b)
            } else {
                loaded_before(a, b)
            }
        };
        // The pending mailboxes in load order.
        let mut pending = [0usize; TX_MAILBOXES];
        let mut n = 0;
        for y in (0..TX_MAILBOXES).filter(|&y| t & tsr::tme(y) == 0) {
            let mut i = n;
            while i > 0 && loaded_before(y, pending[i - 1]) {
                pending[i] = pending[i - 1];
                i -= 1;
            }
            pending[i] = y;
            n += 1;
        }
        let pending = &pending[..n];
        // The first in the hardware's order among `pending` without `skip`.
        let first_without = |skip: Option<usize>| {
            pending
                .iter()
                .copied()
                .filter(|&y| Some(y) != skip)
                .reduce(|a, b| if before(b, a) { b } else { a })
        };
        let first = first_without(None);
        if self.regs.read32(MSR) & msr::TXM == 0 {
            return if first == Some(x) {
                MailboxState::Scheduled
            } else {
                MailboxState::Pending
            };
        }
        // The mailboxes that may be on the bus: the first of each earliest-loaded part.
        let mut on_bus = 0u8;
        let mut best: Option<usize> = None;
        for &y in pending {
            if best.is_none_or(|b| before(y, b)) {
                best = Some(y);
                on_bus |= 1 << y;
            }
        }
        if on_bus.count_ones() == 1 {
            return if first == Some(x) {
                MailboxState::Transmitting
            } else if first_without(first) == Some(x) {
                MailboxState::Scheduled
            } else {
                MailboxState::Pending
            };
        }
        let maybe_next = pending
            .iter()
            .filter(|&&y| on_bus & (1 << y) != 0)
            .any(|&y| first_without(Some(y)) == Some(x));
        if on_bus & (1 << x) != 0 || maybe_next {
            MailboxState::Scheduled
        } else {
            MailboxState::Pending
        }
    }

    /// `ABRQx` of the loaded mailbox holding `token` (RM0410 §40.9.2); a mailbox on the
    /// bus finishes first, so the completion may still say sent. A mailbox whose
    /// displacement abort ended but is not settled yet still holds its frame for the
    /// queue: it is marked aborted, so that `settle` reports it aborted instead of
    /// queueing it again.
    unsafe fn request_abort(&self, token: Token) -> bool {
        let t = self.regs.read32(TSR);
        let displacing = self.displacing.load(Ordering::Relaxed);
        for x in 0..TX_MAILBOXES {
            let loaded = t & tsr::tme(x) == 0;
            let coming_back = displacing & (1 << x) != 0;
            if (loaded || coming_back) && self.tokens[x].load(Ordering::Acquire) == token.0 {
                self.aborting.fetch_or(1 << x, Ordering::Relaxed);
                if loaded {
                    self.regs.write32(TSR, tsr::abrq(x));
                }
                return true;
            }
        }
        false
    }

    /// `ABRQx` of every loaded mailbox; mailboxes whose displacement abort ended
    /// unsettled are marked aborted (see `request_abort`).
    unsafe fn abort_all_mailboxes(&self) {
        let t = self.regs.read32(TSR);
        let displacing = self.displacing.load(Ordering::Relaxed);
        for x in 0..TX_MAILBOXES {
            let loaded = t & tsr::tme(x) == 0;
            if loaded || displacing & (1 << x) != 0 {
                self.aborting.fetch_or(1 << x, Ordering::Relaxed);
                if loaded {
                    self.regs.write32(TSR, tsr::abrq(x));
                }
            }
        }
    }

    /// `CAN_RFxR.FMPx` > 0: copies the output mailbox and releases it (`RFOMx`); an
    /// overrun (`FOVRx`, frames lost in hardware) is acknowledged with `FULLx`.
    #[inline(always)]
    unsafe fn read_rx(&self, queue: usize, events: &mut FifoEvents) -> Option<RawFrame> {
        let x = queue & 1;
        let r = self.regs.read32(rfxr(x));
        if r & (rfxr::FOVR | rfxr::FULL) != 0 {
            self.acknowledge_full(x, r, events);
        }
        if rfxr::FMP.get(r) == 0 {
            return None;
        }
        // The generation before the frame: a frame of the old list read while
        // `install_filters` drains the FIFOs carries the old generation (never the new).
        // Filters fixed (`SWITCH` = false): no generation, nothing to read.
        let generation = if SWITCH {
            self.generation.load(Ordering::Acquire)
        } else {
            0
        };
        let raw = [
            self.regs.read32(rixr(x)),
            self.regs.read32(rdtxr(x)) | (x as u32) << 4,
            self.regs.read32(rdlxr(x)),
            self.regs.read32(rdhxr(x)),
            generation,
        ];
        self.regs.write32(rfxr(x), rfxr::RFOM);
        Some(raw)
    }

    /// The user's filter through the map of the installed plan
    /// ([`FmiMap::resolve`]: a table entry, or a search for a merged or superset
    /// entry); `None` (dropped and counted) for a frame no user filter accepts.
    #[inline]
    unsafe fn decode(&self, raw: &RawFrame, _map: &()) -> Option<RxFrame> {
        let [ir, dt, lo, hi, generation] = *raw;
        if SWITCH && generation != self.generation.load(Ordering::Relaxed) {
            // Accepted by a filter list replaced since: dropped (counted by the driver).
            return None;
        }
        let frame = mailbox::frame_of(ir, rdtxr::DLC.get(dt), lo, hi);
        let fifo = if (dt >> 4) & 1 == 0 {
            Fifo::Fifo0
        } else {
            Fifo::Fifo1
        };
        // SAFETY: the receive half's context, the only one touching the map.
        let map = unsafe { &*self.fmi.get() };
        let filter = map.resolve(
            fifo,
            rdtxr::FMI.get(dt) as u8,
            frame.raw_id(),
            frame.is_extended(),
            frame.is_remote(),
        )?;
        Some(RxFrame {
            frame,
            filter,
            // Added by the driver from `raw_timestamp`, widened on the interrupt side.
            timestamp: None,
            hw_match: (rdtxr::FMI.get(dt) as u16) | ((((dt >> 4) & 1) as u16) << 8),
        })
    }

    /// `CAN_RFxR.FMPx` ≠ 0 (RM0410 §40.9.2: the number of messages pending in FIFO x;
    /// reading `CAN_RFxR` has no side effect, its write bits act only when written).
    fn rx_pending(&self, queue: usize) -> bool {
        rfxr::FMP.get(self.regs.read32(rfxr(queue & 1))) != 0
    }

    fn raw_timestamp(&self, raw: &RawFrame) -> Option<u16> {
        self.config
            .get_timestamps()
            .then_some(rdtxr::TIME.get(raw[1]) as u16)
    }

    /// Programs the banks under `CAN_FMR.FINIT` (reception through the block stops,
    /// RM0410 §40.7.4) and, still under it, releases and discards what the old banks
    /// accepted into FIFO 0 and FIFO 1 (`RFOMx`) and moves to the next generation —
    /// before `FINIT` is cleared, so that every frame read afterwards, which the new
    /// banks accepted, carries the new one (a frame read between the end of the switch
    /// and a later bump would carry the old generation and be dropped). Then the
    /// thread-side map is switched (`decode` runs in this context only, after this
    /// returns). Frames of the old list still in the driver's ring carry the old
    /// generation: `decode` drops them.
    ///
    /// Refused with [`Error::Unsupported`] when the filters are fixed (`SWITCH` =
    /// false, [`Can::into_split_fixed`]): its frames carry no generation.
    unsafe fn install_filters(&self, filters: &FilterPlan<K>) -> Result<(), Error> {
        if !SWITCH {
            return Err(Error::Unsupported);
        }
        // The map first: a plan it cannot hold is refused before any bank changes.
        let fmi = filters.fmi_map_sized::<K, M>()?;
        let drain = || {
            for x in 0..2 {
                // At most three frames per FIFO (RM0410 §40.7.5); the receive
                // interrupt may release some too.
                for _ in 0..2 * RX_FIFO_DEPTH {
                    if rfxr::FMP.get(self.regs.read32(rfxr(x))) == 0 {
                        break;
                    }
                    self.regs.write32(rfxr(x), rfxr::RFOM);
                    // Counted (`take_filter_switch_discards`).
                    self.discarded.fetch_add(1, Ordering::Relaxed);
                }
            }
            // Nothing enters the FIFOs under `FINIT`: what the receive interrupt reads
            // from now on was accepted by the new banks.
            let next = self.generation.load(Ordering::Relaxed).wrapping_add(1);
            self.generation.store(next, Ordering::Release);
        };
        let r = match &self.filter_regs {
            Some(f) => {
                filter_block::program_then(f, self.config.get_chip(), self.instance, filters, drain)
            }
            None => filter_block::program_then(
                &self.regs,
                self.config.get_chip(),
                self.instance,
                filters,
                drain,
            ),
        };
        r.map_err(|_| Error::InvalidArgument)?;
        let fed = match &self.filter_regs {
            Some(f) => filter_block::fed_fifos(f, self.config.get_chip(), self.instance),
            None => filter_block::fed_fifos(&self.regs, self.config.get_chip(), self.instance),
        };
        self.fed.store(fed, Ordering::Relaxed);
        // SAFETY: the receive half's context, the only one touching the map.
        unsafe { *self.fmi.get() = fmi };
        Ok(())
    }

    unsafe fn filter_map(&self) {}

    /// The FIFOs the active banks of the installed filters are assigned to
    /// (`CAN_FA1R`, `CAN_FFA1R`, read when they were installed): a `FifoPolicy::Fifo0`
    /// plan feeds FIFO 0 only.
    fn fed_rx_queues(&self) -> u8 {
        self.fed.load(Ordering::Relaxed)
    }

    /// The FIFO frames `install_filters` released under `FINIT` (`RFOMx`).
    unsafe fn take_filter_switch_discards(&self) -> u32 {
        self.discarded.swap(0, Ordering::Relaxed)
    }

    /// `CAN_MSR`: `ERRI`, `WKUI`, `SLAKI` acknowledged; `CAN_ESR.LEC` reported and set
    /// to 0b111 so the next error is seen as new (notes "Error management").
    unsafe fn take_status(&self) -> StatusEvents {
        // Acknowledge first, then read the error register: an error latched after the
        // acknowledge raises ERRI again instead of being lost.
        let m = self.regs.read32(MSR);
        let ack = m & (msr::ERRI | msr::WKUI | msr::SLAKI);
        if ack != 0 {
            self.regs.write32(MSR, ack);
        }
        let e = self.regs.read32(ESR);
        let code = lec(esr::LEC.get(e));
        let bus_error = if code != LastErrorCode::None {
            self.last_error.store(code);
            self.regs.write32(ESR, esr::LEC.val(esr::LEC_SOFTWARE));
            Some(code)
        } else {
            None
        };
        StatusEvents {
            bus_error,
            status: self.status_now(),
            wakeup: m & msr::WKUI != 0,
        }
    }

    fn error_status(&self) -> ErrorStatus {
        self.status_now()
    }

    fn on_bus(&self) -> bool {
        self.regs.read32(MSR) & (msr::INAK | msr::SLAK) == 0
    }

    unsafe fn set_mode(&self, mode: Mode) -> Result<(), Error> {
        mode::request(&self.regs, mode, self.wait.load(Ordering::Relaxed))
    }

    /// Manual recovery (`ABOM` = 0): when bus-off, enter and leave initialization mode;
    /// the hardware then waits for 128 × 11 recessive bits. Refused with
    /// [`Error::WrongMode`] when recovery is automatic (nothing to start).
    unsafe fn recover(&self) -> Result<(), Error> {
        if self.config.get_recovery() == Recovery::Automatic {
            return Err(Error::WrongMode);
        }
        if self.regs.read32(ESR) & esr::BOFF == 0 {
            return Ok(());
        }
        let bound = self.wait.load(Ordering::Relaxed);
        mode::request(&self.regs, Mode::Stopped, bound)?;
        mode::request(&self.regs, Mode::Normal, bound)
    }

    /// The bit-timing rule every bxCAN entry point applies ([`crate::config::timing_rule`]
    /// of the [`Config`]'s APB1 clock, [`Config::get_clock_hz`]: [`Limits::BXCAN`]);
    /// the banks this instance owns now (`CAN2SB`, RM0410 §40.7.4): four 16-bit list
    /// identifiers (standard) or two 32-bit ones (extended) per bank; three transmit
    /// mailboxes, two receive FIFOs of three (§40.7.3, §40.7.5); no triple sampling;
    /// 16-bit time stamps only with `TTCM` (§40.7.8, [`Config::get_timestamps`]);
    /// wake-up events when `CAN_IER.WKUIE` is enabled (§40.8, `CAN_MSR.WKUI`).
    fn capabilities(&self) -> Capabilities {
        let (s, e) = self.bank_range();
        let banks = (e - s) as u16;
        Capabilities::new(
            self.config.get_clock_hz(),
            Limits::BXCAN,
            ModeSupport {
                loop_back: true,
                listen_only: true,
                one_shot: true,
                triple_sampling: false,
                manual_recovery: true,
                timestamps: true,
            },
            4 * banks,
            2 * banks,
            TX_MAILBOXES as u8,
            2,
            RX_FIFO_DEPTH as u8,
            self.config.get_timestamps().then_some(16),
        )
        .with_timing_rule(crate::config::timing_rule(self.config.get_clock_hz()))
        .with_wakeup_events(self.config.get_interrupts() & crate::regs::ier::WKUIE != 0)
    }

    /// `CAN_BTR.LBKM` (loop-back, silent or not) and `SILM`.
    fn bus_mode(&self) -> BusMode {
        let b = self.regs.read32(BTR);
        if b & btr::LBKM != 0 {
            BusMode::LoopBack
        } else if b & btr::SILM != 0 {
            BusMode::ListenOnly
        } else {
            BusMode::Normal
        }
    }

    fn bus_off_recovery(&self) -> BusOffRecovery {
        self.config.get_recovery()
    }

    /// In initialization mode only (`CAN_BTR` is writable only then, RM0410 §40.9.2):
    /// BRP, TS1, TS2, SJW; the mode bits stay. The acknowledge bound grows for a slower
    /// rate.
    unsafe fn set_timing(&self, timing: &Timing) -> Result<(), Error> {
        let stopped = mode::current(&self.regs) == Mode::Stopped;
        twocan_core::hardware::check_timing_for(&self.capabilities(), timing, stopped)?;
        let bits = timing.bxcan_btr().map_err(Error::Timing)?;
        self.regs
            .modify32(BTR, |v| (v & !BXCAN_BTR_TIMING_MASK) | bits);
        if let Ok(polls) =
            frame_in_flight_wait(timing.actual_bitrate(), self.config.get_clock_hz(), 2)
        {
            let polls = polls.min(u32::MAX as u64) as u32;
            self.wait.fetch_max(polls, Ordering::Relaxed);
        }
        Ok(())
    }

    /// In initialization mode only: `CAN_BTR.SILM` (listen-only), `LBKM` (loop-back).
    unsafe fn set_bus_mode(&self, mode: BusMode) -> Result<(), Error> {
        if mode::current(&self.regs) != Mode::Stopped {
            return Err(Error::WrongMode);
        }
        let bits = match mode {
            BusMode::Normal => 0,
            BusMode::ListenOnly => btr::SILM,
            BusMode::LoopBack => btr::LBKM,
        };
        self.regs
            .modify32(BTR, |v| (v & !(btr::SILM | btr::LBKM)) | bits);
        self.listen_only
            .store(mode == BusMode::ListenOnly, Ordering::Relaxed);
        Ok(())
    }
}
