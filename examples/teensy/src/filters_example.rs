//! The configuration of the `teensy-filters` example, kept in the library so that host
//! tests run it through `check` and the model's `begin` (a filter list the manual's rules
//! refuse would otherwise only show as a blink code on the board).
//!
//! A secondary filter shares the global mask, so it must be exact or pass-all (ACAN
//! §13.4): the two masked filters are primary.

use twocan_core::{Filter, Format, Frame, FrameError, FrameKind};
use twocan_flexcan::Settings;

/// Number of filters (primary then secondary, as ACAN numbers them).
pub const FILTERS: usize = 5;

/// ACAN §4: 125 kbit/s, loop-back and self reception.
pub const SETTINGS: Settings = {
    let mut s = Settings::new(125_000);
    s.loop_back = true;
    s.self_reception = true;
    s
};

/// Filters #0–#2: standard data 0x300–0x30F (masked), extended data 0x18FF_xx00
/// (masked), standard data 0x234.
pub fn primary() -> [Filter; 3] {
    [
        Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, 0x300),
        Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_00FF, 0x18FF_0000),
        Filter::exact(FrameKind::Data, Format::Standard, 0x234),
    ]
}

/// Filters #3–#4: extended data 0x123456, standard remote 0x542.
pub fn secondary() -> [Filter; 2] {
    [
        Filter::exact(FrameKind::Data, Format::Extended, 0x12_3456),
        Filter::exact(FrameKind::Remote, Format::Standard, 0x542),
    ]
}

/// The frames the example sends, in order, with the filter index each must arrive
/// through (`None`: rejected by every filter).
pub fn frames() -> [(Result<Frame, FrameError>, Option<usize>); 6] {
    [
        (Frame::extended(0x12_3456, &[0]), Some(3)),
        (Frame::standard(0x234, &[1, 2]), Some(2)),
        (Frame::remote(0x542, false, 0), Some(4)),
        (Frame::standard(0x305, &[3]), Some(0)),
        (Frame::extended(0x18FF_2A00, &[4; 8]), Some(1)),
        (Frame::standard(0x777, &[5]), None),
    ]
}
