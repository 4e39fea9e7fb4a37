//! Async echo on CAN1 at 500 kbit/s, on `embassy-executor` (thread-mode executor,
//! Cortex-M platform, no embassy HAL): every frame received is sent back with its
//! identifier plus one (`twocan_app::asynch::echo`), through `rx.recv().await` and
//! `tx.send().await` of the split driver's halves.
//!
//! The four bxCAN vectors (TX, RX0, RX1, SCE; RM0008 §24.8, RM0390 §30.8) run the driver's handlers
//! as in the other examples (`can::start` puts them in place, then unmasks the lines);
//! the handlers wake the waiting task through its waker, and the executor sleeps in
//! `WFE` between wakes. Pins: Blue Pill PB8 = RX, PB9 = TX; NUCLEO-F446RE PA11 = RX,
//! PA12 = TX, through a transceiver, 120 Ω at each end. With a USB-CAN adapter on the
//! bus, `cansend can0 123#01` answers `124#01`. Two echo boards on one bus would echo
//! each other forever: pair it with a tester.
//!
//! The LED toggles every 50 echoes; `ECHOED` counts them for a debugger. Blink codes:
//! 5 CAN set-up (no transceiver: `enable` waits for 11 recessive bits, RM0008 §24.4.1, RM0390 §30.4.1),
//! 6 panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::sync::atomic::{AtomicU32, Ordering};

    use embassy_executor::Executor;
    use static_cell::StaticCell;
    use twocan_app::asynch::{echo, EchoStats};
    use twocan_bxcan::{const_plan, BxCan, FifoPolicy, Instance, Recovery};
    use twocan_core::Filter;
    use twocan_stm32::board::BIT_RATE;
    use twocan_stm32::board::CAN1_BANKS;
    use twocan_stm32::can::{self, CanRxHalf, CanState, CanTxHalf};
    use twocan_stm32::rt::{self, Led, CAN_BLINKS};

    static CAN1: CanState = CanState::new();
    twocan_stm32::can1_vectors!();
    static EXECUTOR: StaticCell<Executor> = StaticCell::new();

    /// Echoes sent so far (for a debugger).
    // `#[used]`: only stored to here, it must stay in the image for a debugger (and
    // can-fil) to read.
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
        // The hand-over from the board's HAL: CAN1's PAC singleton and pins by value
        // (`twocan_bxcan::hal::f1::can`, `hal::f4::can1`), its clock enabled; the bit
        // timing solved for the APB1 frequency of the HAL's clocks, for the board's part.
        let can1 = boot.can.can1();
        let config = can1
            .config(BIT_RATE)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS))
            .recovery(Recovery::Automatic);
        // The registers for the in-place constructor (nothing configured yet): the
        // controller is configured in place in `CAN1` (`BxCan::can1_in`), so no
        // controller, filter map or plan moves through `main`.
        let regs = can1
            .into_registers(&config)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        // One FIFO keeps the frames in arrival order.
        // Planned at build time (`const_plan!`, see `stm32-loopback`).
        let plan = const_plan!([Filter::pass_all()], CAN1_BANKS.fifo(FifoPolicy::Fifo0));
        let (tx, rx) = can::start(
            &CAN1,
            Instance::Can1,
            |slot| BxCan::can1_in(slot, regs, &config, plan).map_err(|f| f.error),
            rt::CAN1_IRQS,
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
    eprintln!("stm32-async-echo: {}", twocan_stm32::HOST_NOTE);
}
