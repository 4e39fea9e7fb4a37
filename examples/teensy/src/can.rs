//! The split driver of a FlexCAN instance as the examples use it: its shared state in a
//! `static` ([`CanState`]), its interrupt handles in the instance's [`Vectors`], which
//! the device vectors of `rt` run, and `start`, which puts the handles in
//! place **before** it unmasks the interrupt lines — so an interrupt never finds a
//! vector with nothing to run (the line would stay asserted).
//!
//! Interrupt lines (Kinetis RM, FlexCAN "Interrupts"): the ORed message-buffer vector
//! runs the transmit handler and the Rx FIFO's receive handler; the bus-off, error and
//! Tx/Rx-warning vectors run the status handler.

use twocan_core::irq_cell::IrqCell;
use twocan_core::split::{Rx, RxIrq, State, StatusIrq, Tx, TxIrq};
use twocan_core::FifoQueue;
use twocan_flexcan::regs::FlexCanRegs;
use twocan_flexcan::{FlexCanHw, RECEIVE_BUFFER_SIZE, TRANSMIT_BUFFER_SIZE};

/// Completions kept for the thread side.
pub const COMPLETIONS: usize = 8;

/// The controller on target registers.
pub type Hw = FlexCanHw<FlexCanRegs>;
/// ACAN's buffer sizes: receive 32, transmit 16 (ACAN table 7).
pub type Queue = FifoQueue<TRANSMIT_BUFFER_SIZE>;
/// The shared state a `static` holds.
pub type CanState = State<Hw, RECEIVE_BUFFER_SIZE, Queue, 0, COMPLETIONS>;
/// The transmit half.
pub type CanTxHalf = Tx<'static, Hw, RECEIVE_BUFFER_SIZE, Queue, 0, COMPLETIONS>;
/// The receive half.
pub type CanRxHalf = Rx<'static, Hw, RECEIVE_BUFFER_SIZE, Queue, 0, COMPLETIONS>;
/// What the message-buffer vector runs: settle and refill the transmit mailboxes, drain
/// the Rx FIFO.
pub type MessageHandlers = (
    TxIrq<'static, Hw, RECEIVE_BUFFER_SIZE, Queue, 0, COMPLETIONS>,
    RxIrq<'static, Hw, RECEIVE_BUFFER_SIZE, Queue, 0, COMPLETIONS>,
);
/// What the bus-off, error and warning vectors run.
pub type StatusHandler = StatusIrq<'static, Hw, RECEIVE_BUFFER_SIZE, Queue, 0, COMPLETIONS>;

/// The interrupt handles of one FlexCAN instance.
pub struct Vectors {
    message: IrqCell<MessageHandlers>,
    status: IrqCell<StatusHandler>,
}

impl Default for Vectors {
    fn default() -> Self {
        Self::new()
    }
}

impl Vectors {
    /// Empty: the vectors do nothing until `start` fills them.
    pub const fn new() -> Self {
        Vectors {
            message: IrqCell::new(),
            status: IrqCell::new(),
        }
    }

    /// The message-buffer vector's work; `false` when no handle is in place.
    #[inline]
    pub fn on_message(&self) -> bool {
        self.message.run(|(tx, rx)| {
            tx.on_interrupt();
            rx.on_interrupt();
        })
    }

    /// The status vectors' work; `false` when no handle is in place.
    #[inline]
    pub fn on_status(&self) -> bool {
        self.status.run(|s| s.on_interrupt())
    }

    /// Puts the interrupt handles in place; `false` if there were some already.
    pub fn install(&self, message: MessageHandlers, status: StatusHandler) -> bool {
        self.message.put(message).is_ok() && self.status.put(status).is_ok()
    }
}

/// FlexCAN0's handles, run by `CAN0_*` vectors of `rt`.
pub static CAN0_VECTORS: Vectors = Vectors::new();
/// FlexCAN1's handles (Teensy 3.6), run by its `CAN1_*` vectors.
#[cfg(feature = "teensy36")]
pub static CAN1_VECTORS: Vectors = Vectors::new();

/// Splits `state` over `hw`, puts the interrupt handles in `vectors`, then sets the
/// message interrupt's priority (`mMessageIRQPriority`, ACAN §16.7.4) and unmasks the
/// instance's interrupt lines. Returns the thread-side halves; `None` when `state` was
/// split already or the instance has no interrupt numbers.
#[cfg(target_os = "none")]
pub fn start(
    state: &'static CanState,
    vectors: &'static Vectors,
    hw: Hw,
    nvic: &mut cortex_m::peripheral::NVIC,
) -> Option<(CanTxHalf, CanRxHalf)> {
    let irqs = hw.target().irqs()?;
    let priority = hw.message_irq_priority();
    let parts = state.split(hw).ok()?;
    if !vectors.install((parts.tx_irq, parts.rx0_irq), parts.status_irq) {
        return None;
    }
    crate::rt::enable_can_irqs(nvic, irqs, priority);
    Some((parts.tx, parts.rx))
}
