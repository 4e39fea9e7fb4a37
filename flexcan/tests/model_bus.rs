//! The bus side: self reception, listen-only, loop-back ("Self reception", "Listen-only
//! mode", "Loop-back mode"), and modules on the simulated bus of `twocan_sim`, on every
//! module of `support::CHIPS`.

#[path = "model_support.rs"]
mod support;

use support::*;
use twocan_core::registers::Registers;
use twocan_flexcan::model::{Chip, FlexCanModel};
use twocan_flexcan::regs::{self, code, ctrl1, mcr};
use twocan_sim::{Bus, BusNode, SimNode, TxResult};

on_every_chip!(
    self_reception_on_and_off,
    listen_only_receives_but_never_acknowledges_nor_transmits,
    loop_back_is_internal_and_deaf_to_the_bus,
    loop_back_synchronises_on_its_own_recessive_output,
    two_modules_and_a_plain_node_on_the_simulated_bus,
    a_lone_module_stops_at_error_passive_on_the_simulated_bus,
    extreme_bus_times_do_not_overflow,
);

/// A started module with the Rx FIFO accepting everything; `srxdis` and CTRL1 `bits`
/// as given.
fn rig(chip: Chip, srxdis: bool, bits: u32) -> Rig {
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    r.setup_fifo(0, true, &[0; 8], &[0; 8], 0);
    if srxdis {
        r.set_bits(regs::MCR, mcr::SRXDIS);
    } else {
        r.clear_bits(regs::MCR, mcr::SRXDIS);
    }
    r.ctrl1(bits);
    r.start();
    r
}

fn self_reception_on_and_off(chip: Chip) {
    let frame = std(0x123, &[1, 2]);
    let mut r = rig(chip, false, 0);
    r.load_mb(8, &frame, code::TX_DATA);
    let req = r.m.poll_tx(r.now).unwrap();
    assert!(!req.internal && !req.self_ack, "on the wire");
    r.transmit_all();
    assert_eq!(r.drain_fifo(), vec![(frame, 0)]);

    let mut r = rig(chip, true, 0);
    r.load_mb(8, &frame, code::TX_DATA);
    r.transmit_all();
    assert_eq!(r.m.fifo_len(), 0);
    assert_eq!(r.rd(regs::IFLAG1), 1 << 8, "transmitted all the same");
}

fn listen_only_receives_but_never_acknowledges_nor_transmits(chip: Chip) {
    let mut r = rig(chip, true, ctrl1::LOM);
    assert!(r.m.listens());
    assert!(!r.m.acknowledges());
    assert!(!r.m.error_active(), "listen-only behaves as error passive");
    // ESR1[FLTCONF] reads error passive in listen-only mode, with both counters at 0.
    let esr1 = r.m.peek32(regs::ESR1);
    assert_eq!(
        twocan_flexcan::regs::esr1::FLTCONF.get(esr1),
        twocan_flexcan::regs::esr1::FLTCONF_ERROR_PASSIVE
    );
    assert_eq!(r.rd(regs::ECR), 0);
    r.load_mb(8, &std(0x1, &[]), code::TX_DATA);
    assert!(r.m.poll_tx(r.now).is_none());
    r.deliver(&ext(0x1_0000, &[9]));
    assert_eq!(r.drain_fifo(), vec![(ext(0x1_0000, &[9]), 0)]);
    assert_eq!(r.code(8), code::TX_DATA, "still pending");
}

fn loop_back_is_internal_and_deaf_to_the_bus(chip: Chip) {
    let mut r = rig(chip, false, ctrl1::LPB);
    assert!(!r.m.listens() && !r.m.acknowledges());
    r.deliver(&std(0x7, &[]));
    assert_eq!(r.m.fifo_len(), 0, "the bus is not sampled");
    r.load_mb(8, &std(0x8, &[8]), code::TX_DATA);
    let req = r.m.poll_tx(r.now).unwrap();
    assert!(req.internal && req.self_ack);
    assert_eq!(r.transmit(TxResult::Acked), Some(std(0x8, &[8])));
    assert_eq!(r.drain_fifo(), vec![(std(0x8, &[8]), 0)]);
    // Loop-back with self reception disabled: sent, not received.
    let mut r = rig(chip, true, ctrl1::LPB);
    r.load_mb(8, &std(0x8, &[8]), code::TX_DATA);
    r.transmit_all();
    assert_eq!(r.m.fifo_len(), 0);
}

fn loop_back_synchronises_on_its_own_recessive_output(chip: Chip) {
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    r.ctrl1(ctrl1::LPB);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.busy(11); // bus traffic does not matter: the receiver sees the Tx pin
    assert!(r.m.is_synchronised());
}

/// A module set up for the bus: FIFO accepting everything, given SRXDIS, left in freeze.
fn module(m: &mut FlexCanModel, srxdis: bool) {
    support::accept_all_into_fifo(m, if srxdis { mcr::SRXDIS } else { 0 });
}

fn start(m: &mut FlexCanModel) {
    m.modify32(regs::MCR, |v| v & !mcr::HALT);
}

fn fifo_frames(m: &mut FlexCanModel) -> Vec<twocan_core::Frame> {
    let mut out = Vec::new();
    while m.read32(regs::IFLAG1) & (1 << 5) != 0 {
        let c = m.read32(regs::mb_cs(0));
        let i = m.read32(regs::mb_id(0));
        let w0 = m.read32(regs::mb_word0(0));
        let w1 = m.read32(regs::mb_word1(0));
        out.push(decode(c, i, w0, w1));
        m.write32(regs::IFLAG1, 1 << 5);
    }
    out
}

fn two_modules_and_a_plain_node_on_the_simulated_bus(chip: Chip) {
    let mut bus = Bus::new(500_000).unwrap();
    let mut a = FlexCanModel::new(chip);
    let mut b = FlexCanModel::new(chip);
    let sniffer = SimNode::new().with_listen_only(true).shared();
    module(&mut a, true);
    module(&mut b, false);
    bus.attach("a", a.clone());
    bus.attach("b", b.clone());
    bus.attach("sniffer", sniffer.clone());
    start(&mut a);
    start(&mut b);

    // Two frames from a, one from b: lowest ID first on the wire.
    let f1 = std(0x300, &[1]);
    let f2 = ext(0x0AB_CDEF, &[2, 2]);
    let f3 = std(0x100, &[3, 3, 3]);
    let load = |m: &mut FlexCanModel, n: usize, f: &twocan_core::Frame, c: u32| {
        let mut r = Rig {
            m: m.clone(),
            now: 0,
        };
        r.load_mb(n, f, c);
    };
    load(&mut a, 8, &f1, code::TX_DATA);
    load(&mut a, 9, &f2, code::TX_DATA);
    load(&mut b, 8, &f3, code::TX_DATA);
    bus.run_until_idle(10_000).unwrap();

    let mut expect = vec![f1, f2, f3];
    expect.sort_by_key(|f| f.priority());
    assert_eq!(sniffer.borrow().received_frames(), expect);
    assert_eq!(
        fifo_frames(&mut b),
        expect,
        "b receives a's frames and its own"
    );
    assert_eq!(fifo_frames(&mut a), vec![f3], "a has self reception off");
    assert_eq!(a.read32(regs::IFLAG1) & 0x300, 0x300);
    assert_eq!(
        a.error_counters(),
        twocan_core::ErrorCounters { tec: 0, rec: 0 }
    );

    // Remote request from a answered by b's RANSWER mailbox; a's REMOTE mailbox turns
    // into a receive mailbox and takes the answer (mailboxes before the FIFO: MRP). A
    // remote request that b's FIFO filters accept would go to the FIFO unanswered, so b's
    // filters now check RTR (= 0: data frames only).
    let answer = std(0x444, &[4, 4, 4, 4]);
    b.modify32(regs::MCR, |v| v | mcr::FRZ | mcr::HALT);
    for n in 0..8 {
        b.write32(regs::rximr(n), 1 << 31);
    }
    start(&mut b);
    load(&mut b, 10, &answer, code::RX_RANSWER);
    a.modify32(regs::MCR, |v| v | mcr::FRZ | mcr::HALT);
    a.modify32(regs::CTRL2, |v| v | regs::ctrl2::MRP);
    start(&mut a);
    load(&mut a, 10, &remote(0x444, false, 4), code::TX_REMOTE);
    bus.run_until_idle(10_000).unwrap();
    let got = sniffer.borrow().received_frames();
    assert_eq!(&got[3..], &[remote(0x444, false, 4), answer]);
    let mut ra = Rig {
        m: a.clone(),
        now: 0,
    };
    assert_eq!(ra.read_mb(10).0, answer);
    assert_eq!(
        Rig {
            m: b.clone(),
            now: 0
        }
        .code(10),
        code::RX_RANSWER
    );
}

fn a_lone_module_stops_at_error_passive_on_the_simulated_bus(chip: Chip) {
    let mut bus = Bus::new(125_000).unwrap();
    let mut a = FlexCanModel::new(chip);
    module(&mut a, true);
    bus.attach("a", a.clone());
    start(&mut a);
    let mut r = Rig {
        m: a.clone(),
        now: 0,
    };
    r.load_mb(8, &std(0x10, &[]), code::TX_DATA);
    bus.run_for(20_000);
    assert_eq!(
        a.error_counters().tec,
        128,
        "no acknowledge: passive, then no more counting"
    );
    assert_ne!(a.read32(regs::ESR1) & regs::esr1::ACKERR, 0);
    assert_eq!(r.code(8), code::TX_DATA);
}

fn extreme_bus_times_do_not_overflow(chip: Chip) {
    use twocan_sim::BusTime;
    let end = BusTime {
        sof: u64::MAX,
        now: u64::MAX,
    };
    // Received and transmitted frames stamped at the very end of time.
    let mut r = rig(chip, false, 0);
    r.m.rx(&std(0x10, &[1]), false, end);
    assert_eq!(r.m.fifo_len(), 1);
    let frame = std(0x11, &[2]);
    r.load_mb(8, &frame, code::TX_DATA);
    r.m.tx_result(&frame, TxResult::Acked, end);
    assert_eq!(r.code(8), code::TX_INACTIVE);
    r.m.advance(u64::MAX, true, u64::MAX);
    // Waiting for synchronisation with a frame pending: the wake-up saturates.
    let mut r = rig(chip, false, 0);
    r.freeze();
    r.clear_bits(regs::MCR, mcr::HALT);
    assert!(!r.m.is_synchronised());
    r.load_mb(8, &frame, code::TX_DATA);
    assert_eq!(r.m.next_wakeup(u64::MAX - 1), Some(u64::MAX));
    assert_eq!(r.m.next_wakeup(u64::MAX), Some(u64::MAX));
    // Bus-off with a frame pending: the recovery wake-up saturates too.
    let mut r = rig(chip, false, 0);
    r.load_mb(8, &frame, code::TX_DATA);
    for _ in 0..32 {
        r.m.tx_result(
            &frame,
            TxResult::Error(twocan_core::error::LastErrorCode::BitDominant),
            BusTime {
                sof: r.now,
                now: r.now,
            },
        );
    }
    assert_eq!(
        twocan_flexcan::regs::esr1::FLTCONF.get(r.m.peek32(regs::ESR1)),
        twocan_flexcan::regs::esr1::FLTCONF_BUS_OFF
    );
    assert_eq!(r.m.next_wakeup(u64::MAX), Some(u64::MAX));
    r.m.rx_error(
        twocan_core::error::LastErrorCode::Crc,
        false,
        BusTime {
            sof: u64::MAX,
            now: u64::MAX,
        },
    );
}
