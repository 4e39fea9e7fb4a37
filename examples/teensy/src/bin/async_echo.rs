//! Async echo on FlexCAN0 at 500 kbit/s, on `embassy-executor` (thread-mode executor,
//! Cortex-M platform, no HAL): every frame received is sent back with its identifier
//! plus one (`twocan_app::asynch::echo`), through `rx.recv().await` and
//! `tx.send().await` of the split driver's halves.
//!
//! The FlexCAN vectors run the driver's interrupt handlers as in the other examples
//! (`CAN0.start`, `twocan_flexcan::rt`, puts them in place, then unmasks the lines); the handlers wake the
//! waiting task through its waker, and the executor sleeps in `WFE` between wakes.
//! Try it with a USB-CAN adapter on the bus (Teensy pins 3 = CAN0 TX, 4 = CAN0 RX,
//! through a transceiver, 120 Ω at each end): `cansend can0 123#01` answers `124#01`.
//! Two echo boards on one bus would echo each other forever: pair it with a tester.
//!
//! The LED toggles every 50 echoes; `ECHOED` counts them for a debugger.
//! Blink codes when it stops: 2–4 clock start-up, 5 FlexCAN `begin`, 6 panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::sync::atomic::{AtomicU32, Ordering};

    use embassy_executor::Executor;
    use static_cell::StaticCell;
    use twocan_app::asynch::{echo, EchoStats};
    use twocan_flexcan::pin::{settings_for, Pin3, Pin4};
    use twocan_flexcan::{BeginPlan, Can0, Settings};
    use twocan_teensy::can::{CanRxHalf, CanState, CanTxHalf, TableSlot};
    use twocan_teensy::io::Mmio;
    use twocan_teensy::led::Led;
    use twocan_teensy::rt::{self, CAN_BLINKS};

    static CAN0: CanState = CanState::new();
    /// CAN0's filter table (`begin_in` compiles the list straight into it).
    static TABLE0: TableSlot = TableSlot::new();
    static EXECUTOR: StaticCell<Executor> = StaticCell::new();

    /// Echoes sent so far (for a debugger). `#[used]`: only ever stored to, the
    /// optimiser would otherwise drop it (and the debugger's symbol with it).
    #[used]
    pub static ECHOED: AtomicU32 = AtomicU32::new(0);

    const SETTINGS: Settings = twocan_teensy::configs::BUS;

    /// Receives and echoes, forever; drains the completions it does not wait for.
    #[embassy_executor::task]
    async fn echo_task(mut tx: CanTxHalf, mut rx: CanRxHalf, mut led: Led<Mmio>) {
        let mut stats = EchoStats::default();
        loop {
            // A receive error (none on FlexCAN today) is counted by the driver; go on.
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
        let token = Can0::take().unwrap_or_else(|| rt::halt(CAN_BLINKS));
        let (tx, rx) = CAN0
            .start_in_place(
                token.target(),
                |hw| {
                    token.begin_in_place(
                        hw,
                        &const {
                            BeginPlan::new_or_panic(
                                Can0::TARGET,
                                &settings_for(&SETTINGS, Pin3, Pin4),
                                SETTINGS.configuration,
                            )
                        },
                        &twocan_teensy::configs::ECHO_FILTERS,
                        &[],
                        TABLE0.take().unwrap_or_else(|| rt::halt(CAN_BLINKS)),
                    )
                },
                &mut boot.core.NVIC,
            )
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        let led = boot.led;
        EXECUTOR.init(Executor::new()).run(|spawner| {
            spawner.spawn(echo_task(tx, rx, led).unwrap_or_else(|_| rt::halt(CAN_BLINKS)));
        })
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("teensy-async-echo: {}", twocan_teensy::HOST_NOTE);
}
