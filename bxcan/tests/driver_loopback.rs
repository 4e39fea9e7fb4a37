//! The driver against the model in loop-back mode: frames of every format and kind,
//! through `twocan_core::Driver`, time stamps, each filter bank mode, and planner plans
//! checked end to end against can-core's `Filter::matches` in list order.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_bxcan::filters::NO_FILTER;
use twocan_bxcan::{plan, Bank, Can, Fifo, FifoPolicy, FilterPlan, PlanOptions};
use twocan_core::{Driver, ErrorState, Filter, Format, Frame, FrameKind, Mode, TxPolicy};

#[test]
fn loopback_standard_extended_remote_through_the_driver() {
    let (can, _regs, bus) = can1_with(&loopback_config(TxPolicy::Fifo), &pass_all());
    let mut d: Driver<_, 16, 8, 16> = Driver::new(can.into_split());
    assert_eq!(d.state(), ErrorState::Active);
    let frames = [
        Frame::standard(0x123, &[1, 2, 3]).unwrap(),
        Frame::extended(0x1ABC_DEF0, &[0xFF; 8]).unwrap(),
        Frame::remote(0x7FF, false, 4).unwrap(),
        Frame::remote(0x0000_0001, true, 0).unwrap(),
        Frame::standard(0, &[]).unwrap(),
    ];
    for f in &frames {
        d.try_send(f).unwrap();
    }
    for _ in 0..20 {
        run(&bus, 200);
        d.on_interrupt();
    }
    let mut got = Vec::new();
    while let Ok(rx) = d.receive() {
        assert_eq!(rx.filter, 0);
        assert_eq!(rx.timestamp, None);
        got.push(rx.frame);
    }
    assert_eq!(got, frames);
    assert_eq!(d.traffic().sent, 5);
    assert_eq!(d.traffic().received, 5);
}

#[test]
fn embedded_can_blocking_traits_work_over_the_driver() {
    use embedded_can::blocking::Can as _;
    let cfg = loopback_config(TxPolicy::Fifo);
    let (can, regs, _bus) = can1_with(&cfg, &pass_all());
    // Time passes while the driver polls (reads of CAN_MSR in on_interrupt).
    let _ = regs;
    let mut d: Driver<_, 8, 8, 8> = Driver::new(can.into_split());
    let f = Frame::extended(0x42, &[9, 8, 7]).unwrap();
    d.transmit(&f).unwrap();
    assert_eq!(embedded_can::blocking::Can::receive(&mut d).unwrap(), f);
}

#[test]
fn time_stamps_with_ttcm() {
    let cfg = loopback_config(TxPolicy::Fifo).timestamps(true);
    let (can, _regs, bus) = can1_with(&cfg, &pass_all());
    let mut can = driver(can);
    can.try_send(&std(1)).unwrap();
    settle(&bus);
    run(&bus, 1000);
    can.try_send(&std(2)).unwrap();
    settle(&bus);
    let rx = drain(&mut can);
    assert_eq!(rx.len(), 2);
    let (t1, t2) = (rx[0].timestamp.unwrap(), rx[1].timestamp.unwrap());
    // The counter runs in bit times: the second frame started ≥ 1000 bits later.
    assert!(t2.bit_times_since(t1).unwrap() >= 1000, "{t1:?} {t2:?}");
}

#[test]
fn each_bank_mode_end_to_end() {
    let a = Filter::standard(0x10);
    let b = Filter::exact(FrameKind::Remote, Format::Extended, 0x1_0000);
    let c = Filter::masked(FrameKind::Any, Format::Standard, 0x7F0, 0x200);
    let d = Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_8000, 0x0ABC_8000);
    let e = Filter::standard(0x300);
    let mut p = FilterPlan::manual();
    p.set_bank(0, Bank::list32(&a, &b, Fifo::Fifo0).unwrap())
        .unwrap();
    p.set_bank(1, Bank::mask32(&c, Fifo::Fifo1).unwrap())
        .unwrap();
    p.set_bank(2, Bank::mask16(&d, &d, Fifo::Fifo0).unwrap())
        .unwrap();
    p.set_bank(
        3,
        Bank::list16([&e, &e, &e, &a], Fifo::Fifo1)
            .unwrap()
            .deactivated(),
    )
    .unwrap();
    // After the deactivated bank, which still takes FIFO 1 numbers 1..4: FMI 5, 6.
    let g = Filter::standard(0x301);
    p.set_bank(4, Bank::list32(&g, &g, Fifo::Fifo1).unwrap())
        .unwrap();
    let cfg = loopback_config(TxPolicy::Fifo);
    let (can, _regs, bus) = can1_with(&cfg, &p);
    let mut can = driver(can);
    let frames = [
        Frame::standard(0x10, &[]).unwrap(),         // bank 0 slot 0
        Frame::remote(0x1_0000, true, 2).unwrap(),   // bank 0 slot 1
        Frame::extended(0x1_0000, &[]).unwrap(),     // data: rejected
        Frame::remote(0x20F, false, 1).unwrap(),     // bank 1
        Frame::standard(0x210, &[]).unwrap(),        // rejected
        Frame::extended(0x0ABC_8123, &[5]).unwrap(), // bank 2 (16-bit mask, prefix)
        Frame::extended(0x0ABC_0123, &[5]).unwrap(), // rejected
        Frame::standard(0x300, &[]).unwrap(),        // bank 3 deactivated: rejected
        Frame::standard(0x301, &[]).unwrap(),        // bank 4, FIFO 1 FMI 5
    ];
    let mut got = Vec::new();
    for f in &frames {
        can.try_send(f).unwrap();
        settle(&bus);
        got.extend(drain(&mut can).into_iter().map(|r| (r.frame, r.filter)));
    }
    for f in &frames {
        let want = p.evaluate(f).map(|a| a.filter);
        let seen = got.iter().find(|(g, _)| g == f).map(|(_, i)| *i);
        assert_eq!(seen, want, "{f:?}");
    }
    assert_eq!(got.len(), 5);
    assert_eq!(p.fmi_of(4, 0), Some((Fifo::Fifo1, 5)));
}

/// A plan from the planner, installed, and every frame of a sweep sent in loop-back:
/// the model's accept/reject and reported index must equal the first match in list order.
fn end_to_end(filters: &[Filter], fifo: FifoPolicy, frames: &[Frame]) {
    let p = plan(filters, PlanOptions::new(14).fifo(fifo)).unwrap();
    let cfg = loopback_config(TxPolicy::Fifo);
    let (can, _regs, bus) = can1_with(&cfg, &p);
    let mut can = driver(can);
    for f in frames {
        can.try_send(f).unwrap();
        settle(&bus);
        let rx = drain(&mut can);
        let want = filters.iter().position(|x| x.matches(f)).map(|i| i as u16);
        let got = match rx.as_slice() {
            [] => None,
            [one] => {
                assert_eq!(one.frame, *f);
                Some(one.filter)
            }
            more => panic!("several frames {more:?}"),
        };
        assert_eq!(got, want, "frame {f:?} plan {p:?}");
        assert_ne!(got, Some(NO_FILTER));
    }
}

fn sweep_frames(ids: &[u32]) -> Vec<Frame> {
    let mut v = Vec::new();
    for &id in ids {
        for flip in [
            0u32,
            1,
            2,
            4,
            8,
            0x10,
            0x100,
            0x400,
            1 << 15,
            1 << 18,
            1 << 28,
        ] {
            let x = id ^ flip;
            if x <= 0x7FF {
                v.push(Frame::standard(x as u16, &[1]).unwrap());
                v.push(Frame::remote(x, false, 1).unwrap());
            }
            v.push(Frame::extended(x & 0x1FFF_FFFF, &[2]).unwrap());
            v.push(Frame::remote(x & 0x1FFF_FFFF, true, 0).unwrap());
        }
    }
    v
}

#[test]
fn planner_plans_are_exact_end_to_end() {
    let filters = [
        Filter::masked(FrameKind::Data, Format::Standard, 0x7F1, 0x100),
        Filter::masked(FrameKind::Any, Format::Standard, 0x7FC, 0x104),
        Filter::standard(0x105),
        Filter::standard(0x200),
        Filter::standard(0x201),
        Filter::standard(0x202),
        Filter::exact(FrameKind::Any, Format::Standard, 0x203),
        Filter::extended(0x0012_3456),
        Filter::exact(FrameKind::Remote, Format::Extended, 0x0012_3457),
        Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_8000, 0x0000_8000),
        Filter::masked(FrameKind::Any, Format::Extended, 0x1FFF_FF00, 0x1000_0000),
        Filter::kind_format(FrameKind::Remote, Format::Any),
    ];
    let ids = [
        0x100,
        0x104,
        0x105,
        0x200,
        0x203,
        0x0012_3456,
        0x0000_8001,
        0x1000_0042,
    ];
    let frames = sweep_frames(&ids);
    end_to_end(&filters, FifoPolicy::Fifo0, &frames);
    end_to_end(&filters, FifoPolicy::Balanced, &frames);
}

#[test]
fn nine_ids_merged_into_one_bank_end_to_end() {
    let filters: Vec<Filter> = (0..9).map(|i| Filter::standard(0x700 + i)).collect();
    // One entry per identifier: three 16-bit list banks.
    let list_only = plan(&filters, PlanOptions::new(14).merge(false)).unwrap();
    assert_eq!(list_only.bank_count(), 3);
    // Merged (the default): 0x700..=0x707 is one exact mask, 0x708 a list entry.
    let p = plan(&filters, PlanOptions::new(14)).unwrap();
    assert_eq!(p.bank_count(), 1);
    let frames: Vec<Frame> = (0x6F0..0x720)
        .map(|i| Frame::standard(i, &[]).unwrap())
        .collect();
    end_to_end(&filters, FifoPolicy::Fifo1, &frames);
}

#[test]
fn install_filters_keeps_the_operating_mode() {
    let cfg = loopback_config(TxPolicy::Fifo);
    let (can, _regs, bus) = can1_with(&cfg, &pass_all());
    let mut can = driver(can);
    assert_eq!(can.hardware().mode(), Mode::Normal);
    let only = plan(&[Filter::standard(0x55)], PlanOptions::new(14)).unwrap();
    can.set_filters(&only).unwrap();
    assert_eq!(can.hardware().mode(), Mode::Normal);
    can.try_send(&std(0x54)).unwrap();
    can.try_send(&std(0x55)).unwrap();
    settle(&bus);
    let rx = drain(&mut can);
    assert_eq!(rx.len(), 1);
    assert_eq!((rx[0].frame, rx[0].filter), (std(0x55), 0));
    // A plan larger than the instance's 14 banks is refused.
    let big: Vec<Filter> = (0..15)
        .map(|i| Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_FFF0, i << 8))
        .collect();
    let p = plan(&big, PlanOptions::new(28)).unwrap();
    assert_eq!(
        can.set_filters(&p),
        Err(twocan_core::Error::InvalidArgument)
    );
    assert_eq!(
        can.hardware().plan(&big, FifoPolicy::Fifo0).unwrap_err(),
        twocan_bxcan::PlanError::TooManyBanks {
            needed: 15,
            available: 14
        }
    );
}

#[test]
fn can3_has_fourteen_banks_of_its_own() {
    let bus = new_bus();
    let model = twocan_bxcan::model::BxCanModel::can3();
    bus.borrow_mut().attach("can3", model.clone());
    let regs = Clocked::new(model, &bus);
    let init = Can::can3(regs, &loopback_config(TxPolicy::Fifo))
        .map_err(|f| f.error)
        .unwrap();
    assert_eq!(init.can().bank_range(), (0, 14));
    let mut init = init;
    let p = init
        .can()
        .plan(&[Filter::extended(7)], FifoPolicy::Fifo0)
        .unwrap();
    init.set_filters(&p).unwrap();
    let mut can = driver(init.enable().map_err(|f| f.error).unwrap());
    can.try_send(&Frame::extended(7, &[]).unwrap()).unwrap();
    can.try_send(&Frame::extended(8, &[]).unwrap()).unwrap();
    settle(&bus);
    let rx = drain(&mut can);
    assert_eq!(rx.len(), 1);
    assert_eq!(rx[0].filter, 0);
}
