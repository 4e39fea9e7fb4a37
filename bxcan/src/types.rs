//! Short names for the driver over bxCAN in its common configurations: the split
//! driver's state, halves and interrupt handlers with the controller filled in, a
//! receive ring per FIFO of the same size (RM0410 §40.7.5: two receive FIFOs, either
//! fed by the filters), and the examples' sizes as defaults. Each alias keeps the
//! register access as parameters: `R` for the controller's registers and `F` for the
//! filter block — the whole block of one instance ([`CanRegs`], the default: CAN1 alone
//! or CAN3), or [`ControlRegs`](crate::regs::ControlRegs) with CAN1's
//! [`FilterRegs`](crate::regs::FilterRegs) lent to CAN1 and CAN2
//! (RM0410 §40.9: CAN2 has no filter block of its own).
//!
//! ```
//! use twocan_core::CanRx;
//! use twocan_bxcan::regs::{ControlRegs, FilterRegs};
//! use twocan_bxcan::types::{BxRx, BxState};
//!
//! fn stack<R: CanRx>(_rx: &mut R) {}
//! // CAN1 alone, and CAN2 next to CAN1 (its control window, CAN1's filters lent).
//! static CAN1: BxState = BxState::new();
//! static CAN2: BxState<ControlRegs, &'static FilterRegs> = BxState::new();
//! fn task(rx: &mut BxRx<'static, ControlRegs, &'static FilterRegs>) {
//!     stack(rx)
//! }
//! # let _ = (&CAN1, &CAN2, task as fn(&mut BxRx<'static, ControlRegs, &'static FilterRegs>));
//! ```

use twocan_core::split::{Rx, Rx0Irq, Rx1Irq, State, StatusIrq, Tx, TxIrq};
use twocan_core::FifoQueue;

use crate::regs::CanRegs;
use crate::BxCan;

/// Receive ring per FIFO, by default.
pub const RX_RING: usize = 32;
/// Transmit queue, by default.
pub const TX_QUEUE: usize = 16;
/// Completions kept for the thread side, by default.
pub const COMPLETIONS: usize = 8;

/// A transmit queue in request order (`CAN_MCR.TXFP = 1`, the driver's default).
pub type Queue = FifoQueue<TX_QUEUE>;

/// The shared state a `static` holds: a receive ring of `RX` frames per FIFO,
/// transmit queue `Q`, `DONE` completions.
pub type BxState<
    R = CanRegs,
    F = R,
    const RX: usize = RX_RING,
    Q = Queue,
    const DONE: usize = COMPLETIONS,
> = State<BxCan<R, F>, RX, Q, RX, DONE>;

/// A handle type of the split driver over this backend, its defaults filled in.
macro_rules! alias {
    ($(#[$doc:meta])* $name:ident = $target:ident) => {
        $(#[$doc])*
        pub type $name<
            'a,
            R = CanRegs,
            F = R,
            const RX: usize = RX_RING,
            Q = Queue,
            const DONE: usize = COMPLETIONS,
        > = $target<'a, BxCan<R, F>, RX, Q, RX, DONE>;
    };
}

alias! {
    /// The transmit half (implements [`twocan_core::CanTx`]).
    BxTx = Tx
}
alias! {
    /// The receive half (implements [`twocan_core::CanRx`]).
    BxRx = Rx
}
alias! {
    /// The transmit handler (`CANx_TX` line).
    BxTxIrq = TxIrq
}
alias! {
    /// FIFO 0's receive handler (`CANx_RX0` line).
    BxRx0Irq = Rx0Irq
}
alias! {
    /// FIFO 1's receive handler (`CANx_RX1` line).
    BxRx1Irq = Rx1Irq
}
alias! {
    /// The status handler (`CANx_SCE` line).
    BxStatusIrq = StatusIrq
}
