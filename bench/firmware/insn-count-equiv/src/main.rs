//! Instructions per frame and stack high-water marks of the **feature-equivalent**
//! service around the `bxcan` crate 0.8 (`shared/bxcan_equiv.rs`) on a Cortex-M4 under
//! QEMU (`-machine mps2-an386`), counted by the TCG plugin `bench/plugin/insn_count.c`.
//! Built twice, with feature `lean` and with feature `full`; can-bench merges its
//! figures with those of `insn-count` (our driver and the bare crate, built separately
//! so that neither image shares the crate's code with the other and each keeps it
//! inlined as a firmware using it alone would). The register stand-in is the one of
//! `insn-count` (`shared/ram_can.rs`).
#![no_std]
#![no_main]

use core::hint::black_box;

use cortex_m_rt::entry;
use twocan_core::timing::{solve_cia, Limits};

#[path = "../../shared/bxcan_equiv.rs"]
mod equiv;
#[path = "../../shared/qemu.rs"]
mod qemu;
#[path = "../../shared/ram_bxcan_crate.rs"]
mod ram_bxcan_crate;
#[path = "../../shared/ram_can.rs"]
mod ram_can;

use qemu::{
    check, config_stack_depth, fail, measure, report_stack, responder_off, responder_on,
    stack_depth, REPEAT,
};
use ram_bxcan_crate::RamCan1;
use ram_can::{loaded, released, reset_block, restore, save, snapshots, Snapshots, DATA, ID};

/// The `CAN_BTR` value of our configuration (the same bit timing on every side).
const BTR: u32 = match solve_cia(54_000_000, 500_000, &Limits::BXCAN) {
    Ok(t) => match t.bxcan_btr() {
        Ok(v) => v,
        Err(_) => panic!("timing does not fit CAN_BTR"),
    },
    Err(_) => panic!("no bit timing for 500 kbit/s from 54 MHz"),
};

#[cfg(feature = "lean")]
const REGIONS: &[&str] = REGIONS_ALL.split_at(5).0;
#[cfg(feature = "full")]
const REGIONS: &[&str] = &REGIONS_ALL;

const REGIONS_ALL: [&str; 7] = [
    "empty",
    "equiv.tx",
    "equiv.rx_irq",
    "equiv.take",
    "equiv.tx.one_busy",
    // full only
    "equiv.tx_irq",
    "equiv.take_completion",
];

const EMPTY: usize = 0;
const EQUIV_TX: usize = 1;
const EQUIV_RX_IRQ: usize = 2;
const EQUIV_TAKE: usize = 3;
const EQUIV_TX_ONE_BUSY: usize = 4;
#[cfg(feature = "full")]
const EQUIV_TX_IRQ: usize = 5;
#[cfg(feature = "full")]
const EQUIV_TAKE_COMPLETION: usize = 6;

#[cfg(feature = "lean")]
const ROUNDTRIP_EQUIV: &[&str] = &["equiv.tx", "equiv.rx_irq", "equiv.take"];
#[cfg(feature = "full")]
const ROUNDTRIP_EQUIV: &[&str] = &[
    "equiv.tx",
    "equiv.tx_irq",
    "equiv.rx_irq",
    "equiv.take",
    "equiv.take_completion",
];

/// Prints the configuration's stack figure (the upper bound: the handshake stand-in's
/// exception frames included) and, as a note, the lower bound
/// (`qemu::config_stack_depth`).
fn report_config_stack(key: &str, low: u32, high: u32) {
    report_stack(key, high);
    qemu::note(key, ".low", low);
}

// ------------------------------------------------------------------ the equivalent

type Service = equiv::Service<'static, RamCan1>;

#[inline(never)]
fn equiv_send(s: &mut equiv::Sender<'_, RamCan1>, f: &bxcan::Frame) -> Option<u32> {
    s.send(f).ok()
}

#[cfg(feature = "full")]
#[inline(never)]
fn equiv_tx_irq(h: &mut equiv::TxHandler<'_, RamCan1>) {
    h.on_interrupt()
}

#[inline(never)]
fn equiv_rx_irq(h: &mut equiv::RxHandler<'_, RamCan1>) {
    h.on_interrupt()
}

#[inline(never)]
fn equiv_take(r: &mut equiv::Receiver<'_>) -> Option<equiv::Taken> {
    r.take()
}

#[cfg(feature = "full")]
#[inline(never)]
fn equiv_take_completion(c: &mut equiv::Completions<'_>) -> Option<equiv::Completion> {
    c.take()
}

/// The equivalent's configuration: the crate's, then the service split over its
/// storage.
#[inline(never)]
fn equiv_configure(storage: &'static mut equiv::Storage) -> Service {
    equiv::split(
        ram_bxcan_crate::configure(BTR, cfg!(feature = "full")),
        storage,
    )
}

fn run_equiv(snap: &Snapshots, s: &mut Service) {
    let id = match bxcan::StandardId::new(ID) {
        Some(id) => id,
        None => fail("bxcan id"),
    };
    let frame = bxcan::Frame::new_data(id, DATA);
    for _ in 0..REPEAT {
        restore(&snap.tx_free);
        let (ss, ff) = (black_box(&mut s.sender), black_box(&frame));
        let token = measure::<EQUIV_TX, _>(|| equiv_send(ss, ff));
        check(token.is_some() && loaded(0), "equivalent send");

        #[cfg(feature = "full")]
        {
            // The TX interrupt: one completion, `RQCP0` acknowledged.
            restore(&snap.tx_done);
            let h = black_box(&mut s.tx_irq);
            measure::<EQUIV_TX_IRQ, _>(|| equiv_tx_irq(h));
            check(
                ram_can::reg_read(twocan_bxcan::regs::TSR) == twocan_bxcan::regs::tsr::RQCP0,
                "equivalent tx irq acknowledged RQCP0",
            );
            let c = black_box(&mut s.completions);
            let done = measure::<EQUIV_TAKE_COMPLETION, _>(|| equiv_take_completion(c));
            check(
                done.is_some_and(|c| Some(c.token) == token && c.sent),
                "equivalent completion",
            );
        }

        restore(&snap.rx_one);
        let h = black_box(&mut s.rx_irq);
        measure::<EQUIV_RX_IRQ, _>(|| equiv_rx_irq(h));
        check(released(), "equivalent rx irq");
        let r = black_box(&mut s.receiver);
        let rx = measure::<EQUIV_TAKE, _>(|| equiv_take(r));
        check(
            rx.is_some_and(|r| r.frame == frame && r.filter == 0),
            "equivalent take",
        );

        restore(&snap.tx_one_busy);
        let (ss, ff) = (black_box(&mut s.sender), black_box(&frame));
        let token = measure::<EQUIV_TX_ONE_BUSY, _>(|| equiv_send(ss, ff));
        check(token.is_some() && loaded(1), "equivalent send one busy");
    }
    restore(&snap.tx_free);
    let (t, bytes, _) = stack_depth(|| equiv_send(&mut s.sender, &frame));
    check(t.is_some(), "equivalent stack send");
    report_stack("equiv.tx", bytes);
    #[cfg(feature = "full")]
    {
        restore(&snap.tx_done);
        let ((), bytes, _) = stack_depth(|| equiv_tx_irq(&mut s.tx_irq));
        report_stack("equiv.tx_irq", bytes);
        let (c, bytes, _) = stack_depth(|| equiv_take_completion(&mut s.completions));
        check(c.is_some(), "equivalent stack take completion");
        report_stack("equiv.take_completion", bytes);
    }
    restore(&snap.rx_one);
    let ((), bytes, _) = stack_depth(|| equiv_rx_irq(&mut s.rx_irq));
    report_stack("equiv.rx_irq", bytes);
    let (r, bytes, _) = stack_depth(|| equiv_take(&mut s.receiver));
    check(r.is_some(), "equivalent stack take");
    report_stack("equiv.take", bytes);
    check(
        s.counts.overruns.get() == 0 && s.counts.ring_overflows.get() == 0,
        "equivalent: no overrun, no overflow",
    );
}

#[entry]
fn main() -> ! {
    let Some(mut core) = cortex_m::Peripherals::take() else {
        fail("core peripherals");
    };
    qemu::announce(REGIONS);
    qemu::report_roundtrip("equiv", ROUNDTRIP_EQUIV);
    qemu::variant(equiv::VARIANT);
    for _ in 0..REPEAT {
        measure::<EMPTY, _>(|| ());
    }
    let Some(storage) = cortex_m::singleton!(: equiv::Storage = equiv::Storage::new()) else {
        fail("equivalent storage");
    };
    reset_block();
    responder_on(&mut core.SYST);
    let (mut service, low, high) = config_stack_depth(|| equiv_configure(storage));
    responder_off(&mut core.SYST);
    report_config_stack("equiv.config", low, high);
    run_equiv(&snapshots(&save()), &mut service);
    qemu::finish()
}
