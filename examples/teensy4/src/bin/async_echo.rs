//! Async echo on CAN1 of a Teensy 4.0 / 4.1 at 500 kbit/s, on `embassy-executor`
//! (thread-mode executor, no HAL): every frame received is sent back with its identifier
//! plus one (`twocan_app::asynch::echo`, the Teensy 3 example's code path). Pins 22 =
//! CAN1 TX, 23 = CAN1 RX, through a transceiver: `cansend can0 123#01` answers `124#01`.
//! `ECHOED` counts the echoes.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::sync::atomic::{AtomicU32, Ordering};

    use embassy_executor::Executor;
    use static_cell::StaticCell;
    use twocan_app::asynch::{echo, EchoStats};
    use twocan_flexcan::layout::Imxrt1062;
    use twocan_flexcan::pin::{settings_for, Pin22, Pin23};
    use twocan_flexcan::{BeginPlan, Can1};
    use twocan_teensy4::can::{CanRxHalf, CanState, CanTxHalf, TableSlot};
    use twocan_teensy4::configs::{BUS, ECHO_FILTERS};
    use twocan_teensy4::rt::{self, CAN_HALT};

    static CAN1: CanState = CanState::new();
    /// CAN1's filter table (`begin_in` compiles the list straight into it).
    static TABLE1: TableSlot = TableSlot::new_sized();
    static EXECUTOR: StaticCell<Executor> = StaticCell::new();

    /// Echoes sent so far.
    pub static ECHOED: AtomicU32 = AtomicU32::new(0);

    #[embassy_executor::task]
    async fn echo_task(mut tx: CanTxHalf, mut rx: CanRxHalf) {
        let mut stats = EchoStats::default();
        loop {
            let _ = echo(&mut tx, &mut rx, &mut stats).await;
            while tx.take_completion().is_some() {}
            // A read-modify-write: a plain store to a static nothing reads may be dropped.
            ECHOED.fetch_max(stats.echoed, Ordering::Relaxed);
        }
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        let can = Can1::take().unwrap_or_else(|| rt::halt(CAN_HALT));
        let (tx, rx) = CAN1
            .start_in_place(
                can.target(),
                |hw| {
                    can.begin_in_place(
                        hw,
                        &const {
                            BeginPlan::<Imxrt1062>::new_with_layout_or_panic(
                                Can1::TARGET,
                                &settings_for(&BUS, Pin22, Pin23),
                                BUS.configuration,
                            )
                        },
                        &ECHO_FILTERS,
                        &[],
                        TABLE1.take().unwrap_or_else(|| rt::halt(CAN_HALT)),
                    )
                },
                &mut boot.core.NVIC,
            )
            .unwrap_or_else(|_| rt::halt(CAN_HALT));
        EXECUTOR.init(Executor::new()).run(|spawner| {
            spawner.spawn(echo_task(tx, rx).unwrap_or_else(|_| rt::halt(CAN_HALT)));
        })
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("teensy4-async-echo: {}", twocan_teensy4::HOST_NOTE);
}
