//! Moving a simulated board between the one-struct [`twocan_core::Driver`] and the split
//! driver: [`split_flex`] and [`split_bx`] take the controller out of a [`FlexNode`] /
//! [`BxNode`] and split a [`State`](twocan_core::State) of the caller over it — the transmit and receive
//! halves for the application, the interrupt handlers as [`Serviced`] nodes that run
//! when the model raises a line, as the chips' vectors would. [`unsplit_flex`] and
//! [`unsplit_bx`] go back: the halves and handlers are given up, the state hands the
//! controller back, and it becomes a one-struct driver again. The type aliases name the
//! host nodes' configuration of each backend's split driver
//! (`twocan_flexcan::types`, `twocan_bxcan::types` with the host's sizes).
//!
//! ```
//! use twocan_core::{Filter, Frame};
//! use twocan_host::split::{split_bx, split_flex, BxState, FlexState};
//! use twocan_host::{BxNode, FlexNode, Harness};
//!
//! let mut h = Harness::new(500_000).unwrap();
//! let teensy = FlexNode::teensy36_can0(&mut h, &[Filter::pass_all()]).unwrap();
//! let stm32 = BxNode::stm32f767_can1(&mut h, &[Filter::pass_all()]).unwrap();
//! let (fs, bs) = (FlexState::new(), BxState::new());
//! let (mut fi, mut ftx, _frx) = split_flex(&fs, teensy).unwrap();
//! let (mut bi, _btx, mut brx) = split_bx(&bs, stm32).unwrap();
//! let frame = Frame::standard(0x123, &[1, 2, 3]).unwrap();
//! ftx.try_send(&frame).unwrap();
//! h.run_for(1_000, &mut [&mut fi, &mut bi]);
//! assert_eq!(brx.receive().unwrap().frame, frame);
//! ```

use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::types as bx;
use twocan_bxcan::BxCan;
use twocan_core::{Driver, ErrorState, FifoQueue};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::types as flex;
use twocan_flexcan::FlexCanHw;

use twocan_sim::NodeId;

use crate::{BxNode, Clocked, FlexNode, Serviced, SetupError, RX_RING, TX_RING};

/// Completion ring of the split nodes.
pub const COMPLETIONS: usize = 8;

/// The FlexCAN controller over its model.
pub type FlexHw = FlexCanHw<FlexRegs>;
/// The FlexCAN model's registers, bus time passing while the driver polls.
pub type FlexRegs = Clocked<FlexCanModel>;
/// The bxCAN controller over its model.
pub type BxHw = BxCan<BxRegs>;
/// The bxCAN model's registers, bus time passing while the driver polls.
pub type BxRegs = Clocked<BxCanModel>;
/// The transmit queue of both (request order).
pub type Queue = FifoQueue<TX_RING>;
/// The shared state of a split FlexCAN node.
pub type FlexState = flex::FlexState<FlexRegs, RX_RING, Queue, COMPLETIONS>;
/// The shared state of a split bxCAN node (a receive ring per FIFO).
pub type BxState = bx::BxState<BxRegs, BxRegs, RX_RING, Queue, COMPLETIONS>;
/// FlexCAN transmit half.
pub type FlexTx<'a> = flex::FlexTx<'a, FlexRegs, RX_RING, Queue, COMPLETIONS>;
/// FlexCAN receive half.
pub type FlexRx<'a> = flex::FlexRx<'a, FlexRegs, RX_RING, Queue, COMPLETIONS>;
/// bxCAN transmit half.
pub type BxTx<'a> = bx::BxTx<'a, BxRegs, BxRegs, RX_RING, Queue, COMPLETIONS>;
/// bxCAN receive half.
pub type BxRx<'a> = bx::BxRx<'a, BxRegs, BxRegs, RX_RING, Queue, COMPLETIONS>;

/// The interrupt handlers of a split FlexCAN node: the ORed message-buffer vector
/// (transmit, then receive) and the status vectors.
pub struct FlexIrqs<'a> {
    /// The peripheral model (its interrupt request, its counters).
    pub model: FlexCanModel,
    /// The node's place on the bus.
    pub id: NodeId,
    tx: flex::FlexTxIrq<'a, FlexRegs, RX_RING, Queue, COMPLETIONS>,
    rx: flex::FlexRxIrq<'a, FlexRegs, RX_RING, Queue, COMPLETIONS>,
    status: flex::FlexStatusIrq<'a, FlexRegs, RX_RING, Queue, COMPLETIONS>,
}

impl FlexIrqs<'_> {
    /// The error state last recorded by the status handler.
    pub fn state(&self) -> ErrorState {
        self.status.last_state()
    }
}

impl Serviced for FlexIrqs<'_> {
    fn service(&mut self) -> bool {
        // A controller leaving bus-off raises no interrupt: read the state every time.
        self.status.poll_state();
        if !self.model.irq_pending() {
            return false;
        }
        self.tx.on_interrupt();
        self.rx.on_interrupt();
        self.status.on_interrupt();
        true
    }
}

/// The interrupt handlers of a split bxCAN node, one per line (TX, RX0, RX1, SCE).
pub struct BxIrqs<'a> {
    /// The peripheral model (its interrupt lines, its counters).
    pub model: BxCanModel,
    /// The node's place on the bus.
    pub id: NodeId,
    tx: bx::BxTxIrq<'a, BxRegs, BxRegs, RX_RING, Queue, COMPLETIONS>,
    rx0: bx::BxRx0Irq<'a, BxRegs, BxRegs, RX_RING, Queue, COMPLETIONS>,
    rx1: bx::BxRx1Irq<'a, BxRegs, BxRegs, RX_RING, Queue, COMPLETIONS>,
    status: bx::BxStatusIrq<'a, BxRegs, BxRegs, RX_RING, Queue, COMPLETIONS>,
}

impl BxIrqs<'_> {
    /// The error state last recorded by the status handler.
    pub fn state(&self) -> ErrorState {
        self.status.last_state()
    }
}

impl Serviced for BxIrqs<'_> {
    fn service(&mut self) -> bool {
        self.status.poll_state();
        let l = self.model.irq_lines();
        if l.tx {
            self.tx.on_interrupt();
        }
        if l.rx0 {
            self.rx0.on_interrupt();
        }
        if l.rx1 {
            self.rx1.on_interrupt();
        }
        if l.sce {
            self.status.on_interrupt();
        }
        l.tx || l.rx0 || l.rx1 || l.sce
    }
}

/// Takes the controller out of `node`'s one-struct driver and splits `state` over it.
#[allow(clippy::type_complexity)]
pub fn split_flex(
    state: &FlexState,
    node: FlexNode,
) -> Result<(FlexIrqs<'_>, FlexTx<'_>, FlexRx<'_>), SetupError> {
    let FlexNode { model, driver, id } = node;
    let p = state
        .split(driver.release())
        .map_err(|(e, _)| SetupError::Driver(e))?;
    let irqs = FlexIrqs {
        model,
        id,
        tx: p.tx_irq,
        rx: p.rx0_irq,
        status: p.status_irq,
    };
    Ok((irqs, p.tx, p.rx))
}

/// Takes the controller out of `node`'s one-struct driver and splits `state` over it.
#[allow(clippy::type_complexity)]
pub fn split_bx(
    state: &BxState,
    node: BxNode,
) -> Result<(BxIrqs<'_>, BxTx<'_>, BxRx<'_>), SetupError> {
    let BxNode { model, driver, id } = node;
    let p = state
        .split(driver.release())
        .map_err(|(e, _)| SetupError::Driver(e))?;
    let irqs = BxIrqs {
        model,
        id,
        tx: p.tx_irq,
        rx0: p.rx0_irq,
        rx1: p.rx1_irq,
        status: p.status_irq,
    };
    Ok((irqs, p.tx, p.rx))
}

/// The way back from [`split_flex`]: once the halves and handlers are dropped, takes the
/// controller out of `state` and makes it a one-struct driver again, with the `model`
/// and `id` the handlers held ([`FlexIrqs::model`], [`FlexIrqs::id`]). `None` when the
/// state was never split.
pub fn unsplit_flex(state: FlexState, model: FlexCanModel, id: NodeId) -> Option<FlexNode> {
    let hw = state.into_hardware()?;
    Some(FlexNode {
        model,
        driver: Driver::new(hw),
        id,
    })
}

/// The way back from [`split_bx`] (see [`unsplit_flex`]).
pub fn unsplit_bx(state: BxState, model: BxCanModel, id: NodeId) -> Option<BxNode> {
    let hw = state.into_hardware()?;
    Some(BxNode {
        model,
        driver: Driver::new(hw),
        id,
    })
}
