//! The interface between the simulated bus and a node on it (a peripheral model).
//!
//! The bus owns time (in bit times) and the wire; each node owns its controller's rules.
//! At every point where the bus is idle, the bus asks each node for the frame its
//! controller would start ([`BusNode::poll_tx`]), resolves arbitration with
//! [`twocan_core::priority::Priority`], computes the frame's exact length, and reports the
//! outcome to everyone: the winner gets [`BusNode::tx_result`], losers get
//! [`TxResult::ArbitrationLost`], listeners get [`BusNode::rx`] or [`BusNode::rx_error`].
//! Between frames, [`BusNode::advance`] lets time pass (timers, bus-off recovery).

use twocan_core::error::LastErrorCode;
use twocan_core::frame::Frame;

/// A frame a node wants to start at the next start-of-frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TxRequest {
    /// The frame.
    pub frame: Frame,
    /// The node acknowledges its own frame (self-test: bxCAN loop-back ignores the
    /// acknowledge slot), so it never gets an acknowledge error.
    pub self_ack: bool,
    /// The frame does not reach the wire at all (FlexCAN LPB, bxCAN loop-back + silent):
    /// only the node itself sees it; it takes no part in arbitration with other nodes.
    pub internal: bool,
}

/// How a transmission attempt ended for its transmitter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TxResult {
    /// Sent without error and acknowledged.
    Acked,
    /// Another node's frame won arbitration; this node became a receiver of it.
    ArbitrationLost,
    /// An error was detected (`code` says which); an error frame followed.
    Error(LastErrorCode),
}

/// A fault-confinement event that the outcome of an attempt does not carry (ISO 11898-1
/// §12.1.4.2), for [`BusNode::confinement_event`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConfinementEvent {
    /// Rule 3, exception 2: the transmit error reported next — a stuff error on a
    /// recessive stuff bit of the arbitration field read dominant — leaves TEC unchanged.
    /// Told right before that [`BusNode::tx_result`].
    ArbitrationStuffException,
    /// Rules 4 and 5 (a bit error during the node's own active error flag) and rule 6
    /// (dominant bits after its flag): `count` times +8 to TEC (`transmitter`) or REC.
    /// Told at the end of the attempt.
    FlagPenalties {
        /// The node was a transmitter of the attempt.
        transmitter: bool,
        /// Number of +8 penalties.
        count: u8,
    },
}

/// Times of the bus event being reported, in bit times since the bus started.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BusTime {
    /// Start-of-frame bit of the frame concerned.
    pub sof: u64,
    /// The current time (end of the event).
    pub now: u64,
}

/// A node on the simulated bus: implemented by each peripheral model.
pub trait BusNode {
    /// Called when the bus is idle: the frame the controller would start now, if any.
    /// Calling it must not change the node's state (the bus may call it repeatedly).
    fn poll_tx(&mut self, now: u64) -> Option<TxRequest>;

    /// Whether the node would drive a dominant acknowledge bit for a frame it received
    /// correctly (on the bus, not bus-off, not silent / listen-only, not asleep).
    fn acknowledges(&self) -> bool;

    /// Whether the node samples the bus at all (silent / listen-only nodes do; sleeping,
    /// bus-off and initialization-mode nodes do not).
    fn listens(&self) -> bool;

    /// Whether an error detected by this node is signalled by an active error flag
    /// (which destroys the frame for everyone) — true for an error-active node.
    fn error_active(&self) -> bool;

    /// The end of this node's transmission attempt of `frame`.
    fn tx_result(&mut self, frame: &Frame, result: TxResult, time: BusTime);

    /// A frame correctly received from the bus (or, for a self-receiving node, its own).
    fn rx(&mut self, frame: &Frame, own: bool, time: BusTime);

    /// An error detected while receiving; `dominant_after_flag` applies ISO 11898-1
    /// rule 2 (REC + 8).
    fn rx_error(&mut self, code: LastErrorCode, dominant_after_flag: bool, time: BusTime);

    /// `bits` bit times passed ending at `now`; `idle` says the bus was recessive all along.
    fn advance(&mut self, bits: u64, idle: bool, now: u64);

    /// The frame attempt in which this node was a transmitter (it did not lose arbitration)
    /// is over: `time.now` is the end of the last end of frame or error delimiter, where the
    /// intermission starts; always after [`BusNode::tx_result`]. `dominant_in_passive_flag`:
    /// the node sent a passive error flag and read a dominant bit during it (ISO 11898-1
    /// §12.1.4.2 rule 3, exception 1 then does not apply). Nodes use it for
    /// [`crate::fault::FaultConfinement::transmission_ended`] (that exception and suspend
    /// transmission). The default does nothing.
    fn tx_attempt_end(&mut self, dominant_in_passive_flag: bool, time: BusTime) {
        let _ = (dominant_in_passive_flag, time);
    }

    /// A frame attempt starts (its SOF is at `time.sof`): `transmitter` for a node whose
    /// [`BusNode::poll_tx`] request takes part in arbitration (it may lose it later), false
    /// for a node that only listens. From here until its outcome is reported the node is
    /// in the frame: a controller shows it as "transmitting" / "receiving", and a mailbox
    /// whose frame is on the wire is in transmission. The default does nothing.
    fn attempt_started(&mut self, transmitter: bool, time: BusTime) {
        let _ = (transmitter, time);
    }

    /// A fault-confinement event the outcome does not carry (see [`ConfinementEvent`]).
    /// Nodes apply it with [`crate::fault::FaultConfinement::arbitration_stuff_exception`]
    /// and [`crate::fault::FaultConfinement::confinement_penalties`]. The
    /// default does nothing.
    fn confinement_event(&mut self, event: ConfinementEvent, time: BusTime) {
        let _ = (event, time);
    }

    /// The bus stopped inside a frame attempt at bus time `now` ([`crate::Bus::run_bits`]);
    /// `recessive` is the level of the last bit on the wire (what the controller's receive
    /// pin shows and last sampled). The default does nothing.
    fn paused_in_frame(&mut self, recessive: bool, now: u64) {
        let _ = (recessive, now);
    }

    /// The earliest bus time after `now` at which this node may start a frame on its own,
    /// without software doing anything: the end of its suspend-transmission time, the moment
    /// its bus-off recovery completes, a timer. The bus ends idle stretches there, so that the
    /// node's SOF is exact. `None` (the default) if nothing of the kind is pending; a node
    /// without this hint is still polled after every idle stretch the caller asks for.
    fn next_wakeup(&self, now: u64) -> Option<u64> {
        let _ = now;
        None
    }
}

/// A shared node: the bus drives it while the test keeps its own clone of the `Rc`.
///
/// Each call borrows the `RefCell` for its duration only; holding a borrow of the node
/// across a call into the bus is a programming error that makes `RefCell` panic.
impl<T: BusNode + ?Sized> BusNode for std::rc::Rc<core::cell::RefCell<T>> {
    fn poll_tx(&mut self, now: u64) -> Option<TxRequest> {
        self.borrow_mut().poll_tx(now)
    }
    fn acknowledges(&self) -> bool {
        self.borrow().acknowledges()
    }
    fn listens(&self) -> bool {
        self.borrow().listens()
    }
    fn error_active(&self) -> bool {
        self.borrow().error_active()
    }
    fn tx_result(&mut self, frame: &Frame, result: TxResult, time: BusTime) {
        self.borrow_mut().tx_result(frame, result, time)
    }
    fn rx(&mut self, frame: &Frame, own: bool, time: BusTime) {
        self.borrow_mut().rx(frame, own, time)
    }
    fn rx_error(&mut self, code: LastErrorCode, dominant_after_flag: bool, time: BusTime) {
        self.borrow_mut().rx_error(code, dominant_after_flag, time)
    }
    fn advance(&mut self, bits: u64, idle: bool, now: u64) {
        self.borrow_mut().advance(bits, idle, now)
    }
    fn next_wakeup(&self, now: u64) -> Option<u64> {
        self.borrow().next_wakeup(now)
    }
    fn tx_attempt_end(&mut self, dominant_in_passive_flag: bool, time: BusTime) {
        self.borrow_mut()
            .tx_attempt_end(dominant_in_passive_flag, time)
    }
    fn attempt_started(&mut self, transmitter: bool, time: BusTime) {
        self.borrow_mut().attempt_started(transmitter, time)
    }
    fn paused_in_frame(&mut self, recessive: bool, now: u64) {
        self.borrow_mut().paused_in_frame(recessive, now)
    }
    fn confinement_event(&mut self, event: ConfinementEvent, time: BusTime) {
        self.borrow_mut().confinement_event(event, time)
    }
}
