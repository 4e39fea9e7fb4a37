//! ACAN's `LoopBackDemo` (ACAN manual §4) on FlexCAN0: loop-back and self-reception, so
//! it needs no transceiver and no other node. One standard data frame (identifier 0x542)
//! every second; every frame received toggles the LED. `SENT` and `RECEIVED` can be
//! read with a debugger.
//!
//! Started with the one call of `twocan_flexcan::acan` (ACAN's `begin`): token, begin
//! on the default pins (3 and 4), the library's `static` state, interrupts wired; the
//! settings checked at compile time (`can0_checked`).
//!
//! Blink codes when it stops: 2–4 clock start-up, 5 FlexCAN `begin`, 6 panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::sync::atomic::{AtomicU32, Ordering};

    use twocan_core::Frame;
    use twocan_flexcan::{acan, BeginPlan, Can0, Settings};
    use twocan_teensy::configs::LOOPBACK_FILTERS;
    use twocan_teensy::rt::{self, CAN_BLINKS};
    use twocan_teensy::time::{self, Every};

    /// Frames handed to the driver.
    pub static SENT: AtomicU32 = AtomicU32::new(0);
    /// Frames received back.
    pub static RECEIVED: AtomicU32 = AtomicU32::new(0);

    /// ACAN §4: 125 kbit/s, loop-back and self reception. Computed at compile time
    /// (the bit-timing solver is `const`), so the solver is not in the image.
    const SETTINGS: Settings = twocan_teensy::configs::LOOPBACK;

    /// The settings checked at compile time for FlexCAN0 (`can0_checked`: no check runs
    /// on the board, and the configuration stays within a few hundred bytes of stack).
    const CHECKED: BeginPlan =
        BeginPlan::new_or_panic(Can0::TARGET, &SETTINGS, SETTINGS.configuration);

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        twocan_teensy::info!("teensy-loopback: CAN0 in loop-back, a frame every second");
        let (mut tx, mut rx) =
            acan::can0_checked(&CHECKED, &LOOPBACK_FILTERS, &[], &mut boot.core.NVIC)
                .unwrap_or_else(|_| rt::halt(CAN_BLINKS));

        let message = Frame::standard(0x542, &[]).unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        let mut send = Every::new(time::millis(), 1000);
        let mut due = false;
        loop {
            due |= send.due(time::millis());
            if due && tx.try_send(&message).is_ok() {
                due = false;
                SENT.fetch_add(1, Ordering::Relaxed);
            }
            while tx.take_completion().is_some() {}
            while rx.receive().is_ok() {
                RECEIVED.fetch_add(1, Ordering::Relaxed);
                twocan_teensy::info!(
                    "loop-back frame {=u32} received",
                    RECEIVED.load(Ordering::Relaxed)
                );
                boot.led.toggle();
            }
            cortex_m::asm::wfi();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("teensy-loopback: {}", twocan_teensy::HOST_NOTE);
}
