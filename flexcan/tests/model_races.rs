//! Register accesses that interleave with a frame on the wire (`Bus::run_bits` stops inside
//! a frame): the abort race and the ESR1 read-then-acknowledge race, reproduced at register
//! level against the model, with the procedure that resolves each.
//!
//! - Abort ("Transmission abort mechanism", MCR\[AEN\] = 1): software reads a pending
//!   mailbox, decides to abort and writes ABORT; if the frame is already on the wire the
//!   abort waits for its outcome. Whether the frame was sent is known only after IFLAG:
//!   CODE = INACTIVE (transmitted) or ABORT (aborted). A driver that counts the frame as
//!   aborted when it writes ABORT counts a frame that was sent (and duplicates it if the
//!   application sends it again).
//! - ESR1: its interrupt flags are write-1-to-clear. Writing back every flag instead of
//!   exactly those read clears a flag raised between the read and the write.
//!
//! On every module of `support::CHIPS`.

#[path = "model_support.rs"]
mod support;

use support::{on_every_chip, Rig};
use twocan_core::registers::Registers;
use twocan_core::Frame;
use twocan_flexcan::model::{Chip, FlexCanModel};
use twocan_flexcan::regs::{self, code, cs, ecr, esr1, mcr};
use twocan_sim::{Bus, Fault, SimNode};

on_every_chip!(
    abort_written_while_the_frame_is_on_the_wire_does_not_abort_a_successful_frame,
    abort_written_while_the_frame_is_on_the_wire_aborts_it_if_the_attempt_fails,
    abort_of_a_mailbox_not_yet_on_the_wire_is_immediate,
    writing_back_every_esr1_flag_loses_one_raised_after_the_read,
    freeze_request_waits_for_the_frame_in_flight_at_the_lowest_bit_rate,
);

const MB: usize = 8;

/// A module with the Rx FIFO accepting everything, `extra` MCR bits, optionally a TEC
/// written in freeze, on `bus`, synchronised.
fn module(chip: Chip, bus: &mut Bus, extra: u32, tec: Option<u32>) -> FlexCanModel {
    let m = FlexCanModel::new(chip);
    support::accept_all_into_fifo(&m, mcr::SRXDIS | extra);
    if let Some(tec) = tec {
        m.write32(regs::ECR, ecr::TXERRCNT.val(tec));
    }
    bus.attach("m", m.clone());
    m.modify32(regs::MCR, |v| v & !mcr::HALT);
    bus.run_for(11);
    assert!(m.is_synchronised());
    m
}

fn load(m: &FlexCanModel, f: &Frame) {
    let mut rig = Rig {
        m: m.clone(),
        now: 0,
    };
    rig.load_mb(MB, f, code::TX_DATA);
}

fn mb_code(m: &FlexCanModel) -> u32 {
    cs::CODE.get(m.read32(regs::mb_cs(MB)))
}

/// The driver's abort request: ABORT written into the C/S word.
fn write_abort(m: &mut FlexCanModel) {
    let c = m.read32(regs::mb_cs(MB));
    m.write32(regs::mb_cs(MB), cs::CODE.replace(c, code::TX_ABORT));
}

fn abort_written_while_the_frame_is_on_the_wire_does_not_abort_a_successful_frame(chip: Chip) {
    let mut bus = Bus::new(500_000).unwrap();
    let mut m = module(chip, &mut bus, mcr::AEN, None);
    let peer = SimNode::new().shared();
    bus.attach("peer", peer.clone());
    let f = Frame::standard(0x123, &[1, 2, 3]).unwrap();
    load(&m, &f);

    // 20 bits into the frame: the module is transmitting.
    bus.run_bits(20);
    assert!(bus.in_frame());
    assert_ne!(
        m.read32(regs::ESR1) & esr1::TX,
        0,
        "ESR1[TX] while on the wire"
    );
    assert_eq!(m.read32(regs::ESR1) & esr1::IDLE, 0);

    // The driver sees a pending mailbox and aborts it.
    assert_eq!(mb_code(&m), code::TX_DATA);
    write_abort(&mut m);
    // Nothing is decided yet: no IFLAG, the mailbox still transmits.
    assert_eq!(m.read32(regs::IFLAG1) & (1 << MB), 0);
    assert_eq!(mb_code(&m), code::TX_DATA);

    bus.run_until_idle(10_000).unwrap();
    // The frame went out: IFLAG with CODE = INACTIVE, not ABORT. Deciding "aborted" at the
    // write (the atomic-frame view) would be wrong: the peer has the frame.
    assert_ne!(m.read32(regs::IFLAG1) & (1 << MB), 0);
    assert_eq!(mb_code(&m), code::TX_INACTIVE);
    assert_eq!(peer.borrow().received_frames(), vec![f]);
    assert_ne!(m.read32(regs::ESR1) & esr1::IDLE, 0);
}

fn abort_written_while_the_frame_is_on_the_wire_aborts_it_if_the_attempt_fails(chip: Chip) {
    let mut bus = Bus::new(500_000).unwrap();
    let mut m = module(chip, &mut bus, mcr::AEN, None);
    let peer = SimNode::new().shared();
    bus.attach("peer", peer.clone());
    let f = Frame::standard(0x124, &[4]).unwrap();
    load(&m, &f);
    bus.inject_next(Fault::Bit { at: None });
    bus.run_bits(5);
    write_abort(&mut m);
    bus.run_until_idle(10_000).unwrap();
    // Failed attempt + captured abort: aborted, no retransmission.
    assert_ne!(m.read32(regs::IFLAG1) & (1 << MB), 0);
    assert_eq!(mb_code(&m), code::TX_ABORT);
    assert!(peer.borrow().received_frames().is_empty());
    assert_eq!(bus.trace().records().len(), 1);
}

fn abort_of_a_mailbox_not_yet_on_the_wire_is_immediate(chip: Chip) {
    let mut bus = Bus::new(500_000).unwrap();
    let mut m = module(chip, &mut bus, mcr::AEN, None);
    let f = Frame::standard(0x125, &[]).unwrap();
    load(&m, &f);
    write_abort(&mut m);
    assert_ne!(m.read32(regs::IFLAG1) & (1 << MB), 0);
    assert_eq!(mb_code(&m), code::TX_ABORT);
    bus.run_until_idle(10_000).unwrap();
    assert!(bus.trace().records().is_empty());
}

fn writing_back_every_esr1_flag_loses_one_raised_after_the_read(chip: Chip) {
    for exact in [false, true] {
        let mut bus = Bus::new(500_000).unwrap();
        // TEC 240 (ECR written in Freeze mode): one error → 248, the next → bus-off.
        let m = module(chip, &mut bus, 0, Some(240));
        let peer = SimNode::new().shared();
        bus.attach("peer", peer.clone());
        let f = Frame::standard(0x126, &[6]).unwrap();
        load(&m, &f);
        bus.inject_next(Fault::Bit { at: None });
        let first = bus.step().unwrap();
        assert!(!first.record().unwrap().is_error_free());

        // The driver reads ESR1: ERRINT, not yet BOFFINT.
        let read = m.read32(regs::ESR1);
        assert_ne!(read & esr1::ERRINT, 0);
        assert_eq!(read & esr1::BOFFINT, 0);

        // The retransmission hits a bit error too, before the driver writes back: TEC
        // 248 + 8 > 255, bus-off, BOFFINT.
        bus.inject_next(Fault::Bit { at: None });
        while m.read32(regs::ESR1) & esr1::BOFFINT == 0 {
            bus.run_bits(1);
        }
        assert!(
            bus.in_frame(),
            "the flag came while the error frame is on the wire"
        );

        let ack = if exact {
            read & esr1::W1C_BITS
        } else {
            esr1::W1C_BITS
        };
        m.write32(regs::ESR1, ack);
        let after = m.read32(regs::ESR1);
        if exact {
            assert_ne!(
                after & esr1::BOFFINT,
                0,
                "acknowledging what was read keeps it"
            );
        } else {
            assert_eq!(after & esr1::BOFFINT, 0, "the bus-off event is lost");
        }
        assert_eq!(after & esr1::ERRINT, 0);
    }
}

fn freeze_request_waits_for_the_frame_in_flight_at_the_lowest_bit_rate(chip: Chip) {
    use twocan_core::timing::frame_time::{bits_to_micros, MAX_FRAME_IN_FLIGHT_BITS};
    use twocan_sim::frame_bits;
    let mut bus = Bus::new(2_500).unwrap();
    let m = module(chip, &mut bus, 0, None);
    let peer = SimNode::new().shared();
    bus.attach("peer", peer.clone());
    let f = Frame::extended(0, &[0; 8]).unwrap();
    let total = u64::from(frame_bits(&f).total);
    load(&m, &f);
    bus.run_bits(1);
    m.modify32(regs::MCR, |v| v | mcr::FRZ | mcr::HALT);
    let mut waited = 0;
    while m.read32(regs::MCR) & mcr::FRZACK == 0 {
        assert!(bus.in_frame(), "FRZACK only at the end of the frame");
        bus.run_bits(1);
        waited += 1;
        assert!(waited < 1_000);
    }
    assert_eq!(waited, total - 1);
    let us = bus.bits_to_micros(waited);
    assert!(us > 18_000 && us <= bits_to_micros(MAX_FRAME_IN_FLIGHT_BITS, 2_500).unwrap());
    // The frame was sent before freeze.
    assert_eq!(peer.borrow().received_frames(), vec![f]);
    assert_eq!(mb_code(&m), code::TX_INACTIVE);
}
