//! The bus side of the model: what the protocol engine does with the simulated bus's
//! events ([`twocan_sim::BusNode`]).
//!
//! - The module takes part in bus traffic when enabled, out of freeze and synchronised
//!   (11 recessive bits), and not bus-off.
//! - Listen-only (CTRL1\[LOM\]): receives, never acknowledges, never transmits, and behaves
//!   as error passive ("Listen-only mode").
//! - Loop-back (CTRL1\[LPB\]): the transmitted bit stream is fed back internally, the Tx pin
//!   stays recessive and the bus is not sampled; the acknowledge slot is ignored
//!   ("Loop-back mode"). Requests are made with `internal` and `self_ack` set.
//! - Self reception (MCR\[SRXDIS\] = 0): the module receives its own frames if they match a
//!   filter. The simulated bus reports a node's own frame through `rx(.., own = true, ..)`
//!   and the model drops it when SRXDIS = 1.
//! - Suspend transmission: error-passive after transmitting, the module starts no frame
//!   before 8 bits after the intermission (ISO 11898-1 §10.4.6.4; the Kinetis manuals:
//!   "delay its transmission start time (error-passive)").
//! - Frames take bus time: from the start of frame (`BusNode::attempt_started`) the
//!   mailbox that won the internal arbitration is in transmission (an ABORT written then
//!   waits for the outcome, see `mailboxes.rs`) and ESR1\[TX\] / ESR1\[RX\] show the
//!   module transmitting / receiving (ESR1\[IDLE\] clear) until the outcome.
//! - Time stamps are the TIMER value at the bit after SOF (the identifier's start).

use twocan_core::error::LastErrorCode;
use twocan_core::frame::Frame;
use twocan_sim::{BusTime, TxRequest, TxResult};

use crate::regs::mcr;

use super::state::State;

impl State {
    /// Lets time run to `now` (the TIMER counts while the module runs).
    pub fn time_to(&mut self, now: u64) {
        let running = self.running();
        self.timer.advance_to(now, running);
    }

    /// Whether the module may start a transmission.
    pub fn can_transmit(&self) -> bool {
        self.on_bus() && !self.bus_off() && !self.lom()
    }

    /// What the controller would start now (not before suspend transmission has ended).
    pub fn poll_tx(&self, now: u64) -> Option<TxRequest> {
        if !self.can_transmit() || !self.errors.fc.may_start_transmission(now) {
            return None;
        }
        let frame = self.mb_tx_frame(self.select_tx()?)?;
        let lpb = self.lpb();
        Some(TxRequest {
            frame,
            self_ack: lpb,
            internal: lpb,
        })
    }

    /// Drives a dominant ACK for correctly received frames.
    pub fn acknowledges(&self) -> bool {
        self.on_bus() && !self.bus_off() && !self.lom() && !self.lpb()
    }

    /// Samples the bus.
    pub fn listens(&self) -> bool {
        self.on_bus() && !self.bus_off() && !self.lpb()
    }

    /// Signals errors with active error flags.
    pub fn error_active(&self) -> bool {
        self.on_bus() && !self.bus_off() && !self.lom() && !self.errors.fc.is_passive()
    }

    /// The end of a transmission attempt.
    pub fn tx_result(&mut self, frame: &Frame, result: TxResult, time: BusTime) {
        self.time_to(time.now);
        if self.bus_off() {
            self.bus_off_dominant();
            return;
        }
        match result {
            TxResult::Acked => {
                if let Some(n) = self.tx_succeeded_mb(frame) {
                    let stamp = self.timer.value_at(time.sof.saturating_add(1));
                    self.tx_done(n, stamp);
                }
                self.transmit_ok();
            }
            TxResult::ArbitrationLost => {
                self.tx_failed();
                self.transmitting = false;
                self.receiving = self.listens();
            }
            TxResult::Error(code) => {
                self.tx_failed();
                self.transmit_error(code);
            }
        }
    }

    /// A frame received correctly (or the module's own frame).
    pub fn rx(&mut self, frame: &Frame, own: bool, time: BusTime) {
        self.time_to(time.now);
        self.rx_inner(frame, own, time);
        if !own {
            // A freeze or disable request that waited for this frame takes effect now.
            self.receiving = false;
            self.settle_modes();
        }
    }

    fn rx_inner(&mut self, frame: &Frame, own: bool, time: BusTime) {
        if self.bus_off() {
            self.bus_off_dominant();
            return;
        }
        if own {
            if !self.on_bus() || self.mcr_bit(mcr::SRXDIS) {
                return;
            }
        } else {
            if !self.listens() {
                self.sync_run = 0;
                return;
            }
            self.receive_ok();
        }
        let stamp = self.timer.value_at(time.sof.saturating_add(1));
        self.accept_frame(frame, stamp);
    }

    /// An error detected while receiving.
    pub fn rx_error(&mut self, code: LastErrorCode, dominant_after_flag: bool, time: BusTime) {
        self.time_to(time.now);
        self.rx_error_inner(code, dominant_after_flag);
        self.receiving = false;
        self.settle_modes();
    }

    fn rx_error_inner(&mut self, code: LastErrorCode, dominant_after_flag: bool) {
        if self.bus_off() {
            self.bus_off_dominant();
            return;
        }
        if !self.listens() {
            self.sync_run = 0;
            return;
        }
        self.receive_error(code, dominant_after_flag);
    }

    /// The next time the module could start a frame without software acting: the end of
    /// bus synchronisation or of automatic bus-off recovery, when a transmission waits.
    pub fn next_wakeup(&self, now: u64) -> Option<u64> {
        if !self.running() || self.lom() || self.select_tx().is_none() {
            return None;
        }
        if let Some(left) = self.bus_off_bits_left() {
            if self.errors.boffrec_latched {
                return None;
            }
            return Some(now.saturating_add(left.max(1)));
        }
        if !self.synched {
            return Some(now.saturating_add(11u64.saturating_sub(self.sync_run).max(1)));
        }
        self.errors.fc.suspend_end(now)
    }

    /// The end of an attempt the module transmitted (see `BusNode::tx_attempt_end`).
    pub fn tx_attempt_end(&mut self, dominant_in_passive_flag: bool, time: BusTime) {
        self.time_to(time.now);
        self.transmitting = false;
        self.transmission_ended(time.now, dominant_in_passive_flag);
        self.settle_modes();
    }

    /// A frame attempt starts (see `BusNode::attempt_started`).
    pub fn attempt_started(&mut self, transmitter: bool, time: BusTime) {
        self.time_to(time.sof);
        if transmitter {
            self.transmitting = true;
            self.tx_started();
        } else {
            self.receiving = true;
        }
    }

    /// `bits` bit times passed, ending at `now`.
    pub fn advance(&mut self, bits: u64, idle: bool, now: u64) {
        // Time the bus did not report to this node (frames it did not listen to) was not
        // recessive.
        let unreported = now.saturating_sub(bits) > self.timer.at();
        self.time_to(now);
        if unreported {
            self.bus_off_dominant();
            self.sync_run = 0;
        }
        if self.bus_off() {
            if idle || self.lpb() {
                self.bus_off_idle(bits);
            } else {
                self.bus_off_dominant();
            }
        } else {
            self.sync_bits(bits, idle);
        }
    }
}
