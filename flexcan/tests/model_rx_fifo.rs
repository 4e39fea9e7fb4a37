//! Rx FIFO and ID filter table ("Rx FIFO structure", "Rx FIFO", CTRL2[RFFN] table "Rx FIFO
//! filter: possible structures", RXIMR/RXMGMASK/RXFGMASK, RXFIR, "Matching process"), on
//! every module of `support::CHIPS`.

#[path = "model_support.rs"]
mod support;

use support::*;
use twocan_flexcan::model::Chip;
use twocan_flexcan::regs::{self, code, cs, ctrl1, ctrl2, iflag1, mcr};

on_every_chip!(
    loop_back_data_and_remote_frames_through_the_fifo,
    fifo_output_window_and_table_area_are_not_mailboxes,
    filter_table_split_for_each_rffn,
    idhit_numbers_every_element_of_the_14_18_table,
    rtr_and_ide_bits_of_format_a_elements,
    fifo_is_six_deep_warns_at_five_and_overflows,
    mailbox_reception_priority_against_the_fifo,
    format_b_and_c_and_d,
    remote_request_matching_the_fifo_is_stored_not_answered,
);

fn loop_back_data_and_remote_frames_through_the_fifo(chip: Chip) {
    let mut r = Rig::loopback_fifo(chip);
    let data = std(0x542, &[1, 2, 3, 4, 5, 6, 7, 8]);
    let rtr = remote(0x1FFF_5678, true, 3);
    // RFFN = 0: the FIFO and its table take MB0–MB7, MB8 is the first mailbox.
    r.load_mb(8, &data, code::TX_DATA);
    r.load_mb(9, &rtr, code::TX_REMOTE);
    let sent = r.transmit_all();
    assert_eq!(sent, vec![data, rtr], "data frame first (lower ID wins)");
    assert_eq!(r.code(8), code::TX_INACTIVE);
    assert_eq!(
        r.code(9),
        code::RX_EMPTY,
        "a sent remote frame turns into an Rx mailbox"
    );
    assert_eq!(r.rd(regs::IFLAG1) & 0x300, 0x300);
    let got = r.drain_fifo();
    assert_eq!(got, vec![(data, 0), (rtr, 0)]);
    assert_eq!(r.m.fifo_len(), 0);
}

fn fifo_output_window_and_table_area_are_not_mailboxes(chip: Chip) {
    let mut r = Rig::loopback_fifo(chip);
    r.freeze();
    // MB0–MB5 are the FIFO engine: writes ignored.
    r.wr(regs::mb_word0(1), 0x1234_5678);
    assert_eq!(r.rd(regs::mb_word0(1)), 0);
    // MB6–MB7 hold the filter table: not transmitted even with a Tx code pattern.
    r.wr(regs::mb_cs(6), code::TX_DATA << 24);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    assert!(r.transmit(twocan_sim::TxResult::Acked).is_none());
}

/// Every RFFN value of the manual's table ([`Manual::fifo_individual`]: RFFN 0–3 on the
/// Kinetis parts, 0–0xF on the RT1062, whose elements 32–127 are never individually
/// masked): the split between individually and globally masked elements, and
/// lowest-element-wins (IDHIT). MCR\[MAXMB\] is raised to the last message buffer first:
/// CTRL2\[RFFN\] "cannot be programmed with values that make the number of Message
/// Buffers occupied by Rx FIFO and ID Filter exceed the number of Mailboxes present,
/// defined by MCR\[MAXMB\]" (RFFN ≥ 5 occupies more than MB0–MB15 on the RT1062).
fn filter_table_split_for_each_rffn(chip: Chip) {
    let want = Manual::of(chip);
    let mbs = want.message_buffers;
    for &(rffn, individual) in want.fifo_individual {
        let elements = 8 * (rffn as usize + 1);
        let mut r = Rig::on(chip);
        r.enable_into_freeze();
        r.wr(
            regs::MCR,
            mcr::MAXMB.replace(r.rd(regs::MCR), mbs as u32 - 1),
        );
        // Every element accepts standard data frames with ID 0 under its mask; every
        // RXIMR compares all bits (also those of buffers past the individually masked
        // elements: they must not be used for the elements under RXFGMASK).
        let table = vec![elem_a(0, false, false); elements];
        let exact = vec![exact_mask_a(false); mbs];
        r.setup_fifo(rffn, true, &table, &exact, 0);
        r.start();
        // ID 0 matches element 0 first.
        r.deliver(&std(0, &[]));
        assert_eq!(r.pop_fifo().map(|(_, h, _)| h), Some(0), "rffn {rffn}");
        // ID 0x123 passes only elements under the (all-don't-care) global mask; RFFN 0
        // has none (all 8 elements are individually masked).
        let global_hit = (elements > individual).then_some(individual as u32);
        r.deliver(&std(0x123, &[]));
        assert_eq!(r.pop_fifo().map(|(_, h, _)| h), global_hit, "rffn {rffn}");
        // The global mask is 0: even RTR and IDE are don't-care there.
        r.deliver(&ext(0x123, &[]));
        assert_eq!(r.pop_fifo().map(|(_, h, _)| h), global_hit, "rffn {rffn}");
        if global_hit.is_none() {
            assert_eq!(r.m.frames_discarded(), 2);
        }

        // IRMQ = 0: RXMGMASK replaces the individual masks.
        r.freeze();
        r.clear_bits(regs::MCR, mcr::IRMQ);
        for n in 0..mbs {
            r.wr(regs::rximr(n), 0);
        }
        r.wr(regs::RXMGMASK, exact_mask_a(false));
        r.clear_bits(regs::MCR, mcr::HALT);
        r.idle(11);
        r.deliver(&std(0x456, &[]));
        let expect = if elements > individual {
            Some(individual as u32)
        } else {
            None
        };
        assert_eq!(
            r.pop_fifo().map(|(_, h, _)| h),
            expect,
            "rffn {rffn} IRMQ=0"
        );
        r.freeze();
        r.wr(regs::RXMGMASK, 0);
        r.clear_bits(regs::MCR, mcr::HALT);
        r.idle(11);
        r.deliver(&std(0x456, &[]));
        assert_eq!(
            r.pop_fifo().map(|(_, h, _)| h),
            Some(0),
            "rffn {rffn} RXMGMASK = 0"
        );
    }
}

fn idhit_numbers_every_element_of_the_14_18_table(chip: Chip) {
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    let table: Vec<u32> = (0..32).map(|k| elem_a(0x100 + k, false, false)).collect();
    r.setup_fifo(
        3,
        true,
        &table,
        &[exact_mask_a(false); 16],
        exact_mask_a(false),
    );
    r.start();
    for k in (0..32u16).rev() {
        r.deliver(&std(0x100 + k, &[k as u8]));
        let (f, hit, _) = r.pop_fifo().unwrap();
        assert_eq!((f, hit), (std(0x100 + k, &[k as u8]), k as u32));
    }
    r.deliver(&std(0x200, &[]));
    assert!(
        r.pop_fifo().is_none(),
        "a frame matching nothing is discarded"
    );
    assert_eq!(r.m.frames_discarded(), 1);
    // MB14 and MB15 are the remaining mailboxes (up to MCR[MAXMB], 0xF out of reset on
    // the RT1062 too: IMXRT1060RM MCR reset 0x5980_000F).
    r.freeze();
    r.load_mb(14, &std(0x10, &[]), code::TX_DATA);
    r.load_mb(13, &std(0x01, &[]), code::TX_DATA); // table storage: ignored as a mailbox
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    assert_eq!(r.transmit_all(), vec![std(0x10, &[])]);
}

fn rtr_and_ide_bits_of_format_a_elements(chip: Chip) {
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    let table = [
        elem_a(0x555, false, true),       // 0: standard remote 0x555
        elem_a(0x1ABC_DEF0, true, false), // 1: extended data 0x1ABCDEF0
        elem_a(0x0AB, false, false),      // 2: standard data 0x0AB
        elem_a(0, false, false),          // 3..7: nothing useful
        0,
        0,
        0,
        0,
    ];
    let masks = [
        exact_mask_a(false),
        exact_mask_a(true),
        exact_mask_a(false) & !(0x0F << 19), // low 4 ID bits don't care
        exact_mask_a(false),
        exact_mask_a(false),
        exact_mask_a(false),
        exact_mask_a(false),
        exact_mask_a(false),
    ];
    r.setup_fifo(0, true, &table, &masks, 0);
    r.set_bits(regs::CTRL2, ctrl2::RRS); // store remote requests like data frames
    r.start();
    for (frame, hit) in [
        (remote(0x555, false, 2), Some(0)),
        (std(0x555, &[]), None),
        (ext(0x1ABC_DEF0, &[9]), Some(1)),
        (remote(0x1ABC_DEF0, true, 0), None),
        (ext(0x0AB << 18, &[]), None),
        (std(0x0A0, &[]), Some(2)),
        (std(0x0AF, &[]), Some(2)),
        (std(0x0BF, &[]), None),
    ] {
        r.deliver(&frame);
        assert_eq!(
            r.pop_fifo().map(|(f, h, _)| (f, h)),
            hit.map(|h| (frame, h)),
            "{frame:?}"
        );
    }
}

fn fifo_is_six_deep_warns_at_five_and_overflows(chip: Chip) {
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    r.setup_fifo(0, true, &[0; 8], &[0; 8], 0);
    r.wr(regs::IMASK1, iflag1::BUF5I | iflag1::BUF6I | iflag1::BUF7I);
    r.start();
    assert!(!r.m.irq().message_buffer);
    for k in 0..4u8 {
        r.deliver(&std(k as u16, &[k]));
    }
    assert_eq!(r.rd(regs::IFLAG1) & 0xE0, iflag1::BUF5I);
    assert!(r.m.irq().message_buffer);
    r.deliver(&std(4, &[4]));
    assert_eq!(
        r.rd(regs::IFLAG1) & 0xE0,
        iflag1::BUF5I | iflag1::BUF6I,
        "warning at 5"
    );
    r.deliver(&std(5, &[5]));
    assert_eq!(r.m.fifo_len(), 6);
    assert_eq!(r.rd(regs::IFLAG1) & iflag1::BUF7I, 0);
    r.deliver(&std(6, &[6]));
    assert_eq!(r.m.fifo_len(), 6);
    assert_ne!(r.rd(regs::IFLAG1) & iflag1::BUF7I, 0, "overflow");
    assert_eq!((r.m.fifo_overflows(), r.m.frames_lost()), (1, 1));
    // Write 0: nothing; write 1: clear (warning and overflow are W1C).
    r.wr(regs::IFLAG1, 0);
    assert_eq!(r.rd(regs::IFLAG1) & 0xE0, 0xE0);
    r.wr(regs::IFLAG1, iflag1::BUF6I | iflag1::BUF7I);
    assert_eq!(r.rd(regs::IFLAG1) & 0xE0, iflag1::BUF5I);
    // The six oldest frames come out in order; the seventh was lost.
    let ids: Vec<u32> = r.drain_fifo().iter().map(|(f, _)| f.raw_id()).collect();
    assert_eq!(ids, vec![0, 1, 2, 3, 4, 5]);
    assert_eq!(r.rd(regs::IFLAG1) & 0xFF, 0);
    assert!(!r.m.irq().message_buffer);
    // Popping an empty FIFO does nothing; bits 0–4 are unused with the FIFO on.
    r.wr(regs::IFLAG1, 0xFF);
    assert_eq!(r.rd(regs::IFLAG1), 0);
}

fn mailbox_reception_priority_against_the_fifo(chip: Chip) {
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    r.setup_fifo(0, true, &[0; 8], &[0; 8], 0);
    r.wr(regs::rximr(8), u32::MAX);
    r.rx_mb(8, 0x321, false);
    r.start();
    // MRP = 0: the FIFO first.
    r.deliver(&std(0x321, &[1]));
    assert_eq!(r.m.fifo_len(), 1);
    assert_eq!(r.code(8), code::RX_EMPTY);
    // MRP = 1: the mailbox first.
    r.freeze();
    r.set_bits(regs::CTRL2, ctrl2::MRP);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    r.deliver(&std(0x321, &[2]));
    assert_eq!(r.code(8), code::RX_FULL);
    assert_eq!(r.m.fifo_len(), 1);
    // MRP = 1, IRMQ = 1, mailbox not free, FIFO not full: the FIFO takes it.
    r.deliver(&std(0x321, &[3]));
    assert_eq!(r.m.fifo_len(), 2);
    // MRP = 0 with the FIFO full: a free mailbox takes the frame.
    r.freeze();
    r.clear_bits(regs::CTRL2, ctrl2::MRP);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    for k in 0..4 {
        r.deliver(&std(0x10 + k, &[]));
    }
    assert_eq!(r.m.fifo_len(), 6);
    let (f, code_read, _) = r.read_mb(8); // read and unlock: serviced, free again
    assert_eq!((f, code_read), (std(0x321, &[2]), code::RX_FULL));
    r.deliver(&std(0x321, &[4]));
    assert_eq!(r.read_mb(8).0, std(0x321, &[4]));
    assert_eq!(r.m.fifo_overflows(), 0);
    // FIFO full and the mailbox not free: IRMQ = 1 overruns the last matching mailbox.
    r.deliver(&std(0x321, &[5]));
    assert_eq!(
        r.code(8),
        code::RX_FULL,
        "serviced mailbox is free: plain FULL"
    );
    r.deliver(&std(0x321, &[6]));
    assert_eq!(r.code(8), code::RX_OVERRUN);
    assert_eq!(r.m.mailbox_overruns(), 1);
    // A frame matching only the (full) FIFO is lost.
    r.deliver(&std(0x7, &[]));
    assert_eq!(r.m.fifo_overflows(), 1);
}

fn format_b_and_c_and_d(chip: Chip) {
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    r.setup_fifo(0, true, &[], &[u32::MAX; 8], u32::MAX);
    // Format B: element 0 = {std data 0x123, std remote 0x456}; element 1 = {ext 14 MSBs}.
    r.wr(
        regs::MCR,
        mcr::IDAM.replace(r.rd(regs::MCR), mcr::IDAM_FORMAT_B),
    );
    let e0 = (0x123 << 19) | (1 << 15) | (0x456 << 3);
    let ext_id = 0x1555_4321u32;
    let e1 = (1 << 30) | (((ext_id >> 15) & 0x3FFF) << 16);
    r.wr(regs::rx_fifo_filter(0), e0);
    r.wr(regs::rx_fifo_filter(1), e1);
    for n in 2..8 {
        r.wr(regs::rx_fifo_filter(n), 0xFFFF_FFFF);
    }
    r.set_bits(regs::CTRL2, ctrl2::RRS);
    r.start();
    r.deliver(&std(0x123, &[]));
    r.deliver(&remote(0x456, false, 0));
    r.deliver(&ext(ext_id & !0x7FFF, &[]));
    r.deliver(&std(0x456, &[]));
    let hits: Vec<u32> = r.drain_fifo().iter().map(|(_, h)| *h).collect();
    assert_eq!(hits, vec![0, 1, 2], "IDAF numbers: two per element");

    // Format C: 8 MSBs of the ID, four filters per element, remote frames accepted.
    r.freeze();
    r.wr(
        regs::MCR,
        mcr::IDAM.replace(r.rd(regs::MCR), mcr::IDAM_FORMAT_C),
    );
    r.wr(regs::rx_fifo_filter(0), 0x0102_0304);
    r.wr(regs::rx_fifo_filter(1), 0x0506_0708);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    r.deliver(&std(0x04 << 3 | 5, &[]));
    r.deliver(&remote(0x06 << 21 | 77, true, 1));
    let hits: Vec<u32> = r.drain_fifo().iter().map(|(_, h)| *h).collect();
    assert_eq!(hits, vec![3, 5]);

    // Format D: everything rejected.
    r.freeze();
    r.wr(
        regs::MCR,
        mcr::IDAM.replace(r.rd(regs::MCR), mcr::IDAM_FORMAT_D),
    );
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    r.deliver(&std(0x123, &[]));
    assert_eq!(r.m.fifo_len(), 0);
}

fn remote_request_matching_the_fifo_is_stored_not_answered(chip: Chip) {
    let mut r = Rig::loopback_fifo(chip);
    r.freeze();
    r.load_mb(10, &std(0x300, &[0xAA]), code::RX_RANSWER);
    r.clear_bits(regs::MCR, mcr::HALT);
    r.idle(11);
    r.clear_bits(regs::CTRL1, ctrl1::LPB); // (freeze-only: ignored, stays in loop-back)
    assert_ne!(r.rd(regs::CTRL1) & ctrl1::LPB, 0);
    r.deliver(&remote(0x300, false, 1)); // not received: loop-back ignores the bus
    assert_eq!(r.m.fifo_len(), 0);
    r.load_mb(8, &remote(0x300, false, 1), code::TX_REMOTE);
    r.transmit_all();
    assert_eq!(r.drain_fifo(), vec![(remote(0x300, false, 1), 0)]);
    assert_eq!(r.code(10), code::RX_RANSWER, "the FIFO took the request");
    assert_eq!(r.m.peek32(regs::mb_cs(10)) & cs::RTR, 0);
}
