//! The portable application (`twocan_app::App`, the module the firmware examples run) on
//! a Teensy 3.6 FlexCAN node and an STM32F767 bxCAN node sharing one simulated bus, with
//! a plain "other ECU" sending traffic neither application asked for and a listen-only
//! sniffer that records every frame on the wire with its start-of-frame time.

use std::cell::RefCell;
use std::rc::Rc;

use twocan_app::App;
use twocan_core::Frame;
use twocan_host::{BxNode, FlexNode, Harness, Serviced};
use twocan_sim::{RandomFaults, SimNode};

/// What the other ECU sends every fifth period: standard, extended and remote frames
/// no filter of either application takes, cycling through every DLC.
pub fn other_ecu_frame(k: u32) -> Frame {
    let dlc = ((k / 3) % 9) as usize;
    let data: Vec<u8> = (0..dlc)
        .map(|i| (k as u8).wrapping_mul(31).wrapping_add(i as u8))
        .collect();
    match k % 3 {
        0 => Frame::standard(0x300 + (k % 16) as u16, &data),
        1 => Frame::extended(0x0CF0_0400 | (k % 8), &data),
        _ => Frame::remote(0x400 + (k % 32), k.is_multiple_of(2), dlc as u8),
    }
    .expect("valid frame")
}

/// The two application nodes, the other ECU and the sniffer after a run.
pub struct AppBus {
    /// The harness (the bus and its trace).
    pub h: Harness,
    /// The Teensy's application (node 1).
    pub teensy_app: App,
    /// The STM32's application (node 2).
    pub stm32_app: App,
    /// FlexCAN can0 of the Teensy 3.6.
    pub teensy: FlexNode,
    /// bxCAN CAN1 of the STM32F767.
    pub stm32: BxNode,
    /// The other ECU.
    pub other: Rc<RefCell<SimNode>>,
    /// A listen-only node that keeps every frame it saw.
    pub sniffer: Rc<RefCell<SimNode>>,
    /// Application periods run (each application stepped once per period).
    pub periods: u32,
    /// Frames the Teensy's application queued during the periods (before the last step).
    pub teensy_queued: u32,
    /// Frames the STM32's application queued during the periods.
    pub stm32_queued: u32,
}

/// Bus time of one application period (1 ms).
pub fn period_bits(bit_rate: u32) -> u64 {
    u64::from(bit_rate) / 1000
}

/// Runs `periods` application periods of 1 ms at `bit_rate`, then lets the bus drain for
/// 5 ms and steps each application once more so that it handles everything received.
pub fn run_apps(bit_rate: u32, periods: u32, faults: Option<RandomFaults>) -> AppBus {
    let mut h = Harness::new(bit_rate).expect("bus");
    let mut teensy_app = App::new(1, 2);
    let mut stm32_app = App::new(2, 1);
    let mut teensy = FlexNode::teensy36_can0(&mut h, &teensy_app.filters()).expect("teensy");
    let mut stm32 = BxNode::stm32f767_can1(&mut h, &stm32_app.filters()).expect("stm32");
    let other = SimNode::new().shared();
    let sniffer = SimNode::new().with_listen_only(true).shared();
    {
        let mut bus = h.bus().borrow_mut();
        bus.attach("other-ecu", other.clone());
        bus.attach("sniffer", sniffer.clone());
    }
    // Both controllers synchronised before the first period.
    h.run_for(20, &mut [&mut teensy as &mut dyn Serviced, &mut stm32]);
    h.bus().borrow_mut().set_random_faults(faults);
    let period = period_bits(bit_rate);
    let start = h.now();
    for p in 0..periods {
        teensy_app.step(&mut teensy.driver);
        stm32_app.step(&mut stm32.driver);
        if p % 5 == 0 {
            other.borrow_mut().send(other_ecu_frame(p / 5));
        }
        h.run_until(
            start + u64::from(p + 1) * period,
            &mut [&mut teensy as &mut dyn Serviced, &mut stm32],
        );
    }
    h.run_for(
        5 * period,
        &mut [&mut teensy as &mut dyn Serviced, &mut stm32],
    );
    let teensy_queued = teensy.driver.traffic().queued;
    let stm32_queued = stm32.driver.traffic().queued;
    // Handle what arrived. (This step queues frames of its own; they are not counted.)
    teensy_app.step(&mut teensy.driver);
    stm32_app.step(&mut stm32.driver);
    AppBus {
        h,
        teensy_app,
        stm32_app,
        teensy,
        stm32,
        other,
        sniffer,
        periods,
        teensy_queued,
        stm32_queued,
    }
}
