//! The FlexCAN [`Controller`]: what twocan-core's generic driver needs, over the
//! registers (ACAN §3 data flow, §8–§10, §17).
//!
//! # Mailboxes and transmit order
//!
//! Data frames go through MB15, the one data mailbox (ACAN §3 table 1): the driver's
//! transmit ring is first-in first-out ([`TxPolicy::Fifo`]) and holds the next frame
//! until MB15 is free again, so data frames leave strictly in the order given to
//! `try_send` (ACAN §3 "sequentiality"). Remote frames go to the first free
//! remote-frame mailbox of the configuration (7, 5, 3 or 1, ACAN §9); on the bus
//! they compete with the pending data frame by identifier priority (`CTRL1.LBUF`
//! = 0), so, as in ACAN, there is no order between a remote frame and data frames.
//! [`Controller::transmit`] answers `WouldBlock` when the mailbox kind the frame
//! needs is busy. Through [`twocan_core::Driver::try_send`], a frame joins the ring
//! behind any frame already queued (the ring never reorders); calling
//! `driver.controller_mut().transmit(&remote)` sends a remote frame straight to a
//! free remote mailbox, never queued — ACAN's behaviour for remote frames.
//!
//! [`MailboxId`] numbering: `MailboxId(0)` is MB15 (data), `MailboxId(1..=n)` the
//! remote-frame mailboxes in increasing MB order.
//!
//! After sending a remote frame the hardware turns its mailbox into a receive
//! mailbox for the answer (Kinetis RM, "Tx CODE 1100 with RTR = 1"); the Rx FIFO is
//! matched first (`CTRL2.MRP` = 0) and the driver deactivates the mailbox when it
//! accounts the transmission, so answers reach the application through the filters
//! only.
//!
//! # Receiving
//!
//! [`Controller::receive`] reads the Rx FIFO output (MB0), the `RXFIR.IDHIT` of the
//! element that accepted it, then pops the FIFO by writing 1 to `IFLAG1.BUF5I` (the
//! reading order of the reference manual). `IDHIT` becomes the user's filter index
//! through [`FilterTable::filter_index`] (an `IDHIT` that maps to no filter gives
//! [`crate::UNKNOWN_FILTER`] and is counted, see [`FlexCan::unresolved_filter_hits`]);
//! the TIME STAMP field becomes
//! [`RxFrame::timestamp`]. A FIFO overflow (`IFLAG1.BUF7I`: at least one frame lost,
//! the hardware does not count them) is reported as one overrun.

use core::cell::Cell;

use twocan_core::{
    Controller, Error, ErrorCounters, ErrorState, ErrorStatus, Events, Frame, LastErrorCode,
    MailboxId, MailboxState, Mode, Registers, RxFrame, TxPolicy,
};

use crate::configuration::{Configuration, DATA_MAILBOX};
use crate::filters::{FilterTable, UNKNOWN_FILTER};
use crate::handshake;
use crate::instance::Target;
use crate::message_buffer::MbWords;
use crate::regs::{self, code, cs, esr1, iflag1, rxfir, ECR, ESR1, IFLAG1, RXFIR, TIMER};
use crate::status;

/// What settling a mailbox found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Settled {
    /// No completion to account.
    Nothing,
    /// The transmission ended on the bus.
    Sent,
    /// The transmission was aborted.
    Aborted,
}

/// A configured FlexCAN module (the value `begin` returns), over registers `R`.
///
/// It implements [`Controller`]; wrap it in [`twocan_core::Driver`] (or
/// [`crate::AcanDriver`] for ACAN's buffer sizes) to get ACAN's `tryToSend`,
/// `receive`, `dispatchReceivedMessage` and buffer statistics.
#[derive(Debug)]
pub struct FlexCan<R: Registers> {
    pub(crate) regs: R,
    pub(crate) target: Target,
    pub(crate) table: FilterTable,
    pub(crate) listen_only: bool,
    pub(crate) polls: u32,
    pub(crate) irq_priority: u8,
    pub(crate) mode: Mode,
    /// Mailboxes loaded for transmission whose end has not been accounted (bit n: MBn).
    pub(crate) in_flight: u16,
    /// Completions accounted outside `take_events` (when a mailbox is reused).
    pub(crate) pending: Events,
    /// The newest error `ESR1` reported.
    pub(crate) last_error: Cell<LastErrorCode>,
    /// An error read from `ESR1` not yet handed out by `take_events`.
    pub(crate) unreported_error: Cell<Option<LastErrorCode>>,
    /// `ESR1.FLTCONF` as `take_events` last saw it.
    pub(crate) fault: u32,
    /// Frames received with an `IDHIT` that maps to no filter.
    pub(crate) unresolved_hits: u32,
}

impl<R: Registers> FlexCan<R> {
    pub(crate) fn configured(
        regs: R,
        target: Target,
        table: FilterTable,
        listen_only: bool,
        polls: u32,
        irq_priority: u8,
    ) -> Self {
        FlexCan {
            regs,
            target,
            table,
            listen_only,
            polls,
            irq_priority,
            mode: Mode::Normal,
            in_flight: 0,
            pending: Events::default(),
            last_error: Cell::new(LastErrorCode::None),
            unreported_error: Cell::new(None),
            fault: esr1::FLTCONF_ERROR_ACTIVE,
            unresolved_hits: 0,
        }
    }

    /// The module and board this controller drives.
    pub const fn target(&self) -> Target {
        self.target
    }

    /// The message-buffer partition (ACAN §11).
    pub const fn configuration(&self) -> Configuration {
        self.table.configuration()
    }

    /// The installed filters (ACAN §12–§13), with the filter numbering.
    pub const fn filters(&self) -> &FilterTable {
        &self.table
    }

    /// The message interrupt priority of the settings (ACAN §16.7.4), for the NVIC.
    pub const fn message_irq_priority(&self) -> u8 {
        self.irq_priority
    }

    /// The mode the controller was last put in.
    pub const fn mode(&self) -> Mode {
        self.mode
    }

    /// The registers (for the model's inspection methods in tests).
    pub const fn registers(&self) -> &R {
        &self.regs
    }

    /// The registers, mutably (for the model's bus and fault-injection methods).
    pub fn registers_mut(&mut self) -> &mut R {
        &mut self.regs
    }

    /// Frames received whose `RXFIR.IDHIT` maps to none of the installed filters (beyond
    /// the table, which the hardware does not produce): they were handed out with
    /// filter index [`crate::UNKNOWN_FILTER`] rather than a wrong index. Saturates.
    pub const fn unresolved_filter_hits(&self) -> u32 {
        self.unresolved_hits
    }

    /// Gives the registers back.
    pub fn into_registers(self) -> R {
        self.regs
    }

    /// The free-running timer (`TIMER`, one count per bit time): the time base of
    /// [`RxFrame::timestamp`].
    pub fn timer(&self) -> u16 {
        regs::timer::TIMER.get(self.regs.read32(TIMER)) as u16
    }

    /// The transmit mailboxes: the remote-frame ones, then MB15.
    fn tx_mailboxes(&self) -> core::ops::RangeInclusive<usize> {
        self.configuration().first_remote_mailbox() as usize..=DATA_MAILBOX as usize
    }

    /// The message buffer behind a [`MailboxId`] (see the module docs).
    fn mailbox(&self, id: MailboxId) -> Option<usize> {
        let c = self.configuration();
        match id.0 {
            0 => Some(DATA_MAILBOX as usize),
            k if k <= c.remote_mailbox_count() => Some((c.first_remote_mailbox() + k - 1) as usize),
            _ => None,
        }
    }

    /// Accounts the end of mailbox `mb`'s transmission if its flag is up, acknowledges
    /// the flag and leaves the mailbox inactive.
    fn settle(&mut self, mb: usize) -> Settled {
        let flag = iflag1::buf(mb);
        if self.regs.read32(IFLAG1) & flag == 0 {
            return Settled::Nothing;
        }
        let code = cs::CODE.get(self.regs.read32(regs::mb_cs(mb)));
        let bit = 1u16 << mb;
        let outcome = if self.in_flight & bit == 0 {
            Settled::Nothing
        } else if code == code::TX_ABORT {
            self.pending.aborted = self.pending.aborted.saturating_add(1);
            Settled::Aborted
        } else {
            self.pending.sent = self.pending.sent.saturating_add(1);
            Settled::Sent
        };
        self.in_flight &= !bit;
        self.regs.write32(IFLAG1, flag);
        // A remote-frame mailbox is now an Rx mailbox (or an aborted one shows ABORT):
        // deactivate it.
        if !matches!(code, code::TX_INACTIVE | code::TX_DATA | code::TX_TANSWER) {
            self.regs
                .write32(regs::mb_cs(mb), cs::CODE.val(code::TX_INACTIVE));
        }
        outcome
    }

    /// Whether mailbox `mb` may be loaded (accounting a finished transmission first).
    fn is_free(&mut self, mb: usize) -> bool {
        self.settle(mb);
        self.in_flight & (1 << mb) == 0
    }

    /// Loads `frame` into the free mailbox `mb` and requests its transmission
    /// (reference manual "Transmit process": ID and data, then the control word).
    fn load(&mut self, mb: usize, frame: &Frame) {
        if cs::CODE.get(self.regs.read32(regs::mb_cs(mb))) != code::TX_INACTIVE {
            self.regs
                .write32(regs::mb_cs(mb), cs::CODE.val(code::TX_INACTIVE));
        }
        MbWords::transmit(frame).write(&mut self.regs, mb);
        self.in_flight |= 1 << mb;
    }

    /// Reads `ESR1` (which clears its error bits) and keeps the error it reports.
    fn read_esr1(&self) -> u32 {
        let value = self.regs.read32(ESR1);
        if let Some(code) = status::last_error(value) {
            self.last_error.set(code);
            self.unreported_error.set(Some(code));
        }
        value
    }

    /// Writes the filter table and masks (freeze mode).
    pub(crate) fn write_filters(regs: &R, table: &FilterTable) {
        for (i, e) in table.elements().iter().enumerate() {
            regs.write32(regs::rx_fifo_filter(i), *e);
        }
        for (i, m) in table.individual_masks().iter().enumerate() {
            regs.write32(regs::rximr(i), *m);
        }
        regs.write32(regs::RXFGMASK, table.global_mask());
    }
}

impl<R: Registers> Controller for FlexCan<R> {
    type Filters = FilterTable;

    /// Rewrites the ID filter table and masks in freeze mode, then restores the mode.
    /// The table must be compiled for the controller's [`Configuration`]
    /// ([`Error::InvalidArgument`] otherwise): the partition of the message buffers is
    /// fixed by `begin`. Frames already in the Rx FIFO carry the `IDHIT` of the old
    /// table: service the interrupt before, for exact indices.
    fn install_filters(&mut self, filters: &FilterTable) -> Result<(), Error> {
        if filters.configuration() != self.configuration() {
            return Err(Error::InvalidArgument);
        }
        let previous = self.mode;
        self.set_mode(Mode::Stopped)?;
        Self::write_filters(&mut self.regs, filters);
        self.table = filters.clone();
        self.set_mode(previous)
    }

    fn tx_policy(&self) -> TxPolicy {
        TxPolicy::Fifo
    }

    /// One data mailbox plus the remote-frame mailboxes.
    fn mailbox_count(&self) -> u8 {
        1 + self.configuration().remote_mailbox_count()
    }

    /// Data frame: into MB15 when it is free. Remote frame: into the first free
    /// remote-frame mailbox. `WouldBlock` when that kind is busy;
    /// [`Error::WrongMode`] in listen-only mode (the module does not transmit) and
    /// while disabled ([`Mode::Sleep`]). Never displaces a frame.
    fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, Error> {
        if self.listen_only || self.mode == Mode::Sleep {
            return Err(nb::Error::Other(Error::WrongMode));
        }
        let candidates = if frame.is_remote() {
            self.configuration().first_remote_mailbox() as usize..DATA_MAILBOX as usize
        } else {
            DATA_MAILBOX as usize..DATA_MAILBOX as usize + 1
        };
        for mb in candidates {
            if self.is_free(mb) {
                self.load(mb, frame);
                return Ok(None);
            }
        }
        Err(nb::Error::WouldBlock)
    }

    /// `Empty` or `Pending`: FlexCAN does not tell which loaded mailbox is on the bus.
    fn mailbox_state(&self, mailbox: MailboxId) -> MailboxState {
        let Some(mb) = self.mailbox(mailbox) else {
            return MailboxState::Empty;
        };
        let done = self.regs.read32(IFLAG1) & iflag1::buf(mb) != 0;
        if self.in_flight & (1 << mb) == 0 || done {
            MailboxState::Empty
        } else {
            MailboxState::Pending
        }
    }

    /// Writes the ABORT code (`MCR.AEN` = 1) and waits, bounded, for the mailbox's
    /// flag: `true` if it was aborted, `false` if it was not pending, was sent
    /// meanwhile, or is still on the bus when the bound expires (its end is then
    /// accounted by [`Controller::take_events`]).
    fn abort(&mut self, mailbox: MailboxId) -> bool {
        let Some(mb) = self.mailbox(mailbox) else {
            return false;
        };
        if self.mode == Mode::Sleep || self.is_free(mb) {
            return false;
        }
        let control = self.regs.read32(regs::mb_cs(mb));
        self.regs
            .write32(regs::mb_cs(mb), cs::CODE.replace(control, code::TX_ABORT));
        for _ in 0..self.polls.max(1) {
            match self.settle(mb) {
                Settled::Aborted => return true,
                Settled::Sent => return false,
                Settled::Nothing => {}
            }
        }
        false
    }

    fn receive(&mut self) -> nb::Result<RxFrame, Error> {
        if self.mode == Mode::Sleep || self.regs.read32(IFLAG1) & iflag1::BUF5I == 0 {
            return Err(nb::Error::WouldBlock);
        }
        let words = MbWords::read(&self.regs, 0);
        let hit = rxfir::IDHIT.get(self.regs.read32(RXFIR)) as usize;
        self.regs.write32(IFLAG1, iflag1::BUF5I);
        let frame = words
            .frame()
            .map_err(|e| nb::Error::Other(Error::Frame(e)))?;
        let filter = self.table.filter_index(hit, &frame).unwrap_or_else(|| {
            self.unresolved_hits = self.unresolved_hits.saturating_add(1);
            UNKNOWN_FILTER
        });
        Ok(RxFrame {
            frame,
            filter,
            timestamp: Some(words.timestamp()),
        })
    }

    fn take_events(&mut self) -> Events {
        if self.mode != Mode::Sleep {
            for mb in self.tx_mailboxes() {
                self.settle(mb);
            }
            let flags = self.regs.read32(IFLAG1);
            if flags & iflag1::BUF7I != 0 {
                self.pending.overruns = self.pending.overruns.saturating_add(1);
            }
            let fifo_acks = flags & (iflag1::BUF6I | iflag1::BUF7I);
            if fifo_acks != 0 {
                self.regs.write32(IFLAG1, fifo_acks);
            }
            let esr = self.read_esr1();
            if esr & esr1::W1C_BITS != 0 {
                self.regs.write32(ESR1, esr & esr1::W1C_BITS);
            }
            let fault = regs::esr1::FLTCONF.get(esr);
            let transitions = esr1::BOFFINT | esr1::TWRNINT | esr1::RWRNINT;
            if fault != self.fault || esr & transitions != 0 {
                self.pending.state_changed = true;
                self.fault = fault;
            }
            if esr & esr1::WAKINT != 0 {
                self.pending.wakeup = true;
            }
        }
        let mut events = core::mem::take(&mut self.pending);
        events.bus_error = self.unreported_error.take();
        events
    }

    /// ACAN §17: error active / passive / bus-off (plus warning from the counters),
    /// REC, TEC — 256 while bus-off. `Stopped` in freeze mode, `Sleeping` while
    /// disabled (counters then read as 0: the module is not clocked).
    fn error_status(&self) -> ErrorStatus {
        if self.mode == Mode::Sleep {
            return ErrorStatus {
                state: ErrorState::Sleeping,
                counters: ErrorCounters::default(),
                last_error: self.last_error.get(),
            };
        }
        let esr = self.read_esr1();
        let (state, counters) = status::decode(esr, self.regs.read32(ECR));
        let state = if self.mode == Mode::Stopped {
            ErrorState::Stopped
        } else {
            state
        };
        ErrorStatus {
            state,
            counters,
            last_error: self.last_error.get(),
        }
    }

    /// `Normal`: on the bus — out of freeze and synchronised to it (`ESR1.SYNCH`, 11
    /// recessive bits; internal in loop-back mode), so a frame starting after the
    /// return is received. If the module leaves freeze but does not synchronise within
    /// the bound (a bus stuck dominant), the mode is `Normal` and the result
    /// [`Error::Timeout`]; errors `ESR1` reports meanwhile are kept. `Stopped`: freeze
    /// mode. `Sleep`: module disabled (`MDIS`, low-power acknowledge). Each step
    /// waits, bounded, for its acknowledge bit ([`Error::Timeout`]); asking again for
    /// the same mode repeats the request, so a change that timed out can be retried.
    fn set_mode(&mut self, mode: Mode) -> Result<(), Error> {
        let polls = self.polls;
        // From the hardware, not from the last request: a timed-out change may have
        // completed since.
        let disabled = self.regs.read32(regs::MCR) & (regs::mcr::MDIS | regs::mcr::LPMACK) != 0;
        if disabled && mode != Mode::Sleep {
            handshake::enable(&mut self.regs, polls)?;
        }
        match mode {
            Mode::Normal => {
                handshake::leave_freeze(&mut self.regs, polls)?;
                // Out of freeze: the module runs, even if it does not synchronise in time.
                self.mode = mode;
                let (last, unreported) = (&self.last_error, &self.unreported_error);
                return handshake::wait_synch(&self.regs, polls, |esr| {
                    if let Some(code) = status::last_error(esr) {
                        last.set(code);
                        unreported.set(Some(code));
                    }
                });
            }
            Mode::Stopped => handshake::freeze(&mut self.regs, polls)?,
            Mode::Sleep => handshake::disable(&mut self.regs, polls)?,
        }
        self.mode = mode;
        Ok(())
    }

    /// Recovery from bus-off is automatic (`CTRL1.BOFFREC` = 0, after 128 × 11
    /// recessive bits): nothing to do.
    fn recover(&mut self) -> Result<(), Error> {
        Ok(())
    }
}
