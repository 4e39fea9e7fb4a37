//! The portable application (`twocan_app::App`, the same module as the host demo and the
//! Teensy 3 / STM32F7 `app` examples) on CAN1 of a Teensy 4.0 / 4.1 at 500 kbit/s, as
//! node 1 talking with node 2 (pins 22 = CAN1 TX, 23 = CAN1 RX, through a transceiver).
//! The application runs every 10 ms; `STATS` mirrors its counters, `STATE_CHANGES` /
//! `WORST_STATE` the error-state changes the driver reports.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::cell::RefCell;
    use core::sync::atomic::AtomicU32;

    use critical_section::Mutex;
    use twocan_app::firmware::{FirmwareLoop, Published};
    use twocan_app::{App, AppStats};
    use twocan_flexcan::layout::Imxrt1062;
    use twocan_flexcan::pin::{settings_for, Pin22, Pin23};
    use twocan_flexcan::{BeginPlan, Can1};
    use twocan_teensy4::can::{CanState, TableSlot};
    use twocan_teensy4::configs::{APP_NODES, BUS};
    use twocan_teensy4::rt::{self, CAN_HALT};
    use twocan_teensy4::time::{self, Every};

    static CAN1: CanState = CanState::new();
    /// CAN1's filter table (`begin_in` compiles the list straight into it).
    static TABLE1: TableSlot = TableSlot::new_sized();

    /// The application's counters, copied after each step (`None` before the first).
    pub static STATS: Mutex<RefCell<Option<AppStats>>> = Mutex::new(RefCell::new(None));
    /// Error-state changes the driver reported.
    pub static STATE_CHANGES: AtomicU32 = AtomicU32::new(0);
    /// The worst fault-confinement state reported so far (`ErrorState` order).
    pub static WORST_STATE: AtomicU32 = AtomicU32::new(0);
    /// The driver's receive FIFO overruns and warnings (`ErrorStatistics`), after each step.
    pub static OVERRUNS: AtomicU32 = AtomicU32::new(0);
    /// See [`OVERRUNS`].
    pub static FIFO_WARNINGS: AtomicU32 = AtomicU32::new(0);

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        let (node, peer) = APP_NODES;
        twocan_teensy4::info!(
            "teensy4-app: node {=u8}, peer {=u8}, CAN1 at {=u32} bit/s",
            node,
            peer,
            BUS.actual_bit_rate()
        );
        let mut app = App::new(node, peer);
        let can = Can1::take().unwrap_or_else(|| rt::halt(CAN_HALT));
        let (mut tx, mut rx) = CAN1
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
                        &app.filters(),
                        &[],
                        TABLE1.take().unwrap_or_else(|| rt::halt(CAN_HALT)),
                    )
                },
                &mut boot.core.NVIC,
            )
            .unwrap_or_else(|_| rt::halt(CAN_HALT));
        let published = Published {
            stats: &STATS,
            state_changes: &STATE_CHANGES,
            worst_state: &WORST_STATE,
            overruns: &OVERRUNS,
            fifo_warnings: &FIFO_WARNINGS,
        };
        let mut main_loop = FirmwareLoop::new();
        let mut period = Every::new(time::millis(), 10);
        loop {
            if period.due(time::millis()) {
                main_loop.step_split(&mut app, &mut tx, &mut rx, &published, |c| {
                    twocan_teensy4::warn!(
                        "CAN1 error state {} (TEC {=u16}, REC {=u16})",
                        c.state,
                        c.counters.tec,
                        c.counters.rec
                    );
                });
            }
            cortex_m::asm::wfi();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("teensy4-app: {}", twocan_teensy4::HOST_NOTE);
}
