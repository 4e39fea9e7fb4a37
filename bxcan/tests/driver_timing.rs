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
use twocan_core::Mode;

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
    assert_eq!(d.set_timing(&t), Ok(()));
    assert_eq!(d.set_timing(&slowest(2_110)), Ok(()));
}

/// The reset-value table of `docs/differences.md`: `CAN_IER` resets to 0 and the driver
/// writes `DEFAULT_INTERRUPTS`, the 11 sources the table names (0x0001_8F5B: FIFO full
/// and sleep acknowledge off); `CAN_FMR.FINIT` (1 at reset) is 0 once the filters are
/// programmed, and the controller has left sleep mode (`SLEEP` 1 at reset).
#[test]
fn registers_the_reset_value_table_names() {
    use twocan_bxcan::config::DEFAULT_INTERRUPTS;
    use twocan_bxcan::model::BxCanModel;
    use twocan_bxcan::regs::{self, fmr, ier, mcr};
    use twocan_core::Registers;
    let fresh = BxCanModel::can1();
    assert_eq!(fresh.read32(regs::IER), 0);
    assert_eq!(fresh.read32(regs::FMR) & fmr::FINIT, fmr::FINIT);
    assert_eq!(fresh.read32(regs::MCR) & mcr::SLEEP, mcr::SLEEP);
    assert_eq!(DEFAULT_INTERRUPTS, 0x0001_8F5B);
    assert_eq!(DEFAULT_INTERRUPTS.count_ones(), 11);
    assert_eq!(
        DEFAULT_INTERRUPTS & (ier::FFIE0 | ier::FFIE1 | ier::SLKIE),
        0
    );
    let (_can, clocked, _bus) = can1_with(&config(), &pass_all());
    let m = &clocked.model;
    assert_eq!(m.read32(regs::IER), DEFAULT_INTERRUPTS);
    assert_eq!(m.read32(regs::FMR) & fmr::FINIT, 0);
    assert_eq!(m.read32(regs::MCR) & (mcr::SLEEP | mcr::INRQ), 0);
}
