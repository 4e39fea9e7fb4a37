//! Teensy 3.6 only: FlexCAN0 and FlexCAN1 talking to each other through their
//! transceivers, each running the portable application (`twocan_app::App`): CAN0 is
//! node 1, CAN1 node 2, at 500 kbit/s.
//!
//! Wiring: a transceiver on CAN0 (pins 3 = TX, 4 = RX) and one on CAN1 (pins 33 = TX,
//! 34 = RX), their CANH together and CANL together, 120 Ω at each end of that bus.
//!
//! Both applications run every 10 ms; the LED toggles every 50 heartbeats each node got
//! from the other. `STATS` holds both nodes' counters for a debugger.
//!
//! Blink codes when it stops: 2–4 clock start-up, 5 FlexCAN `begin`, 6 panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::cell::RefCell;

    use critical_section::Mutex;
    use twocan_app::{App, AppStats};
    use twocan_flexcan::pin::{settings_for, Pin3, Pin33, Pin34, Pin4};
    use twocan_flexcan::{BeginPlan, Can0, Can1, Settings};
    use twocan_teensy::can::{CanState, TableSlot};
    use twocan_teensy::rt::{self, CAN_BLINKS};
    use twocan_teensy::time::{self, Every};

    static CAN0: CanState = CanState::new();
    /// CAN0's filter table (`begin_in` compiles the list straight into it).
    static TABLE0: TableSlot = TableSlot::new();
    static CAN1: CanState = CanState::new();
    /// CAN1's filter table (`begin_in` compiles the list straight into it).
    static TABLE1: TableSlot = TableSlot::new();

    /// The counters of node 1 (CAN0) and node 2 (CAN1), copied after each step
    /// (`None` before the first).
    pub static STATS: Mutex<RefCell<Option<[AppStats; 2]>>> = Mutex::new(RefCell::new(None));

    /// 500 kbit/s, computed at compile time (the bit-timing solver is `const`).
    const SETTINGS: Settings = twocan_teensy::configs::BUS;

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        let [(n1, p1), (n2, p2)] = twocan_teensy::configs::CAN0_CAN1_NODES;
        let mut node1 = App::new(n1, p1);
        let mut node2 = App::new(n2, p2);

        let can0 = Can0::take().unwrap_or_else(|| rt::halt(CAN_BLINKS));
        let can1 = Can1::take().unwrap_or_else(|| rt::halt(CAN_BLINKS));
        let nvic = &mut boot.core.NVIC;
        let (mut tx0, mut rx0) = CAN0
            .start_in_place(
                can0.target(),
                |hw| {
                    can0.begin_in_place(
                        hw,
                        &const {
                            BeginPlan::new_or_panic(
                                Can0::TARGET,
                                &settings_for(&SETTINGS, Pin3, Pin4),
                                SETTINGS.configuration,
                            )
                        },
                        &node1.filters(),
                        &[],
                        TABLE0.take().unwrap_or_else(|| rt::halt(CAN_BLINKS)),
                    )
                },
                nvic,
            )
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        let (mut tx1, mut rx1) = CAN1
            .start_in_place(
                can1.target(),
                |hw| {
                    can1.begin_in_place(
                        hw,
                        &const {
                            BeginPlan::new_or_panic(
                                Can1::TARGET,
                                &settings_for(&SETTINGS, Pin33, Pin34),
                                SETTINGS.configuration,
                            )
                        },
                        &node2.filters(),
                        &[],
                        TABLE1.take().unwrap_or_else(|| rt::halt(CAN_BLINKS)),
                    )
                },
                nvic,
            )
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));

        let mut period = Every::new(time::millis(), 10);
        let mut shown = 0;
        loop {
            if period.due(time::millis()) {
                node1.handle(&mut rx0);
                node1.publish(&mut tx0);
                node2.handle(&mut rx1);
                node2.publish(&mut tx1);
                while tx0.take_completion().is_some() {}
                while tx1.take_completion().is_some() {}
                let stats = [node1.stats(), node2.stats()];
                critical_section::with(|cs| *STATS.borrow_ref_mut(cs) = Some(stats));
                let both = stats[0].heartbeats.min(stats[1].heartbeats);
                if both >= shown + 50 {
                    shown = both;
                    boot.led.toggle();
                }
            }
            cortex_m::asm::wfi();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("teensy-can0-can1: {}", twocan_teensy::HOST_NOTE);
}
