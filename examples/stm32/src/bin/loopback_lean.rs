//! `stm32-loopback` with the driver's lean choice (issue 21): the same loop-back on CAN1
//! (the F103's `CAN`; RM0008 §24.5.2 / RM0390 §30.5.2 "Loop back mode": frames are
//! received back internally, no transceiver needed), one pass-all filter bank, one
//! standard data frame (identifier 0x542) every second, the LED toggled by every frame
//! received; `SENT` and `RECEIVED` count them.
//!
//! What differs from `stm32-loopback` is the state's type, `can::LeanState` instead of
//! `CanState` (one line), and what it takes:
//! - fire-and-forget transmit: no completion ring (`DONE` = 0), nothing to take back,
//!   and so no abort of a queued frame (`stm32-loopback`'s withdrawn follower);
//! - no traffic statistics and no time stamps (`twocan_core::Lean`);
//! - the filter planned at compile time (`const_plan!`, as in `stm32-loopback`) and
//!   fixed: the filter map holds exactly the plan's match indices, with no lookup key
//!   and no filter generation per frame;
//! - CAN1's registers at their fixed address (`twocan_bxcan::regs::Can1At`, from the
//!   hand-over's `into_registers_at`: the per-frame code loads no base address).
//!
//! The controller is configured in place in the `static` state (`BxCan::can1_in`), as
//! in `stm32-loopback`.
//!
//! Blink codes when it stops: 5 bxCAN configuration, 6 panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::sync::atomic::{AtomicU32, Ordering};

    use twocan_bxcan::{const_plan, BxCan, FifoPolicy, Instance, PlanOptions};
    use twocan_core::{Filter, Frame};
    use twocan_stm32::board::CAN1_BANKS;
    use twocan_stm32::can::{self, LeanState};
    use twocan_stm32::rt::{self, CAN_BLINKS};
    use twocan_stm32::time::{self, Every};

    /// The filter list: everything, to FIFO 0 of CAN1's banks.
    const FILTERS: [Filter; 1] = [Filter::pass_all()];
    /// Planner options: CAN1's banks, FIFO 0.
    const OPTIONS: PlanOptions = CAN1_BANKS.fifo(FifoPolicy::Fifo0);

    /// The lean state, its filter map sized to the plan (the one line that differs from
    /// `stm32-loopback`'s `CanState`).
    static CAN1: LeanState<{ const_plan!(FILTERS, OPTIONS).match_indices() }> = LeanState::new();
    twocan_stm32::can1_vectors!();

    /// Frames handed to the driver.
    pub static SENT: AtomicU32 = AtomicU32::new(0);
    /// Frames received back.
    pub static RECEIVED: AtomicU32 = AtomicU32::new(0);

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        twocan_stm32::info!("stm32-loopback-lean: CAN1 in loop-back, a frame every second");
        // The hand-over from the board's HAL, as in `stm32-loopback`.
        let can1 = boot.can.can1();
        let config = can1
            .config(125_000)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS))
            .loopback(true);
        // The registers at CAN1's fixed address (`Can1At`, the state's register type):
        // the window the hand-over made from CAN1's singleton, now zero-sized.
        let regs = can1
            .into_registers_at(&config)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        let (mut tx, mut rx) = can::start(
            &CAN1,
            Instance::Can1,
            |slot| {
                BxCan::can1_in(slot, regs, &config, const_plan!(FILTERS, OPTIONS))
                    .map_err(|f| f.error)
            },
            rt::CAN1_IRQS,
            &mut boot.core.NVIC,
        )
        .unwrap_or_else(|| rt::halt(CAN_BLINKS));

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
            while let Ok(frame) = rx.receive() {
                if frame.frame != message {
                    continue;
                }
                RECEIVED.fetch_add(1, Ordering::Relaxed);
                twocan_stm32::info!(
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
    eprintln!("stm32-loopback-lean: {}", twocan_stm32::HOST_NOTE);
}
