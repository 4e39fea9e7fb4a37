//! The portable application (`twocan_app::App`, the same module as the host demo) on
//! CAN1 at 500 kbit/s, as node 2 talking with node 1 — the Teensy `app` example is
//! node 1 — over a bus with transceivers (NUCLEO-F767ZI: CAN1 on PD0 = RX, PD1 = TX;
//! 32F746G-DISCO: PB8 = RX (Arduino D15), PB9 = TX (D14); 120 Ω at each end).
//!
//! The application's portable filters are compiled by the bxCAN planner into FIFO 0
//! (one FIFO keeps the frames in arrival order). It runs every 10 ms; the LED toggles
//! every 50 heartbeats from the peer. `STATS` mirrors the counters for a debugger,
//! `STATE_CHANGES` / `WORST_STATE` the error-state changes the driver reports.
//!
//! Without a transceiver (or with CANRX not recessive) `enable` times out waiting for 11
//! recessive bits (RM0410 §40.4.1): blink code 5. 6: panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::cell::RefCell;
    use core::sync::atomic::AtomicU32;

    use critical_section::Mutex;
    use twocan_app::firmware::{FirmwareLoop, Published};
    use twocan_app::{App, AppStats};
    use twocan_bxcan::{hal, planner, BxCan, FifoPolicy, Instance, Recovery};
    use twocan_stm32f7::board::BIT_RATE;
    use twocan_stm32f7::can::{self, CanState};
    use twocan_stm32f7::rt::{self, CAN_BLINKS};
    use twocan_stm32f7::time::{self, Every};

    /// This node and its peer.
    const NODE: u8 = 2;
    const PEER: u8 = 1;

    static CAN1: CanState = CanState::new();

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

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        twocan_stm32f7::info!(
            "stm32f7-app: node {=u8}, peer {=u8}, CAN1 at {=u32} bit/s",
            NODE,
            PEER,
            BIT_RATE
        );
        let mut app = App::new(NODE, PEER);
        // The hand-over: CAN1's singleton and pins (AF9), CAN1 clocked through APB1; the
        // bit timing is solved for the APB1 frequency of the HAL's clocks.
        let (tx_pin, rx_pin) = boot.can1_pins;
        let can1 = hal::can1(boot.can1, tx_pin, rx_pin, &mut boot.apb1, &boot.clocks);
        let config = can1
            .config(BIT_RATE)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS))
            .recovery(Recovery::Automatic);
        // The HAL's hand-over gives the registers (and the bank count for
        // the planner); the application's list is planned at run time into the
        // planner's `static` working memory, and the controller configured in place in
        // `CAN1`.
        let options = can1.plan_options(&config, FifoPolicy::Fifo0);
        let regs = can1
            .into_registers(&config)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        let scratch = can::PLANNER.take().unwrap_or_else(|| rt::halt(CAN_BLINKS));
        let plan = planner::plan_in(&app.filters(), options, scratch)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        let (mut tx, mut rx) = can::start(
            &CAN1,
            Instance::Can1,
            |slot| BxCan::can1_in(slot, regs, &config, plan).map_err(|f| f.error),
            &mut boot.core.NVIC,
        )
        .unwrap_or_else(|| rt::halt(CAN_BLINKS));
        twocan_stm32f7::info!(
            "CAN1 on the bus with the application's {=usize} filters",
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
                    twocan_stm32f7::warn!(
                        "CAN1 error state {} (TEC {=u16}, REC {=u16})",
                        c.state,
                        c.counters.tec,
                        c.counters.rec
                    );
                });
                let stats = step.stats;
                if step.log {
                    twocan_stm32f7::info!(
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
    eprintln!("stm32f7-app: {}", twocan_stm32f7::HOST_NOTE);
}
