//! Minimal loop-back firmware, feature-equivalent `bxcan` side: the behaviour of
//! `loopback-bxcan` (CAN1 of an STM32F7 in loop-back mode at 500 kbit/s from a 54 MHz
//! APB1, one accept-all filter bank to FIFO 0, one frame sent and received by polling)
//! plus the service work an application adds around the `bxcan` crate 0.8 to get what
//! twocan's driver offers: a transmit interrupt that clears the completions (`RQCPx`) and
//! counts them, a receive interrupt that drains FIFO 0 into a `heapless::Deque` ring
//! counting hardware overruns and ring overflows and reads `CAN_ESR` for the error
//! state, and the thread side taking frames from the ring.
//!
//! The `Can` value and the ring live in one `critical_section::Mutex` static, as in
//! `loopback-bxcan`; one context polls the two handlers in place of the interrupt lines.
#![no_std]
#![no_main]

use core::cell::RefCell;

use bxcan::filter::Mask32;
use bxcan::{Fifo, Frame, StandardId};
use cortex_m_rt::entry;
use critical_section::Mutex;
use heapless::Deque;
use panic_halt as _;
use twocan_core::timing::{solve_cia, Limits};

#[path = "../../shared/stm32f7.rs"]
mod stm32f7;

const APB1_HZ: u32 = 54_000_000;
const BITRATE: u32 = 500_000;
const ID: u16 = 0x123;
const DATA: [u8; 8] = [0x01, 0x23, 0x45, 0x67, 0x89, 0xAB, 0xCD, 0xEF];
/// Bound on the polls for the looped-back frame (a frame lasts ~250 µs at 500 kbit/s).
const POLLS: u32 = 1_000_000;
/// Receive ring capacity (frames), as `loopback-twocan`.
const RX: usize = 8;

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
/// `CAN_ESR` (RM0410 §40.9.2), which the `bxcan` crate does not expose.
const CAN1_ESR: usize = CAN1_BASE + 0x18;

// SAFETY: `REGISTERS` is CAN1's register block, clocked by `stm32f7::clocks`; only the
// one `bxcan::Can<Can1>` of this firmware accesses it (and `service` reads `CAN_ESR`).
unsafe impl bxcan::Instance for Can1 {
    const REGISTERS: *mut bxcan::RegisterBlock = CAN1_BASE as *mut _;
}

// SAFETY: CAN1 owns the dual filter block of 28 banks (RM0410 §40.2).
unsafe impl bxcan::FilterOwner for Can1 {
    const NUM_FILTER_BANKS: u8 = 28;
}

// SAFETY: CAN1 is the master instance of the dual CAN.
unsafe impl bxcan::MasterInstance for Can1 {}

/// The driver and the application's service state.
struct Service {
    can: bxcan::Can<Can1>,
    ring: Deque<Frame, RX>,
    completions: u32,
    overruns: u32,
    ring_overflows: u32,
    esr: u32,
}

static CAN: Mutex<RefCell<Option<Service>>> = Mutex::new(RefCell::new(None));

fn start() -> bool {
    let mut can = bxcan::Can::builder(Can1)
        .set_bit_timing(BTR)
        .set_loopback(true)
        .leave_disabled();
    can.modify_filters()
        .enable_bank(0, Fifo::Fifo0, Mask32::accept_all());
    if nb::block!(can.enable_non_blocking()).is_err() {
        return false;
    }
    critical_section::with(|cs| {
        CAN.borrow_ref_mut(cs).replace(Service {
            can,
            ring: Deque::new(),
            completions: 0,
            overruns: 0,
            ring_overflows: 0,
            esr: 0,
        })
    });
    true
}

/// The TX interrupt's work: completions cleared and counted.
fn on_tx(s: &mut Service) {
    while s.can.clear_request_completed_flag().is_some() {
        s.completions += 1;
    }
}

/// The RX0 interrupt's work: FIFO 0 into the ring, overruns counted, `CAN_ESR` read.
fn on_rx0(s: &mut Service) {
    loop {
        match s.can.rx0().receive() {
            Ok(f) => {
                if s.ring.push_back(f).is_err() {
                    s.ring_overflows += 1;
                }
            }
            Err(nb::Error::Other(_)) => s.overruns += 1,
            Err(nb::Error::WouldBlock) => break,
        }
    }
    // SAFETY: `CAN_ESR` of CAN1 (see `Can1`); a read has no side effect.
    s.esr = unsafe { core::ptr::read_volatile(CAN1_ESR as *const u32) };
}

fn loop_back() -> bool {
    let Some(id) = StandardId::new(ID) else {
        return false;
    };
    let frame = Frame::new_data(id, DATA);
    let sent = critical_section::with(|cs| {
        let mut s = CAN.borrow_ref_mut(cs);
        s.as_mut().is_some_and(|s| s.can.transmit(&frame).is_ok())
    });
    if !sent {
        return false;
    }
    for _ in 0..POLLS {
        let got = critical_section::with(|cs| {
            let mut s = CAN.borrow_ref_mut(cs);
            let s = s.as_mut()?;
            on_tx(s);
            on_rx0(s);
            s.ring.pop_front().map(|f| (f, s.completions))
        });
        if let Some((rx, completions)) = got {
            return rx == frame && completions == 1;
        }
    }
    false
}

#[entry]
fn main() -> ! {
    let ok = stm32f7::clocks().is_ok() && start() && loop_back();
    if !ok {
        panic!("loop-back failed");
    }
    loop {
        cortex_m::asm::wfi();
    }
}
