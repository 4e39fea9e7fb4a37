//! Frame lengths, bit stuffing and CRC-15 of the simulated bus.

use twocan_core::Frame;
use twocan_sim::bits::{crc15_bytes, max_stuff_bits, stuff, wire_bits, INTERMISSION_BITS};
use twocan_sim::{crc15, frame_bits};

fn std_frame(id: u16, data: &[u8]) -> Frame {
    Frame::standard(id, data).unwrap()
}

fn ext_frame(id: u32, data: &[u8]) -> Frame {
    Frame::extended(id, data).unwrap()
}

#[test]
fn crc15_check_value() {
    // CRC-15/CAN: poly 0x4599, init 0, no reflection, no final XOR; check("123456789") = 0x059E.
    assert_eq!(crc15_bytes(b"123456789"), 0x059E);
    assert_eq!(crc15([true]), 0x4599);
    assert_eq!(crc15([false, true]), 0x4599);
    assert_eq!(crc15([true, false]), ((0x4599 << 1) & 0x7FFF) ^ 0x4599);
}

/// Values checked against a separate throw-away implementation written from the standard's
/// description (CRC register shifted MSB-first, stuffing after five equal bits).
#[test]
fn known_vectors() {
    struct V {
        frame: Frame,
        crc: u16,
        stuff: u32,
        unstuffed: u32,
    }
    let vectors = [
        V {
            frame: std_frame(0, &[]),
            crc: 0,
            stuff: 6,
            unstuffed: 44,
        },
        V {
            frame: std_frame(0, &[0; 8]),
            crc: 5211,
            stuff: 16,
            unstuffed: 108,
        },
        V {
            frame: std_frame(0x123, &[0xDE, 0xAD, 0xBE, 0xEF]),
            crc: 20075,
            stuff: 2,
            unstuffed: 76,
        },
        V {
            frame: std_frame(0x7FF, &[0xFF; 8]),
            crc: 19593,
            stuff: 15,
            unstuffed: 108,
        },
        V {
            frame: std_frame(0x555, &[0x55; 8]),
            crc: 6916,
            stuff: 1,
            unstuffed: 108,
        },
        V {
            frame: ext_frame(0, &[0; 8]),
            crc: 15791,
            stuff: 19,
            unstuffed: 128,
        },
        V {
            frame: ext_frame(0x1ABC_DEF0, &[1, 2, 3]),
            crc: 1848,
            stuff: 5,
            unstuffed: 88,
        },
        V {
            frame: ext_frame(0x1FFF_FFFF, &[0xFF; 8]),
            crc: 7017,
            stuff: 18,
            unstuffed: 128,
        },
        V {
            frame: Frame::remote(0x123, false, 4).unwrap(),
            crc: 17234,
            stuff: 0,
            unstuffed: 44,
        },
    ];
    for v in vectors {
        let b = frame_bits(&v.frame);
        assert_eq!(b.crc, v.crc, "{:?}", v.frame);
        assert_eq!(b.stuff_bits, v.stuff, "{:?}", v.frame);
        assert_eq!(b.unstuffed, v.unstuffed, "{:?}", v.frame);
        assert_eq!(b.total, v.unstuffed + v.stuff);
        assert_eq!(b.total_with_intermission, b.total + 3);
    }
}

#[test]
fn id0_dlc0_is_44_bits_plus_6_stuff_bits() {
    // Worked by hand in the sim::bits module comment.
    let b = frame_bits(&std_frame(0, &[]));
    assert_eq!(
        (
            b.unstuffed,
            b.stuff_bits,
            b.total,
            b.total_with_intermission
        ),
        (44, 6, 50, 53)
    );
}

#[test]
fn minimum_frame_is_47_bit_times_unstuffed() {
    let b = frame_bits(&std_frame(0x2AA, &[]));
    assert_eq!(b.unstuffed + INTERMISSION_BITS, 47);
    let r = frame_bits(&Frame::remote(0x2AA, false, 8).unwrap());
    assert_eq!(r.unstuffed, 44);
}

#[test]
fn all_zero_payload_worst_case() {
    // All-zero bytes: a recessive stuff bit after every fifth dominant bit.
    let b = frame_bits(&std_frame(0, &[0; 8]));
    assert_eq!(b.stuff_bits, 16);
    assert_eq!(b.total_with_intermission, 108 + 16 + 3);
    for n in 0..=8usize {
        let s = frame_bits(&std_frame(0, &[0; 8][..n]));
        assert!(s.stuff_bits <= max_stuff_bits(false, n as u8));
        let e = frame_bits(&ext_frame(0, &[0; 8][..n]));
        assert!(e.stuff_bits <= max_stuff_bits(true, n as u8));
    }
    // In the data field: DLC 8 ends in three zeros, so the first stuff bit comes after two
    // data zeros, then one after every five: 1 + 62 / 5 = 13 stuff bits among 64 zeros.
    let (wire, b) = wire_bits(&std_frame(0x7FF, &[0; 8]));
    let data = &wire[b.control_end as usize..b.data_end as usize];
    assert_eq!(data.iter().filter(|&&x| !x).count(), 64);
    assert_eq!(data.iter().filter(|&&x| x).count(), 13);
    // The bound is reached only when stuff bits start runs of four (00000 1111 0000 1111 ...),
    // which all-zero data does not do.
    assert!(b.stuff_bits < max_stuff_bits(false, 8));
}

#[test]
fn stuff_bits_count_toward_the_next_run() {
    // 00000 -> stuff 1, then 1111 joins the stuff bit: a run of five ones -> stuff 0.
    let out = stuff(&[false, false, false, false, false, true, true, true, true]);
    assert_eq!(out.len(), 11);
    assert!(out[5]);
    assert!(!out[10]);
}
