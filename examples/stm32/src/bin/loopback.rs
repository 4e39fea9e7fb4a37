//! ACAN's `LoopBackDemo` (ACAN manual §4) on bxCAN: CAN1 (the F103's `CAN`) in
//! loop-back mode (RM0008 §24.5.2 / RM0390 §30.5.2 "Loop back mode": frames are
//! received back internally, no transceiver needed), one pass-all filter bank, one
//! standard data frame (identifier 0x542) every second; every frame received toggles the
//! LED. `SENT` and `RECEIVED` can be read with a debugger.
//!
//! Blink codes when it stops: 5 bxCAN configuration, 6 panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::sync::atomic::{AtomicU32, Ordering};

    use twocan_bxcan::{const_plan, BxCan, FifoPolicy, Instance};
    use twocan_core::{Filter, Frame};
    use twocan_stm32::board::CAN1_BANKS;
    use twocan_stm32::can::{self, CanState};
    use twocan_stm32::rt::{self, CAN_BLINKS};
    use twocan_stm32::time::{self, Every};

    static CAN1: CanState = CanState::new();
    twocan_stm32::can1_vectors!();

    /// Frames handed to the driver.
    pub static SENT: AtomicU32 = AtomicU32::new(0);
    /// Frames received back.
    pub static RECEIVED: AtomicU32 = AtomicU32::new(0);
    /// Frames withdrawn: after each frame, a second one (identifier 0x543) is queued
    /// behind it and aborted at once; it must never come back.
    pub static WITHDRAWN: AtomicU32 = AtomicU32::new(0);
    /// Frames received that are not the one sent (a withdrawn frame that went out).
    pub static STRAY: AtomicU32 = AtomicU32::new(0);

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        twocan_stm32::info!("stm32-loopback: CAN1 in loop-back, a frame every second");
        // The hand-over from the board's HAL: CAN1's PAC singleton and pins by value
        // (`twocan_bxcan::hal::f1::can`, `hal::f4::can1`), its clock enabled; the bit
        // timing solved for the APB1 frequency of the HAL's clocks, for the board's part.
        let can1 = boot.can.can1();
        let config = can1
            .config(125_000)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS))
            .loopback(true);
        // The registers for the in-place constructor (nothing configured yet): the
        // controller is configured in place in `CAN1` (`BxCan::can1_in`), so no
        // controller, filter map or plan moves through `main`.
        let regs = can1
            .into_registers(&config)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        // Planned at build time (`const_plan!`): the run-time planner's working memory
        // (about 90 KB) does not fit the F103C8's 20 KiB of RAM.
        let plan = const_plan!([Filter::pass_all()], CAN1_BANKS.fifo(FifoPolicy::Fifo0));
        let (mut tx, mut rx) = can::start(
            &CAN1,
            Instance::Can1,
            |slot| BxCan::can1_in(slot, regs, &config, plan).map_err(|f| f.error),
            rt::CAN1_IRQS,
            &mut boot.core.NVIC,
        )
        .unwrap_or_else(|| rt::halt(CAN_BLINKS));

        let message = Frame::standard(0x542, &[]).unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        let withdrawn = Frame::standard(0x543, &[]).unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        let mut send = Every::new(time::millis(), 1000);
        let mut due = false;
        loop {
            due |= send.due(time::millis());
            if due && tx.try_send(&message).is_ok() {
                due = false;
                SENT.fetch_add(1, Ordering::Relaxed);
                // A second frame waits in another mailbox while the first is on the
                // wire: its abort (RM0410 §40.7.3 "Abort") must take it back.
                if let Ok(token) = tx.try_send(&withdrawn) {
                    if tx.abort(token) != twocan_core::AbortRequest::NotFound {
                        WITHDRAWN.fetch_add(1, Ordering::Relaxed);
                    }
                }
            }
            while tx.take_completion().is_some() {}
            while let Ok(frame) = rx.receive() {
                if frame.frame != message {
                    STRAY.fetch_add(1, Ordering::Relaxed);
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
    eprintln!("stm32-loopback: {}", twocan_stm32::HOST_NOTE);
}
