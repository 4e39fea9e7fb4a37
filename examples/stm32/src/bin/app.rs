//! The portable application (`twocan_app::App`, the same module as the host demo) on
//! CAN1 at 500 kbit/s: the NUCLEO-F446RE as node 2 talking with node 1 — the Teensy
//! `app` example is node 1 — and the Blue Pill as node 3 talking with node 2 (the three
//! on one bus, `Board::app`), over a bus with transceivers (Blue Pill: CAN on PB8 = RX, PB9 = TX;
//! NUCLEO-F446RE: CAN1 on PA11 = RX, PA12 = TX; 120 Ω at each end).
//!
//! The application's portable filters are compiled by the bxCAN planner into FIFO 0
//! (one FIFO keeps the frames in arrival order). It runs every 10 ms; the LED toggles
//! every 50 heartbeats from the peer. `STATS` mirrors the counters for a debugger,
//! `STATE_CHANGES` / `WORST_STATE` the error-state changes the driver reports.
//!
//! Without a transceiver (or with CANRX not recessive) `enable` times out waiting for 11
//! recessive bits (RM0008 §24.4.1, RM0390 §30.4.1): blink code 5. 6: panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::cell::RefCell;
    use core::sync::atomic::AtomicU32;

    use critical_section::Mutex;
    use twocan_app::firmware::{FirmwareLoop, Published};
    use twocan_app::{App, AppStats};
    use twocan_bxcan::{const_plan, BxCan, FifoPolicy, Instance, Recovery};
    use twocan_stm32::board::BIT_RATE;
    use twocan_stm32::board::CAN1_BANKS;
    use twocan_stm32::can::{self, CanRxHalf, CanState, CanTxHalf};
    use twocan_stm32::rt::{self, CAN_BLINKS};
    use twocan_stm32::time::{self, Every};
    use twocan_stm32::BOARD;

    /// This node and its peer (per board: `Board::app`).
    const NODE: u8 = BOARD.app.0;
    const PEER: u8 = BOARD.app.1;

    static CAN1: CanState = CanState::new();
    twocan_stm32::can1_vectors!();

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
        twocan_stm32::info!(
            "stm32-app: node {=u8}, peer {=u8}, CAN1 at {=u32} bit/s",
            NODE,
            PEER,
            BIT_RATE
        );
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
        // The application's filters (`twocan_app::filters_for`, the list `app.filters()`
        // returns) planned at build time (`const_plan!`, see `stm32-loopback`).
        let plan = const_plan!(
            twocan_app::filters_for(NODE, PEER),
            CAN1_BANKS.fifo(FifoPolicy::Fifo0)
        );
        let (tx, rx) = can::start(
            &CAN1,
            Instance::Can1,
            |slot| BxCan::can1_in(slot, regs, &config, plan).map_err(|f| f.error),
            rt::CAN1_IRQS,
            &mut boot.core.NVIC,
        )
        .unwrap_or_else(|| rt::halt(CAN_BLINKS));
        run(tx, rx, boot.led)
    }

    /// The application after the configuration, in a function of its own (not
    /// inlined): its state (the node, the loop, their call-backs' frames) takes stack
    /// only once the configuration is done.
    #[inline(never)]
    fn run(mut tx: CanTxHalf, mut rx: CanRxHalf, mut led: rt::Led) -> ! {
        let mut app = App::new(NODE, PEER);
        twocan_stm32::info!(
            "CAN1 on the bus with the application's {=usize} filters",
            twocan_app::FILTER_COUNT
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
                    twocan_stm32::warn!(
                        "CAN1 error state {} (TEC {=u16}, REC {=u16})",
                        c.state,
                        c.counters.tec,
                        c.counters.rec
                    );
                });
                let stats = step.stats;
                if step.log {
                    twocan_stm32::info!(
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
                    led.toggle();
                }
            }
            cortex_m::asm::wfi();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("stm32-app: {}", twocan_stm32::HOST_NOTE);
}
