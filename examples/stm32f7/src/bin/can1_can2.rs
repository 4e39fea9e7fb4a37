//! NUCLEO-F767ZI only: CAN1 and CAN2 talking to each other through their transceivers,
//! each running the portable application (`twocan_app::App`): CAN1 is node 1, CAN2
//! node 2, at 500 kbit/s.
//!
//! Wiring: a transceiver on CAN1 (PD0 = RX, PD1 = TX) and one on CAN2 (PB5 = RX,
//! PB6 = TX), CANH to CANH and CANL to CANL, 120 Ω at each end.
//!
//! CAN2 has no filter banks of its own (RM0410 §40.3 "dual CAN"): CAN1 is configured
//! with `CAN2SB = 14` (banks 0–13 for CAN1, 14–27 for CAN2), and CAN2's filters are
//! written through CAN1's register block. Each node's portable filter list is planned
//! for its own banks; the match indices come back as each node's own filter indices.
//!
//! The LED toggles every 50 heartbeats each node got from the other; `STATS` holds both
//! nodes' counters. Blink codes: 5 bxCAN configuration (or no transceiver: `enable`
//! waits for 11 recessive bits), 6 panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::cell::RefCell;

    use critical_section::Mutex;
    use twocan_app::{filters_for, App, AppStats};
    use twocan_bxcan::hal::{self, Can1Filters};
    use twocan_bxcan::regs::ControlRegs;
    use twocan_bxcan::{const_plan, BxCan, FifoPolicy, Instance, PlanOptions, Recovery};
    use twocan_stm32f7::board::BIT_RATE;
    use twocan_stm32f7::can::{self, CanRxHalf, CanState, CanTxHalf};
    use twocan_stm32f7::rt::{self, Led, CAN_BLINKS};
    use twocan_stm32f7::time::{self, Every};

    // Each controller owns its control registers and shares CAN1's filter block (RM0410
    // §40.9.4) through the `Can1Filters` handle of the hand-over.
    type Shared = CanState<ControlRegs, Can1Filters>;
    type SharedTx = CanTxHalf<ControlRegs, Can1Filters>;
    type SharedRx = CanRxHalf<ControlRegs, Can1Filters>;
    static CAN1: Shared = Shared::new();
    static CAN2: Shared = Shared::new();

    /// The counters of node 1 (CAN1) and node 2 (CAN2), copied after each step
    /// (`None` before the first).
    pub static STATS: Mutex<RefCell<Option<[AppStats; 2]>>> = Mutex::new(RefCell::new(None));

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        // The hand-over: CAN1 in dual mode gives the filter-block handle that CAN2 needs.
        let (tx1, rx1) = boot.can1_pins;
        let (can1, filters) = hal::can1_dual(boot.can1, tx1, rx1, &mut boot.apb1, &boot.clocks);
        let (tx2, rx2) = boot.can2_pins;
        let can2 = hal::can2(boot.can2, tx2, rx2, &mut boot.apb1, &boot.clocks, filters);
        let base = can1
            .config(BIT_RATE)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS))
            .recovery(Recovery::Automatic);
        let config1 = base
            .can2_start_bank(14)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));

        // The HAL's hand-over gives the registers, nothing configured yet; each node's
        // list is planned at compile time for its 14 banks (`config1` splits the block
        // at 14: CAN1 0-13, CAN2 14-27), and each controller is configured in place in
        // its state.
        let (regs1, filters1) = can1
            .into_registers(&config1)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        let (regs2, filters2) = can2
            .into_registers(&base)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        let plan1 = const_plan!(
            filters_for(1, 2),
            PlanOptions::new(14).fifo(FifoPolicy::Fifo0)
        );
        let plan2 = const_plan!(
            filters_for(2, 1),
            PlanOptions::new(14).fifo(FifoPolicy::Fifo1)
        );
        let (tx1, rx1) = can::start(
            &CAN1,
            Instance::Can1,
            |slot| BxCan::can1_dual_in(slot, regs1, filters1, &config1, plan1).map_err(|f| f.error),
            &mut boot.core.NVIC,
        )
        .unwrap_or_else(|| rt::halt(CAN_BLINKS));
        let (tx2, rx2) = can::start(
            &CAN2,
            Instance::Can2,
            |slot| BxCan::can2_in(slot, regs2, filters2, &base, plan2).map_err(|f| f.error),
            &mut boot.core.NVIC,
        )
        .unwrap_or_else(|| rt::halt(CAN_BLINKS));

        run([(tx1, rx1), (tx2, rx2)], boot.led)
    }

    /// The application after the configuration, in a function of its own (not
    /// inlined): its state (the two nodes, their call-backs' frames) takes stack only
    /// once the configuration is done. Node 1 on CAN1, node 2 on CAN2 (their filter
    /// lists: `filters_for` above).
    #[inline(never)]
    fn run(halves: [(SharedTx, SharedRx); 2], mut led: Led) -> ! {
        let [(mut tx1, mut rx1), (mut tx2, mut rx2)] = halves;
        let mut node1 = App::new(1, 2);
        let mut node2 = App::new(2, 1);
        let mut period = Every::new(time::millis(), 10);
        let mut shown = 0;
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
                let both = stats[0].heartbeats.min(stats[1].heartbeats);
                if both >= shown + 50 {
                    shown = both;
                    led.toggle();
                }
            }
            cortex_m::asm::wfi();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("stm32f7-can1-can2: {}", twocan_stm32f7::HOST_NOTE);
}
