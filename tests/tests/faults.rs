//! Issue 6, item 3: fault scenarios on both controllers. Each one ends with every frame
//! either delivered (a plain ISO node on the bus counts what it got) or counted by the
//! driver (failed, aborted) or by the hardware (lost in a FIFO overrun).

use twocan_bxcan::regs::{msr, MSR};
use twocan_bxcan::FifoPolicy;
use twocan_core::{Error, ErrorState, Filter, Frame, MailboxId, Mode, Priority, Registers};
use twocan_host::{BxNode, Harness, Serviced};
use twocan_sim::{Fault, NodeId, SimNode, TxResult};
use twocan_tests::backend::{
    bxcan_config, Backend, BxCanBackend, Dut, FlexCanBackend, ManualRecoveryCount, NodeOptions,
    OverrunPolicy, Recovery, Refused,
};
use twocan_tests::support::{
    acked, attach_peer, attach_sim, drain, ext_frame, remote_frame, run, settle, std_frame, Peer,
};

const RATE: u32 = 500_000;
/// ISO 11898-1: bus-off recovery waits for 128 occurrences of 11 consecutive recessive bits.
const RECOVERY_BITS: u64 = 128 * 11;

fn node<B: Backend>(h: &mut Harness, opts: &NodeOptions) -> B::Node {
    let mut n = B::attach(h, opts).unwrap_or_else(|e| panic!("{}: {e:?}", B::NAME));
    run(h, &mut n, 20); // synchronised to the idle bus
    n
}

/// Runs until `cond` holds (servicing the node after every bus event) or `max_bits`
/// pass; gives whether it held and every error state seen on the way.
fn run_until<N: Dut>(
    h: &mut Harness,
    dut: &mut N,
    max_bits: u64,
    mut cond: impl FnMut(&mut N) -> bool,
) -> (bool, Vec<ErrorState>) {
    let end = h.now() + max_bits;
    let mut states = vec![dut.driver().state()];
    loop {
        if cond(dut) {
            return (true, states);
        }
        if h.now() >= end {
            return (false, states);
        }
        run(h, dut, 1);
        let s = dut.driver().state();
        if states.last() != Some(&s) {
            states.push(s);
        }
    }
}

// --- lone node --------------------------------------------------------------------------

fn lone_node_goes_error_passive_never_bus_off<B: Backend>() {
    let mut h = Harness::new(RATE).unwrap();
    let mut dut = node::<B>(&mut h, &NodeOptions::pass_all());
    let f = std_frame(0x0A5, &[1, 2, 3]);
    dut.driver().try_send(&f).unwrap();
    // Nobody acknowledges: acknowledge error, TEC + 8 per attempt up to 128 (error
    // passive); then ISO 11898-1 exception: an error-passive transmitter that sees no
    // dominant bit in its passive error flag after an acknowledge error keeps its TEC.
    let (_, states) = run_until(&mut h, &mut dut, 50_000, |_| false);
    assert_eq!(dut.driver_ref().counters().tec, 128, "{}", B::NAME);
    assert_eq!(dut.driver().state(), ErrorState::Passive, "{}", B::NAME);
    assert!(
        !states.contains(&ErrorState::BusOff),
        "{}: {states:?}",
        B::NAME
    );
    assert_eq!(
        states,
        [ErrorState::Active, ErrorState::Warning, ErrorState::Passive],
        "{}",
        B::NAME
    );
    assert!(dut.driver_ref().error_stats().acknowledge >= 16);
    assert_eq!(dut.driver_ref().traffic().sent, 0);
    // The frame is not lost: a node joins, acknowledges, gets it once; TEC - 1.
    let (peer, _) = attach_peer(&h, "peer");
    settle(&mut h, &mut dut, &[&peer], 10_000);
    assert_eq!(peer.borrow().received_frames(), vec![f], "{}", B::NAME);
    assert_eq!(dut.driver_ref().traffic().sent, 1);
    assert_eq!(dut.driver_ref().counters().tec, 127);
}

// --- bus-off ----------------------------------------------------------------------------

/// 32 bit errors on the node's transmissions: TEC + 8 each → 256 → bus-off. Gives the
/// bus time when the driver saw bus-off.
fn drive_to_bus_off<N: Dut>(h: &mut Harness, dut: &mut N, f: &Frame) -> u64 {
    let me = dut.bus_id();
    h.bus()
        .borrow_mut()
        .inject_from(me, 32, Fault::Bit { at: None });
    dut.driver().try_send(f).unwrap();
    let (off, states) = run_until(h, dut, 20_000, |d| d.driver().state() == ErrorState::BusOff);
    assert!(off, "{states:?}");
    assert_eq!(
        states,
        [
            ErrorState::Active,
            ErrorState::Warning,
            ErrorState::Passive,
            ErrorState::BusOff
        ]
    );
    assert_eq!(
        dut.driver_ref().counters().tec,
        256,
        "TEC reads 256 while bus-off"
    );
    assert_eq!(dut.driver_ref().error_stats().bus_off, 1);
    assert_eq!(dut.driver_ref().error_stats().bit, 32);
    assert_eq!(
        dut.driver().try_send(&std_frame(1, &[])),
        Err(nb::Error::Other(Error::BusOff))
    );
    h.now()
}

fn bus_off_then_automatic_recovery<B: Backend>() {
    let mut h = Harness::new(RATE).unwrap();
    let mut dut = node::<B>(&mut h, &NodeOptions::pass_all());
    let (peer, _) = attach_peer(&h, "peer");
    let f = std_frame(0x066, &[6]);
    let t = drive_to_bus_off(&mut h, &mut dut, &f);
    // Recovery needs 128 × 11 recessive bits; the node's own error delimiter and the
    // intermission (11 bits) may already count as the first sequence.
    let (early, _) = run_until(&mut h, &mut dut, RECOVERY_BITS - 11 - 20, |d| {
        d.driver().state() != ErrorState::BusOff
    });
    assert!(!early, "{}: left bus-off before 128 × 11 bits", B::NAME);
    let (back, _) = run_until(&mut h, &mut dut, 100, |d| {
        d.driver().state() == ErrorState::Active
    });
    assert!(back, "{}: not active after {} bits", B::NAME, h.now() - t);
    assert_eq!(dut.driver_ref().counters().tec, 0);
    assert_eq!(dut.driver_ref().counters().rec, 0);
    // The frame that was pending goes out after recovery: delivered once.
    settle(&mut h, &mut dut, &[&peer], 10_000);
    assert_eq!(peer.borrow().received_frames(), vec![f], "{}", B::NAME);
    assert_eq!(dut.driver_ref().traffic().sent, 1);
}

fn bus_off_then_manual_recovery<B: Backend>() {
    let mut h = Harness::new(RATE).unwrap();
    let opts = NodeOptions::pass_all().recovery(Recovery::Manual);
    if !B::MANUAL_RECOVERY {
        // FlexCAN (ACAN): CTRL1.BOFFREC = 0, recovery is automatic and cannot be held.
        assert!(matches!(
            B::attach(&mut h, &opts),
            Err(Refused::Unsupported(_))
        ));
        let mut dut = node::<B>(&mut h, &NodeOptions::pass_all());
        let (_peer, _) = attach_peer(&h, "peer");
        drive_to_bus_off(&mut h, &mut dut, &std_frame(0x77, &[]));
        assert_eq!(
            dut.driver().recover(),
            Err(twocan_core::Error::WrongMode),
            "refused: nothing to start, recovery is automatic"
        );
        let (back, _) = run_until(&mut h, &mut dut, RECOVERY_BITS + 100, |d| {
            d.driver().state() == ErrorState::Active
        });
        assert!(back);
        return;
    }
    let mut dut = node::<B>(&mut h, &opts);
    let (peer, _) = attach_peer(&h, "peer");
    let f = std_frame(0x077, &[7, 7]);
    drive_to_bus_off(&mut h, &mut dut, &f);
    // Ten times the recovery time: still bus-off without software.
    let (left, _) = run_until(&mut h, &mut dut, 10 * RECOVERY_BITS, |d| {
        d.driver().state() != ErrorState::BusOff
    });
    assert!(!left, "{}: recovered without software", B::NAME);
    assert!(peer.borrow().received_frames().is_empty());
    // Software starts the recovery; 128 × 11 recessive bits later the node is active.
    dut.driver().recover().unwrap();
    let t = h.now();
    let (back, _) = run_until(&mut h, &mut dut, RECOVERY_BITS + 100, |d| {
        d.driver().state() == ErrorState::Active
    });
    assert!(back, "{}", B::NAME);
    // bxCAN counts the 128 × 11 recessive bits from the request; FlexCAN counted them
    // while bus-off and is back at once (Kinetis RM, CTRL1.BOFFREC).
    let at_least = match B::MANUAL_RECOVERY_COUNT {
        ManualRecoveryCount::FromRequest => RECOVERY_BITS - 11,
        ManualRecoveryCount::FromBusOff => 0,
    };
    assert!(h.now() - t >= at_least, "{}: {} bits", B::NAME, h.now() - t);
    assert_eq!(dut.driver_ref().counters().tec, 0);
    settle(&mut h, &mut dut, &[&peer], 10_000);
    assert_eq!(peer.borrow().received_frames(), vec![f], "{}", B::NAME);
}

// --- receive FIFO overrun ---------------------------------------------------------------

/// The peer sends `depth + extra` frames back to back while the node's interrupt is not
/// serviced; then it is, once. The FIFO keeps `depth` frames by its overrun rule.
fn overrun_burst<N: Dut>(
    h: &mut Harness,
    dut: &mut N,
    peer: &Peer,
    depth: usize,
    policy: OverrunPolicy,
    what: &str,
) {
    let extra = 4;
    let frames: Vec<Frame> = (0..depth + extra)
        .map(|k| std_frame(0x100 + k as u16, &[k as u8]))
        .collect();
    for f in &frames {
        peer.borrow_mut().send(*f);
    }
    // The bus alone: nothing services the node.
    h.bus().borrow_mut().run_until_idle(100_000).unwrap();
    assert_eq!(acked(peer), frames, "{what}");
    dut.driver().on_interrupt();
    let got: Vec<Frame> = drain(dut).iter().map(|r| r.frame).collect();
    let kept: Vec<Frame> = match policy {
        OverrunPolicy::DiscardNew => frames[..depth].to_vec(),
        OverrunPolicy::OverwriteNewest => {
            let mut v = frames[..depth - 1].to_vec();
            v.push(*frames.last().unwrap());
            v
        }
    };
    assert_eq!(got, kept, "{what}");
    assert_eq!(dut.hw_lost(), extra as u64, "{what}: lost frames counted");
    assert_eq!(
        frames.len() as u64,
        got.len() as u64 + dut.hw_lost(),
        "{what}: sent = received + lost"
    );
    // The hardware flags an overrun, it does not count frames: one overrun seen.
    assert_eq!(
        dut.driver_ref().error_stats().hardware_overruns,
        1,
        "{what}"
    );
}

fn rx_fifo_overrun<B: Backend>() {
    let mut h = Harness::new(RATE).unwrap();
    let mut dut = node::<B>(&mut h, &NodeOptions::pass_all());
    let (peer, _) = attach_peer(&h, "peer");
    overrun_burst(
        &mut h,
        &mut dut,
        &peer,
        B::RX_FIFO_DEPTH,
        B::OVERRUN,
        B::NAME,
    );
}

#[test]
fn bxcan_rx_fifo_overrun_locked_keeps_the_oldest() {
    // RFLM = 1: a full FIFO discards the new frame (RM0410 §40.7.5 "locked mode").
    let mut h = Harness::new(RATE).unwrap();
    let config = bxcan_config(RATE, Recovery::Automatic)
        .unwrap()
        .rx_fifo_lock(true);
    let mut dut =
        BxNode::with_config(&mut h, &config, &[Filter::pass_all()], FifoPolicy::Fifo0).unwrap();
    run(&mut h, &mut dut, 20);
    let (peer, _) = attach_peer(&h, "peer");
    overrun_burst(
        &mut h,
        &mut dut,
        &peer,
        3,
        OverrunPolicy::DiscardNew,
        "bxCAN RFLM = 1",
    );
}

// --- transmit abort ---------------------------------------------------------------------

fn transmit_abort<B: Backend>() {
    let mut h = Harness::new(RATE).unwrap();
    let mut dut = node::<B>(&mut h, &NodeOptions::pass_all());
    let (peer, _) = attach_peer(&h, "peer");
    // The peer keeps the bus busy with identifiers that always win arbitration.
    for k in 0..60u8 {
        peer.borrow_mut().send(std_frame(0x001, &[k]));
    }
    let ours: Vec<Frame> = (0..3).map(|k| std_frame(0x7F0 + k, &[k as u8])).collect();
    for f in &ours {
        dut.driver().try_send(f).unwrap();
    }
    run(&mut h, &mut dut, 1_000);
    assert_eq!(
        dut.driver_ref().traffic().sent,
        0,
        "{}: lost every arbitration",
        B::NAME
    );
    assert!(
        h.bus()
            .borrow()
            .node_stats(dut.bus_id())
            .unwrap()
            .arbitration_lost
            > 0
    );
    let dropped = dut.driver().abort_all();
    settle(&mut h, &mut dut, &[&peer], 50_000);
    let t = dut.driver_ref().traffic();
    assert_eq!(t.queued, 3);
    assert_eq!(t.sent, 0, "{}", B::NAME);
    assert_eq!(
        t.aborted,
        3,
        "{}: {dropped} dropped from the queue",
        B::NAME
    );
    // None of them reached the bus.
    let on_bus = peer.borrow().received_frames();
    assert!(on_bus.iter().all(|f| !ours.contains(f)), "{}", B::NAME);
    assert_eq!(acked(&peer).len(), 60);
    for m in 0..3 {
        assert_eq!(
            dut.driver_ref().mailbox_state(MailboxId(m)),
            twocan_core::MailboxState::Empty
        );
    }
}

// --- sleep ------------------------------------------------------------------------------

fn sleep_then_software_wake_up<B: Backend>() {
    let mut h = Harness::new(RATE).unwrap();
    let mut dut = node::<B>(&mut h, &NodeOptions::pass_all());
    let (peer, _) = attach_peer(&h, "peer");
    let (witness, _) = attach_sim(&h, "witness", SimNode::new());
    dut.driver().set_mode(Mode::Sleep).unwrap();
    assert_eq!(dut.driver().state(), ErrorState::Sleeping, "{}", B::NAME);
    // Asleep: the node neither receives nor acknowledges (the witness does).
    let a = std_frame(0x0A0, &[0xA]);
    peer.borrow_mut().send(a);
    settle(&mut h, &mut dut, &[&peer], 10_000);
    assert_eq!(witness.borrow().received_frames(), vec![a]);
    assert!(drain(&mut dut).is_empty(), "{}", B::NAME);
    assert_eq!(dut.driver_ref().traffic().received, 0);
    // Software wakes it; it synchronises and receives again.
    dut.driver().set_mode(Mode::Normal).unwrap();
    run(&mut h, &mut dut, 20);
    assert_eq!(dut.driver().state(), ErrorState::Active, "{}", B::NAME);
    let b = std_frame(0x0B0, &[0xB]);
    peer.borrow_mut().send(b);
    settle(&mut h, &mut dut, &[&peer], 10_000);
    let got: Vec<Frame> = drain(&mut dut).iter().map(|r| r.frame).collect();
    assert_eq!(got, vec![b], "{}", B::NAME);
}

#[test]
fn bxcan_sleep_then_wake_up_on_bus_activity() {
    // AWUM: bus activity wakes the controller (WKUI), which then waits for 11 recessive
    // bits before it takes part: the frame that woke it is not received (RM0410 §40.4.3).
    let mut h = Harness::new(RATE).unwrap();
    let config = bxcan_config(RATE, Recovery::Automatic)
        .unwrap()
        .auto_wakeup(true);
    let mut dut =
        BxNode::with_config(&mut h, &config, &[Filter::pass_all()], FifoPolicy::Fifo0).unwrap();
    run(&mut h, &mut dut, 20);
    let (peer, _) = attach_peer(&h, "peer");
    let (witness, _) = attach_sim(&h, "witness", SimNode::new());
    dut.driver.set_mode(Mode::Sleep).unwrap();
    assert_eq!(dut.driver.state(), ErrorState::Sleeping);
    dut.driver.on_interrupt(); // SLAKI acknowledged
    while dut.driver.take_state_change().is_some() {}
    run(&mut h, &mut dut, 500);
    assert_eq!(
        dut.driver.state(),
        ErrorState::Sleeping,
        "no activity, no wake-up"
    );
    let a = std_frame(0x0A0, &[0xA]);
    peer.borrow_mut().send(a);
    // The bus alone (no interrupt service): the wake-up interrupt is raised.
    h.bus().borrow_mut().step();
    assert_ne!(dut.model.read32(MSR) & msr::WKUI, 0, "WKUI");
    assert!(dut.model.irq_lines().sce, "wake-up interrupt line");
    // Serviced: WKUI acknowledged, the driver sees sleeping → active.
    settle(&mut h, &mut dut, &[&peer], 10_000);
    assert_eq!(dut.model.read32(MSR) & msr::WKUI, 0);
    assert_eq!(
        dut.driver.take_state_change().map(|c| c.state),
        Some(ErrorState::Active)
    );
    assert_eq!(dut.driver.shared_state().wakeups(), 1);
    assert_eq!(dut.driver.wakeups(), 1);
    assert!(dut.driver.capabilities().wakeup_events);
    assert_eq!(witness.borrow().received_frames(), vec![a]);
    assert!(
        drain(&mut dut).is_empty(),
        "the wake-up frame is not received"
    );
    let b = std_frame(0x0B0, &[0xB]);
    peer.borrow_mut().send(b);
    settle(&mut h, &mut dut, &[&peer], 10_000);
    let got: Vec<Frame> = drain(&mut dut).iter().map(|r| r.frame).collect();
    assert_eq!(got, vec![b]);
}

// --- one-shot (bxCAN NART) --------------------------------------------------------------

#[test]
fn bxcan_one_shot_failure_is_counted_not_retried() {
    let mut h = Harness::new(RATE).unwrap();
    let config = bxcan_config(RATE, Recovery::Automatic)
        .unwrap()
        .one_shot(true);
    let mut dut =
        BxNode::with_config(&mut h, &config, &[Filter::pass_all()], FifoPolicy::Fifo0).unwrap();
    run(&mut h, &mut dut, 20);
    let (peer, peer_id) = attach_peer(&h, "peer");
    // 1. An error: NART tries once, the frame is reported failed, never retried.
    h.bus()
        .borrow_mut()
        .inject_from(dut.id, 1, Fault::Bit { at: None });
    let a = std_frame(0x300, &[1]);
    dut.driver.try_send(&a).unwrap();
    settle(&mut h, &mut dut, &[&peer], 5_000);
    let t = dut.driver.traffic();
    assert_eq!((t.sent, t.failed), (0, 1), "{t:?}");
    assert_eq!(h.bus().borrow().node_stats(dut.id).unwrap().tx_errors, 1);
    // 2. Arbitration lost: also the end of a one-shot frame (RM0410: "transmitted only
    //    once, independently of the result (successful, error or arbitration lost)").
    let b = std_frame(0x301, &[2]);
    let winner = std_frame(0x001, &[0]);
    peer.borrow_mut().send(winner);
    dut.driver.try_send(&b).unwrap();
    settle(&mut h, &mut dut, &[&peer], 5_000);
    let t = dut.driver.traffic();
    assert_eq!((t.sent, t.failed), (0, 2), "{t:?}");
    // 3. Success.
    let c = std_frame(0x302, &[3]);
    dut.driver.try_send(&c).unwrap();
    settle(&mut h, &mut dut, &[&peer], 5_000);
    let t = dut.driver.traffic();
    assert_eq!((t.queued, t.sent, t.failed), (3, 1, 2), "{t:?}");
    assert_eq!(
        peer.borrow().received_frames(),
        vec![c],
        "failed frames never reach the bus"
    );
    let _ = peer_id;
}

// --- arbitration between the two controllers --------------------------------------------

#[test]
fn arbitration_between_flexcan_and_bxcan() {
    // Each pair is handed to the two drivers at the same idle point; the frame that
    // `Priority` ranks first goes first, the loser retries and arrives right after.
    let pairs: [(Frame, Frame, bool); 6] = [
        // (FlexCAN's, bxCAN's, FlexCAN wins) — written from the CAN rules.
        (std_frame(0x200, &[1]), std_frame(0x100, &[2]), false), // lower identifier
        (std_frame(0x100, &[3]), std_frame(0x200, &[4]), true),
        (ext_frame(0x100 << 18, &[5]), std_frame(0x100, &[6]), false), // SRR/IDE recessive
        (std_frame(0x300, &[7]), remote_frame(0x300, false, 1), true), // RTR recessive
        (
            remote_frame(0x0123_4567, true, 2),
            ext_frame(0x0123_4567, &[8]),
            false,
        ),
        // An extended identifier's first 11 bits are its base: 0x0000_0001 has base 0.
        (ext_frame(0x0000_0001, &[9]), std_frame(0x001, &[10]), true),
    ];
    let mut h = Harness::new(RATE).unwrap();
    let mut flex = node::<FlexCanBackend>(&mut h, &NodeOptions::pass_all());
    let mut bx = node::<BxCanBackend>(&mut h, &NodeOptions::pass_all());
    let (flex_id, bx_id): (NodeId, NodeId) = (flex.id, bx.id);
    for (k, (ff, bf, flex_wins)) in pairs.iter().enumerate() {
        assert_eq!(Priority::of(ff) < Priority::of(bf), *flex_wins, "pair {k}");
        h.bus().borrow_mut().trace_mut().clear();
        flex.driver.try_send(ff).unwrap();
        bx.driver.try_send(bf).unwrap();
        h.run_for(2_000, &mut [&mut flex as &mut dyn Serviced, &mut bx]);
        let bus = h.bus().borrow();
        let records: Vec<_> = bus
            .trace()
            .records()
            .iter()
            .filter(|r| !r.internal)
            .collect();
        assert_eq!(records.len(), 2, "pair {k}: two attempts, no error");
        let (first, second, loser) = if *flex_wins {
            (ff, bf, bx_id)
        } else {
            (bf, ff, flex_id)
        };
        assert_eq!(records[0].frame, *first, "pair {k}");
        assert_eq!(records[0].arbitration_losers, vec![loser], "pair {k}");
        assert!(records[0].is_error_free() && records[1].is_error_free());
        assert_eq!(records[1].frame, *second, "pair {k}: the loser retried");
        assert!(records[1].arbitration_losers.is_empty());
        drop(bus);
        let at_bx: Vec<Frame> = std::iter::from_fn(|| bx.driver.receive().ok())
            .map(|r| r.frame)
            .collect();
        let at_flex: Vec<Frame> = std::iter::from_fn(|| flex.driver.receive().ok())
            .map(|r| r.frame)
            .collect();
        assert_eq!((at_bx, at_flex), (vec![*ff], vec![*bf]), "pair {k}");
    }
    let n = pairs.len() as u32;
    assert_eq!(flex.driver.traffic().sent, n);
    assert_eq!(bx.driver.traffic().sent, n);
    let lost_flex = pairs.iter().filter(|p| !p.2).count() as u64;
    let bus = h.bus().borrow();
    assert_eq!(bus.node_stats(flex_id).unwrap().arbitration_lost, lost_flex);
    assert_eq!(
        bus.node_stats(bx_id).unwrap().arbitration_lost,
        pairs.len() as u64 - lost_flex
    );
    assert!(bus
        .trace()
        .records()
        .iter()
        .all(|r| r.reports.iter().all(|p| !matches!(
            p.outcome,
            twocan_sim::NodeOutcome::Transmitted(TxResult::Error(_))
        ))));
}

macro_rules! suite {
    ($module:ident, $backend:ty) => {
        mod $module {
            use super::*;

            #[test]
            fn lone_node_goes_error_passive_never_bus_off() {
                super::lone_node_goes_error_passive_never_bus_off::<$backend>();
            }
            #[test]
            fn bus_off_then_automatic_recovery() {
                super::bus_off_then_automatic_recovery::<$backend>();
            }
            #[test]
            fn bus_off_then_manual_recovery() {
                super::bus_off_then_manual_recovery::<$backend>();
            }
            #[test]
            fn rx_fifo_overrun() {
                super::rx_fifo_overrun::<$backend>();
            }
            #[test]
            fn transmit_abort() {
                super::transmit_abort::<$backend>();
            }
            #[test]
            fn sleep_then_software_wake_up() {
                super::sleep_then_software_wake_up::<$backend>();
            }
        }
    };
}

suite!(flexcan, FlexCanBackend);
suite!(bxcan, BxCanBackend);

#[test]
fn harness_stm32_node_recovers_from_bus_off_by_itself() {
    let mut h = Harness::new(RATE).unwrap();
    let mut dut = BxNode::stm32f767_can1(&mut h, &[Filter::pass_all()]).unwrap();
    run(&mut h, &mut dut, 20);
    let (peer, _) = attach_peer(&h, "peer");
    let f = std_frame(0x099, &[9]);
    drive_to_bus_off(&mut h, &mut dut, &f);
    let (back, _) = run_until(&mut h, &mut dut, RECOVERY_BITS + 100, |d| {
        d.driver().state() == ErrorState::Active
    });
    assert!(back, "still bus-off after 128 × 11 recessive bits");
    settle(&mut h, &mut dut, &[&peer], 10_000);
    assert_eq!(peer.borrow().received_frames(), vec![f]);
}
