//! Portable acceptance filters.
//!
//! One description serves both controllers: a frame kind (data / remote / any) × a
//! format (standard / extended / any) × an identifier with a mask, or pass-all. Backends
//! compile a list of these into their hardware (FlexCAN ID table, bxCAN filter banks) and
//! map the hardware match index back to the position of the filter in the user's list.
//!
//! The conformance rules are those of ACAN §12.3–12.4 and §13.4: the identifier and the
//! mask must fit the format (11 bits standard, 29 bits extended), and the acceptance value
//! may not have a bit set outside the mask (such a filter could never match).

pub use crate::error::FilterError;
use crate::frame::Frame;

/// Which frame kinds a filter accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrameKind {
    /// Data frames only.
    Data,
    /// Remote frames only.
    Remote,
    /// Both.
    Any,
}

impl FrameKind {
    /// Whether a frame with `remote` kind is accepted.
    pub const fn accepts(self, remote: bool) -> bool {
        match self {
            FrameKind::Data => !remote,
            FrameKind::Remote => remote,
            FrameKind::Any => true,
        }
    }
}

/// Which identifier formats a filter accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Format {
    /// 11-bit identifiers.
    Standard,
    /// 29-bit identifiers.
    Extended,
    /// Both (only with a zero mask: the identifier is not compared).
    Any,
}

impl Format {
    /// Whether a frame with `extended` format is accepted.
    pub const fn accepts(self, extended: bool) -> bool {
        match self {
            Format::Standard => !extended,
            Format::Extended => extended,
            Format::Any => true,
        }
    }

    /// The largest identifier of the format (the all-ones mask).
    pub const fn id_mask(self) -> u32 {
        match self {
            Format::Standard => 0x7FF,
            Format::Extended | Format::Any => 0x1FFF_FFFF,
        }
    }
}

/// A portable acceptance filter.
///
/// A frame matches when its kind and format are accepted and
/// `frame_id & mask == id`.
///
/// ```
/// use twocan_core::{Filter, FilterError, Format, Frame, FrameKind};
///
/// // Standard data frames 0x120..=0x12F (ACAN's (kind, format, mask, acceptance) filter).
/// const RANGE: Filter = Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, 0x120);
/// assert_eq!(RANGE.check(), Ok(()));
/// assert!(RANGE.matches(&Frame::standard(0x12A, &[1]).unwrap()));
/// assert!(!RANGE.matches(&Frame::standard(0x130, &[1]).unwrap()));
/// assert!(!RANGE.matches(&Frame::extended(0x12A, &[1]).unwrap())); // other format
/// assert!(!RANGE.matches(&Frame::remote(0x12A, false, 0).unwrap())); // other kind
///
/// // Bad filters are refused with a reason, never accepted silently.
/// let never = Filter::masked(FrameKind::Data, Format::Standard, 0x700, 0x0FF);
/// assert_eq!(never.check(), Err(FilterError::AcceptanceOutsideMask));
/// assert_eq!(Filter::standard(0x800).check(), Err(FilterError::IdOutOfRange));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Filter {
    /// Accepted frame kinds.
    pub kind: FrameKind,
    /// Accepted identifier formats.
    pub format: Format,
    /// The acceptance value (compared where `mask` has ones).
    pub id: u32,
    /// Which identifier bits are compared (all ones: a single identifier).
    pub mask: u32,
}

impl Filter {
    /// Accepts every frame (ACAN's pass-all primary filter).
    pub const fn pass_all() -> Self {
        Filter {
            kind: FrameKind::Any,
            format: Format::Any,
            id: 0,
            mask: 0,
        }
    }

    /// Accepts every frame of one kind and format, whatever the identifier.
    pub const fn kind_format(kind: FrameKind, format: Format) -> Self {
        Filter {
            kind,
            format,
            id: 0,
            mask: 0,
        }
    }

    /// Accepts exactly one identifier (ACAN's `(kind, format, identifier)` filter).
    pub const fn exact(kind: FrameKind, format: Format, id: u32) -> Self {
        Filter {
            kind,
            format,
            id,
            mask: format.id_mask(),
        }
    }

    /// A data-frame filter for one standard identifier.
    pub const fn standard(id: u16) -> Self {
        Self::exact(FrameKind::Data, Format::Standard, id as u32)
    }

    /// A data-frame filter for one extended identifier.
    pub const fn extended(id: u32) -> Self {
        Self::exact(FrameKind::Data, Format::Extended, id)
    }

    /// Accepts identifiers with `id & mask == acceptance` (ACAN's `(kind, format, mask,
    /// acceptance)` filter).
    pub const fn masked(kind: FrameKind, format: Format, mask: u32, acceptance: u32) -> Self {
        Filter {
            kind,
            format,
            id: acceptance,
            mask,
        }
    }

    /// Checks conformance (ACAN §12.3–12.4, §13.4).
    pub const fn check(&self) -> Result<(), FilterError> {
        let limit = self.format.id_mask();
        if let Format::Any = self.format {
            if self.mask != 0 || self.id != 0 {
                return Err(FilterError::AnyFormatWithIdentifier);
            }
        }
        if self.mask > limit {
            return Err(FilterError::MaskOutOfRange);
        }
        if self.id > limit {
            return Err(FilterError::IdOutOfRange);
        }
        if self.id & !self.mask != 0 {
            return Err(FilterError::AcceptanceOutsideMask);
        }
        Ok(())
    }

    /// Whether the filter accepts every frame.
    pub const fn is_pass_all(&self) -> bool {
        matches!(self.kind, FrameKind::Any) && matches!(self.format, Format::Any)
    }

    /// Whether the filter compares a single identifier (every identifier bit in the mask).
    pub const fn is_exact(&self) -> bool {
        !matches!(self.format, Format::Any) && self.mask == self.format.id_mask()
    }

    /// The reference semantics every backend's hardware encoding must reproduce.
    pub fn matches(&self, frame: &Frame) -> bool {
        self.kind.accepts(frame.is_remote())
            && self.format.accepts(frame.is_extended())
            && (frame.raw_id() & self.mask) == self.id
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conformance() {
        assert_eq!(
            Filter::standard(0x800).check(),
            Err(FilterError::IdOutOfRange)
        );
        assert_eq!(
            Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, 0x800).check(),
            Err(FilterError::IdOutOfRange)
        );
        assert_eq!(
            Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, 0x001).check(),
            Err(FilterError::AcceptanceOutsideMask)
        );
        assert_eq!(
            Filter::masked(FrameKind::Data, Format::Extended, 0x3FFF_FFFF, 0).check(),
            Err(FilterError::MaskOutOfRange)
        );
        assert_eq!(
            Filter::masked(FrameKind::Any, Format::Any, 1, 1).check(),
            Err(FilterError::AnyFormatWithIdentifier)
        );
        assert_eq!(Filter::extended(0x1FFF_FFFF).check(), Ok(()));
        assert_eq!(Filter::pass_all().check(), Ok(()));
        assert_eq!(
            Filter::kind_format(FrameKind::Remote, Format::Any).check(),
            Ok(())
        );
    }

    #[test]
    fn matching() {
        let f = Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, 0x120);
        assert!(f.matches(&Frame::standard(0x12F, &[]).unwrap()));
        assert!(!f.matches(&Frame::standard(0x130, &[]).unwrap()));
        assert!(!f.matches(&Frame::extended(0x120, &[]).unwrap()));
        let remote = Frame::new_remote(crate::frame::standard_id(0x120).unwrap(), 0).unwrap();
        assert!(!f.matches(&remote));
        assert!(Filter::pass_all().matches(&remote));
        assert!(Filter::kind_format(FrameKind::Remote, Format::Any).matches(&remote));
    }

    const CONST_FILTER: Filter = Filter::extended(0x1234);
    const _: () = assert!(CONST_FILTER.check().is_ok());
}
