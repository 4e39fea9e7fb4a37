//! Register encodings of a [`Timing`].
//!
//! * bxCAN `CAN_BTR` (RM0410 §40.9.2, reset 0x0123_0000): `BRP[9:0]` bits 9:0,
//!   `TS1[3:0]` bits 19:16, `TS2[2:0]` bits 22:20, `SJW[1:0]` bits 25:24, each
//!   holding the count minus one; `LBKM` (bit 30, loop back) and `SILM` (bit 31,
//!   silent) are mode bits, not timing: [`Timing::bxcan_btr`] leaves them 0.
//! * FlexCAN `CTRL1` (K20/K64/K66 reference manuals, "Control 1 register"):
//!   `PRESDIV` bits 31:24, `RJW` bits 23:22, `PSEG1` bits 21:19, `PSEG2` bits
//!   18:16, `SMP` bit 7, `PROPSEG` bits 2:0, each count minus one (SMP: 1 = three
//!   samples). The other CTRL1 bits (BOFFMSK, ERRMSK, CLKSRC, LPB, TWRNMSK,
//!   RWRNMSK, BOFFREC, TSYN, LBUF, LOM) are not timing: [`Timing::flexcan_ctrl1`]
//!   leaves them 0; merge with [`FLEXCAN_CTRL1_TIMING_MASK`].
//!
//! Encoding refuses counts that break the timing's rules or do not fit the
//! register fields ([`TimingError::Inconsistent`]), and a timing for the other
//! controller ([`TimingError::WrongController`]).

use super::error::TimingError;
use super::limits::{Controller, Limits};
use super::segments::{consistency_with, Timing};

/// bxCAN `CAN_BTR` bits that hold timing (BRP, TS1, TS2, SJW).
pub const BXCAN_BTR_TIMING_MASK: u32 = 0x03FF_03FF & !(1 << 23) & !(0xF << 26);
/// bxCAN `CAN_BTR.LBKM`: loop back mode (debug), bit 30. Not timing.
pub const BXCAN_BTR_LBKM: u32 = 1 << 30;
/// bxCAN `CAN_BTR.SILM`: silent mode (debug), bit 31. Not timing.
pub const BXCAN_BTR_SILM: u32 = 1 << 31;
/// FlexCAN `CTRL1` bits that hold timing (PRESDIV, RJW, PSEG1, PSEG2, SMP, PROPSEG).
pub const FLEXCAN_CTRL1_TIMING_MASK: u32 = 0xFFFF_0087;
/// FlexCAN `CTRL1.SMP`: triple sampling, bit 7.
pub const FLEXCAN_CTRL1_SMP: u32 = 1 << 7;

/// The raw bxCAN `CAN_BTR` timing fields (count minus one each).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BxcanBtr {
    /// `BRP[9:0]` = prescaler − 1.
    pub brp: u16,
    /// `TS1[3:0]` = tseg1 − 1.
    pub ts1: u8,
    /// `TS2[2:0]` = tseg2 − 1.
    pub ts2: u8,
    /// `SJW[1:0]` = SJW − 1.
    pub sjw: u8,
}

impl BxcanBtr {
    /// The register value (mode bits LBKM/SILM clear). Fields are masked to their widths.
    pub const fn bits(self) -> u32 {
        (self.brp as u32 & 0x3FF)
            | (self.ts1 as u32 & 0xF) << 16
            | (self.ts2 as u32 & 0x7) << 20
            | (self.sjw as u32 & 0x3) << 24
    }

    /// The timing fields of a register value (mode and reserved bits ignored).
    pub const fn from_bits(btr: u32) -> Self {
        BxcanBtr {
            brp: (btr & 0x3FF) as u16,
            ts1: ((btr >> 16) & 0xF) as u8,
            ts2: ((btr >> 20) & 0x7) as u8,
            sjw: ((btr >> 24) & 0x3) as u8,
        }
    }
}

/// The raw FlexCAN `CTRL1` timing fields (count minus one each).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FlexcanCtrl1 {
    /// `PRESDIV` (bits 31:24) = prescaler − 1.
    pub presdiv: u8,
    /// `RJW` (bits 23:22) = SJW − 1.
    pub rjw: u8,
    /// `PSEG1` (bits 21:19) = phase segment 1 − 1.
    pub pseg1: u8,
    /// `PSEG2` (bits 18:16) = phase segment 2 − 1.
    pub pseg2: u8,
    /// `SMP` (bit 7): triple sampling.
    pub smp: bool,
    /// `PROPSEG` (bits 2:0) = propagation segment − 1.
    pub propseg: u8,
}

impl FlexcanCtrl1 {
    /// The timing bits of CTRL1 (all other bits clear). Fields are masked to their widths.
    pub const fn bits(self) -> u32 {
        (self.presdiv as u32) << 24
            | (self.rjw as u32 & 0x3) << 22
            | (self.pseg1 as u32 & 0x7) << 19
            | (self.pseg2 as u32 & 0x7) << 16
            | if self.smp { FLEXCAN_CTRL1_SMP } else { 0 }
            | (self.propseg as u32 & 0x7)
    }

    /// The timing fields of a CTRL1 value (other bits ignored).
    pub const fn from_bits(ctrl1: u32) -> Self {
        FlexcanCtrl1 {
            presdiv: (ctrl1 >> 24) as u8,
            rjw: ((ctrl1 >> 22) & 0x3) as u8,
            pseg1: ((ctrl1 >> 19) & 0x7) as u8,
            pseg2: ((ctrl1 >> 16) & 0x7) as u8,
            smp: ctrl1 & FLEXCAN_CTRL1_SMP != 0,
            propseg: (ctrl1 & 0x7) as u8,
        }
    }
}

impl Timing {
    /// Checks the controller and that the counts are consistent both with the
    /// timing's limits and with the controller's register widths.
    const fn check_encodable(&self, controller: Controller) -> Result<(), TimingError> {
        if !matches!(
            (self.limits.controller, controller),
            (Controller::FlexCan, Controller::FlexCan) | (Controller::BxCan, Controller::BxCan)
        ) {
            return Err(TimingError::WrongController);
        }
        let own = self.consistency();
        let hw: Limits = controller.limits();
        let width = consistency_with(self, &hw);
        let all = own.union(width);
        if all.is_ok() {
            Ok(())
        } else {
            Err(TimingError::Inconsistent(all))
        }
    }

    /// The bxCAN `CAN_BTR` fields of this timing.
    pub const fn bxcan_btr_fields(&self) -> Result<BxcanBtr, TimingError> {
        if let Err(e) = self.check_encodable(Controller::BxCan) {
            return Err(e);
        }
        Ok(BxcanBtr {
            brp: self.prescaler - 1,
            ts1: (self.tseg1() - 1) as u8,
            ts2: self.phase_seg2 - 1,
            sjw: self.sjw - 1,
        })
    }

    /// The bxCAN `CAN_BTR` value of this timing, mode bits (LBKM, SILM) clear.
    pub const fn bxcan_btr(&self) -> Result<u32, TimingError> {
        match self.bxcan_btr_fields() {
            Ok(f) => Ok(f.bits()),
            Err(e) => Err(e),
        }
    }

    /// The FlexCAN `CTRL1` timing fields of this timing.
    pub const fn flexcan_ctrl1_fields(&self) -> Result<FlexcanCtrl1, TimingError> {
        if let Err(e) = self.check_encodable(Controller::FlexCan) {
            return Err(e);
        }
        Ok(FlexcanCtrl1 {
            presdiv: (self.prescaler - 1) as u8,
            rjw: self.sjw - 1,
            pseg1: self.phase_seg1 - 1,
            pseg2: self.phase_seg2 - 1,
            smp: self.triple_sampling,
            propseg: self.prop_seg - 1,
        })
    }

    /// The FlexCAN `CTRL1` timing bits of this timing (other bits clear; write
    /// `(ctrl1 & !FLEXCAN_CTRL1_TIMING_MASK) | value`).
    pub const fn flexcan_ctrl1(&self) -> Result<u32, TimingError> {
        match self.flexcan_ctrl1_fields() {
            Ok(f) => Ok(f.bits()),
            Err(e) => Err(e),
        }
    }

    /// The timing held by a bxCAN `CAN_BTR` value (mode bits ignored), with
    /// [`Limits::BXCAN`].
    pub const fn from_bxcan_btr(clock_hz: u32, bitrate: u32, btr: u32) -> Timing {
        let f = BxcanBtr::from_bits(btr);
        Timing {
            clock_hz,
            bitrate,
            limits: Limits::BXCAN,
            prescaler: f.brp + 1,
            prop_seg: 0,
            phase_seg1: f.ts1 + 1,
            phase_seg2: f.ts2 + 1,
            sjw: f.sjw + 1,
            triple_sampling: false,
        }
    }

    /// The timing held by a FlexCAN `CTRL1` value (non-timing bits ignored),
    /// with [`Limits::FLEXCAN`].
    pub const fn from_flexcan_ctrl1(clock_hz: u32, bitrate: u32, ctrl1: u32) -> Timing {
        let f = FlexcanCtrl1::from_bits(ctrl1);
        Timing {
            clock_hz,
            bitrate,
            limits: Limits::FLEXCAN,
            prescaler: f.presdiv as u16 + 1,
            prop_seg: f.propseg + 1,
            phase_seg1: f.pseg1 + 1,
            phase_seg2: f.pseg2 + 1,
            sjw: f.rjw + 1,
            triple_sampling: f.smp,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timing::Consistency;

    #[test]
    fn masks() {
        assert_eq!(BXCAN_BTR_TIMING_MASK, 0x037F_03FF);
        assert_eq!(BXCAN_BTR_TIMING_MASK & (BXCAN_BTR_LBKM | BXCAN_BTR_SILM), 0);
        let all = FlexcanCtrl1 {
            presdiv: 0xFF,
            rjw: 3,
            pseg1: 7,
            pseg2: 7,
            smp: true,
            propseg: 7,
        };
        assert_eq!(all.bits(), FLEXCAN_CTRL1_TIMING_MASK);
        let all = BxcanBtr {
            brp: 0x3FF,
            ts1: 15,
            ts2: 7,
            sjw: 3,
        };
        assert_eq!(all.bits(), BXCAN_BTR_TIMING_MASK);
    }

    #[test]
    fn bxcan_reset_value_decodes() {
        // RM0410: CAN_BTR reset value 0x0123_0000: BRP 0, TS1 3, TS2 2, SJW 1.
        let t = Timing::from_bxcan_btr(54_000_000, 500_000, 0x0123_0000);
        assert_eq!(
            (t.prescaler, t.phase_seg1, t.phase_seg2, t.sjw),
            (1, 4, 3, 2)
        );
        assert_eq!(t.bxcan_btr(), Ok(0x0123_0000));
        // Mode bits are not timing.
        let t2 = Timing::from_bxcan_btr(54_000_000, 500_000, 0xC123_0000);
        assert_eq!(t, t2);
    }

    #[test]
    fn flexcan_fields_positions() {
        let t = Timing {
            clock_hz: 16_000_000,
            bitrate: 440_000,
            limits: Limits::FLEXCAN,
            prescaler: 2,
            prop_seg: 6,
            phase_seg1: 5,
            phase_seg2: 6,
            sjw: 4,
            triple_sampling: true,
        };
        let v = t.flexcan_ctrl1().unwrap();
        assert_eq!(v >> 24, 1);
        assert_eq!((v >> 22) & 3, 3);
        assert_eq!((v >> 19) & 7, 4);
        assert_eq!((v >> 16) & 7, 5);
        assert_eq!(v & 0x80, 0x80);
        assert_eq!(v & 7, 5);
        assert_eq!(v & !FLEXCAN_CTRL1_TIMING_MASK, 0);
        assert_eq!(
            Timing::from_flexcan_ctrl1(16_000_000, 440_000, v | 0x0000_1000),
            t
        );
    }

    #[test]
    fn refuses_wrong_controller_and_inconsistent() {
        let t = Timing::from_tsegs(16_000_000, 500_000, &Limits::FLEXCAN, 2, 13, 2);
        assert_eq!(t.bxcan_btr(), Err(TimingError::WrongController));
        let b = Timing::from_tsegs(54_000_000, 500_000, &Limits::BXCAN, 6, 15, 2);
        assert_eq!(b.flexcan_ctrl1(), Err(TimingError::WrongController));
        let mut bad = t;
        bad.prescaler = 0;
        assert_eq!(
            bad.flexcan_ctrl1(),
            Err(TimingError::Inconsistent(Consistency::PRESCALER_TOO_SMALL))
        );
        // Custom limits wider than the register: still refused.
        let mut wide = Limits::FLEXCAN;
        wide.prescaler.max = 1000;
        let mut w = Timing::from_tsegs(16_000_000, 1_000, &wide, 500, 13, 2);
        assert!(w.consistency().is_ok());
        assert_eq!(
            w.flexcan_ctrl1(),
            Err(TimingError::Inconsistent(Consistency::PRESCALER_TOO_LARGE))
        );
        w.prescaler = 256;
        assert!(w.flexcan_ctrl1().is_ok());
    }
}
