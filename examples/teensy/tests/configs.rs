//! Every Teensy example's FlexCAN configuration — settings and filter lists — on every
//! board it builds for, through the same checks as the firmware (`check`, ACAN table 5)
//! and the model's `begin`: a configuration the manual's rules refuse fails here, not
//! as a blink code on the board. (The `filters` example once passed masked filters as
//! secondary filters, which ACAN §13.4 forbids.)

use twocan_app::{App, FILTER_COUNT};
use twocan_core::Filter;
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::{
    check, Board, ConfigErrors, FlexCan, HostSystem, IdleClocked, Instance, Target,
};
use twocan_teensy::configs::{self, ExampleConfig};
use twocan_teensy::filters_example;

/// The configurations the bins use (`twocan_teensy::configs`: the bins take their
/// settings and filter lists from the same constants).
fn examples() -> [ExampleConfig; 6] {
    configs::every_example()
}

#[test]
fn the_lists_are_the_sources_in_full() {
    let [loopback, filters, app, can0, can1, echo] = examples();
    assert_eq!(&loopback.primary[..], &[Filter::pass_all()][..]);
    assert!(loopback.secondary.is_empty());
    assert_eq!(&filters.primary[..], &filters_example::primary()[..]);
    assert_eq!(&filters.secondary[..], &filters_example::secondary()[..]);
    let (node, peer) = configs::APP_NODES;
    assert_eq!(&app.primary[..], &App::new(node, peer).filters()[..]);
    assert_eq!(app.primary.len(), FILTER_COUNT);
    for (cfg, (node, peer)) in [can0, can1].iter().zip(configs::CAN0_CAN1_NODES) {
        assert_eq!(&cfg.primary[..], &App::new(node, peer).filters()[..]);
    }
    assert_eq!(&echo.primary[..], &configs::ECHO_FILTERS[..]);
}

fn model(board: Board) -> FlexCanModel {
    FlexCanModel::new(Target::new(board, Instance::Can0).model_chip())
}

#[test]
fn every_example_configuration_passes_check_and_begin_on_every_board() {
    let mut ran = 0;
    for board in Board::KINETIS {
        for ExampleConfig {
            name,
            instance,
            settings,
            primary,
            secondary,
        } in examples()
        {
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
