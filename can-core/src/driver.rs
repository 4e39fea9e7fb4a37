//! The one-struct driver for polling code and tests, built on the split driver's pieces
//! ([`crate::split`]): it owns a [`State`] and plays every role itself, so it needs no
//! `static` and no interrupt. Firmware that takes interrupts uses the split handles.
//!
//! ```
//! use twocan_core::mock::{block, MockHardware};
//! use twocan_core::{Driver, Frame, TxOutcome};
//!
//! let mut can: Driver<MockHardware, 8, 4> = Driver::new(MockHardware::new(3).with_loopback(true));
//! let frame = Frame::standard(0x123, &[1, 2, 3])?;
//! // `nb::block!` in firmware; `block` is its bounded form for the mock.
//! let token = block("room to send", || can.try_send(&frame))?;
//! can.hardware().complete_all();          // the mock puts its mailboxes on the "bus"
//! can.on_interrupt();                     // what the interrupt handlers would do
//! assert_eq!(block("the frame back", || can.receive())?.frame, frame);
//! let done = can.take_completion().unwrap();
//! assert_eq!((done.token, done.outcome), (token, TxOutcome::Sent));
//! # Ok::<(), twocan_core::Error>(())
//! ```

use crate::capabilities::{BusMode, Capabilities};
use crate::controller::{ErrorStatus, Mode};
use crate::dispatch::Dispatcher;
use crate::error::{Error, ErrorCounters, ErrorState, ErrorStatistics, LastErrorCode};
use crate::frame::{Frame, RxFrame};
use crate::hardware::{Completion, Hardware, Token};
use crate::mailbox::TxPolicy;
use crate::split::{AbortRequest, Rx0Irq, Rx1Irq, State, StateChange, StatusIrq, Tx, TxIrq};
use crate::spsc::BufferStats;
use crate::timing::Timing;
use crate::txqueue::AnyQueue;

pub use crate::split::TrafficStats;

/// Capacity of the one-struct driver's completion ring.
pub const DRIVER_COMPLETIONS: usize = 32;

/// The portable CAN driver over controller `H` with a receive ring of `RX` frames (and
/// `RX1` for a second hardware receive queue), a transmit queue of `TX` frames in the
/// controller's order, and a completion ring of [`DRIVER_COMPLETIONS`].
///
/// With `RX1 = 0` on a controller with two receive queues (bxCAN), frames that the
/// filters put in the second queue are still taken from the hardware (its FIFO never
/// stays full) and counted in [`TrafficStats::rx_ring_overflows`]: give `RX1` room
/// when a filter plan uses FIFO 1.
pub struct Driver<H: Hardware, const RX: usize, const TX: usize, const RX1: usize = 0> {
    state: State<H, RX, AnyQueue<TX>, RX1, DRIVER_COMPLETIONS>,
    next: u32,
    map: H::FilterMap,
    last: ErrorState,
}

type St<H, const RX: usize, const TX: usize, const RX1: usize> =
    State<H, RX, AnyQueue<TX>, RX1, DRIVER_COMPLETIONS>;

impl<H: Hardware, const RX: usize, const TX: usize, const RX1: usize> Driver<H, RX, TX, RX1> {
    /// Wraps a configured controller; the queue takes the controller's transmit order.
    pub fn new(hardware: H) -> Self {
        const {
            assert!(
                RX > 0 && TX > 0,
                "the receive and transmit rings need room for a frame"
            )
        };
        let mut state = State::new();
        let (map, status) = state.install(hardware);
        Driver {
            state,
            next: 0,
            map,
            last: status.state,
        }
    }

    fn with_tx<T>(
        &mut self,
        f: impl FnOnce(&mut Tx<'_, H, RX, AnyQueue<TX>, RX1, DRIVER_COMPLETIONS>) -> T,
    ) -> T {
        let mut tx = Tx {
            s: &self.state,
            next: self.next,
        };
        let r = f(&mut tx);
        self.next = tx.next;
        r
    }

    /// The controller (for backend-specific operations).
    pub fn hardware(&self) -> &H {
        self.shared().owned_hardware().expect("installed by new")
    }

    fn shared(&self) -> &St<H, RX, TX, RX1> {
        &self.state
    }

    /// The token the next accepted frame will get.
    pub fn next_token(&self) -> Token {
        Token(self.next)
    }

    /// Gives the controller back.
    pub fn release(mut self) -> H {
        self.state.uninstall().expect("installed by new")
    }

    /// Accepts `frame` for transmission ([`Tx::try_send`]): its token, or
    /// `WouldBlock` when the queue is full; an error means not accepted.
    pub fn try_send(&mut self, frame: &Frame) -> nb::Result<Token, Error> {
        self.with_tx(|tx| tx.try_send(frame))
    }

    /// Loads `frame` into a free mailbox now or `WouldBlock`, never queued
    /// ([`Tx::try_send_now`]).
    pub fn try_send_now(&mut self, frame: &Frame) -> nb::Result<Token, Error> {
        self.with_tx(|tx| tx.try_send_now(frame))
    }

    /// The next completion, in order.
    pub fn take_completion(&mut self) -> Option<Completion> {
        self.with_tx(|tx| tx.take_completion())
    }

    /// Aborts the frame of `token`, queued or in a mailbox.
    pub fn abort(&mut self, token: Token) -> AbortRequest {
        self.with_tx(|tx| tx.abort(token))
    }

    /// Drops every queued frame and requests the abort of every mailbox; returns the
    /// number of queued frames dropped (each has an `Aborted` completion).
    pub fn abort_all(&mut self) -> usize {
        self.with_tx(|tx| tx.abort_all())
    }

    /// Takes the oldest received frame ([`crate::split::Rx::receive`]).
    pub fn receive(&mut self) -> nb::Result<RxFrame, Error> {
        // SAFETY: the driver plays every role; it is the rings' only consumer.
        unsafe { self.state.receive_with(&self.map) }
    }

    /// Frames waiting in the receive ring(s).
    pub fn available(&self) -> usize {
        self.state.rx_stats().count
    }

    /// Takes one frame and hands it to its filter's call-back; whether one was taken.
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

    /// Every interrupt handler's work (transmit, receive queues, status) and a read of
    /// the error state (controllers leaving bus-off raise no interrupt). Never blocks.
    pub fn on_interrupt(&mut self) {
        let s = &self.state;
        TxIrq { s }.on_interrupt();
        Rx0Irq { s }.on_interrupt();
        if H::RX_QUEUES > 1 {
            // Also without a ring for it (`RX1 = 0`): the hardware queue is released and
            // its frames are counted as ring overflows, never left in the hardware.
            Rx1Irq { s }.on_interrupt();
        }
        let mut status = StatusIrq { s, last: self.last };
        status.on_interrupt();
        status.poll_state();
        self.last = status.last;
    }

    /// The transmit line's handler ([`TxIrq::on_interrupt`]).
    pub fn on_tx(&mut self) {
        TxIrq { s: &self.state }.on_interrupt();
    }

    /// The receive handler of hardware queue `queue` ([`crate::split::RxIrq::on_interrupt`]; a
    /// queue the controller does not have: nothing).
    pub fn on_rx(&mut self, queue: u8) {
        let s = &self.state;
        match queue {
            0 => Rx0Irq { s }.on_interrupt(),
            1 => Rx1Irq { s }.on_interrupt(),
            _ => {}
        }
    }

    /// The status line's handler ([`StatusIrq::on_interrupt`]), then a read of the
    /// error state (a controller leaving bus-off raises no interrupt).
    pub fn on_status(&mut self) {
        let mut status = StatusIrq {
            s: &self.state,
            last: self.last,
        };
        status.on_interrupt();
        status.poll_state();
        self.last = status.last;
    }

    /// The next error-state change, in order, with the counters at the change.
    pub fn take_state_change(&mut self) -> Option<StateChange> {
        // SAFETY: the driver plays every role; it is the ring's only consumer.
        unsafe { self.state.pop_change() }
    }

    /// The error state, read now (a change is recorded).
    pub fn state(&mut self) -> ErrorState {
        let mut status = StatusIrq {
            s: &self.state,
            last: self.last,
        };
        status.poll_state();
        self.last = status.last;
        self.last
    }

    /// The controller's error status, read now.
    pub fn error_status(&self) -> ErrorStatus {
        self.hardware().error_status()
    }

    /// TEC (256 while bus-off) and REC.
    pub fn counters(&self) -> ErrorCounters {
        self.error_status().counters
    }

    /// The last error code the controller latched.
    pub fn last_error(&self) -> LastErrorCode {
        self.error_status().last_error
    }

    /// Error statistics.
    pub fn error_stats(&self) -> ErrorStatistics {
        self.state.error_stats()
    }

    /// Wake-up events the status handler has seen (bus activity while the controller
    /// slept; [`Capabilities::wakeup_events`] says whether the controller reports them
    /// as configured).
    pub fn wakeups(&self) -> u32 {
        self.state.wakeups()
    }

    /// Traffic statistics.
    pub fn traffic(&self) -> TrafficStats {
        self.state.traffic()
    }

    /// Receive ring figures (ACAN `receiveBufferSize/Count/PeakCount`): the rings the
    /// installed filters feed ([`State::rx_stats`]).
    pub fn rx_stats(&self) -> BufferStats {
        self.state.rx_stats()
    }

    /// The figures of receive ring `queue` ([`State::rx_ring_stats`]).
    pub fn rx_ring_stats(&self, queue: usize) -> Option<BufferStats> {
        self.state.rx_ring_stats(queue)
    }

    /// Transmit queue figures (ACAN `transmitBufferSize/Count/PeakCount`).
    pub fn tx_stats(&self) -> BufferStats {
        self.state.tx_stats()
    }

    /// Sets the peaks of both rings back to their counts.
    pub fn reset_peaks(&self) {
        self.state.reset_peaks()
    }

    /// State of one transmit mailbox, read now.
    pub fn mailbox_state(
        &self,
        mailbox: crate::mailbox::MailboxId,
    ) -> crate::mailbox::MailboxState {
        self.hardware().mailbox_state(mailbox)
    }

    /// The transmit order.
    pub fn tx_policy(&self) -> TxPolicy {
        self.hardware().tx_policy()
    }

    /// Changes the operating mode.
    pub fn set_mode(&mut self, mode: Mode) -> Result<(), Error> {
        // SAFETY: the driver plays every role; `&mut self` makes this the control
        // context, with no filter switch or other control call running.
        let r = unsafe { self.hardware().set_mode(mode) };
        self.state();
        r
    }

    /// Starts bus-off recovery by software (refused where recovery is automatic).
    pub fn recover(&mut self) -> Result<(), Error> {
        // SAFETY: the control context, as in `set_mode`.
        let r = unsafe { self.hardware().recover() };
        self.state();
        r
    }

    /// What the controller can do, as configured now.
    pub fn capabilities(&self) -> Capabilities {
        self.hardware().capabilities()
    }

    /// The bus mode in force.
    pub fn bus_mode(&self) -> BusMode {
        self.hardware().bus_mode()
    }

    /// Stopped controller only: a new bit timing; the filters stay
    /// ([`Hardware::set_timing`]).
    pub fn set_timing(&mut self, timing: &Timing) -> Result<(), Error> {
        // SAFETY: the control context, as in `set_mode`.
        unsafe { self.hardware().set_timing(timing) }
    }

    /// Stopped controller only: the bit timing for `bitrate` from the controller's clock,
    /// sample point at `sample_point_permille` ([`Capabilities::timing_for`]); gives
    /// the timing written. The filters stay.
    pub fn set_bitrate(
        &mut self,
        bitrate: u32,
        sample_point_permille: u16,
    ) -> Result<Timing, Error> {
        let t = self
            .capabilities()
            .timing_for(bitrate, sample_point_permille)
            .map_err(Error::Timing)?;
        // SAFETY: the control context, as in `set_mode`.
        unsafe { self.hardware().set_timing(&t)? };
        Ok(t)
    }

    /// Stopped controller only: the bus mode used from the next start; the filters stay
    /// ([`Hardware::set_bus_mode`]).
    pub fn set_bus_mode(&mut self, mode: BusMode) -> Result<(), Error> {
        // SAFETY: the control context, as in `set_mode`.
        unsafe { self.hardware().set_bus_mode(mode) }
    }

    /// Installs a new compiled filter list, atomically: once it returns, no frame is
    /// reported with an index of the old list (see [`crate::hardware`]); the old list's
    /// frames discarded on the way are counted in [`TrafficStats::rx_dropped`].
    pub fn set_filters(&mut self, filters: &H::Filters) -> Result<(), Error> {
        // SAFETY: the driver plays the receive half, the context of `install_filters`
        // (`&mut self`: nothing else runs meanwhile).
        self.map = unsafe { self.hardware().install_filters(filters)? };
        // SAFETY: as above.
        unsafe { self.state.count_filter_switch_discards() };
        Ok(())
    }

    /// The controller seen from the receive half's context, for a backend's
    /// receive-side methods (FlexCAN's installed filter table); see
    /// [`crate::hardware::ReceiveContext`].
    pub fn receive_context(&mut self) -> crate::hardware::ReceiveContext<'_, H> {
        // SAFETY: the driver plays the receive half; `&mut self` is held for the
        // context's lifetime, so no filter switch runs meanwhile.
        unsafe { crate::hardware::ReceiveContext::new(self.hardware()) }
    }

    /// Reads the controller's time stamp counter where software can, so that time
    /// stamps stay exact across a quiet bus ([`State::refresh_timestamps`]: at least
    /// once every 65,536 bit times without frames; [`Driver::on_interrupt`] and
    /// [`Driver::on_status`] do it too).
    pub fn refresh_timestamps(&self) {
        self.state.refresh_timestamps()
    }

    /// The shared state (statistics).
    pub fn shared_state(&self) -> &State<H, RX, AnyQueue<TX>, RX1, DRIVER_COMPLETIONS> {
        &self.state
    }
}

impl<H: Hardware, const RX: usize, const TX: usize, const RX1: usize> embedded_can::nb::Can
    for Driver<H, RX, TX, RX1>
{
    type Frame = Frame;
    type Error = Error;

    /// Queues the frame; never displaces a queued frame (the driver's queue keeps it).
    fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, Error> {
        self.try_send(frame).map(|_| None)
    }

    fn receive(&mut self) -> nb::Result<Frame, Error> {
        Driver::receive(self).map(|rx| rx.frame)
    }
}

impl<H: Hardware, const RX: usize, const TX: usize, const RX1: usize> embedded_can::blocking::Can
    for Driver<H, RX, TX, RX1>
{
    type Frame = Frame;
    type Error = Error;

    /// Waits for room in the transmit queue, servicing the controller while waiting.
    /// Fails at once on a fault (bus-off) and with [`Error::WrongMode`] when the queue
    /// is full while the controller is off the bus (stopped, asleep): nothing would
    /// ever free it.
    fn transmit(&mut self, frame: &Frame) -> Result<(), Error> {
        loop {
            match self.try_send(frame) {
                Ok(_) => return Ok(()),
                Err(nb::Error::Other(e)) => return Err(e),
                Err(nb::Error::WouldBlock) => {
                    if !self.hardware().on_bus() {
                        return Err(Error::WrongMode);
                    }
                    self.on_interrupt();
                }
            }
        }
    }

    /// Waits for a frame, servicing the controller while waiting; fails with
    /// [`Error::WrongMode`] when nothing is waiting and the controller is off the bus.
    fn receive(&mut self) -> Result<Frame, Error> {
        loop {
            if let Ok(rx) = Driver::receive(self) {
                return Ok(rx.frame);
            }
            if !self.hardware().on_bus() {
                return Err(Error::WrongMode);
            }
            self.on_interrupt();
        }
    }
}
