//! Two FlexCAN modules of one Teensy 4.0 / 4.1 on one bus: CAN1 (pins 22/23) runs node 1
//! of the portable application, CAN2 (pins 1/0) node 2, both at 500 kbit/s from the one
//! CAN clock root. Wire both transceivers to the same bus (120 Ω at each end). `STATS`
//! holds both nodes' counters.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::cell::RefCell;

    use critical_section::Mutex;
    use twocan_app::{App, AppStats};
    use twocan_flexcan::layout::Imxrt1062;
    use twocan_flexcan::pin::{settings_for, Pin0, Pin1, Pin22, Pin23};
    use twocan_flexcan::{BeginPlan, Can1, Can2};
    use twocan_teensy4::can::{CanState, TableSlot};
    use twocan_teensy4::configs::{BUS, CAN1_CAN2_NODES};
    use twocan_teensy4::rt::{self, CAN_HALT};
    use twocan_teensy4::time::{self, Every};

    static CAN1: CanState = CanState::new();
    /// CAN1's filter table (`begin_in` compiles the list straight into it).
    static TABLE1: TableSlot = TableSlot::new_sized();
    static CAN2: CanState = CanState::new();
    /// CAN2's filter table (`begin_in` compiles the list straight into it).
    static TABLE2: TableSlot = TableSlot::new_sized();

    /// The counters of node 1 (CAN1) and node 2 (CAN2), copied after each step.
    pub static STATS: Mutex<RefCell<Option<[AppStats; 2]>>> = Mutex::new(RefCell::new(None));

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        let [(n1, p1), (n2, p2)] = CAN1_CAN2_NODES;
        let mut node1 = App::new(n1, p1);
        let mut node2 = App::new(n2, p2);
        let can1 = Can1::take().unwrap_or_else(|| rt::halt(CAN_HALT));
        let can2 = Can2::take().unwrap_or_else(|| rt::halt(CAN_HALT));
        let nvic = &mut boot.core.NVIC;
        let (mut tx1, mut rx1) = CAN1
            .start_in_place(
                can1.target(),
                |hw| {
                    can1.begin_in_place(
                        hw,
                        &const {
                            BeginPlan::<Imxrt1062>::new_with_layout_or_panic(
                                Can1::TARGET,
                                &settings_for(&BUS, Pin22, Pin23),
                                BUS.configuration,
                            )
                        },
                        &node1.filters(),
                        &[],
                        TABLE1.take().unwrap_or_else(|| rt::halt(CAN_HALT)),
                    )
                },
                nvic,
            )
            .unwrap_or_else(|_| rt::halt(CAN_HALT));
        let (mut tx2, mut rx2) = CAN2
            .start_in_place(
                can2.target(),
                |hw| {
                    can2.begin_in_place(
                        hw,
                        &const {
                            BeginPlan::<Imxrt1062>::new_with_layout_or_panic(
                                Can2::TARGET,
                                &settings_for(&BUS, Pin1, Pin0),
                                BUS.configuration,
                            )
                        },
                        &node2.filters(),
                        &[],
                        TABLE2.take().unwrap_or_else(|| rt::halt(CAN_HALT)),
                    )
                },
                nvic,
            )
            .unwrap_or_else(|_| rt::halt(CAN_HALT));
        let mut period = Every::new(time::millis(), 10);
        loop {
            if period.due(time::millis()) {
                node1.handle(&mut rx1);
                node1.publish(&mut tx1);
                node2.handle(&mut rx2);
                node2.publish(&mut tx2);
                while tx1.take_completion().is_some() {}
                while tx2.take_completion().is_some() {}
                let stats = [node1.stats(), node2.stats()];
                critical_section::with(|cs| *STATS.borrow_ref_mut(cs) = Some(stats));
            }
            cortex_m::asm::wfi();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("teensy4-can1-can2: {}", twocan_teensy4::HOST_NOTE);
}
