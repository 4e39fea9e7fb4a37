//! Issue 6, item 5: candump round trip.
//!
//! The portable application runs on the FlexCAN and bxCAN nodes (with an other ECU adding
//! standard, extended and remote frames of every DLC); the test writes
//!
//! - the bus trace in candump `-l` log format: `<target-dir>/candump/trace.log`
//!   (`Trace::write_candump`),
//! - the frames a listen-only sniffer node saw on the wire, as JSON lines (time stamp of
//!   the start of frame, identifier, format, kind, DLC, data hex):
//!   `<target-dir>/candump/expected.jsonl`,
//!
//! where `<target-dir>` is the cargo target directory (`target/` unless
//! `CARGO_TARGET_DIR` says otherwise; `TWOCAN_CANDUMP_DIR` overrides the folder).
//! `tests/python/check_candump.py trace.log expected.jsonl` then reads the log with
//! python-can's `can.LogReader` and compares frame by frame. This test also parses the
//! log itself, and runs the Python check when python-can is installed.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

use twocan_core::Frame;
use twocan_tests::app_bus::run_apps;
use twocan_tests::support::json_line;

const RATE: u32 = 500_000;
const PERIODS: u32 = 300;

fn candump_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("TWOCAN_CANDUMP_DIR") {
        return PathBuf::from(d);
    }
    // CARGO_TARGET_TMPDIR is `<target-dir>/tmp` for integration tests.
    Path::new(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .expect("target dir")
        .join("candump")
}

/// Parses one `candump -l` line: `(seconds.micros) iface ID#DATA` / `ID#R[dlc]`.
fn parse_line(line: &str) -> (u64, Frame) {
    let mut parts = line.split_whitespace();
    let ts = parts.next().expect("time stamp");
    let _iface = parts.next().expect("interface");
    let body = parts.next().expect("frame");
    let ts = ts.trim_start_matches('(').trim_end_matches(')');
    let (s, us) = ts.split_once('.').expect("seconds.micros");
    assert_eq!(us.len(), 6, "microseconds: {line}");
    let micros = s.parse::<u64>().unwrap() * 1_000_000 + us.parse::<u64>().unwrap();
    let (id, data) = body.split_once('#').expect("#");
    let extended = id.len() == 8;
    assert!(id.len() == 3 || extended, "{line}");
    let raw = u32::from_str_radix(id, 16).unwrap();
    let frame = if let Some(dlc) = data.strip_prefix('R') {
        let dlc = if dlc.is_empty() {
            0
        } else {
            dlc.parse().unwrap()
        };
        Frame::remote(raw, extended, dlc).unwrap()
    } else {
        let bytes: Vec<u8> = (0..data.len() / 2)
            .map(|i| u8::from_str_radix(&data[2 * i..2 * i + 2], 16).unwrap())
            .collect();
        if extended {
            Frame::extended(raw, &bytes).unwrap()
        } else {
            Frame::standard(raw as u16, &bytes).unwrap()
        }
    };
    (micros, frame)
}

fn python_can_available() -> bool {
    Command::new("python3")
        .args(["-c", "import can"])
        .status()
        .is_ok_and(|s| s.success())
}

fn check_script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("python/check_candump.py")
}

#[test]
fn candump_log_round_trip() {
    let b = run_apps(RATE, PERIODS, None);
    let bus = b.h.bus().borrow();
    // Expected: what the sniffer saw, with its start-of-frame time in microseconds.
    let seen: Vec<(u64, Frame)> = b
        .sniffer
        .borrow()
        .received()
        .iter()
        .map(|r| (r.time.sof * 1_000_000 / u64::from(RATE), r.frame))
        .collect();
    assert!(seen.iter().any(|(_, f)| f.is_remote() && f.is_extended()));
    assert!(seen.iter().any(|(_, f)| f.is_remote() && !f.is_extended()));
    assert!(seen.iter().any(|(_, f)| !f.is_remote() && f.is_extended()));
    assert!((0..=8).all(|n| seen.iter().any(|(_, f)| f.dlc() == n && !f.is_remote())));

    let dir = candump_dir();
    fs::create_dir_all(&dir).unwrap();
    let log_path = dir.join("trace.log");
    let json_path = dir.join("expected.jsonl");
    let mut log = fs::File::create(&log_path).unwrap();
    bus.trace().write_candump(&mut log, "can0").unwrap();
    log.flush().unwrap();
    let mut json = String::new();
    for (us, f) in &seen {
        json.push_str(&json_line(*us, f));
        json.push('\n');
    }
    fs::write(&json_path, &json).unwrap();
    println!("candump: {} frames in {}", seen.len(), log_path.display());
    println!("expected: {}", json_path.display());

    // Our own reading of the log agrees with the sniffer, frame by frame.
    let text = fs::read_to_string(&log_path).unwrap();
    let logged: Vec<(u64, Frame)> = text.lines().map(parse_line).collect();
    assert_eq!(logged.len(), seen.len());
    for (k, (l, s)) in logged.iter().zip(&seen).enumerate() {
        assert_eq!(l, s, "frame {k}");
    }

    // python-can's reading, when it is installed (CI installs it and also runs the
    // script on these files).
    if !python_can_available() {
        println!("python-can not installed: skipping the python check here");
        return;
    }
    let out = Command::new("python3")
        .arg(check_script())
        .arg(&log_path)
        .arg(&json_path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}");
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains(&format!("{} passed, 0 failed", seen.len())),
        "{stdout}"
    );

    // The check can fail: one data byte changed in the expectation is caught.
    let tampered_path = dir.join("tampered.jsonl");
    let k = seen
        .iter()
        .position(|(_, f)| f.dlc() > 0 && !f.is_remote())
        .unwrap();
    let mut lines: Vec<String> = json.lines().map(str::to_owned).collect();
    let (us, f) = seen[k];
    let mut data = f.data().to_vec();
    data[0] ^= 0x01;
    let changed = if f.is_extended() {
        Frame::extended(f.raw_id(), &data)
    } else {
        Frame::standard(f.raw_id() as u16, &data)
    }
    .unwrap();
    lines[k] = json_line(us, &changed);
    fs::write(&tampered_path, lines.join("\n") + "\n").unwrap();
    let out = Command::new("python3")
        .arg(check_script())
        .arg(&log_path)
        .arg(&tampered_path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains(", 1 failed"), "{stdout}");
}
