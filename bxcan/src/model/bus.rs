//! The bus side of a controller: what it offers to transmit, how it takes the outcome,
//! what it receives, and how time passes (the `twocan_sim::BusNode` contract).
//!
//! Rules modelled:
//! - Only normal mode takes part in bus traffic; a bus-off controller neither transmits
//!   nor receives (RM0410 40.7.6).
//! - Test modes (RM0410 40.5): silent (`BTR.SILM`) receives but sends only recessive bits
//!   — it never starts a transmission and never acknowledges; loop back (`BTR.LBKM`)
//!   sends on the bus, acknowledges its own frames (acknowledge errors ignored:
//!   `TxRequest::self_ack`), disregards CANRX (receives nothing from the others) and
//!   receives its own frames through its filters; loop back + silent sends nothing on
//!   the wire (`TxRequest::internal`). Own frames come back through
//!   [`BusNode::rx`] with `own = true` and are stored only in loop back mode.
//! - Time (RM0410 40.4, 40.7.2, 40.7.6): only [`BusNode::advance`] with `idle = true`
//!   counts recessive bits (for SYNC and bus-off recovery); frames, errors, non-idle
//!   spans and unreported gaps in the bus time are bus activity, which restarts the
//!   runs of recessive bits and, in sleep mode, is a wake-up event (`WKUI`; with
//!   `MCR.AWUM` hardware clears `SLEEP`; RM0410 40.4.3 "Sleep mode").
//! - The mailbox offered by `poll_tx` is in transmit state until the bus reports the
//!   attempt ([`BusNode::tx_result`]), reports idle time or polls again (then nothing was
//!   started: the bus polls only while idle).
//! - [`BusNode::next_wakeup`]: the end of SYNC, and the end of each run of 11 recessive
//!   bits of a bus-off recovery under way, so that the bus stops its idle stretches there.
//! - Suspend transmission: error-passive after transmitting, the controller starts no frame
//!   before 8 bits after the intermission (ISO 11898-1 §10.4.6.4), counted by the shared
//!   `FaultConfinement` from the end of the frame or error frame.
//! - Time stamps are the TTCM timer at the start of frame (`BusTime::sof`).

use twocan_core::{Frame, LastErrorCode};
use twocan_sim::{BusNode, BusTime, ConfinementEvent, TxRequest, TxResult};

use super::controller::Controller;
use super::modes::Mode;
use super::rx::RxMessage;
use super::tx::Attempt;
use super::BxCanModel;
use crate::regs::{mcr, TX_MAILBOXES};

impl Controller {
    /// Whether the controller samples the bus (normal mode, not bus-off, not loop back,
    /// not frozen by a debug halt).
    pub(crate) fn listens(&self) -> bool {
        self.mode() == Mode::Normal && !self.errors.is_bus_off() && !self.lbkm() && !self.frozen()
    }

    /// Whether the controller would acknowledge a frame it received.
    pub(crate) fn acknowledges(&self) -> bool {
        self.listens() && !self.silm()
    }

    /// Notes the bus time `now`; an unreported span before `start` (after the first time
    /// the controller has seen) is bus activity.
    fn observe(&mut self, start: u64, now: u64) {
        let gap = self.time_known && start > self.now;
        self.time_known = true;
        self.now = self.now.max(now);
        if gap {
            self.activity();
        }
    }

    /// Bus activity: restarts recessive runs; wakes a sleeping controller.
    fn activity(&mut self) {
        self.modes.activity();
        self.errors.dominant();
        if self.mode() == Mode::Sleep {
            self.wkui = true;
            if self.has(mcr::AWUM) {
                self.mcr &= !mcr::SLEEP;
            }
        }
        self.settle();
    }

    fn poll_tx(&mut self, now: u64) -> Option<TxRequest> {
        // The bus polls only while idle: a frame offered before and not reported since was
        // not started (another node's internal frame went first). An abort or a mode
        // request that waited for it takes effect now.
        if self.tx.offered().is_some() {
            self.tx.bus_idle();
            self.settle();
        }
        if self.mode() != Mode::Normal
            || self.modes.syncing()
            || self.errors.is_bus_off()
            || self.frozen()
            || !self.errors.fault_confinement().may_start_transmission(now)
        {
            return None;
        }
        let (lbkm, silm) = (self.lbkm(), self.silm());
        if silm && !lbkm {
            return None;
        }
        let x = self.tx.next(self.has(mcr::TXFP))?;
        let frame = self.tx.frame(x, self.timer.at(now), self.has(mcr::TTCM))?;
        self.tx.set_offered(x);
        Some(TxRequest {
            frame,
            self_ack: lbkm,
            internal: lbkm && silm,
        })
    }

    /// The mailbox that sent `frame` (start of frame at `sof`): the one offered if its
    /// arbitration field matches, else one whose frame is identical, else one with the
    /// same arbitration field.
    fn mailbox_of(&self, frame: &Frame, sof: u64) -> Option<usize> {
        let ttcm = self.has(mcr::TTCM);
        let stamp = self.timer.at(sof);
        let key = frame.priority();
        let built = |x: usize| {
            self.tx
                .frame(x, stamp, ttcm)
                .filter(|_| self.tx.is_requested(x))
        };
        let same_key = |x: &usize| built(*x).is_some_and(|f| f.priority() == key);
        let identical = |x: &usize| built(*x).as_ref() == Some(frame);
        self.tx
            .offered()
            .filter(same_key)
            .or_else(|| (0..TX_MAILBOXES).find(identical))
            .or_else(|| (0..TX_MAILBOXES).find(same_key))
    }

    fn tx_result(&mut self, frame: &Frame, result: TxResult, time: BusTime) {
        self.observe(time.sof, time.now);
        if result == TxResult::ArbitrationLost {
            self.txm = false;
            self.rxm = self.listens();
        }
        self.modes.activity();
        self.errors.dominant();
        let mailbox = self.mailbox_of(frame, time.sof);
        let attempt = match result {
            TxResult::Acked => {
                self.errors.transmit_ok();
                Attempt::Ok
            }
            TxResult::ArbitrationLost => Attempt::ArbitrationLost,
            TxResult::Error(code) => {
                self.errors.transmit_error(code);
                self.error_detected();
                Attempt::Error
            }
        };
        match mailbox {
            Some(x) => {
                if self.has(mcr::TTCM) {
                    self.tx.stamp(x, self.timer.at(time.sof));
                }
                self.tx.complete(x, attempt, self.has(mcr::NART));
            }
            None => self.tx.bus_idle(),
        }
        self.settle();
    }

    /// Filters a valid frame and stores it in its FIFO.
    fn deliver(&mut self, frame: &Frame, sof: u64) {
        let accepted = self.filters.borrow_mut().accept(self.owner, frame);
        let Some(a) = accepted else {
            self.dropped = self.dropped.saturating_add(1);
            return;
        };
        let time = if self.has(mcr::TTCM) {
            self.timer.at(sof)
        } else {
            0
        };
        let locked = self.has(mcr::RFLM);
        if let Some(fifo) = self.rx.get_mut(a.fifo) {
            fifo.store(RxMessage::new(frame, a.fmi, time), locked);
        }
    }

    fn rx(&mut self, frame: &Frame, own: bool, time: BusTime) {
        self.observe(time.sof, time.now);
        if own {
            if self.lbkm() && self.mode() == Mode::Normal && !self.errors.is_bus_off() {
                self.deliver(frame, time.sof);
            }
            return;
        }
        // The reception completes (and is stored) before a mode request that waited for it
        // takes effect.
        self.activity();
        if self.listens() {
            self.errors.receive_ok();
            self.deliver(frame, time.sof);
        }
        self.rxm = false;
        self.settle();
    }

    fn rx_error(&mut self, code: LastErrorCode, dominant_after_flag: bool, time: BusTime) {
        self.observe(time.sof, time.now);
        self.activity();
        if self.listens() {
            self.errors.receive_error(code, dominant_after_flag);
            self.error_detected();
        }
        self.rxm = false;
        self.settle();
    }

    /// The bus time at which the controller changes state on its own while the bus stays
    /// idle: the end of SYNC (leaving initialization or sleep mode), or the end of the
    /// current run of 11 recessive bits of a bus-off recovery that is under way.
    fn next_wakeup(&self, now: u64) -> Option<u64> {
        if self.ack_stuck {
            return None;
        }
        if let Some(left) = self.modes.sync_left() {
            return Some(now.saturating_add(left));
        }
        let recovering =
            self.mode() == Mode::Normal && self.errors.recovery_under_way(self.has(mcr::ABOM));
        if recovering {
            return Some(now.saturating_add(self.errors.recovery_bits_to_next_sequence()));
        }
        let waiting = self.tx.next(self.has(mcr::TXFP)).is_some();
        if waiting {
            self.errors.fault_confinement().suspend_end(now)
        } else {
            None
        }
    }

    /// The end of an attempt the controller transmitted (see `BusNode::tx_attempt_end`).
    fn tx_attempt_end(&mut self, dominant_in_passive_flag: bool, time: BusTime) {
        self.observe(time.sof, time.now);
        self.txm = false;
        if self
            .errors
            .transmission_ended(time.now, dominant_in_passive_flag)
        {
            self.error_detected();
        }
        self.settle();
    }

    /// A fault-confinement event (see `BusNode::confinement_event`).
    fn confinement_event(&mut self, event: ConfinementEvent, time: BusTime) {
        self.observe(time.sof, time.now);
        match event {
            ConfinementEvent::ArbitrationStuffException => {
                self.errors.arbitration_stuff_exception()
            }
            ConfinementEvent::FlagPenalties { transmitter, count } => {
                self.errors.flag_penalties(transmitter, count);
                self.error_detected();
            }
        }
        self.settle();
    }

    /// A frame attempt starts (see `BusNode::attempt_started`).
    fn attempt_started(&mut self, transmitter: bool, time: BusTime) {
        self.observe(time.sof, time.sof);
        if transmitter {
            self.txm = true;
        } else {
            self.rxm = true;
        }
    }

    fn advance(&mut self, bits: u64, idle: bool, now: u64) {
        self.level = true;
        self.observe(now.saturating_sub(bits), now);
        if !idle {
            self.activity();
            return;
        }
        // Nothing was started: the mailbox offered is scheduled again.
        self.tx.bus_idle();
        let (transition, mut normal_bits) = self.modes.recessive(bits, self.ack_stuck);
        if let Some((from, to)) = transition {
            self.entered(from, to);
        }
        if self.mode() != Mode::Normal {
            normal_bits = 0;
        }
        self.errors.recessive_bits(normal_bits, self.has(mcr::ABOM));
        self.settle();
    }
}

impl BusNode for BxCanModel {
    fn poll_tx(&mut self, now: u64) -> Option<TxRequest> {
        self.inner.borrow_mut().poll_tx(now)
    }

    fn acknowledges(&self) -> bool {
        self.inner.borrow().acknowledges()
    }

    fn listens(&self) -> bool {
        self.inner.borrow().listens()
    }

    fn error_active(&self) -> bool {
        let c = self.inner.borrow();
        !c.errors.is_bus_off() && !c.errors.is_passive()
    }

    fn tx_result(&mut self, frame: &Frame, result: TxResult, time: BusTime) {
        self.inner.borrow_mut().tx_result(frame, result, time);
    }

    fn rx(&mut self, frame: &Frame, own: bool, time: BusTime) {
        self.inner.borrow_mut().rx(frame, own, time);
    }

    fn rx_error(&mut self, code: LastErrorCode, dominant_after_flag: bool, time: BusTime) {
        self.inner
            .borrow_mut()
            .rx_error(code, dominant_after_flag, time);
    }

    fn advance(&mut self, bits: u64, idle: bool, now: u64) {
        self.inner.borrow_mut().advance(bits, idle, now);
    }

    fn next_wakeup(&self, now: u64) -> Option<u64> {
        self.inner.borrow().next_wakeup(now)
    }

    fn tx_attempt_end(&mut self, dominant_in_passive_flag: bool, time: BusTime) {
        self.inner
            .borrow_mut()
            .tx_attempt_end(dominant_in_passive_flag, time);
    }

    fn attempt_started(&mut self, transmitter: bool, time: BusTime) {
        self.inner.borrow_mut().attempt_started(transmitter, time);
    }

    fn paused_in_frame(&mut self, recessive: bool, _now: u64) {
        self.inner.borrow_mut().level = recessive;
    }

    fn confinement_event(&mut self, event: ConfinementEvent, time: BusTime) {
        self.inner.borrow_mut().confinement_event(event, time);
    }
}
