//! Minimal loop-back firmware with the async API (feature `async`): `loopback-twocan`'s
//! behaviour (CAN1 of an STM32F7 in loop-back mode at 500 kbit/s from a 54 MHz APB1, one
//! accept-all filter bank to FIFO 0, one frame) with the frame sent by `Tx::send` and
//! taken by `Rx::recv`, futures polled by a hand-rolled loop with a flag waker (no
//! executor crate) while the TX and RX0 handlers are polled in place of the interrupt
//! lines. can-bench reports its flash as the async firmware's.
#![no_std]
#![no_main]

use core::future::Future;
use core::pin::pin;
use core::task::{Context, Poll};

use cortex_m_rt::entry;
use panic_halt as _;
use twocan_bxcan::{regs::CAN1_BASE, BxCan, Config, PlanOptions};
use twocan_core::split::{Parts, State};
use twocan_core::{Error, FifoQueue, Filter, Frame, Mmio, TxPolicy};

#[path = "../../shared/flag_waker.rs"]
mod flag_waker;
#[path = "../../shared/stm32f7.rs"]
mod startup;

const APB1_HZ: u32 = 54_000_000;
const BITRATE: u32 = 500_000;
const ID: u16 = 0x123;
const DATA: [u8; 8] = [0x01, 0x23, 0x45, 0x67, 0x89, 0xAB, 0xCD, 0xEF];
/// Bound on the polls for the looped-back frame (a frame lasts ~250 µs at 500 kbit/s).
const POLLS: u32 = 1_000_000;

const CONFIG: Config = match Config::from_bitrate(APB1_HZ, BITRATE) {
    Ok(c) => c.loopback(true).tx_policy(TxPolicy::Fifo),
    Err(_) => panic!("no bit timing for 500 kbit/s from 54 MHz"),
};

/// One accept-all filter to FIFO 0, planned at compile time (CAN1's 14 banks at reset).
const FILTERS: [Filter; 1] = [Filter::pass_all()];

/// The controller: CAN1, no merged-filter lookup keys (the plan has none).
type Hw = BxCan<Mmio, Mmio, 0>;

static CAN: State<Hw, 8, FifoQueue<8>> = State::new();

/// CAN1 configured in place in [`CAN`] (`State::split_with`, `BxCan::can1_in`: no
/// controller, plan or filter map moves through the configuration), then split.
fn start() -> Result<Parts<'static, Hw, 8, FifoQueue<8>, 0, 8>, Error> {
    // SAFETY: CAN1's register block (RM0410 §2.2.2), clocked by `stm32f7::clocks`;
    // nothing else in this firmware touches it.
    let regs = unsafe { Mmio::new(CAN1_BASE) };
    let plan = twocan_bxcan::const_plan!(FILTERS, PlanOptions::new(14));
    CAN.split_with(|slot| Hw::can1_in(slot, regs, &CONFIG, plan).map_err(|f| f.error))
}

/// Polls `f` to completion, running `idle` (the interrupt lines' work) between polls.
fn run<F: Future>(f: F, mut idle: impl FnMut()) -> Option<F::Output> {
    let waker = flag_waker::waker();
    let mut cx = Context::from_waker(&waker);
    let mut f = pin!(f);
    for _ in 0..POLLS {
        if let Poll::Ready(v) = f.as_mut().poll(&mut cx) {
            return Some(v);
        }
        while !flag_waker::take() {
            idle();
        }
    }
    None
}

fn loop_back(mut p: Parts<'static, Hw, 8, FifoQueue<8>, 0, 8>) -> Result<bool, Error> {
    let frame = Frame::standard(ID, &DATA)?;
    let (tx_irq, rx0_irq) = (&mut p.tx_irq, &mut p.rx0_irq);
    let mut lines = || {
        tx_irq.on_interrupt();
        rx0_irq.on_interrupt();
    };
    let token = run(p.tx.send(&frame), &mut lines).ok_or(Error::WrongMode)??;
    let rx = run(p.rx.recv(), &mut lines).ok_or(Error::WrongMode)??;
    let done = run(p.tx.completed(token), &mut lines).ok_or(Error::WrongMode)??;
    Ok(rx.frame == frame && done.token == token)
}

#[entry]
fn main() -> ! {
    let ok = startup::clocks().is_ok() && start().and_then(loop_back) == Ok(true);
    if !ok {
        panic!("loop-back failed");
    }
    loop {
        cortex_m::asm::wfi();
    }
}
