//! The rule flags a bit timing check reports: [`Consistency`] (ACAN §16.2, table 6).
//!
//! Its own module so that the error type ([`super::TimingError::Inconsistent`]) and the
//! timing value ([`super::Timing::consistency`]) both build on it without importing each
//! other.

use core::fmt;

bitflags::bitflags! {
    /// Bit flags naming every violated bit timing rule; empty means consistent
    /// (ACAN §16.2: "returns 0 if CAN bit decomposition is consistent").
    ///
    /// Bits 0..=10 have the positions of ACAN table 6; each "is zero" rule there is
    /// checked here as "below the controller minimum", each "greater than" rule as
    /// "above the controller maximum" (same thing for FlexCAN except PSEG2, whose
    /// minimum is 2 per the §16.1 constraint list). Bits 11..=13 are rules the ACAN
    /// table does not list: SJW ≤ phase segment 1 (CAN rule SJW ≤ min(PS1, PS2)),
    /// and the two triple-sampling rules of §16.1.
    ///
    /// ```
    /// use twocan_core::timing::Consistency;
    ///
    /// let c = Consistency::SJW_TOO_LARGE | Consistency::PRESCALER_TOO_SMALL;
    /// assert_eq!(c.bits(), 0b10_0000_0001); // ACAN table 6 bits 9 and 0
    /// assert!(c.contains(Consistency::SJW_TOO_LARGE) && !c.is_ok());
    /// assert_eq!(c.to_string(), "PRESCALER_TOO_SMALL, SJW_TOO_LARGE");
    /// assert_eq!(Consistency::from_bits_truncate(u32::MAX), Consistency::ALL);
    /// ```
    #[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct Consistency: u32 {
        /// Prescaler below minimum (ACAN table 6 bit 0, `kBitRatePrescalerIsZero`).
        const PRESCALER_TOO_SMALL = 1 << 0;
        /// Prescaler above maximum (bit 1, `kBitRatePrescalerIsGreaterThan256`).
        const PRESCALER_TOO_LARGE = 1 << 1;
        /// Propagation segment below minimum (bit 2, `kPropagationSegmentIsZero`).
        const PROP_SEG_TOO_SMALL = 1 << 2;
        /// Propagation segment above maximum (bit 3, `kPropagationSegmentIsGreaterThan8`;
        /// for bxCAN any non-zero value, as TS1 has no separate propagation field).
        const PROP_SEG_TOO_LARGE = 1 << 3;
        /// Phase segment 1 below minimum (bit 4, `kPhaseSegment1IsZero`).
        const PHASE_SEG1_TOO_SMALL = 1 << 4;
        /// Phase segment 1 above maximum (bit 5, `kPhaseSegment1IsGreaterThan8`).
        const PHASE_SEG1_TOO_LARGE = 1 << 5;
        /// Phase segment 2 below minimum (bit 6, `kPhaseSegment2IsZero`; FlexCAN
        /// minimum is 2).
        const PHASE_SEG2_TOO_SMALL = 1 << 6;
        /// Phase segment 2 above maximum (bit 7, `kPhaseSegment2IsGreaterThan8`).
        const PHASE_SEG2_TOO_LARGE = 1 << 7;
        /// SJW below minimum (bit 8, `kRJWIsZero`).
        const SJW_TOO_SMALL = 1 << 8;
        /// SJW above maximum (bit 9, `kRJWIsGreaterThan4`).
        const SJW_TOO_LARGE = 1 << 9;
        /// SJW greater than phase segment 2 (bit 10, `kRJWIsGreaterThanPhaseSegment2`).
        const SJW_ABOVE_PHASE_SEG2 = 1 << 10;
        /// SJW greater than phase segment 1 (not in ACAN table 6; checked when
        /// [`Limits::sjw_le_phase_seg1`](super::Limits::sjw_le_phase_seg1) is set, i.e. FlexCAN).
        const SJW_ABOVE_PHASE_SEG1 = 1 << 11;
        /// Triple sampling asked on a controller without it (bxCAN).
        const TRIPLE_SAMPLING_UNSUPPORTED = 1 << 12;
        /// Triple sampling with phase segment 1 below its triple-sampling minimum
        /// (ACAN §16.1: "Triple sampling: 2 ≤ mPhaseSegment1 ≤ 8").
        const TRIPLE_SAMPLING_PHASE_SEG1_TOO_SMALL = 1 << 13;
    }
}

impl Consistency {
    /// No rule violated.
    pub const OK: Consistency = Consistency::empty();
    /// Every flag defined above.
    pub const ALL: Consistency = Consistency::all();

    /// No rule is violated.
    pub const fn is_ok(self) -> bool {
        self.is_empty()
    }

    /// Number of violated rules.
    pub const fn count(self) -> u32 {
        self.bits().count_ones()
    }

    /// Names of the set flags, lowest bit first (for messages).
    pub fn names(self) -> impl Iterator<Item = &'static str> {
        self.iter_names().map(|(name, _)| name)
    }
}

impl fmt::Debug for Consistency {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Consistency(")?;
        if self.is_ok() {
            f.write_str("OK")?;
        }
        for (i, name) in self.names().enumerate() {
            if i > 0 {
                f.write_str(" | ")?;
            }
            f.write_str(name)?;
        }
        f.write_str(")")
    }
}

impl fmt::Display for Consistency {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_ok() {
            return f.write_str("consistent");
        }
        for (i, name) in self.names().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            f.write_str(name)?;
        }
        Ok(())
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for Consistency {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "Consistency({=u32:#x})", self.bits());
    }
}
