//! Minimal loop-back firmware, twocan side: CAN1 of an STM32F7 in loop-back mode at
//! 500 kbit/s from a 54 MHz APB1, one accept-all filter bank to FIFO 0, one frame sent and
//! received by polling. `loopback-bxcan` does the same with the bare `bxcan` crate,
//! `loopback-bxcan-equiv` with the `bxcan` crate plus what an application adds to get
//! our features (a receive ring, completion and overrun accounting, the error register);
//! `can-bench` builds the three side by side to compare flash and RAM.
//!
//! The driver is the split shape as an application sharing it with the CAN interrupts
//! keeps it: a `static State` (all zeros, `.bss`, no flash image) split once into the
//! transmit and receive halves and the per-line interrupt handlers, with the FIFO
//! transmit policy (`FifoQueue`: no priority queue linked). Here one context polls the
//! handlers in place of the interrupt lines.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use panic_halt as _;
use twocan_bxcan::{regs::CAN1_BASE, Bank, BxCan, Can, Config, Fifo, FilterPlan};
use twocan_core::split::State;
use twocan_core::{Error, FifoQueue, Filter, Frame, Mmio, TxPolicy};

#[path = "../../shared/stm32f7.rs"]
mod stm32f7;

const APB1_HZ: u32 = 54_000_000;
const BITRATE: u32 = 500_000;
const ID: u16 = 0x123;
const DATA: [u8; 8] = [0x01, 0x23, 0x45, 0x67, 0x89, 0xAB, 0xCD, 0xEF];
/// Bound on the polls for the looped-back frame (a frame lasts ~250 µs at 500 kbit/s).
const POLLS: u32 = 1_000_000;

/// Request-order transmit (TXFP = 1), the order of `FifoQueue`.
const CONFIG: Config = match Config::from_bitrate(APB1_HZ, BITRATE) {
    Ok(c) => c.loopback(true).tx_policy(TxPolicy::Fifo),
    Err(_) => panic!("no bit timing for 500 kbit/s from 54 MHz"),
};

/// Receive ring (FIFO 0) and transmit queue capacities, as `loopback-bxcan-equiv`.
const RX: usize = 8;
/// See [`RX`].
const TX: usize = 8;

/// The driver's shared state (exported under a fixed name so that can-bench can read its
/// size from the ELF).
#[no_mangle]
static BENCH_CAN_STATE: State<BxCan<Mmio>, RX, FifoQueue<TX>> = State::new();

fn start() -> Result<BxCan<Mmio>, Error> {
    // SAFETY: CAN1's register block (RM0410 §2.2.2), clocked by `stm32f7::clocks`;
    // nothing else in this firmware touches it.
    let regs = unsafe { Mmio::new(CAN1_BASE) };
    let mut init = Can::can1(regs, &CONFIG).map_err(|_| Error::WrongMode)?;
    // One accept-all bank to FIFO 0, set by hand as with the `bxcan` crate (the filter
    // planner is not linked).
    let mut plan = FilterPlan::manual();
    let bank =
        Bank::mask32(&Filter::pass_all(), Fifo::Fifo0).map_err(|_| Error::InvalidArgument)?;
    plan.set_bank(0, bank)?;
    init.set_filters(&plan)?;
    let can = init.enable().map_err(|_| Error::WrongMode)?;
    Ok(can.into_split())
}

fn loop_back(hw: BxCan<Mmio>) -> Result<bool, Error> {
    let frame = Frame::standard(ID, &DATA)?;
    let mut p = BENCH_CAN_STATE.split(hw).map_err(|(e, _)| e)?;
    p.tx.try_send(&frame).map_err(|_| Error::WrongMode)?;
    for _ in 0..POLLS {
        p.tx_irq.on_interrupt();
        p.rx0_irq.on_interrupt();
        if let Ok(rx) = p.rx.receive() {
            let sent = p.tx.take_completion().is_some();
            return Ok(sent && rx.frame == frame && rx.filter == FilterPlan::slot_index(0, 0));
        }
    }
    Ok(false)
}

#[entry]
fn main() -> ! {
    let ok = stm32f7::clocks().is_ok() && start().and_then(loop_back) == Ok(true);
    if !ok {
        panic!("loop-back failed");
    }
    loop {
        cortex_m::asm::wfi();
    }
}
