//! `can-fil`: runs firmware ELFs of the twocan examples on emulated boards sharing one
//! simulated CAN bus, and reports what each did.
//!
//! ```text
//! can-fil --board teensy36 ELF [--board nucleo-f767zi ELF ...] --seconds S
//!         [--bitrate B] [--trace FILE] [--quantum-us Q] [--stack]
//! ```
//! Exit status 0 only when every firmware ran without a fault, a stuck interrupt, a
//! livelock or a halt; 2 on bad arguments.

use std::process::ExitCode;

use twocan_fil::elf::Image;
use twocan_fil::profile::{self, BOARDS};
use twocan_fil::report;
use twocan_fil::world::World;

const USAGE: &str = "usage: can-fil --board BOARD ELF [--board BOARD ELF ...] --seconds S [--bitrate B] [--trace FILE] [--quantum-us Q] [--traffic ID,PERIOD_MS[,BITRATE] ...] [--stack]\nboards: teensy32 teensy35 teensy36 nucleo-f767zi disco-f746g bluepill nucleo-f446re teensy41";

struct Args {
    boards: Vec<(String, String)>,
    seconds: f64,
    bitrate: u32,
    trace: Option<String>,
    quantum_us: u64,
    traffic: Vec<(u32, u64, u32)>,
    stack: bool,
}

fn parse(mut it: impl Iterator<Item = String>) -> Result<Args, String> {
    let mut a = Args {
        boards: Vec::new(),
        seconds: 1.0,
        bitrate: 500_000,
        trace: None,
        quantum_us: 20,
        traffic: Vec::new(),
        stack: false,
    };
    let mut seconds = false;
    while let Some(arg) = it.next() {
        let mut value = |what: &str| it.next().ok_or(format!("{arg} needs {what}"));
        match arg.as_str() {
            "--board" => {
                let b = value("a board name")?;
                if !BOARDS.contains(&b.as_str()) {
                    return Err(format!("unknown board {b:?}"));
                }
                let elf = value("an ELF path")?;
                a.boards.push((b, elf));
            }
            "--seconds" => {
                let v = value("a number")?;
                a.seconds = v
                    .parse()
                    .map_err(|_| format!("--seconds {v:?}: not a number"))?;
                if !(a.seconds > 0.0 && a.seconds <= 3600.0) {
                    return Err("--seconds must be in (0, 3600]".into());
                }
                seconds = true;
            }
            "--bitrate" => {
                let v = value("bits per second")?;
                a.bitrate = v
                    .parse()
                    .map_err(|_| format!("--bitrate {v:?}: not a number"))?;
            }
            "--trace" => a.trace = Some(value("a file")?),
            "--quantum-us" => {
                let v = value("microseconds")?;
                a.quantum_us = v
                    .parse()
                    .map_err(|_| format!("--quantum-us {v:?}: not a number"))?;
                if a.quantum_us == 0 {
                    return Err("--quantum-us must be at least 1".into());
                }
            }
            "--traffic" => {
                // ID,PERIOD_MS[,BITRATE]: a plain node sending a standard data frame.
                let v = value("ID,PERIOD_MS[,BITRATE]")?;
                let parts: Vec<&str> = v.split(',').collect();
                let bad = || format!("--traffic {v:?}: expected ID,PERIOD_MS[,BITRATE]");
                if !(2..=3).contains(&parts.len()) {
                    return Err(bad());
                }
                let id = u32::from_str_radix(parts[0].trim_start_matches("0x"), 16)
                    .map_err(|_| bad())?;
                if id > 0x7FF {
                    return Err(format!("--traffic: 0x{id:X} is not a standard identifier"));
                }
                let period: u64 = parts[1].parse().map_err(|_| bad())?;
                if period == 0 {
                    return Err("--traffic: period must be at least 1 ms".into());
                }
                let rate = match parts.get(2) {
                    Some(r) => r.parse().map_err(|_| bad())?,
                    None => 0,
                };
                a.traffic.push((id, period, rate));
            }
            // Paint each board's stack and report its high-water marks (src/stack.rs).
            "--stack" => a.stack = true,
            "-h" | "--help" => return Err(String::new()),
            other => return Err(format!("unexpected argument {other:?}")),
        }
    }
    if a.boards.is_empty() {
        return Err("no --board given".into());
    }
    if !seconds {
        return Err("--seconds is required".into());
    }
    Ok(a)
}

fn main() -> ExitCode {
    let args = match parse(std::env::args().skip(1)) {
        Ok(a) => a,
        Err(e) => {
            if !e.is_empty() {
                eprintln!("can-fil: {e}");
            }
            eprintln!("{USAGE}");
            return ExitCode::from(2);
        }
    };
    let mut world = match World::new(args.bitrate) {
        Ok(w) => w,
        Err(e) => {
            eprintln!("can-fil: {e}");
            return ExitCode::from(2);
        }
    };
    world.quantum_ps = u128::from(args.quantum_us) * 1_000_000;
    for (board, elf) in &args.boards {
        let image = match Image::load(elf) {
            Ok(i) => i,
            Err(e) => {
                eprintln!("can-fil: {e}");
                return ExitCode::from(2);
            }
        };
        let profile = profile::by_name(board).expect("checked by parse");
        let index = match world.add_board(profile, image) {
            Ok(i) => i,
            Err(e) => {
                eprintln!("can-fil: {board}: {e}");
                return ExitCode::from(2);
            }
        };
        if args.stack {
            if let Err(e) = world.machines[index].paint_stack() {
                eprintln!("can-fil: {board}: {e}");
                return ExitCode::from(2);
            }
        }
    }
    for (n, (id, period, rate)) in args.traffic.iter().enumerate() {
        let frame = match twocan_core::Frame::standard(*id as u16, &[n as u8, 0x55]) {
            Ok(f) => f,
            Err(e) => {
                eprintln!("can-fil: --traffic 0x{id:X}: {e:?}");
                return ExitCode::from(2);
            }
        };
        let rate = if *rate == 0 { args.bitrate } else { *rate };
        world.add_node(
            &format!("node{}", n + 1),
            twocan_sim::SimNode::new(),
            rate,
            vec![frame],
            u128::from(*period) * 1_000_000_000,
        );
    }
    let start = std::time::Instant::now();
    world.run_for((args.seconds * 1e12) as u128);
    let wall = start.elapsed().as_secs_f64();
    print!("{}", report::render(&world));
    let total: u64 = world.machines.iter().map(|m| m.board().instructions).sum();
    println!(
        "\nhost: {wall:.2} s, {:.1} M instructions per host second",
        total as f64 / wall.max(1e-9) / 1e6
    );
    if let Some(path) = &args.trace {
        if let Err(e) = std::fs::write(path, world.candump()) {
            eprintln!("can-fil: {path}: {e}");
            return ExitCode::from(1);
        }
    }
    if world.clean() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
