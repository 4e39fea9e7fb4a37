//! ACAN §13: secondary filters alone and with primary filters, pass-all placement,
//! numbering (§13.5), sent in loop-back through the real driver and the model.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_core::{Filter, Format, Frame, FrameKind};
use twocan_flexcan::Configuration;

fn ext_123456() -> Filter {
    Filter::exact(FrameKind::Data, Format::Extended, 0x123456)
}
fn std_234() -> Filter {
    Filter::exact(FrameKind::Data, Format::Standard, 0x234)
}
fn remote_542() -> Filter {
    Filter::exact(FrameKind::Remote, Format::Standard, 0x542)
}

fn frames() -> Vec<Frame> {
    vec![
        ext_data(0x123456, &[1]),
        std_data(0x234, &[2, 3]),
        remote(0x542, false),
        std_data(0x542, &[]),
        remote(0x123456, true),
        ext_data(0x234, &[]),
        std_data(0x235, &[]),
    ]
}

#[test]
fn secondary_without_primary_13_1() {
    let got = indices(
        &loop_back(125_000),
        &[],
        &[ext_123456(), std_234(), remote_542()],
        &frames(),
    );
    assert_eq!(got, vec![Some(0), Some(1), Some(2), None, None, None, None]);
}

#[test]
fn primary_and_secondary_13_2_and_idx_13_5() {
    let got = indices(
        &loop_back(125_000),
        &[ext_123456()],
        &[std_234(), remote_542()],
        &frames(),
    );
    assert_eq!(got, vec![Some(0), Some(1), Some(2), None, None, None, None]);
}

#[test]
fn secondary_matching_a_primary_never_matches_13_2() {
    let got = indices(
        &loop_back(125_000),
        &[std_234()],
        &[std_234(), remote_542()],
        &frames(),
    );
    assert_eq!(got, vec![None, Some(0), Some(2), None, None, None, None]);
}

#[test]
fn duplicate_secondary_never_matches_13_1() {
    let got = indices(
        &loop_back(125_000),
        &[],
        &[std_234(), std_234(), remote_542()],
        &frames(),
    );
    assert_eq!(got, vec![None, Some(0), Some(2), None, None, None, None]);
}

#[test]
fn secondary_pass_all_last_13_3() {
    let secondary = [ext_123456(), std_234(), remote_542(), Filter::pass_all()];
    let got = indices(&loop_back(125_000), &[], &secondary, &frames());
    assert_eq!(
        got,
        vec![
            Some(0),
            Some(1),
            Some(2),
            Some(3),
            Some(3),
            Some(3),
            Some(3)
        ]
    );
}

#[test]
fn secondary_after_pass_all_never_matches_13_3() {
    let secondary = [ext_123456(), std_234(), Filter::pass_all(), remote_542()];
    let got = indices(&loop_back(125_000), &[], &secondary, &frames());
    assert_eq!(
        got,
        vec![
            Some(0),
            Some(1),
            Some(2),
            Some(2),
            Some(2),
            Some(2),
            Some(2)
        ]
    );
}

#[test]
fn secondary_pass_all_with_primaries() {
    let primary = [
        remote_542(),
        Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, 0x230),
    ];
    let secondary = [ext_123456(), Filter::pass_all(), std_234()];
    let got = indices(&loop_back(125_000), &primary, &secondary, &frames());
    assert_eq!(
        got,
        vec![
            Some(2),
            Some(1),
            Some(0),
            Some(3),
            Some(3),
            Some(3),
            Some(1)
        ]
    );
}

#[test]
fn primary_pass_all_hides_every_secondary_13_3() {
    let got = indices(
        &loop_back(125_000),
        &[Filter::pass_all()],
        &[std_234(), remote_542()],
        &frames(),
    );
    assert_eq!(got, vec![Some(0); 7]);
}

#[test]
fn every_slot_of_the_largest_configuration() {
    let mut settings = loop_back(125_000);
    settings.configuration = Configuration::Filters14_18;
    let primary: Vec<Filter> = (0..14u16).map(|i| Filter::standard(0x100 + i)).collect();
    let secondary: Vec<Filter> = (0..18u32)
        .map(|i| {
            if i.is_multiple_of(2) {
                Filter::extended(0x10000 + i)
            } else {
                Filter::exact(FrameKind::Remote, Format::Standard, 0x300 + i)
            }
        })
        .collect();
    let mut frames: Vec<Frame> = (0..14u16).map(|i| std_data(0x100 + i, &[])).collect();
    frames.extend((0..18u32).map(|i| {
        if i.is_multiple_of(2) {
            ext_data(0x10000 + i, &[])
        } else {
            remote(0x300 + i, false)
        }
    }));
    frames.push(std_data(0x300 + 1, &[]));
    frames.push(remote(0x10000, true));
    let got = indices(&settings, &primary, &secondary, &frames);
    let mut want: Vec<Option<u16>> = (0..32).map(Some).collect();
    want.extend([None, None]);
    assert_eq!(got, want);
}

#[test]
fn secondaries_of_10_6() {
    let mut settings = loop_back(125_000);
    settings.configuration = Configuration::Filters10_6;
    let secondary: Vec<Filter> = (0..6u16).map(|i| Filter::standard(0x700 + i)).collect();
    let frames: Vec<Frame> = (0..7u16).map(|i| std_data(0x700 + i, &[i as u8])).collect();
    let got = indices(&settings, &[], &secondary, &frames);
    assert_eq!(
        got,
        vec![Some(0), Some(1), Some(2), Some(3), Some(4), Some(5), None]
    );
}
