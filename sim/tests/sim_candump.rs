//! The trace of the simulated bus in candump log format.

use twocan_core::Frame;
use twocan_sim::{frame_bits, Bus, Fault, SimNode};

fn ts(us: u64) -> String {
    format!("({:010}.{:06})", us / 1_000_000, us % 1_000_000)
}

#[test]
fn candump_lines() {
    let mut bus = Bus::new(500_000).unwrap(); // 2 µs per bit
    let (a, b) = (SimNode::new().shared(), SimNode::new().shared());
    bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    let frames = [
        Frame::standard(0x123, &[0xDE, 0xAD, 0xBE, 0xEF]).unwrap(),
        Frame::extended(0x1ABC_DEF0, &[0x01, 0x02]).unwrap(),
        Frame::remote(0x123, false, 0).unwrap(),
        Frame::remote(0x7FF, false, 4).unwrap(),
        Frame::standard(0x001, &[]).unwrap(),
        Frame::remote(0x0000_0ABC, true, 8).unwrap(),
    ];
    for f in frames {
        a.borrow_mut().send(f);
    }
    bus.run_until_idle(10_000).unwrap();

    let texts = [
        "123#DEADBEEF",
        "1ABCDEF0#0102",
        "123#R",
        "7FF#R4",
        "001#",
        "00000ABC#R8",
    ];
    let mut expected = String::new();
    let mut t = 0;
    for (f, text) in frames.iter().zip(texts) {
        expected.push_str(&format!("{} can0 {}\n", ts(t * 2), text));
        t += u64::from(frame_bits(f).total_with_intermission);
    }
    let mut out = Vec::new();
    bus.trace().write_candump(&mut out, "can0").unwrap();
    assert_eq!(String::from_utf8(out).unwrap(), expected);
    assert_eq!(bus.trace().candump_string("can0"), expected);

    // The first line, spelled out.
    assert!(expected.starts_with("(0000000000.000000) can0 123#DEADBEEF\n"));
}

#[test]
fn error_frames_only_in_the_variant_with_errors() {
    let mut bus = Bus::new(1_000_000).unwrap(); // 1 µs per bit
    let (a, b) = (SimNode::new().shared(), SimNode::new().shared());
    bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    let f = Frame::standard(0x100, &[0x11]).unwrap();
    a.borrow_mut().send(f);
    bus.inject_next(Fault::Ack);
    bus.run_until_idle(10_000).unwrap();

    let recs = bus.trace().records();
    assert_eq!(recs.len(), 2);
    let ack_slot = u64::from(frame_bits(&f).crc_end) + 1;
    let plain = bus.trace().candump_string("can1");
    assert_eq!(plain, format!("{} can1 100#11\n", ts(recs[1].sof)));

    let mut out = Vec::new();
    bus.trace()
        .write_candump_with_errors(&mut out, "can1")
        .unwrap();
    // CAN_ERR_FLAG | CAN_ERR_ACK | CAN_ERR_PROT | CAN_ERR_BUSERROR; data[2] = CAN_ERR_PROT_TX,
    // data[3] = CAN_ERR_PROT_LOC_ACK.
    let expected = format!(
        "{} can1 200000A8#0000801900000000\n{} can1 100#11\n",
        ts(ack_slot),
        ts(recs[1].sof)
    );
    assert_eq!(String::from_utf8(out).unwrap(), expected);
}

/// Every line has the shape python-can's `CanutilsLogReader` and can-utils' `canplayer`
/// parse: `(secs.micros) iface id#data`.
#[test]
fn lines_parse_like_candump_readers_expect() {
    let mut bus = Bus::new(250_000).unwrap();
    let (a, b) = (SimNode::new().shared(), SimNode::new().shared());
    bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    for i in 0..20u32 {
        let f = match i % 3 {
            0 => Frame::standard((i * 37) as u16 & 0x7FF, &[i as u8; 3]).unwrap(),
            1 => Frame::extended(i.wrapping_mul(0x0123_4567) & 0x1FFF_FFFF, &[]).unwrap(),
            _ => Frame::remote(i, i % 2 == 0, (i % 9) as u8).unwrap(),
        };
        a.borrow_mut().send(f);
    }
    bus.run_until_idle(100_000).unwrap();
    let text = bus.trace().candump_string("vcan0");
    let mut last = 0.0f64;
    for (line, rec) in text.lines().zip(bus.trace().records()) {
        let mut parts = line.split(' ');
        let stamp = parts.next().unwrap();
        assert_eq!(parts.next(), Some("vcan0"));
        let frame = parts.next().unwrap();
        assert!(parts.next().is_none());
        let secs: f64 = stamp
            .trim_start_matches('(')
            .trim_end_matches(')')
            .parse()
            .unwrap();
        assert!(secs >= last);
        last = secs;
        let (id, data) = frame.split_once('#').unwrap();
        assert!(id.len() == 3 || id.len() == 8);
        assert_eq!(id.len() == 8, rec.frame.is_extended());
        assert_eq!(u32::from_str_radix(id, 16).unwrap(), rec.frame.raw_id());
        if let Some(dlc) = data.strip_prefix('R') {
            assert!(rec.frame.is_remote());
            let dlc: u8 = if dlc.is_empty() {
                0
            } else {
                dlc.parse().unwrap()
            };
            assert_eq!(dlc, rec.frame.dlc());
        } else {
            assert_eq!(data.len(), 2 * rec.frame.data().len());
            assert!(data
                .chars()
                .all(|c| c.is_ascii_digit() || ('A'..='F').contains(&c)));
        }
    }
    assert_eq!(text.lines().count(), 20);
}
