//! The async API on the simulated boards (feature `async` of twocan-core): the
//! controllers of [`FlexNode`] and [`BxNode`] split over a [`State`] of the caller, their
//! interrupt handlers as [`Serviced`] nodes (run when the model raises a line, as the
//! chips' vectors would), and [`drive`], a small single-threaded executor that
//! interleaves servicing the interrupts, polling the woken futures and stepping the bus
//! (the models are `Rc`-based: one thread).
//!
//! ```
//! use std::pin::pin;
//! use twocan_core::{Filter, Frame};
//! use twocan_host::asynch::{drive, split_bx, split_flex, BxState, FlexState};
//! use twocan_host::{BxNode, FlexNode, Harness};
//!
//! let mut h = Harness::new(500_000).unwrap();
//! let teensy = FlexNode::teensy36_can0(&mut h, &[Filter::pass_all()]).unwrap();
//! let stm32 = BxNode::stm32f767_can1(&mut h, &[Filter::pass_all()]).unwrap();
//! let (fs, bs) = (FlexState::new(), BxState::new());
//! let (mut fi, mut ftx, _frx) = split_flex(&fs, teensy).unwrap();
//! let (mut bi, _btx, mut brx) = split_bx(&bs, stm32).unwrap();
//! let frame = Frame::standard(0x123, &[1, 2, 3]).unwrap();
//! let mut send = pin!(async { ftx.send(&frame).await.map(|_| ()) });
//! let mut recv = pin!(async { brx.recv().await.map(|f| assert_eq!(f.frame, frame)) });
//! let until = h.now() + 1_000;
//! let done = drive(&mut h, &mut [&mut fi, &mut bi], &mut [send.as_mut(), recv.as_mut()], until);
//! assert!(done.iter().all(|r| matches!(r, Some(Ok(())))));
//! ```

use std::future::Future;
use std::pin::Pin;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::task::{Context, Wake, Waker};

use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::BxCan;
use twocan_core::split::{Rx, Rx0Irq, Rx1Irq, State, StatusIrq, Tx, TxIrq};
use twocan_core::{Error, ErrorState, FifoQueue};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::FlexCanHw;

use crate::{BxNode, Clocked, FlexNode, Harness, Serviced, SetupError, RX_RING, TX_RING};

/// Completion ring of the split nodes.
pub const COMPLETIONS: usize = 8;

/// The FlexCAN controller over its model.
pub type FlexHw = FlexCanHw<Clocked<FlexCanModel>>;
/// The bxCAN controller over its model.
pub type BxHw = BxCan<Clocked<BxCanModel>>;
/// The transmit queue of both (request order).
pub type Queue = FifoQueue<TX_RING>;
/// The shared state of a split FlexCAN node.
pub type FlexState = State<FlexHw, RX_RING, Queue, 0, COMPLETIONS>;
/// The shared state of a split bxCAN node (a receive ring per FIFO).
pub type BxState = State<BxHw, RX_RING, Queue, RX_RING, COMPLETIONS>;
/// FlexCAN transmit half.
pub type FlexTx<'a> = Tx<'a, FlexHw, RX_RING, Queue, 0, COMPLETIONS>;
/// FlexCAN receive half.
pub type FlexRx<'a> = Rx<'a, FlexHw, RX_RING, Queue, 0, COMPLETIONS>;
/// bxCAN transmit half.
pub type BxTx<'a> = Tx<'a, BxHw, RX_RING, Queue, RX_RING, COMPLETIONS>;
/// bxCAN receive half.
pub type BxRx<'a> = Rx<'a, BxHw, RX_RING, Queue, RX_RING, COMPLETIONS>;

/// The interrupt handlers of a split FlexCAN node: the ORed message-buffer vector
/// (transmit, then receive) and the status vectors.
pub struct FlexIrqs<'a> {
    /// The peripheral model (its interrupt request, its counters).
    pub model: FlexCanModel,
    tx: TxIrq<'a, FlexHw, RX_RING, Queue, 0, COMPLETIONS>,
    rx: Rx0Irq<'a, FlexHw, RX_RING, Queue, 0, COMPLETIONS>,
    status: StatusIrq<'a, FlexHw, RX_RING, Queue, 0, COMPLETIONS>,
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
    tx: TxIrq<'a, BxHw, RX_RING, Queue, RX_RING, COMPLETIONS>,
    rx0: Rx0Irq<'a, BxHw, RX_RING, Queue, RX_RING, COMPLETIONS>,
    rx1: Rx1Irq<'a, BxHw, RX_RING, Queue, RX_RING, COMPLETIONS>,
    status: StatusIrq<'a, BxHw, RX_RING, Queue, RX_RING, COMPLETIONS>,
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
    let FlexNode { model, driver, .. } = node;
    let p = state
        .split(driver.release())
        .map_err(|(e, _)| SetupError::Driver(e))?;
    let irqs = FlexIrqs {
        model,
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
    let BxNode { model, driver, .. } = node;
    let p = state
        .split(driver.release())
        .map_err(|(e, _)| SetupError::Driver(e))?;
    let irqs = BxIrqs {
        model,
        tx: p.tx_irq,
        rx0: p.rx0_irq,
        rx1: p.rx1_irq,
        status: p.status_irq,
    };
    Ok((irqs, p.tx, p.rx))
}

/// A waker that marks its future to be polled again.
#[derive(Default)]
struct Flag(AtomicBool);

impl Wake for Flag {
    fn wake(self: Arc<Self>) {
        self.0.store(true, Ordering::Release);
    }
    fn wake_by_ref(self: &Arc<Self>) {
        self.0.store(true, Ordering::Release);
    }
}

/// A future of [`drive`].
pub type Task<'f> = Pin<&'f mut dyn Future<Output = Result<(), Error>>>;

/// Runs `futures` with the bus: services `nodes`, polls each future that was woken
/// (each once at the start), steps the bus by one event when no future is woken, until
/// every future is ready or the bus time reaches `until`. Returns each future's
/// output, `None` for one still pending at `until` (the caller drops it: the async API
/// is cancel-safe).
pub fn drive(
    h: &mut Harness,
    nodes: &mut [&mut dyn Serviced],
    futures: &mut [Task<'_>],
    until: u64,
) -> Vec<Option<Result<(), Error>>> {
    let flags: Vec<Arc<Flag>> = futures
        .iter()
        .map(|_| Arc::new(Flag(AtomicBool::new(true))))
        .collect();
    let wakers: Vec<Waker> = flags.iter().map(|f| Waker::from(f.clone())).collect();
    let mut out: Vec<Option<Result<(), Error>>> = futures.iter().map(|_| None).collect();
    let mut at_end = false;
    loop {
        for n in nodes.iter_mut() {
            n.service();
        }
        for (i, fut) in futures.iter_mut().enumerate() {
            if out[i].is_none() && flags[i].0.swap(false, Ordering::AcqRel) {
                if let std::task::Poll::Ready(v) =
                    fut.as_mut().poll(&mut Context::from_waker(&wakers[i]))
                {
                    out[i] = Some(v);
                }
            }
        }
        let woken =
            (0..futures.len()).any(|i| out[i].is_none() && flags[i].0.load(Ordering::Acquire));
        if at_end && !woken || out.iter().all(Option::is_some) {
            return out;
        }
        if !woken && h.bus().borrow_mut().step_until(until).is_none() {
            at_end = true;
        }
    }
}
