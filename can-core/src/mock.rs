//! A mock [`Hardware`] for tests and examples of the split driver (feature `mock`).
//!
//! Plain memory behind one critical section: up to 8 transmit mailboxes chosen by the
//! policy, a receive FIFO of 3 frames that latches an overrun, an error status the test
//! sets. [`MockHardware::complete`] plays the bus: it "sends" the mailbox the policy
//! selects and, in loop-back, receives the frame back through the filters. A test double
//! for the portable driver, not a model of a real peripheral (those are in the backends).

use core::cell::RefCell;

use critical_section::Mutex;
use heapless::{Deque, Vec};

use crate::capabilities::{BusMode, BusOffRecovery, Capabilities, ModeSupport};
use crate::controller::{ErrorStatus, Mode};
use crate::error::{Error, ErrorCounters, ErrorState, LastErrorCode};
use crate::filter::Filter;
use crate::frame::{Frame, RxFrame};
use crate::hardware::{Completion, FifoEvents, Hardware, Settled, StatusEvents, Token};
use crate::mailbox::{MailboxId, MailboxState, TxOutcome, TxPolicy};

/// Mock filter list: portable filters matched in order (the first match gives the index).
pub type MockFilterList = Vec<Filter, 16>;

/// The CAN clock the mock reports ([`Hardware::capabilities`]).
pub const MOCK_CLOCK_HZ: u32 = 8_000_000;

/// Depth of the mock's receive FIFO.
pub const MOCK_FIFO_DEPTH: usize = 3;

#[derive(Debug, Clone, Copy)]
struct Mailbox {
    frame: Frame,
    token: Token,
    seq: u64,
}

#[derive(Debug)]
struct Inner {
    policy: TxPolicy,
    count: usize,
    mailboxes: [Option<Mailbox>; 8],
    ended: Deque<Settled, 16>,
    seq: u64,
    fifo: Deque<Frame, MOCK_FIFO_DEPTH>,
    overrun: bool,
    filters: MockFilterList,
    status: ErrorStatus,
    pending_error: Option<LastErrorCode>,
    mode: Mode,
    sent: Vec<Frame, 1024>,
    loopback: bool,
    fail_next: bool,
    bitrate: u32,
}

/// How many times [`block`] retries before it gives up.
pub const BLOCK_LIMIT: u32 = 10_000;

/// `nb::block!` with a bound, for tests and examples over the mock: retries `f` while it
/// returns `WouldBlock`, at most [`BLOCK_LIMIT`] times, then panics naming `what` it
/// waited for. Nothing runs between the retries (no interrupt, no bus), so a wait that
/// is not over at once is a bug, and it fails instead of spinning for ever. Firmware
/// waits with `nb::block!` (or services its interrupts meanwhile).
///
/// ```
/// use twocan_core::mock::{block, MockHardware};
/// use twocan_core::{Driver, Frame};
///
/// let mut can: Driver<MockHardware, 8, 4> = Driver::new(MockHardware::new(3));
/// let frame = Frame::standard(0x1, &[])?;
/// block("room for a frame", || can.try_send(&frame))?;
/// let waited = std::panic::catch_unwind(move || block("a frame", || can.receive()));
/// assert!(waited.is_err(), "nothing was received: the wait fails");
/// # Ok::<(), twocan_core::Error>(())
/// ```
#[track_caller]
pub fn block<T, E>(what: &str, mut f: impl FnMut() -> nb::Result<T, E>) -> Result<T, E> {
    for _ in 0..BLOCK_LIMIT {
        match f() {
            Ok(v) => return Ok(v),
            Err(nb::Error::Other(e)) => return Err(e),
            Err(nb::Error::WouldBlock) => {}
        }
    }
    panic!("still waiting for {what} after {BLOCK_LIMIT} tries (WouldBlock)")
}

/// An in-memory controller (see the [module docs](self)).
#[derive(Debug)]
pub struct MockHardware {
    inner: Mutex<RefCell<Inner>>,
}

impl MockHardware {
    /// `mailboxes` (1..=8) transmit mailboxes in request order, normal mode,
    /// error-active, a pass-all filter.
    pub fn new(mailboxes: usize) -> Self {
        let mut filters = Vec::new();
        let _ = filters.push(Filter::pass_all());
        MockHardware {
            inner: Mutex::new(RefCell::new(Inner {
                policy: TxPolicy::Fifo,
                count: mailboxes.clamp(1, 8),
                mailboxes: [None; 8],
                ended: Deque::new(),
                seq: 0,
                fifo: Deque::new(),
                overrun: false,
                filters,
                status: ErrorStatus {
                    state: ErrorState::Active,
                    counters: ErrorCounters::default(),
                    last_error: LastErrorCode::None,
                },
                pending_error: None,
                mode: Mode::Normal,
                sent: Vec::new(),
                loopback: false,
                fail_next: false,
                bitrate: 0,
            })),
        }
    }

    /// The same with `filters` installed (the first match gives the index).
    pub fn with_filters(self, filters: &[Filter]) -> Self {
        self.with(|m| m.filters = filters.iter().copied().take(16).collect());
        self
    }

    /// Forgets the frames sent so far.
    pub fn clear_sent(&self) {
        self.with(|m| m.sent.clear());
    }

    /// The same with identifier-priority transmit order.
    pub fn with_policy(self, policy: TxPolicy) -> Self {
        self.with(|m| m.policy = policy);
        self
    }

    /// The bit rate of the last timing [`Hardware::set_timing`] took (0: none yet).
    pub fn bitrate(&self) -> u32 {
        self.with(|m| m.bitrate)
    }

    /// Received frames come back (loop-back).
    pub fn with_loopback(self, on: bool) -> Self {
        self.with(|m| m.loopback = on);
        self
    }

    fn with<T>(&self, f: impl FnOnce(&mut Inner) -> T) -> T {
        critical_section::with(|cs| f(&mut self.inner.borrow_ref_mut(cs)))
    }

    /// "Sends" the mailbox the policy picks (its completion waits for the transmit
    /// handler); returns the frame. In loop-back the frame is also received.
    pub fn complete(&self) -> Option<Frame> {
        self.with(|m| {
            let mut best: Option<usize> = None;
            for i in 0..m.count {
                let Some(mb) = m.mailboxes[i] else { continue };
                let better = match best.and_then(|b| m.mailboxes[b]) {
                    None => true,
                    Some(b) => match m.policy {
                        TxPolicy::Fifo => mb.seq < b.seq,
                        TxPolicy::Priority => mb.frame.priority().beats(b.frame.priority()),
                    },
                };
                if better {
                    best = Some(i);
                }
            }
            let i = best?;
            let mb = m.mailboxes[i].take()?;
            let outcome = if m.fail_next {
                m.fail_next = false;
                TxOutcome::Failed
            } else {
                TxOutcome::Sent
            };
            let _ = m.ended.push_back(Settled::Done(Completion {
                token: mb.token,
                outcome,
                cause: None,
                timestamp: None,
            }));
            if outcome == TxOutcome::Sent {
                let _ = m.sent.push(mb.frame);
                if m.loopback {
                    Self::receive_into(m, mb.frame);
                }
            }
            Some(mb.frame)
        })
    }

    /// Sends every loaded mailbox; returns how many.
    pub fn complete_all(&self) -> usize {
        let mut n = 0;
        while self.complete().is_some() {
            n += 1;
        }
        n
    }

    /// The next [`MockHardware::complete`] fails (one-shot failure).
    pub fn fail_next(&self) {
        self.with(|m| m.fail_next = true);
    }

    fn receive_into(m: &mut Inner, frame: Frame) {
        if m.filters.iter().any(|f| f.matches(&frame)) && m.fifo.push_back(frame).is_err() {
            m.overrun = true;
        }
    }

    /// A frame arrives from the bus (through the filters).
    pub fn deliver(&self, frame: Frame) {
        self.with(|m| Self::receive_into(m, frame));
    }

    /// Sets the error status (and latches `last` as a new bus error).
    pub fn set_status(&self, state: ErrorState, tec: u16, rec: u16, last: LastErrorCode) {
        self.with(|m| {
            m.status = ErrorStatus {
                state,
                counters: ErrorCounters { tec, rec },
                last_error: last,
            };
            if last != LastErrorCode::None {
                m.pending_error = Some(last);
            }
        });
    }

    /// Frames sent so far, in order.
    pub fn sent(&self) -> Vec<Frame, 1024> {
        self.with(|m| m.sent.clone())
    }

    /// Frames waiting in the receive FIFO.
    pub fn fifo_len(&self) -> usize {
        self.with(|m| m.fifo.len())
    }

    /// Loaded mailboxes.
    pub fn loaded(&self) -> usize {
        self.with(|m| m.mailboxes.iter().filter(|x| x.is_some()).count())
    }
}

// SAFETY: every method goes through the one critical section around `Inner`, so calls
// from any contexts, overlapping or not, see a consistent mock.
unsafe impl Hardware for MockHardware {
    type Raw = Frame;
    type FilterMap = MockFilterList;
    type Filters = MockFilterList;

    fn tx_policy(&self) -> TxPolicy {
        self.with(|m| m.policy)
    }

    fn free_mailbox(&self, _frame: &Frame) -> Result<Option<u8>, Error> {
        self.with(|m| {
            if m.mode != Mode::Normal {
                return Err(Error::WrongMode);
            }
            // A mailbox is free once empty and its completion taken by `settle`.
            if m.ended.len() + m.count > m.ended.capacity() {
                return Ok(None);
            }
            Ok((0..m.count)
                .find(|&i| m.mailboxes[i].is_none())
                .map(|i| i as u8))
        })
    }

    unsafe fn load(&self, mailbox: u8, frame: &Frame, token: Token) {
        self.with(|m| {
            m.seq += 1;
            let seq = m.seq;
            m.mailboxes[mailbox as usize] = Some(Mailbox {
                frame: *frame,
                token,
                seq,
            });
        })
    }

    unsafe fn settle<F: FnMut(Settled)>(&self, mut f: F) {
        while let Some(s) = self.with(|m| m.ended.pop_front()) {
            f(s);
        }
    }

    /// Under the priority order, with every mailbox loaded: the lowest-priority one is
    /// emptied at once when `frame` beats it, and its frame handed back.
    unsafe fn displace(&self, frame: &Frame) -> bool {
        self.with(|m| {
            if m.policy != TxPolicy::Priority || m.mailboxes[..m.count].iter().any(|x| x.is_none())
            {
                return false;
            }
            let mut low = 0;
            for i in 1..m.count {
                let (a, b) = (m.mailboxes[i], m.mailboxes[low]);
                if let (Some(a), Some(b)) = (a, b) {
                    if !a.frame.priority().beats(b.frame.priority()) {
                        low = i;
                    }
                }
            }
            let Some(victim) = m.mailboxes[low] else {
                return false;
            };
            if !frame.priority().beats(victim.frame.priority()) {
                return false;
            }
            m.mailboxes[low] = None;
            let _ = m
                .ended
                .push_back(Settled::Displaced(victim.token, victim.frame));
            true
        })
    }

    fn mailbox_count(&self) -> u8 {
        self.with(|m| m.count as u8)
    }

    /// `Scheduled` for the loaded mailbox the policy sends next, `Pending` for the
    /// other loaded ones.
    fn mailbox_state(&self, mailbox: MailboxId) -> MailboxState {
        let i = mailbox.0 as usize;
        self.with(|m| {
            let Some(Some(me)) = m.mailboxes.get(i).filter(|_| i < m.count) else {
                return MailboxState::Empty;
            };
            let ahead = m.mailboxes[..m.count]
                .iter()
                .flatten()
                .any(|o| match m.policy {
                    TxPolicy::Fifo => o.seq < me.seq,
                    TxPolicy::Priority => o.frame.priority().beats(me.frame.priority()),
                });
            if ahead {
                MailboxState::Pending
            } else {
                MailboxState::Scheduled
            }
        })
    }

    unsafe fn request_abort(&self, token: Token) -> bool {
        self.with(|m| {
            for i in 0..m.count {
                if let Some(mb) = m.mailboxes[i] {
                    if mb.token == token {
                        m.mailboxes[i] = None;
                        let _ = m.ended.push_back(Settled::Done(Completion {
                            token,
                            outcome: TxOutcome::Aborted,
                            cause: None,
                            timestamp: None,
                        }));
                        return true;
                    }
                }
            }
            false
        })
    }

    unsafe fn abort_all_mailboxes(&self) {
        self.with(|m| {
            for i in 0..m.count {
                if let Some(mb) = m.mailboxes[i].take() {
                    let _ = m.ended.push_back(Settled::Done(Completion {
                        token: mb.token,
                        outcome: TxOutcome::Aborted,
                        cause: None,
                        timestamp: None,
                    }));
                }
            }
        })
    }

    unsafe fn read_rx(&self, _queue: usize, events: &mut FifoEvents) -> Option<Frame> {
        self.with(|m| {
            if m.overrun {
                m.overrun = false;
                events.overrun = true;
            }
            m.fifo.pop_front()
        })
    }

    unsafe fn decode(&self, raw: &Frame, map: &MockFilterList) -> Option<RxFrame> {
        let index = map.iter().position(|f| f.matches(raw))?;
        Some(RxFrame {
            frame: *raw,
            filter: index as u16,
            timestamp: None,
            hw_match: 0,
        })
    }

    unsafe fn install_filters(&self, filters: &MockFilterList) -> Result<MockFilterList, Error> {
        self.with(|m| m.filters = filters.clone());
        Ok(filters.clone())
    }

    unsafe fn filter_map(&self) -> MockFilterList {
        self.with(|m| m.filters.clone())
    }

    unsafe fn take_status(&self) -> StatusEvents {
        self.with(|m| StatusEvents {
            bus_error: m.pending_error.take(),
            status: m.status,
            wakeup: false,
        })
    }

    fn error_status(&self) -> ErrorStatus {
        self.with(|m| m.status)
    }

    fn on_bus(&self) -> bool {
        self.with(|m| m.mode == Mode::Normal)
    }

    unsafe fn set_mode(&self, mode: Mode) -> Result<(), Error> {
        self.with(|m| m.mode = mode);
        Ok(())
    }

    unsafe fn recover(&self) -> Result<(), Error> {
        Ok(())
    }

    /// An 8 MHz clock with the bxCAN timing limits, `MOCK_FIFO_DEPTH`, 16 filters.
    fn capabilities(&self) -> Capabilities {
        let count = self.with(|m| m.count) as u8;
        Capabilities::new(
            MOCK_CLOCK_HZ,
            crate::timing::Limits::BXCAN,
            ModeSupport {
                loop_back: true,
                listen_only: false,
                one_shot: false,
                triple_sampling: false,
                manual_recovery: true,
                timestamps: false,
            },
            16,
            16,
            count,
            1,
            MOCK_FIFO_DEPTH as u8,
            None,
        )
    }

    fn bus_mode(&self) -> BusMode {
        if self.with(|m| m.loopback) {
            BusMode::LoopBack
        } else {
            BusMode::Normal
        }
    }

    fn bus_off_recovery(&self) -> BusOffRecovery {
        BusOffRecovery::Manual
    }

    unsafe fn set_timing(&self, timing: &crate::timing::Timing) -> Result<(), Error> {
        let stopped = self.with(|m| m.mode == Mode::Stopped);
        crate::hardware::check_timing_for(&self.capabilities(), timing, stopped)?;
        self.with(|m| m.bitrate = timing.actual_bitrate());
        Ok(())
    }

    unsafe fn set_bus_mode(&self, mode: BusMode) -> Result<(), Error> {
        if !self.capabilities().modes.supports(mode) {
            return Err(Error::Unsupported);
        }
        self.with(|m| {
            if m.mode != Mode::Stopped {
                return Err(Error::WrongMode);
            }
            m.loopback = mode == BusMode::LoopBack;
            Ok(())
        })
    }
}
