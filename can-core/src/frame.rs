//! CAN 2.0 frames: data and remote, standard and extended identifiers.
//!
//! [`Frame`] implements [`embedded_can::Frame`] and uses its [`Id`]. Its constructors check
//! every rule of the frame format and return a [`FrameError`] instead of panicking:
//! identifiers in range (11 or 29 bits), at most 8 data bytes, a DLC code `0..=15`
//! that agrees with the data, no data on a remote frame.
//!
//! A remote frame carries a DLC (the length of the answer it asks for) but no data bytes.
//!
//! **One DLC rule** ([`Frame::check_dlc`]), applied by every constructor and setter
//! that takes a code ([`Frame::remote`], [`Frame::new_remote`], the
//! `embedded_can::Frame::new_remote` of this type, [`Frame::with_dlc`],
//! [`Frame::set_dlc`], [`Frame::from_registers`]): the code fits the four-bit field
//! (`0..=15`, else [`FrameError::DlcTooLarge`]); a data frame's code agrees with its data
//! (`0..=8` equal to the number of bytes, `9..=15` with 8 bytes, else
//! [`FrameError::DlcMismatch`]); a remote frame takes any code (the length asked for is
//! `min(code, 8)`). [`Frame::from_words`], the backends' decoding fast path, masks
//! instead of checking and so lands on the same set of frames.
//!
//! The DLC is kept as written: ISO 11898-1 (classical CAN) gives the DLC field four
//! bits and says codes 9..=15 mean eight data bytes. A frame built with
//! [`Frame::with_dlc`] (or read from a mailbox holding such a code) keeps the code,
//! so it goes back onto the wire unchanged: [`Frame::dlc`] is the code, [`Frame::data`]
//! holds `min(code, 8)` bytes, and `embedded_can::Frame::dlc` — documented as
//! `0..=8` and equal to the data length of a data frame — returns that length.
//! The payload can be read as bytes or, as ACAN's data union offers, as little-endian
//! `u16`/`u32`/`u64` words (ACAN §8.1), without `unsafe`.

use embedded_can::{ExtendedId, Id, StandardId};

pub use crate::error::FrameError;

/// The largest data length of classical CAN, in bytes (and the largest DLC code that
/// is also a length).
pub const MAX_DLC: u8 = 8;

/// The largest DLC code the four-bit field holds (ISO 11898-1: 9..=15 mean 8 bytes).
pub const MAX_DLC_CODE: u8 = 15;

/// Builds a standard [`Id`] from a raw value, checking its range.
pub const fn standard_id(raw: u16) -> Result<Id, FrameError> {
    match StandardId::new(raw) {
        Some(id) => Ok(Id::Standard(id)),
        None => Err(FrameError::StandardIdOutOfRange(raw as u32)),
    }
}

/// Builds an extended [`Id`] from a raw value, checking its range.
pub const fn extended_id(raw: u32) -> Result<Id, FrameError> {
    match ExtendedId::new(raw) {
        Some(id) => Ok(Id::Extended(id)),
        None => Err(FrameError::ExtendedIdOutOfRange(raw)),
    }
}

/// The raw numeric value of an identifier (11 or 29 bits).
pub fn id_raw(id: &Id) -> u32 {
    match id {
        Id::Standard(s) => s.as_raw() as u32,
        Id::Extended(e) => e.as_raw(),
    }
}

/// Builds an [`Id`] from a raw value and a format flag, checking its range.
pub const fn raw_to_id(raw: u32, extended: bool) -> Result<Id, FrameError> {
    if extended {
        extended_id(raw)
    } else if raw > 0x7FF {
        Err(FrameError::StandardIdOutOfRange(raw))
    } else {
        standard_id(raw as u16)
    }
}

/// Whether an identifier is extended (29 bits).
pub const fn id_is_extended(id: &Id) -> bool {
    matches!(id, Id::Extended(_))
}

/// Bit of [`Frame`]'s identifier word marking an extended (29-bit) identifier.
const EXTENDED_BIT: u32 = 1 << 31;
/// Bit of [`Frame`]'s identifier word marking a remote frame.
const REMOTE_BIT: u32 = 1 << 30;
/// The identifier bits of [`Frame`]'s identifier word.
const ID_BITS: u32 = 0x1FFF_FFFF;

/// A classical CAN frame (data or remote), 16 bytes: one identifier word (29-bit
/// identifier, format and kind flags), eight data bytes and the DLC, so copies stay a
/// few word loads and stores (the data bytes are word-aligned: a mailbox register pair
/// is two aligned loads or stores).
///
/// Invariants kept by every constructor and setter: the identifier is in range for its
/// format, the DLC code is `0..=15` (the field as written; the data length is
/// `min(code, 8)`), data bytes beyond the data length (and all bytes of a remote frame)
/// are zero — so the derived equality compares identifier, kind, DLC code and data.
///
/// `Frame::default()` is a standard data frame with identifier 0 and no data.
///
/// ```
/// use twocan_core::{Frame, FrameError};
///
/// // Standard and extended data frames; the data length becomes the DLC.
/// let std_frame = Frame::standard(0x123, &[0xDE, 0xAD])?;
/// assert_eq!((std_frame.raw_id(), std_frame.is_extended()), (0x123, false));
/// assert_eq!((std_frame.dlc(), std_frame.data()), (2, &[0xDE, 0xAD][..]));
/// let ext = Frame::extended(0x1ABC_DEF0, &[1, 2, 3, 4, 5, 6, 7, 8])?;
/// assert!(ext.is_extended() && !ext.is_remote());
/// assert_eq!(ext.data_u32(1), Some(0x0807_0605)); // little-endian word 1 (bytes 4..8)
///
/// // A remote frame asks for `dlc` bytes and carries none.
/// let rtr = Frame::remote(0x7FF, false, 4)?;
/// assert!(rtr.is_remote());
/// assert_eq!((rtr.dlc(), rtr.data().len()), (4, 0));
///
/// // `const` construction.
/// const PING: Frame = match Frame::standard(0x010, &[]) {
///     Ok(f) => f,
///     Err(_) => panic!("bad frame"),
/// };
/// assert_eq!((PING.raw_id(), PING.dlc()), (0x010, 0));
/// assert_eq!(Frame::default(), Frame::standard(0, &[])?);
///
/// // Bad input is a typed error, never a panic.
/// assert_eq!(Frame::standard(0x800, &[]), Err(FrameError::StandardIdOutOfRange(0x800)));
/// assert_eq!(
///     Frame::extended(0x2000_0000, &[]),
///     Err(FrameError::ExtendedIdOutOfRange(0x2000_0000))
/// );
/// assert_eq!(Frame::standard(0x100, &[0; 9]), Err(FrameError::TooMuchData(9)));
/// assert_eq!(Frame::remote(0x100, false, 16), Err(FrameError::DlcTooLarge(16)));
/// let id = twocan_core::frame::standard_id(0x100)?;
/// assert_eq!(
///     Frame::with_dlc(id, &[1, 2], 3),
///     Err(FrameError::DlcMismatch { dlc: 3, len: 2 })
/// );
/// // DLC codes 9..=15 are kept as written, with 8 data bytes (ISO 11898-1); a remote
/// // frame with such a code asks for 8 bytes.
/// let long = Frame::with_dlc(id, &[0; 8], 15)?;
/// assert_eq!((long.dlc(), long.data().len()), (15, 8));
/// assert_eq!(Frame::remote(0x100, false, 9)?.len_from_dlc(), 8);
/// # Ok::<(), FrameError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[repr(C)]
pub struct Frame {
    word: u32,
    data: [u8; 8],
    dlc: u8,
}

#[cfg(feature = "defmt")]
impl defmt::Format for Frame {
    fn format(&self, f: defmt::Formatter) {
        if self.is_remote() {
            defmt::write!(
                f,
                "Frame {{ id: {:x}, ext: {}, remote, dlc: {} }}",
                self.raw_id(),
                self.is_extended(),
                self.dlc
            )
        } else {
            defmt::write!(
                f,
                "Frame {{ id: {:x}, ext: {}, data: {=[u8]:x} }}",
                self.raw_id(),
                self.is_extended(),
                self.data()
            )
        }
    }
}

/// The mask of the data bytes a data frame of DLC 0..=7 carries (that many), over the
/// little-endian 64-bit value of its eight data bytes (codes 8..=15 keep all eight,
/// ISO 11898-1 classic CAN).
const DATA_MASK: [u64; 8] = {
    let mut m = [0; 8];
    let mut n = 0;
    while n < 8 {
        m[n] = (1u64 << (8 * n)) - 1;
        n += 1;
    }
    m
};

impl Frame {
    /// The one DLC rule (module docs): whether a frame of this kind (`remote`) with
    /// `data_len` data bytes may carry the DLC code `dlc`. ISO 11898-1 (classical CAN):
    /// the DLC field has four bits; codes `0..=8` are the data length, `9..=15` mean
    /// eight bytes; a remote frame carries no data and any code (it asks for
    /// `min(code, 8)` bytes).
    ///
    /// ```
    /// use twocan_core::{Frame, FrameError};
    /// assert_eq!(Frame::check_dlc(true, 13, 0), Ok(()));
    /// assert_eq!(Frame::check_dlc(false, 13, 8), Ok(()));
    /// assert_eq!(Frame::check_dlc(false, 13, 7), Err(FrameError::DlcMismatch { dlc: 13, len: 7 }));
    /// assert_eq!(Frame::check_dlc(true, 16, 0), Err(FrameError::DlcTooLarge(16)));
    /// ```
    pub const fn check_dlc(remote: bool, dlc: u8, data_len: usize) -> Result<(), FrameError> {
        if dlc > MAX_DLC_CODE {
            return Err(FrameError::DlcTooLarge(dlc));
        }
        if remote {
            return Ok(());
        }
        let agrees = if dlc > MAX_DLC {
            data_len == MAX_DLC as usize
        } else {
            dlc as usize == data_len
        };
        if agrees {
            Ok(())
        } else {
            Err(FrameError::DlcMismatch { dlc, len: data_len })
        }
    }

    /// A data frame; `data.len()` becomes the DLC.
    pub fn new_data(id: Id, data: &[u8]) -> Result<Self, FrameError> {
        Self::data_frame(id, id_raw(&id), data)
    }

    const fn data_frame(id: Id, raw_id: u32, data: &[u8]) -> Result<Self, FrameError> {
        if data.len() > MAX_DLC as usize {
            return Err(FrameError::TooMuchData(data.len()));
        }
        let mut bytes = [0u8; 8];
        let mut i = 0;
        while i < data.len() {
            bytes[i] = data[i];
            i += 1;
        }
        Ok(Frame {
            word: Self::id_word(raw_id, id_is_extended(&id), false),
            dlc: data.len() as u8,
            data: bytes,
        })
    }

    /// A remote frame with the DLC code `dlc` (`0..=15`, [`Frame::check_dlc`]): it asks
    /// for `min(dlc, 8)` bytes.
    pub fn new_remote(id: Id, dlc: u8) -> Result<Self, FrameError> {
        Self::check_dlc(true, dlc, 0)?;
        Ok(Frame {
            word: Self::id_word(id_raw(&id), id_is_extended(&id), true),
            dlc,
            data: [0; 8],
        })
    }

    /// A remote frame with a raw identifier (`extended` selects 29 bits) and the DLC
    /// code `dlc` (`0..=15`, [`Frame::check_dlc`]).
    pub const fn remote(raw_id: u32, extended: bool, dlc: u8) -> Result<Self, FrameError> {
        if let Err(e) = raw_to_id(raw_id, extended) {
            return Err(e);
        }
        if let Err(e) = Self::check_dlc(true, dlc, 0) {
            return Err(e);
        }
        Ok(Frame {
            word: Self::id_word(raw_id, extended, true),
            dlc,
            data: [0; 8],
        })
    }

    /// A data frame with a standard identifier given as a raw number.
    pub const fn standard(raw_id: u16, data: &[u8]) -> Result<Self, FrameError> {
        match standard_id(raw_id) {
            Ok(id) => Self::data_frame(id, raw_id as u32, data),
            Err(e) => Err(e),
        }
    }

    /// A data frame with an extended identifier given as a raw number.
    pub const fn extended(raw_id: u32, data: &[u8]) -> Result<Self, FrameError> {
        match extended_id(raw_id) {
            Ok(id) => Self::data_frame(id, raw_id, data),
            Err(e) => Err(e),
        }
    }

    /// Builds a frame from the raw fields a controller register holds.
    ///
    /// `data` is always 8 bytes as read from a mailbox; bytes beyond the data length are
    /// ignored for a data frame and dropped for a remote frame. A DLC code of 9..=15 is
    /// kept as written (eight data bytes, ISO 11898-1); above 15 is an error (the field
    /// has four bits).
    pub fn from_raw_parts(
        id: Id,
        remote: bool,
        dlc: u8,
        data: [u8; 8],
    ) -> Result<Self, FrameError> {
        Self::from_registers(id_raw(&id), id_is_extended(&id), remote, dlc, data)
    }

    /// Like [`Frame::from_raw_parts`] with the identifier as a raw number.
    pub const fn from_registers(
        raw_id: u32,
        extended: bool,
        remote: bool,
        dlc: u8,
        data: [u8; 8],
    ) -> Result<Self, FrameError> {
        if let Err(e) = raw_to_id(raw_id, extended) {
            return Err(e);
        }
        // The register always holds 8 bytes: the data length is the one the code gives,
        // so only the field width can be wrong.
        let len = if dlc > MAX_DLC { MAX_DLC } else { dlc };
        let data_len = if remote { 0 } else { len as usize };
        if let Err(e) = Self::check_dlc(remote, dlc, data_len) {
            return Err(e);
        }
        let mut bytes = [0u8; 8];
        if !remote {
            let mut i = 0;
            while i < len as usize {
                bytes[i] = data[i];
                i += 1;
            }
        }
        Ok(Frame {
            word: Self::id_word(raw_id, extended, remote),
            dlc,
            data: bytes,
        })
    }

    /// Builds a frame from an identifier word as [`Frame::id_word`] packs it, a DLC and
    /// the eight data bytes, without re-checking the identifier: the fast path of a
    /// backend decoding its registers. The identifier bits are masked to 29 bits (11
    /// for a standard identifier), the DLC to its four bits and kept as written (ISO
    /// 11898-1: codes 9..=15 mean 8 bytes), bytes beyond the data length (all of them
    /// for a remote frame) are cleared, so every invariant holds whatever the inputs.
    #[inline]
    pub const fn from_words(word: u32, dlc: u8, data: [u8; 8]) -> Self {
        let extended = word & EXTENDED_BIT != 0;
        let id_mask = if extended { ID_BITS } else { 0x7FF };
        let word = word & (EXTENDED_BIT | REMOTE_BIT | id_mask);
        let dlc = dlc & MAX_DLC_CODE;
        // Bytes beyond the data length cleared: none for eight bytes (a compare),
        // else one mask over the little-endian 64-bit value, looked up by the DLC (a
        // load instead of shifts, a byte loop or a `memset` call); a remote frame
        // keeps none.
        let bytes = if word & REMOTE_BIT != 0 {
            [0; 8]
        } else if dlc >= MAX_DLC {
            data
        } else {
            (u64::from_le_bytes(data) & DATA_MASK[(dlc & 7) as usize]).to_le_bytes()
        };
        Frame {
            word,
            dlc,
            data: bytes,
        }
    }

    /// The identifier word of a frame: the raw identifier in bits 28..0, bit 31 set
    /// for an extended identifier, bit 30 for a remote frame.
    #[inline]
    pub const fn id_word(raw_id: u32, extended: bool, remote: bool) -> u32 {
        (raw_id & ID_BITS)
            | if extended { EXTENDED_BIT } else { 0 }
            | if remote { REMOTE_BIT } else { 0 }
    }

    /// This frame's identifier word (see [`Frame::id_word`]).
    #[inline]
    pub const fn word(&self) -> u32 {
        self.word
    }

    /// The identifier.
    pub const fn id(&self) -> Id {
        let raw = self.raw_id();
        if self.is_extended() {
            // SAFETY: every constructor keeps an extended identifier within 29 bits
            // (`from_words` masks it), the range `ExtendedId` requires.
            Id::Extended(unsafe { ExtendedId::new_unchecked(raw) })
        } else {
            // SAFETY: every constructor keeps a standard identifier within 11 bits
            // (`from_words` masks it), the range `StandardId` requires.
            Id::Standard(unsafe { StandardId::new_unchecked(raw as u16) })
        }
    }

    /// The raw identifier value (11 or 29 bits).
    #[inline]
    pub const fn raw_id(&self) -> u32 {
        self.word & ID_BITS
    }

    /// Whether the identifier is extended.
    #[inline]
    pub const fn is_extended(&self) -> bool {
        self.word & EXTENDED_BIT != 0
    }

    /// Whether this is a remote frame.
    #[inline]
    pub const fn is_remote(&self) -> bool {
        self.word & REMOTE_BIT != 0
    }

    /// The data length code as written, `0..=15` (9..=15 only when built with
    /// [`Frame::with_dlc`]/[`Frame::set_dlc`] or read from a mailbox holding such a
    /// code). `embedded_can::Frame::dlc` returns [`Frame::len_from_dlc`] instead.
    #[inline]
    pub const fn dlc(&self) -> u8 {
        self.dlc
    }

    /// The length the DLC stands for: `min(dlc, 8)` (ISO 11898-1). For a data frame
    /// this is the number of data bytes; for a remote frame, the length asked for.
    #[inline]
    pub const fn len_from_dlc(&self) -> u8 {
        if self.dlc > MAX_DLC {
            MAX_DLC
        } else {
            self.dlc
        }
    }

    /// The number of data bytes (`min(dlc, 8)`, 0 for a remote frame).
    #[inline]
    pub const fn data_len(&self) -> usize {
        if self.is_remote() {
            0
        } else {
            self.len_from_dlc() as usize
        }
    }

    /// A data frame with an explicit DLC code: `dlc` `0..=8` must equal `data.len()`,
    /// `9..=15` needs exactly 8 data bytes (ISO 11898-1: such codes mean 8 bytes and
    /// are sent as written). Anything else is a [`FrameError`].
    pub fn with_dlc(id: Id, data: &[u8], dlc: u8) -> Result<Self, FrameError> {
        let mut f = Self::new_data(id, data)?;
        f.set_dlc(dlc)?;
        Ok(f)
    }

    /// Sets the DLC code, keeping the data, by [`Frame::check_dlc`]: a data frame
    /// accepts its own data length (`0..=8`) or, with 8 data bytes, any code `9..=15`; a
    /// remote frame accepts any code `0..=15` (the length asked for is `min(code, 8)`).
    /// Above 15 is [`FrameError::DlcTooLarge`]; a code that disagrees with the data is
    /// [`FrameError::DlcMismatch`]. The frame is unchanged on error.
    pub fn set_dlc(&mut self, dlc: u8) -> Result<(), FrameError> {
        Self::check_dlc(self.is_remote(), dlc, self.data_len())?;
        self.dlc = dlc;
        Ok(())
    }

    /// The data bytes (empty for a remote frame; `min(dlc, 8)` bytes otherwise).
    pub fn data(&self) -> &[u8] {
        &self.data[..self.data_len()]
    }

    /// All eight data bytes, zero beyond the DLC (what a mailbox register pair holds).
    pub const fn data_padded(&self) -> [u8; 8] {
        self.data
    }

    /// Data byte `index`, if it lies within the DLC of a data frame.
    pub fn byte(&self, index: usize) -> Option<u8> {
        self.data().get(index).copied()
    }

    /// Sets data byte `index` (within the DLC of a data frame).
    pub fn set_byte(&mut self, index: usize, value: u8) -> Result<(), FrameError> {
        if self.is_remote() {
            return Err(FrameError::DataOnRemoteFrame);
        }
        if index >= self.data_len() {
            return Err(FrameError::OutOfBounds);
        }
        self.data[index] = value;
        Ok(())
    }

    /// Replaces the payload (and DLC: the new data length) of a data frame.
    pub fn set_data(&mut self, data: &[u8]) -> Result<(), FrameError> {
        if self.is_remote() {
            return Err(FrameError::DataOnRemoteFrame);
        }
        *self = Self::new_data(self.id(), data)?;
        Ok(())
    }

    fn data_word<const W: usize>(&self, index: usize) -> Option<[u8; W]> {
        let start = index.checked_mul(W)?;
        let end = start.checked_add(W)?;
        let bytes = self.data().get(start..end)?;
        let mut out = [0u8; W];
        out.copy_from_slice(bytes);
        Some(out)
    }

    fn set_word<const W: usize>(&mut self, index: usize, bytes: [u8; W]) -> Result<(), FrameError> {
        if self.is_remote() {
            return Err(FrameError::DataOnRemoteFrame);
        }
        let start = index.checked_mul(W).ok_or(FrameError::OutOfBounds)?;
        let end = start.checked_add(W).ok_or(FrameError::OutOfBounds)?;
        if end > self.data_len() {
            return Err(FrameError::OutOfBounds);
        }
        self.data[start..end].copy_from_slice(&bytes);
        Ok(())
    }

    /// Little-endian 16-bit word `index` (bytes `2*index..2*index+2`), if within the DLC.
    pub fn data_u16(&self, index: usize) -> Option<u16> {
        self.data_word::<2>(index).map(u16::from_le_bytes)
    }

    /// Little-endian 32-bit word `index` (bytes `4*index..4*index+4`), if within the DLC.
    pub fn data_u32(&self, index: usize) -> Option<u32> {
        self.data_word::<4>(index).map(u32::from_le_bytes)
    }

    /// The eight bytes as one little-endian 64-bit word, if the DLC is 8.
    pub fn data_u64(&self) -> Option<u64> {
        self.data_word::<8>(0).map(u64::from_le_bytes)
    }

    /// Writes little-endian 16-bit word `index` (must lie within the DLC).
    pub fn set_data_u16(&mut self, index: usize, value: u16) -> Result<(), FrameError> {
        self.set_word(index, value.to_le_bytes())
    }

    /// Writes little-endian 32-bit word `index` (must lie within the DLC).
    pub fn set_data_u32(&mut self, index: usize, value: u32) -> Result<(), FrameError> {
        self.set_word(index, value.to_le_bytes())
    }

    /// Writes the 64-bit little-endian payload (the DLC must be 8).
    pub fn set_data_u64(&mut self, value: u64) -> Result<(), FrameError> {
        self.set_word(0, value.to_le_bytes())
    }
}

impl embedded_can::Frame for Frame {
    fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        Self::new_data(id.into(), data).ok()
    }

    fn new_remote(id: impl Into<Id>, dlc: usize) -> Option<Self> {
        let dlc = u8::try_from(dlc).ok()?;
        Frame::new_remote(id.into(), dlc).ok()
    }

    fn is_extended(&self) -> bool {
        Frame::is_extended(self)
    }

    fn is_remote_frame(&self) -> bool {
        self.is_remote()
    }

    fn id(&self) -> Id {
        Frame::id(self)
    }

    /// The length the DLC stands for, `0..=8` as this trait documents (for a data
    /// frame, the data length): a DLC code of 9..=15 reads as 8 here; the code as
    /// written is [`Frame::dlc`].
    fn dlc(&self) -> usize {
        self.len_from_dlc() as usize
    }

    fn data(&self) -> &[u8] {
        Frame::data(self)
    }
}

// The sizes `docs/differences.md` states (ACAN's `CANMessage` is 16 bytes), checked on
// every target the crate builds for.
const _: () = assert!(core::mem::size_of::<Frame>() == 16);
const _: () = assert!(core::mem::size_of::<RxFrame>() == 32);

/// A frame taken from a controller, with where and when it was accepted (32 bytes: the
/// 16-byte [`Frame`], two 16-bit indices and an 8-byte optional time stamp).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RxFrame {
    /// The frame itself.
    pub frame: Frame,
    /// The index of the user's filter that accepted it (after the backend mapped the
    /// hardware match index back to the order in which the user listed filters).
    pub filter: u16,
    /// When the frame was on the bus, where the controller records it (FlexCAN always;
    /// bxCAN with TTCM only, `None` otherwise): the 16-bit bit-time counter at the
    /// frame's start, extended by the driver on the interrupt side
    /// ([`crate::timestamp`]).
    pub timestamp: Option<crate::timestamp::Timestamp>,
    /// The hardware's own match index, for users who want it next to the portable
    /// [`RxFrame::filter`]: bxCAN `CAN_RDTxR.FMI` with the FIFO number in bit 8,
    /// FlexCAN `RXFIR.IDHIT` (decoded for bxCAN by `twocan_bxcan::fmi`).
    pub hw_match: u16,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dlc_and_ids_are_checked() {
        assert_eq!(
            Frame::standard(0x800, &[]),
            Err(FrameError::StandardIdOutOfRange(0x800))
        );
        assert_eq!(
            Frame::extended(0x2000_0000, &[]),
            Err(FrameError::ExtendedIdOutOfRange(0x2000_0000))
        );
        assert_eq!(
            Frame::standard(0x7FF, &[0; 9]),
            Err(FrameError::TooMuchData(9))
        );
        let id = standard_id(1).unwrap();
        assert_eq!(Frame::new_remote(id, 16), Err(FrameError::DlcTooLarge(16)));
        assert_eq!(Frame::new_remote(id, 9).map(|f| f.len_from_dlc()), Ok(8));
        assert!(Frame::new_remote(id, 8).is_ok());
    }

    #[test]
    fn remote_frame_has_dlc_but_no_data() {
        let mut f = Frame::new_remote(standard_id(0x123).unwrap(), 4).unwrap();
        assert_eq!(f.dlc(), 4);
        assert!(f.data().is_empty());
        assert_eq!(f.set_byte(0, 1), Err(FrameError::DataOnRemoteFrame));
        assert_eq!(f.set_data(&[1]), Err(FrameError::DataOnRemoteFrame));
        assert_eq!(f.set_data_u16(0, 1), Err(FrameError::DataOnRemoteFrame));
        let raw = Frame::from_raw_parts(f.id(), true, 4, [9; 8]).unwrap();
        assert_eq!(raw.data_padded(), [0; 8]);
    }

    #[test]
    fn little_endian_views() {
        let mut f = Frame::extended(0x1234_5678, &[0; 8]).unwrap();
        f.set_data_u64(0x0807_0605_0403_0201).unwrap();
        assert_eq!(f.data(), &[1, 2, 3, 4, 5, 6, 7, 8]);
        assert_eq!(f.data_u16(0), Some(0x0201));
        assert_eq!(f.data_u16(3), Some(0x0807));
        assert_eq!(f.data_u16(4), None);
        assert_eq!(f.data_u32(1), Some(0x0807_0605));
        f.set_data_u32(0, 0xAABB_CCDD).unwrap();
        assert_eq!(f.byte(0), Some(0xDD));
        let mut short = Frame::standard(1, &[1, 2, 3]).unwrap();
        assert_eq!(short.data_u32(0), None);
        assert_eq!(short.data_u64(), None);
        assert_eq!(short.set_data_u32(0, 5), Err(FrameError::OutOfBounds));
        assert_eq!(
            short.set_data_u16(usize::MAX, 5),
            Err(FrameError::OutOfBounds)
        );
        assert_eq!(short.data_u16(usize::MAX), None);
    }

    #[test]
    fn embedded_can_trait() {
        use embedded_can::Frame as _;
        let id = StandardId::new(0x10).unwrap();
        assert!(<Frame as embedded_can::Frame>::new(id, &[0; 9]).is_none());
        assert!(<Frame as embedded_can::Frame>::new_remote(id, 16).is_none());
        // A code of 9..=15 is a valid remote request for 8 bytes; the trait reads 8.
        let r = <Frame as embedded_can::Frame>::new_remote(id, 9).unwrap();
        assert_eq!((r.dlc(), embedded_can::Frame::dlc(&r)), (9, 8));
        assert!(<Frame as embedded_can::Frame>::new_remote(id, usize::MAX).is_none());
        let f = <Frame as embedded_can::Frame>::new(id, &[1, 2]).unwrap();
        assert_eq!(embedded_can::Frame::dlc(&f), 2);
        assert!(!f.is_remote_frame());
        assert!(f.is_data_frame());
        assert!(!embedded_can::Frame::is_extended(&f));
    }

    #[test]
    fn from_words_clears_beyond_the_data_keeps_the_code_and_masks() {
        let all = [0xA1, 0xA2, 0xA3, 0xA4, 0xA5, 0xA6, 0xA7, 0xA8];
        for dlc in 0..=15u8 {
            let f = Frame::from_words(Frame::id_word(0x123, false, false), dlc, all);
            let keep = dlc.min(8) as usize;
            assert_eq!(f.dlc(), dlc, "DLC {dlc} kept as written");
            assert_eq!(f.data(), &all[..keep]);
            let padded = f.data_padded();
            assert!(
                padded[keep..].iter().all(|&b| b == 0),
                "DLC {dlc}: {padded:?}"
            );
            let id = standard_id(0x123).unwrap();
            assert_eq!(f, Frame::with_dlc(id, &all[..keep], dlc).unwrap());
            assert_eq!(
                embedded_can::Frame::dlc(&f),
                keep,
                "the trait's DLC is the length"
            );
        }
        // Only the four bits of the field count.
        assert_eq!(Frame::from_words(0x123, 0x1C, all).dlc(), 0xC);
        // A remote frame keeps its DLC and no data.
        let r = Frame::from_words(Frame::id_word(0x1ABC_DEF1, true, true), 3, all);
        assert_eq!((r.dlc(), r.data_padded()), (3, [0; 8]));
        assert_eq!(r, Frame::remote(0x1ABC_DEF1, true, 3).unwrap());
        // Identifier bits beyond the format are dropped.
        let m = Frame::from_words(0x0000_FFFF, 0, all);
        assert_eq!(m.raw_id(), 0x7FF);
    }

    #[test]
    fn dlc_codes_above_eight_are_kept_as_written() {
        let id = standard_id(0x321).unwrap();
        let eight = [1, 2, 3, 4, 5, 6, 7, 8];
        for code in 9..=15u8 {
            let f = Frame::with_dlc(id, &eight, code).unwrap();
            assert_eq!((f.dlc(), f.len_from_dlc(), f.data_len()), (code, 8, 8));
            assert_eq!(f.data(), &eight);
            assert_eq!(f.data_u64(), Some(0x0807_0605_0403_0201));
            assert_ne!(
                f,
                Frame::new_data(id, &eight).unwrap(),
                "the code is part of the frame"
            );
            let raw = Frame::from_registers(0x321, false, false, code, eight).unwrap();
            assert_eq!(raw, f);
        }
        assert_eq!(
            Frame::with_dlc(id, &eight[..7], 9),
            Err(FrameError::DlcMismatch { dlc: 9, len: 7 })
        );
        assert_eq!(
            Frame::with_dlc(id, &eight[..3], 4),
            Err(FrameError::DlcMismatch { dlc: 4, len: 3 })
        );
        assert_eq!(
            Frame::with_dlc(id, &eight, 16),
            Err(FrameError::DlcTooLarge(16))
        );
        assert_eq!(
            Frame::from_registers(0x321, false, false, 16, eight),
            Err(FrameError::DlcTooLarge(16))
        );
        assert_eq!(Frame::with_dlc(id, &eight[..3], 3).unwrap().dlc(), 3);
        // set_dlc moves between 8 and 9..=15 and leaves the frame alone on error.
        let mut f = Frame::new_data(id, &eight).unwrap();
        f.set_dlc(15).unwrap();
        assert_eq!(f.dlc(), 15);
        assert_eq!(
            f.set_dlc(7),
            Err(FrameError::DlcMismatch { dlc: 7, len: 8 })
        );
        assert_eq!(f.dlc(), 15);
        f.set_dlc(8).unwrap();
        assert_eq!(f, Frame::new_data(id, &eight).unwrap());
        // set_data gives the frame the new length as its DLC.
        f.set_dlc(12).unwrap();
        f.set_data(&[9]).unwrap();
        assert_eq!((f.dlc(), f.data()), (1, &[9u8][..]));
        // A remote frame takes any code; the length asked for is min(code, 8).
        let mut r = Frame::new_remote(id, 2).unwrap();
        r.set_dlc(13).unwrap();
        assert_eq!((r.dlc(), r.len_from_dlc(), r.data_len()), (13, 8, 0));
        assert_eq!(embedded_can::Frame::dlc(&r), 8);
        assert!(r.data().is_empty());
        assert_eq!(r.set_dlc(16), Err(FrameError::DlcTooLarge(16)));
        assert_eq!(core::mem::size_of::<Frame>(), 16);
    }

    /// The sizes `docs/differences.md` states: `Frame` 16 bytes (ACAN's `CANMessage` is
    /// 16 bytes too, with `idx`), `RxFrame` 32 bytes (the frame, the user's filter index,
    /// the hardware match index and an 8-byte optional time stamp, 8-byte aligned).
    #[test]
    fn frame_sizes_are_the_documented_ones() {
        assert_eq!(core::mem::size_of::<Frame>(), 16);
        assert_eq!(core::mem::size_of::<RxFrame>(), 32);
        assert_eq!(core::mem::align_of::<RxFrame>(), 8);
    }

    /// Issue 22, item 10: one DLC rule, whatever builds or changes the frame. Every
    /// remote-frame constructor, `from_registers` and `set_dlc` give the same answer for
    /// every code; so do `with_dlc` and `set_dlc` for data frames of every length.
    #[test]
    fn one_dlc_rule_for_every_constructor() {
        let id = standard_id(0x123).unwrap();
        for dlc in 0..=16u8 {
            let by_remote = Frame::remote(0x123, false, dlc);
            let by_new_remote = Frame::new_remote(id, dlc);
            let by_trait = <Frame as embedded_can::Frame>::new_remote(id, dlc as usize);
            let by_registers = Frame::from_registers(0x123, false, true, dlc, [0; 8]);
            let by_set_dlc = Frame::remote(0x123, false, 0).and_then(|mut f| {
                f.set_dlc(dlc)?;
                Ok(f)
            });
            assert_eq!(by_remote, by_set_dlc, "remote, DLC {dlc}");
            assert_eq!(by_new_remote, by_set_dlc, "remote, DLC {dlc}");
            assert_eq!(by_registers, by_set_dlc, "remote, DLC {dlc}");
            assert_eq!(by_trait, by_set_dlc.ok(), "remote, DLC {dlc}");
            assert_eq!(by_set_dlc.is_ok(), dlc <= MAX_DLC_CODE, "remote, DLC {dlc}");
            for len in 0..=8usize {
                let data = &[0x5Au8; 8][..len];
                let by_with_dlc = Frame::with_dlc(id, data, dlc);
                let by_set_dlc = Frame::new_data(id, data).and_then(|mut f| {
                    f.set_dlc(dlc)?;
                    Ok(f)
                });
                assert_eq!(by_with_dlc, by_set_dlc, "data, DLC {dlc}, {len} bytes");
                let agrees = if dlc > MAX_DLC {
                    len == 8
                } else {
                    dlc as usize == len
                };
                assert_eq!(
                    by_set_dlc.is_ok(),
                    dlc <= MAX_DLC_CODE && agrees,
                    "data, DLC {dlc}, {len} bytes"
                );
            }
        }
    }

    #[test]
    fn equality_ignores_bytes_beyond_dlc() {
        let a = Frame::from_raw_parts(standard_id(5).unwrap(), false, 2, [1, 2, 3, 0, 0, 0, 0, 0]);
        let b = Frame::standard(5, &[1, 2]);
        assert_eq!(a, b);
    }
}
