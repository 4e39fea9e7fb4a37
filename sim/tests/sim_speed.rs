//! Simulator speed on the bare bus (two `SimNode`s, tracing off), fast path and bit-level
//! path in the same run. Ignored by default (timing is meaningful in release mode only):
//!
//! ```text
//! cargo test --release -p twocan-sim --test sim_speed -- --ignored --nocapture
//! ```

use std::time::Instant;

use twocan_core::Frame;
use twocan_sim::{Bus, SimNode};

/// Frames per host second for `frames` frames of 8 bytes from one node to another.
fn frames_per_second(frames: u32, fast: bool) -> f64 {
    let mut bus = Bus::new(1_000_000).unwrap();
    bus.set_tracing(false);
    bus.set_fast_path(fast);
    let a = SimNode::new().shared();
    let b = SimNode::new().shared();
    bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    for i in 0..frames {
        let d = i.to_le_bytes();
        a.borrow_mut().send(
            Frame::standard((i % 0x800) as u16, &[d[0], d[1], d[2], d[3], 1, 2, 3, 4]).unwrap(),
        );
    }
    let start = Instant::now();
    let mut done = 0u32;
    while done < frames {
        bus.step().unwrap();
        done += 1;
    }
    let secs = start.elapsed().as_secs_f64();
    assert_eq!(b.borrow().received().len(), frames as usize);
    f64::from(frames) / secs
}

#[test]
#[ignore = "timing: run in release mode with --ignored"]
fn bare_bus_speed() {
    let n = 400_000;
    let fast = frames_per_second(n, true);
    let slow = frames_per_second(n, false);
    println!(
        "bare bus: fast path {fast:.0} frames/s, bit-level path {slow:.0} frames/s, ratio {:.2}",
        fast / slow
    );
    assert!(fast > slow);
}
