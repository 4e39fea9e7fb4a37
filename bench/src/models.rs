//! Simulator speed with the two real drivers over their behavioural models: our bxCAN
//! backend over `twocan_bxcan::model::BxCanModel` (CAN1) and our FlexCAN backend over
//! `twocan_flexcan::model::FlexCanModel` (Teensy 3.2's FlexCAN0), on one simulated bus,
//! each sending 8-byte frames to the other. The "interrupt handler" (`on_interrupt`) of a
//! driver runs whenever its model raises an interrupt line, between bus events.

use std::time::Instant;

use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::{Bank, Can, Config, Fifo, FilterPlan};
use twocan_core::sim::Bus;
use twocan_core::{Driver, Filter, Frame};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::{AcanDriver, Board, FlexCan, HostSystem, Instance, Settings, Target};

use crate::cmd::{Context, Error, Result};
use crate::simspeed::{Speed, BITRATE, MIN_SECS};

/// The APB1 clock of the bxCAN side (only for its bit timing).
const APB1_HZ: u32 = 54_000_000;
/// Bus events between two looks at the clock.
const EVENTS_PER_CHECK: u32 = 1_000;
/// Bit times one `step_until` may cover when nothing is sent.
const MAX_IDLE_BITS: u64 = 1_000;

fn bxcan_driver(model: &BxCanModel) -> Result<Driver<Can<BxCanModel>, 32, 16>> {
    let config = Config::from_bitrate(APB1_HZ, BITRATE)
        .map_err(|e| Error::new(format!("bxCAN configuration: {e:?}")))?;
    let mut init = Can::can1(model.clone(), &config)
        .map_err(|e| Error::new(format!("bxCAN can1: {:?}", e.error)))?;
    let mut plan = FilterPlan::manual();
    let bank = Bank::mask32(&Filter::pass_all(), Fifo::Fifo0)
        .map_err(|e| Error::new(format!("bxCAN bank: {e:?}")))?;
    plan.set_bank(0, bank)
        .map_err(|e| Error::new(format!("bxCAN filters: {e:?}")))?;
    init.set_filters(&plan)
        .map_err(|e| Error::new(format!("bxCAN filters: {e:?}")))?;
    let can = init
        .enable()
        .map_err(|e| Error::new(format!("bxCAN enable: {:?}", e.error)))?;
    Ok(Driver::new(can))
}

fn flexcan_driver(model: &FlexCanModel) -> Result<AcanDriver<FlexCanModel>> {
    let settings = Settings::new(BITRATE);
    let target = Target::new(Board::Teensy32, Instance::Can0);
    let controller = FlexCan::begin(
        model.clone(),
        &mut HostSystem::new(),
        target,
        &settings,
        &[],
        &[],
    )
    .map_err(|e| Error::new(format!("FlexCAN begin: {e:?}")))?;
    Ok(AcanDriver::new(controller))
}

/// Runs the two drivers against each other; frames delivered per host second.
pub fn two_drivers() -> Result<Speed> {
    let bx_model = BxCanModel::can1();
    let fx_model = FlexCanModel::mk20dx256();
    let mut bx = bxcan_driver(&bx_model)?;
    let mut fx = flexcan_driver(&fx_model)?;
    let mut bus = Bus::new(BITRATE).context("Bus::new")?;
    bus.set_tracing(false);
    bus.attach("bxcan", bx_model.clone());
    bus.attach("flexcan", fx_model.clone());

    let mut sent = [0u64; 2];
    let mut delivered = [0u64; 2];
    let start = Instant::now();
    let mut events = 0u32;
    loop {
        // Keep both transmit queues full.
        loop {
            let n = sent[0];
            let f = Frame::standard(0x100 + (n % 0x100) as u16, &n.to_le_bytes())
                .context("frame")?;
            if bx.try_send(&f).is_err() {
                break;
            }
            sent[0] += 1;
        }
        loop {
            let n = sent[1];
            let f = Frame::standard(0x300 + (n % 0x100) as u16, &n.to_le_bytes())
                .context("frame")?;
            if fx.try_send(&f).is_err() {
                break;
            }
            sent[1] += 1;
        }
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
        if events >= EVENTS_PER_CHECK {
            events = 0;
            if start.elapsed().as_secs_f64() >= MIN_SECS {
                break;
            }
        }
    }
    let secs = start.elapsed().as_secs_f64();
    if delivered[0] == 0 || delivered[1] == 0 {
        return Err(Error::new(format!(
            "the drivers over their models exchanged no frames (received: bxCAN {}, FlexCAN {})",
            delivered[0], delivered[1]
        )));
    }
    let lost = bx.traffic().rx_ring_overflows + fx.traffic().rx_ring_overflows;
    if lost != 0 {
        return Err(Error::new(format!("{lost} frames lost to full receive rings")));
    }
    Ok(Speed {
        scenario: "twocan bxCAN driver over the bxCAN model ⇄ twocan FlexCAN driver over the \
                   FlexCAN model, both sending 8-byte frames, interrupt handler run on each \
                   interrupt line, trace off"
            .into(),
        frames: delivered[0] + delivered[1],
        secs,
        bus_secs: bus.now() as f64 / BITRATE as f64,
    })
}
