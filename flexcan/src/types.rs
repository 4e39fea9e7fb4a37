//! Short names for the driver over FlexCAN in its common configurations: the split
//! driver's state, halves and interrupt handlers with the controller, the unused second
//! receive ring (FlexCAN has one receive queue, the Rx FIFO) and ACAN's buffer sizes
//! filled in. Each alias keeps the register access `R` (the target's [`FlexCanRegs`]
//! by default; a model on the host) and the sizes as parameters with defaults, so
//! `FlexTx<'static>` is the firmware's transmit half and a host test names its own
//! sizes.
//!
//! ```
//! use twocan_core::CanTx;
//! use twocan_flexcan::types::{FlexState, FlexTx};
//!
//! // A protocol stack generic over `CanTx` takes the half as it is.
//! fn stack<T: CanTx>(_tx: &mut T) {}
//! fn task(tx: &mut FlexTx<'static>) {
//!     stack(tx)
//! }
//! static CAN0: FlexState = FlexState::new();
//! # let _ = (&CAN0, task as fn(&mut FlexTx<'static>));
//! ```

use twocan_core::split::{Rx, Rx0Irq, State, StatusIrq, Tx, TxIrq};
use twocan_core::FifoQueue;

use crate::regs::FlexCanRegs;
use crate::{FlexCanHw, RECEIVE_BUFFER_SIZE, TRANSMIT_BUFFER_SIZE};

/// Completions kept for the thread side by default.
pub const COMPLETIONS: usize = 8;

/// ACAN's transmit queue: request order, [`TRANSMIT_BUFFER_SIZE`] frames.
pub type Queue = FifoQueue<TRANSMIT_BUFFER_SIZE>;

/// The shared state a `static` holds: receive ring of `RX` frames (ACAN's
/// [`RECEIVE_BUFFER_SIZE`]), transmit queue `Q`, `DONE` completions.
pub type FlexState<
    R = FlexCanRegs,
    const RX: usize = RECEIVE_BUFFER_SIZE,
    Q = Queue,
    const DONE: usize = COMPLETIONS,
> = State<FlexCanHw<R>, RX, Q, 0, DONE>;

/// A handle type of the split driver over this backend, its defaults filled in.
macro_rules! alias {
    ($(#[$doc:meta])* $name:ident = $target:ident) => {
        $(#[$doc])*
        pub type $name<
            'a,
            R = FlexCanRegs,
            const RX: usize = RECEIVE_BUFFER_SIZE,
            Q = Queue,
            const DONE: usize = COMPLETIONS,
        > = $target<'a, FlexCanHw<R>, RX, Q, 0, DONE>;
    };
}

alias! {
    /// The transmit half (implements [`twocan_core::CanTx`]).
    FlexTx = Tx
}
alias! {
    /// The receive half (implements [`twocan_core::CanRx`]).
    FlexRx = Rx
}
alias! {
    /// The transmit handler (the ORed message-buffer line).
    FlexTxIrq = TxIrq
}
alias! {
    /// The Rx FIFO's receive handler (the ORed message-buffer line).
    FlexRxIrq = Rx0Irq
}
alias! {
    /// The status handler (bus-off, error, Tx/Rx warning lines).
    FlexStatusIrq = StatusIrq
}
