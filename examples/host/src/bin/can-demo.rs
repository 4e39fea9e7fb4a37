//! `can-demo`: a simulated Teensy 3.6 (FlexCAN can0) and a simulated STM32F767 (bxCAN
//! CAN1) on one bus, both running the portable application of `twocan-app`.
//!
//! ```text
//! cargo run --release --bin can-demo -- [--bitrate BPS] [--seconds S] [--error-rate R]
//!                                       [--seed N] [--trace FILE] [--async]
//! ```
//!
//! `--async` runs the application's async form (`App::publish_async`,
//! `App::receive_async`) on the split drivers' async halves, polled by a host executor
//! (`twocan_host::executor::drive`) between the bus events.

use std::cell::RefCell;
use std::fs::File;
use std::io::BufWriter;
use std::path::PathBuf;
use std::pin::pin;
use std::process::ExitCode;
use std::rc::Rc;

use clap::error::ErrorKind;
use clap::{CommandFactory, Parser};
use twocan_app::App;
use twocan_core::{AsyncCanRx, Frame};
use twocan_host::executor::drive;
use twocan_host::split::{split_bx, split_flex, BxState, FlexState};
use twocan_host::{state_name, BxNode, FlexNode, Harness, Serviced};
use twocan_sim::bits::{max_stuff_bits, INTERMISSION_BITS};
use twocan_sim::trace::CandumpWriter;
use twocan_sim::{RandomFaults, SimNode};

/// A simulated Teensy 3.6 (FlexCAN can0) and a simulated STM32F767 (bxCAN CAN1) on one
/// bus, both running the portable application of `twocan-app`.
#[derive(Debug, Parser)]
#[command(name = "can-demo", version)]
struct Args {
    /// Bus bit rate in bit/s, 10000..=1000000
    #[arg(long, value_name = "BPS", default_value_t = 500_000,
          value_parser = clap::value_parser!(u32).range(10_000..=1_000_000))]
    bitrate: u32,
    /// Simulated time to run in seconds, up to 3600; at least one frame time and one
    /// application period (1 ms)
    #[arg(long, value_name = "S", default_value_t = 2.0, value_parser = parse_seconds)]
    seconds: f64,
    /// Probability in [0, 1) that a frame on the bus is hit by an error
    #[arg(long, value_name = "R", default_value_t = 0.0, value_parser = parse_error_rate)]
    error_rate: f64,
    /// Seed of the error injection
    #[arg(long, value_name = "N", default_value_t = 1)]
    seed: u64,
    /// Write every frame on the bus to FILE in the candump log format, as the run goes
    #[arg(long, value_name = "FILE")]
    trace: Option<PathBuf>,
    /// Run the application's async form on the split drivers' async halves, with a host
    /// executor
    #[arg(long = "async")]
    asynch: bool,
}

/// Bit times of the longest classical frame (extended identifier, 8 data bytes, every
/// possible stuff bit) with its intermission: 64 + 64 + 29 + 3 = 160.
const LONGEST_FRAME_BITS: u32 = 64 + 8 * 8 + max_stuff_bits(true, 8) + INTERMISSION_BITS;

fn parse_seconds(text: &str) -> Result<f64, String> {
    let s: f64 = text
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    if s > 0.0 && s <= 3600.0 {
        Ok(s)
    } else {
        Err(format!("{text} is outside (0, 3600]"))
    }
}

fn parse_error_rate(text: &str) -> Result<f64, String> {
    let r: f64 = text
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    if (0.0..1.0).contains(&r) {
        Ok(r)
    } else {
        Err(format!("{text} is outside [0, 1)"))
    }
}

impl Args {
    /// The rules between options: the run must last at least one frame time at the
    /// chosen bit rate, and one application period (the demo steps in whole periods).
    fn check(&self) -> Result<(), clap::Error> {
        let frame_time = f64::from(LONGEST_FRAME_BITS) / f64::from(self.bitrate);
        let minimum = frame_time.max(0.001);
        if self.seconds < minimum {
            return Err(Args::command().error(
                ErrorKind::ValueValidation,
                format!(
                    "--seconds {}: shorter than {minimum} s, the longest of one frame time \
                     ({LONGEST_FRAME_BITS} bits at {} bit/s) and one application period (1 ms)",
                    self.seconds, self.bitrate
                ),
            ));
        }
        Ok(())
    }
}

/// The `--trace` file, opened before the run: candump lines are written to it as the
/// simulation goes (the bus trace is drained every application period).
type TraceSink = CandumpWriter<'static, BufWriter<File>>;

fn open_trace(path: &PathBuf, bitrate: u32) -> Result<TraceSink, String> {
    let file = File::create(path).map_err(|e| format!("--trace {}: {e}", path.display()))?;
    Ok(CandumpWriter::new(BufWriter::new(file), "can0", bitrate))
}

fn main() -> ExitCode {
    // Bad options: clap prints the error and a usage line and exits with status 2.
    let args = Args::parse();
    if let Err(e) = args.check() {
        e.exit();
    }
    // A bad trace path fails at once, before any simulation.
    let mut trace = match args
        .trace
        .as_ref()
        .map(|path| open_trace(path, args.bitrate))
        .transpose()
    {
        Ok(t) => t,
        Err(msg) => {
            eprintln!("can-demo: {msg}");
            return ExitCode::from(2);
        }
    };
    let result = if args.asynch {
        run_async(&args, trace.as_mut())
    } else {
        run(&args, trace.as_mut())
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("can-demo: {msg}");
            ExitCode::from(1)
        }
    }
}

/// The bus with its two boards (running `teensy_app` and `stm32_app`) and a plain
/// third node.
struct Setup {
    h: Harness,
    teensy_app: App,
    stm32_app: App,
    teensy: FlexNode,
    stm32: BxNode,
    other: Rc<RefCell<SimNode>>,
}

fn setup(o: &Args) -> Result<Setup, String> {
    let mut h = Harness::new(o.bitrate).map_err(|e| format!("bus: {e:?}"))?;
    let teensy_app = App::new(1, 2);
    let stm32_app = App::new(2, 1);
    let teensy = FlexNode::teensy36_can0(&mut h, &teensy_app.filters())
        .map_err(|e| format!("Teensy 3.6 can0: {e:?}"))?;
    let stm32 = BxNode::stm32f767_can1(&mut h, &stm32_app.filters())
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
        "can-demo: Teensy 3.6 (FlexCAN can0) + STM32F767 (bxCAN CAN1) at {} bit/s, {} s simulated, error rate {}, seed {}{}",
        o.bitrate,
        o.seconds,
        o.error_rate,
        o.seed,
        if o.asynch { ", async API" } else { "" }
    );
    Ok(Setup {
        h,
        teensy_app,
        stm32_app,
        teensy,
        stm32,
        other,
    })
}

/// The plain node's traffic: a frame every 5th period.
fn other_traffic(other: &Rc<RefCell<SimNode>>, p: u64) {
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
}

/// The periods of the run: (start, period length, number of periods).
fn periods(o: &Args, h: &Harness) -> (u64, u64, u64) {
    // One application period per simulated millisecond.
    let period = u64::from(o.bitrate) / 1000;
    let start = h.now();
    let end = start + (o.seconds * f64::from(o.bitrate)) as u64;
    (start, period, (end - start) / period)
}

/// Writes the frames of the last period to the trace; prints a progress line every
/// tenth of the run.
fn after_period(
    o: &Args,
    h: &Harness,
    trace: &mut Option<&mut TraceSink>,
    p: u64,
    periods: u64,
    start: u64,
    states: [twocan_core::ErrorState; 2],
) -> Result<(), String> {
    if let Some(sink) = trace.as_deref_mut() {
        sink.drain(h.bus().borrow_mut().trace_mut())
            .map_err(|e| format!("--trace: {e}"))?;
    }
    if (p + 1).is_multiple_of((periods / 10).max(1)) {
        let bus = h.bus().borrow();
        println!(
            "  t = {:>7.3} s  frames on bus {:>7}  load {:>5.1} %  teensy {} / stm32 {}",
            (bus.now() - start) as f64 / f64::from(o.bitrate),
            bus.frames_started(),
            bus.load() * 100.0,
            state_name(states[0]),
            state_name(states[1]),
        );
    }
    Ok(())
}

fn run(o: &Args, mut trace: Option<&mut TraceSink>) -> Result<(), String> {
    let Setup {
        mut h,
        mut teensy_app,
        mut stm32_app,
        mut teensy,
        mut stm32,
        other,
    } = setup(o)?;
    let (start, period, periods) = periods(o, &h);
    for p in 0..periods {
        teensy_app.step(&mut teensy.driver);
        stm32_app.step(&mut stm32.driver);
        other_traffic(&other, p);
        h.run_until(
            start + (p + 1) * period,
            &mut [&mut teensy as &mut dyn Serviced, &mut stm32],
        );
        let states = [teensy.driver.state(), stm32.driver.state()];
        after_period(o, &h, &mut trace, p, periods, start, states)?;
    }
    let nodes = [
        NodeReport {
            name: "Teensy 3.6 FlexCAN",
            row: Row::new(
                teensy.driver.traffic(),
                teensy.driver.error_stats(),
                teensy.filtered_out(),
                teensy.lost(),
            ),
            state: teensy.driver.state(),
            counters: teensy.driver.counters(),
        },
        NodeReport {
            name: "STM32F767 bxCAN",
            row: Row::new(
                stm32.driver.traffic(),
                stm32.driver.error_stats(),
                stm32.filtered_out(),
                stm32.lost(),
            ),
            state: stm32.driver.state(),
            counters: stm32.driver.counters(),
        },
    ];
    report(&h, &nodes, &other, [&teensy_app, &stm32_app], trace, o)
}

/// `--async`: the application's async form on the split drivers' async halves. Each
/// period, the host executor runs both nodes' `publish_async` (waiting for room if the
/// queue is full), then both nodes' receive loops (`receive_async` over and over) until
/// the period ends, when the pending receives are dropped: the async API is
/// cancel-safe, so the frames they waited for stay in the rings for the next period.
fn run_async(o: &Args, mut trace: Option<&mut TraceSink>) -> Result<(), String> {
    let Setup {
        mut h,
        mut teensy_app,
        mut stm32_app,
        teensy,
        stm32,
        other,
    } = setup(o)?;
    let (fs, bs) = (FlexState::new(), BxState::new());
    let (mut fi, mut ftx, mut frx) =
        split_flex(&fs, teensy).map_err(|e| format!("Teensy 3.6 can0: {e:?}"))?;
    let (mut bi, mut btx, mut brx) =
        split_bx(&bs, stm32).map_err(|e| format!("STM32F767 CAN1: {e:?}"))?;
    let (start, period, periods) = periods(o, &h);
    for p in 0..periods {
        let end = start + (p + 1) * period;
        other_traffic(&other, p);
        {
            let mut a = pin!(async {
                teensy_app.publish_async(&mut ftx).await;
                Ok(())
            });
            let mut b = pin!(async {
                stm32_app.publish_async(&mut btx).await;
                Ok(())
            });
            // A publish still waiting for room at the period's end is dropped: the app
            // keeps the frame for the next period.
            drive(
                &mut h,
                &mut [&mut fi, &mut bi],
                &mut [a.as_mut(), b.as_mut()],
                end,
            );
        }
        {
            let mut a = pin!(receive_all(&mut teensy_app, &mut frx));
            let mut b = pin!(receive_all(&mut stm32_app, &mut brx));
            let done = drive(
                &mut h,
                &mut [&mut fi, &mut bi],
                &mut [a.as_mut(), b.as_mut()],
                end,
            );
            for (name, r) in ["Teensy 3.6", "STM32F767"].iter().zip(done) {
                if let Some(Err(e)) = r {
                    return Err(format!("{name}: receive failed: {e:?}"));
                }
            }
        }
        while ftx.take_completion().is_some() {}
        while btx.take_completion().is_some() {}
        after_period(
            o,
            &h,
            &mut trace,
            p,
            periods,
            start,
            [fi.state(), bi.state()],
        )?;
    }
    let lost =
        |model_lost: u64, t: twocan_core::TrafficStats| model_lost + t.rx_ring_overflows as u64;
    let (ft, bt) = (fs.traffic(), bs.traffic());
    let bx_model = bi.model.state();
    let nodes = [
        NodeReport {
            name: "Teensy 3.6 FlexCAN",
            row: Row::new(
                ft,
                fs.error_stats(),
                fi.model.frames_discarded(),
                lost(fi.model.frames_lost(), ft),
            ),
            state: fi.state(),
            counters: fs.error_status().map(|s| s.counters).unwrap_or_default(),
        },
        NodeReport {
            name: "STM32F767 bxCAN",
            row: Row::new(
                bt,
                bs.error_stats(),
                bx_model.dropped,
                lost(bx_model.overruns[0] + bx_model.overruns[1], bt),
            ),
            state: bi.state(),
            counters: bs.error_status().map(|s| s.counters).unwrap_or_default(),
        },
    ];
    report(&h, &nodes, &other, [&teensy_app, &stm32_app], trace, o)
}

/// The receive loop of a node: waits for frames and dispatches them, until an error.
async fn receive_all(app: &mut App, rx: &mut impl AsyncCanRx) -> Result<(), twocan_core::Error> {
    loop {
        app.receive_async(rx).await?;
    }
}

/// A simulated board's line of the final table.
struct NodeReport {
    name: &'static str,
    row: Row,
    state: twocan_core::ErrorState,
    counters: twocan_core::ErrorCounters,
}

/// The final table, the applications' counters, and the trace file's summary.
fn report(
    h: &Harness,
    nodes: &[NodeReport; 2],
    other: &Rc<RefCell<SimNode>>,
    apps: [&App; 2],
    trace: Option<&mut TraceSink>,
    o: &Args,
) -> Result<(), String> {
    let bus = h.bus().borrow();
    println!();
    println!(
        "{:<22} {:>8} {:>9} {:>9} {:>5} {:>7} {:>14} {:>9} {:>6}",
        "node", "sent", "received", "filtered", "lost", "errors", "state", "TEC/REC", "load%"
    );
    let load = bus.load() * 100.0;
    for n in nodes {
        println!(
            "{:<22} {:>8} {:>9} {:>9} {:>5} {:>7} {:>14} {:>9} {:>6.1}",
            n.name,
            n.row.sent,
            n.row.received,
            n.row.filtered,
            n.row.lost,
            n.row.errors,
            state_name(n.state),
            format!("{}/{}", n.counters.tec, n.counters.rec),
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
            .filter(|r| matches!(r.result, twocan_sim::TxResult::Acked))
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
    for (name, app) in [("Teensy 3.6", apps[0]), ("STM32F767", apps[1])] {
        let s = app.stats();
        println!(
            "{name:<11} app: heartbeats {} (gaps {}, duplicates {}), measurements {}, status requests {}, answers {}, queue full {}",
            s.heartbeats, s.heartbeat_gaps, s.heartbeat_duplicates, s.measurements, s.requests, s.answers, s.tx_full
        );
    }
    if let (Some(sink), Some(path)) = (trace, &o.trace) {
        sink.flush()
            .map_err(|e| format!("--trace {}: {e}", path.display()))?;
        println!(
            "trace: {} frames written to {}",
            sink.frames_written(),
            path.display()
        );
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
