//! Per-controller bit timing limits, kept as data.
//!
//! A CAN bit is cut into time quanta (tq): one synchronisation quantum, then
//! *tseg1* (propagation segment + phase segment 1), then *tseg2* (phase segment 2).
//! The sample point sits between tseg1 and tseg2. A [`Limits`] value says which
//! counts a controller accepts; the CAN clock is given separately (it depends on
//! the board, not on the peripheral).
//!
//! | | FlexCAN ([`Limits::FLEXCAN`]) | bxCAN ([`Limits::BXCAN`]) |
//! |---|---|---|
//! | prescaler | PRESDIV 1..=256 | BRP 1..=1024 |
//! | propagation segment | PROPSEG 1..=8 | (none: part of TS1) |
//! | phase segment 1 | PSEG1 1..=8 (2..=8 with triple sampling) | TS1 1..=16 |
//! | phase segment 2 | PSEG2 2..=8 | TS2 1..=8 |
//! | SJW | RJW 1..=4, ≤ PSEG2, ≤ PSEG1 | SJW 1..=4, ≤ TS2 |
//! | quanta per bit | 1 + PROPSEG + PSEG1 + PSEG2 = 5..=25 | 1 + TS1 + TS2 = 3..=25 |
//!
//! FlexCAN values are ACAN §16.1 (the constraint list after the 500 kbit/s example)
//! and agree with the K20/K64/K66 reference manuals (CTRL1 fields hold the count
//! minus one; PSEG2 "valid programmable values are 1–7", i.e. 2..=8 quanta).
//! [`Limits::FLEXCAN_KINETIS`] is the same with the Kinetis manual's 8..=25 quanta per
//! bit ("Arbitration and matching timing"): the limits the FlexCAN driver accepts and
//! reports; [`Limits::FLEXCAN`] keeps the field ranges alone, as ACAN computes with
//! them ([`super::flexcan_rules`]).
//! bxCAN values are RM0410 §40.7.7 (CAN_BTR: BRP\[9:0\], TS1\[3:0\], TS2\[2:0\],
//! SJW\[1:0\], each holding the count minus one).
//!
//! How the counts map to register fields:
//!
//! * FlexCAN: `CTRL1.PRESDIV = prescaler − 1`, `PROPSEG = prop_seg − 1`,
//!   `PSEG1 = phase_seg1 − 1`, `PSEG2 = phase_seg2 − 1`, `RJW = sjw − 1`,
//!   `SMP = triple_sampling`. The generic tseg1 is `PROPSEG + PSEG1` quanta.
//! * bxCAN: `BTR.BRP = prescaler − 1`, `TS1 = tseg1 − 1`, `TS2 = phase_seg2 − 1`,
//!   `SJW = sjw − 1`. bxCAN has no separate propagation segment: its limits give
//!   `prop_seg` the range 0..=0 and `phase_seg1` holds the whole TS1.

/// An inclusive range of counts (quanta, or prescaler steps).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Bounds {
    /// Smallest allowed value.
    pub min: u16,
    /// Largest allowed value.
    pub max: u16,
}

impl Bounds {
    /// The range `min..=max`.
    pub const fn new(min: u16, max: u16) -> Self {
        Bounds { min, max }
    }

    /// Whether `value` lies in `min..=max`.
    pub const fn contains(self, value: u16) -> bool {
        value >= self.min && value <= self.max
    }

    /// `value` moved into `min..=max` (assumes `min <= max`).
    pub const fn clamp(self, value: u16) -> u16 {
        if value < self.min {
            self.min
        } else if value > self.max {
            self.max
        } else {
            value
        }
    }
}

/// Which register layout a set of limits belongs to (see [`crate::timing::encode`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Controller {
    /// NXP FlexCAN (Kinetis K20/K64/K66, Teensy 3.x): timing in `CTRL1`.
    FlexCan,
    /// STM32 bxCAN (RM0410 ch. 40): timing in `CAN_BTR`.
    BxCan,
}

impl Controller {
    /// Lower-case name, as the `can-timing` tool spells it.
    pub const fn name(self) -> &'static str {
        match self {
            Controller::FlexCan => "flexcan",
            Controller::BxCan => "bxcan",
        }
    }

    /// The built-in limits of this controller.
    pub const fn limits(self) -> Limits {
        match self {
            Controller::FlexCan => Limits::FLEXCAN,
            Controller::BxCan => Limits::BXCAN,
        }
    }
}

/// The bit timing limits of one controller (see the [module docs](self) for the table).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Limits {
    /// Register layout the counts are encoded into.
    pub controller: Controller,
    /// Clock prescaler (one time quantum = `prescaler` CAN clock periods).
    pub prescaler: Bounds,
    /// Propagation segment in quanta (`0..=0` when the controller has no such field).
    pub prop_seg: Bounds,
    /// Phase segment 1 in quanta (bxCAN: the whole TS1).
    pub phase_seg1: Bounds,
    /// Phase segment 2 in quanta (= tseg2).
    pub phase_seg2: Bounds,
    /// Synchronisation (resynchronisation) jump width in quanta.
    pub sjw: Bounds,
    /// `Some(n)`: triple sampling is available and needs phase segment 1 ≥ `n`
    /// (FlexCAN `CTRL1.SMP`, ACAN §16.1: 2). `None`: no triple sampling.
    pub triple_sampling_min_phase_seg1: Option<u8>,
    /// Whether SJW must also be ≤ phase segment 1 (FlexCAN: yes, the CAN rule
    /// SJW ≤ min(PS1, PS2); bxCAN: TS1 includes the propagation segment, so only
    /// SJW ≤ TS2 is checked).
    pub sjw_le_phase_seg1: bool,
    /// Quanta per bit (1 + tseg1 + tseg2) a rule beyond the field ranges allows: the
    /// counts the fields can express that the controller's manual still forbids
    /// ([`Limits::FLEXCAN_KINETIS`]: at least 8). [`Limits::min_quanta`] and
    /// [`Limits::max_quanta`] are the fields' range narrowed by this one; the solver and
    /// [`crate::timing::Solutions`] search only inside it, and [`Timing::consistency`]
    /// (ACAN table 6) does not look at it: a timing outside it is
    /// [`TimingError::ForbiddenByManual`](crate::timing::TimingError::ForbiddenByManual)
    /// ([`crate::timing::TimingRule::check_timing`]).
    ///
    /// [`Timing::consistency`]: crate::timing::Timing::consistency
    pub quanta: Bounds,
}

impl Limits {
    /// FlexCAN CTRL1 field ranges, ACAN §16.1: `1 ≤ PRESDIV ≤ 256`, `1 ≤ RJW ≤ 4`,
    /// `1 ≤ PROPSEG ≤ 8`, `1 ≤ PSEG1 ≤ 8` (2 with triple sampling), `2 ≤ PSEG2 ≤ 8`,
    /// `RJW ≤ PSEG2`; plus `RJW ≤ PSEG1`; 5..=25 quanta per bit. These reproduce ACAN's
    /// computations (its 3.2 Mbit/s "fastest exact" rate is 5 quanta); the driver
    /// accepts [`Limits::FLEXCAN_KINETIS`].
    pub const FLEXCAN: Limits = Limits {
        controller: Controller::FlexCan,
        prescaler: Bounds::new(1, 256),
        prop_seg: Bounds::new(1, 8),
        phase_seg1: Bounds::new(1, 8),
        phase_seg2: Bounds::new(2, 8),
        sjw: Bounds::new(1, 4),
        triple_sampling_min_phase_seg1: Some(2),
        sjw_le_phase_seg1: true,
        quanta: Bounds::new(5, 25),
    };

    /// What the FlexCAN driver accepts and reports: [`Limits::FLEXCAN`]'s field ranges
    /// with at least 8 quanta per bit (Kinetis K20/K64/K66 reference manuals, FlexCAN
    /// chapter, "Arbitration and matching timing": "the minimum number of time quanta per
    /// CAN bit must be 8").
    pub const FLEXCAN_KINETIS: Limits = Limits {
        quanta: Bounds::new(8, 25),
        ..Limits::FLEXCAN
    };

    /// bxCAN limits, RM0410 §40.7.7 (CAN_BTR): `1 ≤ BRP ≤ 1024`, `1 ≤ TS1 ≤ 16`,
    /// `1 ≤ TS2 ≤ 8`, `1 ≤ SJW ≤ 4`, `SJW ≤ TS2`.
    pub const BXCAN: Limits = Limits {
        controller: Controller::BxCan,
        prescaler: Bounds::new(1, 1024),
        prop_seg: Bounds::new(0, 0),
        phase_seg1: Bounds::new(1, 16),
        phase_seg2: Bounds::new(1, 8),
        sjw: Bounds::new(1, 4),
        triple_sampling_min_phase_seg1: None,
        sjw_le_phase_seg1: false,
        quanta: Bounds::new(3, 25),
    };

    /// Range of the generic tseg1 = propagation segment + phase segment 1.
    pub const fn tseg1(&self) -> Bounds {
        Bounds::new(
            self.prop_seg.min.saturating_add(self.phase_seg1.min),
            self.prop_seg.max.saturating_add(self.phase_seg1.max),
        )
    }

    /// Range of the generic tseg2 = phase segment 2.
    pub const fn tseg2(&self) -> Bounds {
        self.phase_seg2
    }

    /// Fewest quanta in a bit: 1 + min tseg1 + min tseg2, or [`Limits::quanta`]'s
    /// minimum when larger (FlexCAN fields 5, [`Limits::FLEXCAN_KINETIS`] 8, bxCAN 3).
    pub const fn min_quanta(&self) -> u32 {
        let fields = 1 + self.tseg1().min as u32 + self.phase_seg2.min as u32;
        if (self.quanta.min as u32) > fields {
            self.quanta.min as u32
        } else {
            fields
        }
    }

    /// Most quanta in a bit: 1 + max tseg1 + max tseg2, or [`Limits::quanta`]'s maximum
    /// when smaller (25 for all three).
    pub const fn max_quanta(&self) -> u32 {
        let fields = 1 + self.tseg1().max as u32 + self.phase_seg2.max as u32;
        if (self.quanta.max as u32) < fields {
            self.quanta.max as u32
        } else {
            fields
        }
    }

    /// Whether these limits can be used by the solver: every range non-empty (the
    /// quanta per bit too, [`Limits::min_quanta`] ≤ [`Limits::max_quanta`]),
    /// prescaler and phase segments ≥ 1, tseg1, tseg2 and SJW maxima ≤ 255 (they
    /// are `u8` in [`Timing`](crate::timing::Timing)), and the smallest SJW always
    /// possible (SJW min ≤ phase segment minima).
    pub const fn is_valid(&self) -> bool {
        let ranges_ok = self.prescaler.min <= self.prescaler.max
            && self.prop_seg.min <= self.prop_seg.max
            && self.phase_seg1.min <= self.phase_seg1.max
            && self.phase_seg2.min <= self.phase_seg2.max
            && self.sjw.min <= self.sjw.max
            && self.min_quanta() <= self.max_quanta();
        let mins_ok = self.prescaler.min >= 1
            && self.phase_seg1.min >= 1
            && self.phase_seg2.min >= 1
            && self.sjw.min >= 1
            && self.sjw.min <= self.phase_seg2.min
            && (!self.sjw_le_phase_seg1 || self.sjw.min <= self.phase_seg1.min);
        let widths_ok = self.prop_seg.max as u32 + self.phase_seg1.max as u32 <= 255
            && self.phase_seg2.max <= 255
            && self.sjw.max <= 255;
        ranges_ok && mins_ok && widths_ok
    }

    /// Largest SJW these limits allow with the given phase segments:
    /// `min(max SJW, phase_seg2)`, and also `≤ phase_seg1` when
    /// [`sjw_le_phase_seg1`](Self::sjw_le_phase_seg1) is set.
    pub const fn max_sjw(&self, phase_seg1: u8, phase_seg2: u8) -> u8 {
        let mut sjw = self.sjw.max;
        if (phase_seg2 as u16) < sjw {
            sjw = phase_seg2 as u16;
        }
        if self.sjw_le_phase_seg1 && (phase_seg1 as u16) < sjw {
            sjw = phase_seg1 as u16;
        }
        if sjw > 255 {
            255
        } else {
            sjw as u8
        }
    }

    /// Splits a generic tseg1 into (propagation segment, phase segment 1).
    ///
    /// Rule (documented in `docs/bit-timing.md`): like ACAN §16.1's examples,
    /// phase segment 1 gets half of tseg1 rounded down and the propagation segment
    /// gets the rest (10 → 5 + 5 and 11 → 6 + 5, as ACAN shows for 500 and
    /// 440 kbit/s). If that leaves phase segment 1 shorter than the SJW that
    /// phase segment 2 would allow (`min(max SJW, tseg2)`), quanta move from the
    /// propagation segment to phase segment 1 so that SJW is not cut. Finally
    /// both parts are kept inside their ranges. For bxCAN (`prop_seg` 0..=0) the
    /// result is always `(0, tseg1)`.
    ///
    /// The result is meaningful when `tseg1` lies in [`Limits::tseg1`].
    pub const fn split_tseg1(&self, tseg1: u8, tseg2: u8) -> (u8, u8) {
        let t1 = tseg1 as u16;
        let mut ps1 = t1 / 2;
        if self.sjw_le_phase_seg1 {
            let mut wanted = self.sjw.max;
            if (tseg2 as u16) < wanted {
                wanted = tseg2 as u16;
            }
            if ps1 < wanted {
                ps1 = wanted;
            }
        }
        // Keep PROPSEG = tseg1 − PSEG1 inside its range, then PSEG1 inside its own.
        let ps1_min_from_prop = t1.saturating_sub(self.prop_seg.max);
        let ps1_max_from_prop = t1.saturating_sub(self.prop_seg.min);
        if ps1 < ps1_min_from_prop {
            ps1 = ps1_min_from_prop;
        }
        if ps1 > ps1_max_from_prop {
            ps1 = ps1_max_from_prop;
        }
        if ps1 < self.phase_seg1.min && self.phase_seg1.min <= t1 {
            ps1 = self.phase_seg1.min;
        }
        if ps1 > self.phase_seg1.max {
            ps1 = self.phase_seg1.max;
        }
        if ps1 > t1 {
            ps1 = t1;
        }
        let prop = t1 - ps1;
        (prop as u8, ps1 as u8)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_limits_are_valid_and_have_expected_quanta() {
        assert!(Limits::FLEXCAN.is_valid());
        assert!(Limits::BXCAN.is_valid());
        assert_eq!(Limits::FLEXCAN.min_quanta(), 5);
        assert_eq!(Limits::FLEXCAN.max_quanta(), 25);
        assert_eq!(Limits::BXCAN.min_quanta(), 3);
        assert_eq!(Limits::BXCAN.max_quanta(), 25);
        assert_eq!(Limits::FLEXCAN.tseg1(), Bounds::new(2, 16));
        assert_eq!(Limits::BXCAN.tseg1(), Bounds::new(1, 16));
        assert_eq!(Controller::FlexCan.limits(), Limits::FLEXCAN);
        assert_eq!(Controller::BxCan.limits(), Limits::BXCAN);
    }

    #[test]
    fn split_reproduces_acan_examples() {
        // ACAN §16.1: 500 kbit/s and 250 kbit/s (16 quanta): 5 + 5 + 5, RJW 4.
        assert_eq!(Limits::FLEXCAN.split_tseg1(10, 5), (5, 5));
        // ACAN §16.1: 440 kbit/s (18 quanta): PropSeg 6, PS1 5, PS2 6.
        assert_eq!(Limits::FLEXCAN.split_tseg1(11, 6), (6, 5));
    }

    #[test]
    fn split_stays_in_range_and_keeps_sjw() {
        let l = Limits::FLEXCAN;
        let mut t1 = 2u8;
        while t1 <= 16 {
            let mut t2 = 2u8;
            while t2 <= 8 {
                let (p, s) = l.split_tseg1(t1, t2);
                assert_eq!(p + s, t1);
                assert!(l.prop_seg.contains(p as u16), "{t1} {t2}");
                assert!(l.phase_seg1.contains(s as u16), "{t1} {t2}");
                // SJW is as large as any split would allow.
                let best = (1..t1).map(|ps1| l.max_sjw(ps1.min(8), t2)).max().unwrap();
                assert_eq!(l.max_sjw(s, t2), best, "{t1} {t2}");
                t2 += 1;
            }
            t1 += 1;
        }
        for t1 in 1..=16u8 {
            assert_eq!(Limits::BXCAN.split_tseg1(t1, 3), (0, t1));
        }
    }

    #[test]
    fn invalid_limits_detected() {
        let mut l = Limits::FLEXCAN;
        l.prescaler.min = 0;
        assert!(!l.is_valid());
        let mut l = Limits::BXCAN;
        l.phase_seg2 = Bounds::new(5, 4);
        assert!(!l.is_valid());
        let mut l = Limits::BXCAN;
        l.phase_seg1.max = 300;
        assert!(!l.is_valid());
        assert_eq!(Bounds::new(2, 8).clamp(9), 8);
        assert_eq!(Bounds::new(2, 8).clamp(1), 2);
    }
}
