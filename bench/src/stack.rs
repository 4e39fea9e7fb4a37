//! Stack high-water marks of the firmware examples: each example ELF runs under
//! `can-fil --stack` (the firmware-in-the-loop harness, `fil/`, on the board it was
//! built for), which paints the stack before reset and reports the painted depth when
//! the last CAN controller the firmware starts has its first interrupt line unmasked
//! (configuration done, of every controller) and at the end (`fil/src/stack.rs`).

use std::path::Path;
use std::process::Command;
use std::time::Duration;

use crate::cmd::{self, Context, Error, Result};

/// Simulated time each example runs (its configuration ends well before).
pub const SECONDS: &str = "0.2";

/// What `can-fil --stack` reported for one example.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FilStack {
    /// Bytes of stack written until the last CAN controller started had a line
    /// unmasked (`None`: the firmware unmasked none in the run).
    pub configuration: Option<u64>,
    /// Bytes of stack written over the whole run.
    pub whole: u64,
    /// Bytes painted (the stack region).
    pub painted: u64,
}

/// The `can-fil` command line for `elf` on `board`.
pub fn command(can_fil: &Path, board: &str, elf: &Path) -> Command {
    let mut c = Command::new(can_fil);
    c.args(["--stack", "--board", board])
        .arg(elf)
        .args(["--seconds", SECONDS]);
    c
}

/// Runs `elf` on `board` under `can-fil --stack` and reads its stack line. The run's
/// exit status is not required to be 0 (an example alone on the bus may see no
/// acknowledgement); a missing stack line is an error.
pub fn measure(can_fil: &Path, board: &str, elf: &Path) -> Result<FilStack> {
    measure_checked(can_fil, board, elf, false)
}

/// Like [`measure`] for a bench loop-back firmware, which must also have done its job:
/// `can-fil` ends with status 0 (no fault, no halt, no stuck interrupt) and the last
/// instruction is not in the panic handler (the loop-back firmwares panic when the
/// frame does not come back with its filter index and, with completions, its
/// completion).
pub fn measure_loopback(can_fil: &Path, board: &str, elf: &Path) -> Result<FilStack> {
    measure_checked(can_fil, board, elf, true)
}

fn measure_checked(can_fil: &Path, board: &str, elf: &Path, must_pass: bool) -> Result<FilStack> {
    let mut c = command(can_fil, board, elf);
    let out = cmd::run(&mut c, Duration::from_secs(300))
        .context(format!("can-fil --stack {board} {}", elf.display()))?;
    if must_pass && (out.code != Some(0) || panicked(&out.stdout)) {
        return Err(Error::new(format!(
            "the loop-back firmware failed under `{}` (exit {:?}):\n{}",
            cmd::display(&command(can_fil, board, elf)),
            out.code,
            cmd::tail(&out.stdout, 30)
        )));
    }
    parse(&out.stdout).ok_or_else(|| {
        Error::new(format!(
            "`{}` printed no stack line (exit {:?}):\n{}\n{}",
            cmd::display(&command(can_fil, board, elf)),
            out.code,
            cmd::tail(&out.stdout, 20),
            cmd::tail(&out.stderr, 20)
        ))
    })
}

/// Whether the report's last instruction is in the panic handler.
fn panicked(stdout: &str) -> bool {
    stdout
        .lines()
        .map(str::trim)
        .any(|l| l.starts_with("last instruction:") && l.contains("rust_begin_unwind"))
}

/// The number right after `key` in `line`.
fn number_after(line: &str, key: &str) -> Option<u64> {
    let rest = &line[line.find(key)? + key.len()..];
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    digits.parse().ok()
}

/// Reads `stack: configuration N B (...), whole run M B, painted P B ...`.
fn parse(stdout: &str) -> Option<FilStack> {
    let line = stdout
        .lines()
        .map(str::trim)
        .find(|l| l.starts_with("stack:"))?;
    Some(FilStack {
        configuration: number_after(line, "stack: configuration "),
        whole: number_after(line, "whole run ")?,
        painted: number_after(line, "painted ")?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_stack_line() {
        let out = "bus: 500000 bit/s\n\n[teensy36] x\n  instructions: 5\n  stack: \
                   configuration 1208 B (until the last CAN controller started had a line unmasked, \
                   at 812 us), whole run 1376 B, painted 253952 B from 0x1FFF1000\n  \
                   faults: none\n";
        assert_eq!(
            parse(out),
            Some(FilStack {
                configuration: Some(1208),
                whole: 1376,
                painted: 253_952
            })
        );
        let none = "  stack: configuration not reached (no CAN interrupt line unmasked), \
                    whole run 96 B, painted 4096 B from 0x20000000\n";
        assert_eq!(
            parse(none),
            Some(FilStack {
                configuration: None,
                whole: 96,
                painted: 4096
            })
        );
        assert_eq!(parse("no such line\n"), None);
        assert!(panicked(
            "  last instruction: 0x08004DFA in __rustc::rust_begin_unwind\n"
        ));
        assert!(!panicked(
            "  last instruction: 0x08001984 in loopback_twocan::main\n"
        ));
    }
}
