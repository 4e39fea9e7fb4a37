//! `teensy4-loopback` with the driver's lean choice (issue 21): the same loop-back on
//! CAN1 of a Teensy 4.0 / 4.1 (ACAN manual §4: loop-back and self reception, no
//! transceiver needed), one standard data frame (identifier 0x542) every second; `SENT`
//! and `RECEIVED` count them, `rt::HALT` says why it stopped, if it did.
//!
//! What differs from `teensy4-loopback` (and from `teensy-loopback-lean`, the Teensy 3
//! one) is the state's type, `can::LeanState` instead of the one call's `CanState` (one
//! line), and the configuration it takes (the token's planned begin instead of the one
//! call):
//! - fire-and-forget transmit: no completion ring (`DONE` = 0), nothing to take back;
//! - no traffic statistics and no time stamps (`twocan_core::Lean`);
//! - the filter list planned at compile time for the RT1062 layout
//!   (`const_plan_large!`) and read from flash, the settings checked at compile time
//!   (a `const` `BeginPlan<Imxrt1062>`): the token's `begin_planned_in_place` writes
//!   the controller straight into the `static` state, and no check, planner or table
//!   compiler links into the image.
//! - CAN1's registers at their fixed address (`twocan_flexcan::imxrt::Can1At`, the
//!   state's register type, from the consumed token: the per-frame code loads no base).
//!
//! The layout is the RT1062's (the ERR005829 workaround), as in `teensy4-loopback`.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::sync::atomic::{AtomicU32, Ordering};

    use twocan_core::Frame;
    use twocan_flexcan::layout::Imxrt1062;
    use twocan_flexcan::pin::{settings_for, Pin22, Pin23};
    use twocan_flexcan::planner::PlanOptions;
    use twocan_flexcan::{const_plan_large, BeginPlan, Can1, Settings};
    use twocan_teensy4::can::LeanState;
    use twocan_teensy4::configs::{LOOPBACK, LOOPBACK_FILTERS};
    use twocan_teensy4::rt::{self, CAN_HALT};
    use twocan_teensy4::time::{self, Every};

    /// The lean state (the one line that differs from `teensy4-loopback`'s `CanState`).
    static CAN1: LeanState = LeanState::new();

    /// Frames handed to the driver.
    pub static SENT: AtomicU32 = AtomicU32::new(0);
    /// Frames received back.
    pub static RECEIVED: AtomicU32 = AtomicU32::new(0);

    /// ACAN §4: 125 kbit/s, loop-back and self reception, on CAN1's default pins (22
    /// and 23).
    const SETTINGS: Settings = settings_for(&LOOPBACK, Pin22, Pin23);
    /// The settings checked at compile time for CAN1 in the RT1062 layout: settings
    /// `begin` would refuse do not build.
    const CHECKED: BeginPlan<Imxrt1062> =
        BeginPlan::new_with_layout_or_panic(Can1::TARGET, &SETTINGS, SETTINGS.configuration);

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        twocan_teensy4::info!("teensy4-loopback-lean: CAN1 in loop-back, a frame every second");
        let token = Can1::take().unwrap_or_else(|| rt::halt(CAN_HALT));
        // The pass-all filter planned at compile time, for the settings' partition.
        let table =
            const_plan_large!(LOOPBACK_FILTERS, PlanOptions::new(SETTINGS.configuration)).planned();
        let (mut tx, mut rx) = CAN1
            .start_in_place(
                Can1::TARGET,
                |hw| token.begin_planned_in_place(hw, &CHECKED, table),
                &mut boot.core.NVIC,
            )
            .unwrap_or_else(|_| rt::halt(CAN_HALT));

        let message = Frame::standard(0x542, &[]).unwrap_or_else(|_| rt::halt(CAN_HALT));
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
    eprintln!("teensy4-loopback-lean: {}", twocan_teensy4::HOST_NOTE);
}
