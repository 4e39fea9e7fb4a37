//! The examples built with `--features defmt` log through `defmt-rtt`; the harness reads
//! the RTT up-channel from emulated RAM (control block `_SEGGER_RTT`) and decodes the
//! frames with the ELF's `.defmt` table. The decoded lines must say what the firmware
//! did: checked against its exported counters and the application's sending rule.

mod common;

use common::*;
use twocan_fil::rtt::{LogLine, Rtt};

/// The numbers of a line, in order (`"step 100: sent 144, ..."` gives 100, 144, ...).
fn numbers(line: &str) -> Vec<u32> {
    line.split(|c: char| !c.is_ascii_digit())
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().unwrap())
        .collect()
}

/// Timestamps (`ms` hint: seconds with three decimals) in milliseconds.
fn millis(l: &LogLine) -> u32 {
    let (s, ms) = l.timestamp.split_once('.').expect("timestamp s.mmm");
    s.parse::<u32>().unwrap() * 1000 + ms.parse::<u32>().unwrap()
}

#[test]
fn loopback_logs_its_start_and_every_frame_received() {
    for (board, bin, port) in [
        ("teensy36", "teensy-loopback-defmt", "CAN0"),
        ("nucleo-f767zi", "stm32f7-loopback-defmt", "CAN1"),
    ] {
        let Some(mut w) = world(500_000, &[(board, bin)]) else {
            return;
        };
        w.run_for(secs(3.2));
        assert_clean(&w);
        let m = &w.machines[0];
        assert!(m.image.defmt.is_some(), "{board}: .defmt table");
        let rtt = m.board().rtt.as_ref().expect("_SEGGER_RTT found");
        assert_eq!(rtt.error, None, "{board}");
        let lines = m.defmt_lines();
        let prefix = bin.trim_end_matches("-defmt");
        assert_eq!(
            lines[0].message,
            format!("{prefix}: {port} in loop-back, a frame every second"),
            "{board}: {lines:#?}"
        );
        assert!(lines.iter().all(|l| l.level == "info"), "{board}");
        let received = m.read_u32_static("RECEIVED").unwrap();
        assert_eq!(received, 3, "{board}");
        let frames: Vec<&LogLine> = lines[1..].iter().collect();
        assert_eq!(frames.len(), received as usize, "{board}: {lines:#?}");
        for (n, l) in frames.iter().enumerate() {
            assert_eq!(l.message, format!("loop-back frame {} received", n + 1));
        }
        // One frame a second, the first a second after the controller started (a few
        // milliseconds after the start-up line).
        let t: Vec<u32> = lines.iter().map(millis).collect();
        assert!((1000..1010).contains(&(t[1] - t[0])), "{board}: {t:?}");
        for d in t[1..].windows(2).map(|p| p[1] - p[0]) {
            assert!(d.abs_diff(1000) <= 1, "{board}: {t:?}");
        }
    }
}

#[test]
fn app_logs_its_configuration_and_counts() {
    let Some(mut w) = world(
        500_000,
        &[
            ("teensy36", "teensy-app-defmt"),
            ("nucleo-f767zi", "stm32f7-app-defmt"),
        ],
    ) else {
        return;
    };
    w.run_for(secs(2.05));
    assert_clean(&w);
    for (b, (bin, node, peer, port)) in
        [("teensy-app", 1, 2, "CAN0"), ("stm32f7-app", 2, 1, "CAN1")]
            .into_iter()
            .enumerate()
    {
        let m = &w.machines[b];
        let lines = m.defmt_lines();
        assert_eq!(
            lines[0].message,
            format!("{bin}: node {node}, peer {peer}, {port} at 500000 bit/s"),
            "{lines:#?}"
        );
        assert_eq!(
            lines[1].message,
            format!("{port} on the bus with the application's 4 filters")
        );
        // A count line every 100 steps (1 s): steps 100 and 200 by 2.05 s.
        let counts: Vec<Vec<u32>> = lines[2..]
            .iter()
            .map(|l| {
                assert!(l.message.starts_with("step "), "{bin}: {l}");
                numbers(&l.message)
            })
            .collect();
        assert_eq!(counts.len(), 2, "{bin}: {lines:#?}");
        for (k, c) in counts.iter().enumerate() {
            let [steps, sent, heartbeats, gaps, duplicates, measurements, requests, answers, full] =
                c[..]
            else {
                panic!("{bin}: {c:?}");
            };
            assert_eq!(steps, 100 * (k as u32 + 1));
            assert_eq!((gaps, duplicates, full), (0, 0, 0), "{bin}: {c:?}");
            // The peer steps as often; its last heartbeat may not be in yet.
            assert!(
                heartbeats + 2 >= steps && heartbeats <= steps,
                "{bin}: {c:?}"
            );
            // Received from the peer: its measurement every 4th step, its request every
            // 10th, its answers (the last may not be in yet).
            assert!(
                measurements + 1 >= steps / 4 && measurements <= steps / 4,
                "{bin}: {c:?}"
            );
            // App::publish: a heartbeat every step, a measurement every 4th, a request
            // every 10th, an answer for each request received.
            assert_eq!(
                sent,
                steps + steps / 4 + steps / 10 + requests,
                "{bin}: {c:?}"
            );
            assert!(
                requests + 1 >= steps / 10 && answers + 1 >= steps / 10,
                "{bin}: {c:?}"
            );
        }
        // The counts logged are the counts the application kept (`STATS` only grows).
        let last = app_stats(&w, b, 1)[0];
        let c = &counts[1];
        assert!(
            last.sent >= c[1] && last.heartbeats >= c[2],
            "{bin}: {last:?}"
        );
        assert!(last.sent - c[1] <= 10, "{bin}: {last:?} {c:?}");
    }
}

/// The reader against a fake target memory: the wrapped case, the read offset written
/// back, nothing before the identifier is there, a corrupt block reported.
#[test]
fn rtt_reader_follows_the_write_offset_and_wraps() {
    use std::cell::RefCell;
    const CB: u32 = 0x100;
    const BUF: u32 = 0x200;
    let mem = RefCell::new(vec![0u8; 0x300]);
    let put = |a: u32, v: u32| {
        mem.borrow_mut()[a as usize..a as usize + 4].copy_from_slice(&v.to_le_bytes())
    };
    let get =
        |a: u32| u32::from_le_bytes(mem.borrow()[a as usize..a as usize + 4].try_into().unwrap());
    let mut rtt = Rtt::new(CB);
    let drain = |rtt: &mut Rtt| {
        rtt.drain(
            |a, n| {
                mem.borrow()
                    .get(a as usize..a as usize + n)
                    .map(<[u8]>::to_vec)
            },
            |a, b| {
                mem.borrow_mut()[a as usize..a as usize + b.len()].copy_from_slice(b);
                true
            },
        )
    };
    // Not initialised yet: nothing read, no error.
    drain(&mut rtt);
    assert!(rtt.bytes.is_empty() && rtt.error.is_none());
    mem.borrow_mut()[CB as usize..CB as usize + 10].copy_from_slice(b"SEGGER RTT");
    put(CB + 16, 1);
    put(CB + 28, BUF);
    put(CB + 32, 16); // size
    for i in 0..16 {
        mem.borrow_mut()[(BUF + i) as usize] = i as u8;
    }
    put(CB + 36, 5); // write
    put(CB + 40, 2); // read
    drain(&mut rtt);
    assert_eq!(rtt.bytes, [2, 3, 4]);
    assert_eq!(get(CB + 40), 5, "read offset advanced");
    put(CB + 36, 3); // wrapped: 5..16 then 0..3
    drain(&mut rtt);
    assert_eq!(
        rtt.bytes,
        [2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2]
    );
    assert_eq!(get(CB + 40), 3);
    drain(&mut rtt);
    assert_eq!(rtt.bytes.len(), 17, "nothing new");
    put(CB + 36, 99); // beyond the buffer
    drain(&mut rtt);
    assert!(
        rtt.error.as_deref().unwrap().contains("write 99"),
        "{:?}",
        rtt.error
    );
}
