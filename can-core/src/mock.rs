//! A mock [`Controller`] for trait tests and host examples (feature `mock`).
//!
//! It keeps frames in plain memory: `M` transmit mailboxes chosen by the controller's
//! policy, a hardware receive FIFO of `F` frames that counts overruns, and an error status
//! the test sets. [`MockController::complete`] plays the bus: it "sends" the mailbox the
//! policy selects and, in loop-back, receives the frame back. It is a test double for the
//! generic driver, not a model of any real peripheral (those live in the backends).

use heapless::{Deque, Vec};

use crate::controller::{Controller, ErrorStatus, Events, Mode};
use crate::error::{Error, ErrorCounters, ErrorState, LastErrorCode};
use crate::filter::Filter;
use crate::frame::{Frame, RxFrame};
use crate::mailbox::{MailboxId, MailboxState, TxPolicy};

/// Mock filter list: portable filters matched in order (the first match gives the index).
pub type MockFilters = Vec<Filter, 16>;

/// An in-memory controller with `M` mailboxes and a receive FIFO of `F` frames.
#[derive(Debug)]
pub struct MockController<const M: usize, const F: usize> {
    policy: TxPolicy,
    mailboxes: [Option<(u64, Frame)>; M],
    seq: u64,
    fifo: Deque<RxFrame, F>,
    filters: MockFilters,
    events: Events,
    status: ErrorStatus,
    mode: Mode,
    /// Frames "sent" on the bus, in order.
    pub sent: Vec<Frame, 1024>,
    /// Whether sent frames are received back through the filters.
    pub loopback: bool,
    /// Frames dropped because the FIFO was full. The mock reports each as one overrun
    /// event, so here frames and `ErrorStatistics::hardware_overruns` occurrences agree.
    pub overruns: u32,
}

impl<const M: usize, const F: usize> MockController<M, F> {
    /// A controller in normal mode, error-active, with a pass-all filter.
    pub fn new(policy: TxPolicy) -> Self {
        let mut filters = Vec::new();
        let _ = filters.push(Filter::pass_all());
        MockController {
            policy,
            mailboxes: [None; M],
            seq: 0,
            fifo: Deque::new(),
            filters,
            events: Events::default(),
            status: ErrorStatus {
                state: ErrorState::Active,
                counters: ErrorCounters::default(),
                last_error: LastErrorCode::None,
            },
            mode: Mode::Normal,
            sent: Vec::new(),
            loopback: false,
            overruns: 0,
        }
    }

    fn next_mailbox(&self) -> Option<usize> {
        let mut best: Option<usize> = None;
        for (i, m) in self.mailboxes.iter().enumerate() {
            let Some((seq, frame)) = m else { continue };
            let better = match best.and_then(|b| self.mailboxes[b].map(|x| (b, x))) {
                None => true,
                Some((_, (bseq, bframe))) => match self.policy {
                    TxPolicy::Fifo => *seq < bseq,
                    TxPolicy::Priority => frame.priority().beats(bframe.priority()),
                },
            };
            if better {
                best = Some(i);
            }
        }
        best
    }

    /// Sends the mailbox the policy selects; returns the frame sent.
    pub fn complete(&mut self) -> Option<Frame> {
        if self.mode != Mode::Normal || self.status.state == ErrorState::BusOff {
            return None;
        }
        let i = self.next_mailbox()?;
        let (_, frame) = self.mailboxes[i].take()?;
        let _ = self.sent.push(frame);
        self.events.sent = self.events.sent.saturating_add(1);
        if self.loopback {
            self.deliver(frame);
        }
        Some(frame)
    }

    /// A frame arrives from the bus: filtered, then stored or counted as an overrun.
    pub fn deliver(&mut self, frame: Frame) {
        let Some(index) = self.filters.iter().position(|f| f.matches(&frame)) else {
            return;
        };
        let rx = RxFrame {
            frame,
            filter: index as u16,
            timestamp: None,
        };
        if self.fifo.push_back(rx).is_err() {
            self.overruns += 1;
            self.events.overruns = self.events.overruns.saturating_add(1);
        }
    }

    /// Sets the error status the controller reports, flagging a state change.
    pub fn set_status(&mut self, state: ErrorState, tec: u16, rec: u16, last: LastErrorCode) {
        self.status = ErrorStatus {
            state,
            counters: ErrorCounters { tec, rec },
            last_error: last,
        };
        self.events.state_changed = true;
        if last != LastErrorCode::None {
            self.events.bus_error = Some(last);
        }
    }

    /// Replaces the filter list (as `install_filters` does) from test code.
    pub fn install_filters_for_test(&mut self, filters: &MockFilters) {
        let _ = Controller::install_filters(self, filters);
    }

    /// Frames waiting in the hardware FIFO.
    pub fn fifo_len(&self) -> usize {
        self.fifo.len()
    }
}

impl<const M: usize, const F: usize> Controller for MockController<M, F> {
    type Filters = MockFilters;

    fn install_filters(&mut self, filters: &MockFilters) -> Result<(), Error> {
        for f in filters {
            f.check()?;
        }
        self.filters = filters.clone();
        Ok(())
    }

    fn tx_policy(&self) -> TxPolicy {
        self.policy
    }

    fn mailbox_count(&self) -> u8 {
        M as u8
    }

    fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, Error> {
        if self.mode != Mode::Normal {
            return Err(nb::Error::Other(Error::WrongMode));
        }
        self.seq += 1;
        if let Some(slot) = self.mailboxes.iter_mut().find(|m| m.is_none()) {
            *slot = Some((self.seq, *frame));
            return Ok(None);
        }
        if self.policy == TxPolicy::Priority {
            // Displace the lowest-priority mailbox if `frame` beats it.
            let (i, lowest) = self
                .mailboxes
                .iter()
                .enumerate()
                .filter_map(|(i, m)| m.map(|(_, f)| (i, f)))
                .max_by_key(|(_, f)| f.priority())
                .ok_or(nb::Error::WouldBlock)?;
            if frame.priority().beats(lowest.priority()) {
                self.mailboxes[i] = Some((self.seq, *frame));
                return Ok(Some(lowest));
            }
        }
        Err(nb::Error::WouldBlock)
    }

    fn mailbox_state(&self, mailbox: MailboxId) -> MailboxState {
        match self.mailboxes.get(mailbox.0 as usize) {
            Some(Some(_)) if self.next_mailbox() == Some(mailbox.0 as usize) => {
                MailboxState::Scheduled
            }
            Some(Some(_)) => MailboxState::Pending,
            _ => MailboxState::Empty,
        }
    }

    fn abort(&mut self, mailbox: MailboxId) -> bool {
        match self.mailboxes.get_mut(mailbox.0 as usize) {
            Some(slot @ Some(_)) => {
                *slot = None;
                self.events.aborted = self.events.aborted.saturating_add(1);
                true
            }
            _ => false,
        }
    }

    fn receive(&mut self) -> nb::Result<RxFrame, Error> {
        self.fifo.pop_front().ok_or(nb::Error::WouldBlock)
    }

    fn take_events(&mut self) -> Events {
        core::mem::take(&mut self.events)
    }

    fn error_status(&self) -> ErrorStatus {
        match self.mode {
            Mode::Normal => self.status,
            Mode::Stopped => ErrorStatus {
                state: ErrorState::Stopped,
                ..self.status
            },
            Mode::Sleep => ErrorStatus {
                state: ErrorState::Sleeping,
                ..self.status
            },
        }
    }

    fn set_mode(&mut self, mode: Mode) -> Result<(), Error> {
        self.mode = mode;
        Ok(())
    }

    fn recover(&mut self) -> Result<(), Error> {
        if self.status.state == ErrorState::BusOff {
            self.set_status(ErrorState::Active, 0, 0, LastErrorCode::None);
        }
        Ok(())
    }
}
