//! The examples' settings and filter lists for the Teensy 4 (the Teensy 3 examples'
//! configurations with the RT1062's CAN clock): each one `check`ed and begun over the
//! model by `tests/configs.rs`.

use twocan_core::Filter;
use twocan_flexcan::{CanClock, Settings};

/// The CAN clock root every example uses: the 24 MHz oscillator (it does not depend on
/// the PLLs the boot ROM or a start-up code set). All modules share it.
pub const CLOCK: CanClock = CanClock::IMXRT_24MHZ;

/// ACAN §4: 125 kbit/s, loop-back and self reception.
pub const LOOPBACK: Settings = {
    let mut s = Settings::with_clock(125_000, CLOCK);
    s.loop_back = true;
    s.self_reception = true;
    s
};

/// The bus of the `app`, `async-echo` and `can1-can2` examples: 500 kbit/s.
pub const BUS: Settings = Settings::with_clock(500_000, CLOCK);

/// `filters`: ACAN §4's loop-back settings on the Teensy 4 clock.
pub const FILTERS: Settings = LOOPBACK;

/// The loop-back example receives everything.
pub const LOOPBACK_FILTERS: [Filter; 1] = [Filter::pass_all()];

/// `app`: node 1 talking with node 2 (as the Teensy 3 `app`); with the feature
/// `app-node3`, node 3 listening to node 1 (a third node next to a node-1/node-2 pair).
pub const APP_NODES: (u8, u8) = if cfg!(feature = "app-node3") {
    (3, 1)
} else {
    (1, 2)
};

/// `can1-can2`: CAN1 is node 1, CAN2 node 2.
pub const CAN1_CAN2_NODES: [(u8, u8); 2] = [(1, 2), (2, 1)];

/// `async-echo` receives everything.
pub const ECHO_FILTERS: [Filter; 1] = [Filter::pass_all()];
