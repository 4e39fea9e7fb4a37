//! Instructions per frame and stack high-water marks of our FlexCAN split driver and of
//! a hand-written register-level FlexCAN service (`shared/flexcan_hand.rs`), on a
//! Cortex-M4 under QEMU (`-machine mps2-an386`), counted by the TCG plugin
//! `bench/plugin/insn_count.c` between marker stores. Built twice, with feature `lean`
//! and with feature `full` (`shared/flexcan_variant.rs`). The register block stand-in,
//! its snapshots and the write-1-to-clear accessor are in `shared/ram_flexcan.rs`, the
//! markers and the stack painting in `shared/qemu.rs`.
//!
//! Both drivers run on the same block, one after the other, each configured while the
//! SysTick stand-in plays the `MCR` handshakes:
//!
//! - **ours**: a `static State` of the variant's type over `FlexCanHw`, split once; the
//!   transmit half's `try_send` (MB15 free), the transmit handler (MB15's completion),
//!   the Rx FIFO handler (one frame), the receive half's `receive` and, full,
//!   `take_completion`;
//! - **hand-written**: its transmit, Rx FIFO interrupt, take and, full, MB15 interrupt
//!   and completion take.
//!
//! On FlexCAN one interrupt line (ORed message buffers) runs both the transmit and the
//! receive handler; each is measured on its own, from a snapshot holding only its
//! event, on both sides.
#![no_std]
#![no_main]

use core::hint::black_box;

use cortex_m_rt::entry;
use twocan_core::{Frame, Registers, RxFrame, TxOutcome};

#[path = "../../shared/feature_sets.rs"]
mod feature_sets;
#[path = "../../shared/flexcan_hand.rs"]
mod hand;
#[path = "../../shared/qemu.rs"]
mod qemu;
#[path = "../../shared/ram_flexcan.rs"]
mod ram_flexcan;
#[path = "../../shared/flexcan_variant.rs"]
mod variant;

use qemu::{
    check, config_stack_depth, fail, measure, report_stack, responder_off, responder_on,
    stack_depth, REPEAT,
};
use ram_flexcan::{
    loaded, popped, reg_read, reg_write, reset_block, restore, save, snapshots, tx_acknowledged,
    RamFlexCanRegs, Snapshots, DATA, ID,
};

type R = RamFlexCanRegs;

/// The measured regions, in the order of their numbers: `lean+done` measures the
/// completion's take too, full also the hand-written completions.
#[cfg(all(feature = "lean", not(feature = "done")))]
const REGIONS: &[&str] = REGIONS_ALL.split_at(9).0;
#[cfg(feature = "done")]
const REGIONS: &[&str] = REGIONS_ALL.split_at(10).0;
#[cfg(feature = "full")]
const REGIONS: &[&str] = &REGIONS_ALL;

const REGIONS_ALL: [&str; 12] = [
    "empty",
    "twocan.tx.direct",
    "twocan.tx_irq.done",
    "twocan.rx_irq",
    "twocan.rx.receive",
    "hand.tx",
    "hand.rx_irq",
    "hand.take",
    "twocan.rx_irq.overrun",
    // with completions only (full, lean+done)
    "twocan.take_completion",
    // full only
    "hand.tx_irq",
    "hand.take_completion",
];

const EMPTY: usize = 0;
const OURS_SEND: usize = 1;
const OURS_TX_IRQ: usize = 2;
const OURS_RX_IRQ: usize = 3;
const OURS_RECEIVE: usize = 4;
const HAND_TX: usize = 5;
const HAND_RX_IRQ: usize = 6;
const HAND_TAKE: usize = 7;
/// The Rx FIFO handler with one frame and the FIFO's overflow flag set (`IFLAG1.BUF7I`,
/// K66 RM "Rx FIFO"): the rare path, counted out of line.
const OURS_RX_IRQ_OVERRUN: usize = 8;
#[cfg(any(feature = "full", feature = "done"))]
const OURS_TAKE_COMPLETION: usize = 9;
#[cfg(feature = "full")]
const HAND_TX_IRQ: usize = 10;
#[cfg(feature = "full")]
const HAND_TAKE_COMPLETION: usize = 11;

/// What a frame's round trip runs, per side: the send, the handlers the configuration
/// has per frame, the take (and, with completions, the completion's take). The lean
/// variant is the split driver's quiet transmit mode (`State::QUIET_TX`): with nothing
/// queued MB15's interrupt is off (its `IMASK1` bit clear, checked after each direct
/// send), so a frame sent directly costs no transmit handler; the handler's cost when
/// frames are queued is still measured (`twocan.tx_irq.done`).
///
/// The one-feature variants: `lean+stamps` and `lean+counts` leave the quiet mode too
/// (a time stamp or a count to record per frame sent: `State::QUIET_TX`), so their
/// frames run the transmit handler; `lean+done` runs it and takes the completion, as
/// full; `lean+switch` and `lean+planner` stay quiet.
#[cfg(all(
    feature = "lean",
    not(any(feature = "done", feature = "stamps", feature = "counts"))
))]
const ROUNDTRIP_OURS: &[&str] = &["twocan.tx.direct", "twocan.rx_irq", "twocan.rx.receive"];
#[cfg(any(feature = "stamps", feature = "counts"))]
const ROUNDTRIP_OURS: &[&str] = &[
    "twocan.tx.direct",
    "twocan.tx_irq.done",
    "twocan.rx_irq",
    "twocan.rx.receive",
];
#[cfg(any(feature = "full", feature = "done"))]
const ROUNDTRIP_OURS: &[&str] = &[
    "twocan.tx.direct",
    "twocan.tx_irq.done",
    "twocan.rx_irq",
    "twocan.rx.receive",
    "twocan.take_completion",
];
/// Whether the variant is the split driver's quiet transmit mode (checked against
/// `State::QUIET_TX`): lean, and the one-feature variants that record nothing per frame
/// sent.
const QUIET: bool = cfg!(all(
    feature = "lean",
    not(any(feature = "done", feature = "stamps", feature = "counts"))
));
#[cfg(feature = "lean")]
const ROUNDTRIP_HAND: &[&str] = &["hand.tx", "hand.rx_irq", "hand.take"];
#[cfg(feature = "full")]
const ROUNDTRIP_HAND: &[&str] = &[
    "hand.tx",
    "hand.tx_irq",
    "hand.rx_irq",
    "hand.take",
    "hand.take_completion",
];

// ------------------------------------------------------------------ ours

static CAN: variant::OurState<R> = variant::OurState::new();

/// Size of the shared state, read by can-bench.
#[no_mangle]
#[used]
static BENCH_STATE_BYTES: u32 = size_of::<variant::OurState<R>>() as u32;

/// What the state's bytes hold (`State::FOOTPRINT`, `qemu::footprint_words`), read by
/// can-bench: its slots are the rings and queues, the rest is driver state.
#[no_mangle]
#[used]
static BENCH_FOOTPRINT: [u32; 13] = qemu::footprint_words(variant::OurState::<R>::FOOTPRINT);

/// Size of the controller value the state holds, read by can-bench.
#[no_mangle]
#[used]
static BENCH_HW_BYTES: u32 = size_of::<variant::Hw<R>>() as u32;

/// Size of the filter table the controller keeps (`Options::Table`: a planned table's
/// slices, or a reference to a `static` slot), read by can-bench.
#[no_mangle]
#[used]
static BENCH_FMI_BYTES: u32 =
    size_of::<<variant::Opts as twocan_flexcan::options::Options>::Table>() as u32;

/// Size of the clock gate and pin plan the controller keeps for `end` (its layout's
/// own, `Layout::System`: the Kinetis `PortPlan`), read by can-bench.
#[no_mangle]
#[used]
static BENCH_SYSTEM_BYTES: u32 = size_of::<
    <<variant::Opts as twocan_flexcan::options::Options>::Layout as twocan_flexcan::layout::Layout>::System,
>() as u32;

/// The SIM and PORT registers on QEMU: the board has none, so writes go nowhere (clock
/// gates and pin mux are not measured).
struct NoSystem;

impl Registers for NoSystem {
    fn read32(&self, _: usize) -> u32 {
        0
    }
    fn write32(&self, _: usize, _: u32) {}
}

#[inline(never)]
fn ours_try_send(tx: &mut variant::OurTx<R>, f: &Frame) -> bool {
    tx.try_send(f).is_ok()
}

#[inline(never)]
fn ours_tx_irq(h: &mut variant::OurTxIrq<R>) {
    h.on_interrupt()
}

#[inline(never)]
fn ours_rx_irq(h: &mut variant::OurRxIrq<R>) {
    h.on_interrupt()
}

#[inline(never)]
fn ours_receive(rx: &mut variant::OurRx<R>) -> Option<RxFrame> {
    rx.receive().ok()
}

#[cfg(any(feature = "full", feature = "done"))]
#[inline(never)]
fn ours_take_completion(tx: &mut variant::OurTx<R>) -> Option<twocan_core::Completion> {
    tx.take_completion()
}

/// The application's configuration: `begin` in place in the `static` state, split.
#[inline(never)]
fn ours_configure() -> variant::OurParts<R> {
    // SAFETY: the stand-in is used by this driver alone from now on (the hand-written
    // service measured before has given it up).
    let regs = || unsafe { RamFlexCanRegs::new() };
    match variant::start::<20, _, _>(&CAN, regs, &mut NoSystem) {
        Ok(p) => p,
        Err(_) => fail("twocan: begin and split"),
    }
}

fn run_ours(snap: &Snapshots, p: &mut variant::OurParts<R>) {
    let frame = match Frame::standard(ID, &DATA) {
        Ok(f) => f,
        Err(_) => fail("frame"),
    };
    for _ in 0..REPEAT {
        restore(&snap.tx_free);
        let token = p.tx.next_token();
        let (t, f) = (black_box(&mut p.tx), black_box(&frame));
        let ok = measure::<OURS_SEND, _>(|| ours_try_send(t, f));
        check(
            ok && loaded() && CAN.tx_stats().count == 0,
            "twocan try_send",
        );
        // The quiet mode (lean) leaves MB15's interrupt off after a direct send; with
        // completions it stays on.
        check(
            variant::OurState::<R>::QUIET_TX
                == (reg_read(twocan_flexcan::regs::IMASK1)
                    & twocan_flexcan::regs::iflag1::buf(ram_flexcan::TX_MB)
                    == 0),
            "twocan MB15 interrupt off exactly in the quiet mode",
        );
        check(
            variant::OurState::<R>::QUIET_TX == QUIET,
            "the variant is the quiet mode exactly when it records nothing per frame sent",
        );

        restore(&snap.tx_done);
        let h = black_box(&mut p.tx_irq);
        measure::<OURS_TX_IRQ, _>(|| ours_tx_irq(h));
        check(tx_acknowledged(), "twocan tx irq acknowledged MB15");
        let done = {
            #[cfg(any(feature = "full", feature = "done"))]
            {
                let t = black_box(&mut p.tx);
                measure::<OURS_TAKE_COMPLETION, _>(|| ours_take_completion(t))
            }
            #[cfg(not(any(feature = "full", feature = "done")))]
            {
                p.tx.take_completion()
            }
        };
        check(
            if variant::DONE != 0 {
                done.is_some_and(|c| c.token == token && c.outcome == TxOutcome::Sent)
            } else {
                done.is_none()
            },
            "twocan tx irq completion",
        );

        restore(&snap.rx_one);
        let h = black_box(&mut p.rx0_irq);
        measure::<OURS_RX_IRQ, _>(|| ours_rx_irq(h));
        check(popped() && CAN.rx_stats().count == 1, "twocan rx irq");

        let r = black_box(&mut p.rx);
        let rx = measure::<OURS_RECEIVE, _>(|| ours_receive(r));
        check(
            rx.is_some_and(|r| r.frame == frame && r.filter == variant::FILTER_INDEX)
                && CAN.rx_stats().count == 0,
            "twocan receive",
        );

        // The same frame with the FIFO's overflow flag set: the handler takes the frame
        // as above and counts the overrun out of line (`fifo_events`).
        restore(&snap.rx_one);
        reg_write(
            twocan_flexcan::regs::IFLAG1,
            reg_read(twocan_flexcan::regs::IFLAG1) | twocan_flexcan::regs::iflag1::BUF7I,
        );
        let overruns = CAN.error_stats().hardware_overruns;
        let h = black_box(&mut p.rx0_irq);
        measure::<OURS_RX_IRQ_OVERRUN, _>(|| ours_rx_irq(h));
        check(
            popped()
                && CAN.rx_stats().count == 1
                && CAN.error_stats().hardware_overruns == overruns.wrapping_add(1),
            "twocan rx irq with an overrun: the frame taken, the overrun counted",
        );
        // The same call site as the measured take: one copy of the receive path.
        check(
            ours_receive(&mut p.rx).is_some(),
            "twocan receive after an overrun",
        );
    }

    restore(&snap.tx_free);
    let ((), bytes, _) = stack_depth(|| {
        check(ours_try_send(&mut p.tx, &frame), "twocan stack try_send");
    });
    report_stack("twocan.tx.direct", bytes);
    restore(&snap.tx_done);
    let ((), bytes, _) = stack_depth(|| ours_tx_irq(&mut p.tx_irq));
    report_stack("twocan.tx_irq.done", bytes);
    #[cfg(any(feature = "full", feature = "done"))]
    {
        let (c, bytes, _) = stack_depth(|| ours_take_completion(&mut p.tx));
        check(c.is_some(), "twocan stack take_completion");
        report_stack("twocan.take_completion", bytes);
    }
    let _ = p.tx.take_completion();
    restore(&snap.rx_one);
    let ((), bytes, _) = stack_depth(|| ours_rx_irq(&mut p.rx0_irq));
    report_stack("twocan.rx_irq", bytes);
    let (r, bytes, _) = stack_depth(|| ours_receive(&mut p.rx));
    check(r.is_some(), "twocan stack receive");
    report_stack("twocan.rx.receive", bytes);
}

// ------------------------------------------------------------------ hand-written

/// The hand-written service's register access on the stand-in (write-1-to-clear played
/// as `ram_flexcan.rs` says).
struct RamBus;

impl hand::Bus for RamBus {
    #[inline(always)]
    fn read(offset: usize) -> u32 {
        reg_read(offset)
    }
    #[inline(always)]
    fn write(offset: usize, value: u32) {
        reg_write(offset, value)
    }
    #[inline(always)]
    fn w1c(offset: usize, bits: u32) {
        reg_write(offset, reg_read(offset) & !bits)
    }
}

type Hand = hand::Service<'static, RamBus>;

#[inline(never)]
fn hand_send(s: &mut hand::Sender<'_, RamBus>, f: &hand::CanFrame) -> Option<u32> {
    s.send(f).ok()
}

#[cfg(feature = "full")]
#[inline(never)]
fn hand_tx_irq(h: &mut hand::TxHandler<'_, RamBus>) {
    h.on_interrupt()
}

#[inline(never)]
fn hand_rx_irq(h: &mut hand::RxHandler<'_, RamBus>) {
    h.on_interrupt()
}

#[inline(never)]
fn hand_take(r: &mut hand::Receiver<'_>) -> Option<hand::Received> {
    r.take()
}

#[cfg(feature = "full")]
#[inline(never)]
fn hand_take_completion(c: &mut hand::Completions<'_>) -> Option<hand::Completion> {
    c.take()
}

/// The hand-written configuration (retried after a timed-out handshake, as ours), then
/// the split over its storage.
#[inline(never)]
fn hand_configure(storage: &'static mut hand::Storage) -> Hand {
    let mut r = hand::configure::<RamBus>();
    for _ in 0..20 {
        if r.is_ok() {
            break;
        }
        r = hand::configure::<RamBus>();
    }
    check(r.is_ok(), "hand: configure");
    hand::split(storage)
}

fn run_hand(snap: &Snapshots, s: &mut Hand) {
    let frame = hand::CanFrame {
        id: ID as u32,
        extended: false,
        remote: false,
        dlc: 8,
        data: DATA,
    };
    for _ in 0..REPEAT {
        restore(&snap.tx_free);
        let (ss, ff) = (black_box(&mut s.sender), black_box(&frame));
        let token = measure::<HAND_TX, _>(|| hand_send(ss, ff));
        check(token.is_some() && loaded(), "hand send");

        #[cfg(feature = "full")]
        {
            restore(&snap.tx_done);
            let h = black_box(&mut s.tx_irq);
            measure::<HAND_TX_IRQ, _>(|| hand_tx_irq(h));
            check(tx_acknowledged(), "hand tx irq acknowledged MB15");
            let c = black_box(&mut s.completions);
            let done = measure::<HAND_TAKE_COMPLETION, _>(|| hand_take_completion(c));
            check(
                done.is_some_and(|c| Some(c.token) == token && c.sent),
                "hand completion",
            );
        }

        restore(&snap.rx_one);
        let h = black_box(&mut s.rx_irq);
        measure::<HAND_RX_IRQ, _>(|| hand_rx_irq(h));
        check(popped(), "hand rx irq");
        let r = black_box(&mut s.receiver);
        let rx = measure::<HAND_TAKE, _>(|| hand_take(r));
        check(
            rx.is_some_and(|r| r.frame == frame && r.filter == 0),
            "hand take",
        );
    }
    restore(&snap.tx_free);
    let (t, bytes, _) = stack_depth(|| hand_send(&mut s.sender, &frame));
    check(t.is_some(), "hand stack send");
    report_stack("hand.tx", bytes);
    #[cfg(feature = "full")]
    {
        restore(&snap.tx_done);
        let ((), bytes, _) = stack_depth(|| hand_tx_irq(&mut s.tx_irq));
        report_stack("hand.tx_irq", bytes);
        let (c, bytes, _) = stack_depth(|| hand_take_completion(&mut s.completions));
        check(c.is_some(), "hand stack take completion");
        report_stack("hand.take_completion", bytes);
    }
    restore(&snap.rx_one);
    let ((), bytes, _) = stack_depth(|| hand_rx_irq(&mut s.rx_irq));
    report_stack("hand.rx_irq", bytes);
    let (r, bytes, _) = stack_depth(|| hand_take(&mut s.receiver));
    check(r.is_some(), "hand stack take");
    report_stack("hand.take", bytes);
    check(
        s.counts.overruns.get() == 0 && s.counts.ring_overflows.get() == 0,
        "hand: no overrun, no overflow",
    );
}

/// Prints the configuration's stack figure (the upper bound: the handshake stand-in's
/// exception frames included) and, as a note, the lower bound
/// (`qemu::config_stack_depth`).
fn report_config_stack(key: &str, low: u32, high: u32) {
    report_stack(key, high);
    qemu::note(key, ".low", low);
}

#[entry]
fn main() -> ! {
    let Some(mut core) = cortex_m::Peripherals::take() else {
        fail("core peripherals");
    };
    qemu::announce(REGIONS);
    qemu::report_roundtrip("twocan", ROUNDTRIP_OURS);
    qemu::report_roundtrip("hand", ROUNDTRIP_HAND);
    qemu::variant(variant::VARIANT);
    // A one-feature variant (`lean+...`) measures ours alone against its lean run: the
    // hand-written service is built lean.
    check(
        variant::VARIANT.split('+').next() == Some(hand::VARIANT),
        "one variant",
    );
    for _ in 0..REPEAT {
        measure::<EMPTY, _>(|| ());
    }

    let Some(storage) = cortex_m::singleton!(: hand::Storage = hand::Storage::new()) else {
        fail("hand storage");
    };
    reset_block();
    responder_on(&mut core.SYST);
    let (mut service, low, high) = config_stack_depth(|| hand_configure(storage));
    responder_off(&mut core.SYST);
    report_config_stack("hand.config", low, high);
    run_hand(&snapshots(&save()), &mut service);

    reset_block();
    responder_on(&mut core.SYST);
    let (mut parts, low, high) = config_stack_depth(ours_configure);
    responder_off(&mut core.SYST);
    report_config_stack("twocan.config", low, high);
    run_ours(&snapshots(&save()), &mut parts);

    qemu::finish()
}
