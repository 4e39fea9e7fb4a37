//! Issue 11: the async API (`Tx::send`, `Tx::completion`, `Tx::completed`, `Rx::recv`)
//! over both behavioural models: a Teensy 3.6 FlexCAN node and an STM32F767 bxCAN node
//! on one simulated bus, each split over a local [`State`], their interrupt handlers run
//! whenever the model raises a line, and their tasks polled by a small single-threaded
//! executor (the models are `Rc`-based) that interleaves servicing the interrupts,
//! polling the woken tasks and stepping the bus.
//!
//! Every test name carries `async`, so `cargo test --workspace async` runs exactly these.
//! The 100,000-frame run is `#[ignore]`d in debug builds and run in release by CI
//! (`.ci/run`); a 4,000-frame run of the same code stays in the default suite.

use std::cell::RefCell;
use std::future::Future;
use std::pin::Pin;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::task::{Context, Poll, Wake, Waker};

use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::BxCan;
use twocan_core::split::{Parts, State};
use twocan_core::txqueue::TxQueue;
use twocan_core::{
    AsyncCanRx, AsyncCanTx, Error, FifoQueue, Filter, Frame, Hardware, RxFrame, Token, TxOutcome,
};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::FlexCanHw;
use twocan_host::{BxNode, Clocked, FlexNode, Harness, RX_RING, TX_RING};
use twocan_tests::rng::XorShift64;

type FlexHw = FlexCanHw<Clocked<FlexCanModel>>;
type BxHw = BxCan<Clocked<BxCanModel>>;
type Queue = FifoQueue<TX_RING>;
/// Completion ring: the queue plus the mailboxes, so that a sender draining it after
/// each accepted frame never overflows it.
const DONE: usize = TX_RING + 4;
type FlexState = State<FlexHw, RX_RING, Queue, 0, DONE>;
type BxState = State<BxHw, RX_RING, Queue, RX_RING, DONE>;
type FlexParts<'a> = Parts<'a, FlexHw, RX_RING, Queue, 0, DONE>;
type BxParts<'a> = Parts<'a, BxHw, RX_RING, Queue, RX_RING, DONE>;

const RATE: u32 = 1_000_000;
/// A wait longer than this many bit times with every task pending is a hang.
const STALL_BITS: u64 = 100_000;

/// The `k`-th frame a node sends: identifiers of both formats and every length, the
/// sequence number in the first four bytes, so that order and integrity are checked.
fn seq_frame(node: u8, k: u32) -> Frame {
    let len = 4 + (k % 5) as usize;
    let mut data = [0u8; 8];
    data[..4].copy_from_slice(&k.to_le_bytes());
    data[4] = node;
    data[5] = (k >> 3) as u8;
    if k.is_multiple_of(3) {
        Frame::extended(
            0x0100_0000 | (node as u32) << 16 | (k & 0xFFFF),
            &data[..len],
        )
        .expect("29-bit identifier")
    } else {
        Frame::standard(((node as u16) << 8) | (k as u16 & 0xFF), &data[..len])
            .expect("11-bit identifier")
    }
}

/// A waker that counts its wakes and marks its task ready.
#[derive(Default)]
struct Counted {
    wakes: AtomicUsize,
    ready: AtomicBool,
}

impl Wake for Counted {
    fn wake(self: Arc<Self>) {
        self.wake_by_ref();
    }
    fn wake_by_ref(self: &Arc<Self>) {
        self.wakes.fetch_add(1, Ordering::SeqCst);
        self.ready.store(true, Ordering::SeqCst);
    }
}

impl Counted {
    fn new() -> (Arc<Counted>, Waker) {
        let c = Arc::new(Counted::default());
        let w = Waker::from(c.clone());
        (c, w)
    }
    fn wakes(&self) -> usize {
        self.wakes.load(Ordering::SeqCst)
    }
}

/// The two nodes' models, their interrupt handlers, and the bus.
struct Sim<'a> {
    h: Harness,
    flex_model: FlexCanModel,
    bx_model: BxCanModel,
    flex_irq: FlexIrqs<'a>,
    bx_irq: BxIrqs<'a>,
}

struct FlexIrqs<'a> {
    tx: twocan_core::split::TxIrq<'a, FlexHw, RX_RING, Queue, 0, DONE>,
    rx: twocan_core::split::Rx0Irq<'a, FlexHw, RX_RING, Queue, 0, DONE>,
    status: twocan_core::split::StatusIrq<'a, FlexHw, RX_RING, Queue, 0, DONE>,
}

struct BxIrqs<'a> {
    tx: twocan_core::split::TxIrq<'a, BxHw, RX_RING, Queue, RX_RING, DONE>,
    rx0: twocan_core::split::Rx0Irq<'a, BxHw, RX_RING, Queue, RX_RING, DONE>,
    rx1: twocan_core::split::Rx1Irq<'a, BxHw, RX_RING, Queue, RX_RING, DONE>,
    status: twocan_core::split::StatusIrq<'a, BxHw, RX_RING, Queue, RX_RING, DONE>,
}

/// The controllers of the host harness (`FlexNode`, `BxNode`, pass-all filters), taken
/// out of their one-struct drivers to be split over local states.
fn controllers() -> (Harness, FlexCanModel, FlexHw, BxCanModel, BxHw) {
    let mut h = Harness::new(RATE).expect("bit rate");
    h.bus().borrow_mut().set_tracing(false);
    let FlexNode {
        model: fm, driver, ..
    } = FlexNode::teensy36_can0(&mut h, &[Filter::pass_all()]).expect("FlexCAN node");
    let flex = driver.release();
    let BxNode {
        model: bm, driver, ..
    } = BxNode::stm32f767_can1(&mut h, &[Filter::pass_all()]).expect("bxCAN node");
    let bx = driver.release();
    (h, fm, flex, bm, bx)
}

impl<'a> Sim<'a> {
    /// Splits the two states over the harness's controllers; the thread-side halves.
    #[allow(clippy::type_complexity)]
    fn new(
        flex_state: &'a FlexState,
        bx_state: &'a BxState,
    ) -> (
        Sim<'a>,
        (
            twocan_core::split::Tx<'a, FlexHw, RX_RING, Queue, 0, DONE>,
            twocan_core::split::Rx<'a, FlexHw, RX_RING, Queue, 0, DONE>,
        ),
        (
            twocan_core::split::Tx<'a, BxHw, RX_RING, Queue, RX_RING, DONE>,
            twocan_core::split::Rx<'a, BxHw, RX_RING, Queue, RX_RING, DONE>,
        ),
    ) {
        let (h, flex_model, flex, bx_model, bx) = controllers();
        let f: FlexParts<'a> = flex_state.split(flex).ok().expect("first split");
        let b: BxParts<'a> = bx_state.split(bx).ok().expect("first split");
        let sim = Sim {
            h,
            flex_model,
            bx_model,
            flex_irq: FlexIrqs {
                tx: f.tx_irq,
                rx: f.rx0_irq,
                status: f.status_irq,
            },
            bx_irq: BxIrqs {
                tx: b.tx_irq,
                rx0: b.rx0_irq,
                rx1: b.rx1_irq,
                status: b.status_irq,
            },
        };
        (sim, (f.tx, f.rx), (b.tx, b.rx))
    }

    /// Runs the handler of every raised interrupt line, as the chips' vectors would
    /// (bounded: a line its handler never lowers fails the test instead of hanging it).
    fn service(&mut self) {
        let mut rounds = 0u32;
        loop {
            rounds += 1;
            assert!(
                rounds <= 10_000,
                "an interrupt line stayed raised through 10,000 handler runs (FlexCAN {:?}, bxCAN {:?})",
                self.flex_model.irq(),
                self.bx_model.irq_lines()
            );
            let mut any = false;
            if self.flex_model.irq_pending() {
                // The ORed message-buffer vector and the status vectors.
                self.flex_irq.tx.on_interrupt();
                self.flex_irq.rx.on_interrupt();
                self.flex_irq.status.on_interrupt();
                any = true;
            }
            let l = self.bx_model.irq_lines();
            if l.tx {
                self.bx_irq.tx.on_interrupt();
            }
            if l.rx0 {
                self.bx_irq.rx0.on_interrupt();
            }
            if l.rx1 {
                self.bx_irq.rx1.on_interrupt();
            }
            if l.sce {
                self.bx_irq.status.on_interrupt();
            }
            any |= l.tx || l.rx0 || l.rx1 || l.sce;
            if !any {
                break;
            }
        }
    }

    /// One bus event (after servicing); `false` when nothing happens for
    /// [`STALL_BITS`].
    fn step(&mut self) -> bool {
        self.service();
        let until = self.h.now() + STALL_BITS;
        let event = self.h.bus().borrow_mut().step_until(until);
        self.service();
        event.is_some()
    }

    /// Lets the bus run `bits` bit times, servicing the interrupts.
    fn idle(&mut self, bits: u64) {
        let until = self.h.now() + bits;
        loop {
            self.service();
            if self.h.bus().borrow_mut().step_until(until).is_none() {
                break;
            }
        }
        self.service();
    }
}

type Task<'a> = Pin<Box<dyn Future<Output = ()> + 'a>>;

/// Polls every woken task, steps the bus when none is, until all tasks are done.
/// Returns the number of polls; panics on a hang (every task pending, bus idle).
fn run_tasks<'a>(sim: &mut Sim<'_>, tasks: Vec<Task<'a>>) -> u64 {
    let mut tasks: Vec<(Option<Task<'a>>, Arc<Counted>, Waker)> = tasks
        .into_iter()
        .map(|t| {
            let (c, w) = Counted::new();
            c.ready.store(true, Ordering::SeqCst);
            (Some(t), c, w)
        })
        .collect();
    let mut polls = 0;
    // Bus time of the last poll: the run fails when no task is woken for a simulated
    // second (a task waiting for a frame that never comes while the bus idles on).
    let mut last_poll = sim.h.now();
    loop {
        sim.service();
        let mut polled = false;
        for (task, c, w) in tasks.iter_mut() {
            if task.is_some() && c.ready.swap(false, Ordering::SeqCst) {
                polled = true;
                polls += 1;
                let mut cx = Context::from_waker(w);
                if task.as_mut().unwrap().as_mut().poll(&mut cx).is_ready() {
                    *task = None;
                }
            }
        }
        if tasks.iter().all(|(t, _, _)| t.is_none()) {
            return polls;
        }
        if polled {
            last_poll = sim.h.now();
        } else {
            assert!(sim.step(), "hang: every task waits and the bus is idle");
            let quiet = sim.h.now() - last_poll;
            assert!(
                quiet < 500_000,
                "hang: no task woken for {quiet} bit times ({polls} polls so far)"
            );
        }
    }
}

/// Sends frames `0..n` of `node` through the async API, drains the completions, and
/// waits for the last one; checks that every completion is `Sent`, in token order.
async fn sender<T>(tx: &mut T, node: u8, n: u32, done: &RefCell<u32>)
where
    T: AsyncCanTx + Completions,
{
    let mut next_done = None::<u32>;
    let mut check = |c: twocan_core::Completion| {
        assert_eq!(c.outcome, TxOutcome::Sent, "node {node}: {c:?}");
        let t = c.token.0;
        if let Some(prev) = next_done {
            assert_eq!(t, prev, "node {node}: completions in token order");
        }
        next_done = Some(t.wrapping_add(1));
        *done.borrow_mut() += 1;
    };
    let mut last = None;
    for k in 0..n {
        let token = tx.send(&seq_frame(node, k)).await.expect("accepted");
        last = Some(token);
        while let Some(c) = tx.take() {
            check(c);
        }
    }
    while *done.borrow() < n {
        let c = tx.wait().await;
        check(c);
    }
    if let Some(t) = last {
        assert_eq!(next_done, Some(t.0.wrapping_add(1)));
    }
}

/// Receives `n` frames of `node` and checks each against the sent sequence.
async fn receiver<R: AsyncCanRx>(rx: &mut R, node: u8, n: u32, got: &RefCell<u32>) {
    for k in 0..n {
        let f: RxFrame = rx.recv().await.expect("no receive error");
        assert_eq!(
            f.frame,
            seq_frame(node, k),
            "frame {k} from node {node}: lost, duplicated or reordered"
        );
        assert_eq!(f.filter, 0, "the pass-all filter is user filter 0");
        *got.borrow_mut() += 1;
    }
}

/// The completion half of the transmit API, for the generic sender.
trait Completions {
    fn take(&mut self) -> Option<twocan_core::Completion>;
    fn wait(&mut self) -> impl Future<Output = twocan_core::Completion>;
}

impl<H: Hardware, const RX: usize, Q: TxQueue, const RX1: usize, const D: usize> Completions
    for twocan_core::split::Tx<'_, H, RX, Q, RX1, D>
{
    fn take(&mut self) -> Option<twocan_core::Completion> {
        self.take_completion()
    }
    fn wait(&mut self) -> impl Future<Output = twocan_core::Completion> {
        self.completion()
    }
}

/// Both nodes send `n` frames to each other at once through the async API; each
/// receives exactly the other's sequence.
fn exchange(n: u32) {
    let (fs, bs) = (FlexState::new(), BxState::new());
    let (mut sim, (mut ftx, mut frx), (mut btx, mut brx)) = Sim::new(&fs, &bs);
    let counts: [RefCell<u32>; 4] = Default::default();
    let tasks: Vec<Task<'_>> = vec![
        Box::pin(sender(&mut ftx, 1, n, &counts[0])),
        Box::pin(sender(&mut btx, 2, n, &counts[1])),
        Box::pin(receiver(&mut brx, 1, n, &counts[2])),
        Box::pin(receiver(&mut frx, 2, n, &counts[3])),
    ];
    let polls = run_tasks(&mut sim, tasks);
    let counts = counts.map(|c| c.into_inner());
    assert_eq!(counts, [n; 4], "completions and receptions: {polls} polls");
    // Nothing more arrives: no duplicate came after the last frame.
    sim.idle(10_000);
    assert_eq!(frx.receive().err(), Some(nb::Error::WouldBlock));
    assert_eq!(brx.receive().err(), Some(nb::Error::WouldBlock));
    for t in [fs.traffic(), bs.traffic()] {
        assert_eq!((t.queued, t.sent, t.received), (n, n, n), "{t:?}");
        assert_eq!(t.rx_ring_overflows + t.completion_overflows, 0, "{t:?}");
    }
    assert_eq!(sim.flex_model.frames_lost(), 0);
    let s = sim.bx_model.state();
    assert_eq!(s.overruns, [0, 0]);
}

#[test]
fn async_exchange_4k_frames_each_way() {
    exchange(4_000);
}

/// The figure: 100,000 frames each way (200,000 in all). Slow in debug: CI
/// runs it in release (`cargo test --release -p twocan-tests --test async_io -- --ignored`).
#[test]
#[ignore = "100,000 frames each way: run in release (see .ci/run)"]
fn async_exchange_100k_frames_each_way() {
    exchange(100_000);
}

/// A future that the chaos loop polls at most until a seeded random drop.
type Slot<'a, T> = Option<(Pin<Box<dyn Future<Output = T> + 'a>>, Arc<Counted>, Waker)>;

/// Per direction: the sender's pending `send` and the receiver's pending `recv` are
/// dropped at seeded random points (a third of the polls find theirs dropped); the
/// sender then sends the same frame again with a new future. Checks that the receiver
/// sees the sequence exactly (a dropped `send` accepted nothing, a dropped `recv` took
/// nothing), and that a dropped future's waker is never woken afterwards.
struct Chaos<'a> {
    node: u8,
    n: u32,
    next_send: u32,
    next_recv: u32,
    send: Slot<'a, Result<Token, Error>>,
    recv: Slot<'a, Result<RxFrame, Error>>,
    dropped: Vec<(Arc<Counted>, usize)>,
    /// Pending futures dropped: sends, receives.
    drops: [u32; 2],
}

impl<'a> Chaos<'a> {
    fn new(node: u8, n: u32) -> Self {
        Chaos {
            node,
            n,
            next_send: 0,
            next_recv: 0,
            send: None,
            recv: None,
            dropped: Vec::new(),
            drops: [0; 2],
        }
    }

    fn done(&self) -> bool {
        self.next_recv == self.n
    }

    fn drop_slot<T>(slot: &mut Slot<'a, T>, dropped: &mut Vec<(Arc<Counted>, usize)>) {
        if let Some((fut, c, _w)) = slot.take() {
            drop(fut);
            let n = c.wakes();
            dropped.push((c, n));
        }
    }

    /// One round: the sender makes up to a random number of attempts (so that the
    /// transmit queue fills and sends pend), the receiver polls until it pends; before
    /// each attempt, a pending future is dropped with probability 1/3; a new future is
    /// made for the same frame (send) or the next one (receive).
    // The futures hold the half's `RefCell` borrow while they wait: one future per half
    // at a time, as `&mut` would enforce; a drop releases it.
    #[allow(clippy::await_holding_refcell_ref)]
    fn round<T: AsyncCanTx, R: AsyncCanRx>(
        &mut self,
        tx: &'a RefCell<T>,
        rx: &'a RefCell<R>,
        rng: &mut XorShift64,
    ) -> Result<(), String> {
        for _ in 0..rng.up_to(80) {
            if self.send.is_some() && rng.up_to(2) == 0 {
                Self::drop_slot(&mut self.send, &mut self.dropped);
                self.drops[0] += 1;
            }
            if self.send.is_none() {
                if self.next_send == self.n {
                    break;
                }
                let frame = seq_frame(self.node, self.next_send);
                let fut: Pin<Box<dyn Future<Output = _> + 'a>> =
                    Box::pin(async move { tx.borrow_mut().send(&frame).await });
                let (c, w) = Counted::new();
                self.send = Some((fut, c, w));
            }
            let Some((fut, _, w)) = self.send.as_mut() else {
                break;
            };
            match fut.as_mut().poll(&mut Context::from_waker(w)) {
                Poll::Ready(r) => {
                    r.expect("accepted");
                    self.next_send += 1;
                    self.send = None;
                }
                Poll::Pending => break,
            }
        }
        // The receiver drains until its future pends (a lagging receiver would only
        // overflow the ring, which is counted and not what is tested here).
        loop {
            if self.recv.is_some() && rng.up_to(2) == 0 {
                Self::drop_slot(&mut self.recv, &mut self.dropped);
                self.drops[1] += 1;
            }
            if self.recv.is_none() {
                if self.next_recv == self.n {
                    break;
                }
                let fut: Pin<Box<dyn Future<Output = _> + 'a>> =
                    Box::pin(async move { rx.borrow_mut().recv().await });
                let (c, w) = Counted::new();
                self.recv = Some((fut, c, w));
            }
            let Some((fut, _, w)) = self.recv.as_mut() else {
                break;
            };
            match fut.as_mut().poll(&mut Context::from_waker(w)) {
                Poll::Ready(r) => {
                    let f = r.map_err(|e| format!("receive error {e:?}"))?;
                    if f.frame != seq_frame(self.node, self.next_recv) {
                        return Err(format!(
                            "frame {} of node {}: lost, duplicated or reordered: got {:?}",
                            self.next_recv, self.node, f.frame
                        ));
                    }
                    self.next_recv += 1;
                    self.recv = None;
                }
                Poll::Pending => break,
            }
        }
        Ok(())
    }

    /// No dropped future's waker was woken after its drop.
    fn check_stale(&self) {
        for (c, at_drop) in &self.dropped {
            assert_eq!(c.wakes(), *at_drop, "a dropped future's waker was woken");
        }
    }
}

fn drop_mid_wait(seed: u64, n: u32) {
    let (fs, bs) = (FlexState::new(), BxState::new());
    let (mut sim, (ftx, frx), (btx, brx)) = Sim::new(&fs, &bs);
    let (ftx, frx, btx, brx) = (
        RefCell::new(ftx),
        RefCell::new(frx),
        RefCell::new(btx),
        RefCell::new(brx),
    );
    let mut rng = XorShift64::new(seed);
    // Node 1 (FlexCAN) sends to node 2's receiver (bxCAN) and the other way round.
    let mut a = Chaos::new(1, n);
    let mut b = Chaos::new(2, n);
    let mut rounds = 0u64;
    while !(a.done() && b.done()) {
        let r = a
            .round(&ftx, &brx, &mut rng)
            .and_then(|()| b.round(&btx, &frx, &mut rng));
        if let Err(e) = r {
            panic!(
                "{e} (seed {seed}, round {rounds}, bit {}): FlexCAN {:?} lost {}, bxCAN {:?} {:?}",
                sim.h.now(),
                fs.traffic(),
                sim.flex_model.frames_lost(),
                bs.traffic(),
                sim.bx_model.state().overruns
            );
        }
        // Service and let the bus move a random number of events (0 = poll again).
        for _ in 0..rng.up_to(2) {
            assert!(sim.step(), "hang with futures pending (seed {seed})");
        }
        sim.service();
        rounds += 1;
        assert!(rounds < 200 * n as u64, "no progress (seed {seed})");
    }
    for d in [a.drops, b.drops] {
        assert!(
            d.iter().all(|&k| k >= 20),
            "the run dropped sends and receives mid-wait: {d:?} (seed {seed})"
        );
    }
    eprintln!(
        "seed {seed}: dropped mid-wait (send, recv): {:?} {:?}",
        a.drops, b.drops
    );
    sim.idle(10_000);
    a.check_stale();
    b.check_stale();
    assert_eq!(
        frx.borrow_mut().receive().err(),
        Some(nb::Error::WouldBlock)
    );
    assert_eq!(
        brx.borrow_mut().receive().err(),
        Some(nb::Error::WouldBlock)
    );
    for t in [fs.traffic(), bs.traffic()] {
        assert_eq!(
            (t.queued, t.sent, t.received),
            (n, n, n),
            "{t:?} (seed {seed})"
        );
        assert_eq!(t.rx_ring_overflows, 0, "{t:?}");
    }
}

#[test]
fn async_futures_dropped_mid_wait_lose_nothing() {
    for seed in [1, 0x5EED, 0xC0FF_EE11, 42_424_242] {
        drop_mid_wait(seed, 3_000);
    }
}

/// Polls `fut` once with `w`; its output if ready.
fn poll_once<F: Future + ?Sized>(fut: Pin<&mut F>, w: &Waker) -> Option<F::Output> {
    match fut.poll(&mut Context::from_waker(w)) {
        Poll::Ready(v) => Some(v),
        Poll::Pending => None,
    }
}

/// One frame in flight at a time: the task waiting in `completed(token)` is woken
/// exactly once (by the transmit interrupt of that frame's completion), and the
/// receiving task's `recv` exactly once, on both controllers as sender.
#[test]
fn async_completion_wakes_exactly_once_per_completion() {
    let (fs, bs) = (FlexState::new(), BxState::new());
    let (mut sim, (mut ftx, mut frx), (mut btx, mut brx)) = Sim::new(&fs, &bs);
    for k in 0..400u32 {
        let from_flex = k % 2 == 0;
        let node = if from_flex { 1 } else { 2 };
        let frame = seq_frame(node, k);
        let (tc, tw) = Counted::new();
        let (rc, rw) = Counted::new();
        if from_flex {
            let token = poll_once(pin_box(ftx.send(&frame)).as_mut(), &tw)
                .expect("an empty queue takes the frame at once")
                .expect("accepted");
            let mut done = pin_box(ftx.completed(token));
            let mut got = pin_box(brx.recv());
            run_once_each(
                &mut sim, &mut done, &tw, &tc, &mut got, &rw, &rc, token, &frame,
            );
        } else {
            let token = poll_once(pin_box(btx.send(&frame)).as_mut(), &tw)
                .expect("an empty queue takes the frame at once")
                .expect("accepted");
            let mut done = pin_box(btx.completed(token));
            let mut got = pin_box(frx.recv());
            run_once_each(
                &mut sim, &mut done, &tw, &tc, &mut got, &rw, &rc, token, &frame,
            );
        }
    }
}

fn pin_box<'a, F: Future + 'a>(f: F) -> Pin<Box<dyn Future<Output = F::Output> + 'a>> {
    Box::pin(f)
}

#[allow(clippy::too_many_arguments)]
fn run_once_each(
    sim: &mut Sim<'_>,
    done: &mut Pin<Box<dyn Future<Output = Result<twocan_core::Completion, Error>> + '_>>,
    tw: &Waker,
    tc: &Counted,
    got: &mut Pin<Box<dyn Future<Output = Result<RxFrame, Error>> + '_>>,
    rw: &Waker,
    rc: &Counted,
    token: Token,
    frame: &Frame,
) {
    assert!(poll_once(done.as_mut(), tw).is_none(), "not sent yet");
    assert!(poll_once(got.as_mut(), rw).is_none(), "not received yet");
    let wakes_before = tc.wakes();
    // Run until the frame is through and the bus idles again.
    sim.idle(2_000);
    assert_eq!(tc.wakes() - wakes_before, 1, "completion waker woken once");
    assert_eq!(rc.wakes(), 1, "receiver woken once");
    let c = poll_once(done.as_mut(), tw)
        .expect("completion after the wake")
        .expect("not lost");
    assert_eq!((c.token, c.outcome), (token, TxOutcome::Sent));
    let f = poll_once(got.as_mut(), rw)
        .expect("frame after the wake")
        .expect("no receive error");
    assert_eq!(&f.frame, frame);
}

/// `Rx::event` on a bxCAN node alone on the bus: its frame is never acknowledged, so
/// each attempt adds 8 to TEC (ISO 11898-1 §12.1.4.2, acknowledge error) until the node
/// is error passive (128), where an acknowledge error no longer raises it. The task
/// waiting in `event` sees the two changes in order, warning then passive.
#[test]
fn async_event_follows_the_error_state_of_an_unacknowledged_sender() {
    use std::pin::pin;
    use twocan_core::{ErrorState, RxEvent};
    use twocan_host::executor::drive;
    use twocan_host::split::{split_bx, BxState};

    let mut h = Harness::new(500_000).expect("bit rate");
    let node = BxNode::stm32f767_can1(&mut h, &[Filter::pass_all()]).expect("bxCAN node");
    let bs = BxState::new();
    let (mut irqs, mut tx, mut rx) = split_bx(&bs, node).expect("split");
    tx.try_send(&seq_frame(2, 0)).expect("accepted");
    let seen = RefCell::new(Vec::new());
    let mut watch = pin!(async {
        for _ in 0..2 {
            match rx.event().await? {
                RxEvent::StateChange(c) => seen.borrow_mut().push((c.state, c.counters.tec)),
                RxEvent::Frame(f) => panic!("no frame expected: {f:?}"),
            }
        }
        Ok(())
    });
    let until = h.now() + 20_000;
    let done = drive(&mut h, &mut [&mut irqs], &mut [watch.as_mut()], until);
    assert!(matches!(done[0], Some(Ok(()))), "{done:?}");
    let seen = seen.borrow().clone();
    assert_eq!(seen.len(), 2, "{seen:?}");
    assert_eq!(seen[0].0, ErrorState::Warning, "{seen:?}");
    assert!((96..128).contains(&seen[0].1), "{seen:?}");
    assert_eq!(seen[1], (ErrorState::Passive, 128), "{seen:?}");
}
