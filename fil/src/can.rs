//! The CAN controllers of a board: the project's behavioural models, their register
//! windows and their interrupt lines.

use twocan_bxcan::model::BxCanModel;
use twocan_core::registers::Registers;
use twocan_flexcan::model::layout::{CBT, CBT_BTF};
use twocan_flexcan::model::{Chip, FlexCanModel};

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
    /// (Kinetis FlexCAN: message buffers, bus off, error, tx warning, rx warning, wake-up;
    /// i.MX RT1062 FlexCAN: its one line, the OR of all requests; bxCAN: TX, RX0, RX1,
    /// SCE). The FlexCAN model ORs the two warning requests into one: the harness drives
    /// the tx-warning vector with it.
    pub fn lines(&self) -> Vec<bool> {
        match self {
            Model::FlexCan(m) if matches!(m.chip(), Chip::Imxrt1062(_)) => vec![m.irq().any()],
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

    /// Whether the controller takes part in bus traffic (FlexCAN out of freeze and
    /// disable; bxCAN in normal mode).
    pub fn on_bus(&self) -> bool {
        match self {
            Model::FlexCan(m) => m.mode() == twocan_flexcan::model::ModelMode::Normal,
            Model::BxCan(m) => m.state().mode == twocan_bxcan::model::Mode::Normal,
        }
    }

    /// Frames the controller's receive FIFO(s) lost to an overrun so far.
    pub fn frames_lost(&self) -> u64 {
        match self {
            Model::FlexCan(m) => m.frames_lost(),
            Model::BxCan(m) => {
                let s = m.state();
                s.overruns[0] + s.overruns[1]
            }
        }
    }

    /// `CTRL1[CLKSRC]` of a FlexCAN (false for bxCAN).
    pub fn clksrc(&self) -> bool {
        match self {
            Model::FlexCan(m) => m.peek32(0x04) & (1 << 13) != 0,
            Model::BxCan(_) => false,
        }
    }

    /// Gives a FlexCAN's protocol engine its clock or takes it away (bxCAN: nothing; its
    /// clock is the register clock).
    pub fn set_engine_clock(&self, clocked: bool) {
        if let Model::FlexCan(m) = self {
            m.set_freeze_ack_stuck(!clocked);
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
                // CBT[BTF] = 1 (RT1062 CAN3, IMXRT1060RM "CAN Bit Timing register"):
                // EPRESDIV (30–21), EPROPSEG (15–10), EPSEG1 (9–5), EPSEG2 (4–0) replace
                // CTRL1's fields. CBT reads 0 on the modules that lack it.
                let cbt = m.peek32(CBT);
                let (presdiv, propseg, pseg1, pseg2) = if cbt & CBT_BTF != 0 {
                    (
                        (cbt >> 21) & 0x3FF,
                        (cbt >> 10) & 0x3F,
                        (cbt >> 5) & 0x1F,
                        cbt & 0x1F,
                    )
                } else {
                    (ctrl1 >> 24, ctrl1 & 7, (ctrl1 >> 19) & 7, (ctrl1 >> 16) & 7)
                };
                let clk = if ctrl1 & (1 << 13) != 0 {
                    bus_hz
                } else {
                    can_hz
                };
                let tq =
                    1 + (u64::from(propseg) + 1) + (u64::from(pseg1) + 1) + (u64::from(pseg2) + 1);
                (clk > 0).then(|| clk / ((u64::from(presdiv) + 1) * tq))
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

#[cfg(test)]
mod tests {
    use super::*;
    use twocan_flexcan::model::Rt1062Can;

    /// CAN3's `CBT` (BTF = 1) replaces `CTRL1`'s timing fields; CAN1 has no `CBT`.
    #[test]
    fn flexcan_bit_rate_from_ctrl1_or_cbt() {
        let mut can3 = Model::FlexCan(FlexCanModel::imxrt1062(Rt1062Can::Can3));
        // CTRL1 (in Freeze mode out of reset): PRESDIV 4 (÷5), PROPSEG 2, PSEG1 3, PSEG2 3
        // → 1 + 3 + 4 + 4 = 12 tq: 24 MHz / 60 = 400 kbit/s.
        can3.write32(0x04, (4 << 24) | (3 << 19) | (3 << 16) | 2);
        assert_eq!(can3.programmed_bit_rate(24_000_000, 0), Some(400_000));
        // CBT: EPROPSEG 10, EPSEG1 7, EPSEG2 4 → 1 + 11 + 8 + 5 = 25 tq;
        // EPRESDIV 3 (÷4): 80 MHz / (4 × 25) = 800 kbit/s.
        can3.write32(CBT, CBT_BTF | (3 << 21) | (10 << 10) | (7 << 5) | 4);
        assert_eq!(can3.programmed_bit_rate(80_000_000, 0), Some(800_000));
        let mut can1 = Model::FlexCan(FlexCanModel::imxrt1062(Rt1062Can::Can1));
        can1.write32(0x04, (4 << 24) | (3 << 19) | (3 << 16) | 2);
        can1.write32(CBT, CBT_BTF | (3 << 21));
        assert_eq!(can1.programmed_bit_rate(24_000_000, 0), Some(400_000));
        assert_eq!(can1.lines(), vec![false], "one line per RT1062 module");
    }
}
