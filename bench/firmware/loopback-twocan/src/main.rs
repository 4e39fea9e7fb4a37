//! Minimal loop-back firmware, twocan side: CAN1 of an STM32F7 in loop-back mode at
//! 500 kbit/s from a 54 MHz APB1, one accept-all filter to FIFO 0, one frame sent and
//! received by polling. Built twice, with feature `lean` and with feature `full`: the
//! driver's configuration is the one of `shared/bxcan_variant.rs`, as in `insn-count`.
//! `loopback-bxcan` does the same with the bare `bxcan` crate, `loopback-bxcan-equiv`
//! with the `bxcan` crate plus what an application adds to get the variant's features
//! (`shared/bxcan_equiv.rs`); `can-bench` builds them side by side to compare flash and
//! RAM.
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
use twocan_bxcan::regs::CAN1_BASE;
use twocan_core::{Error, Frame};

#[path = "../../shared/feature_sets.rs"]
mod feature_sets;
#[path = "../../shared/stm32f7.rs"]
mod startup;
#[path = "../../shared/bxcan_variant.rs"]
mod variant;

/// CAN1's register block (RM0410 §2.2.2), read by `variant::Regs`.
const CAN_BASE: usize = CAN1_BASE;

const ID: u16 = 0x123;
const DATA: [u8; 8] = [0x01, 0x23, 0x45, 0x67, 0x89, 0xAB, 0xCD, 0xEF];
/// Bound on the polls for the looped-back frame (a frame lasts ~250 µs at 500 kbit/s).
const POLLS: u32 = 1_000_000;

/// The driver's shared state (exported under a fixed name so that can-bench can read its
/// size from the ELF).
#[no_mangle]
static BENCH_CAN_STATE: variant::OurState = variant::OurState::new();

fn start() -> Result<variant::OurParts, Error> {
    // SAFETY: CAN1's register block (RM0410 §2.2.2), clocked by `stm32f7::clocks`;
    // nothing else in this firmware touches it.
    let regs = unsafe { variant::Regs::new() };
    variant::start::<0>(&BENCH_CAN_STATE, regs)
}

fn loop_back(mut p: variant::OurParts) -> Result<bool, Error> {
    let frame = Frame::standard(ID, &DATA)?;
    p.tx.try_send(&frame).map_err(|_| Error::WrongMode)?;
    for _ in 0..POLLS {
        p.tx_irq.on_interrupt();
        p.rx0_irq.on_interrupt();
        if let Ok(rx) = p.rx.receive() {
            // With completions (full), the frame's completion is taken too (its flag may
            // come after the reception: bounded wait).
            let sent = variant::DONE == 0
                || (0..POLLS).any(|_| {
                    p.tx_irq.on_interrupt();
                    p.tx.take_completion().is_some()
                });
            return Ok(sent && rx.frame == frame && rx.filter == variant::FILTER_INDEX);
        }
    }
    Ok(false)
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
