//! Simulator speed: simulated CAN frames per host second.
//!
//! Each scenario runs batches of frames until at least [`MIN_SECS`] of host time have
//! passed, counting only frames delivered to a receiver, and the time of the bus run
//! (frame construction and queueing included).
//!
//! Every scenario runs twice in the same command, trial by trial: with the bus's fast
//! path (the default: an attempt that cannot fail is resolved without playing its bits,
//! `twocan_sim` `fast.rs`) and forced onto the bit-level path
//! (`Bus::set_fast_path(false)`), so the report gives the fast path's speed as a ratio
//! to the bit-level path measured in the same run ([`SimRow`]).

use std::time::{Duration, Instant};

use twocan_core::Frame;
use twocan_sim::{Bus, SimNode};

use crate::cmd::{Context, Error, Result};

/// Host time each trial of a scenario runs for at least.
pub const MIN_SECS: f64 = 0.5;
/// Trials of each scenario (the report gives the median and the range).
pub const TRIALS: usize = 3;
/// Frames per batch and node.
const BATCH: usize = 2_000;
/// The simulated bit rate (it only converts bit times to seconds).
pub const BITRATE: u32 = 500_000;

/// The result of one trial of a scenario.
#[derive(Debug, Clone)]
pub struct Speed {
    /// What ran.
    pub scenario: String,
    /// Frames delivered.
    pub frames: u64,
    /// Host seconds.
    pub secs: f64,
    /// Simulated bus seconds.
    pub bus_secs: f64,
}

impl Speed {
    /// Frames per host second.
    pub fn frames_per_sec(&self) -> f64 {
        self.frames as f64 / self.secs
    }

    /// Simulated seconds per host second.
    pub fn speedup(&self) -> f64 {
        self.bus_secs / self.secs
    }
}

fn frame(id: u16, n: u64) -> Result<Frame> {
    Frame::standard(id, &n.to_le_bytes())
        .map_err(|e| Error::new(format!("building a frame: {e:?}")))
}

/// Checks that the run took the path it was asked for: with the fast path on, some
/// attempts were resolved by it; off, none.
pub fn check_path(fast_path: bool, fast_attempts: u64, scenario: &str) -> Result<()> {
    if fast_path == (fast_attempts > 0) {
        Ok(())
    } else {
        Err(Error::new(format!(
            "`{scenario}`: fast path {}, but {fast_attempts} attempts took it",
            if fast_path { "on" } else { "off" }
        )))
    }
}

/// `senders` SimNodes (identifiers 0x100 + node) each sending 8-byte frames, one more
/// listening node; with or without the trace; on the fast path or forced onto the
/// bit-level path.
pub fn bare_bus(senders: usize, tracing: bool, fast_path: bool) -> Result<Speed> {
    let mut bus = Bus::new(BITRATE).context("Bus::new")?;
    bus.set_tracing(tracing);
    bus.set_fast_path(fast_path);
    let nodes: Vec<_> = (0..senders).map(|_| SimNode::new().shared()).collect();
    for (k, n) in nodes.iter().enumerate() {
        bus.attach(&format!("tx{k}"), n.clone());
    }
    let listener = SimNode::new().shared();
    bus.attach("rx", listener.clone());
    let start = Instant::now();
    let mut delivered = 0u64;
    let mut n = 0u64;
    while start.elapsed().as_secs_f64() < MIN_SECS {
        for (k, node) in nodes.iter().enumerate() {
            let mut node = node.borrow_mut();
            for _ in 0..BATCH {
                node.send(frame(0x100 + k as u16, n)?);
                n += 1;
            }
        }
        bus.run_until_idle(u64::MAX / 2)
            .map_err(|b| Error::new(format!("the bus stayed busy until bit {}", b.now)))?;
        // Count and forget what the listener received, so memory stays flat.
        let got = listener.borrow().received().len() as u64;
        delivered += got;
        *listener.borrow_mut() = SimNode::new();
        for node in &nodes {
            *node.borrow_mut() = SimNode::new();
        }
        if tracing {
            bus.trace_mut().clear();
        }
    }
    let secs = start.elapsed().as_secs_f64();
    if delivered != n {
        return Err(Error::new(format!(
            "the listener received {delivered} of {n} frames"
        )));
    }
    let scenario = format!(
        "bare bus: {senders} SimNode sender{} + 1 listener, 8-byte frames, trace {}",
        if senders == 1 { "" } else { "s (arbitration)" },
        if tracing { "on" } else { "off" }
    );
    check_path(fast_path, bus.fast_path_attempts(), &scenario)?;
    Ok(Speed {
        scenario,
        frames: delivered,
        secs,
        bus_secs: bus.now() as f64 / BITRATE as f64,
    })
}

/// The trials of one scenario.
#[derive(Debug, Clone)]
pub struct Trials {
    /// Each trial, in the order run.
    pub runs: Vec<Speed>,
}

impl Trials {
    /// Checks that one trial ran (frames delivered, enough host time).
    fn run_once(s: Speed) -> Result<Speed> {
        if s.frames == 0 || s.secs < Duration::from_millis(100).as_secs_f64() {
            return Err(Error::new(format!("scenario `{}` did not run", s.scenario)));
        }
        Ok(s)
    }

    /// The scenario's description.
    pub fn scenario(&self) -> &str {
        self.runs.first().map(|s| s.scenario.as_str()).unwrap_or("")
    }

    fn sorted(&self) -> Vec<&Speed> {
        let mut v: Vec<&Speed> = self.runs.iter().collect();
        v.sort_by(|a, b| a.frames_per_sec().total_cmp(&b.frames_per_sec()));
        v
    }

    /// The trial with the median frames per second.
    pub fn median(&self) -> &Speed {
        let v = self.sorted();
        v[v.len() / 2]
    }

    /// The slowest and fastest trials' frames per second.
    pub fn range(&self) -> (f64, f64) {
        let v = self.sorted();
        (v[0].frames_per_sec(), v[v.len() - 1].frames_per_sec())
    }
}

/// One scenario on the fast path and forced onto the bit-level path, measured in the
/// same run with the trials interleaved (fast, bit-level, fast, ...), so that both see
/// the same load on the shared host.
#[derive(Debug, Clone)]
pub struct SimRow {
    /// With the fast path (the bus's default).
    pub fast: Trials,
    /// With `Bus::set_fast_path(false)`.
    pub bit_level: Trials,
}

impl SimRow {
    /// Runs `trial(fast_path)` [`TRIALS`] times each way, interleaved.
    pub fn run(mut trial: impl FnMut(bool) -> Result<Speed>) -> Result<SimRow> {
        let mut fast = Vec::new();
        let mut bit_level = Vec::new();
        for _ in 0..TRIALS {
            fast.push(Trials::run_once(trial(true)?)?);
            bit_level.push(Trials::run_once(trial(false)?)?);
        }
        Ok(SimRow {
            fast: Trials { runs: fast },
            bit_level: Trials { runs: bit_level },
        })
    }

    /// Median frames per second on the fast path over the median on the bit-level path.
    pub fn ratio(&self) -> f64 {
        self.fast.median().frames_per_sec() / self.bit_level.median().frames_per_sec()
    }
}
