//! [`SimNode`]: a bare ISO 11898-1 node for testing the bus and for tests elsewhere.
//!
//! It has a FIFO of frames to send (the head is retried until it is acknowledged, unless
//! one-shot), keeps what it receives and what happened to its transmissions, and counts
//! errors with the shared [`FaultConfinement`]. Error-passive, it waits the 8-bit suspend
//! transmission after the intermission that follows each of its transmissions (counted by
//! [`FaultConfinement::transmission_ended`] from the end of the frame or error frame); bus-off, it neither sends nor listens and
//! recovers by itself after 128 × 11 recessive bits (or waits for [`SimNode::recover`]).

use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;
use std::vec::Vec;

use super::node::{BusNode, BusTime, ConfinementEvent, TxRequest, TxResult};
use crate::fault::{FaultConfinement, BUS_OFF_RECOVERY_SEQUENCES};
use twocan_core::error::{ErrorCounters, ErrorState, LastErrorCode};
use twocan_core::frame::Frame;

/// A frame a [`SimNode`] received.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Received {
    /// The frame.
    pub frame: Frame,
    /// It was the node's own frame.
    pub own: bool,
    /// When.
    pub time: BusTime,
}

/// The end of one transmission attempt of a [`SimNode`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TxReport {
    /// The frame.
    pub frame: Frame,
    /// How it ended.
    pub result: TxResult,
    /// When.
    pub time: BusTime,
}

/// An error a [`SimNode`] detected while receiving.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RxErrorReport {
    /// The error.
    pub code: LastErrorCode,
    /// ISO 11898-1 rule 2 applied.
    pub dominant_after_flag: bool,
    /// When.
    pub time: BusTime,
}

/// A bare ISO node (see the [module docs](self)).
#[derive(Debug, Clone, Default)]
pub struct SimNode {
    queue: VecDeque<Frame>,
    received: Vec<Received>,
    tx_reports: Vec<TxReport>,
    rx_errors: Vec<RxErrorReport>,
    fault: FaultConfinement,
    self_ack: bool,
    listen_only: bool,
    receive_own: bool,
    manual_recovery: bool,
    one_shot: bool,
    internal: bool,
    bus_off_count: u32,
    last_error: LastErrorCode,
    // Mirror of the recovery progress (FaultConfinement does not expose it) so that the
    // node can tell the bus exactly when recovery completes.
    recovery_sequences: u64,
    recessive_run: u64,
}

impl SimNode {
    /// An error-active node that acknowledges, does not self-acknowledge, does not keep its
    /// own frames, retries until success and recovers from bus-off automatically.
    pub fn new() -> Self {
        Self::default()
    }

    /// Wraps the node for attaching a clone to a [`Bus`](super::Bus) and keeping the other.
    pub fn shared(self) -> Rc<RefCell<SimNode>> {
        Rc::new(RefCell::new(self))
    }

    /// Acknowledges its own frames (bxCAN loop-back style): never an acknowledge error.
    pub fn with_self_ack(mut self, on: bool) -> Self {
        self.self_ack = on;
        self
    }

    /// Listen-only (silent): receives, never sends, acknowledges or signals errors.
    pub fn with_listen_only(mut self, on: bool) -> Self {
        self.listen_only = on;
        self
    }

    /// Keeps its own successfully sent frames in [`SimNode::received`].
    pub fn with_receive_own(mut self, on: bool) -> Self {
        self.receive_own = on;
        self
    }

    /// Stays bus-off until [`SimNode::recover`] (default: recovers by itself).
    pub fn with_manual_recovery(mut self, on: bool) -> Self {
        self.manual_recovery = on;
        self
    }

    /// Drops a frame after its first attempt whatever the result (no retransmission).
    pub fn with_one_shot(mut self, on: bool) -> Self {
        self.one_shot = on;
        self
    }

    /// Sends its frames as internal (loop-back) requests that never reach the wire.
    pub fn with_internal(mut self, on: bool) -> Self {
        self.internal = on;
        self
    }

    /// Queues a frame for transmission.
    pub fn send(&mut self, frame: Frame) {
        self.queue.push_back(frame);
    }

    /// Frames still waiting to be sent.
    pub fn pending(&self) -> usize {
        self.queue.len()
    }

    /// Frames received so far.
    pub fn received(&self) -> &[Received] {
        &self.received
    }

    /// The received frames only, in order.
    pub fn received_frames(&self) -> Vec<Frame> {
        self.received.iter().map(|r| r.frame).collect()
    }

    /// Every transmission attempt's end, in order.
    pub fn tx_reports(&self) -> &[TxReport] {
        &self.tx_reports
    }

    /// Every receive error, in order.
    pub fn rx_errors(&self) -> &[RxErrorReport] {
        &self.rx_errors
    }

    /// The last error code seen (transmit or receive).
    pub fn last_error(&self) -> LastErrorCode {
        self.last_error
    }

    /// The error counters (TEC reads 256 while bus-off).
    pub fn counters(&self) -> ErrorCounters {
        self.fault.counters()
    }

    /// The fault-confinement state.
    pub fn state(&self) -> ErrorState {
        self.fault.state()
    }

    /// The fault-confinement counters themselves.
    pub fn fault(&self) -> &FaultConfinement {
        &self.fault
    }

    /// Times the node entered bus-off.
    pub fn bus_off_count(&self) -> u32 {
        self.bus_off_count
    }

    /// Leaves bus-off if the 128 × 11 recessive-bit condition is met; returns whether it did.
    pub fn recover(&mut self) -> bool {
        if self.fault.recovery_condition_met() {
            self.fault.recover();
            true
        } else {
            false
        }
    }

    fn entered_bus_off(&mut self) {
        self.bus_off_count += 1;
        self.recovery_sequences = 0;
        self.recessive_run = 0;
    }

    fn bits_to_recovery(&self) -> u64 {
        let left = u64::from(BUS_OFF_RECOVERY_SEQUENCES).saturating_sub(self.recovery_sequences);
        (left * 11).saturating_sub(self.recessive_run)
    }
}

impl BusNode for SimNode {
    fn poll_tx(&mut self, now: u64) -> Option<TxRequest> {
        if self.fault.is_bus_off() || self.listen_only || !self.fault.may_start_transmission(now) {
            return None;
        }
        self.queue.front().map(|&frame| TxRequest {
            frame,
            self_ack: self.self_ack,
            internal: self.internal,
        })
    }

    fn acknowledges(&self) -> bool {
        !self.listen_only && !self.fault.is_bus_off()
    }

    fn listens(&self) -> bool {
        !self.fault.is_bus_off()
    }

    fn error_active(&self) -> bool {
        !self.fault.is_bus_off() && !self.fault.is_passive()
    }

    fn tx_result(&mut self, frame: &Frame, result: TxResult, time: BusTime) {
        self.tx_reports.push(TxReport {
            frame: *frame,
            result,
            time,
        });
        match result {
            TxResult::Acked => {
                self.fault.transmit_succeeded();
                self.queue.pop_front();
            }
            TxResult::ArbitrationLost => {}
            TxResult::Error(code) => {
                self.last_error = code;
                if self.fault.transmit_error(code) {
                    self.entered_bus_off();
                }
                if self.one_shot {
                    self.queue.pop_front();
                }
            }
        }
    }

    fn confinement_event(&mut self, event: ConfinementEvent, _time: BusTime) {
        match event {
            ConfinementEvent::ArbitrationStuffException => {
                self.fault.arbitration_stuff_exception();
            }
            ConfinementEvent::FlagPenalties { transmitter, count } => {
                if self.fault.confinement_penalties(transmitter, count) {
                    self.entered_bus_off();
                }
            }
        }
    }

    fn tx_attempt_end(&mut self, dominant_in_passive_flag: bool, time: BusTime) {
        if self
            .fault
            .transmission_ended(time.now, dominant_in_passive_flag)
        {
            self.entered_bus_off();
        }
    }

    fn rx(&mut self, frame: &Frame, own: bool, time: BusTime) {
        if own {
            if self.receive_own {
                self.received.push(Received {
                    frame: *frame,
                    own,
                    time,
                });
            }
            return;
        }
        self.fault.receive_succeeded();
        self.received.push(Received {
            frame: *frame,
            own,
            time,
        });
    }

    fn rx_error(&mut self, code: LastErrorCode, dominant_after_flag: bool, time: BusTime) {
        self.last_error = code;
        self.fault.receive_error(dominant_after_flag);
        self.rx_errors.push(RxErrorReport {
            code,
            dominant_after_flag,
            time,
        });
    }

    fn advance(&mut self, bits: u64, idle: bool, _now: u64) {
        if !self.fault.is_bus_off() {
            return;
        }
        if idle {
            let total = self.recessive_run + bits;
            self.recovery_sequences =
                (self.recovery_sequences + total / 11).min(u64::from(BUS_OFF_RECOVERY_SEQUENCES));
            self.recessive_run = total % 11;
            if self.fault.idle_bits(bits) && !self.manual_recovery {
                self.fault.recover();
            }
        } else {
            self.fault.dominant_bit();
            self.recessive_run = 0;
        }
    }

    fn next_wakeup(&self, now: u64) -> Option<u64> {
        if self.queue.is_empty() || self.listen_only {
            return None;
        }
        if self.fault.is_bus_off() {
            if self.manual_recovery {
                return None;
            }
            return Some(now + self.bits_to_recovery().max(1));
        }
        self.fault.suspend_end(now)
    }
}
