//! `can-demo`: a simulated Teensy 3.6 (FlexCAN can0) and a simulated STM32F767 (bxCAN
//! CAN1) on one bus, both running the portable application of `twocan-app`.
//!
//! ```text
//! cargo run --release --bin can-demo -- [--bitrate BPS] [--seconds S] [--error-rate R]
//!                                       [--seed N] [--trace FILE]
//! ```

use std::fs::File;
use std::io::{BufWriter, Write};
use std::process::ExitCode;

use twocan_app::App;
use twocan_core::sim::{RandomFaults, SimNode};
use twocan_core::Frame;
use twocan_host::{state_name, BxNode, FlexNode, Harness, Serviced};

const USAGE: &str =
    "usage: can-demo [--bitrate BPS] [--seconds S] [--error-rate R] [--seed N] [--trace FILE]
  --bitrate BPS     bus bit rate, 10000..=1000000 (default 500000)
  --seconds S       simulated time to run, > 0 (default 2)
  --error-rate R    probability in [0, 1) that a frame on the bus is hit by an error (default 0)
  --seed N          seed of the error injection (default 1)
  --trace FILE      write every frame on the bus in the candump log format";

#[derive(Debug)]
struct Options {
    bitrate: u32,
    seconds: f64,
    error_rate: f64,
    seed: u64,
    trace: Option<String>,
}

fn parse(args: &[String]) -> Result<Options, String> {
    let mut o = Options {
        bitrate: 500_000,
        seconds: 2.0,
        error_rate: 0.0,
        seed: 1,
        trace: None,
    };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .cloned()
                .ok_or_else(|| format!("{name} needs a value"))
        };
        match a.as_str() {
            "--bitrate" => {
                let v = value("--bitrate")?;
                o.bitrate = v
                    .parse()
                    .map_err(|_| format!("--bitrate: not a number: {v}"))?;
                if !(10_000..=1_000_000).contains(&o.bitrate) {
                    return Err(format!(
                        "--bitrate: {} is outside 10000..=1000000",
                        o.bitrate
                    ));
                }
            }
            "--seconds" => {
                let v = value("--seconds")?;
                o.seconds = v
                    .parse()
                    .map_err(|_| format!("--seconds: not a number: {v}"))?;
                if !(o.seconds > 0.0 && o.seconds <= 3600.0) {
                    return Err(format!("--seconds: {v} is outside (0, 3600]"));
                }
            }
            "--error-rate" => {
                let v = value("--error-rate")?;
                o.error_rate = v
                    .parse()
                    .map_err(|_| format!("--error-rate: not a number: {v}"))?;
                if !(0.0..1.0).contains(&o.error_rate) {
                    return Err(format!("--error-rate: {v} is outside [0, 1)"));
                }
            }
            "--seed" => {
                let v = value("--seed")?;
                o.seed = v
                    .parse()
                    .map_err(|_| format!("--seed: not a number: {v}"))?;
            }
            "--trace" => o.trace = Some(value("--trace")?),
            "-h" | "--help" => return Err(String::new()),
            other => return Err(format!("unknown option: {other}")),
        }
    }
    Ok(o)
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let o = match parse(&args) {
        Ok(o) => o,
        Err(msg) if msg.is_empty() => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        Err(msg) => {
            eprintln!("can-demo: {msg}\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    match run(&o) {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("can-demo: {msg}");
            ExitCode::from(1)
        }
    }
}

fn run(o: &Options) -> Result<(), String> {
    let mut h = Harness::new(o.bitrate).map_err(|e| format!("bus: {e:?}"))?;
    let mut teensy_app = App::new(1, 2);
    let mut stm32_app = App::new(2, 1);
    let mut teensy = FlexNode::teensy36_can0(&mut h, &teensy_app.filters())
        .map_err(|e| format!("Teensy 3.6 can0: {e:?}"))?;
    let mut stm32 = BxNode::stm32f767_can1(&mut h, &stm32_app.filters())
        .map_err(|e| format!("STM32F767 CAN1: {e:?}"))?;
    // A third, plain ISO node: traffic that neither application asked for, so that the
    // filters have something to refuse.
    let other = SimNode::new().shared();
    {
        let mut bus = h.bus().borrow_mut();
        bus.attach("other-ecu", other.clone());
        bus.set_tracing(o.trace.is_some());
        if o.error_rate > 0.0 {
            bus.set_random_faults(Some(RandomFaults::new(o.seed, o.error_rate)));
        }
    }
    println!(
        "can-demo: Teensy 3.6 (FlexCAN can0) + STM32F767 (bxCAN CAN1) at {} bit/s, {} s simulated, error rate {}, seed {}",
        o.bitrate, o.seconds, o.error_rate, o.seed
    );
    // One application period per simulated millisecond.
    let period = u64::from(o.bitrate) / 1000;
    let start = h.now();
    let end = start + (o.seconds * f64::from(o.bitrate)) as u64;
    let periods = (end - start) / period;
    let progress_every = (periods / 10).max(1);
    for p in 0..periods {
        teensy_app.step(&mut teensy.driver);
        stm32_app.step(&mut stm32.driver);
        if p.is_multiple_of(5) {
            let k = (p / 5) as u32;
            let f = if k.is_multiple_of(2) {
                Frame::standard(0x300 + (k % 16) as u16, &k.to_le_bytes())
            } else {
                Frame::extended(0x0CF0_0400 | (k % 8), &k.to_be_bytes())
            };
            if let Ok(f) = f {
                other.borrow_mut().send(f);
            }
        }
        h.run_until(
            start + (p + 1) * period,
            &mut [&mut teensy as &mut dyn Serviced, &mut stm32],
        );
        if (p + 1).is_multiple_of(progress_every) {
            let bus = h.bus().borrow();
            println!(
                "  t = {:>7.3} s  frames on bus {:>7}  load {:>5.1} %  teensy {} / stm32 {}",
                (bus.now() - start) as f64 / f64::from(o.bitrate),
                bus.frames_started(),
                bus.load() * 100.0,
                state_name(teensy.driver.state()),
                state_name(stm32.driver.state()),
            );
        }
    }
    let bus = h.bus().borrow();
    println!();
    println!(
        "{:<22} {:>8} {:>9} {:>9} {:>5} {:>7} {:>14} {:>9} {:>6}",
        "node", "sent", "received", "filtered", "lost", "errors", "state", "TEC/REC", "load%"
    );
    let load = bus.load() * 100.0;
    let teensy_row = Row::new(
        &teensy_app,
        teensy.driver.traffic(),
        teensy.driver.error_stats(),
        teensy.filtered_out(),
        teensy.lost(),
    );
    let stm32_row = Row::new(
        &stm32_app,
        stm32.driver.traffic(),
        stm32.driver.error_stats(),
        stm32.filtered_out(),
        stm32.lost(),
    );
    for (name, row, state, c) in [
        (
            "Teensy 3.6 FlexCAN",
            teensy_row,
            teensy.driver.state(),
            teensy.driver.counters(),
        ),
        (
            "STM32F767 bxCAN",
            stm32_row,
            stm32.driver.state(),
            stm32.driver.counters(),
        ),
    ] {
        println!(
            "{:<22} {:>8} {:>9} {:>9} {:>5} {:>7} {:>14} {:>9} {:>6.1}",
            name,
            row.sent,
            row.received,
            row.filtered,
            row.lost,
            row.errors,
            state_name(state),
            format!("{}/{}", c.tec, c.rec),
            load
        );
    }
    let o_stats = other.borrow();
    println!(
        "{:<22} {:>8} {:>9} {:>9} {:>5} {:>7} {:>14} {:>9} {:>6.1}",
        "other ECU (plain node)",
        o_stats
            .tx_reports()
            .iter()
            .filter(|r| matches!(r.result, twocan_core::sim::TxResult::Acked))
            .count(),
        o_stats.received().len(),
        "-",
        "-",
        o_stats.rx_errors().len(),
        state_name(o_stats.state()),
        format!("{}/{}", o_stats.counters().tec, o_stats.counters().rec),
        load
    );
    drop(o_stats);
    for (name, app) in [("Teensy 3.6", &teensy_app), ("STM32F767", &stm32_app)] {
        let s = app.stats();
        println!(
            "{name:<11} app: heartbeats {} (gaps {}, duplicates {}), measurements {}, status requests {}, answers {}, queue full {}",
            s.heartbeats, s.heartbeat_gaps, s.heartbeat_duplicates, s.measurements, s.requests, s.answers, s.tx_full
        );
    }
    if let Some(path) = &o.trace {
        let file = File::create(path).map_err(|e| format!("--trace {path}: {e}"))?;
        let mut w = BufWriter::new(file);
        bus.trace()
            .write_candump(&mut w, "can0")
            .map_err(|e| format!("--trace {path}: {e}"))?;
        w.flush().map_err(|e| format!("--trace {path}: {e}"))?;
        println!("trace: {} frames written to {path}", bus.trace().len());
    }
    Ok(())
}

struct Row {
    sent: u32,
    received: u32,
    filtered: u64,
    lost: u64,
    errors: u32,
}

impl Row {
    fn new(
        _app: &App,
        t: twocan_core::TrafficStats,
        e: twocan_core::ErrorStatistics,
        filtered: u64,
        lost: u64,
    ) -> Self {
        Row {
            sent: t.sent,
            received: t.received,
            filtered,
            lost,
            errors: e.stuff + e.form + e.acknowledge + e.bit + e.crc,
        }
    }
}
