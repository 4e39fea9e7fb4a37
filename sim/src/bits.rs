//! The bit-level layout of a classical CAN frame: CRC-15, bit stuffing and exact lengths.
//!
//! Bits are `bool` with `true` = recessive (logical 1) and `false` = dominant (logical 0),
//! sent most significant bit first, as on the wire (ISO 11898-1 §10.4).
//!
//! Layout of a data or remote frame (unstuffed bit counts):
//!
//! ```text
//! standard: SOF 1 | ID[10:0] 11 | RTR 1 | IDE 1 | r0 1 | DLC 4 | data 8*n | CRC 15 | ...
//! extended: SOF 1 | ID[28:18] 11 | SRR 1 | IDE 1 | ID[17:0] 18 | RTR 1 | r1 1 | r0 1 | DLC 4
//!           | data 8*n | CRC 15 | ...
//! tail:     CRC delimiter 1 | ACK slot 1 | ACK delimiter 1 | EOF 7 | (intermission 3)
//! ```
//!
//! So a standard frame is `44 + 8n` bits and an extended one `64 + 8n` bits before stuffing,
//! not counting the 3-bit intermission. The CRC-15 (generator polynomial 0x4599, initial
//! value 0) covers the unstuffed bits from SOF to the end of the data field. Bit stuffing
//! covers SOF through the CRC sequence: after five equal consecutive bits the transmitter
//! inserts one bit of the opposite value, and that stuff bit starts the next run. A stuff
//! bit is also inserted after the last CRC bit when that bit completes a run of five.
//!
//! # A case computed by hand
//!
//! Standard data frame, identifier 0x000, DLC 0:
//!
//! ```text
//! SOF 0 | ID 00000000000 | RTR 0 | IDE 0 | r0 0 | DLC 0000            -> 19 dominant bits
//! CRC over 19 zero bits with initial value 0: every step shifts a zero register and
//! feeds a zero bit, so the XOR with 0x4599 never happens  -> CRC = 0x0000 (15 more zeros)
//! stuffed region = 34 dominant bits: a recessive stuff bit follows zeros no. 5, 10, 15,
//! 20, 25 and 30 (each stuff bit restarts the run; the last 4 zeros form no full run)
//!                                                          -> 6 stuff bits
//! unstuffed = 19 + 15 + 1 (CRC del) + 1 (ACK) + 1 (ACK del) + 7 (EOF) = 44
//! on the wire = 44 + 6 = 50 bits, 53 with the intermission.
//! ```

use twocan_core::frame::Frame;

/// The CRC-15 generator polynomial of classical CAN (x^15 + x^14 + x^10 + x^8 + x^7 + x^4 + x^3 + 1).
pub const CRC15_POLYNOMIAL: u16 = 0x4599;

/// Bits of the intermission that follows every frame and error frame.
pub const INTERMISSION_BITS: u32 = 3;

/// Bits from the CRC delimiter through the end of EOF (CRC del, ACK slot, ACK del, EOF).
pub const TAIL_BITS: u32 = 10;

/// CRC-15 of a bit sequence (`true` = 1), as computed by a CAN controller over the
/// unstuffed bits from SOF to the end of the data field.
pub fn crc15<I: IntoIterator<Item = bool>>(bits: I) -> u16 {
    let mut crc: u16 = 0;
    for bit in bits {
        let feedback = bit ^ (crc & 0x4000 != 0);
        crc = (crc << 1) & 0x7FFF;
        if feedback {
            crc ^= CRC15_POLYNOMIAL;
        }
    }
    crc
}

/// CRC-15 of whole bytes, most significant bit first (the "CRC-15/CAN" catalogue form:
/// the check value of the ASCII string `123456789` is `0x059E`).
pub fn crc15_bytes(bytes: &[u8]) -> u16 {
    crc15(
        bytes
            .iter()
            .flat_map(|b| (0..8).rev().map(move |i| (b >> i) & 1 == 1)),
    )
}

fn push_bits(out: &mut Vec<bool>, value: u32, count: u32) {
    for i in (0..count).rev() {
        out.push((value >> i) & 1 == 1);
    }
}

/// CRC-15 steps for one byte, most significant bit first, from a zero register.
const CRC15_TABLE: [u16; 256] = {
    let mut table = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = (i as u16) << 7;
        let mut k = 0;
        while k < 8 {
            c = if c & 0x4000 != 0 {
                ((c << 1) & 0x7FFF) ^ CRC15_POLYNOMIAL
            } else {
                (c << 1) & 0x7FFF
            };
            k += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
};

/// [`crc15`] of the `n` low bits of `word`, most significant first: the leading `n % 8`
/// bits one at a time, then whole bytes through [`CRC15_TABLE`].
fn crc15_word(word: u128, n: u32) -> u16 {
    let mut crc: u16 = 0;
    let lead = n % 8;
    for i in (n - lead..n).rev() {
        let feedback = ((word >> i) & 1 == 1) ^ (crc & 0x4000 != 0);
        crc = (crc << 1) & 0x7FFF;
        if feedback {
            crc ^= CRC15_POLYNOMIAL;
        }
    }
    let mut i = n - lead;
    while i >= 8 {
        i -= 8;
        let byte = (word >> i) as u8;
        crc = ((crc << 8) & 0x7FFF) ^ CRC15_TABLE[usize::from(((crc >> 7) as u8) ^ byte)];
    }
    crc
}

/// The unstuffed bits SOF..data as a word (last bit in bit 0) and their number.
fn header_word(frame: &Frame) -> (u128, u32) {
    let mut w: u128 = 0;
    let mut n = 0u32;
    let mut put = |value: u32, count: u32| {
        w = (w << count) | u128::from(value & ((1u64 << count) - 1) as u32);
        n += count;
    };
    let raw = frame.raw_id();
    put(0, 1); // SOF
    if frame.is_extended() {
        put(raw >> 18, 11);
        put(0b11, 2); // SRR, IDE
        put(raw & 0x3_FFFF, 18);
        put(u32::from(frame.is_remote()), 1); // RTR
        put(0, 2); // r1, r0
    } else {
        put(raw, 11);
        put(u32::from(frame.is_remote()) << 2, 3); // RTR, IDE, r0
    }
    put(u32::from(frame.dlc()), 4);
    for byte in frame.data() {
        put(u32::from(*byte), 8);
    }
    (w, n)
}

/// The unstuffed bits of a frame from SOF to the end of the data field (the CRC input).
pub fn unstuffed_header_and_data(frame: &Frame) -> Vec<bool> {
    let mut out = Vec::with_capacity(39 + 64);
    let raw = frame.raw_id();
    out.push(false); // SOF
    if frame.is_extended() {
        push_bits(&mut out, raw >> 18, 11);
        out.push(true); // SRR
        out.push(true); // IDE
        push_bits(&mut out, raw & 0x3_FFFF, 18);
        out.push(frame.is_remote()); // RTR
        out.push(false); // r1
        out.push(false); // r0
    } else {
        push_bits(&mut out, raw, 11);
        out.push(frame.is_remote()); // RTR
        out.push(false); // IDE
        out.push(false); // r0
    }
    push_bits(&mut out, u32::from(frame.dlc()), 4);
    for byte in frame.data() {
        push_bits(&mut out, u32::from(*byte), 8);
    }
    out
}

/// Stuffs a bit sequence: after five equal consecutive bits a complementary bit is inserted
/// (also after the last input bit). Returns the stuffed bits.
pub fn stuff(bits: &[bool]) -> Vec<bool> {
    let mut out = Vec::with_capacity(bits.len() + bits.len() / 4 + 1);
    let mut last = true;
    let mut run = 0u32;
    for &bit in bits {
        push_stuffed(&mut out, bit, &mut last, &mut run);
    }
    out
}

fn push_stuffed(out: &mut Vec<bool>, bit: bool, last: &mut bool, run: &mut u32) {
    out.push(bit);
    if bit == *last {
        *run += 1;
    } else {
        *last = bit;
        *run = 1;
    }
    if *run == 5 {
        out.push(!bit);
        *last = !bit;
        *run = 1;
    }
}

/// Exact bit lengths and field boundaries of one frame on the wire.
///
/// Positions are counts of wire (stuffed) bits from SOF: `arbitration_end` is the number of
/// wire bits up to and including the last arbitration bit (IDE for a standard frame, RTR for
/// an extended one), and so on. The CRC delimiter is wire bit number `crc_end` (0-based),
/// the ACK slot `crc_end + 1`, the ACK delimiter `crc_end + 2`, EOF `crc_end + 3 ..= crc_end + 9`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FrameBits {
    /// Bits from SOF through EOF without stuff bits (`44 + 8n` standard, `64 + 8n` extended).
    pub unstuffed: u32,
    /// Stuff bits inserted between SOF and the end of the CRC sequence.
    pub stuff_bits: u32,
    /// Bits on the wire from SOF through EOF: `unstuffed + stuff_bits`.
    pub total: u32,
    /// `total` plus the 3-bit intermission: the bus time the frame occupies.
    pub total_with_intermission: u32,
    /// The CRC-15 sent in the frame.
    pub crc: u16,
    /// Wire bits through the end of the arbitration field.
    pub arbitration_end: u32,
    /// Wire bits through the end of the control field (DLC).
    pub control_end: u32,
    /// Wire bits through the end of the data field.
    pub data_end: u32,
    /// Wire bits through the end of the CRC sequence, including a final stuff bit.
    pub crc_end: u32,
}

/// The wire bits of a frame from SOF through the CRC sequence (stuffed), plus its
/// [`FrameBits`]. The tail (delimiters, ACK, EOF) is not stuffed and not included.
pub fn wire_bits(frame: &Frame) -> (Vec<bool>, FrameBits) {
    // The unstuffed bits SOF..data, most significant first, in one word (at most 103 bits),
    // then the CRC over them: the same bits as `unstuffed_header_and_data`, without a
    // vector of booleans (this runs once per simulated frame).
    let (header, data_unstuffed) = header_word(frame);
    let crc = crc15_word(header, data_unstuffed);
    let (arb_unstuffed, ctrl_unstuffed) = if frame.is_extended() {
        (33, 39)
    } else {
        (14, 19)
    };
    let data_unstuffed = data_unstuffed as usize;
    let count = data_unstuffed + 15;
    // Left-aligned: the next bit is always bit 127 (at most 118 bits).
    let mut all = ((header << 15) | u128::from(crc)) << (128 - count);

    // At most 118 bits and 29 stuff bits: a fixed buffer, copied out once.
    let mut buf = [false; 160];
    let mut n = 0usize;
    let mut last = true;
    let mut run = 0u32;
    // Each field boundary is right after the field's last bit, before a stuff bit that may
    // follow it.
    let mut ends = [0u32; 4];
    let lengths = [
        arb_unstuffed,
        ctrl_unstuffed - arb_unstuffed,
        data_unstuffed - ctrl_unstuffed,
        15,
    ];
    let mut previous = 0;
    for (end, len) in ends.iter_mut().zip(lengths) {
        // An empty field (no data) ends where the one before it ends.
        *end = previous;
        for _ in 0..len {
            let bit = all >> 127 == 1;
            all <<= 1;
            buf[n] = bit;
            n += 1;
            if bit == last {
                run += 1;
            } else {
                last = bit;
                run = 1;
            }
            *end = n as u32;
            if run == 5 {
                buf[n] = !bit;
                n += 1;
                last = !bit;
                run = 1;
            }
        }
        previous = *end;
    }
    let out = buf[..n].to_vec();
    let [arbitration_end, control_end, data_end, _] = ends;
    let crc_end = n as u32;
    let unstuffed = data_unstuffed as u32 + 15 + TAIL_BITS;
    let stuff_bits = crc_end - (data_unstuffed as u32 + 15);
    let total = unstuffed + stuff_bits;
    let bits = FrameBits {
        unstuffed,
        stuff_bits,
        total,
        total_with_intermission: total + INTERMISSION_BITS,
        crc,
        arbitration_end,
        control_end,
        data_end,
        crc_end,
    };
    (out, bits)
}

/// Exact bit lengths of a frame (see [`FrameBits`]).
pub fn frame_bits(frame: &Frame) -> FrameBits {
    wire_bits(frame).1
}

/// The most stuff bits a frame of this format and data length can need:
/// `floor((control + 8n + 15 - 1) / 4)` where `control` is the unstuffed length of SOF
/// through DLC (19 standard, 39 extended) — the usual worst-case bound from the
/// stuffing rule (the first run needs 5 bits, every later one 4).
pub const fn max_stuff_bits(extended: bool, data_len: u8) -> u32 {
    let header = if extended { 39 } else { 19 };
    let stuffed = header + 8 * data_len as u32 + 15;
    (stuffed - 1) / 4
}

#[cfg(test)]
mod tests {
    use super::*;
    use twocan_core::frame::Frame;

    #[test]
    fn wire_bits_equals_stuffing_the_boolean_header_and_crc() {
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..3_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let len = (x % 9) as usize;
            let data: Vec<u8> = (0..len).map(|i| (x >> (8 * i)) as u8).collect();
            let f = match x % 4 {
                0 => Frame::standard((x >> 20) as u16 & 0x7FF, &data).unwrap(),
                1 => Frame::extended((x >> 20) as u32 & 0x1FFF_FFFF, &data).unwrap(),
                2 => Frame::remote((x >> 20) as u32 & 0x7FF, false, len as u8).unwrap(),
                _ => Frame::remote((x >> 20) as u32 & 0x1FFF_FFFF, true, len as u8).unwrap(),
            };
            // Every third frame with eight bytes carries a DLC code 9..=15 as written.
            let f = if f.data_len() == 8 && x.is_multiple_of(3) {
                let mut g = f;
                g.set_dlc(9 + (x >> 40) as u8 % 7).unwrap();
                g
            } else {
                f
            };
            let mut bits = unstuffed_header_and_data(&f);
            let crc = crc15(bits.iter().copied());
            bits.extend((0..15).rev().map(|i| (crc >> i) & 1 == 1));
            let (wire, layout) = wire_bits(&f);
            assert_eq!(wire, stuff(&bits), "{f:?}");
            assert_eq!(layout.crc, crc);
        }
    }

    #[test]
    fn crc_catalogue_check_value() {
        assert_eq!(crc15_bytes(b"123456789"), 0x059E);
        assert_eq!(crc15(core::iter::empty()), 0);
        assert_eq!(crc15([false; 40]), 0);
    }

    #[test]
    fn hand_computed_id0_dlc0() {
        let f = Frame::standard(0, &[]).unwrap();
        let (wire, b) = wire_bits(&f);
        assert_eq!(b.unstuffed, 44);
        assert_eq!(b.crc, 0);
        assert_eq!(b.stuff_bits, 6);
        assert_eq!(b.total, 50);
        assert_eq!(b.total_with_intermission, 53);
        assert_eq!(b.crc_end, 40);
        // 00000 1 00000 1 00000 1 00000 1 00000 1 00000 1 0000
        let mut expected = Vec::new();
        for _ in 0..6 {
            expected.extend([false; 5]);
            expected.push(true);
        }
        expected.extend([false; 4]);
        assert_eq!(wire, expected);
    }

    #[test]
    fn stuffing_counts_stuff_bits_in_runs() {
        // 5 zeros -> stuff 1; that 1 and four more 1s make a run of 5 -> stuff 0.
        let input = [false, false, false, false, false, true, true, true, true];
        let out = stuff(&input);
        assert_eq!(
            out,
            vec![false, false, false, false, false, true, true, true, true, true, false]
        );
        assert!(stuff(&[true, false, true, false]).len() == 4);
    }

    #[test]
    fn a_dlc_code_above_eight_is_sent_as_written_with_eight_bytes() {
        let data = [0x5A; 8];
        let eight = Frame::standard(0x123, &data).unwrap();
        let mut twelve = eight;
        twelve.set_dlc(12).unwrap();
        let bits = unstuffed_header_and_data(&twelve);
        // SOF, 11 identifier bits, RTR, IDE, r0, then the four DLC bits.
        let dlc: Vec<bool> = bits[15..19].to_vec();
        assert_eq!(dlc, vec![true, true, false, false]);
        assert_eq!(bits.len(), 19 + 64, "eight data bytes follow");
        assert_eq!(&bits[19..], &unstuffed_header_and_data(&eight)[19..]);
        let (a, b) = (frame_bits(&eight), frame_bits(&twelve));
        assert_eq!(a.unstuffed, b.unstuffed);
        assert_ne!(a.crc, b.crc, "the CRC covers the DLC code");
        let mut r = Frame::remote(0x123, false, 8).unwrap();
        r.set_dlc(15).unwrap();
        let bits = unstuffed_header_and_data(&r);
        assert_eq!(bits.len(), 19, "a remote frame has no data field");
        assert!(bits[15..19].iter().all(|&b| b));
    }

    #[test]
    fn unstuffed_lengths() {
        for n in 0..=8u8 {
            let data = [0x55u8; 8];
            let s = frame_bits(&Frame::standard(0x555, &data[..n as usize]).unwrap());
            assert_eq!(s.unstuffed, 44 + 8 * u32::from(n));
            let e = frame_bits(&Frame::extended(0x1555_5555, &data[..n as usize]).unwrap());
            assert_eq!(e.unstuffed, 64 + 8 * u32::from(n));
            let r = frame_bits(&Frame::remote(0x555, false, n).unwrap());
            assert_eq!(r.unstuffed, 44, "remote frames carry no data");
        }
        // The shortest frame occupies 47 bit times with its intermission, before stuffing.
        let min = frame_bits(&Frame::standard(0x555, &[]).unwrap());
        assert_eq!(min.unstuffed + INTERMISSION_BITS, 47);
    }

    #[test]
    fn field_boundaries_without_stuffing() {
        // Alternating identifier bits avoid stuffing in the arbitration field.
        let f = Frame::standard(0x555, &[]).unwrap();
        let b = frame_bits(&f);
        assert_eq!(b.arbitration_end, 14);
        let e = frame_bits(&Frame::extended(0x1555_5555, &[]).unwrap());
        assert!(e.arbitration_end >= 33);
        assert!(b.control_end >= 19 && b.data_end == b.control_end);
        assert_eq!(b.crc_end, b.total - TAIL_BITS);
    }

    #[test]
    fn all_zero_payload_stuffing_stays_within_the_bound() {
        for n in 0..=8u8 {
            let f = Frame::standard(0, &[0u8; 8][..n as usize]).unwrap();
            let b = frame_bits(&f);
            assert!(b.stuff_bits <= max_stuff_bits(false, n), "n={n} {b:?}");
            let f = Frame::extended(0, &[0u8; 8][..n as usize]).unwrap();
            let b = frame_bits(&f);
            assert!(b.stuff_bits <= max_stuff_bits(true, n), "n={n} {b:?}");
        }
        assert_eq!(max_stuff_bits(false, 8), 24);
        assert_eq!(max_stuff_bits(true, 8), 29);
    }

    #[test]
    fn no_six_equal_bits_on_the_wire() {
        let frames = [
            Frame::standard(0, &[0; 8]).unwrap(),
            Frame::standard(0x7FF, &[0xFF; 8]).unwrap(),
            Frame::extended(0x1FFF_FFFF, &[0xFF; 8]).unwrap(),
            Frame::extended(0, &[0; 8]).unwrap(),
            Frame::remote(0x7FF, false, 8).unwrap(),
        ];
        for f in frames {
            let (wire, b) = wire_bits(&f);
            assert_eq!(wire.len() as u32, b.crc_end);
            let mut run = 0;
            let mut last = None;
            for bit in wire {
                if Some(bit) == last {
                    run += 1;
                } else {
                    run = 1;
                    last = Some(bit);
                }
                assert!(run <= 5);
            }
        }
    }
}
