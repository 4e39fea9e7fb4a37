//! Minimal loop-back firmware, twocan side: CAN1 of an STM32F7 in loop-back mode at
//! 500 kbit/s from a 54 MHz APB1, one accept-all filter bank to FIFO 0, one frame sent
//! and received by polling. `loopback-bxcan` does the same with the `bxcan` crate; the
//! two are built side by side by `can-bench` to compare flash and RAM.
//!
//! The driver lives in a `critical_section::Mutex` static, as an application sharing it
//! with the CAN interrupt would keep it, so its rings count in `.bss`.
#![no_std]
#![no_main]

use core::cell::RefCell;

use cortex_m_rt::entry;
use critical_section::Mutex;
use panic_halt as _;
use twocan_bxcan::{regs::CAN1_BASE, Bank, Can, Config, Fifo, FilterPlan};
use twocan_core::{Driver, Error, Filter, Frame, Mmio, TxPolicy};

#[path = "../../shared/stm32f7.rs"]
mod stm32f7;

const APB1_HZ: u32 = 54_000_000;
const BITRATE: u32 = 500_000;
const ID: u16 = 0x123;
const DATA: [u8; 8] = [0x01, 0x23, 0x45, 0x67, 0x89, 0xAB, 0xCD, 0xEF];
/// Bound on the polls for the looped-back frame (a frame lasts ~250 µs at 500 kbit/s).
const POLLS: u32 = 1_000_000;

/// Identifier-priority transmit order (TXFP = 0), as the `bxcan` crate uses.
const CONFIG: Config = match Config::from_bitrate(APB1_HZ, BITRATE) {
    Ok(c) => c.loopback(true).tx_policy(TxPolicy::Priority),
    Err(_) => panic!("no bit timing for 500 kbit/s from 54 MHz"),
};

type Can1 = Driver<Can<Mmio>, 8, 8>;

static CAN: Mutex<RefCell<Option<Can1>>> = Mutex::new(RefCell::new(None));

fn start() -> Result<(), Error> {
    // SAFETY: CAN1's register block (RM0410 §2.2.2), clocked by `stm32f7::clocks`;
    // nothing else in this firmware touches it.
    let regs = unsafe { Mmio::new(CAN1_BASE) };
    let mut init = Can::can1(regs, &CONFIG)?;
    let mut filters = FilterPlan::manual();
    let bank =
        Bank::mask32(&Filter::pass_all(), Fifo::Fifo0).map_err(|_| Error::InvalidArgument)?;
    filters.set_bank(0, bank)?;
    init.set_filters(&filters)?;
    let can = init.enable()?;
    critical_section::with(|cs| CAN.borrow_ref_mut(cs).replace(Driver::new(can)));
    Ok(())
}

fn loop_back() -> Result<bool, Error> {
    let frame = Frame::standard(ID, &DATA)?;
    critical_section::with(|cs| {
        let mut can = CAN.borrow_ref_mut(cs);
        let can = can.as_mut().ok_or(Error::WrongMode)?;
        can.try_send(&frame).map_err(|_| Error::WrongMode)?;
        for _ in 0..POLLS {
            can.on_interrupt();
            if let Ok(rx) = can.receive() {
                return Ok(rx.frame == frame);
            }
        }
        Ok(false)
    })
}

#[entry]
fn main() -> ! {
    let ok = stm32f7::clocks().is_ok() && start().is_ok() && loop_back() == Ok(true);
    if !ok {
        panic!("loop-back failed");
    }
    loop {
        cortex_m::asm::wfi();
    }
}
