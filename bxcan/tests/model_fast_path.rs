//! The simulator's fast path (fault-free attempts resolved in one step) against the
//! bit-level path with a bxCAN model node on the bus: on random seeded scenarios (plain
//! nodes, random traffic, random faults, the model transmitting from its three mailboxes
//! and receiving into FIFO 0), `Bus::set_fast_path(true)` and `(false)` give the same
//! trace, statistics, bus time, plain-node counters and reports, and the same model
//! registers and received frames. The scenarios are `twocan_test_support::scenario`'s;
//! this file plugs the model in.
#![cfg(feature = "model")]

#[path = "model_bus.rs"]
mod tiny;

use tiny::{enter_init, load, receive, Received};
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{self, esr, fa1r, fmr, fs1r, msr, tsr};
use twocan_core::{Frame, Registers};
use twocan_sim::Bus;
use twocan_test_support::scenario::{compare_paths, Lcg, Model};

/// CAN1 accepting everything into FIFO 0 (bank 0, 32-bit mask 0), with NART on one
/// scenario in four and automatic bus-off recovery, playing its firmware: refills empty
/// mailboxes and reads FIFO 0 out.
struct Can1(BxCanModel);

impl Model for Can1 {
    type Received = Received;
    const REGISTERS: &'static str = "MSR TSR RF0R ESR";

    fn start(bus: &mut Bus, rng: &mut Lcg) -> Self {
        let nart = if rng.draw().is_multiple_of(4) {
            regs::mcr::NART
        } else {
            0
        };
        let mut m = BxCanModel::can1();
        bus.attach("bx", m.clone());
        enter_init(&mut m);
        m.modify32(regs::FMR, |v| v | fmr::FINIT);
        m.modify32(regs::FS1R, |v| v | fs1r::fsc(0));
        m.write32(regs::fir1(0), 0);
        m.write32(regs::fir2(0), 0);
        m.modify32(regs::FA1R, |v| v | fa1r::fact(0));
        m.modify32(regs::FMR, |v| v & !fmr::FINIT);
        m.write32(regs::MCR, nart | regs::mcr::ABOM);
        bus.run_until_idle(100).unwrap();
        assert_eq!(m.read32(regs::MSR) & msr::INAK, 0);
        Can1(m)
    }

    fn refill(&mut self, mine: &[Frame], loaded: &mut usize) {
        for x in 0..3 {
            if *loaded < mine.len() && self.0.read32(regs::TSR) & tsr::tme(x) != 0 {
                load(&mut self.0, x, &mine[*loaded]);
                *loaded += 1;
            }
        }
    }

    fn drain(&mut self, out: &mut Vec<Received>) {
        while let Some(r) = receive(&mut self.0, 0) {
            out.push(r);
        }
    }

    fn registers(&self) -> Vec<u32> {
        [regs::MSR, regs::TSR, regs::RF0R, regs::ESR]
            .iter()
            .map(|&r| self.0.read32(r))
            .collect()
    }

    fn error_count(r: &[u32]) -> u32 {
        esr::TEC.get(r[3]) + esr::REC.get(r[3])
    }
}

#[test]
fn fast_and_bit_level_paths_agree_with_a_bxcan_model_on_the_bus() {
    let t = compare_paths::<Can1>(0..40).unwrap_or_else(|e| panic!("{e}"));
    eprintln!("{t:?}");
    // Both paths were exercised, and the model saw errors in some scenarios.
    assert!(t.fast_attempts > 100, "{t:?}");
    assert!(t.frames_started > t.fast_attempts + 100, "{t:?}");
    assert!(t.errors > 0, "{t:?}");
    assert!(t.received > 100, "{t:?}");
    assert!(t.sent_by_model > 100, "{t:?}");
}
