//! Minimal FlexCAN loop-back firmware, hand-written side: the behaviour of
//! `loopback-flexcan` (FlexCAN0 of a Teensy 3.6 in loop-back mode at 500 kbit/s, one
//! pass-all filter, one frame sent and received by polling) with the register-level
//! service of `shared/flexcan_hand.rs` (the same code `insn-count-flexcan` measures):
//! built twice, with feature `lean` and with feature `full`.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use panic_halt as _;

#[path = "../../shared/flexcan_hand.rs"]
mod hand;
#[path = "../../shared/kinetis.rs"]
mod startup;

const ID: u32 = 0x123;
const DATA: [u8; 8] = [0x01, 0x23, 0x45, 0x67, 0x89, 0xAB, 0xCD, 0xEF];
/// Bound on the polls for the looped-back frame (a frame lasts ~250 µs at 500 kbit/s).
const POLLS: u32 = 1_000_000;

fn loop_back() -> bool {
    hand::system_teensy36();
    if hand::configure::<hand::Can0>().is_err() {
        return false;
    }
    let Some(storage) = cortex_m::singleton!(: hand::Storage = hand::Storage::new()) else {
        return false;
    };
    let mut s = hand::split::<hand::Can0>(storage);
    let frame = hand::CanFrame {
        id: ID,
        extended: false,
        remote: false,
        dlc: 8,
        data: DATA,
    };
    let Ok(token) = s.sender.send(&frame) else {
        return false;
    };
    for _ in 0..POLLS {
        // The ORed message-buffer line runs both handlers.
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
    let ok = startup::init().is_ok() && loop_back();
    if !ok {
        panic!("loop-back failed");
    }
    loop {
        cortex_m::asm::wfi();
    }
}
