//! Issue 27: receive backlog on both controllers. Frames arrive while the receive
//! interrupt is not serviced (masked, or its handler delayed): exactly as many as the
//! hardware FIFO holds (3 in a bxCAN FIFO, RM0410 §40.7.5; 6 in the FlexCAN Rx FIFO,
//! K66 RM "Rx FIFO"), then more. Every frame that fit is delivered, in order, with the
//! right contents; the FIFO flags (bxCAN `FULLx`/`FOVRx`; FlexCAN `IFLAG1.BUF6I`
//! warning, `BUF7I` overflow) are raised by the burst, acknowledged by one service, and
//! each overrun is counted exactly once; after the service no interrupt line stays
//! asserted.

use twocan_bxcan::regs::{rfxr, RF0R, RF1R};
use twocan_bxcan::FifoPolicy;
use twocan_core::{Filter, Frame, Registers};
use twocan_flexcan::regs::{iflag1, IFLAG1};
use twocan_host::{BxNode, FlexNode, Harness};
use twocan_tests::backend::{bxcan_config, Backend, Dut, FlexCanBackend, NodeOptions, Recovery};
use twocan_tests::support::{acked, attach_peer, drain, run, std_frame, Peer};

const RATE: u32 = 500_000;

/// The FIFO's flags as the hardware shows them: (frames pending, warning or full,
/// overrun).
trait FifoFlags: Dut {
    fn fifo(&self) -> (u32, bool, bool);
}

impl FifoFlags for FlexNode {
    fn fifo(&self) -> (u32, bool, bool) {
        let f = self.model.read32(IFLAG1);
        (
            u32::from(f & iflag1::BUF5I != 0),
            f & iflag1::BUF6I != 0,
            f & iflag1::BUF7I != 0,
        )
    }
}

/// A bxCAN node and the FIFO its filters feed.
struct Bx(BxNode, usize);

impl twocan_host::Serviced for Bx {
    fn service(&mut self) -> bool {
        self.0.service()
    }
}

impl Dut for Bx {
    type C = <BxNode as Dut>::C;
    fn driver(&mut self) -> &mut twocan_core::Driver<Self::C, 64, 32, 64> {
        self.0.driver()
    }
    fn driver_ref(&self) -> &twocan_core::Driver<Self::C, 64, 32, 64> {
        self.0.driver_ref()
    }
    fn bus_id(&self) -> twocan_sim::NodeId {
        self.0.bus_id()
    }
    fn irq_pending(&self) -> bool {
        self.0.irq_pending()
    }
    fn hw_lost(&self) -> u64 {
        self.0.hw_lost()
    }
    fn filtered_out(&self) -> u64 {
        self.0.filtered_out()
    }
    fn bitrate_in_registers(&self) -> u32 {
        self.0.bitrate_in_registers()
    }
}

impl FifoFlags for Bx {
    fn fifo(&self) -> (u32, bool, bool) {
        let r = self.0.model.read32(if self.1 == 0 { RF0R } else { RF1R });
        (rfxr::FMP.get(r), r & rfxr::FULL != 0, r & rfxr::FOVR != 0)
    }
}

fn flexcan(h: &mut Harness) -> FlexNode {
    let mut n = FlexCanBackend::attach(h, &NodeOptions::pass_all()).expect("FlexCAN node");
    run(h, &mut n, 20);
    n
}

fn bxcan(h: &mut Harness, fifo: usize) -> Bx {
    let config = bxcan_config(RATE, Recovery::Automatic).expect("bxCAN config");
    let policy = if fifo == 0 {
        FifoPolicy::Fifo0
    } else {
        FifoPolicy::Fifo1
    };
    let mut n = Bx(
        BxNode::with_config(h, &config, &[Filter::pass_all()], policy).expect("bxCAN node"),
        fifo,
    );
    run(h, &mut n, 20);
    n
}

/// `n` distinct frames numbered from `first` (identifier and data carry the number).
fn burst(first: usize, n: usize) -> Vec<Frame> {
    (first..first + n)
        .map(|k| std_frame(0x200 + k as u16, &[k as u8, !(k as u8), 0x5A]))
        .collect()
}

/// The peer sends `frames` back to back while nothing services the node; the bus alone
/// runs (bounded) until they are all acknowledged.
fn unserviced<N: Dut>(h: &mut Harness, dut: &N, peer: &Peer, frames: &[Frame], what: &str) {
    let before = acked(peer).len();
    for f in frames {
        peer.borrow_mut().send(*f);
    }
    h.bus()
        .borrow_mut()
        .run_until_idle(200_000)
        .unwrap_or_else(|e| {
            panic!("{what}: the burst did not end within 200,000 bit times: {e:?}")
        });
    assert_eq!(
        &acked(peer)[before..],
        frames,
        "{what}: every frame of the burst acknowledged (the node's controller did)"
    );
    assert!(
        dut.irq_pending(),
        "{what}: the burst raised the receive line"
    );
}

/// The frames a full FIFO of `depth` keeps of `burst`: the first ones (FlexCAN; bxCAN
/// with `RFLM` = 1), or the first `depth - 1` and the newest (bxCAN with `RFLM` = 0, the
/// reset value: "the last message stored in the FIFO will be overwritten", RM0410
/// §40.7.5).
fn kept(burst: &[Frame], depth: usize, overwrite_newest: bool) -> Vec<Frame> {
    if overwrite_newest {
        let mut v = burst[..depth - 1].to_vec();
        v.push(*burst.last().expect("a burst"));
        v
    } else {
        burst[..depth].to_vec()
    }
}

/// The whole scenario on one node whose FIFO holds `depth` frames, the flag that says
/// "`warn_at` frames or more" (FlexCAN warning at 5, bxCAN `FULL` at 3).
fn backlog<N: FifoFlags>(
    h: &mut Harness,
    dut: &mut N,
    depth: usize,
    warn_at: usize,
    overwrite_newest: bool,
    what: &str,
) {
    let (peer, _) = attach_peer(h, "peer");
    let overruns = |d: &N| d.driver_ref().error_stats().hardware_overruns;
    let warnings = |d: &N| d.driver_ref().error_stats().hardware_fifo_warnings;
    assert!(
        depth >= warn_at,
        "{what}: a full FIFO is at its warning level"
    );

    // 1. Exactly as many frames as the FIFO holds: the warning (or full) flag, no
    //    overrun; one service delivers them all in order and acknowledges the flag.
    let fits = burst(0, depth);
    unserviced(h, dut, &peer, &fits, what);
    let (pending, warn, over) = dut.fifo();
    assert!(pending > 0, "{what}: frames pending before the service");
    assert!(
        depth < warn_at || warn,
        "{what}: {depth} frames raise the warning/full flag"
    );
    assert!(!over, "{what}: {depth} frames fit: no overrun flag");
    dut.driver().on_interrupt();
    assert_eq!(
        dut.fifo(),
        (0, false, false),
        "{what}: FIFO emptied, flags acknowledged"
    );
    assert!(
        !dut.irq_pending(),
        "{what}: no line left asserted after the service"
    );
    let got: Vec<Frame> = drain(dut).iter().map(|r| r.frame).collect();
    assert_eq!(got, fits, "{what}: every frame that fit, in order, intact");
    assert_eq!(overruns(dut), 0, "{what}: no overrun counted");
    assert_eq!(
        warnings(dut),
        1,
        "{what}: the warning/full flag counted once"
    );
    assert_eq!(dut.hw_lost(), 0, "{what}: nothing lost in hardware");

    // 2. Three more than it holds: the first `depth` kept, 3 lost, one overrun counted.
    let over_burst = burst(100, depth + 3);
    unserviced(h, dut, &peer, &over_burst, what);
    assert!(dut.fifo().2, "{what}: the overrun flag raised");
    dut.driver().on_interrupt();
    assert_eq!(
        dut.fifo(),
        (0, false, false),
        "{what}: flags acknowledged after the overrun"
    );
    assert!(
        !dut.irq_pending(),
        "{what}: no line left asserted after the overrun"
    );
    let got: Vec<Frame> = drain(dut).iter().map(|r| r.frame).collect();
    assert_eq!(
        got,
        kept(&over_burst, depth, overwrite_newest),
        "{what}: the frames the FIFO kept, in order"
    );
    assert_eq!(dut.hw_lost(), 3, "{what}: 3 frames lost in hardware");
    assert_eq!(overruns(dut), 1, "{what}: one overrun counted");
    assert_eq!(
        warnings(dut),
        2,
        "{what}: the warning raised again, counted once"
    );

    // 3. Serviced traffic afterwards: the overrun is not counted again (its flag was
    //    acknowledged), and frames flow as usual.
    let after = burst(200, 2);
    for f in &after {
        peer.borrow_mut().send(*f);
    }
    run(h, dut, 2_000);
    let got: Vec<Frame> = drain(dut).iter().map(|r| r.frame).collect();
    assert_eq!(got, after, "{what}: serviced frames after the overrun");
    assert_eq!(overruns(dut), 1, "{what}: still one overrun");
    assert_eq!(
        warnings(dut),
        2,
        "{what}: serviced traffic raises no warning"
    );
    assert!(!dut.irq_pending(), "{what}: idle lines");

    // 4. A second overrun: counted once more, exactly.
    let again = burst(300, depth + 1);
    unserviced(h, dut, &peer, &again, what);
    dut.driver().on_interrupt();
    let got: Vec<Frame> = drain(dut).iter().map(|r| r.frame).collect();
    assert_eq!(
        got,
        kept(&again, depth, overwrite_newest),
        "{what}: second overrun, the frames the FIFO kept"
    );
    assert_eq!(overruns(dut), 2, "{what}: two overruns counted");
    assert_eq!(warnings(dut), 3, "{what}: three warnings counted");
    assert_eq!(dut.hw_lost(), 4, "{what}: 3 + 1 frames lost");
    // Every frame the peer sent is either delivered or counted lost.
    let delivered = dut.driver_ref().traffic().received;
    assert_eq!(
        u64::from(delivered) + dut.hw_lost(),
        acked(&peer).len() as u64,
        "{what}: received + lost = sent"
    );
}

#[test]
fn flexcan_rx_fifo_backlog_six_then_more() {
    let mut h = Harness::new(RATE).unwrap();
    let mut dut = flexcan(&mut h);
    backlog(&mut h, &mut dut, 6, 5, false, "FlexCAN Rx FIFO");
}

#[test]
fn bxcan_fifo0_backlog_three_then_more() {
    let mut h = Harness::new(RATE).unwrap();
    let mut dut = bxcan(&mut h, 0);
    backlog(&mut h, &mut dut, 3, 3, true, "bxCAN FIFO 0");
}

#[test]
fn bxcan_fifo1_backlog_three_then_more() {
    let mut h = Harness::new(RATE).unwrap();
    let mut dut = bxcan(&mut h, 1);
    backlog(&mut h, &mut dut, 3, 3, true, "bxCAN FIFO 1");
}

/// A delayed handler while traffic goes on: the node is serviced only every `every`
/// frames' worth of bus time (its handler late by up to that), with bursts that fit the
/// FIFO; nothing is lost, nothing reordered, no overrun.
fn delayed_handler<N: FifoFlags>(h: &mut Harness, dut: &mut N, depth: usize, what: &str) {
    let (peer, _) = attach_peer(h, "peer");
    let mut sent = Vec::new();
    for round in 0..5 {
        let frames = burst(10 * round, depth);
        unserviced(h, dut, &peer, &frames, what);
        sent.extend(frames);
        // The handler runs late, once, then the bus goes on a little serviced.
        run(h, dut, 50);
    }
    let got: Vec<Frame> = drain(dut).iter().map(|r| r.frame).collect();
    assert_eq!(got, sent, "{what}: all frames, in order");
    assert_eq!(
        dut.driver_ref().error_stats().hardware_overruns,
        0,
        "{what}"
    );
    assert_eq!(
        dut.driver_ref().error_stats().hardware_fifo_warnings,
        5,
        "{what}: each of the 5 bursts filled the FIFO to its warning level once"
    );
    assert_eq!(dut.hw_lost(), 0, "{what}");
}

#[test]
fn delayed_receive_handler_loses_nothing_that_fits() {
    let mut h = Harness::new(RATE).unwrap();
    let mut dut = flexcan(&mut h);
    delayed_handler(&mut h, &mut dut, 6, "FlexCAN");
    let mut h = Harness::new(RATE).unwrap();
    let mut dut = bxcan(&mut h, 0);
    delayed_handler(&mut h, &mut dut, 3, "bxCAN FIFO 0");
    let mut h = Harness::new(RATE).unwrap();
    let mut dut = bxcan(&mut h, 1);
    delayed_handler(&mut h, &mut dut, 3, "bxCAN FIFO 1");
}
