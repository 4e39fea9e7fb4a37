//! Simulator speed with the two real drivers over their behavioural models.
//!
//! [`two_drivers`]: our bxCAN
//! backend over `twocan_bxcan::model::BxCanModel` (CAN1) and our FlexCAN backend over
//! `twocan_flexcan::model::FlexCanModel` (Teensy 3.2's FlexCAN0), on one simulated bus,
//! each sending 8-byte frames to the other. The "interrupt handler" (`on_interrupt`) of a
//! driver runs whenever its model raises an interrupt line, between bus events.
//!
//! [`harness`]: the same traffic through `twocan_host::Harness` (the cross-controller
//! harness of `can-demo` and the cross-backend tests: a Teensy 3.6's FlexCAN0 and an
//! STM32F767's CAN1, register access that lets bus time pass while a driver spins on an
//! acknowledge bit, every node serviced after each bus event).

use std::time::Instant;

use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::{Bank, BxCan, Can, Config, Fifo, FilterPlan};
use twocan_core::{Driver, Filter, Frame};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::{
    AcanDriver, Board, FlexCan, HostSystem, IdleClocked, Instance, Settings, Target,
};
use twocan_host::{BxNode, FlexNode, Harness};
use twocan_sim::Bus;

use crate::cmd::{Context, Error, Result};
use crate::simspeed::{Speed, BITRATE, MIN_SECS};

/// The APB1 clock of the bxCAN side (only for its bit timing).
const APB1_HZ: u32 = 54_000_000;
/// Frames each side queues per round (the transmit rings hold 16).
const ROUND: usize = 8;
/// Bus events allowed for one round before the run is declared stuck.
const MAX_EVENTS_PER_ROUND: u32 = 10_000;
/// Bit times one `step_until` may cover when nothing is sent.
const MAX_IDLE_BITS: u64 = 1_000;

/// Configures the bxCAN side. Leaving initialization mode takes 11 recessive bits on the
/// bus (RM0410 §40.4.2), so the bus runs a few bit times between bounded tries.
fn bxcan_driver(model: &BxCanModel, bus: &mut Bus) -> Result<Driver<BxCan<BxCanModel>, 32, 16>> {
    let config = Config::from_bitrate(APB1_HZ, BITRATE)
        .map_err(|e| Error::new(format!("bxCAN configuration: {e:?}")))?
        .wait_iterations(4);
    let mut init = Can::can1(model.clone(), &config)
        .map_err(|e| Error::new(format!("bxCAN can1: {:?}", e.error)))?;
    let mut plan = FilterPlan::manual();
    let bank = Bank::mask32(&Filter::pass_all(), Fifo::Fifo0)
        .map_err(|e| Error::new(format!("bxCAN bank: {e:?}")))?;
    plan.set_bank(0, bank)
        .map_err(|e| Error::new(format!("bxCAN filters: {e:?}")))?;
    init.set_filters(&plan)
        .map_err(|e| Error::new(format!("bxCAN filters: {e:?}")))?;
    for _ in 0..100 {
        match init.enable() {
            Ok(can) => return Ok(Driver::new(can.into_split())),
            Err(failed) => {
                init = failed.value;
                bus.run_for(4);
            }
        }
    }
    Err(Error::new(
        "bxCAN model: no INAK = 0 after 400 bit times of idle bus",
    ))
}

fn flexcan_driver(model: &FlexCanModel) -> Result<AcanDriver<IdleClocked>> {
    let settings = Settings::new(BITRATE);
    let target = Target::new(Board::Teensy32, Instance::Can0);
    // `begin` waits for ESR1.SYNCH: let idle bus time pass while it polls.
    let controller = FlexCan::begin(
        IdleClocked::new(model.clone()),
        &mut HostSystem::new(),
        target,
        &settings,
        &[Filter::pass_all()],
        &[],
    )
    .map_err(|e| Error::new(format!("FlexCAN begin: {e:?}")))?;
    Ok(AcanDriver::new(controller.into_split()))
}

/// Runs the two drivers against each other; frames delivered per host second. With
/// `fast_path` false the bus plays every attempt bit by bit.
pub fn two_drivers(fast_path: bool) -> Result<Speed> {
    let bx_model = BxCanModel::can1();
    let fx_model = FlexCanModel::mk20dx256();
    let mut bus = Bus::new(BITRATE).context("Bus::new")?;
    bus.set_tracing(false);
    bus.set_fast_path(fast_path);
    bus.attach("bxcan", bx_model.clone());
    bus.attach("flexcan", fx_model.clone());
    let mut fx = flexcan_driver(&fx_model)?;
    let mut bx = bxcan_driver(&bx_model, &mut bus)?;

    // Rounds: each side queues ROUND frames, then the bus runs until both receivers have
    // them all (bxCAN's identifiers win arbitration, so without rounds it would starve the
    // FlexCAN side).
    let mut sent = 0u64;
    let mut delivered = [0u64; 2];
    let start = Instant::now();
    while start.elapsed().as_secs_f64() < MIN_SECS {
        for _ in 0..ROUND {
            let data = sent.to_le_bytes();
            let id = (sent % 0x100) as u16;
            let a = Frame::standard(0x100 + id, &data);
            let b = Frame::standard(0x300 + id, &data);
            let (a, b) = match (a, b) {
                (Ok(a), Ok(b)) => (a, b),
                _ => return Err(Error::new("building a frame")),
            };
            if bx.try_send(&a).is_err() || fx.try_send(&b).is_err() {
                return Err(Error::new("a transmit queue refused a frame of the round"));
            }
            sent += 1;
        }
        let mut events = 0u32;
        while delivered[0] < sent || delivered[1] < sent {
            bus.step_until(bus.now() + MAX_IDLE_BITS);
            if bx_model.irq_lines().any() {
                bx.on_interrupt();
            }
            while bx.receive().is_ok() {
                delivered[0] += 1;
            }
            if fx_model.irq_pending() {
                fx.on_interrupt();
            }
            while fx.receive().is_ok() {
                delivered[1] += 1;
            }
            events += 1;
            if events > MAX_EVENTS_PER_ROUND {
                return Err(Error::new(format!(
                    "the drivers over their models stopped exchanging frames (sent {sent} \
                     each way, received: bxCAN {}, FlexCAN {})",
                    delivered[0], delivered[1]
                )));
            }
        }
    }
    let secs = start.elapsed().as_secs_f64();
    let lost = bx.traffic().rx_ring_overflows + fx.traffic().rx_ring_overflows;
    if lost != 0 {
        return Err(Error::new(format!(
            "{lost} frames lost to full receive rings"
        )));
    }
    let scenario = "twocan bxCAN driver over the bxCAN model ⇄ twocan FlexCAN driver over the \
                    FlexCAN model, both sending 8-byte frames, interrupt handler run on each \
                    interrupt line, trace off";
    crate::simspeed::check_path(fast_path, bus.fast_path_attempts(), scenario)?;
    Ok(Speed {
        scenario: scenario.into(),
        frames: delivered[0] + delivered[1],
        secs,
        bus_secs: bus.now() as f64 / BITRATE as f64,
    })
}

/// Bit times the harness runs between two looks at the receive rings (about one frame).
const HARNESS_STEP_BITS: u64 = 150;

/// The same traffic as [`two_drivers`] through the `twocan-host` harness.
pub fn harness(fast_path: bool) -> Result<Speed> {
    let mut h = Harness::new(BITRATE).map_err(|e| Error::new(format!("harness: {e:?}")))?;
    h.bus().borrow_mut().set_tracing(false);
    h.bus().borrow_mut().set_fast_path(fast_path);
    let mut teensy = FlexNode::teensy36_can0(&mut h, &[Filter::pass_all()])
        .map_err(|e| Error::new(format!("harness FlexCAN node: {e:?}")))?;
    let mut stm32 = BxNode::stm32f767_can1(&mut h, &[Filter::pass_all()])
        .map_err(|e| Error::new(format!("harness bxCAN node: {e:?}")))?;
    let start_bits = h.now();
    let mut sent = 0u64;
    let mut delivered = [0u64; 2];
    let start = Instant::now();
    while start.elapsed().as_secs_f64() < MIN_SECS {
        for _ in 0..ROUND {
            let data = sent.to_le_bytes();
            let id = (sent % 0x100) as u16;
            let (a, b) = match (
                Frame::standard(0x100 + id, &data),
                Frame::standard(0x300 + id, &data),
            ) {
                (Ok(a), Ok(b)) => (a, b),
                _ => return Err(Error::new("building a frame")),
            };
            if stm32.driver.try_send(&a).is_err() || teensy.driver.try_send(&b).is_err() {
                return Err(Error::new("a transmit queue refused a frame of the round"));
            }
            sent += 1;
        }
        let mut steps = 0u32;
        while delivered[0] < sent || delivered[1] < sent {
            h.run_for(HARNESS_STEP_BITS, &mut [&mut teensy, &mut stm32]);
            while teensy.driver.receive().is_ok() {
                delivered[0] += 1;
            }
            while stm32.driver.receive().is_ok() {
                delivered[1] += 1;
            }
            steps += 1;
            if steps > MAX_EVENTS_PER_ROUND {
                return Err(Error::new(format!(
                    "the harness stopped exchanging frames (sent {sent} each way, received: \
                     FlexCAN {}, bxCAN {})",
                    delivered[0], delivered[1]
                )));
            }
        }
    }
    let secs = start.elapsed().as_secs_f64();
    if teensy.lost() + stm32.lost() != 0 {
        return Err(Error::new("the harness nodes lost frames"));
    }
    let scenario = "the same through `twocan_host::Harness` (can-demo's harness: Teensy 3.6 \
                    FlexCAN0 ⇄ STM32F767 CAN1, clocked register access, every node serviced \
                    after each bus event), trace off";
    let fast_attempts = h.bus().borrow().fast_path_attempts();
    crate::simspeed::check_path(fast_path, fast_attempts, scenario)?;
    Ok(Speed {
        scenario: scenario.into(),
        frames: delivered[0] + delivered[1],
        secs,
        bus_secs: (h.now() - start_bits) as f64 / BITRATE as f64,
    })
}
