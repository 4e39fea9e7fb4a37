//! Instructions per frame of the twocan async receive path (issue 11) on a Cortex-M4 under
//! QEMU (`-machine mps2-an386`), counted by the TCG plugin `bench/plugin/insn_count.c`:
//! the split driver built with the `async` feature, on the RAM stand-in for CAN1's
//! registers of `shared/ram_can.rs` (see there for the method).
//!
//! One frame's trip through the async API, as an executor drives it:
//!
//! 1. `async.recv.pending`: the task polls its `Rx::recv` future with the ring empty —
//!    it registers the task's waker and returns `Pending`;
//! 2. `async.rx_irq`: the RX0 interrupt handler moves one frame from FIFO 0 into the ring
//!    and wakes the registered waker (once per interrupt);
//! 3. `async.recv.ready`: the woken task polls again — the future takes the frame,
//!    decoded, with its filter index, and returns `Ready`.
//!
//! The waker is a flag (`shared/flag_waker.rs`), the executor a hand-rolled poll: what
//! an executor adds around a wake (queueing the task) is not counted. For comparison the
//! same build measures the non-async `Rx::receive` (`async.receive`), so the difference
//! is the async machinery alone.
#![no_std]
#![no_main]

use core::future::Future;
use core::hint::black_box;
use core::pin::{pin, Pin};
use core::task::{Context, Poll};

use cortex_m_rt::entry;
use twocan_bxcan::{BxCan, Config};
use twocan_core::split::{Rx, Rx0Irq, State};
use twocan_core::{Error, FifoQueue, Frame, Mmio, RxFrame, TxPolicy};

#[path = "../../shared/flag_waker.rs"]
mod flag_waker;
#[path = "../../shared/qemu.rs"]
mod qemu;
#[path = "../../shared/ram_can.rs"]
mod ram_can;

use qemu::{check, fail, measure, responder_off, responder_on, REPEAT};
use ram_can::{released, reset_block, restore, save, snapshots, DATA, ID, REGS};

const APB1_HZ: u32 = 54_000_000;
const BITRATE: u32 = 500_000;
const RX: usize = 8;
const TXQ: usize = 8;

const CONFIG: Config = match Config::from_bitrate(APB1_HZ, BITRATE) {
    Ok(c) => c.loopback(true).tx_policy(TxPolicy::Fifo),
    Err(_) => panic!("no bit timing"),
};

const REGIONS: [&str; 5] = [
    "empty",
    "async.recv.pending",
    "async.rx_irq",
    "async.recv.ready",
    "async.receive",
];
const EMPTY: usize = 0;
const RECV_PENDING: usize = 1;
const RX_IRQ: usize = 2;
const RECV_READY: usize = 3;
const RECEIVE: usize = 4;

type Hw = BxCan<Mmio>;
type Q = FifoQueue<TXQ>;
type OurRx = Rx<'static, Hw, RX, Q, 0, 8>;
type OurRxIrq = Rx0Irq<'static, Hw, RX, Q, 0, 8>;

/// The driver's shared state (with the waker cells of the `async` feature).
static CAN: State<Hw, RX, Q> = State::new();

#[inline(never)]
fn poll_recv<F: Future<Output = Result<RxFrame, Error>>>(
    f: Pin<&mut F>,
    cx: &mut Context<'_>,
) -> Poll<Result<RxFrame, Error>> {
    f.poll(cx)
}

#[inline(never)]
fn rx_irq(h: &mut OurRxIrq) {
    h.on_interrupt()
}

#[inline(never)]
fn receive(rx: &mut OurRx) -> Option<RxFrame> {
    rx.receive().ok()
}

/// Our driver on the stand-in, configured with [`CONFIG`] and one accept-all bank to
/// FIFO 0 (run with the handshake stand-in; a timed-out request is retried, see
/// `qemu::responder_on`).
fn configure() -> Hw {
    use twocan_bxcan::{Bank, Can, Fifo, FilterPlan};
    use twocan_core::Filter;
    // SAFETY: `REGS` is the RAM stand-in for CAN1's registers, used by this driver only.
    let regs = unsafe { Mmio::new(REGS) };
    let mut attempt = Can::can1(regs, &CONFIG);
    for _ in 0..20 {
        match attempt {
            Err(f) if f.error == Error::Timeout => attempt = f.value.reconfigure(&CONFIG),
            _ => break,
        }
    }
    let Ok(mut init) = attempt else {
        fail("twocan: can1");
    };
    let mut plan = FilterPlan::manual();
    let Ok(bank) = Bank::mask32(&Filter::pass_all(), Fifo::Fifo0) else {
        fail("twocan: bank");
    };
    check(plan.set_bank(0, bank).is_ok(), "twocan: set_bank");
    check(init.set_filters(&plan).is_ok(), "twocan: set_filters");
    let mut attempt = init.enable();
    for _ in 0..20 {
        match attempt {
            Err(f) if f.error == Error::Timeout => attempt = f.value.enable(),
            _ => break,
        }
    }
    match attempt {
        Ok(can) => can.into_split(),
        Err(_) => fail("twocan: enable"),
    }
}

#[entry]
fn main() -> ! {
    let Some(mut core) = cortex_m::Peripherals::take() else {
        fail("core peripherals");
    };
    qemu::announce(&REGIONS);
    for _ in 0..REPEAT {
        measure::<EMPTY, _>(|| ());
    }
    reset_block();
    responder_on(&mut core.SYST);
    let hw = configure();
    responder_off(&mut core.SYST);
    let snap = snapshots(&save());
    let Ok(mut p) = CAN.split(hw) else {
        fail("twocan: split");
    };
    let frame = match Frame::standard(ID, &DATA) {
        Ok(f) => f,
        Err(_) => fail("frame"),
    };
    let waker = flag_waker::waker();
    let mut cx = Context::from_waker(&waker);
    for _ in 0..REPEAT {
        {
            let mut fut = pin!(p.rx.recv());
            let (f, c) = (black_box(fut.as_mut()), black_box(&mut cx));
            let r = measure::<RECV_PENDING, _>(|| poll_recv(f, c));
            check(r.is_pending() && !flag_waker::take(), "recv pending");

            restore(&snap.rx_one);
            let h = black_box(&mut p.rx0_irq);
            measure::<RX_IRQ, _>(|| rx_irq(h));
            check(released() && flag_waker::take(), "rx irq woke the task");

            let (f, c) = (black_box(fut.as_mut()), black_box(&mut cx));
            let r = measure::<RECV_READY, _>(|| poll_recv(f, c));
            check(
                matches!(r, Poll::Ready(Ok(ref r)) if r.frame == frame),
                "recv ready",
            );
        }
        restore(&snap.rx_one);
        p.rx0_irq.on_interrupt();
        check(!flag_waker::take(), "no waker registered: no wake");
        let r = black_box(&mut p.rx);
        let got = measure::<RECEIVE, _>(|| receive(r));
        check(got.is_some_and(|g| g.frame == frame), "receive");
    }
    qemu::finish()
}
