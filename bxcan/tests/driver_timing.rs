//! Issue 22, item 6: the bit timings bxCAN reports are the ones every entry point
//! accepts. The slowest `CAN_BTR` timing (BRP 1024, 1 + 16 + 8 quanta: 25,600 APB1
//! clocks per bit, 2,109.375 bit/s at 54 MHz) is accepted by `Config::from_timing` and by
//! `set_timing` on a stopped controller, and the capabilities' slowest rate does not
//! exclude it.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_bxcan::Config;
use twocan_core::timing::{Limits, Timing, DEFAULT_TOLERANCE_PPM};
use twocan_core::{Hardware, Mode};

/// The slowest timing the `CAN_BTR` fields hold, wished at `wished` bit/s.
fn slowest(wished: u32) -> Timing {
    Timing::from_tsegs(APB1, wished, &Limits::BXCAN, 1024, 16, 8)
}

#[test]
fn slowest_register_timing_is_accepted_by_every_entry_point() {
    let t = slowest(2_109);
    assert_eq!(t.clocks_per_bit(), 25_600);
    assert!(t.consistency().is_ok());
    // The builder takes it.
    assert!(Config::from_timing(t, DEFAULT_TOLERANCE_PPM).is_ok());
    // The running driver reports a slowest rate that includes it, and takes it too.
    let (can, _regs, _bus) = can1_with(&config(), &pass_all());
    let mut d = driver(can);
    let caps = d.capabilities();
    assert!(caps.min_bitrate <= t.actual_bitrate(), "{caps:?}");
    d.set_mode(Mode::Stopped).unwrap();
    assert_eq!(d.hardware().set_timing(&t), Ok(()));
    assert_eq!(d.hardware().set_timing(&slowest(2_110)), Ok(()));
}
