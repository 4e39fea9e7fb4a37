//! Minimal loop-back firmware, feature-equivalent `bxcan` side: the behaviour of
//! `loopback-bxcan` (CAN1 of an STM32F7 in loop-back mode at 500 kbit/s from a 54 MHz
//! APB1, one accept-all filter bank to FIFO 0, one frame sent and received by polling)
//! plus the service an application adds around the `bxcan` crate 0.8 to get what our
//! driver's variant offers (`shared/bxcan_equiv.rs`, the same code `insn-count`
//! measures): built twice, with feature `lean` and with feature `full`.
//!
//! The service is split once over a `static` storage (`cortex_m::singleton!`); one
//! context polls the handlers in place of the interrupt lines.
#![no_std]
#![no_main]

use bxcan::filter::Mask32;
use bxcan::{Fifo, Frame, StandardId};
use cortex_m_rt::entry;
use panic_halt as _;
use twocan_core::timing::{solve_cia, Limits};

#[path = "../../shared/bxcan_equiv.rs"]
mod equiv;
#[path = "../../shared/stm32f7.rs"]
mod startup;

const APB1_HZ: u32 = 54_000_000;
const BITRATE: u32 = 500_000;
const ID: u16 = 0x123;
const DATA: [u8; 8] = [0x01, 0x23, 0x45, 0x67, 0x89, 0xAB, 0xCD, 0xEF];
/// Bound on the polls for the looped-back frame (a frame lasts ~250 µs at 500 kbit/s).
const POLLS: u32 = 1_000_000;

/// The same CAN_BTR timing as `loopback-twocan` (computed at compile time; `bxcan` takes
/// a raw CAN_BTR value).
const BTR: u32 = match solve_cia(APB1_HZ, BITRATE, &Limits::BXCAN) {
    Ok(t) => match t.bxcan_btr() {
        Ok(v) => v,
        Err(_) => panic!("timing does not fit CAN_BTR"),
    },
    Err(_) => panic!("no bit timing for 500 kbit/s from 54 MHz"),
};

/// CAN1 of the STM32F7.
struct Can1;

/// CAN1's register block (RM0410 §2.2.2).
const CAN1_BASE: usize = 0x4000_6400;

// SAFETY: `REGISTERS` is CAN1's register block, clocked by `stm32f7::clocks`; only the
// one `bxcan::Can<Can1>` of this firmware and its service (`shared/bxcan_equiv.rs`:
// `CAN_TSR` acknowledgements, reads of `CAN_RDT0R`, `CAN_TDTxR` and `CAN_ESR`) access it.
unsafe impl bxcan::Instance for Can1 {
    const REGISTERS: *mut bxcan::RegisterBlock = CAN1_BASE as *mut _;
}

// SAFETY: CAN1 owns the dual filter block of 28 banks (RM0410 §40.2).
unsafe impl bxcan::FilterOwner for Can1 {
    const NUM_FILTER_BANKS: u8 = 28;
}

// SAFETY: CAN1 is the master instance of the dual CAN.
unsafe impl bxcan::MasterInstance for Can1 {}

fn start() -> Option<bxcan::Can<Can1>> {
    let mut can = bxcan::Can::builder(Can1)
        .set_bit_timing(BTR)
        .set_loopback(true)
        .leave_disabled();
    can.modify_filters()
        .enable_bank(0, Fifo::Fifo0, Mask32::accept_all());
    #[cfg(feature = "full")]
    // SAFETY: `CAN_MCR` of CAN1 in initialization mode (`leave_disabled`): TTCM (bit 7)
    // turns the receive and transmit time stamps on (the crate has no switch for it).
    unsafe {
        let mcr = CAN1_BASE as *mut u32;
        mcr.write_volatile(mcr.read_volatile() | (1 << 7));
    }
    nb::block!(can.enable_non_blocking()).ok()?;
    Some(can)
}

fn loop_back(can: bxcan::Can<Can1>) -> bool {
    let Some(id) = StandardId::new(ID) else {
        return false;
    };
    let frame = Frame::new_data(id, DATA);
    let Some(storage) = cortex_m::singleton!(: equiv::Storage = equiv::Storage::new()) else {
        return false;
    };
    let mut s = equiv::split(can, storage);
    let Ok(token) = nb::block!(s.sender.send(&frame));
    for _ in 0..POLLS {
        #[cfg(feature = "full")]
        s.tx_irq.on_interrupt();
        s.rx_irq.on_interrupt();
        if let Some(rx) = s.receiver.take() {
            // The completion may come after the reception: bounded wait.
            #[cfg(feature = "full")]
            let sent = (0..POLLS).any(|_| {
                s.tx_irq.on_interrupt();
                s.completions
                    .take()
                    .is_some_and(|c| c.token == token && c.sent)
            });
            #[cfg(feature = "lean")]
            let sent = token == 0;
            return sent && rx.frame == frame && rx.filter == 0;
        }
    }
    false
}

#[entry]
fn main() -> ! {
    let ok = startup::clocks().is_ok() && start().is_some_and(loop_back);
    if !ok {
        panic!("loop-back failed");
    }
    loop {
        cortex_m::asm::wfi();
    }
}
