//! The simulator's fast path (fault-free attempts resolved in one step) against the
//! bit-level path with a FlexCAN model node on the bus: on random seeded scenarios (plain
//! nodes, random traffic, random faults, the model transmitting from MB8 and receiving
//! into its Rx FIFO), `Bus::set_fast_path(true)` and `(false)` give the same trace,
//! statistics, bus time, plain-node counters and reports, and the same model registers
//! and received frames (with their time stamps). The scenarios are
//! `twocan_test_support::scenario`'s; this file plugs the model in.
#![cfg(feature = "model")]

#[path = "model_support.rs"]
mod support;

use support::{accept_all_into_fifo, Rig};
use twocan_core::registers::Registers;
use twocan_core::Frame;
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::regs::{self, code, ecr, mcr};
use twocan_sim::Bus;
use twocan_test_support::scenario::{compare_paths, Lcg, Model};

const MB: usize = 8;

/// A module with the Rx FIFO accepting everything and MB8..15 inactive, synchronised,
/// playing its firmware: reloads MB8 when its frame went (IFLAG1 bit 8, acknowledged)
/// and reads the Rx FIFO out.
struct Module(Rig);

impl Model for Module {
    type Received = (Frame, u32, u16);
    const REGISTERS: &'static str = "ECR IFLAG1 MB8.CS";

    fn start(bus: &mut Bus, _rng: &mut Lcg) -> Self {
        let m = FlexCanModel::mk20dx256();
        accept_all_into_fifo(&m, mcr::SRXDIS);
        bus.attach("fc", m.clone());
        m.modify32(regs::MCR, |v| v & !mcr::HALT);
        bus.run_for(11);
        assert!(m.is_synchronised());
        Module(Rig { m, now: 0 })
    }

    fn refill(&mut self, mine: &[Frame], loaded: &mut usize) {
        let m = &self.0.m;
        let done = m.read32(regs::IFLAG1) & (1 << MB) != 0;
        if done {
            m.write32(regs::IFLAG1, 1 << MB);
        }
        if *loaded < mine.len() && (*loaded == 0 || done) {
            self.0.load_mb(MB, &mine[*loaded], code::TX_DATA);
            *loaded += 1;
        }
    }

    fn drain(&mut self, out: &mut Vec<(Frame, u32, u16)>) {
        while let Some(r) = self.0.pop_fifo() {
            out.push(r);
        }
    }

    fn registers(&self) -> Vec<u32> {
        [regs::ECR, regs::IFLAG1, regs::mb_cs(MB)]
            .iter()
            .map(|&r| self.0.m.read32(r))
            .collect()
    }

    fn error_count(r: &[u32]) -> u32 {
        ecr::TXERRCNT.get(r[0]) + ecr::RXERRCNT.get(r[0])
    }
}

#[test]
fn fast_and_bit_level_paths_agree_with_a_flexcan_model_on_the_bus() {
    let t = compare_paths::<Module>(0..40).unwrap_or_else(|e| panic!("{e}"));
    eprintln!("{t:?}");
    // Both paths were exercised; the model received, sent and saw errors.
    assert!(t.fast_attempts > 100, "{t:?}");
    assert!(t.frames_started > t.fast_attempts + 100, "{t:?}");
    assert!(t.errors > 0, "{t:?}");
    assert!(t.received > 100, "{t:?}");
    assert!(t.sent_by_model > 100, "{t:?}");
}
