//! The FlexCAN settings of the examples, in the library so that a host test runs every
//! example's configuration (settings and filter lists, on every board) through `check`
//! and the model's `begin` (`tests/configs.rs`): a configuration the manual's rules
//! refuse fails CI instead of blinking code 5 on a board.

use heapless::Vec;
use twocan_app::{App, FILTER_COUNT};
use twocan_core::Filter;
use twocan_flexcan::{Instance, Settings};

use crate::filters_example;

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

/// `teensy-loopback`'s filters: one primary pass-all (an empty list receives nothing, unlike
/// ACAN §4; see `docs/differences.md`).
pub const LOOPBACK_FILTERS: [Filter; 1] = [Filter::pass_all()];

/// `teensy-app`: this node's number and its peer's (the portable application's filter
/// list is `App::new(node, peer).filters()`, as primary filters).
pub const APP_NODES: (u8, u8) = (1, 2);

/// `teensy-can0-can1`: the application node on FlexCAN0 and on FlexCAN1 (each
/// `(node, peer)`), talking to each other; their filter lists as primary filters.
pub const CAN0_CAN1_NODES: [(u8, u8); 2] = [(1, 2), (2, 1)];

/// `teensy-async-echo`'s primary filters: everything is echoed.
pub const ECHO_FILTERS: [Filter; 1] = [Filter::pass_all()];

/// The most filters of one list among the examples.
pub const MAX_EXAMPLE_FILTERS: usize = 16;

// Every example's list fits a `FilterList` (so `list` drops nothing).
const _: () =
    assert!(FILTER_COUNT <= MAX_EXAMPLE_FILTERS && filters_example::FILTERS <= MAX_EXAMPLE_FILTERS);

/// A filter list of [`ExampleConfig`].
pub type FilterList = Vec<Filter, MAX_EXAMPLE_FILTERS>;

/// One firmware example's FlexCAN configuration, exactly as its bin passes it to
/// `begin`: the values come from the constants above (and [`filters_example`]), which
/// the bins use too.
#[derive(Debug, Clone)]
pub struct ExampleConfig {
    /// The example (and instance, for the two-controller one).
    pub name: &'static str,
    /// The FlexCAN instance it starts.
    pub instance: Instance,
    /// Its settings.
    pub settings: Settings,
    /// Its primary filters.
    pub primary: FilterList,
    /// Its secondary filters.
    pub secondary: FilterList,
}

fn list(filters: &[Filter]) -> FilterList {
    let mut v = FilterList::new();
    for f in filters {
        // Cannot fail: every list fits (the assertion above; the host test also compares
        // the lengths with the sources).
        let _ = v.push(*f);
    }
    v
}

/// Every example's configuration (`teensy-can0-can1` once per instance; it needs
/// FlexCAN1, i.e. a Teensy 3.6).
pub fn every_example() -> [ExampleConfig; 6] {
    let app = |(node, peer): (u8, u8)| list(&App::new(node, peer).filters());
    [
        ExampleConfig {
            name: "loopback",
            instance: Instance::Can0,
            settings: LOOPBACK,
            primary: list(&LOOPBACK_FILTERS),
            secondary: list(&[]),
        },
        ExampleConfig {
            name: "filters",
            instance: Instance::Can0,
            settings: filters_example::SETTINGS,
            primary: list(&filters_example::primary()),
            secondary: list(&filters_example::secondary()),
        },
        ExampleConfig {
            name: "app",
            instance: Instance::Can0,
            settings: BUS,
            primary: app(APP_NODES),
            secondary: list(&[]),
        },
        ExampleConfig {
            name: "can0-can1 (can0)",
            instance: Instance::Can0,
            settings: BUS,
            primary: app(CAN0_CAN1_NODES[0]),
            secondary: list(&[]),
        },
        ExampleConfig {
            name: "can0-can1 (can1)",
            instance: Instance::Can1,
            settings: BUS,
            primary: app(CAN0_CAN1_NODES[1]),
            secondary: list(&[]),
        },
        ExampleConfig {
            name: "async-echo",
            instance: Instance::Can0,
            settings: BUS,
            primary: list(&ECHO_FILTERS),
            secondary: list(&[]),
        },
    ]
}
