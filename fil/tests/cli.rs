//! The `can-fil` command: report, exit status, candump trace, argument errors.

mod common;

use std::process::Command;

fn can_fil(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_can-fil"))
        .args(args)
        .output()
        .expect("run can-fil");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn path(board: &str, name: &str) -> Option<String> {
    common::elf(board, name)?;
    Some(
        common::elf_dir()
            .join(board)
            .join(name)
            .display()
            .to_string(),
    )
}

#[test]
fn two_boards_on_one_bus_with_a_trace() {
    let (Some(t), Some(s)) = (
        path("teensy36", "teensy-app"),
        path("nucleo-f767zi", "stm32f7-app"),
    ) else {
        return;
    };
    let trace = std::env::temp_dir().join(format!("can-fil-{}.log", std::process::id()));
    let trace_s = trace.display().to_string();
    let (code, out, err) = can_fil(&[
        "--board",
        "teensy36",
        &t,
        "--board",
        "nucleo-f767zi",
        &s,
        "--seconds",
        "0.5",
        "--trace",
        &trace_s,
    ]);
    assert_eq!(code, 0, "{out}{err}");
    for want in [
        "[teensy36]",
        "[nucleo-f767zi]",
        "instructions: ",
        "IRQ 75 (CAN0 ORed message buffer)",
        "IRQ 20 (CAN1 CAN1_RX0)",
        "faults: none",
    ] {
        assert!(out.contains(want), "{want:?} missing in\n{out}");
    }
    let log = std::fs::read_to_string(&trace).expect("trace written");
    let _ = std::fs::remove_file(&trace);
    // candump -l lines: "(seconds.micros) can0 ID#DATA".
    let lines: Vec<&str> = log.lines().collect();
    assert!(lines.len() > 50, "{} lines", lines.len());
    assert!(lines.iter().any(|l| l.contains(" can0 101#")));
    assert!(lines.iter().any(|l| l.contains(" can0 102#")));
    assert!(lines
        .iter()
        .all(|l| l.starts_with('(') && l.contains(") can0 ")));
}

#[test]
fn a_fault_makes_the_exit_status_non_zero() {
    let Some(g) = path("negative", "kinetis-gate") else {
        return;
    };
    let (code, out, _) = can_fil(&["--board", "teensy36", &g, "--seconds", "0.002"]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains(
            "FAULT: BusFault: CAN0 read with its clock gated (SIM_SCGC6.FLEXCAN0 = 0) at PC 0x"
        ),
        "{out}"
    );
    assert!(out.contains("-> HardFault handler"), "{out}");
    assert!(out.contains("| kinetis-gate: fault handler"), "{out}");
}

#[test]
fn bad_arguments_are_refused_with_usage() {
    for args in [
        vec!["--seconds", "1"],
        vec!["--board", "teensy40", "x", "--seconds", "1"],
        vec!["--board", "teensy36", "/nonexistent.elf", "--seconds", "1"],
        vec!["--board", "teensy36", "x", "--seconds", "-1"],
        vec!["--board", "teensy36", "x"],
        vec![
            "--board",
            "teensy36",
            "x",
            "--seconds",
            "1",
            "--traffic",
            "800,1",
        ],
    ] {
        let (code, _, err) = can_fil(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains("can-fil:"), "{args:?}: {err}");
    }
}

/// A firmware built with `defmt`: its decoded log is in the report, under its board.
#[test]
fn the_report_shows_the_decoded_defmt_log() {
    let Some(t) = path("teensy36", "teensy-loopback-defmt") else {
        return;
    };
    let (code, out, err) = can_fil(&["--board", "teensy36", &t, "--seconds", "1.1"]);
    assert_eq!(code, 0, "{out}{err}");
    let log = out
        .split_once("  defmt log (2 lines):\n")
        .unwrap_or_else(|| panic!("{out}"))
        .1;
    let lines: Vec<&str> = log.lines().take(2).collect();
    assert!(
        lines[0].starts_with("    | 0.000 INFO  teensy-loopback: CAN0 in loop-back"),
        "{out}"
    );
    assert!(
        lines[1].starts_with("    | 1.00")
            && lines[1].ends_with("INFO  loop-back frame 1 received"),
        "{out}"
    );
    // Without `defmt` there is no log section.
    let Some(plain) = path("teensy36", "teensy-loopback") else {
        return;
    };
    let (_, out, _) = can_fil(&["--board", "teensy36", &plain, "--seconds", "0.1"]);
    assert!(!out.contains("defmt log"), "{out}");
}

/// `--stack`: the painted stack's configuration mark (taken when the last CAN controller
/// the firmware starts has a line unmasked) and the whole run's; without the option
/// there is no stack line.
#[test]
fn the_stack_option_reports_the_painted_depths() {
    let Some(t) = path("teensy36", "teensy-loopback") else {
        return;
    };
    let (code, out, err) = can_fil(&["--stack", "--board", "teensy36", &t, "--seconds", "0.1"]);
    assert_eq!(code, 0, "{out}{err}");
    let line = out
        .lines()
        .map(str::trim)
        .find(|l| l.starts_with("stack: configuration "))
        .unwrap_or_else(|| panic!("{out}"));
    let number_after = |key: &str| -> u64 {
        let rest = &line[line.find(key).unwrap_or_else(|| panic!("{line}")) + key.len()..];
        rest.split(' ').next().unwrap().parse().unwrap()
    };
    let config = number_after("stack: configuration ");
    let whole = number_after("whole run ");
    let painted = number_after("painted ");
    // Start-up and `begin` use some stack; the run never uses less than its
    // configuration; nothing overflows the painted region.
    assert!(config > 0 && config <= whole && whole < painted, "{line}");
    let (_, out, _) = can_fil(&["--board", "teensy36", &t, "--seconds", "0.1"]);
    assert!(!out.contains("stack:"), "{out}");
}
