//! The portable application (`twocan_app::App`, the same module as the host demo) on
//! FlexCAN0 at 500 kbit/s, as node 1 talking with node 2.
//!
//! Node 2 is any other board running its `app` example with the roles swapped — the
//! STM32F7 `app` example is node 2 — on the same bus, through transceivers (Teensy
//! pins 3 = CAN0 TX, 4 = CAN0 RX; 120 Ω at each end). Without a peer, frames are not
//! acknowledged and the controller goes error passive: the LED then stays still.
//!
//! The application runs every 10 ms; the LED toggles every 50 heartbeats received from
//! the peer. `STATS` mirrors the application's counters for a debugger,
//! `STATE_CHANGES` / `WORST_STATE` the error-state changes the driver reports.
//!
//! Blink codes when it stops: 2–4 clock start-up, 5 FlexCAN `begin`, 6 panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::cell::RefCell;
    use core::sync::atomic::AtomicU32;

    use critical_section::Mutex;
    use twocan_app::firmware::{FirmwareLoop, Published};
    use twocan_app::{App, AppStats};
    use twocan_flexcan::pin::{settings_for, Pin3, Pin4};
    use twocan_flexcan::{BeginPlan, Can0, Settings};
    use twocan_teensy::can::{CanState, TableSlot};
    use twocan_teensy::rt::{self, CAN_BLINKS};
    use twocan_teensy::time::{self, Every};

    static CAN0: CanState = CanState::new();
    /// CAN0's filter table (`begin_in` compiles the list straight into it).
    static TABLE0: TableSlot = TableSlot::new();

    /// The application's counters, copied after each step (`None` before the first).
    pub static STATS: Mutex<RefCell<Option<AppStats>>> = Mutex::new(RefCell::new(None));

    /// Error-state changes the driver reported (`take_state_change`), for a debugger.
    pub static STATE_CHANGES: AtomicU32 = AtomicU32::new(0);
    /// The worst fault-confinement state reported so far: 0 error active, 1 warning,
    /// 2 error passive, 3 bus-off (`ErrorState` in declaration order).
    pub static WORST_STATE: AtomicU32 = AtomicU32::new(0);
    /// The driver's receive FIFO overruns and warnings (`ErrorStatistics`), after each step.
    pub static OVERRUNS: AtomicU32 = AtomicU32::new(0);
    /// See [`OVERRUNS`].
    pub static FIFO_WARNINGS: AtomicU32 = AtomicU32::new(0);

    /// 500 kbit/s, computed at compile time (the bit-timing solver is `const`).
    const SETTINGS: Settings = twocan_teensy::configs::BUS;

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        let (node, peer) = twocan_teensy::configs::APP_NODES;
        twocan_teensy::info!(
            "teensy-app: node {=u8}, peer {=u8}, CAN0 at {=u32} bit/s",
            node,
            peer,
            SETTINGS.actual_bit_rate()
        );
        let mut app = App::new(node, peer);
        let token = Can0::take().unwrap_or_else(|| rt::halt(CAN_BLINKS));
        // The application's portable filter list, as primary filters.
        let (mut tx, mut rx) = CAN0
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
                        &app.filters(),
                        &[],
                        TABLE0.take().unwrap_or_else(|| rt::halt(CAN_BLINKS)),
                    )
                },
                &mut boot.core.NVIC,
            )
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        twocan_teensy::info!(
            "CAN0 on the bus with the application's {=usize} filters",
            app.filters().len()
        );
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
                let step = main_loop.step_split(&mut app, &mut tx, &mut rx, &published, |c| {
                    twocan_teensy::warn!(
                        "CAN0 error state {} (TEC {=u16}, REC {=u16})",
                        c.state,
                        c.counters.tec,
                        c.counters.rec
                    );
                });
                let stats = step.stats;
                if step.log {
                    twocan_teensy::info!(
                        "step {=u32}: sent {=u32}, heartbeats {=u32} (gaps {=u32}, duplicates {=u32}), measurements {=u32}, requests {=u32}, answers {=u32}, queue full {=u32}",
                        step.steps,
                        stats.sent,
                        stats.heartbeats,
                        stats.heartbeat_gaps,
                        stats.heartbeat_duplicates,
                        stats.measurements,
                        stats.requests,
                        stats.answers,
                        stats.tx_full
                    );
                }
                if step.blink {
                    boot.led.toggle();
                }
            }
            cortex_m::asm::wfi();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("teensy-app: {}", twocan_teensy::HOST_NOTE);
}
