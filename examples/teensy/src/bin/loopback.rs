//! ACAN's `LoopBackDemo` (ACAN manual §4) on FlexCAN0: loop-back and self-reception, so
//! it needs no transceiver and no other node. One standard data frame (identifier 0x542)
//! every second; every frame received toggles the LED. `SENT` and `RECEIVED` can be
//! read with a debugger.
//!
//! Blink codes when it stops: 2–4 clock start-up, 5 FlexCAN `begin`, 6 panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::sync::atomic::{AtomicU32, Ordering};

    use twocan_core::{Frame, Mmio};
    use twocan_flexcan::{
        AcanDriver, Can0, FlexCan, Settings, RECEIVE_BUFFER_SIZE, TRANSMIT_BUFFER_SIZE,
    };
    use twocan_teensy::rt::{self, CAN_BLINKS};
    use twocan_teensy::shared::SharedDriver;
    use twocan_teensy::time::{self, Every};

    static CAN0: SharedDriver<FlexCan<Mmio>, RECEIVE_BUFFER_SIZE, TRANSMIT_BUFFER_SIZE> =
        SharedDriver::new();

    /// Frames handed to the driver.
    pub static SENT: AtomicU32 = AtomicU32::new(0);
    /// Frames received back.
    pub static RECEIVED: AtomicU32 = AtomicU32::new(0);

    /// ACAN §4: 125 kbit/s, loop-back and self reception. Computed at compile time
    /// (the bit-timing solver is `const`), so the solver is not in the image.
    const SETTINGS: Settings = {
        let mut s = Settings::new(125_000);
        s.loop_back = true;
        s.self_reception = true;
        s
    };

    #[no_mangle]
    extern "C" fn CAN0_ORED_MESSAGE_BUFFER() {
        CAN0.on_interrupt();
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        let token = Can0::take().unwrap_or_else(|| rt::halt(CAN_BLINKS));
        let can = token
            .begin(&SETTINGS, &[], &[])
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        rt::enable_can_irq(&mut boot.core.NVIC, &can);
        let driver: AcanDriver<Mmio> = AcanDriver::new(can);
        if CAN0.install(driver).is_err() {
            rt::halt(CAN_BLINKS);
        }

        let message = Frame::standard(0x542, &[]).unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        let mut send = Every::new(time::millis(), 1000);
        let mut due = false;
        loop {
            due |= send.due(time::millis());
            if due && CAN0.with(|d| d.try_send(&message).is_ok()) == Some(true) {
                due = false;
                SENT.fetch_add(1, Ordering::Relaxed);
            }
            while let Some(Ok(_frame)) = CAN0.with(|d| d.receive()) {
                RECEIVED.fetch_add(1, Ordering::Relaxed);
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
