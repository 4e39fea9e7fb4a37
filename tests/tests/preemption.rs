//! The transmit interrupt (and the receive and status ones) preempting the thread at
//! every register access of `try_send` and `abort`, in turn, on both controllers and in
//! both transmit orders, with frames of one identifier and of mixed identifiers (issue
//! 22; the harness is `twocan_tests::preempt`). Every run checks: one completion per
//! accepted frame, `sent + failed + aborted == queued`, the queue count back to 0, sent
//! frames on the wire once and aborted ones never, and the wire order against the
//! submission order (request order: all frames; identifier priority: frames of equal
//! priority).

use twocan_core::{FifoQueue, Frame, Lean, PriorityQueue, Registers, State, TxPolicy};
use twocan_flexcan::Configuration;
use twocan_tests::preempt::{
    bxcan_rig, bxcan_rig_with, flexcan_rig, flexcan_rig_quiet, flexcan_rig_quiet_with,
    flexcan_rig_with, flexcan_rt_rig, run_script, sweep, BxHw, FlexHw, FlexRtHw, Rig, Step, Swept,
    RX,
};

/// Frames of one identifier, told apart by their data.
fn one_identifier(n: u8) -> Vec<Frame> {
    (0..n)
        .map(|k| Frame::standard(0x123, &[k]).unwrap())
        .collect()
}

/// Data frames of mixed identifiers (some repeated, one extended), tagged by data.
fn mixed(n: u8) -> Vec<Frame> {
    let ids = [0x300u16, 0x120, 0x300, 0x7F0, 0x050, 0x120, 0x300, 0x010];
    (0..n)
        .map(|k| {
            if k % 5 == 4 {
                Frame::extended(0x0ABC_DE00 | k as u32, &[k]).unwrap()
            } else {
                Frame::standard(ids[k as usize % ids.len()], &[k]).unwrap()
            }
        })
        .collect()
}

/// Data and remote frames mixed (FlexCAN sends them from different mailboxes), tagged
/// by data or, for remote frames, by identifier and DLC.
fn data_and_remote(n: u8) -> Vec<Frame> {
    (0..n)
        .map(|k| match k % 3 {
            0 => Frame::standard(0x400 - k as u16, &[k]).unwrap(),
            1 => Frame::remote(0x200, false, (k / 3) % 9).unwrap(),
            _ => Frame::remote(0x100 + k as u32, false, 1).unwrap(),
        })
        .collect()
}

/// A frame of the peer, higher in priority than ours: our frames lose arbitration to
/// it and the receive handler runs.
fn peer_frame(k: u8) -> Frame {
    Frame::standard(0x008, &[0xEE, k]).unwrap()
}

/// Submissions with the bus moving (and stopping inside frames) in between.
fn sends(frames: &[Frame]) -> Vec<Step> {
    let mut steps = vec![Step::Peer(peer_frame(0))];
    for (i, f) in frames.iter().enumerate() {
        steps.push(Step::Send(*f));
        if i % 3 == 2 {
            steps.push(Step::Bus(23 + (17 * i as u64) % 50));
        }
        if i == 4 {
            steps.push(Step::Peer(peer_frame(1)));
        }
    }
    steps
}

/// Submissions mixing `try_send` and `try_send_now`, a `poll` from the thread, then
/// `abort_all` with frames queued and loaded.
fn sends_now_poll_abort_all(frames: &[Frame]) -> Vec<Step> {
    let mut steps = vec![Step::Peer(peer_frame(0))];
    for (i, f) in frames.iter().enumerate() {
        steps.push(if i % 4 == 1 {
            Step::SendNow(*f)
        } else {
            Step::Send(*f)
        });
        if i == 3 {
            steps.push(Step::Poll);
        }
        if i % 5 == 4 {
            steps.push(Step::Bus(31));
        }
    }
    steps.extend([Step::Poll, Step::AbortAll]);
    steps
}

/// [`sends_now_poll_abort_all`] with the bus moving after every submission and the peer
/// sending often: on FlexCAN the receive handler shares the line, and in the quiet mode
/// a data frame's end raises none, so the peer's frames are what the preempting
/// handlers find to do at most points.
fn sends_now_poll_abort_all_busy(frames: &[Frame]) -> Vec<Step> {
    let mut steps = vec![Step::Peer(peer_frame(0))];
    for (i, f) in frames.iter().enumerate() {
        steps.push(if i % 4 == 1 {
            Step::SendNow(*f)
        } else {
            Step::Send(*f)
        });
        if i == 3 {
            steps.push(Step::Poll);
        }
        if i % 2 == 1 {
            steps.push(Step::Peer(peer_frame(i as u8 + 1)));
        }
        steps.push(Step::Bus(31 + 7 * (i as u64 % 3)));
    }
    steps.extend([Step::Poll, Step::AbortAll]);
    steps
}

/// Submissions, then aborts of queued, loaded and finished frames in between bus runs.
fn sends_and_aborts(frames: &[Frame]) -> Vec<Step> {
    let n = frames.len();
    let mut steps = sends(frames);
    steps.extend([
        Step::Abort(n - 1),
        Step::Bus(41),
        Step::Abort(1),
        Step::Abort(n - 2),
        Step::Bus(60),
        Step::Abort(n - 3),
        Step::Abort(0),
    ]);
    steps
}

/// Aborts of the frame on the wire (the bus stopped inside it), of the next one, and of
/// frames just loaded: the abort races the end of the transmission.
fn aborts_on_the_wire(frames: &[Frame]) -> Vec<Step> {
    let mut steps = Vec::new();
    for (i, pair) in frames.chunks(2).enumerate() {
        let first = 2 * i;
        if i % 2 == 0 {
            steps.push(Step::Peer(peer_frame(i as u8)));
        }
        for f in pair {
            steps.push(Step::Send(*f));
        }
        steps.push(Step::Bus(20 + 9 * i as u64));
        steps.push(Step::Abort(first));
        if pair.len() == 2 && i % 2 == 1 {
            steps.push(Step::Abort(first + 1));
        }
    }
    steps
}

/// Reports a sweep's size; at least a tenth of its preemption points found a handler
/// with work to do (the sweep is not vacuous).
fn report(what: &str, swept: Swept) {
    eprintln!(
        "{what}: {} accesses, {} preemption points, {} with a handler servicing a line; \
         plain run: {} sent, {} aborted",
        swept.accesses, swept.points, swept.with_work, swept.sent_aborted.0, swept.sent_aborted.1
    );
    assert!(swept.with_work * 10 >= swept.points, "{what}: {swept:?}");
}

const N: u8 = 12;

/// One test per controller and order, frame set and scenario.
macro_rules! sweeps {
    ($($name:ident: $rig:expr, $policy:expr, $frames:expr, $scenario:ident;)*) => {$(
        #[test]
        fn $name() {
            let steps = $scenario(&$frames);
            let what = stringify!($name);
            report(what, sweep($rig, $policy, &steps, what));
        }
    )*};
}

fn bx_fifo() -> twocan_tests::preempt::Rig<BxHw, FifoQueue<4>> {
    bxcan_rig(TxPolicy::Fifo)
}

fn bx_priority() -> twocan_tests::preempt::Rig<BxHw, PriorityQueue<4>> {
    bxcan_rig(TxPolicy::Priority)
}

/// bxCAN in the quiet transmit mode: no completion ring, `Lean`, request order (the
/// transmit interrupt on only while frames are queued).
fn bx_quiet() -> twocan_tests::preempt::Rig<BxHw, FifoQueue<4>, 0, Lean> {
    bxcan_rig_with(TxPolicy::Fifo)
}

fn flex() -> twocan_tests::preempt::Rig<FlexHw, FifoQueue<4>> {
    flexcan_rig()
}

/// FlexCAN in the quiet transmit mode: no completion ring, `Lean`, request order (the
/// data mailbox's interrupt on only while frames are queued).
fn flex_quiet() -> Rig<FlexHw, FifoQueue<4>, 0, Lean> {
    flexcan_rig_quiet()
}

/// The same on a Teensy 4.1 in the RT1062 layout, ACAN's first configuration (the
/// ERR005829 reserved mailbox MB8, remote-frame mailboxes MB9–MB15, data mailbox MB16:
/// `IFLAG1`/`IMASK1`).
fn flex_rt_quiet() -> Rig<FlexRtHw, FifoQueue<4>, 0, Lean> {
    flexcan_rt_rig(Configuration::Filters8_0)
}

/// The RT1062 layout with the transmit mailboxes above MB31 (RFFN 8: `IFLAG2`/`IMASK2`).
fn flex_rt_quiet_high() -> Rig<FlexRtHw, FifoQueue<4>, 0, Lean> {
    flexcan_rt_rig(Configuration::Filters24_48)
}

use twocan_core::TxPolicy::{Fifo, Priority};

sweeps! {
    bxcan_request_order_one_identifier_send: bx_fifo, Fifo, one_identifier(N), sends;
    bxcan_request_order_one_identifier_abort: bx_fifo, Fifo, one_identifier(N), sends_and_aborts;
    bxcan_request_order_one_identifier_abort_on_the_wire: bx_fifo, Fifo, one_identifier(N), aborts_on_the_wire;
    bxcan_request_order_mixed_send: bx_fifo, Fifo, mixed(N), sends;
    bxcan_request_order_mixed_abort: bx_fifo, Fifo, mixed(N), sends_and_aborts;
    bxcan_request_order_mixed_abort_on_the_wire: bx_fifo, Fifo, mixed(N), aborts_on_the_wire;
    bxcan_quiet_one_identifier_send: bx_quiet, Fifo, one_identifier(N), sends;
    bxcan_quiet_one_identifier_abort: bx_quiet, Fifo, one_identifier(N), sends_and_aborts;
    bxcan_quiet_mixed_send: bx_quiet, Fifo, mixed(N), sends;
    bxcan_quiet_mixed_abort_on_the_wire: bx_quiet, Fifo, mixed(N), aborts_on_the_wire;
    bxcan_quiet_send_now_poll_abort_all: bx_quiet, Fifo, mixed(N), sends_now_poll_abort_all;
    bxcan_request_order_send_now_poll_abort_all: bx_fifo, Fifo, mixed(N), sends_now_poll_abort_all;
    bxcan_priority_one_identifier_send: bx_priority, Priority, one_identifier(N), sends;
    bxcan_priority_one_identifier_abort: bx_priority, Priority, one_identifier(N), sends_and_aborts;
    bxcan_priority_one_identifier_abort_on_the_wire: bx_priority, Priority, one_identifier(N), aborts_on_the_wire;
    bxcan_priority_mixed_send: bx_priority, Priority, mixed(N), sends;
    bxcan_priority_mixed_abort: bx_priority, Priority, mixed(N), sends_and_aborts;
    bxcan_priority_mixed_abort_on_the_wire: bx_priority, Priority, mixed(N), aborts_on_the_wire;
    flexcan_one_identifier_send: flex, Fifo, one_identifier(N), sends;
    flexcan_one_identifier_abort: flex, Fifo, one_identifier(N), sends_and_aborts;
    flexcan_one_identifier_abort_on_the_wire: flex, Fifo, one_identifier(N), aborts_on_the_wire;
    flexcan_mixed_send: flex, Fifo, mixed(N), sends;
    flexcan_mixed_abort: flex, Fifo, mixed(N), sends_and_aborts;
    flexcan_mixed_abort_on_the_wire: flex, Fifo, mixed(N), aborts_on_the_wire;
    flexcan_data_and_remote_send: flex, Fifo, data_and_remote(N), sends;
    flexcan_data_and_remote_abort: flex, Fifo, data_and_remote(N), sends_and_aborts;
    flexcan_data_and_remote_abort_on_the_wire: flex, Fifo, data_and_remote(N), aborts_on_the_wire;
    flexcan_data_and_remote_send_now_poll_abort_all: flex, Fifo, data_and_remote(N), sends_now_poll_abort_all_busy;
    flexcan_quiet_one_identifier_send: flex_quiet, Fifo, one_identifier(N), sends;
    flexcan_quiet_one_identifier_abort: flex_quiet, Fifo, one_identifier(N), sends_and_aborts;
    flexcan_quiet_mixed_send: flex_quiet, Fifo, mixed(N), sends;
    flexcan_quiet_mixed_abort_on_the_wire: flex_quiet, Fifo, mixed(N), aborts_on_the_wire;
    flexcan_quiet_send_now_poll_abort_all: flex_quiet, Fifo, mixed(N), sends_now_poll_abort_all_busy;
    flexcan_quiet_data_and_remote_send: flex_quiet, Fifo, data_and_remote(N), sends;
    flexcan_quiet_data_and_remote_abort: flex_quiet, Fifo, data_and_remote(N), sends_and_aborts;
    flexcan_quiet_data_and_remote_send_now_poll_abort_all: flex_quiet, Fifo, data_and_remote(N), sends_now_poll_abort_all_busy;
    flexcan_rt1062_quiet_mixed_send: flex_rt_quiet, Fifo, mixed(N), sends;
    flexcan_rt1062_quiet_data_and_remote_abort: flex_rt_quiet, Fifo, data_and_remote(N), sends_and_aborts;
    flexcan_rt1062_quiet_send_now_poll_abort_all: flex_rt_quiet, Fifo, data_and_remote(N), sends_now_poll_abort_all_busy;
    flexcan_rt1062_high_quiet_mixed_send: flex_rt_quiet_high, Fifo, mixed(N), sends;
    flexcan_rt1062_high_quiet_data_and_remote_abort_on_the_wire: flex_rt_quiet_high, Fifo, data_and_remote(N), aborts_on_the_wire;
    flexcan_rt1062_high_quiet_send_now_poll_abort_all: flex_rt_quiet_high, Fifo, data_and_remote(N), sends_now_poll_abort_all_busy;
}

#[test]
fn flexcan_abort_during_a_retry_loop_takes_effect() {
    // Nobody acknowledges: the frame is sent again and again (acknowledge errors), the
    // module transmitting most of the time and no message-buffer interrupt coming. An
    // abort asked while the frame is on the wire must still end it, aborted, without a
    // transmit-half call after it (the split handlers: the error line runs the status
    // handler only).
    let mut rig =
        flexcan_rig_with::<FifoQueue<4>>(twocan_sim::SimNode::new().with_listen_only(true));
    let f = Frame::standard(0x123, &[1]).unwrap();
    let t = rig.tx.try_send(&f).unwrap();
    rig.bus.borrow_mut().run_bits(300);
    rig.preemption.run_handlers();
    rig.bus.borrow_mut().run_bits(25);
    assert!(rig.bus.borrow().in_frame(), "on the wire");
    assert_eq!(rig.tx.abort(t), twocan_core::AbortRequest::Requested);
    for _ in 0..20 {
        rig.preemption.run_handlers();
        rig.bus.borrow_mut().run_bits(100);
    }
    rig.preemption.run_handlers();
    let c = rig.tx.take_completion().expect("the abort took effect");
    assert_eq!((c.token, c.outcome), (t, twocan_core::TxOutcome::Aborted));
    let t = rig.state.traffic();
    assert_eq!((t.queued, t.sent, t.aborted), (1, 0, 1));
    assert!(
        !rig.bus.borrow().in_frame() && rig.bus.borrow_mut().step().is_none(),
        "no more attempts"
    );
}

/// The quiet mode is what `bx_quiet` runs (settled at compile time), and in it the
/// transmit interrupt is enabled exactly while frames wait in the queue: after a burst
/// that had to queue, the queue drains through the interrupt and `CAN_IER.TMEIE` is
/// off again; frames sent one at a time with the bus idle in between leave without
/// any transmit interrupt (the line never rises).
#[test]
fn bxcan_quiet_mode_enables_the_transmit_interrupt_only_while_frames_wait() {
    // Settled at compile time: checked by the compiler.
    const {
        assert!(State::<BxHw, RX, FifoQueue<4>, RX, 0, Lean>::QUIET_TX);
        assert!(!State::<BxHw, RX, FifoQueue<4>, RX, 0, twocan_core::Full>::QUIET_TX);
        assert!(!State::<BxHw, RX, FifoQueue<4>, RX, 8, Lean>::QUIET_TX);
        assert!(!State::<BxHw, RX, PriorityQueue<4>, RX, 0, Lean>::QUIET_TX);
    }
    let ier = |rig: &twocan_tests::preempt::Rig<BxHw, FifoQueue<4>, 0, Lean>| {
        rig.state
            .hardware()
            .unwrap()
            .registers()
            .read32(twocan_bxcan::regs::IER)
    };
    let tmeie = twocan_bxcan::regs::ier::TMEIE;

    // Split: nothing queued, the interrupt off; the other enables as configured.
    let rig = bx_quiet();
    assert_eq!(ier(&rig) & tmeie, 0);
    assert_ne!(ier(&rig) & twocan_bxcan::regs::ier::FMPIE0, 0);
    // A burst of eight: three go to the mailboxes, the rest queue and are refilled
    // from the interrupt; at the end the queue is empty and the interrupt off.
    let burst: Vec<Step> = one_identifier(8).into_iter().map(Step::Send).collect();
    let rig = bx_quiet();
    let state = rig.state;
    let o = run_script(rig, &burst, None);
    o.check(TxPolicy::Fifo, "quiet burst");
    assert_eq!(o.wire.len(), 8);
    let hw = state.hardware().unwrap();
    assert_eq!(hw.registers().read32(twocan_bxcan::regs::IER) & tmeie, 0);
    drop(hw);

    // One at a time, the bus idle in between: no transmit interrupt at all.
    let mut rig = bx_quiet();
    let bus = rig.bus.clone();
    for k in 0..6u8 {
        let f = Frame::standard(0x200, &[k]).unwrap();
        rig.tx.try_send(&f).unwrap();
        for _ in 0..4 {
            bus.borrow_mut().step();
            assert_eq!(ier(&rig) & tmeie, 0, "frame {k}: the interrupt stays off");
        }
    }
    assert_eq!(rig.peer.borrow().received_frames().len(), 6);
    assert_eq!(rig.tx.stats().count, 0);
}

/// The data mailbox's interrupt enable of a FlexCAN rig (`IMASK1` bit 15 on the
/// Teensy 3.6), the Rx FIFO's (`BUF5I`, `BUF7I`) and the remote-frame mailboxes'
/// ([`remote_bits`]), read from the model.
fn flex_masks(rig: &Rig<FlexHw, FifoQueue<4>, 0, Lean>) -> (bool, u32, u32) {
    let imask = rig
        .state
        .hardware()
        .unwrap()
        .registers()
        .read32(twocan_flexcan::regs::IMASK1);
    let fifo = twocan_flexcan::regs::iflag1::BUF5I | twocan_flexcan::regs::iflag1::BUF7I;
    (imask & 1 << 15 != 0, imask & fifo, imask & remote_bits(rig))
}

/// Whether the data mailbox (MB15) of a FlexCAN rig holds a pending frame (code `DATA`)
/// with its flag set: a stale flag from the end of an earlier frame, which would keep
/// the message-buffer line raised and make the handler take the new frame for ended.
fn stale_flag(rig: &Rig<FlexHw, FifoQueue<4>, 0, Lean>) -> bool {
    let hw = rig.state.hardware().unwrap();
    let r = hw.registers();
    let pending = twocan_flexcan::regs::cs::CODE.get(r.read32(twocan_flexcan::regs::mb_cs(15)))
        == twocan_flexcan::regs::code::TX_DATA;
    pending && r.read32(twocan_flexcan::regs::IFLAG1) & 1 << 15 != 0
}

/// The remote-frame mailboxes' bits of a FlexCAN rig (MB12–MB14 in ACAN's default
/// configuration).
fn remote_bits(rig: &Rig<FlexHw, FifoQueue<4>, 0, Lean>) -> u32 {
    let first = rig
        .state
        .hardware()
        .unwrap()
        .configuration()
        .first_remote_mailbox();
    0x7FFF >> first << first
}

/// The quiet mode is what `flex_quiet` runs (settled at compile time), and in it the data
/// mailbox's interrupt is enabled exactly while frames wait in the queue: frames sent one
/// at a time with the bus idle in between leave without the message-buffer line ever
/// rising (nothing received either: the peer is silent); a burst that had to queue
/// raises it and is refilled from it, and the enable is off again once the queue is
/// empty. The Rx FIFO's enables and the remote-frame mailboxes' are never touched.
#[test]
fn flexcan_quiet_mode_enables_the_data_mailbox_interrupt_only_while_frames_wait() {
    const {
        assert!(State::<FlexHw, RX, FifoQueue<4>, RX, 0, Lean>::QUIET_TX);
        assert!(!State::<FlexHw, RX, FifoQueue<4>, RX, 0, twocan_core::Full>::QUIET_TX);
        assert!(!State::<FlexHw, RX, FifoQueue<4>, RX, 8, Lean>::QUIET_TX);
    }
    let fifo = twocan_flexcan::regs::iflag1::BUF5I | twocan_flexcan::regs::iflag1::BUF7I;
    let rig = flex_quiet();
    let remote = remote_bits(&rig);
    assert_ne!(remote, 0);
    assert_eq!(
        flex_masks(&rig),
        (false, fifo, remote),
        "split: the data mailbox's off"
    );

    // One at a time, the bus idle in between: the line never rises.
    let mut rig = flex_quiet();
    let bus = rig.bus.clone();
    for k in 0..6u8 {
        let f = Frame::standard(0x200, &[k]).unwrap();
        rig.tx.try_send(&f).unwrap();
        assert!(!stale_flag(&rig), "frame {k}: loaded with its flag clear");
        for _ in 0..4 {
            bus.borrow_mut().step();
            assert!(
                !rig.preemption.run_handlers(),
                "frame {k}: no message-buffer interrupt"
            );
            assert_eq!(flex_masks(&rig), (false, fifo, remote), "frame {k}");
        }
    }
    assert_eq!(rig.peer.borrow().received_frames().len(), 6);
    assert_eq!(rig.tx.stats().count, 0);

    // A burst of five: one goes to the data mailbox, the rest queue (the enable on) and
    // are refilled from the interrupt; at the end the queue is empty and the enable off.
    let mut rig = flex_quiet();
    let bus = rig.bus.clone();
    let burst = one_identifier(5);
    for f in &burst {
        rig.tx.try_send(f).unwrap();
    }
    assert_eq!(flex_masks(&rig), (true, fifo, remote), "frames wait");
    let mut entries = 0;
    for _ in 0..40 {
        bus.borrow_mut().step();
        entries += rig.preemption.run_handlers() as usize;
        assert!(
            !stale_flag(&rig),
            "a refilled mailbox loaded with its flag clear"
        );
    }
    assert_eq!(entries, 4, "one interrupt per refill");
    assert_eq!(rig.peer.borrow().received_frames(), burst);
    assert_eq!(flex_masks(&rig), (false, fifo, remote), "queue empty");
}

/// The quiet mode keeps FlexCAN's remote-frame path: `try_send_now` puts a remote frame
/// straight into a remote-frame mailbox beside a pending data frame (and it leaves first
/// when its identifier wins), while `try_send` keeps one frame of the request order in a
/// mailbox at a time (a frame behind a pending one waits in the queue, whatever their
/// identifiers).
#[test]
fn flexcan_quiet_mode_keeps_the_remote_frame_mailboxes() {
    let mut rig = flex_quiet();
    let data = Frame::standard(0x400, &[1]).unwrap();
    let now = Frame::remote(0x100, false, 0).unwrap();
    let later = Frame::remote(0x101, false, 0).unwrap();
    rig.tx.try_send(&data).unwrap();
    rig.tx
        .try_send_now(&now)
        .expect("a remote-frame mailbox, whatever is loaded");
    rig.tx.try_send(&later).unwrap();
    assert_eq!(
        rig.tx.stats().count,
        1,
        "the request order's remote frame waits"
    );
    for _ in 0..40 {
        rig.bus.borrow_mut().step();
        rig.preemption.run_handlers();
    }
    assert_eq!(rig.peer.borrow().received_frames(), vec![now, data, later]);
    assert_eq!(rig.tx.stats().count, 0);
    // A data frame whose identifier would win behind a pending remote frame of the
    // request order waits for it too.
    let remote = Frame::remote(0x300, false, 0).unwrap();
    let urgent = Frame::standard(0x050, &[2]).unwrap();
    rig.tx.try_send(&remote).unwrap();
    rig.tx.try_send(&urgent).unwrap();
    assert_eq!(
        rig.tx.stats().count,
        1,
        "the data frame waits for the remote frame"
    );
    for _ in 0..40 {
        rig.bus.borrow_mut().step();
        rig.preemption.run_handlers();
    }
    assert_eq!(
        rig.peer.borrow().received_frames()[3..],
        [remote, urgent],
        "request order"
    );
    // Every remote-frame mailbox made inactive again (their interrupt stayed on).
    let first = rig
        .state
        .hardware()
        .unwrap()
        .configuration()
        .first_remote_mailbox();
    let hw = rig.state.hardware().unwrap();
    for mb in usize::from(first)..15 {
        let cs = hw.registers().read32(twocan_flexcan::regs::mb_cs(mb));
        assert_eq!(
            twocan_flexcan::regs::cs::CODE.get(cs),
            twocan_flexcan::regs::code::TX_INACTIVE,
            "MB{mb}"
        );
    }
}

/// Listen-only and stopped refuse the quiet mode's direct path exactly as the other
/// mode's: a typed error, the frame not accepted.
#[test]
fn flexcan_quiet_mode_refuses_to_send_in_listen_only_and_sleep() {
    use twocan_core::{BusMode, Error, Mode};
    let mut rig = flex_quiet();
    let f = Frame::standard(0x10, &[]).unwrap();
    rig.rx.set_mode(Mode::Stopped).unwrap();
    rig.rx.set_bus_mode(BusMode::ListenOnly).unwrap();
    rig.rx.set_mode(Mode::Normal).unwrap();
    assert_eq!(rig.tx.try_send(&f), Err(nb::Error::Other(Error::WrongMode)));
    assert_eq!(
        rig.tx.try_send_now(&f),
        Err(nb::Error::Other(Error::WrongMode))
    );
    let r = Frame::remote(0x10, false, 0).unwrap();
    assert_eq!(
        rig.tx.try_send_now(&r),
        Err(nb::Error::Other(Error::WrongMode))
    );
    rig.rx.set_mode(Mode::Stopped).unwrap();
    rig.rx.set_bus_mode(BusMode::Normal).unwrap();
    rig.rx.set_mode(Mode::Sleep).unwrap();
    assert_eq!(rig.tx.try_send(&f), Err(nb::Error::Other(Error::WrongMode)));
    assert_eq!(
        rig.tx.try_send_now(&f),
        Err(nb::Error::Other(Error::WrongMode))
    );
    rig.rx.set_mode(Mode::Normal).unwrap();
    assert!(rig.tx.try_send(&f).is_ok());
    assert_eq!(rig.state.traffic().queued, 0, "Lean: no counters");
}

/// In the quiet mode `loaded` keeps mailboxes whose end was never acknowledged, and every
/// query confirms with the mailbox: the abort of a frame already sent finds nothing
/// (`NotFound`) and the mailbox reads empty; the abort of a pending one is requested,
/// and the aborted data mailbox (code ABORT, its flag set, no interrupt to acknowledge
/// it) takes the next frame at once, from `try_send` and from `try_send_now`.
#[test]
fn flexcan_quiet_mode_queries_confirm_with_the_mailbox() {
    use twocan_core::{AbortRequest, Hardware, MailboxId, MailboxState};
    use twocan_flexcan::regs::{code, cs, mb_cs, mb_id, IFLAG1};
    let state_of = |rig: &Rig<FlexHw, FifoQueue<4>, 0, Lean>| {
        rig.state.hardware().unwrap().mailbox_state(MailboxId(0))
    };
    let mut rig = flex_quiet();
    let bus = rig.bus.clone();
    let sent = Frame::standard(0x123, &[1]).unwrap();
    let t = rig.tx.try_send(&sent).unwrap();
    assert_eq!(state_of(&rig), MailboxState::Pending);
    for _ in 0..4 {
        bus.borrow_mut().step();
        assert!(!rig.preemption.run_handlers());
    }
    assert_eq!(rig.peer.borrow().received_frames(), vec![sent]);
    assert_eq!(
        state_of(&rig),
        MailboxState::Empty,
        "sent, not acknowledged"
    );
    assert_eq!(rig.tx.abort(t), AbortRequest::NotFound);

    // Nobody acknowledges: a frame stays pending (retried) until aborted.
    let mut rig = flexcan_rig_quiet_with::<FifoQueue<4>, 0, Lean>(
        twocan_sim::SimNode::new().with_listen_only(true),
    );
    let regs = |rig: &Rig<FlexHw, FifoQueue<4>, 0, Lean>, offset| {
        rig.state.hardware().unwrap().registers().read32(offset)
    };
    let a = rig
        .tx
        .try_send(&Frame::standard(0x124, &[2]).unwrap())
        .unwrap();
    rig.bus.borrow_mut().run_bits(300);
    assert_eq!(state_of(&rig), MailboxState::Pending);
    assert_eq!(rig.tx.abort(a), AbortRequest::Requested);
    rig.bus.borrow_mut().run_bits(100);
    assert_eq!(state_of(&rig), MailboxState::Empty);
    assert_eq!(cs::CODE.get(regs(&rig, mb_cs(15))), code::TX_ABORT);
    assert_ne!(regs(&rig, IFLAG1) & 1 << 15, 0, "aborted, not acknowledged");
    let b = Frame::standard(0x125, &[3]).unwrap();
    rig.tx.try_send(&b).expect("the aborted mailbox, at once");
    assert_eq!(rig.tx.stats().count, 0, "loaded directly");
    assert_eq!(regs(&rig, mb_id(15)) >> 18, 0x125);
    let c = rig
        .tx
        .try_send(&Frame::standard(0x126, &[4]).unwrap())
        .unwrap();
    assert_eq!(rig.tx.abort(c), AbortRequest::Dequeued);
    rig.tx.abort_all();
    rig.bus.borrow_mut().run_bits(100);
    assert_eq!(cs::CODE.get(regs(&rig, mb_cs(15))), code::TX_ABORT);
    let d = Frame::standard(0x127, &[5]).unwrap();
    rig.tx
        .try_send_now(&d)
        .expect("the aborted mailbox, at once");
    assert_eq!(regs(&rig, mb_id(15)) >> 18, 0x127);
    assert_eq!(state_of(&rig), MailboxState::Pending);
    assert_eq!(rig.tx.stats().count, 0);
}
