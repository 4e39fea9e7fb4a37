//! Instructions per frame of the twocan split driver (bxCAN backend) and of the `bxcan`
//! crate 0.8, on a Cortex-M4 under QEMU (`-machine mps2-an386`), counted by the TCG
//! plugin `bench/plugin/insn_count.c` between marker stores. The register block stand-in,
//! its snapshots and the markers are in `shared/ram_can.rs`.
//!
//! Three drivers run on the same block, one after the other:
//!
//! - **ours**: a `static State<BxCan<Mmio>, 8, FifoQueue<8>>` (zero-initialised, `.bss`),
//!   split once; the transmit half's `try_send`, the transmit and FIFO 0 receive
//!   interrupt handlers, and the receive half's `receive` (decoded frame with the user's
//!   filter index) are measured;
//! - **bxcan**: the `bxcan` crate's `Can::transmit` and `Can::receive`, bare;
//! - **equivalent**: what an application needs around the `bxcan` crate to offer what
//!   ours does — a TX interrupt that clears the completions (`RQCPx`) and counts them, an
//!   RX0 interrupt that drains FIFO 0 into a `heapless::spsc` ring (lock-free, like ours),
//!   counting hardware overruns and ring overflows and reading `CAN_ESR` for the error
//!   state, and the thread side taking the frame from the ring.
//!
//! Every receive-interrupt figure is **one frame per interrupt** (the snapshot holds one
//! frame; the handler's loop then finds FIFO 0 empty), so it includes the handler's
//! per-interrupt cost once.
//!
//! The firmware prints `region <n> <key>` for each measured region and `done` through
//! semihosting, then exits with the semihosting exit call.
#![no_std]
#![no_main]

use core::hint::black_box;

use bxcan::filter::Mask32;
use cortex_m_rt::entry;
use heapless::spsc::{Consumer, Producer, Queue};
use twocan_bxcan::RawFrame;
use twocan_bxcan::{BxCan, Config, FilterPlan};
use twocan_core::split::{Rx, Rx0Irq, State, StateChange, Tx, TxIrq, STATE_CHANGES};
use twocan_core::timing::{solve_cia, Limits};
use twocan_core::txqueue::Queued;
use twocan_core::Completion;
use twocan_core::{FifoQueue, Frame, Mmio, RxFrame, TxOutcome, TxPolicy};

#[path = "../../shared/ram_can.rs"]
mod ram_can;

use ram_can::{
    check, fail, loaded, measure, reg_read, released, reset_block, responder_off, responder_on,
    restore, save, snapshots, Snapshots, DATA, ID, REGS, REPEAT,
};

const APB1_HZ: u32 = 54_000_000;
const BITRATE: u32 = 500_000;

/// Receive ring (frames) and transmit queue capacities of both sides.
const RX: usize = 8;
/// See [`RX`].
const TXQ: usize = 8;
/// Completion ring capacity (the `State` default).
const DONE: usize = 8;

/// Loop-back, request-order transmit (TXFP = 1, the FIFO policy of `FifoQueue`).
const CONFIG: Config = match Config::from_bitrate(APB1_HZ, BITRATE) {
    Ok(c) => c.loopback(true).tx_policy(TxPolicy::Fifo),
    Err(_) => panic!("no bit timing"),
};
const BTR: u32 = match solve_cia(APB1_HZ, BITRATE, &Limits::BXCAN) {
    Ok(t) => match t.bxcan_btr() {
        Ok(v) => v,
        Err(_) => panic!("no CAN_BTR value"),
    },
    Err(_) => panic!("no bit timing"),
};

/// The measured regions, in the order of their numbers.
const REGIONS: [&str; 16] = [
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
    "equiv.tx_irq.clear",
    "equiv.tx_irq.idle",
    "equiv.rx_irq",
    "equiv.take",
    "bxcan.rx0.receive",
];

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
const EQUIV_TX_CLEAR: usize = 11;
const EQUIV_TX_IDLE: usize = 12;
const EQUIV_RX_IRQ: usize = 13;
const EQUIV_TAKE: usize = 14;
const THEIRS_RX0_RECEIVE: usize = 15;

// ------------------------------------------------------------------ ours

type Hw = BxCan<Mmio>;
type Q = FifoQueue<TXQ>;
type OurState = State<Hw, RX, Q, 0, DONE>;
type OurTx = Tx<'static, Hw, RX, Q, 0, DONE>;
type OurRx = Rx<'static, Hw, RX, Q, 0, DONE>;
type OurTxIrq = TxIrq<'static, Hw, RX, Q, 0, DONE>;
type OurRxIrq = Rx0Irq<'static, Hw, RX, Q, 0, DONE>;

/// The driver's shared state: all zeros, in `.bss`. The same type as `loopback-twocan`'s.
static CAN: OurState = State::new();

/// Size of [`OurState`], read by can-bench (checked against `loopback-twocan`'s static).
#[no_mangle]
#[used]
static BENCH_STATE_BYTES: u32 = size_of::<OurState>() as u32;

/// Size of the controller value the state holds (`BxCan<Mmio>`), read by can-bench.
#[no_mangle]
#[used]
static BENCH_HW_BYTES: u32 = size_of::<Hw>() as u32;

/// Size of the filter map inside it (`FmiMap`), read by can-bench.
#[no_mangle]
#[used]
static BENCH_FMI_BYTES: u32 = size_of::<twocan_bxcan::filters::FmiMap>() as u32;

/// Bytes of [`OurState`] that are ring and queue slots (receive ring, transmit queue,
/// completion ring, state-change ring), read by can-bench: the rest is driver state.
#[no_mangle]
#[used]
static BENCH_RING_BYTES: u32 = (RX * size_of::<RawFrame>()
    + TXQ * size_of::<Queued>()
    + DONE * size_of::<Completion>()
    + STATE_CHANGES * size_of::<StateChange>()) as u32;

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

fn configure_ours() -> Hw {
    ram_can::configure_ours(&CONFIG)
}

fn run_ours(snap: &Snapshots, hw: Hw) {
    let Ok(mut p) = CAN.split(hw) else {
        fail("twocan: split");
    };
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

        // Its completion: the transmit interrupt settles mailbox 0.
        restore(&snap.tx_done);
        let h = black_box(&mut p.tx_irq);
        measure::<OURS_TX_IRQ_DONE, _>(|| ours_tx_irq(h));
        check(
            reg_read(twocan_bxcan::regs::TSR) == twocan_bxcan::regs::tsr::RQCP0,
            "twocan tx irq acknowledged RQCP0",
        );
        check(
            p.tx.take_completion()
                .is_some_and(|c| c.token == token && c.outcome == TxOutcome::Sent),
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
        // The one-busy and queued frames never complete on this block: their
        // completions are not expected, and none arrived.
        check(
            p.tx.take_completion().is_none(),
            "twocan no stray completion",
        );
    }
}

// ------------------------------------------------------------------ the bxcan crate

/// The RAM stand-in as a `bxcan` instance.
struct RamCan1;

// SAFETY: `REGISTERS` points to the RAM block at `REGS`, laid out as bxCAN's register
// block (0x320 bytes, aligned), used by one driver at a time.
unsafe impl bxcan::Instance for RamCan1 {
    const REGISTERS: *mut bxcan::RegisterBlock = REGS as *mut _;
}

// SAFETY: the stand-in has CAN1's 28 filter banks.
unsafe impl bxcan::FilterOwner for RamCan1 {
    const NUM_FILTER_BANKS: u8 = 28;
}

// SAFETY: the stand-in is CAN1, the master instance.
unsafe impl bxcan::MasterInstance for RamCan1 {}

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

/// The feature-equivalent application state around the `bxcan` crate.
struct Equiv {
    completions: u32,
    overruns: u32,
    ring_overflows: u32,
    esr: u32,
}

/// `CAN_ESR`, which the `bxcan` crate 0.8 does not expose: read through its register
/// block pointer (RM0410 §40.9.2, offset 0x18).
fn esr_of(_: &Theirs) -> u32 {
    // SAFETY: `REGISTERS` + 0x18 is `CAN_ESR` of the instance the `Can` owns; a read has
    // no side effect.
    unsafe {
        core::ptr::read_volatile(
            (<RamCan1 as bxcan::Instance>::REGISTERS as *const u8).add(0x18) as *const u32,
        )
    }
}

/// The TX interrupt's step: clears one `RQCPx` and counts the completion
/// (`Can::clear_tx_interrupt` loops over this until it returns `None`).
#[inline(never)]
fn equiv_tx_step(c: &mut Theirs, e: &mut Equiv) -> bool {
    match c.clear_request_completed_flag() {
        Some(_) => {
            e.completions += 1;
            true
        }
        None => false,
    }
}

/// The RX0 interrupt: FIFO 0 into the ring, overruns and overflows counted, `CAN_ESR`
/// read for the error state.
#[inline(never)]
fn equiv_rx_irq(c: &mut Theirs, p: &mut Producer<'_, bxcan::Frame>, e: &mut Equiv) {
    loop {
        match c.rx0().receive() {
            Ok(f) => {
                if p.enqueue(f).is_err() {
                    e.ring_overflows += 1;
                }
            }
            Err(nb::Error::Other(_)) => e.overruns += 1,
            Err(nb::Error::WouldBlock) => break,
        }
    }
    e.esr = esr_of(c);
}

#[inline(never)]
fn equiv_take(q: &mut Consumer<'_, bxcan::Frame>) -> Option<bxcan::Frame> {
    q.dequeue()
}

fn configure_theirs() -> Theirs {
    let mut can = bxcan::Can::builder(RamCan1)
        .set_bit_timing(BTR)
        .set_loopback(true)
        .leave_disabled();
    can.modify_filters()
        .enable_bank(0, bxcan::Fifo::Fifo0, Mask32::accept_all());
    check(
        nb::block!(can.enable_non_blocking()).is_ok(),
        "bxcan enable",
    );
    can
}

fn run_theirs(snap: &Snapshots, can: &mut Theirs) {
    let id = match bxcan::StandardId::new(ID) {
        Some(id) => id,
        None => fail("bxcan id"),
    };
    let frame = bxcan::Frame::new_data(id, DATA);
    let mut ring: Queue<bxcan::Frame, { RX + 1 }> = Queue::new();
    let (mut producer, mut consumer) = ring.split();
    let mut e = Equiv {
        completions: 0,
        overruns: 0,
        ring_overflows: 0,
        esr: 1,
    };
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

        // The feature-equivalent service. TX interrupt: one completion cleared, then
        // the call that finds none (on RAM the flag does not clear, so the two calls of
        // `clear_tx_interrupt`'s loop are measured on their own snapshots).
        restore(&snap.tx_done);
        let before = e.completions;
        let (cc, ee) = (black_box(&mut *can), black_box(&mut e));
        let more = measure::<EQUIV_TX_CLEAR, _>(|| equiv_tx_step(cc, ee));
        check(
            more && e.completions == before + 1,
            "equivalent tx irq clears RQCP0",
        );
        restore(&snap.tx_free);
        let (cc, ee) = (black_box(&mut *can), black_box(&mut e));
        let more = measure::<EQUIV_TX_IDLE, _>(|| equiv_tx_step(cc, ee));
        check(!more, "equivalent tx irq ends");

        restore(&snap.rx_one);
        let (cc, pp, ee) = (
            black_box(&mut *can),
            black_box(&mut producer),
            black_box(&mut e),
        );
        measure::<EQUIV_RX_IRQ, _>(|| equiv_rx_irq(cc, pp, ee));
        check(
            released() && consumer.len() == 1 && e.esr == 0,
            "equivalent rx irq",
        );
        let cq = black_box(&mut consumer);
        let rx = measure::<EQUIV_TAKE, _>(|| equiv_take(cq));
        check(rx.as_ref() == Some(&frame), "equivalent take");
    }
    check(
        e.overruns == 0 && e.ring_overflows == 0,
        "equivalent: no overrun",
    );
}

#[entry]
fn main() -> ! {
    let Some(mut core) = cortex_m::Peripherals::take() else {
        fail("core peripherals");
    };
    ram_can::announce(&REGIONS);
    for _ in 0..REPEAT {
        measure::<EMPTY, _>(|| ());
    }

    // Theirs: configure with the handshake stand-in, snapshot, measure, give the block up.
    reset_block();
    responder_on(&mut core.SYST);
    let mut theirs = configure_theirs();
    responder_off(&mut core.SYST);
    run_theirs(&snapshots(&save()), &mut theirs);
    let _ = theirs.free();

    // Ours: the same from a fresh reset block.
    reset_block();
    responder_on(&mut core.SYST);
    let hw = configure_ours();
    responder_off(&mut core.SYST);
    run_ours(&snapshots(&save()), hw);

    ram_can::finish()
}
