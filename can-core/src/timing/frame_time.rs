//! Worst-case frame durations, for bounding the waits a driver makes while a frame may be
//! on the bus (bxCAN INAK/SLAK acknowledgements, FlexCAN FRZACK/LPMACK).
//!
//! A controller asked to enter initialization, sleep or freeze mode finishes the frame in
//! flight first (RM0410 40.4.1 "Initialization mode": "the request is acknowledged ... after
//! the current CAN activity"; Kinetis "Freeze mode": "after the CAN bus becomes idle or
//! after the current frame"). A fixed iteration count that covers a short frame at
//! 1 Mbit/s expires long before the longest frame at 10 kbit/s or less, so the bounds here
//! are computed from the configured bit rate.
//!
//! Frame lengths (ISO 11898-1 §10.4, §10.5): the stuffed region runs from SOF to the end of
//! the CRC sequence; in the worst case a stuff bit follows the first 5 bits and then every
//! 4 bits, ⌊(n − 1) / 4⌋ stuff bits for an `n`-bit region. Then come the CRC delimiter,
//! the ACK slot and delimiter, 7 bits of end of frame and 3 of intermission.
//!
//! ```
//! use twocan_core::timing::frame_time::{
//!     bits_to_cycles, max_frame_bits, MAX_FRAME_BITS, MAX_FRAME_IN_FLIGHT_BITS,
//! };
//! assert_eq!(max_frame_bits(false, 8), 135);
//! assert_eq!(MAX_FRAME_BITS, 160); // extended, 8 data bytes
//! // The slowest exact ACAN bit rate, 2.5 kbit/s: a frame in flight lasts up to 76.4 ms,
//! // 13.75 million cycles of a 180 MHz core.
//! assert_eq!(bits_to_cycles(MAX_FRAME_IN_FLIGHT_BITS, 2_500, 180_000_000), Ok(13_752_000));
//! ```

/// Bits from SOF to the end of the CRC sequence, before stuffing, for an identifier
/// format and a data field of `data_len` bytes (0 for a remote frame): SOF, the
/// arbitration and control fields, the data, 15 CRC bits.
pub const fn unstuffed_region_bits(extended: bool, data_len: u8) -> u32 {
    // SOF 1 + ID 11 + RTR 1 + IDE 1 + r0 1 + DLC 4 = 19; extended adds SRR, ID 18, r1: 20.
    let header = if extended { 39 } else { 19 };
    let data = if data_len > 8 { 8 } else { data_len } as u32;
    header + 8 * data + 15
}

/// The most stuff bits an `n`-bit stuffed region can hold.
pub const fn max_stuff_bits(region_bits: u32) -> u32 {
    if region_bits == 0 {
        0
    } else {
        (region_bits - 1) / 4
    }
}

/// Bits after the CRC sequence: CRC delimiter 1, ACK slot 1, ACK delimiter 1, EOF 7,
/// intermission 3.
pub const TAIL_AND_INTERMISSION_BITS: u32 = 1 + 2 + 7 + 3;

/// The longest a frame of this format and data length can take on the bus, with the worst
/// stuffing and the intermission after it.
pub const fn max_frame_bits(extended: bool, data_len: u8) -> u32 {
    let region = unstuffed_region_bits(extended, data_len);
    region + max_stuff_bits(region) + TAIL_AND_INTERMISSION_BITS
}

/// The longest classical frame: extended identifier, 8 data bytes, worst stuffing,
/// intermission included (160 bits).
pub const MAX_FRAME_BITS: u32 = max_frame_bits(true, 8);

/// The longest error frame on a healthy bus: error flags of 6 bits that overlap into at
/// most 12 dominant bits, an 8-bit error delimiter and the intermission (ISO 11898-1
/// §10.4.4, §10.4.6.2).
pub const MAX_ERROR_FRAME_BITS: u32 = 12 + 8 + 3;

/// Suspend transmission of an error-passive transmitter (ISO 11898-1 §10.4.6.4).
pub const SUSPEND_TRANSMISSION_BITS: u32 = 8;

/// The bound for "the frame in flight" on a healthy bus: the longest frame, an error frame
/// after it (an error can still be detected in the end of frame) and the suspend
/// transmission of an error-passive node (191 bits).
pub const MAX_FRAME_IN_FLIGHT_BITS: u32 =
    MAX_FRAME_BITS + MAX_ERROR_FRAME_BITS + SUSPEND_TRANSMISSION_BITS;

/// A duration that cannot be computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrameTimeError {
    /// A bit rate of 0 bit/s.
    BitRateZero,
    /// A clock of 0 Hz.
    ClockZero,
}

impl core::fmt::Display for FrameTimeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            FrameTimeError::BitRateZero => "bit rate must be above 0 bit/s",
            FrameTimeError::ClockZero => "clock must be above 0 Hz",
        })
    }
}

impl core::error::Error for FrameTimeError {}

/// Clock cycles of `clock_hz` that `bits` bit times at `bit_rate` bit/s last, rounded up.
///
/// A wait loop that polls a register and gives up after this many iterations lasts at
/// least that long, since every iteration takes at least one cycle.
pub const fn bits_to_cycles(
    bits: u32,
    bit_rate: u32,
    clock_hz: u32,
) -> Result<u64, FrameTimeError> {
    if bit_rate == 0 {
        return Err(FrameTimeError::BitRateZero);
    }
    if clock_hz == 0 {
        return Err(FrameTimeError::ClockZero);
    }
    let num = bits as u64 * clock_hz as u64;
    Ok(num.div_ceil(bit_rate as u64))
}

/// Microseconds that `bits` bit times at `bit_rate` bit/s last, rounded up.
pub const fn bits_to_micros(bits: u32, bit_rate: u32) -> Result<u64, FrameTimeError> {
    bits_to_cycles(bits, bit_rate, 1_000_000)
}

/// A wait bound in polling iterations for "until the frame in flight is over": the
/// [`MAX_FRAME_IN_FLIGHT_BITS`] at `bit_rate`, in cycles of `cpu_hz`, times
/// `margin` (at least 1; 2 is a sensible default: it absorbs the acknowledge delay of
/// the controller's clock domain crossing).
pub const fn frame_in_flight_wait(
    bit_rate: u32,
    cpu_hz: u32,
    margin: u32,
) -> Result<u64, FrameTimeError> {
    let margin = if margin == 0 { 1 } else { margin } as u64;
    match bits_to_cycles(MAX_FRAME_IN_FLIGHT_BITS, bit_rate, cpu_hz) {
        Ok(c) => Ok(c.saturating_mul(margin)),
        Err(e) => Err(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_worst_case_lengths() {
        // The classical figures: standard 8 bytes 135 bits, extended 8 bytes 160 bits,
        // standard 0 bytes 55 bits (all with the 3-bit intermission).
        assert_eq!(max_frame_bits(false, 8), 135);
        assert_eq!(max_frame_bits(true, 8), 160);
        assert_eq!(max_frame_bits(false, 0), 55);
        assert_eq!(max_frame_bits(true, 0), 80);
        assert_eq!(max_frame_bits(true, 15), 160, "data length is at most 8");
        assert_eq!(MAX_FRAME_IN_FLIGHT_BITS, 191);
    }

    #[test]
    fn cycles_round_up_and_refuse_zero() {
        assert_eq!(bits_to_cycles(1, 3, 10), Ok(4));
        assert_eq!(bits_to_cycles(160, 1_000_000, 216_000_000), Ok(34_560));
        assert_eq!(bits_to_cycles(1, 0, 1), Err(FrameTimeError::BitRateZero));
        assert_eq!(bits_to_cycles(1, 1, 0), Err(FrameTimeError::ClockZero));
        assert_eq!(bits_to_micros(191, 2_500), Ok(76_400));
        assert_eq!(
            frame_in_flight_wait(2_500, 16_000_000, 2),
            Ok(2 * 1_222_400)
        );
        assert_eq!(frame_in_flight_wait(2_500, 16_000_000, 0), Ok(1_222_400));
    }

    #[test]
    fn a_fixed_short_frame_bound_is_too_short_at_the_slowest_rates() {
        // 18 ms (the old bxCAN bound) covers a frame in flight only above ~10.6 kbit/s.
        let at = |rate| bits_to_micros(MAX_FRAME_IN_FLIGHT_BITS, rate).unwrap();
        assert!(at(10_000) > 18_000);
        assert!(at(125_000) < 18_000);
    }

    #[test]
    fn frame_time_error_is_an_error_with_a_message() {
        fn as_error(e: &dyn core::error::Error) -> std::string::String {
            std::format!("{e}")
        }
        assert_eq!(
            as_error(&FrameTimeError::BitRateZero),
            "bit rate must be above 0 bit/s"
        );
        assert_eq!(
            as_error(&FrameTimeError::ClockZero),
            "clock must be above 0 Hz"
        );
    }
}
