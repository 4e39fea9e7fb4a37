//! The CAN controllers of a board: the project's behavioural models, their register
//! windows and their interrupt lines.

use twocan_bxcan::model::BxCanModel;
use twocan_core::registers::Registers;
use twocan_flexcan::model::FlexCanModel;

use crate::profile::{CanInstance, CanKind};

/// A model handle (the bus holds a clone).
#[derive(Debug, Clone)]
pub enum Model {
    /// FlexCAN.
    FlexCan(FlexCanModel),
    /// bxCAN.
    BxCan(BxCanModel),
}

impl Model {
    /// 32-bit register read at `offset`.
    pub fn read32(&self, offset: usize) -> u32 {
        match self {
            Model::FlexCan(m) => m.read32(offset),
            Model::BxCan(m) => m.read32(offset),
        }
    }

    /// 32-bit register write at `offset`.
    pub fn write32(&mut self, offset: usize, value: u32) {
        match self {
            Model::FlexCan(m) => m.write32(offset, value),
            Model::BxCan(m) => m.write32(offset, value),
        }
    }

    /// Levels of the controller's lines, in the order of the profile's `irqs` list
    /// (FlexCAN: message buffers, bus off, error, tx warning, rx warning, wake-up; bxCAN:
    /// TX, RX0, RX1, SCE). The FlexCAN model ORs the two warning requests into one: the
    /// harness drives the tx-warning vector with it.
    pub fn lines(&self) -> Vec<bool> {
        match self {
            Model::FlexCan(m) => {
                let i = m.irq();
                vec![
                    i.message_buffer,
                    i.bus_off,
                    i.error,
                    i.warning,
                    false,
                    false,
                ]
            }
            Model::BxCan(m) => {
                let l = m.irq_lines();
                vec![l.tx, l.rx0, l.rx1, l.sce]
            }
        }
    }

    /// Whether the controller is in an internal loop-back mode whose frames never reach
    /// the wire (FlexCAN `CTRL1.LPB`; bxCAN `BTR.LBKM` with `BTR.SILM`).
    pub fn internal_loop_back(&self) -> bool {
        match self {
            Model::FlexCan(m) => m.peek32(0x04) & (1 << 12) != 0,
            Model::BxCan(m) => m.read32(0x1C) & (3 << 30) == 3 << 30,
        }
    }

    /// Transmit and receive error counters.
    pub fn counters(&self) -> (u16, u16) {
        let c = match self {
            Model::FlexCan(m) => m.error_counters(),
            Model::BxCan(m) => m.state().counters,
        };
        (c.tec, c.rec)
    }

    /// The bit rate the controller is programmed for, decoded from its bit-timing
    /// register and the clock that feeds it (`None` if not programmed / no clock):
    /// FlexCAN `CTRL1` (PRESDIV, PROPSEG, PSEG1, PSEG2; K66 RM §43.4.2; CLKSRC = 1 takes
    /// the bus clock, passed as `bus_hz`); bxCAN `CAN_BTR` (BRP, TS1, TS2; RM0410
    /// §40.7.7).
    pub fn programmed_bit_rate(&self, can_hz: u64, bus_hz: u64) -> Option<u64> {
        match self {
            Model::FlexCan(m) => {
                let ctrl1 = m.peek32(0x04);
                let presdiv = u64::from(ctrl1 >> 24) + 1;
                let pseg1 = u64::from((ctrl1 >> 19) & 7) + 1;
                let pseg2 = u64::from((ctrl1 >> 16) & 7) + 1;
                let propseg = u64::from(ctrl1 & 7) + 1;
                let clk = if ctrl1 & (1 << 13) != 0 {
                    bus_hz
                } else {
                    can_hz
                };
                let tq = 1 + propseg + pseg1 + pseg2;
                (clk > 0).then(|| clk / (presdiv * tq))
            }
            Model::BxCan(m) => {
                let btr = m.read32(0x1C);
                let brp = u64::from(btr & 0x3FF) + 1;
                let ts1 = u64::from((btr >> 16) & 0xF) + 1;
                let ts2 = u64::from((btr >> 20) & 7) + 1;
                (can_hz > 0).then(|| can_hz / (brp * (1 + ts1 + ts2)))
            }
        }
    }
}

/// A controller of a board with its window and lines.
#[derive(Debug, Clone)]
pub struct Port {
    /// The profile's description.
    pub instance: CanInstance,
    /// The model.
    pub model: Model,
}

/// Creates the models of a board's CAN instances: the bxCAN instances of one part come from
/// one [`BxCanModel::of_part`] (CAN1 and CAN2 share the filter block, as on the chip).
pub fn ports(instances: &[CanInstance]) -> Vec<Port> {
    let mut out = Vec::new();
    let mut bx: Option<Vec<BxCanModel>> = None;
    for inst in instances {
        let model = match inst.kind {
            CanKind::FlexCan(chip) => Model::FlexCan(FlexCanModel::new(chip)),
            CanKind::BxCan { instance, part } => {
                let models = bx.get_or_insert_with(|| BxCanModel::of_part(part));
                // Instance numbers come from the part's own list (`bxcan_instances`).
                let index = usize::from(instance.saturating_sub(1));
                Model::BxCan(models.get(index).cloned().expect("an instance of the part"))
            }
        };
        out.push(Port {
            instance: inst.clone(),
            model,
        });
    }
    out
}
