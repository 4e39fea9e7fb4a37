//! Minimal FlexCAN loop-back firmware, twocan side: FlexCAN0 of a Teensy 3.6 in
//! loop-back mode with self reception at 500 kbit/s from the 16 MHz oscillator clock,
//! one pass-all filter, one frame sent and received by polling. Built twice, with
//! feature `lean` and with feature `full`: the driver's configuration is the one of
//! `shared/flexcan_variant.rs`, as in `insn-count-flexcan`. `loopback-flexcan-hand` does
//! the same with the hand-written service (`shared/flexcan_hand.rs`); `can-bench` builds
//! them side by side to compare flash and RAM.
//!
//! The driver is kept as an interrupt-driven application keeps it: a `static State`
//! (all zeros, `.bss`) split once; one context polls the handlers in place of the
//! interrupt line.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use panic_halt as _;
use twocan_core::{Frame, Mmio};
use twocan_flexcan::regs::{Can0At, SystemRegs};

#[path = "../../shared/feature_sets.rs"]
mod feature_sets;
#[path = "../../shared/kinetis.rs"]
mod startup;
#[path = "../../shared/flexcan_variant.rs"]
mod variant;

const ID: u16 = 0x123;
const DATA: [u8; 8] = [0x01, 0x23, 0x45, 0x67, 0x89, 0xAB, 0xCD, 0xEF];
/// Bound on the polls for the looped-back frame (a frame lasts ~250 µs at 500 kbit/s).
const POLLS: u32 = 1_000_000;

type R = Can0At;

/// The driver's shared state (exported under a fixed name so that can-bench can read its
/// size from the ELF).
#[no_mangle]
static BENCH_CAN_STATE: variant::OurState<R> = variant::OurState::new();

fn start() -> Option<variant::OurParts<R>> {
    // SAFETY: FlexCAN0's register block (K66 RM memory map "CAN0"); nothing else in this
    // firmware touches it.
    let regs = || unsafe { Can0At::new() };
    // SAFETY: base 0 with absolute offsets, the window SIM..PORTE: `begin` only touches
    // the clock gates and the PCRs of FlexCAN0's pins.
    let mut sys: SystemRegs = unsafe { Mmio::new(0) };
    variant::start::<0, _, _>(&BENCH_CAN_STATE, regs, &mut sys).ok()
}

fn loop_back(mut p: variant::OurParts<R>) -> bool {
    let Ok(frame) = Frame::standard(ID, &DATA) else {
        return false;
    };
    if p.tx.try_send(&frame).is_err() {
        return false;
    }
    for _ in 0..POLLS {
        // The ORed message-buffer line runs both handlers.
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
            return sent && rx.frame == frame && rx.filter == variant::FILTER_INDEX;
        }
    }
    false
}

#[entry]
fn main() -> ! {
    let ok = startup::init().is_ok() && start().is_some_and(loop_back);
    if !ok {
        panic!("loop-back failed");
    }
    loop {
        cortex_m::asm::wfi();
    }
}
