//! ACAN's `LoopBackDemo` (ACAN manual §4) on CAN1 of a Teensy 4.0 / 4.1: loop-back and
//! self reception, so it needs no transceiver and no other node. One standard data frame
//! (identifier 0x542) every second. `SENT` and `RECEIVED` count them for a debugger or
//! `can-fil`; `rt::HALT` says why it stopped, if it did.
//!
//! Started with the one call of `twocan_flexcan::acan` (ACAN_T4's `begin`): token, begin
//! on CAN1's default pins (22 and 23) in the RT1062 layout (the ERR005829 workaround),
//! the library's `static` state, the `CAN1` line wired.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::sync::atomic::{AtomicU32, Ordering};

    use twocan_core::Frame;
    use twocan_flexcan::layout::Imxrt1062;
    use twocan_flexcan::{acan, BeginPlan, Can1};
    use twocan_teensy4::configs::{LOOPBACK, LOOPBACK_FILTERS};
    use twocan_teensy4::rt::{self, CAN_HALT};
    use twocan_teensy4::time::{self, Every};

    /// Frames handed to the driver.
    pub static SENT: AtomicU32 = AtomicU32::new(0);
    /// Frames received back.
    pub static RECEIVED: AtomicU32 = AtomicU32::new(0);

    /// The settings checked at compile time for CAN1 in the RT1062 layout, the one
    /// call's (`can1_checked`: no check runs on the board, and the configuration stays
    /// within a few hundred bytes of stack).
    const CHECKED: BeginPlan<Imxrt1062> =
        BeginPlan::new_with_layout_or_panic(Can1::TARGET, &LOOPBACK, LOOPBACK.configuration);

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        twocan_teensy4::info!("teensy4-loopback: CAN1 in loop-back, a frame every second");
        let (mut tx, mut rx) =
            acan::can1_checked(&CHECKED, &LOOPBACK_FILTERS, &[], &mut boot.core.NVIC)
                .unwrap_or_else(|_| rt::halt(CAN_HALT));
        let message = Frame::standard(0x542, &[]).unwrap_or_else(|_| rt::halt(CAN_HALT));
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
                twocan_teensy4::info!(
                    "loop-back frame {=u32} received",
                    RECEIVED.load(Ordering::Relaxed)
                );
            }
            cortex_m::asm::wfi();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("teensy4-loopback: {}", twocan_teensy4::HOST_NOTE);
}
