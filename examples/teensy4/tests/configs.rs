//! Every Teensy 4 example's configuration passes `check` and the model's `begin` on the
//! module it uses, on both boards, in the layout the examples use (the RT1062's,
//! `Imxrt1062`): a configuration the driver refuses would otherwise only show on the
//! board as `rt::HALT` = 5.

use twocan_app::App;
use twocan_core::{Filter, Registers};
use twocan_flexcan::begin::check_with_layout;
use twocan_flexcan::layout::{Imxrt1062, LargeFilterTable, Layout};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::options::FullInSlot;
use twocan_flexcan::regs::{self, FlexCanRegs};
use twocan_flexcan::rt::IrqState;
use twocan_flexcan::{
    check, BeginPlan, Board, ConfigErrors, FlexCan, HostSystem, IdleClocked, Instance, Settings,
    Target,
};
use twocan_teensy4::can::{self, CanState};
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
                check_with_layout::<Imxrt1062>(target, &settings, &primary, &secondary),
                ConfigErrors::NONE,
                "{name} on {board:?}"
            );
            assert!(
                BeginPlan::<Imxrt1062>::new_with_layout(target, &settings, settings.configuration)
                    .is_ok(),
                "{name} on {board:?}"
            );
            let model = FlexCanModel::new(target.model_chip());
            let began = FlexCan::<_, Imxrt1062>::begin_with_layout(
                IdleClocked::new(model.clone()),
                &mut HostSystem::new(),
                target,
                &settings,
                &primary,
                &secondary,
            );
            assert!(began.is_ok(), "{name} on {board:?}: {:?}", began.err());
            // The RT1062 layout: the ERR005829 reserved mailbox, the data mailbox after
            // it is `MCR[MAXMB]`.
            let c = settings.configuration;
            assert_eq!(
                regs::mcr::MAXMB.get(model.read32(regs::MCR)),
                u32::from(Imxrt1062::data_mailbox(c)),
                "{name}"
            );
            assert_eq!(
                model.read32(regs::IMASK1) & 1 << c.reserved_mailbox(),
                0,
                "{name}"
            );
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

/// The examples' state and table are the RT1062 layout's: these bindings do not compile
/// if `twocan_teensy4::can` goes back to ACAN's layout.
#[test]
fn the_examples_types_are_in_the_rt1062_layout() {
    let state = CanState::new();
    let _: &IrqState<
        FlexCanRegs,
        { twocan_flexcan::RECEIVE_BUFFER_SIZE },
        can::Queue,
        { can::COMPLETIONS },
        FullInSlot<Imxrt1062>,
    > = &state;
    let slot = can::TableSlot::new_sized();
    let _: &twocan_flexcan::filters::TableSlot<LargeFilterTable> = &slot;
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
