//! The adjustable timing value and its consistency check.
//!
//! [`Timing`] plays the role of ACAN's `ACANSettings` bit fields (ACAN §16.1,
//! table 7): the solver fills it in, the caller may then change any count
//! (prescaler, propagation segment, phase segments, SJW, triple sampling) and
//! check the result with [`Timing::consistency`], which reports every violated
//! rule at once as [`Consistency`] flags (ACAN §16.2, table 6).

pub use super::consistency::Consistency;
use super::error::TimingError;
use super::limits::Limits;

/// A CAN bit timing: the clock, the wished bit rate, the controller limits and
/// the counts the caller may adjust (ACAN §16.1 "You can change the property
/// values…").
///
/// All derived values are methods, so they follow any change of the counts.
/// They never panic, whatever the fields hold; when the counts are not
/// consistent ([`Timing::consistency`]) the values are, as ACAN §16.3–16.6 say,
/// irrelevant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Timing {
    /// CAN clock in Hz (FlexCAN on Teensy 3.x with ACAN: 16 MHz; bxCAN: APB1).
    pub clock_hz: u32,
    /// The wished bit rate, bit/s (ACAN `mWhishedBitRate`).
    pub bitrate: u32,
    /// Limits of the controller this timing is for.
    pub limits: Limits,
    /// Prescaler: one quantum is `prescaler` clock periods (ACAN `mBitRatePrescaler`).
    pub prescaler: u16,
    /// Propagation segment in quanta (ACAN `mPropagationSegment`; bxCAN: 0).
    pub prop_seg: u8,
    /// Phase segment 1 in quanta (ACAN `mPhaseSegment1`; bxCAN: TS1).
    pub phase_seg1: u8,
    /// Phase segment 2 in quanta (ACAN `mPhaseSegment2`; bxCAN: TS2).
    pub phase_seg2: u8,
    /// Synchronisation jump width in quanta (ACAN `mRJW`).
    pub sjw: u8,
    /// Three samples per bit (ACAN `mTripleSampling`, FlexCAN `CTRL1.SMP`).
    pub triple_sampling: bool,
}

impl Timing {
    /// A timing with the given prescaler, tseg1 and tseg2: tseg1 is split by
    /// [`Limits::split_tseg1`], SJW is [`Limits::max_sjw`], single sampling.
    /// Nothing is checked; see [`Timing::consistency`].
    pub const fn from_tsegs(
        clock_hz: u32,
        bitrate: u32,
        limits: &Limits,
        prescaler: u16,
        tseg1: u8,
        tseg2: u8,
    ) -> Timing {
        let (prop_seg, phase_seg1) = limits.split_tseg1(tseg1, tseg2);
        Timing {
            clock_hz,
            bitrate,
            limits: *limits,
            prescaler,
            prop_seg,
            phase_seg1,
            phase_seg2: tseg2,
            sjw: limits.max_sjw(phase_seg1, tseg2),
            triple_sampling: false,
        }
    }

    /// tseg1 = propagation segment + phase segment 1, in quanta (bxCAN: TS1).
    pub const fn tseg1(&self) -> u32 {
        self.prop_seg as u32 + self.phase_seg1 as u32
    }

    /// tseg2 = phase segment 2, in quanta.
    pub const fn tseg2(&self) -> u32 {
        self.phase_seg2 as u32
    }

    /// Quanta per bit: 1 (sync) + tseg1 + tseg2 (ACAN §16.1 bit rate formula).
    pub const fn quanta(&self) -> u32 {
        1 + self.tseg1() + self.tseg2()
    }

    /// Clock periods per bit: prescaler × quanta.
    pub const fn clocks_per_bit(&self) -> u64 {
        self.prescaler as u64 * self.quanta() as u64
    }

    /// Actual bit rate, rounded down (ACAN §16.3: clock / (prescaler × quanta));
    /// 0 if the prescaler is 0.
    pub const fn actual_bitrate(&self) -> u32 {
        match (self.clock_hz as u64).checked_div(self.clocks_per_bit()) {
            Some(rate) => rate as u32,
            None => 0,
        }
    }

    /// Whether the actual bit rate equals the wished one exactly (ACAN §16.4).
    pub const fn is_exact(&self) -> bool {
        let n = self.clocks_per_bit();
        n != 0 && self.bitrate != 0 && n * self.bitrate as u64 == self.clock_hz as u64
    }

    /// Distance of the actual bit rate from the wished one in ppm (ACAN §16.5):
    /// `|actual_bitrate() − bitrate| × 10⁶ / bitrate`, rounded down, where
    /// `actual_bitrate()` is itself rounded down as in §16.3. This is the
    /// definition that gives the manual's 124 ppm for 842 kbit/s and
    /// 10,100 ppm for 440 kbit/s. `u64::MAX` if the wished rate is 0.
    pub const fn ppm_from_wished(&self) -> u64 {
        if self.bitrate == 0 {
            return u64::MAX;
        }
        let actual = self.actual_bitrate() as u64;
        let wished = self.bitrate as u64;
        actual.abs_diff(wished) * 1_000_000 / wished
    }

    /// Whether the actual bit rate is within `tolerance_ppm` of the wished one,
    /// as ACAN's acceptance test (§16.1, default [`DEFAULT_TOLERANCE_PPM`]):
    /// `ppm_from_wished() ≤ tolerance_ppm`, and with a tolerance of 0 the rate
    /// must be exact ([`Timing::is_exact`]).
    ///
    /// [`DEFAULT_TOLERANCE_PPM`]: crate::timing::DEFAULT_TOLERANCE_PPM
    pub const fn within_tolerance(&self, tolerance_ppm: u32) -> bool {
        if tolerance_ppm == 0 {
            self.is_exact()
        } else {
            self.ppm_from_wished() <= tolerance_ppm as u64
        }
    }

    /// Sample point in per mille of the bit, rounded down:
    /// `1000 × (1 + tseg1) / quanta` (ACAN §16.1 formula, which gives per cent).
    /// With triple sampling this is the last (regular) sample; see
    /// [`Timing::first_sample_point`].
    pub const fn sample_point(&self) -> u16 {
        ((1 + self.tseg1()) * 1000 / self.quanta()) as u16
    }

    /// Point of the first sample in per mille, as ACAN §16.6 reports it: with
    /// triple sampling one quantum before [`Timing::sample_point`] (ACAN §16.1
    /// "Sampling first point" formula), otherwise the sample point itself.
    pub const fn first_sample_point(&self) -> u16 {
        let sp = 1 + self.tseg1();
        let sp = if self.triple_sampling { sp - 1 } else { sp };
        (sp * 1000 / self.quanta()) as u16
    }

    /// Oscillator tolerance this timing gives, in ppm, rounded down (the CAN
    /// rule of ISO 11898-1 / Bosch): the smaller of
    /// `SJW / (20 × quanta)` and `min(PS1, PS2) / (2 × (13 × quanta − PS2))`.
    pub const fn oscillator_tolerance_ppm(&self) -> u32 {
        let q = self.quanta() as u64;
        let ps2 = self.phase_seg2 as u64;
        let ps1 = self.phase_seg1 as u64;
        let min_ps = if ps1 < ps2 { ps1 } else { ps2 };
        let by_sjw = self.sjw as u64 * 1_000_000 / (20 * q);
        // 13 × q − PS2 ≥ 13 + 12 × PS2 > 0 since q ≥ 1 + PS2.
        let by_phase = min_ps * 1_000_000 / (2 * (13 * q - ps2));
        (if by_sjw < by_phase { by_sjw } else { by_phase }) as u32
    }

    /// Every rule the counts violate, at once (ACAN §16.2, table 6, with this
    /// timing's [`Limits`]; see [`Consistency`] for the extra rules).
    pub const fn consistency(&self) -> Consistency {
        consistency_with(self, &self.limits)
    }

    /// What a backend does before writing the registers (ACAN §15.2): error
    /// [`TimingError::Inconsistent`] if a rule is violated (§15.2.2), else
    /// [`TimingError::TooFarFromWishedBitrate`] if not
    /// [within `tolerance_ppm`](Timing::within_tolerance) (§15.2.1), else the timing.
    pub const fn validate(self, tolerance_ppm: u32) -> Result<Timing, TimingError> {
        let c = self.consistency();
        if !c.is_ok() {
            Err(TimingError::Inconsistent(c))
        } else if !self.within_tolerance(tolerance_ppm) {
            Err(TimingError::TooFarFromWishedBitrate)
        } else {
            Ok(self)
        }
    }
}

/// The consistency rules of `t`'s counts against `limits` (used with the
/// timing's own limits, and by the encoders with the register widths).
pub(crate) const fn consistency_with(t: &Timing, limits: &Limits) -> Consistency {
    let mut f = 0u32;
    let l = limits;
    if t.prescaler < l.prescaler.min {
        f |= Consistency::PRESCALER_TOO_SMALL.bits();
    }
    if t.prescaler > l.prescaler.max {
        f |= Consistency::PRESCALER_TOO_LARGE.bits();
    }
    if (t.prop_seg as u16) < l.prop_seg.min {
        f |= Consistency::PROP_SEG_TOO_SMALL.bits();
    }
    if (t.prop_seg as u16) > l.prop_seg.max {
        f |= Consistency::PROP_SEG_TOO_LARGE.bits();
    }
    if (t.phase_seg1 as u16) < l.phase_seg1.min {
        f |= Consistency::PHASE_SEG1_TOO_SMALL.bits();
    }
    if (t.phase_seg1 as u16) > l.phase_seg1.max {
        f |= Consistency::PHASE_SEG1_TOO_LARGE.bits();
    }
    if (t.phase_seg2 as u16) < l.phase_seg2.min {
        f |= Consistency::PHASE_SEG2_TOO_SMALL.bits();
    }
    if (t.phase_seg2 as u16) > l.phase_seg2.max {
        f |= Consistency::PHASE_SEG2_TOO_LARGE.bits();
    }
    if (t.sjw as u16) < l.sjw.min {
        f |= Consistency::SJW_TOO_SMALL.bits();
    }
    if (t.sjw as u16) > l.sjw.max {
        f |= Consistency::SJW_TOO_LARGE.bits();
    }
    if t.sjw > t.phase_seg2 {
        f |= Consistency::SJW_ABOVE_PHASE_SEG2.bits();
    }
    if l.sjw_le_phase_seg1 && t.sjw > t.phase_seg1 {
        f |= Consistency::SJW_ABOVE_PHASE_SEG1.bits();
    }
    if t.triple_sampling {
        match l.triple_sampling_min_phase_seg1 {
            None => f |= Consistency::TRIPLE_SAMPLING_UNSUPPORTED.bits(),
            Some(min) => {
                if t.phase_seg1 < min {
                    f |= Consistency::TRIPLE_SAMPLING_PHASE_SEG1_TOO_SMALL.bits();
                }
            }
        }
    }
    Consistency::from_bits_retain(f)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn acan_500k() -> Timing {
        // ACAN §16.1 / table 7 layout at 500 kbit/s: BRP 2, 5 + 5 + 5, RJW 4.
        Timing {
            clock_hz: 16_000_000,
            bitrate: 500_000,
            limits: Limits::FLEXCAN,
            prescaler: 2,
            prop_seg: 5,
            phase_seg1: 5,
            phase_seg2: 5,
            sjw: 4,
            triple_sampling: false,
        }
    }

    #[test]
    fn acan_500k_adjustment_example() {
        // ACAN §16.1: 68 % before, PS1++ / PS2-- gives 75 %, rate unchanged, consistent.
        let mut t = acan_500k();
        assert_eq!(t.sample_point() / 10, 68);
        t.phase_seg1 += 1;
        t.phase_seg2 -= 1;
        assert_eq!(t.sample_point(), 750);
        assert_eq!(t.actual_bitrate(), 500_000);
        assert!(t.is_exact());
        assert!(t.consistency().is_ok());
    }

    #[test]
    fn acan_16_2_phase_seg1_zero_is_0x10() {
        let mut t = acan_500k();
        t.phase_seg1 = 0;
        let c = t.consistency();
        // ACAN prints 0x10; with RJW 4 > PS1 0 our extra bit 11 is set too.
        assert!(c.contains(Consistency::PHASE_SEG1_TOO_SMALL));
        assert_eq!(c.bits() & 0x7FF, 0x10);
        assert_eq!(
            c,
            Consistency::PHASE_SEG1_TOO_SMALL | Consistency::SJW_ABOVE_PHASE_SEG1
        );
    }

    #[test]
    fn every_flag_reported_at_once() {
        let mut t = acan_500k();
        t.prescaler = 0;
        t.prop_seg = 9;
        t.phase_seg1 = 1;
        t.phase_seg2 = 1;
        t.sjw = 5;
        t.triple_sampling = true;
        let c = t.consistency();
        let want = Consistency::PRESCALER_TOO_SMALL
            | Consistency::PROP_SEG_TOO_LARGE
            | Consistency::PHASE_SEG2_TOO_SMALL
            | Consistency::SJW_TOO_LARGE
            | Consistency::SJW_ABOVE_PHASE_SEG2
            | Consistency::SJW_ABOVE_PHASE_SEG1
            | Consistency::TRIPLE_SAMPLING_PHASE_SEG1_TOO_SMALL;
        assert_eq!(c, want);
        assert_eq!(c.count(), 7);
        // Values stay computable without panics.
        assert_eq!(t.actual_bitrate(), 0);
        assert!(!t.is_exact());
        let _ = t.sample_point();
        let _ = t.oscillator_tolerance_ppm();

        let mut t = acan_500k();
        t.prescaler = 257;
        t.prop_seg = 0;
        t.phase_seg1 = 9;
        t.phase_seg2 = 9;
        t.sjw = 0;
        assert_eq!(
            t.consistency(),
            Consistency::PRESCALER_TOO_LARGE
                | Consistency::PROP_SEG_TOO_SMALL
                | Consistency::PHASE_SEG1_TOO_LARGE
                | Consistency::PHASE_SEG2_TOO_LARGE
                | Consistency::SJW_TOO_SMALL
        );
        t.phase_seg2 = 0;
        assert!(t.consistency().contains(Consistency::PHASE_SEG2_TOO_SMALL));
    }

    #[test]
    fn bxcan_rules() {
        let mut t = Timing::from_tsegs(54_000_000, 500_000, &Limits::BXCAN, 6, 15, 2);
        assert!(t.consistency().is_ok());
        t.triple_sampling = true;
        t.prop_seg = 1;
        t.phase_seg1 = 17;
        t.sjw = 3;
        assert_eq!(
            t.consistency(),
            Consistency::TRIPLE_SAMPLING_UNSUPPORTED
                | Consistency::PROP_SEG_TOO_LARGE
                | Consistency::PHASE_SEG1_TOO_LARGE
                | Consistency::SJW_ABOVE_PHASE_SEG2
        );
        t.prescaler = 1025;
        assert!(t.consistency().contains(Consistency::PRESCALER_TOO_LARGE));
    }

    #[test]
    fn flag_formatting() {
        assert_eq!(format!("{:?}", Consistency::OK), "Consistency(OK)");
        assert_eq!(
            format!(
                "{:?}",
                Consistency::SJW_TOO_LARGE | Consistency::PRESCALER_TOO_SMALL
            ),
            "Consistency(PRESCALER_TOO_SMALL | SJW_TOO_LARGE)"
        );
        assert_eq!(format!("{}", Consistency::OK), "consistent");
        assert_eq!(Consistency::from_bits_truncate(u32::MAX), Consistency::ALL);
        assert!(Consistency::ALL.intersects(Consistency::SJW_TOO_SMALL));
        let mut c = Consistency::OK;
        c |= Consistency::SJW_TOO_SMALL;
        assert_eq!(c.bits(), 1 << 8);
    }

    #[test]
    fn oscillator_tolerance_formula() {
        // 500 kbit/s, 16 quanta, PS1 5, PS2 5, SJW 4:
        // SJW / (20 × 16) = 12500 ppm; 5 / (2 × (208 − 5)) = 12315 ppm.
        assert_eq!(acan_500k().oscillator_tolerance_ppm(), 12_315);
        let mut t = acan_500k();
        t.sjw = 1; // 1 / 320 = 3125 ppm
        assert_eq!(t.oscillator_tolerance_ppm(), 3_125);
    }

    #[test]
    fn triple_sampling_first_point() {
        let mut t = acan_500k();
        t.triple_sampling = true;
        assert_eq!(t.sample_point(), 687);
        assert_eq!(t.first_sample_point(), 625);
        t.triple_sampling = false;
        assert_eq!(t.first_sample_point(), 687);
    }
}
