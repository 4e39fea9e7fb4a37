//! The FlexCAN settings of the examples, in the library so that a host test runs every
//! example's configuration (settings and filter lists, on every board) through `check`
//! and the model's `begin` (`tests/configs.rs`): a configuration the manual's rules
//! refuse fails CI instead of blinking code 5 on a board.

use twocan_flexcan::Settings;

/// `teensy-loopback`: ACAN §4, 125 kbit/s, loop-back and self reception; the pass-all
/// filter (ACAN's "no filter": an empty list receives nothing in twocan).
pub const LOOPBACK: Settings = {
    let mut s = Settings::new(125_000);
    s.loop_back = true;
    s.self_reception = true;
    s
};

/// `teensy-app`, `teensy-can0-can1`, `teensy-async-echo`: 500 kbit/s, on a bus with
/// transceivers (filters: the portable application's list, or pass-all for the echo).
pub const BUS: Settings = Settings::new(500_000);
