//! Async echo on CAN1 at 500 kbit/s, on `embassy-executor` (thread-mode executor,
//! Cortex-M platform, no embassy HAL): every frame received is sent back with its
//! identifier plus one (`twocan_app::asynch::echo`), through `rx.recv().await` and
//! `tx.send().await` of the split driver's halves.
//!
//! The four bxCAN vectors (TX, RX0, RX1, SCE, RM0410 §40.8) run the driver's handlers
//! as in the other examples (`can::start` puts them in place, then unmasks the lines);
//! the handlers wake the waiting task through its waker, and the executor sleeps in
//! `WFE` between wakes. Pins: NUCLEO-F767ZI PD0 = RX, PD1 = TX; 32F746G-DISCO PB8 = RX,
//! PB9 = TX, through a transceiver, 120 Ω at each end. With a USB-CAN adapter on the
//! bus, `cansend can0 123#01` answers `124#01`. Two echo boards on one bus would echo
//! each other forever: pair it with a tester.
//!
//! The LED toggles every 50 echoes; `ECHOED` counts them for a debugger. Blink codes:
//! 5 CAN set-up (no transceiver: `enable` waits for 11 recessive bits, RM0410 §40.4.1),
//! 6 panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::sync::atomic::{AtomicU32, Ordering};

    use embassy_executor::Executor;
    use static_cell::StaticCell;
    use stm32f7xx_hal::pac::interrupt;
    use twocan_app::asynch::{echo, EchoStats};
    use twocan_bxcan::{regs, Can, Config, FifoPolicy, Recovery};
    use twocan_core::{Filter, Mmio};
    use twocan_stm32f7::board::BIT_RATE;
    use twocan_stm32f7::can::{self, CanRxHalf, CanState, CanTxHalf, Vectors};
    use twocan_stm32f7::rt::{self, Led, CAN_BLINKS};

    static CAN1: CanState = CanState::new();
    static CAN1_VECTORS: Vectors = Vectors::new();
    static EXECUTOR: StaticCell<Executor> = StaticCell::new();

    /// Echoes sent so far (for a debugger).
    pub static ECHOED: AtomicU32 = AtomicU32::new(0);

    #[interrupt]
    fn CAN1_TX() {
        CAN1_VECTORS.on_tx();
    }
    #[interrupt]
    fn CAN1_RX0() {
        CAN1_VECTORS.on_rx0();
    }
    #[interrupt]
    fn CAN1_RX1() {
        CAN1_VECTORS.on_rx1();
    }
    #[interrupt]
    fn CAN1_SCE() {
        CAN1_VECTORS.on_sce();
    }

    /// Receives and echoes, forever; drains the completions it does not wait for.
    #[embassy_executor::task]
    async fn echo_task(mut tx: CanTxHalf, mut rx: CanRxHalf, mut led: Led) {
        let mut stats = EchoStats::default();
        loop {
            // A receive error (none on bxCAN today) is counted by the driver; go on.
            let _ = echo(&mut tx, &mut rx, &mut stats).await;
            while tx.take_completion().is_some() {}
            ECHOED.store(stats.echoed, Ordering::Relaxed);
            if stats.echoed.is_multiple_of(50) {
                led.toggle();
            }
        }
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let boot = rt::boot();
        let apb1 = boot.clocks.pclk1().raw();
        let config = Config::from_bitrate(apb1, BIT_RATE)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS))
            .recovery(Recovery::Automatic);
        // SAFETY: `boot` clocked CAN1 and dropped its PAC singleton; this is the only
        // access to CAN1's registers.
        let regs = unsafe { Mmio::new(regs::CAN1_BASE) };
        let mut init = Can::can1(regs, &config).unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        // One FIFO keeps the frames in arrival order.
        let plan = init
            .can()
            .plan(&[Filter::pass_all()], FifoPolicy::Fifo0)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        if init.set_filters(&plan).is_err() {
            rt::halt(CAN_BLINKS);
        }
        let can = init.enable().unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        let (tx, rx) = can::start(&CAN1, &CAN1_VECTORS, can.into_split(), rt::CAN1_IRQS)
            .unwrap_or_else(|| rt::halt(CAN_BLINKS));
        let led = boot.led;
        EXECUTOR.init(Executor::new()).run(|spawner| {
            spawner.spawn(echo_task(tx, rx, led).unwrap_or_else(|_| rt::halt(CAN_BLINKS)));
        })
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("stm32f7-async-echo: {}", twocan_stm32f7::HOST_NOTE);
}
