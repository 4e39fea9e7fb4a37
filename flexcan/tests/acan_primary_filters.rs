//! ACAN §12: primary filters — the examples of §12.1–12.5, each frame sent in
//! loop-back through the real driver and the model, the received filter index checked.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_core::{Filter, Format, Frame, FrameKind};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::{Configuration, InstalledFilters};

fn filters_0_1_2() -> [Filter; 3] {
    [
        Filter::exact(FrameKind::Data, Format::Extended, 0x123456), // Filter #0
        Filter::exact(FrameKind::Data, Format::Standard, 0x234),    // Filter #1
        Filter::exact(FrameKind::Remote, Format::Standard, 0x542),  // Filter #2
    ]
}

/// The frames of the examples, then frames that match none of the three filters.
fn frames() -> Vec<Frame> {
    vec![
        ext_data(0x123456, &[1]),
        std_data(0x234, &[2, 3]),
        remote(0x542, false),
        // Same identifiers, other kind or format: no filter takes them.
        std_data(0x542, &[]),
        remote(0x123456, true),
        ext_data(0x234, &[]),
        remote(0x234, false),
        std_data(0x235, &[]),
        ext_data(0x123457, &[]),
    ]
}

#[test]
fn example_12_1_and_receive_idx_12_5() {
    let got = indices(&loop_back(125_000), &filters_0_1_2(), &[], &frames());
    assert_eq!(
        got,
        vec![
            Some(0),
            Some(1),
            Some(2),
            None,
            None,
            None,
            None,
            None,
            None
        ]
    );
}

#[test]
fn rejected_frames_are_discarded_by_the_hardware() {
    let (model, mut can) = begin::<32, 16>(&loop_back(125_000), &filters_0_1_2(), &[]).unwrap();
    let mut bus = bus_with(125_000, &[&model]);
    for f in frames() {
        can.try_send(&f).unwrap();
        run1(&mut bus, &mut can, 1_000);
    }
    assert_eq!(drain(&mut can).len(), 3);
    assert_eq!(can.traffic().sent, 9);
    // The four rejected data frames are counted by the model as discarded (it does not
    // count the two rejected remote frames received back in loop-back).
    assert_eq!(model.frames_discarded(), 4);
}

#[test]
fn duplicate_filter_never_matches() {
    let mut list = filters_0_1_2().to_vec();
    list.push(Filter::exact(FrameKind::Data, Format::Standard, 0x234)); // Filter #3
    let got = indices(&loop_back(125_000), &list, &[], &frames());
    assert_eq!(
        got,
        vec![
            Some(0),
            Some(1),
            Some(2),
            None,
            None,
            None,
            None,
            None,
            None
        ]
    );
}

#[test]
fn pass_all_last_catches_the_rest_12_2() {
    let mut list = filters_0_1_2().to_vec();
    list.push(Filter::pass_all()); // Filter #3
    let got = indices(&loop_back(125_000), &list, &[], &frames());
    assert_eq!(
        got,
        vec![
            Some(0),
            Some(1),
            Some(2),
            Some(3),
            Some(3),
            Some(3),
            Some(3),
            Some(3),
            Some(3)
        ]
    );
}

#[test]
fn filters_after_pass_all_never_match_12_2() {
    let list = [
        Filter::exact(FrameKind::Data, Format::Extended, 0x123456), // Filter #0
        Filter::exact(FrameKind::Data, Format::Standard, 0x234),    // Filter #1
        Filter::pass_all(),                                         // Filter #2
        Filter::exact(FrameKind::Remote, Format::Standard, 0x542),  // Filter #3
    ];
    let got = indices(&loop_back(125_000), &list, &[], &frames());
    assert_eq!(
        got,
        vec![
            Some(0),
            Some(1),
            Some(2),
            Some(2),
            Some(2),
            Some(2),
            Some(2),
            Some(2),
            Some(2)
        ]
    );
}

#[test]
fn mask_and_acceptance_12_3() {
    // Standard data frames 0x540..=0x543: mask 0x7FC, acceptance 0x540.
    let f = Filter::masked(FrameKind::Data, Format::Standard, 0x7FC, 0x540);
    let frames = [
        std_data(0x540, &[]),
        std_data(0x541, &[]),
        std_data(0x542, &[]),
        std_data(0x543, &[]),
        std_data(0x544, &[]),
        std_data(0x53F, &[]),
        remote(0x541, false),
        ext_data(0x541, &[]),
        ext_data(0x541 << 18, &[]),
    ];
    let got = indices(&loop_back(125_000), &[f], &[], &frames);
    assert_eq!(
        got,
        vec![
            Some(0),
            Some(0),
            Some(0),
            Some(0),
            None,
            None,
            None,
            None,
            None
        ]
    );
}

#[test]
fn extended_mask_and_kind_any() {
    // Beyond ACAN: a primary filter of kind "any" (data and remote).
    let list = [
        Filter::masked(
            FrameKind::Remote,
            Format::Extended,
            0x1FFF_FF00,
            0x0ABC_DE00,
        ),
        Filter::exact(FrameKind::Any, Format::Standard, 0x100),
        Filter::kind_format(FrameKind::Remote, Format::Any),
    ];
    let frames = [
        remote(0x0ABC_DE42, true),
        ext_data(0x0ABC_DE42, &[]),
        std_data(0x100, &[]),
        remote(0x100, false),
        remote(0x7FF, false),
        remote(0x1FFF_FFFF, true),
        std_data(0x101, &[]),
    ];
    let got = indices(&loop_back(125_000), &list, &[], &frames);
    assert_eq!(
        got,
        vec![Some(0), None, Some(1), Some(1), Some(2), Some(2), None]
    );
}

#[test]
fn every_primary_slot_of_every_configuration() {
    for c in Configuration::ALL {
        let n = c.primary_filter_capacity();
        let list: Vec<Filter> = (0..n as u32)
            .map(|i| Filter::standard(0x100 + i as u16))
            .collect();
        let mut settings = loop_back(125_000);
        settings.configuration = c;
        let frames: Vec<Frame> = (0..n as u16 + 2)
            .map(|i| std_data(0x100 + i, &[]))
            .collect();
        let got = indices(&settings, &list, &[], &frames);
        let want: Vec<Option<u16>> = (0..n as u16 + 2)
            .map(|i| (i < n as u16).then_some(i))
            .collect();
        assert_eq!(got, want, "{c:?}");
    }
}

#[test]
fn unused_elements_accept_nothing_extra() {
    // One filter in the largest table: the 31 unused elements must not widen it.
    let mut settings = loop_back(125_000);
    settings.configuration = Configuration::Filters14_18;
    let f = Filter::exact(FrameKind::Data, Format::Extended, 0x1234);
    let frames = [
        ext_data(0x1234, &[]),
        std_data(0, &[]),
        ext_data(0, &[]),
        remote(0x1234, true),
        remote(0, false),
    ];
    let got = indices(&settings, &[f], &[], &frames);
    assert_eq!(got, vec![Some(0), None, None, None, None]);
}

#[test]
fn table_and_masks_written_as_compiled() {
    let (model, mut can) = begin::<32, 16>(&loop_back(125_000), &filters_0_1_2(), &[]).unwrap();
    let table = can.receive_context().filters();
    for (i, e) in table.elements().iter().enumerate() {
        assert_eq!(
            model.peek32(twocan_flexcan::regs::rx_fifo_filter(i)),
            *e,
            "element {i}"
        );
    }
    for (i, m) in table.individual_masks().iter().enumerate() {
        assert_eq!(model.peek32(twocan_flexcan::regs::rximr(i)), *m, "RXIMR{i}");
    }
    assert_eq!(
        model.peek32(twocan_flexcan::regs::RXFGMASK),
        table.global_mask()
    );
    let _: &FlexCanModel = can.hardware().registers();
}

/// Register access that reports an `RXFIR.IDHIT` beyond the table (the hardware never
/// does; a stale or corrupted value).
#[derive(Debug)]
struct IdhitBeyondTable(Ticking);

impl twocan_core::Registers for IdhitBeyondTable {
    fn read32(&self, offset: usize) -> u32 {
        if offset == twocan_flexcan::regs::RXFIR {
            0x1FF
        } else {
            self.0.read32(offset)
        }
    }
    fn write32(&self, offset: usize, value: u32) {
        self.0.write32(offset, value);
    }
}

#[test]
fn unreachable_idhit_is_no_filter_and_is_counted() {
    let model = model_for(twocan_flexcan::Board::Teensy32);
    let controller = twocan_flexcan::FlexCan::begin(
        IdhitBeyondTable(Ticking::new(model.clone())),
        &mut twocan_flexcan::HostSystem::new(),
        twocan_flexcan::Target::new(
            twocan_flexcan::Board::Teensy32,
            twocan_flexcan::Instance::Can0,
        ),
        &loop_back(125_000),
        &filters_0_1_2(),
        &[],
    )
    .unwrap();
    let mut can: twocan_core::Driver<_, 8, 8> = twocan_core::Driver::new(controller.into_split());
    let mut bus = bus_with(125_000, &[&model]);
    let f = Frame::standard(0x234, &[1]).unwrap();
    can.try_send(&f).unwrap();
    for _ in 0..1_000 {
        if model.irq_pending() {
            can.on_interrupt();
        }
        if bus.step_until(bus.now() + 1_000).is_none() {
            break;
        }
    }
    if model.irq_pending() {
        can.on_interrupt();
    }
    let rx = can.receive().unwrap();
    assert_eq!(rx.frame, f);
    // Not filter #0 (the old fallback): the distinct "no filter" index, counted.
    assert_eq!(rx.filter, twocan_flexcan::UNKNOWN_FILTER);
    assert_eq!(can.hardware().unresolved_filter_hits(), 1);
    assert!(can.receive().is_err());
}
