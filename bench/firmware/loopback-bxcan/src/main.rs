//! Minimal loop-back firmware, `bxcan` crate side: the same behaviour as
//! `loopback-twocan` — CAN1 of an STM32F7 in loop-back mode at 500 kbit/s from a 54 MHz
//! APB1, one accept-all filter bank to FIFO 0, one frame sent and received by polling —
//! with the `bxcan` crate 0.8 from crates.io.
//!
//! The `Can` value lives in a `critical_section::Mutex` static as in `loopback-twocan`.
#![no_std]
#![no_main]

use core::cell::RefCell;

use bxcan::filter::Mask32;
use bxcan::{Fifo, Frame, StandardId};
use cortex_m_rt::entry;
use critical_section::Mutex;
use panic_halt as _;
use twocan_core::timing::{solve_cia, Limits};

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

// SAFETY: `REGISTERS` is CAN1's register block (RM0410 §2.2.2, 0x4000_6400), clocked by
// `stm32f7::clocks`; only the one `bxcan::Can<Can1>` of this firmware accesses it.
unsafe impl bxcan::Instance for Can1 {
    const REGISTERS: *mut bxcan::RegisterBlock = 0x4000_6400 as *mut _;
}

// SAFETY: CAN1 owns the dual filter block of 28 banks (RM0410 §40.2).
unsafe impl bxcan::FilterOwner for Can1 {
    const NUM_FILTER_BANKS: u8 = 28;
}

// SAFETY: CAN1 is the master instance of the dual CAN.
unsafe impl bxcan::MasterInstance for Can1 {}

static CAN: Mutex<RefCell<Option<bxcan::Can<Can1>>>> = Mutex::new(RefCell::new(None));

fn start() {
    let mut can = bxcan::Can::builder(Can1)
        .set_bit_timing(BTR)
        .set_loopback(true)
        .leave_disabled();
    can.modify_filters()
        .enable_bank(0, Fifo::Fifo0, Mask32::accept_all());
    let ok = nb::block!(can.enable_non_blocking());
    if ok.is_ok() {
        critical_section::with(|cs| CAN.borrow_ref_mut(cs).replace(can));
    }
}

fn loop_back() -> bool {
    let Some(id) = StandardId::new(ID) else {
        return false;
    };
    let frame = Frame::new_data(id, DATA);
    critical_section::with(|cs| {
        let mut can = CAN.borrow_ref_mut(cs);
        let Some(can) = can.as_mut() else {
            return false;
        };
        if can.transmit(&frame).is_err() {
            return false;
        }
        for _ in 0..POLLS {
            match can.receive() {
                Ok(rx) => return rx == frame,
                Err(nb::Error::WouldBlock) => {}
                Err(nb::Error::Other(_overrun)) => return false,
            }
        }
        false
    })
}

#[entry]
fn main() -> ! {
    let ok = startup::clocks().is_ok() && {
        start();
        loop_back()
    };
    if !ok {
        panic!("loop-back failed");
    }
    loop {
        cortex_m::asm::wfi();
    }
}
