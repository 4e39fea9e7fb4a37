//! The driver with the i.MX RT1062 layout ([`twocan_flexcan::layout::Imxrt1062`]) over
//! the FlexCAN model's RT1062 variants: Rx FIFO filter tables of 32, 64, 96 and 128
//! elements (`CTRL2[RFFN]` 3, 7, 0xB, 0xF; IMXRT1060RM, FlexCAN chapter, table "Rx FIFO
//! filter: possible structures"), every primary and secondary filter reporting its user
//! index, and the transmit mailboxes after the table — above MB31 from RFFN 0xC on,
//! their flags in `IFLAG2`/`IMASK2`, `MCR[MAXMB]` = the data mailbox — completing
//! every accepted frame exactly once, in order, remote frames included; aborts there;
//! a filter switch of a 128-element table; `end` and `begin` again; a 128-element plan
//! made at compile time on the lean path; and the typed errors of a table too large for
//! the layout or the chip.

mod common;

use common::*;
use twocan_core::{
    AbortRequest, Driver, Filter, Format, Frame, FrameKind, Hardware, MailboxId, MailboxState,
    Registers, Token, TxOutcome,
};
use twocan_flexcan::begin::check_with_layout;
use twocan_flexcan::layout::{Imxrt1062, Layout};
use twocan_flexcan::regs::{self, ctrl2, iflag1, mcr};
use twocan_flexcan::{
    BeginError, Board, CanClock, ConfigErrors, Configuration, FlexCan, FlexCanHw, HostSystem,
    InstalledFilters, Instance, LargeFilterTable, Settings, Target,
};

/// The driver over the model, the RT1062 layout.
type Large<const RX: usize, const TX: usize> = CanRt<RX, TX>;

const T41: [Target; 3] = [
    Target::new(Board::Teensy41, Instance::Can1),
    Target::new(Board::Teensy41, Instance::Can2),
    Target::new(Board::Teensy41, Instance::Can3),
];

/// The table sizes of the issue: 32, 64, 96 and 128 elements.
const SIZES: [Configuration; 4] = [
    Configuration::Filters14_18,
    Configuration::Filters22_42,
    Configuration::Filters30_66,
    Configuration::Filters32_96,
];

fn settings(configuration: Configuration, loop_back: bool) -> Settings {
    let mut s = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
    s.configuration = configuration;
    s.loop_back = loop_back;
    s.self_reception = loop_back;
    s
}

/// A full table for `c`: primary filters of every kind (exact standard data, a masked
/// extended range, exact remote), secondary filters of exact extended identifiers.
fn lists(c: Configuration) -> (Vec<Filter>, Vec<Filter>) {
    let p = c.primary_filter_capacity();
    let primary = (0..p)
        .map(|i| match i % 3 {
            0 => Filter::standard(0x100 + i as u16),
            1 => Filter::masked(
                FrameKind::Data,
                Format::Extended,
                0x1FFF_FF00,
                0x0100_0000 + ((i as u32) << 8),
            ),
            _ => Filter::exact(FrameKind::Remote, Format::Standard, 0x400 + i as u32),
        })
        .collect();
    let secondary = (0..c.secondary_filter_capacity())
        .map(|j| Filter::extended(0x0002_0000 + j as u32))
        .collect();
    (primary, secondary)
}

/// A frame each filter of [`lists`] accepts, with its user index.
fn frames(c: Configuration) -> Vec<(Frame, u16)> {
    let p = c.primary_filter_capacity();
    let mut out: Vec<(Frame, u16)> = (0..p)
        .map(|i| {
            let f = match i % 3 {
                0 => std_data(0x100 + i as u16, &[i as u8]),
                1 => ext_data(0x0100_0000 + ((i as u32) << 8) + 0x5A, &[i as u8, 1]),
                _ => remote(0x400 + i as u32, false),
            };
            (f, i as u16)
        })
        .collect();
    out.extend((0..c.secondary_filter_capacity()).map(|j| {
        (
            ext_data(0x0002_0000 + j as u32, &[j as u8, 2, 3]),
            (p + j) as u16,
        )
    }));
    out
}

/// Sends `frames` in batches the transmit ring holds, runs the bus after each, and
/// checks that every frame comes back (loop-back, self reception) with its user index
/// and completes exactly once, sent, in the order it was accepted.
fn send_and_check<const RX: usize, const TX: usize>(
    bus: &mut twocan_sim::Bus,
    can: &mut Large<RX, TX>,
    frames: &[(Frame, u16)],
) {
    for batch in frames.chunks(TX) {
        let mut tokens: Vec<Token> = Vec::new();
        for (f, _) in batch {
            tokens.push(can.try_send(f).unwrap());
        }
        run(bus, &mut [can], 200 * batch.len() as u64 + 500);
        let got: Vec<(Frame, u16)> = drain(can).iter().map(|r| (r.frame, r.filter)).collect();
        assert_eq!(got, batch.to_vec());
        let done: Vec<_> = std::iter::from_fn(|| can.take_completion()).collect();
        assert_eq!(
            done.iter().map(|c| c.token).collect::<Vec<_>>(),
            tokens,
            "one completion per frame, in order"
        );
        assert!(done.iter().all(|c| c.outcome == TxOutcome::Sent));
    }
}

#[test]
fn tables_of_32_64_96_and_128_elements_give_every_user_index() {
    for (k, c) in SIZES.into_iter().enumerate() {
        let target = T41[k % 3];
        let (primary, secondary) = lists(c);
        let (model, mut can) =
            begin_rt_on_exact::<64, 16>(target, &settings(c, true), &primary, &secondary)
                .unwrap_or_else(|e| panic!("{c:?}: {e:?}"));
        assert_eq!(
            can.receive_context().filters().elements().len(),
            c.table_elements()
        );
        let r = can.hardware().registers();
        assert_eq!(ctrl2::RFFN.get(r.read32(regs::CTRL2)), u32::from(c.rffn()));
        assert_eq!(
            mcr::MAXMB.get(r.read32(regs::MCR)),
            u32::from(Imxrt1062::data_mailbox(c))
        );
        // The transmit mailboxes' interrupts: IMASK1 below MB32, IMASK2 above.
        let tx: u64 = (Imxrt1062::first_remote_mailbox(c)..=Imxrt1062::data_mailbox(c))
            .fold(0, |m, mb| m | 1 << mb);
        let fifo = u64::from(iflag1::BUF5I | iflag1::BUF7I);
        let imask = u64::from(r.read32(regs::IMASK1)) | u64::from(r.read32(regs::IMASK2)) << 32;
        assert_eq!(imask, fifo | tx, "{c:?}");
        let caps = can.capabilities();
        assert_eq!(
            usize::from(caps.max_standard_filters),
            c.table_elements(),
            "{c:?}"
        );
        assert_eq!(
            can.hardware().mailbox_count(),
            1 + c.remote_mailbox_count(),
            "{c:?}"
        );
        let mut bus = bus_with(500_000, &[&model]);
        send_and_check(&mut bus, &mut can, &frames(c));
        // A frame no filter accepts is not received.
        can.try_send(&std_data(0x7FF, &[])).unwrap();
        run(&mut bus, &mut [&mut can], 500);
        assert!(drain(&mut can).is_empty(), "{c:?}");
        assert_eq!(
            can.take_completion().map(|c| c.outcome),
            Some(TxOutcome::Sent)
        );
    }
}

#[test]
fn every_rffn_of_the_chip_begins_and_sends_from_its_mailboxes() {
    // The largest RFFN the layout accepts on the RT1062 is the chip's.
    assert_eq!(Imxrt1062::max_rffn(T41[0].board.chip()), 0xF);
    for c in Configuration::EVERY {
        let (primary, secondary) = lists(c);
        let (model, mut can) =
            begin_rt_on_exact::<32, 8>(T41[0], &settings(c, true), &primary, &secondary)
                .unwrap_or_else(|e| panic!("{c:?}: {e:?}"));
        let mut bus = bus_with(500_000, &[&model]);
        // The first and last filters of each kind.
        let all = frames(c);
        let pick: Vec<(Frame, u16)> = [0, 1, 2, primary.len(), all.len() - 1]
            .into_iter()
            .filter_map(|i| all.get(i).copied())
            .collect();
        send_and_check(&mut bus, &mut can, &pick);
    }
}

#[test]
fn remote_frames_from_mailboxes_above_mb31_complete_once_in_order() {
    let c = Configuration::Filters32_96;
    assert!(Imxrt1062::first_remote_mailbox(c) >= 32 && c.remote_mailbox_count() == 7);
    let (model, mut can) =
        begin_rt_on_exact::<32, 16>(T41[2], &settings(c, true), &[Filter::pass_all()], &[])
            .unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    // Remote frames straight into their mailboxes (several at once: their flags end
    // together in IFLAG2), data frames through the data mailbox.
    let mut tokens = Vec::new();
    for i in 0..7u32 {
        tokens.push(can.try_send_now(&remote(0x500 - i, false)).unwrap());
    }
    assert!(
        can.try_send_now(&remote(0x10, false)).is_err(),
        "seven mailboxes"
    );
    for m in 1..=7 {
        assert_eq!(can.mailbox_state(MailboxId(m)), MailboxState::Pending);
    }
    for i in 0..3u16 {
        tokens.push(can.try_send(&std_data(0x600 + i, &[i as u8])).unwrap());
    }
    run(&mut bus, &mut [&mut can], 5_000);
    let got = drain(&mut can);
    assert_eq!(got.len(), 10);
    assert!(got.iter().all(|r| r.filter == 0));
    // The remote frames win arbitration by identifier (smallest first).
    let remotes: Vec<u32> = got
        .iter()
        .filter(|r| r.frame.is_remote())
        .map(|r| r.frame.raw_id())
        .collect();
    assert_eq!(remotes, (0..7).map(|i| 0x500 - 6 + i).collect::<Vec<_>>());
    let done: Vec<_> = std::iter::from_fn(|| can.take_completion()).collect();
    assert_eq!(
        done.len(),
        tokens.len(),
        "one completion per accepted frame"
    );
    let mut seen: Vec<Token> = done.iter().map(|c| c.token).collect();
    seen.sort_by_key(|t| t.0);
    assert_eq!(seen, tokens);
    assert!(done.iter().all(|c| c.outcome == TxOutcome::Sent));
    // Data frames complete in request order.
    let data: Vec<Token> = done
        .iter()
        .map(|c| c.token)
        .filter(|t| tokens[7..].contains(t))
        .collect();
    assert_eq!(data, tokens[7..].to_vec());
    let r = can.hardware().registers();
    assert_eq!(r.read32(regs::IFLAG2), 0, "every flag acknowledged");
}

#[test]
fn abort_in_a_mailbox_above_mb31() {
    // Normal mode, alone on the bus: nothing leaves the mailboxes before bus time.
    let c = Configuration::Filters32_80;
    let (_model, mut can) =
        begin_rt_on_exact::<32, 16>(T41[1], &settings(c, false), &[Filter::pass_all()], &[])
            .unwrap();
    let data = can.try_send(&std_data(0x123, &[1])).unwrap();
    let rtr = can.try_send_now(&remote(0x42, false)).unwrap();
    assert_eq!(can.mailbox_state(MailboxId(0)), MailboxState::Pending);
    assert_eq!(can.abort(data), AbortRequest::Requested);
    assert_eq!(can.abort(rtr), AbortRequest::Requested);
    can.on_interrupt();
    let done: Vec<_> = std::iter::from_fn(|| can.take_completion()).collect();
    assert_eq!(
        done.iter()
            .map(|c| (c.token, c.outcome))
            .collect::<Vec<_>>(),
        vec![(data, TxOutcome::Aborted), (rtr, TxOutcome::Aborted)]
    );
    for m in 0..can.hardware().mailbox_count() {
        assert_eq!(can.mailbox_state(MailboxId(m)), MailboxState::Empty);
    }
    // The data mailbox (MB42) is usable again.
    can.try_send(&std_data(0x124, &[])).unwrap();
    assert_eq!(can.mailbox_state(MailboxId(0)), MailboxState::Pending);
}

#[test]
fn a_128_element_table_is_switched_while_running() {
    let c = Configuration::Filters32_96;
    let (primary, secondary) = lists(c);
    let (model, mut can) =
        begin_rt_on_exact::<64, 16>(T41[0], &settings(c, true), &primary, &secondary).unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    // The lists swapped: the old secondary identifiers are now the first filters.
    let new_primary: Vec<Filter> = secondary[..32].to_vec();
    let new_secondary: Vec<Filter> = (0..96u32).map(|j| Filter::extended(0x3000 + j)).collect();
    let table = LargeFilterTable::compile_for(c, &new_primary, &new_secondary).unwrap();
    can.set_filters(&table).unwrap();
    let frames: Vec<(Frame, u16)> = vec![
        (ext_data(0x0002_0000, &[]), 0),
        (ext_data(0x0002_001F, &[]), 31),
        (ext_data(0x3000, &[]), 32),
        (ext_data(0x305F, &[]), 127),
    ];
    send_and_check(&mut bus, &mut can, &frames);
    // A table of another configuration is refused.
    let other = LargeFilterTable::compile_for(Configuration::Filters30_66, &[], &[]).unwrap();
    assert!(can.set_filters(&other).is_err());
}

#[test]
fn too_large_a_table_is_a_typed_error() {
    let c = Configuration::Filters32_96;
    let (primary, secondary) = lists(c);
    // One primary filter more than the 32 individual masks.
    let mut more = primary.clone();
    more.push(Filter::standard(0x7F0));
    let s = settings(c, true);
    let expected = ConfigErrors::TOO_MANY_PRIMARY_FILTERS;
    assert_eq!(
        check_with_layout::<Imxrt1062>(T41[0], &s, &more, &secondary),
        expected
    );
    let e = begin_rt_on_exact::<8, 8>(T41[0], &s, &more, &secondary)
        .map(|_| ())
        .unwrap_err();
    assert_eq!(e, BeginError::Config(expected));
    // The RT1062 layout on a Kinetis chip: RFFN 0–3 only (16 message buffers).
    let t36 = Target::new(Board::Teensy36, Instance::Can0);
    let mut k = Settings::new(500_000);
    k.configuration = Configuration::Filters16_24;
    assert_eq!(
        check_with_layout::<Imxrt1062>(t36, &k, &[], &[]),
        ConfigErrors::CONFIGURATION_NOT_ON_CHIP
    );
    let e = begin_rt_on_exact::<8, 8>(t36, &k, &[Filter::pass_all()], &[])
        .map(|_| ())
        .unwrap_err();
    assert_eq!(
        e,
        BeginError::Config(ConfigErrors::CONFIGURATION_NOT_ON_CHIP)
    );
    // ... and none of ACAN's either: the ERR005829 reserved mailbox puts their data
    // mailbox at MB16, beyond a Kinetis module's 16 buffers (the default layout runs
    // them there).
    for c in Configuration::ALL {
        k.configuration = c;
        assert_eq!(Imxrt1062::data_mailbox(c), 16);
        assert_eq!(
            check_with_layout::<Imxrt1062>(t36, &k, &[], &[]),
            ConfigErrors::CONFIGURATION_NOT_ON_CHIP,
            "{c:?}"
        );
        let e = begin_rt_on_exact::<8, 8>(t36, &k, &[Filter::pass_all()], &[])
            .map(|_| ())
            .unwrap_err();
        assert_eq!(
            e,
            BeginError::Config(ConfigErrors::CONFIGURATION_NOT_ON_CHIP)
        );
        assert!(check_with_layout::<twocan_flexcan::layout::Kinetis>(t36, &k, &[], &[]).is_empty());
    }
    // A table too large for the table type is refused by the compiler of lists too.
    assert_eq!(
        twocan_flexcan::FilterTable::compile(Configuration::Filters16_24, &[], &[]).unwrap_err(),
        ConfigErrors::CONFIGURATION_NOT_ON_CHIP
    );
}

#[test]
fn end_masks_the_mailboxes_above_mb31_and_begin_runs_again() {
    let c = Configuration::Filters32_96;
    let (_model, can) =
        begin_rt_on_exact::<8, 8>(T41[0], &settings(c, true), &[Filter::pass_all()], &[]).unwrap();
    let tx = (Imxrt1062::first_remote_mailbox(c)..=Imxrt1062::data_mailbox(c))
        .fold(0u32, |m, mb| m | 1 << (mb - 32));
    assert_eq!(can.hardware().registers().read32(regs::IMASK2), tx);
    let hw = can.release();
    let (regs, _table) = hw.end(&mut HostSystem::new()).map_err(|(_, e)| e).unwrap();
    assert_eq!(regs.read32(regs::IMASK2), 0);
    assert_eq!(regs.read32(regs::IMASK1), 0);
    assert_eq!(regs.read32(regs::IFLAG2), 0);
    // The reserved mailbox (MB38) is left INACTIVE by the driver and by `end`.
    assert_eq!(
        regs::cs::CODE.get(regs.read32(regs::mb_cs(38))),
        regs::code::TX_INACTIVE
    );
    // The same registers begin again, with a table of another size.
    let c = Configuration::Filters22_42;
    let can = FlexCan::<_, Imxrt1062>::begin_with_layout(
        regs,
        &mut HostSystem::new(),
        T41[0],
        &settings(c, true),
        &[Filter::pass_all()],
        &[],
    )
    .unwrap();
    let r = can.registers();
    assert_eq!(
        mcr::MAXMB.get(r.read32(regs::MCR)),
        u32::from(Imxrt1062::data_mailbox(c))
    );
    assert_eq!(r.read32(regs::IMASK2), 0, "MB23–MB30: IMASK1");
    assert_eq!(
        r.read32(regs::IMASK1),
        iflag1::BUF5I | iflag1::BUF7I | 0xFF << 23,
        "the reserved MB22 masked"
    );
    assert_eq!(
        regs::cs::CODE.get(r.read32(regs::mb_cs(22))),
        regs::code::TX_INACTIVE
    );
    let mut can: Large<8, 8> = Driver::new(can.into_split());
    can.try_send(&std_data(0x42, &[])).unwrap();
}

/// The lean path with the RT1062 layout: a table of 128 elements planned at compile
/// time, the settings checked for the layout beforehand, the controller read from flash
/// ([`twocan_flexcan::options::Lean`]`<Imxrt1062>`), frames sent from MB39–MB46 (MB38 the ERR005829 reserved mailbox).
#[test]
fn a_const_plan_of_128_elements_on_the_lean_path() {
    use twocan_flexcan::begin::BeginPlan;
    use twocan_flexcan::const_plan_large;
    use twocan_flexcan::options::Lean;
    use twocan_flexcan::planner::PlanOptions;

    const IDS: [Filter; 128] = {
        let mut f = [Filter::pass_all(); 128];
        let mut i = 0;
        while i < 128 {
            f[i] = Filter::extended(0x0040_0000 + 9 * i as u32);
            i += 1;
        }
        f
    };
    let plan = const_plan_large!(IDS, PlanOptions::choose().merge(false)).planned();
    assert_eq!(plan.configuration(), Configuration::Filters32_96);
    let s = settings(plan.configuration(), true);
    // The default layout refuses the plan's configuration; the RT1062 layout takes it.
    assert!(BeginPlan::new(T41[2], &s, plan.configuration()).is_err());
    let checked = BeginPlan::<Imxrt1062>::new_with_layout(T41[2], &s, plan.configuration())
        .expect("the RT1062 layout takes RFFN 0xF");
    let model = model_of(T41[2]);
    model.scramble_ram(0x1EA7);
    let hw: FlexCanHw<_, Lean<Imxrt1062>> = FlexCan::begin_checked(
        Ticking::new(model.clone()),
        &mut HostSystem::new(),
        &checked,
        plan,
    )
    .unwrap();
    let mut can: LeanLarge = Driver::new(hw);
    let mut bus = bus_with(500_000, &[&model]);
    for i in [0u32, 31, 32, 100, 127] {
        let f = ext_data(0x0040_0000 + 9 * i, &[i as u8]);
        can.try_send(&f).unwrap();
        run(&mut bus, &mut [&mut can], 400);
        let got: Vec<(Frame, u16)> = core::iter::from_fn(|| can.receive().ok())
            .map(|r| (r.frame, r.filter))
            .collect();
        assert_eq!(got, vec![(f, i as u16)]);
    }
    assert_eq!(can.traffic().sent, 5);
    assert_eq!(model.read32(regs::IFLAG2), 0, "every flag acknowledged");
    // The lean path reserves the ERR005829 mailbox as well (MB38, over scrambled RAM
    // at `begin`: INACTIVE, masked).
    assert_eq!(
        regs::cs::CODE.get(model.read32(regs::mb_cs(38))),
        regs::code::TX_INACTIVE
    );
    assert_eq!(model.read32(regs::IMASK2) & 1 << (38 - 32), 0);
}

/// The lean driver with the RT1062 layout.
type LeanLarge = Driver<FlexCanHw<Ticking, twocan_flexcan::options::Lean<Imxrt1062>>, 32, 16>;

/// The bit-timing rule follows the buffers the configuration enables (IMXRT1060RM,
/// "Arbitration and matching timing": 16 peripheral clocks per CAN bit up to 16
/// buffers, 30 above 32): at 1 Mbit/s with the peripheral clock the 24 MHz CAN clock
/// (no bus clock given), 14/18 is taken and 32/96 (MB0–MB46) refused, by `check`,
/// `begin` and the running controller's `set_bitrate` alike; with the RT1062's 150 MHz
/// IPG clock given, both are taken.
#[test]
fn the_timing_rule_counts_the_enabled_buffers() {
    let fast = |c: Configuration, bus: Option<u32>| {
        let mut s = Settings::with_clock(1_000_000, CanClock::IMXRT_24MHZ);
        s.configuration = c;
        s.bus_clock_hz = bus;
        s
    };
    let pass = [Filter::pass_all()];
    for (c, ok) in [
        (Configuration::Filters14_18, true),
        (Configuration::Filters32_96, false),
    ] {
        let s = fast(c, None);
        let e = check_with_layout::<Imxrt1062>(T41[0], &s, &pass, &[]);
        assert_eq!(e.is_empty(), ok, "{c:?}: {e:?}");
        assert_eq!(
            begin_rt_on_exact::<8, 8>(T41[0], &s, &pass, &[]).is_ok(),
            ok
        );
        let s = fast(c, Some(150_000_000));
        assert_eq!(
            check_with_layout::<Imxrt1062>(T41[0], &s, &pass, &[]),
            ConfigErrors::NONE
        );
    }
    // The running controller applies the same rule: 32/96 at 500 kbit/s, then 1 Mbit/s
    // refused with nothing written; the capabilities report the 30-clock rule.
    let (_model, mut can) = begin_rt_on_exact::<8, 8>(
        T41[0],
        &settings(Configuration::Filters32_96, false),
        &pass,
        &[],
    )
    .unwrap();
    let caps = can.capabilities();
    assert!(caps.timing_rule().check_bitrate(1_000_000).is_err());
    assert!(caps.timing_rule().check_bitrate(500_000).is_ok());
    can.set_mode(twocan_core::Mode::Stopped).unwrap();
    let ctrl1 = can.hardware().registers().read32(regs::CTRL1);
    assert!(can.set_bitrate(1_000_000, 750).is_err());
    assert_eq!(
        can.hardware().registers().read32(regs::CTRL1),
        ctrl1,
        "nothing written"
    );
    assert!(can.set_bitrate(250_000, 750).is_ok());
}
