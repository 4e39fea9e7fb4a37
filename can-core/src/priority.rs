//! The one priority ordering of CAN frames, used everywhere in the workspace.
//!
//! Bus arbitration (ISO 11898-1 §10.4.4.3) compares the arbitration field bit by bit,
//! dominant (0) winning. For classical frames the field is sent as
//!
//! ```text
//! standard: ID[10:0] RTR IDE=0
//! extended: ID[28:18] SRR=1 IDE=1 ID[17:0] RTR
//! ```
//!
//! [`Priority`] packs exactly those bits, in that order, into one integer, so that
//! "smaller key" is "wins arbitration". Consequences, all tested below:
//! - a smaller identifier wins;
//! - with equal base identifier, a standard frame wins over an extended one;
//! - with equal identifier and format, a data frame wins over a remote frame;
//! - a standard remote frame wins over an extended frame with the same base identifier
//!   (its RTR bit meets the extended frame's recessive SRR, then its dominant IDE wins).
//!
//! The transmit queues, the bxCAN "priority by identifier" policy, the models and the
//! simulated bus's arbitration all use this key.

use crate::frame::Frame;

impl Frame {
    /// The arbitration priority key of this frame: smaller wins bus arbitration.
    ///
    /// See [`crate::priority`] for the ordering.
    pub const fn priority(&self) -> Priority {
        Priority::of(self)
    }
}

/// Arbitration key: smaller wins. Totally ordered; equal only for identical arbitration fields.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Priority(u32);

impl Priority {
    /// The key of a frame's arbitration field.
    pub const fn of(frame: &Frame) -> Self {
        Self::from_raw(frame.raw_id(), frame.is_extended(), frame.is_remote())
    }

    /// The key of a raw identifier (`extended` says 29 bits) with a frame kind.
    pub const fn from_raw(raw: u32, extended: bool, remote: bool) -> Self {
        // 11 base bits, 2 bits (RTR|SRR, IDE), 18 extension bits, 1 RTR bit = 32 bits.
        let rtr = remote as u32;
        if extended {
            let base = (raw >> 18) & 0x7FF;
            let ext = raw & 0x3_FFFF;
            Priority((base << 21) | (1 << 20) | (1 << 19) | (ext << 1) | rtr)
        } else {
            Priority(((raw & 0x7FF) << 21) | (rtr << 20))
        }
    }

    /// The raw key, for display and tests.
    pub const fn raw(self) -> u32 {
        self.0
    }

    /// Whether `self` wins arbitration against `other`.
    pub const fn beats(self, other: Priority) -> bool {
        self.0 < other.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{extended_id, standard_id};
    use embedded_can::Id;

    fn d(id: Id) -> Frame {
        Frame::new_data(id, &[]).unwrap()
    }
    fn r(id: Id) -> Frame {
        Frame::new_remote(id, 0).unwrap()
    }

    #[test]
    fn ordering_rules() {
        let s = |x| standard_id(x).unwrap();
        let e = |x| extended_id(x).unwrap();
        assert!(d(s(0x100)).priority().beats(d(s(0x101)).priority()));
        assert!(d(s(0x100)).priority().beats(r(s(0x100)).priority()));
        // standard before extended with the same base identifier
        assert!(d(s(0x100)).priority().beats(d(e(0x100 << 18)).priority()));
        assert!(r(s(0x100)).priority().beats(d(e(0x100 << 18)).priority()));
        // extended with a smaller base wins over standard with a larger one
        assert!(d(e(0x0FF << 18 | 0x3FFFF))
            .priority()
            .beats(d(s(0x100)).priority()));
        assert!(d(e(5)).priority().beats(r(e(5)).priority()));
        assert!(r(e(5)).priority().beats(d(e(6)).priority()));
        assert_eq!(d(s(7)).priority(), d(s(7)).priority());
    }
}
