//! `teensy-loopback` with the driver's lean choice (issue 21): the same loop-back on
//! FlexCAN0 (ACAN manual §4: loop-back and self reception, no transceiver needed), one
//! standard data frame (identifier 0x542) every second, the LED toggled by every frame
//! received; `SENT` and `RECEIVED` count them.
//!
//! What differs from `teensy-loopback` is the state's type, `can::LeanState` instead of
//! `CanState` (one line), and the configuration it takes (the token's planned begin
//! instead of the one call `acan::can0_checked`, about ten lines):
//! - fire-and-forget transmit: no completion ring (`DONE` = 0), nothing to take back;
//! - no traffic statistics and no time stamps (`twocan_core::Lean`);
//! - the filter list planned at compile time (`const_plan!`) and read from flash, the
//!   settings checked at compile time (a `const` `BeginPlan`): the token's
//!   `begin_planned_in_place` writes the controller straight into the `static` state,
//!   and no check, planner or table compiler links into the image.
//! - FlexCAN0's registers at their fixed address (`twocan_flexcan::regs::Can0At`, the
//!   state's register type, from the consumed token: the per-frame code loads no base).
//!
//! Blink codes when it stops: 2–4 clock start-up, 5 FlexCAN `begin`, 6 panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::sync::atomic::{AtomicU32, Ordering};

    use twocan_core::Frame;
    use twocan_flexcan::pin::{settings_for, Pin3, Pin4};
    use twocan_flexcan::planner::PlanOptions;
    use twocan_flexcan::{const_plan, BeginPlan, Can0, Settings};
    use twocan_teensy::can::LeanState;
    use twocan_teensy::configs::{LOOPBACK, LOOPBACK_FILTERS};
    use twocan_teensy::rt::{self, CAN_BLINKS};
    use twocan_teensy::time::{self, Every};

    /// The lean state (the one line that differs from `teensy-loopback`'s `CanState`).
    static CAN0: LeanState = LeanState::new();

    /// Frames handed to the driver.
    pub static SENT: AtomicU32 = AtomicU32::new(0);
    /// Frames received back.
    pub static RECEIVED: AtomicU32 = AtomicU32::new(0);

    /// ACAN §4: 125 kbit/s, loop-back and self reception, on pins 3 and 4.
    const SETTINGS: Settings = settings_for(&LOOPBACK, Pin3, Pin4);
    /// The settings checked at compile time for FlexCAN0: settings `begin` would refuse
    /// do not build.
    const CHECKED: BeginPlan =
        BeginPlan::new_or_panic(Can0::TARGET, &SETTINGS, SETTINGS.configuration);

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        twocan_teensy::info!("teensy-loopback-lean: CAN0 in loop-back, a frame every second");
        let token = Can0::take().unwrap_or_else(|| rt::halt(CAN_BLINKS));
        // The pass-all filter planned at compile time, for the settings' partition.
        let table =
            const_plan!(LOOPBACK_FILTERS, PlanOptions::new(SETTINGS.configuration)).planned();
        let (mut tx, mut rx) = CAN0
            .start_in_place(
                Can0::TARGET,
                |hw| token.begin_planned_in_place(hw, &CHECKED, table),
                &mut boot.core.NVIC,
            )
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));

        let message = Frame::standard(0x542, &[]).unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        let mut send = Every::new(time::millis(), 1000);
        let mut due = false;
        loop {
            due |= send.due(time::millis());
            // Fire and forget: accepted means queued; no completion comes back.
            if due && tx.try_send(&message).is_ok() {
                due = false;
                SENT.fetch_add(1, Ordering::Relaxed);
            }
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
    eprintln!("teensy-loopback-lean: {}", twocan_teensy::HOST_NOTE);
}
