//! Every Teensy example's FlexCAN configuration — settings and filter lists — on every
//! board it builds for, through the same checks as the firmware (`check`, ACAN table 5)
//! and the model's `begin`: a configuration the manual's rules refuse fails here, not
//! as a blink code on the board. (The `filters` example once passed masked filters as
//! secondary filters, which ACAN §13.4 forbids.)

use twocan_app::App;
use twocan_core::Filter;
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::{
    check, Board, ConfigErrors, FlexCan, HostSystem, IdleClocked, Instance, Settings, Target,
};
use twocan_teensy::{configs, filters_example};

/// One example's configuration: (example, instance, settings, primary, secondary).
type Example = (&'static str, Instance, Settings, Vec<Filter>, Vec<Filter>);

fn examples() -> Vec<Example> {
    let node1 = App::new(1, 2);
    let node2 = App::new(2, 1);
    vec![
        (
            "loopback",
            Instance::Can0,
            configs::LOOPBACK,
            vec![Filter::pass_all()],
            vec![],
        ),
        (
            "filters",
            Instance::Can0,
            filters_example::SETTINGS,
            filters_example::primary().to_vec(),
            filters_example::secondary().to_vec(),
        ),
        (
            "app",
            Instance::Can0,
            configs::BUS,
            node1.filters().to_vec(),
            vec![],
        ),
        (
            "can0-can1 (can0)",
            Instance::Can0,
            configs::BUS,
            node1.filters().to_vec(),
            vec![],
        ),
        (
            "can0-can1 (can1)",
            Instance::Can1,
            configs::BUS,
            node2.filters().to_vec(),
            vec![],
        ),
        (
            "async-echo",
            Instance::Can0,
            configs::BUS,
            vec![Filter::pass_all()],
            vec![],
        ),
    ]
}

fn model(board: Board) -> FlexCanModel {
    match board {
        Board::Teensy32 => FlexCanModel::mk20dx256(),
        Board::Teensy35 => FlexCanModel::mk64fx512(),
        Board::Teensy36 => FlexCanModel::mk66fx1m0(),
    }
}

#[test]
fn every_example_configuration_passes_check_and_begin_on_every_board() {
    let mut ran = 0;
    for board in Board::ALL {
        for (name, instance, settings, primary, secondary) in examples() {
            // can0-can1 needs FlexCAN1: Teensy 3.6 only (its bin requires teensy36).
            if instance == Instance::Can1 && board != Board::Teensy36 {
                continue;
            }
            let target = Target::new(board, instance);
            assert_eq!(
                check(target, &settings, &primary, &secondary),
                ConfigErrors::NONE,
                "{name} on {board:?}"
            );
            let began = FlexCan::begin(
                IdleClocked::new(model(board)),
                &mut HostSystem::new(),
                target,
                &settings,
                &primary,
                &secondary,
            );
            assert!(began.is_ok(), "{name} on {board:?}: {:?}", began.err());
            ran += 1;
        }
    }
    assert_eq!(ran, 3 * 5 + 1);
}

#[test]
fn the_old_filters_configuration_is_refused() {
    // The regression this test exists for: masked filters as secondary filters.
    let old_secondary = filters_example::primary()[..2].to_vec();
    let flags = check(
        Target::new(Board::Teensy32, Instance::Can0),
        &filters_example::SETTINGS,
        &[],
        &old_secondary,
    );
    assert!(flags.contains(ConfigErrors::SECONDARY_FILTER_NOT_CONFORM));
}
