//! Instructions per frame and stack high-water marks of the twocan split driver (bxCAN
//! backend) and of the bare `bxcan` crate 0.8, on a Cortex-M4 under QEMU
//! (`-machine mps2-an386`), counted by the TCG plugin `bench/plugin/insn_count.c`
//! between marker stores. Built twice, with feature `lean` and with feature `full`
//! (`shared/bxcan_variant.rs`), and, for issue 21's cost of each choice, once per
//! one-feature variant (`lean` plus one of `done`, `stamps`, `counts`, `switch`,
//! `planner`). The register block stand-in and its snapshots are in
//! `shared/ram_can.rs`, the markers and the stack painting in `shared/qemu.rs`. The
//! feature-equivalent service is measured by `insn-count-equiv` (a separate image, so
//! that the crate's `transmit` is not shared by two callers and stays inlined in each,
//! as in a firmware using it alone); can-bench merges the two runs.
//!
//! Two drivers run on the same block, one after the other:
//!
//! - **ours**: a `static State` of the variant's type (zero-initialised, `.bss`), split
//!   once; the transmit half's `try_send`, the transmit and FIFO 0 receive interrupt
//!   handlers, the receive half's `receive` (decoded frame with the user's filter index)
//!   and, with completions (full, `lean+done`), `take_completion` are measured;
//! - **bxcan**: the `bxcan` crate's `Can::transmit`, `Can::receive` and `Rx0::receive`,
//!   bare.
//!
//! Every receive-interrupt figure is **one frame per interrupt** (the snapshot holds one
//! frame; the handler's loop then finds FIFO 0 empty), so it includes the handler's
//! per-interrupt cost once. After the counts, each measured call runs once more between
//! [`qemu::stack_depth`]'s painting and scan for its stack high-water mark, and so does
//! each driver's configuration (mode handshakes played by the SysTick stand-in).
//!
//! The firmware prints its region names, round trips, stack figures and `done` through
//! semihosting (`shared/qemu.rs` lists the lines), then exits with the semihosting exit
//! call.
#![no_std]
#![no_main]

use core::hint::black_box;

use cortex_m_rt::entry;
use twocan_bxcan::FilterPlan;
use twocan_core::{Frame, RxFrame, TxOutcome};

#[path = "../../shared/feature_sets.rs"]
mod feature_sets;
#[path = "../../shared/qemu.rs"]
mod qemu;
#[path = "../../shared/ram_bxcan_crate.rs"]
mod ram_bxcan_crate;
#[path = "../../shared/ram_can.rs"]
mod ram_can;
#[path = "../../shared/bxcan_variant.rs"]
mod variant;

use qemu::{
    check, config_stack_depth, fail, measure, report_stack, responder_off, responder_on,
    stack_depth, REPEAT,
};
use ram_bxcan_crate::RamCan1;
use ram_can::{
    loaded, reg_read, reg_write, released, reset_block, restore, save, snapshots, Snapshots, DATA,
    ID, REGS,
};
use variant::{OurParts, OurRx, OurRxIrq, OurState, OurTx, OurTxIrq, DONE};

/// The measured regions, in the order of their numbers; a variant with completions
/// (full, `lean+done`) measures the completion's take too.
#[cfg(not(any(feature = "full", feature = "done")))]
const REGIONS: &[&str] = REGIONS_ALL.split_at(14).0;
#[cfg(any(feature = "full", feature = "done"))]
const REGIONS: &[&str] = &REGIONS_ALL;

const REGIONS_ALL: [&str; 15] = [
    "empty",
    "twocan.tx.direct",
    "twocan.tx.one_busy",
    "twocan.tx.queued",
    "twocan.tx_irq.refill",
    "twocan.tx_irq.done",
    "twocan.rx_irq",
    "twocan.rx.receive",
    "bxcan.transmit",
    "bxcan.transmit.one_busy",
    "bxcan.receive",
    "bxcan.rx0.receive",
    "twocan.tx_irq.done.unloaded",
    "twocan.rx_irq.overrun",
    // with completions only
    "twocan.take_completion",
];

/// The RAM stand-in for CAN1's registers, read by `variant::Regs`.
const CAN_BASE: usize = REGS;

const EMPTY: usize = 0;
const OURS_SEND_DIRECT: usize = 1;
const OURS_SEND_ONE_BUSY: usize = 2;
const OURS_SEND_QUEUED: usize = 3;
const OURS_TX_IRQ_REFILL: usize = 4;
const OURS_TX_IRQ_DONE: usize = 5;
const OURS_RX_IRQ: usize = 6;
const OURS_RECEIVE: usize = 7;
const THEIRS_TRANSMIT: usize = 8;
const THEIRS_TRANSMIT_ONE_BUSY: usize = 9;
const THEIRS_RECEIVE: usize = 10;
const THEIRS_RX0_RECEIVE: usize = 11;
const OURS_TX_IRQ_UNLOADED: usize = 12;
/// The receive handler with one frame and FIFO 0's overrun flag set (`FOVR0`, RM0410
/// §40.8.5): the rare path, counted out of line.
const OURS_RX_IRQ_OVERRUN: usize = 13;
#[cfg(any(feature = "full", feature = "done"))]
const OURS_TAKE_COMPLETION: usize = 14;

/// What a frame's round trip runs, per side: the send, the handlers the configuration
/// has per frame, the take (and, with completions, the completion's take). The lean
/// variant is the split driver's quiet transmit mode (`State::QUIET_TX`): with nothing
/// queued its transmit interrupt is off (`CAN_IER.TMEIE` = 0, checked after each direct
/// send), so a frame sent directly costs no transmit handler; the handler's cost when
/// frames are queued is still measured (`twocan.tx_irq.refill`, `.done`).
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
    not(any(
        feature = "done",
        feature = "stamps",
        feature = "counts"
    ))
));

// ------------------------------------------------------------------ ours

/// The driver's shared state: all zeros, in `.bss`. The same type as `loopback-twocan`'s.
static CAN: OurState = OurState::new();

/// Size of [`OurState`], read by can-bench (checked against `loopback-twocan`'s static).
#[no_mangle]
#[used]
static BENCH_STATE_BYTES: u32 = size_of::<OurState>() as u32;

/// Size of the controller value the state holds, read by can-bench.
#[no_mangle]
#[used]
static BENCH_HW_BYTES: u32 = size_of::<variant::Hw>() as u32;

/// Size of the filter map inside it (`FmiMap`), read by can-bench.
#[no_mangle]
#[used]
static BENCH_FMI_BYTES: u32 =
    size_of::<twocan_bxcan::filters::FmiMap<{ variant::KEYS }, { variant::FMIS }>>() as u32;

/// What [`OurState`]'s bytes hold (`State::FOOTPRINT`, `qemu::footprint_words`), read by
/// can-bench: its slots are the rings and queues, the rest is driver state.
#[no_mangle]
#[used]
static BENCH_FOOTPRINT: [u32; 13] = qemu::footprint_words(OurState::FOOTPRINT);

#[inline(never)]
fn ours_try_send(tx: &mut OurTx, f: &Frame) -> bool {
    tx.try_send(f).is_ok()
}

#[inline(never)]
fn ours_tx_irq(h: &mut OurTxIrq) {
    h.on_interrupt()
}

#[inline(never)]
fn ours_rx_irq(h: &mut OurRxIrq) {
    h.on_interrupt()
}

#[inline(never)]
fn ours_receive(rx: &mut OurRx) -> Option<RxFrame> {
    rx.receive().ok()
}

#[cfg(any(feature = "full", feature = "done"))]
#[inline(never)]
fn ours_take_completion(tx: &mut OurTx) -> Option<twocan_core::Completion> {
    tx.take_completion()
}

/// The application's configuration: the controller configured and started, then split
/// into the `static` state.
#[inline(never)]
fn ours_configure() -> OurParts {
    // SAFETY: `REGS` is the RAM stand-in for CAN1's registers; this driver alone uses it
    // from now on (the `bxcan` crate has given it up).
    let regs = unsafe { variant::Regs::new() };
    match variant::start::<20>(&CAN, regs) {
        Ok(p) => p,
        Err(_) => fail("twocan: configure"),
    }
}

/// Prints the configuration's stack figure (the upper bound: the handshake stand-in's
/// exception frames included) and, as a note, the lower bound
/// (`qemu::config_stack_depth`).
fn report_config_stack(key: &str, low: u32, high: u32) {
    report_stack(key, high);
    qemu::note(key, ".low", low);
}

fn run_ours(snap: &Snapshots, p: &mut OurParts) {
    let frame = match Frame::standard(ID, &DATA) {
        Ok(f) => f,
        Err(_) => fail("frame"),
    };
    for _ in 0..REPEAT {
        // Direct path: queue empty, mailbox free.
        restore(&snap.tx_free);
        let token = p.tx.next_token();
        let (t, f) = (black_box(&mut p.tx), black_box(&frame));
        let ok = measure::<OURS_SEND_DIRECT, _>(|| ours_try_send(t, f));
        check(
            ok && loaded(0) && CAN.tx_stats().count == 0,
            "twocan try_send direct",
        );
        // The quiet mode (lean) leaves the transmit interrupt off after a direct send;
        // with completions, time stamps or statistics it stays on.
        check(
            OurState::QUIET_TX
                == (reg_read(twocan_bxcan::regs::IER) & twocan_bxcan::regs::ier::TMEIE == 0),
            "twocan transmit interrupt off exactly in the quiet mode",
        );
        check(
            OurState::QUIET_TX == QUIET,
            "the lean variant is the quiet mode",
        );

        // Its completion: the transmit interrupt settles mailbox 0.
        restore(&snap.tx_done);
        let h = black_box(&mut p.tx_irq);
        measure::<OURS_TX_IRQ_DONE, _>(|| ours_tx_irq(h));
        check(
            reg_read(twocan_bxcan::regs::TSR) == twocan_bxcan::regs::tsr::RQCP0,
            "twocan tx irq acknowledged RQCP0",
        );
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
            if DONE != 0 {
                done.is_some_and(|c| c.token == token && c.outcome == TxOutcome::Sent)
            } else {
                done.is_none()
            },
            "twocan tx irq completion",
        );

        // Receive interrupt: one frame, FIFO 0 → ring.
        restore(&snap.rx_one);
        let h = black_box(&mut p.rx0_irq);
        measure::<OURS_RX_IRQ, _>(|| ours_rx_irq(h));
        check(released() && CAN.rx_stats().count == 1, "twocan rx irq");

        // The thread side takes it, decoded, with its filter index.
        let r = black_box(&mut p.rx);
        let rx = measure::<OURS_RECEIVE, _>(|| ours_receive(r));
        check(
            rx.is_some_and(|r| r.frame == frame && r.filter == FilterPlan::slot_index(0, 0))
                && CAN.rx_stats().count == 0,
            "twocan receive",
        );

        // The same frame with FIFO 0's overrun flag set: the handler takes the frame as
        // above and counts the overrun out of line (`fifo_events`).
        restore(&snap.rx_one);
        reg_write(
            twocan_bxcan::regs::RF0R,
            reg_read(twocan_bxcan::regs::RF0R) | twocan_bxcan::regs::rfxr::FOVR,
        );
        let overruns = CAN.error_stats().hardware_overruns;
        let h = black_box(&mut p.rx0_irq);
        measure::<OURS_RX_IRQ_OVERRUN, _>(|| ours_rx_irq(h));
        check(
            released()
                && CAN.rx_stats().count == 1
                && CAN.error_stats().hardware_overruns == overruns.wrapping_add(1),
            "twocan rx irq with an overrun: the frame taken, the overrun counted",
        );
        // The same call site as the measured take: one copy of the receive path.
        check(
            ours_receive(&mut p.rx).is_some(),
            "twocan receive after an overrun",
        );

        restore(&snap.tx_one_busy);
        let (t, f) = (black_box(&mut p.tx), black_box(&frame));
        let ok = measure::<OURS_SEND_ONE_BUSY, _>(|| ours_try_send(t, f));
        check(
            ok && loaded(1) && CAN.tx_stats().count == 0,
            "twocan try_send one busy",
        );

        restore(&snap.tx_full);
        let (t, f) = (black_box(&mut p.tx), black_box(&frame));
        let ok = measure::<OURS_SEND_QUEUED, _>(|| ours_try_send(t, f));
        check(ok && CAN.tx_stats().count == 1, "twocan try_send queued");

        restore(&snap.tx_refill);
        let h = black_box(&mut p.tx_irq);
        measure::<OURS_TX_IRQ_REFILL, _>(|| ours_tx_irq(h));
        check(
            loaded(0) && CAN.tx_stats().count == 0,
            "twocan tx irq refill",
        );

        // A transmit interrupt with nothing to settle (mailbox 0's flag already
        // acknowledged, as after a refill): the handler's fixed cost.
        restore(&snap.tx_free);
        let h = black_box(&mut p.tx_irq);
        measure::<OURS_TX_IRQ_UNLOADED, _>(|| ours_tx_irq(h));
        // The one-busy and queued frames never complete on this block: their
        // completions are not expected, and none arrived.
        check(
            p.tx.take_completion().is_none(),
            "twocan no stray completion",
        );
    }

    // Stack high-water marks of the per-frame calls (one run each, outside the markers).
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

// ------------------------------------------------------------------ the bxcan crate

type Theirs = bxcan::Can<RamCan1>;

#[inline(never)]
fn theirs_transmit(c: &mut Theirs, f: &bxcan::Frame) -> bool {
    c.transmit(f).is_ok()
}

#[inline(never)]
fn theirs_receive(c: &mut Theirs) -> Option<bxcan::Frame> {
    c.receive().ok()
}

#[inline(never)]
fn theirs_rx0_receive(c: &mut bxcan::Rx0<RamCan1>) -> Option<bxcan::Frame> {
    c.receive().ok()
}

fn run_theirs(snap: &Snapshots, can: &mut Theirs) {
    let id = match bxcan::StandardId::new(ID) {
        Some(id) => id,
        None => fail("bxcan id"),
    };
    let frame = bxcan::Frame::new_data(id, DATA);
    for _ in 0..REPEAT {
        restore(&snap.tx_free);
        let (cc, ff) = (black_box(&mut *can), black_box(&frame));
        let ok = measure::<THEIRS_TRANSMIT, _>(|| theirs_transmit(cc, ff));
        check(ok && loaded(0), "bxcan transmit");

        restore(&snap.tx_one_busy);
        let (cc, ff) = (black_box(&mut *can), black_box(&frame));
        let ok = measure::<THEIRS_TRANSMIT_ONE_BUSY, _>(|| theirs_transmit(cc, ff));
        check(ok && loaded(1), "bxcan transmit one busy");

        restore(&snap.rx_one);
        let cc = black_box(&mut *can);
        let rx = measure::<THEIRS_RECEIVE, _>(|| theirs_receive(cc));
        check(rx.as_ref() == Some(&frame) && released(), "bxcan receive");

        restore(&snap.rx_one);
        let cc = black_box(can.rx0());
        let rx = measure::<THEIRS_RX0_RECEIVE, _>(|| theirs_rx0_receive(cc));
        check(
            rx.as_ref() == Some(&frame) && released(),
            "bxcan rx0 receive",
        );
    }
    restore(&snap.tx_free);
    let (ok, bytes, _) = stack_depth(|| theirs_transmit(can, &frame));
    check(ok, "bxcan stack transmit");
    report_stack("bxcan.transmit", bytes);
    restore(&snap.rx_one);
    let (rx, bytes, _) = stack_depth(|| theirs_rx0_receive(can.rx0()));
    check(rx.is_some(), "bxcan stack rx0 receive");
    report_stack("bxcan.rx0.receive", bytes);
}

#[entry]
fn main() -> ! {
    let Some(mut core) = cortex_m::Peripherals::take() else {
        fail("core peripherals");
    };
    qemu::announce(REGIONS);
    qemu::report_roundtrip("twocan", ROUNDTRIP_OURS);
    qemu::variant(variant::VARIANT);
    for _ in 0..REPEAT {
        measure::<EMPTY, _>(|| ());
    }

    // The bare crate: configure with the handshake stand-in, snapshot, measure, give
    // the block up.
    reset_block();
    responder_on(&mut core.SYST);
    let (mut theirs, low, high) =
        config_stack_depth(|| ram_bxcan_crate::configure(variant::CONFIG.btr_value(), false));
    responder_off(&mut core.SYST);
    report_config_stack("bxcan.config", low, high);
    run_theirs(&snapshots(&save()), &mut theirs);
    let _ = theirs.free();

    // Ours: the same from a fresh reset block.
    reset_block();
    responder_on(&mut core.SYST);
    let (mut parts, low, high) = config_stack_depth(ours_configure);
    responder_off(&mut core.SYST);
    report_config_stack("twocan.config", low, high);
    run_ours(&snapshots(&save()), &mut parts);

    qemu::finish()
}
