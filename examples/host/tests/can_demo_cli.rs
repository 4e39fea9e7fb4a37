//! The `can-demo` command line: option forms, refusals with exit status 2 before any
//! simulation, and the streamed `--trace` file.

use std::path::PathBuf;
use std::process::{Command, Output};

fn can_demo(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_can-demo"))
        .args(args)
        .output()
        .expect("can-demo runs")
}

fn scratch(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name)
}

#[test]
fn bad_trace_path_fails_at_once_with_status_2() {
    let out = can_demo(&["--seconds", "3600", "--trace", "/nonexistent-dir/trace.log"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("--trace /nonexistent-dir/trace.log"),
        "{stderr}"
    );
    // Nothing was simulated: no progress line.
    assert!(
        out.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
}

#[test]
fn runs_shorter_than_a_frame_or_a_period_are_refused() {
    // 160 bits at 10 kbit/s: 16 ms.
    let out = can_demo(&["--bitrate=10000", "--seconds=0.015"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("one frame time"));
    // One application period: 1 ms.
    let out = can_demo(&["--seconds", "0.0009"]);
    assert_eq!(out.status.code(), Some(2));
    for bad in [
        &["--bitrate", "9999"][..],
        &["--error-rate", "1"],
        &["--seconds", "-1"],
        &["--seed", "x"],
        &["--frob"],
    ] {
        assert_eq!(can_demo(bad).status.code(), Some(2), "{bad:?}");
    }
}

#[test]
fn trace_is_streamed_in_candump_form() {
    let path = scratch("can_demo_cli_trace.log");
    let p = path.to_str().unwrap();
    let out = can_demo(&[
        "--bitrate",
        "500000",
        "--seconds=0.05",
        &format!("--trace={p}"),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines.len() > 10, "{} lines", lines.len());
    for l in &lines {
        // `(0000000000.000123) can0 123#DEADBEEF`
        let (stamp, rest) = l.split_once(' ').unwrap();
        assert!(
            stamp.starts_with('(') && stamp.ends_with(')') && stamp.len() == 19,
            "{l}"
        );
        assert!(rest.starts_with("can0 ") && rest.contains('#'), "{l}");
    }
    // Time order, across the drains of every period.
    let stamps: Vec<&str> = lines.iter().map(|l| &l[..19]).collect();
    assert!(stamps.windows(2).all(|w| w[0] <= w[1]));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains(&format!("trace: {} frames written", lines.len())),
        "{stdout}"
    );
}

#[test]
fn async_demo_runs_the_async_app_on_both_boards() {
    let out = can_demo(&["--async", "--seconds", "0.2"]);
    assert_eq!(out.status.code(), Some(0));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("async API"), "{stdout}");
    // 200 periods: both applications heard every heartbeat of the other, in order.
    let apps: Vec<&str> = stdout.lines().filter(|l| l.contains(" app: ")).collect();
    assert_eq!(apps.len(), 2, "{stdout}");
    for line in apps {
        assert!(
            line.contains("heartbeats 200 (gaps 0, duplicates 0)") && line.contains("queue full 0"),
            "{line}"
        );
    }
}
