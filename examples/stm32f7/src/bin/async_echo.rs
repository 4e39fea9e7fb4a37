//! Async echo on CAN1 at 500 kbit/s, on `embassy-executor` (thread-mode executor,
//! Cortex-M platform, no embassy HAL): every frame received is sent back with its
//! identifier plus one (`twocan_app::asynch::echo`), through `rx.recv().await` and
//! `tx.send().await` of the split driver's halves.
//!
//! The library's four bxCAN entry points (TX, RX0, RX1, SCE, RM0410 §40.8) run the
//! driver's handlers as in the other examples (`can::start` puts them in place, then
//! unmasks the lines);
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
    use twocan_app::asynch::{echo, EchoStats};
    use twocan_bxcan::{const_plan, hal, BxCan, Instance, PlanOptions, Recovery};
    use twocan_core::Filter;
    use twocan_stm32f7::board::BIT_RATE;
    use twocan_stm32f7::can::{self, CanRxHalf, CanState, CanTxHalf};
    use twocan_stm32f7::rt::{self, Led, CAN_BLINKS};

    static CAN1: CanState = CanState::new();
    static EXECUTOR: StaticCell<Executor> = StaticCell::new();

    /// Echoes sent so far (for a debugger). `#[used]`: only ever stored to, the
    /// optimiser would otherwise drop it (and the debugger's symbol with it).
    #[used]
    pub static ECHOED: AtomicU32 = AtomicU32::new(0);

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
        let mut boot = rt::boot();
        // The hand-over: CAN1's singleton and pins (AF9), CAN1 clocked through APB1; the
        // bit timing is solved for the APB1 frequency of the HAL's clocks.
        let (tx_pin, rx_pin) = boot.can1_pins;
        let can1 = hal::can1(boot.can1, tx_pin, rx_pin, &mut boot.apb1, &boot.clocks);
        let config = can1
            .config(BIT_RATE)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS))
            .recovery(Recovery::Automatic);
        // The HAL's hand-over gives the registers (nothing configured yet); the controller is then
        // configured in place in `CAN1` with a plan computed at compile time. One FIFO
        // keeps the frames in arrival order.
        let regs = can1
            .into_registers(&config)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        let plan = const_plan!([Filter::pass_all()], PlanOptions::new(14));
        let (tx, rx) = can::start(
            &CAN1,
            Instance::Can1,
            |slot| BxCan::can1_in(slot, regs, &config, plan).map_err(|f| f.error),
            &mut boot.core.NVIC,
        )
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
