//! The generic driver: one API over every controller.
//!
//! [`Driver`] owns a [`Controller`] and two software rings: the transmit queue in front of
//! the mailboxes and the receive ring behind the hardware FIFO. Thread code calls
//! [`Driver::try_send`], [`Driver::receive`] and [`Driver::dispatch`]; the interrupt
//! handler calls [`Driver::on_interrupt`], which moves frames between the hardware and the
//! rings and never blocks.
//!
//! Transmit order: under [`TxPolicy::Fifo`] frames leave in the order handed to
//! `try_send` (a frame never overtakes one queued before it: while the queue holds
//! anything, new frames join its tail). Under [`TxPolicy::Priority`] the queue is
//! ordered by arbitration priority and the backend may displace a lower-priority
//! mailbox, so a high-priority frame never waits behind lower ones.
//!
//! In firmware the driver lives in a `critical_section::Mutex<RefCell<Option<Driver>>>`
//! shared by the interrupt handler and thread code.

use crate::buffer::{BufferStats, Ring, TxQueue};
use crate::controller::{Controller, ErrorStatus, Events, Mode};
use crate::dispatch::Dispatcher;
use crate::error::{Error, ErrorCounters, ErrorState, ErrorStatistics, LastErrorCode};
use crate::frame::{Frame, RxFrame};
use crate::mailbox::{MailboxId, MailboxState, TxPolicy};

/// Traffic counters kept by the driver (saturating).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TrafficStats {
    /// Frames accepted by `try_send`.
    pub queued: u32,
    /// Frames the controller reported sent.
    pub sent: u32,
    /// Frames that failed (one-shot mode).
    pub failed: u32,
    /// Frames aborted on request (including queued frames dropped by `abort_all`).
    pub aborted: u32,
    /// Frames taken from the hardware into the receive ring.
    pub received: u32,
    /// Frames lost because the receive ring was full.
    pub rx_ring_overflows: u32,
    /// Error-state transitions observed.
    pub state_changes: u32,
}

/// The portable CAN driver over controller `C`, with a receive ring of `RX` frames and a
/// transmit queue of `TX` frames.
pub struct Driver<C: Controller, const RX: usize, const TX: usize> {
    controller: C,
    rx: Ring<RxFrame, RX>,
    tx: TxQueue<TX>,
    traffic: TrafficStats,
    errors: ErrorStatistics,
    state: ErrorState,
    state_change: Option<ErrorState>,
}

impl<C: Controller, const RX: usize, const TX: usize> Driver<C, RX, TX> {
    /// Wraps a configured controller; the transmit queue takes the controller's policy.
    pub fn new(controller: C) -> Self {
        const {
            assert!(
                RX > 0 && TX > 0,
                "the receive and transmit rings need room for a frame"
            )
        };
        let state = controller.error_status().state;
        Driver {
            tx: TxQueue::new(controller.tx_policy()),
            controller,
            rx: Ring::new(),
            traffic: TrafficStats::default(),
            errors: ErrorStatistics::default(),
            state,
            state_change: None,
        }
    }

    /// The controller (for backend-specific operations).
    pub fn controller(&self) -> &C {
        &self.controller
    }

    /// The controller, mutably (for backend-specific operations).
    pub fn controller_mut(&mut self) -> &mut C {
        &mut self.controller
    }

    /// Gives the controller back.
    pub fn release(self) -> C {
        self.controller
    }

    /// Queues `frame` for transmission (ACAN `tryToSend`).
    ///
    /// `WouldBlock` when the transmit queue is full; that rejection is counted in
    /// [`Driver::tx_stats`] (`overflows`, and `peak` becomes size + 1).
    pub fn try_send(&mut self, frame: &Frame) -> nb::Result<(), Error> {
        if self.state == ErrorState::BusOff {
            // Recovery (automatic, or by another path) raises no interrupt on every
            // controller: read the state again before refusing.
            self.track_state();
            if self.state == ErrorState::BusOff {
                return Err(nb::Error::Other(Error::BusOff));
            }
        }
        if self.tx.is_empty() {
            match self.controller.transmit(frame) {
                Ok(displaced) => {
                    self.traffic.queued = self.traffic.queued.saturating_add(1);
                    if let Some(old) = displaced {
                        // Room is guaranteed: the queue was empty.
                        let _ = self.tx.requeue(old);
                    }
                    return Ok(());
                }
                Err(nb::Error::WouldBlock) => {}
                Err(nb::Error::Other(e)) => return Err(nb::Error::Other(e)),
            }
        }
        if self.tx.is_full() {
            // Make what progress the hardware allows without waiting for the interrupt
            // (completed mailboxes refilled from the queue), so that polling `try_send`
            // with interrupts off, as `nb::block!` does, cannot spin for ever.
            self.on_interrupt();
        }
        match self.tx.push(*frame) {
            Ok(()) => {
                self.traffic.queued = self.traffic.queued.saturating_add(1);
                // A higher-priority frame may displace a pending mailbox now.
                self.pump_tx().map_err(nb::Error::Other)?;
                Ok(())
            }
            Err(_) => Err(nb::Error::WouldBlock),
        }
    }

    /// Takes the oldest frame of the receive ring. `WouldBlock` when it is empty.
    pub fn receive(&mut self) -> nb::Result<RxFrame, Error> {
        self.rx.pop().ok_or(nb::Error::WouldBlock)
    }

    /// Takes one received frame and hands it to its filter's call-back (ACAN
    /// `dispatchReceivedMessage`). Returns whether a frame was taken from the ring; a frame
    /// without call-back is counted by the dispatcher.
    pub fn dispatch<Ctx, const N: usize>(
        &mut self,
        dispatcher: &mut Dispatcher<Ctx, N>,
        ctx: &mut Ctx,
    ) -> bool {
        match self.rx.pop() {
            Some(frame) => {
                dispatcher.dispatch(ctx, &frame);
                true
            }
            None => false,
        }
    }

    /// The interrupt handler's work: acknowledge causes, drain the hardware receive FIFO(s)
    /// into the ring, refill free mailboxes from the queue, track the error state.
    /// Never blocks. Also usable by polling from thread code.
    pub fn on_interrupt(&mut self) {
        let events = self.controller.take_events();
        self.account(&events);
        self.drain_rx();
        // Errors of `transmit` here are faults of the controller state (bus-off, wrong
        // mode): the frames stay queued and the state tracking below reports the cause.
        let _ = self.pump_tx();
        self.track_state();
    }

    fn account(&mut self, e: &Events) {
        let t = &mut self.traffic;
        t.sent = t.sent.saturating_add(e.sent as u32);
        t.failed = t.failed.saturating_add(e.failed as u32);
        t.aborted = t.aborted.saturating_add(e.aborted as u32);
        if let Some(code) = e.bus_error {
            self.errors.record(code);
        }
        self.errors.hardware_overruns = self
            .errors
            .hardware_overruns
            .saturating_add(e.overruns as u32);
    }

    fn drain_rx(&mut self) {
        loop {
            match self.controller.receive() {
                Ok(frame) => {
                    self.traffic.received = self.traffic.received.saturating_add(1);
                    if self.rx.push(frame).is_err() {
                        self.traffic.rx_ring_overflows =
                            self.traffic.rx_ring_overflows.saturating_add(1);
                    }
                }
                Err(nb::Error::WouldBlock) => break,
                // A receive fault (overrun reported inline) is already counted by events.
                Err(nb::Error::Other(_)) => break,
            }
        }
    }

    fn pump_tx(&mut self) -> Result<(), Error> {
        while let Some(next) = self.tx.pop() {
            match self.controller.transmit(&next) {
                Ok(None) => {}
                Ok(Some(displaced)) => {
                    // One slot was just freed by the pop above.
                    let _ = self.tx.requeue(displaced);
                }
                Err(nb::Error::WouldBlock) => {
                    let _ = self.tx.requeue(next);
                    return Ok(());
                }
                Err(nb::Error::Other(e)) => {
                    let _ = self.tx.requeue(next);
                    return Err(e);
                }
            }
        }
        Ok(())
    }

    fn track_state(&mut self) {
        let now = self.controller.error_status().state;
        if now != self.state {
            if now == ErrorState::BusOff {
                self.errors.bus_off = self.errors.bus_off.saturating_add(1);
            }
            self.state = now;
            self.state_change = Some(now);
            self.traffic.state_changes = self.traffic.state_changes.saturating_add(1);
        }
    }

    /// The newest error-state change since the last call, if any.
    pub fn take_state_change(&mut self) -> Option<ErrorState> {
        self.state_change.take()
    }

    /// The controller's error state as last observed by [`Driver::on_interrupt`] or read now.
    pub fn state(&mut self) -> ErrorState {
        self.track_state();
        self.state
    }

    /// The controller's full error status, read now.
    pub fn error_status(&self) -> ErrorStatus {
        self.controller.error_status()
    }

    /// TEC (256 while bus-off) and REC.
    pub fn counters(&self) -> ErrorCounters {
        self.controller.error_status().counters
    }

    /// The last error code the controller latched.
    pub fn last_error(&self) -> LastErrorCode {
        self.controller.error_status().last_error
    }

    /// Error statistics kept by the driver.
    pub fn error_stats(&self) -> ErrorStatistics {
        self.errors
    }

    /// Traffic statistics kept by the driver.
    pub fn traffic(&self) -> TrafficStats {
        self.traffic
    }

    /// Receive ring figures (ACAN `receiveBufferSize/Count/PeakCount`).
    pub fn rx_stats(&self) -> BufferStats {
        self.rx.stats()
    }

    /// Transmit queue figures (ACAN `transmitBufferSize/Count/PeakCount`).
    pub fn tx_stats(&self) -> BufferStats {
        self.tx.stats()
    }

    /// The transmit policy.
    pub fn tx_policy(&self) -> TxPolicy {
        self.controller.tx_policy()
    }

    /// State of one transmit mailbox.
    pub fn mailbox_state(&self, mailbox: MailboxId) -> MailboxState {
        self.controller.mailbox_state(mailbox)
    }

    /// Requests the abort of one mailbox (see [`Controller::abort`]).
    pub fn abort(&mut self, mailbox: MailboxId) -> bool {
        self.controller.abort(mailbox)
    }

    /// Drops every queued frame and requests the abort of every mailbox. Returns the
    /// number of queued frames dropped (mailbox aborts are counted when reported).
    pub fn abort_all(&mut self) -> usize {
        let dropped = self.tx.clear();
        self.traffic.aborted = self.traffic.aborted.saturating_add(dropped as u32);
        for m in 0..self.controller.mailbox_count() {
            self.controller.abort(MailboxId(m));
        }
        dropped
    }

    /// Changes the operating mode.
    pub fn set_mode(&mut self, mode: Mode) -> Result<(), Error> {
        let r = self.controller.set_mode(mode);
        self.track_state();
        r
    }

    /// Starts bus-off recovery by software.
    pub fn recover(&mut self) -> Result<(), Error> {
        let r = self.controller.recover();
        self.track_state();
        r
    }

    /// Installs a new compiled filter list.
    pub fn set_filters(&mut self, filters: &C::Filters) -> Result<(), Error> {
        self.controller.install_filters(filters)
    }
}

impl<C: Controller, const RX: usize, const TX: usize> embedded_can::nb::Can for Driver<C, RX, TX> {
    type Frame = Frame;
    type Error = Error;

    /// Queues the frame; never displaces a queued frame (the driver's queue keeps it).
    fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, Error> {
        self.try_send(frame).map(|()| None)
    }

    fn receive(&mut self) -> nb::Result<Frame, Error> {
        Driver::receive(self).map(|rx| rx.frame)
    }
}

impl<C: Controller, const RX: usize, const TX: usize> embedded_can::blocking::Can
    for Driver<C, RX, TX>
{
    type Frame = Frame;
    type Error = Error;

    /// Waits for room in the transmit queue, servicing the controller while waiting (so it
    /// also works with interrupts disabled). Fails at once on a fault such as bus-off.
    fn transmit(&mut self, frame: &Frame) -> Result<(), Error> {
        loop {
            match self.try_send(frame) {
                Ok(()) => return Ok(()),
                Err(nb::Error::Other(e)) => return Err(e),
                Err(nb::Error::WouldBlock) => self.on_interrupt(),
            }
        }
    }

    /// Waits for a frame, servicing the controller while waiting.
    fn receive(&mut self) -> Result<Frame, Error> {
        loop {
            if let Ok(rx) = Driver::receive(self) {
                return Ok(rx.frame);
            }
            self.on_interrupt();
        }
    }
}
