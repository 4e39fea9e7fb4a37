//! Every Teensy 4 example's configuration passes `check` and the model's `begin` on the
//! module it uses, on both boards: a configuration the driver refuses would otherwise
//! only show on the board as `rt::HALT` = 5.

use twocan_app::App;
use twocan_core::Filter;
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::{
    check, Board, ConfigErrors, FlexCan, HostSystem, IdleClocked, Instance, Settings, Target,
};
use twocan_teensy4::configs::{self, APP_NODES, CAN1_CAN2_NODES};
use twocan_teensy4::filters_example;

/// An example: name, module, settings, primary and secondary filters.
type Example = (&'static str, Instance, Settings, Vec<Filter>, Vec<Filter>);

fn examples() -> Vec<Example> {
    let app = |(n, p): (u8, u8)| App::new(n, p).filters().to_vec();
    vec![
        (
            "loopback",
            Instance::Can1,
            configs::LOOPBACK,
            configs::LOOPBACK_FILTERS.to_vec(),
            vec![],
        ),
        (
            "filters",
            Instance::Can1,
            configs::FILTERS,
            filters_example::primary().to_vec(),
            filters_example::secondary().to_vec(),
        ),
        ("app", Instance::Can1, configs::BUS, app(APP_NODES), vec![]),
        (
            "app node 3",
            Instance::Can1,
            configs::BUS,
            app((3, 1)),
            vec![],
        ),
        (
            "async-echo",
            Instance::Can1,
            configs::BUS,
            configs::ECHO_FILTERS.to_vec(),
            vec![],
        ),
        (
            "can1-can2 (CAN1)",
            Instance::Can1,
            configs::BUS,
            app(CAN1_CAN2_NODES[0]),
            vec![],
        ),
        (
            "can1-can2 (CAN2)",
            Instance::Can2,
            configs::BUS,
            app(CAN1_CAN2_NODES[1]),
            vec![],
        ),
    ]
}

#[test]
fn every_example_configuration_passes_check_and_begin_on_both_boards() {
    let mut ran = 0;
    for board in Board::IMXRT {
        for (name, instance, settings, primary, secondary) in examples() {
            let target = Target::new(board, instance);
            assert_eq!(
                check(target, &settings, &primary, &secondary),
                ConfigErrors::NONE,
                "{name} on {board:?}"
            );
            let model = FlexCanModel::new(target.model_chip());
            let began = FlexCan::begin(
                IdleClocked::new(model),
                &mut HostSystem::new(),
                target,
                &settings,
                &primary,
                &secondary,
            );
            assert!(began.is_ok(), "{name} on {board:?}: {:?}", began.err());
            assert_eq!(
                settings.actual_bit_rate(),
                settings.wished_bit_rate(),
                "{name}"
            );
            ran += 1;
        }
    }
    assert_eq!(ran, 2 * 7);
}

#[test]
fn the_kinetis_settings_are_refused_on_the_teensy_4() {
    // The Teensy 3 `filters_example::SETTINGS` (16 MHz) is not the Teensy 4's.
    let t = Target::new(Board::Teensy41, Instance::Can1);
    assert_eq!(
        check(t, &filters_example::SETTINGS, &[Filter::pass_all()], &[]),
        ConfigErrors::CLOCK_NOT_ON_CHIP
    );
}
