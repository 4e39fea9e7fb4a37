//! Regression tests of issue 26 ("Soundness first"): what the split driver's safe API
//! must never allow, tried from several threads. Small enough for Miri (`.ci/run` runs
//! this file under it, with several scheduler seeds), which reports a data race where a
//! native run may only see wrong values.

use std::marker::PhantomData;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Barrier;

use twocan_core::mock::{MockFilterList, MockHardware};
use twocan_core::split::State;
use twocan_core::timing::Timing;
use twocan_core::{
    AnyQueue, BusMode, BusOffRecovery, Capabilities, Error, ErrorStatus, FifoEvents, FifoQueue,
    Frame, Hardware, MailboxId, MailboxState, Mode, RxFrame, Settled, StatusEvents, Token,
    TxPolicy,
};

/// Rounds of each race: many natively, a few under Miri (each is slow there).
const ROUNDS: usize = if cfg!(miri) { 4 } else { 300 };

/// Item 1: a context that polls `State::hardware()` while another splits never reads a
/// controller that is not written yet (`split` claims, writes, then publishes).
#[test]
fn hardware_is_never_seen_before_it_is_written() {
    for _ in 0..ROUNDS {
        let state: State<MockHardware, 4, FifoQueue<2>> = State::new();
        std::thread::scope(|s| {
            let reader = s.spawn(|| loop {
                if let Some(hw) = state.hardware() {
                    return hw.mailbox_count();
                }
                std::hint::spin_loop();
            });
            let timer = s.spawn(|| {
                // Any context may refresh the time stamps: never before the controller.
                for _ in 0..50 {
                    state.refresh_timestamps();
                    let _ = state.error_status();
                }
            });
            let parts = state.split(MockHardware::new(3)).ok().unwrap();
            assert_eq!(
                reader.join().unwrap(),
                3,
                "a controller read before it was written"
            );
            timer.join().unwrap();
            drop(parts);
        });
    }
}

/// Found by reading (issue 26): `split` ran `AnyQueue::adopt` before claiming the state,
/// so a losing concurrent `split` could switch the winner's queue to its own order.
#[test]
fn a_losing_split_leaves_the_winners_queue_order_alone() {
    let frame = |id| Frame::standard(id, &[]).unwrap();
    for _ in 0..ROUNDS {
        let state: State<MockHardware, 4, AnyQueue<4>> = State::new();
        let start = Barrier::new(2);
        let both_tried = Barrier::new(2);
        let orders = std::thread::scope(|s| {
            let contender = |policy: TxPolicy| {
                let (state, start, both_tried) = (&state, &start, &both_tried);
                s.spawn(move || {
                    let hw = MockHardware::new(1).with_policy(policy);
                    start.wait();
                    let parts = state.split(hw);
                    both_tried.wait();
                    let mut p = parts.ok()?;
                    // One mailbox: the first frame takes it, the two others queue.
                    for id in [0x300, 0x200, 0x100] {
                        p.tx.try_send(&frame(id)).unwrap();
                    }
                    let hw = state.hardware().unwrap();
                    for _ in 0..4 {
                        hw.complete();
                        p.tx_irq.on_interrupt();
                    }
                    let sent: Vec<u32> = hw.sent().iter().map(|f| f.raw_id()).collect();
                    Some((policy, sent))
                })
            };
            let a = contender(TxPolicy::Fifo);
            let b = contender(TxPolicy::Priority);
            [a.join().unwrap(), b.join().unwrap()]
        });
        let (policy, sent) = orders.into_iter().flatten().next().expect("one split wins");
        let b = sent.iter().position(|&id| id == 0x200).unwrap();
        let c = sent.iter().position(|&id| id == 0x100).unwrap();
        match policy {
            TxPolicy::Fifo => assert!(b < c, "request order lost: {sent:x?}"),
            TxPolicy::Priority => assert!(c < b, "identifier order lost: {sent:x?}"),
        }
    }
}

/// A controller for these tests: the mock, with two receive queues that hand out
/// `feed[q]` frames each (from whichever context drains them), and a marker `M` that
/// decides the controller's `Send`/`Sync`.
struct Fed<M = ()> {
    mock: MockHardware,
    feed: [AtomicU32; 2],
    _marker: PhantomData<M>,
}

impl<M> Fed<M> {
    fn new(frames: [u32; 2]) -> Self {
        Fed {
            mock: MockHardware::new(3),
            feed: frames.map(AtomicU32::new),
            _marker: PhantomData,
        }
    }
}

// SAFETY: the mock keeps every `Hardware` promise (one critical section around its
// state); `feed` is atomic, each queue's counter decremented by its one `read_rx`
// context.
unsafe impl<M> Hardware for Fed<M> {
    type Raw = Frame;
    type FilterMap = MockFilterList;
    type Filters = MockFilterList;
    const RX_QUEUES: usize = 2;

    fn tx_policy(&self) -> TxPolicy {
        self.mock.tx_policy()
    }
    fn free_mailbox(&self, frame: &Frame) -> Result<Option<u8>, Error> {
        self.mock.free_mailbox(frame)
    }
    unsafe fn load(&self, mailbox: u8, frame: &Frame, token: Token) {
        // SAFETY: the caller's contract, passed on.
        unsafe { self.mock.load(mailbox, frame, token) }
    }
    unsafe fn settle<F: FnMut(Settled)>(&self, f: F) {
        // SAFETY: the caller's contract, passed on.
        unsafe { self.mock.settle(f) }
    }
    fn mailbox_count(&self) -> u8 {
        self.mock.mailbox_count()
    }
    fn mailbox_state(&self, mailbox: MailboxId) -> MailboxState {
        self.mock.mailbox_state(mailbox)
    }
    unsafe fn request_abort(&self, token: Token) -> bool {
        // SAFETY: the caller's contract, passed on.
        unsafe { self.mock.request_abort(token) }
    }
    unsafe fn abort_all_mailboxes(&self) {
        // SAFETY: the caller's contract, passed on.
        unsafe { self.mock.abort_all_mailboxes() }
    }
    unsafe fn read_rx(&self, queue: usize, events: &mut FifoEvents) -> Option<Frame> {
        let left = &self.feed[queue];
        let n = left.load(Ordering::Relaxed);
        if n > 0 {
            left.store(n - 1, Ordering::Relaxed);
            events.overrun = true;
            return Some(Frame::standard(queue as u16, &[]).unwrap());
        }
        // SAFETY: the caller's contract, passed on.
        (queue == 0).then(|| unsafe { self.mock.read_rx(0, events) })?
    }
    unsafe fn decode(&self, raw: &Frame, map: &MockFilterList) -> Option<RxFrame> {
        // SAFETY: the caller's contract, passed on.
        unsafe { self.mock.decode(raw, map) }
    }
    unsafe fn install_filters(&self, filters: &MockFilterList) -> Result<MockFilterList, Error> {
        // SAFETY: the caller's contract, passed on.
        unsafe { self.mock.install_filters(filters) }
    }
    unsafe fn filter_map(&self) -> MockFilterList {
        // SAFETY: the caller's contract, passed on.
        unsafe { self.mock.filter_map() }
    }
    unsafe fn take_status(&self) -> StatusEvents {
        // SAFETY: the caller's contract, passed on.
        unsafe { self.mock.take_status() }
    }
    fn error_status(&self) -> ErrorStatus {
        self.mock.error_status()
    }
    fn on_bus(&self) -> bool {
        self.mock.on_bus()
    }
    unsafe fn set_mode(&self, mode: Mode) -> Result<(), Error> {
        // SAFETY: the caller's contract, passed on.
        unsafe { self.mock.set_mode(mode) }
    }
    unsafe fn recover(&self) -> Result<(), Error> {
        // SAFETY: the caller's contract, passed on.
        unsafe { self.mock.recover() }
    }
    fn capabilities(&self) -> Capabilities {
        self.mock.capabilities()
    }
    fn bus_mode(&self) -> BusMode {
        self.mock.bus_mode()
    }
    fn bus_off_recovery(&self) -> BusOffRecovery {
        self.mock.bus_off_recovery()
    }
    unsafe fn set_timing(&self, timing: &Timing) -> Result<(), Error> {
        // SAFETY: the caller's contract, passed on.
        unsafe { self.mock.set_timing(timing) }
    }
    unsafe fn set_bus_mode(&self, mode: BusMode) -> Result<(), Error> {
        // SAFETY: the caller's contract, passed on.
        unsafe { self.mock.set_bus_mode(mode) }
    }
}

/// Whether `T: Sync`, decided at compile time (an inherent constant whose bound fails
/// gives way to the trait's).
struct Probe<T: ?Sized>(PhantomData<T>);
trait NotSync {
    const SYNC: bool = false;
}
impl<T: ?Sized> NotSync for Probe<T> {}
impl<T: ?Sized + Sync> Probe<T> {
    const SYNC: bool = true;
}

/// `Sync` but not `Send` (a guard must be released on the thread that took it).
type SyncNotSend = std::sync::MutexGuard<'static, ()>;

/// Item 2: sharing a `State` lets any thread move a controller in (`split` through
/// `&State`) that the owner drops later on its own thread, so the state may be shared
/// only when the controller may move between threads (`H: Send`), as for `OnceLock`.
#[test]
fn a_state_is_shared_only_over_a_controller_that_may_move() {
    let sync = [
        // The probe sees a `Sync` controller.
        Probe::<Fed<SyncNotSend>>::SYNC,
        // A state over it must not be `Sync`: the controller is not `Send`.
        Probe::<State<Fed<SyncNotSend>, 4, FifoQueue<2>>>::SYNC,
        Probe::<State<Fed, 4, FifoQueue<2>>>::SYNC,
        Probe::<State<MockHardware, 4, FifoQueue<2>>>::SYNC,
    ];
    assert_eq!(sync, [true, false, true, true]);
}

/// Item 8: bxCAN's RX0 and RX1 handlers preempt each other when their priorities
/// differ; neither may lose the other's counts (received frames, hardware overruns).
#[test]
fn two_receive_handlers_lose_no_counts() {
    const CALLS: u32 = if cfg!(miri) { 40 } else { 200_000 };
    let state: State<Fed, 4, FifoQueue<2>, 4> = State::new();
    let p = state.split(Fed::new([0, 0])).ok().unwrap();
    let hw = state.hardware().unwrap();
    let (mut rx0, mut rx1) = (p.rx0_irq, p.rx1_irq);
    std::thread::scope(|s| {
        s.spawn(|| {
            for _ in 0..CALLS {
                // One frame with an overrun per interrupt (the feed is this queue's).
                hw.feed[0].store(1, Ordering::Relaxed);
                rx0.on_interrupt();
            }
        });
        s.spawn(|| {
            for _ in 0..CALLS {
                hw.feed[1].store(1, Ordering::Relaxed);
                rx1.on_interrupt();
            }
        });
    });
    assert_eq!(state.traffic().received, 2 * CALLS);
    assert_eq!(state.error_stats().hardware_overruns, 2 * CALLS);
}

/// Found by reading (issue 26): `AbortRequest::NotFound` said "completed already", but
/// a frame whose mailbox ended and was not settled yet is not found, and its completion
/// comes afterwards. The documentation now says so; this is the case it describes.
#[test]
fn not_found_may_still_have_its_completion_to_come() {
    use twocan_core::{AbortRequest, TxOutcome};
    let state: State<MockHardware, 4, FifoQueue<2>> = State::new();
    let mut p = state.split(MockHardware::new(1)).ok().unwrap();
    let token = p.tx.try_send(&Frame::standard(0x10, &[]).unwrap()).unwrap();
    state.hardware().unwrap().complete(); // sent; the transmit interrupt has not run
    assert_eq!(p.tx.abort(token), AbortRequest::NotFound);
    assert_eq!(p.tx.take_completion(), None, "not delivered yet");
    p.tx_irq.on_interrupt();
    let done = p.tx.take_completion().unwrap();
    assert_eq!((done.token, done.outcome), (token, TxOutcome::Sent));
}
