//! Simulator speed: simulated CAN frames per host second.
//!
//! Each scenario runs batches of frames until at least [`MIN_SECS`] of host time have
//! passed, counting only frames delivered to a receiver, and the time of the bus run
//! (frame construction and queueing included).

use std::time::{Duration, Instant};

use twocan_core::sim::{Bus, SimNode};
use twocan_core::Frame;

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

/// `senders` SimNodes (identifiers 0x100 + node) each sending 8-byte frames, one more
/// listening node; with or without the trace.
pub fn bare_bus(senders: usize, tracing: bool) -> Result<Speed> {
    let mut bus = Bus::new(BITRATE).context("Bus::new")?;
    bus.set_tracing(tracing);
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
    Ok(Speed {
        scenario: format!(
            "bare bus: {senders} SimNode sender{} + 1 listener, 8-byte frames, trace {}",
            if senders == 1 { "" } else { "s (arbitration)" },
            if tracing { "on" } else { "off" }
        ),
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
    /// Runs `trial` [`TRIALS`] times.
    pub fn run(mut trial: impl FnMut() -> Result<Speed>) -> Result<Trials> {
        let mut runs = Vec::new();
        for _ in 0..TRIALS {
            let s = trial()?;
            if s.frames == 0 || s.secs < Duration::from_millis(100).as_secs_f64() {
                return Err(Error::new(format!("scenario `{}` did not run", s.scenario)));
            }
            runs.push(s);
        }
        Ok(Trials { runs })
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
