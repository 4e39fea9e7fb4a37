//! CAN1 and CAN2 sharing CAN1's filter block, split at `CAN2SB` (set through CAN1's
//! configuration); CAN2's filters written through CAN1's registers.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::{Can, FifoPolicy};
use twocan_core::{Driver, Filter, Frame, TxPolicy};

#[test]
fn can2_uses_can1_banks_from_the_start_bank() {
    let bus = new_bus();
    let (m1, m2) = BxCanModel::can1_can2();
    bus.borrow_mut().attach("can1", m1.clone());
    bus.borrow_mut().attach("can2", m2.clone());
    let r1 = Clocked::new(m1.clone(), &bus);
    let r2 = Clocked::new(m2, &bus);

    let cfg1 = loopback_config(TxPolicy::Fifo).can2_start_bank(10).unwrap();
    let mut init1 = Can::can1(r1, &cfg1).map_err(|f| f.error).unwrap();
    assert_eq!(init1.can().bank_range(), (0, 10));
    // CAN2's filter access goes through a second handle on CAN1's registers.
    let mut init2 = Can::can2(r2, m1.clone(), &loopback_config(TxPolicy::Fifo))
        .map_err(|f| f.error)
        .unwrap();
    assert_eq!(init2.can().bank_range(), (10, 28));

    let f1 = [
        Filter::standard(0x100),
        Filter::standard(0x101),
        Filter::extended(0x1_0000),
    ];
    let f2 = [
        Filter::extended(0x2_0000),
        Filter::standard(0x200),
        Filter::masked(
            twocan_core::FrameKind::Data,
            twocan_core::Format::Standard,
            0x7F0,
            0x300,
        ),
    ];
    let p1 = init1.can().plan(&f1, FifoPolicy::Fifo0).unwrap();
    let p2 = init2.can().plan(&f2, FifoPolicy::Balanced).unwrap();
    init1.set_filters(&p1).unwrap();
    init2.set_filters(&p2).unwrap();
    let can1 = init1.enable().map_err(|f| f.error).unwrap();
    let can2 = init2.enable().map_err(|f| f.error).unwrap();
    let mut d1: Driver<_, 16, 8, 16> = Driver::new(can1.into_split());
    let mut d2: Driver<_, 16, 8, 16> = Driver::new(can2.into_split());

    let probe = [
        Frame::standard(0x100, &[]).unwrap(),
        Frame::standard(0x101, &[]).unwrap(),
        Frame::extended(0x1_0000, &[]).unwrap(),
        Frame::extended(0x2_0000, &[]).unwrap(),
        Frame::standard(0x200, &[]).unwrap(),
        Frame::standard(0x30A, &[]).unwrap(),
        Frame::standard(0x400, &[]).unwrap(),
    ];
    for (who, d_filters) in [(1, &f1[..]), (2, &f2[..])] {
        for f in &probe {
            if who == 1 {
                d1.try_send(f).unwrap();
            } else {
                d2.try_send(f).unwrap();
            }
            for _ in 0..5 {
                run(&bus, 200);
                d1.on_interrupt();
                d2.on_interrupt();
            }
            let rx = if who == 1 { d1.receive() } else { d2.receive() };
            let want = d_filters
                .iter()
                .position(|x| x.matches(f))
                .map(|i| i as u16);
            let got = rx.ok().map(|r| {
                assert_eq!(r.frame, *f);
                r.filter
            });
            assert_eq!(got, want, "CAN{who} frame {f:?}");
            // Loop-back disregards CANRX (RM0410 §40.5.2): the other controller sees
            // nothing; drain both so the next check starts clean.
            while d1.receive().is_ok() {}
            while d2.receive().is_ok() {}
        }
    }
    let (t1, t2) = (d1.traffic(), d2.traffic());
    assert_eq!((t1.queued, t1.sent), (7, 7));
    assert_eq!((t2.queued, t2.sent), (7, 7));
}

type D1 = Driver<twocan_bxcan::BxCan<Clocked>, 16, 8, 16>;
type D2 = Driver<twocan_bxcan::BxCan<Clocked, BxCanModel>, 16, 8, 16>;

/// Sends each probe frame from CAN`who` in loop-back and checks the filter index the
/// driver reports against the first of `filters` that accepts it.
fn probe_loopback(bus: &SharedBus, d1: &mut D1, d2: &mut D2, who: u8, filters: &[Filter]) {
    let probe = [
        Frame::standard(0x100, &[]).unwrap(),
        Frame::extended(0x1_0000, &[]).unwrap(),
        Frame::extended(0x2_0000, &[]).unwrap(),
        Frame::standard(0x200, &[]).unwrap(),
        Frame::standard(0x30A, &[]).unwrap(),
        Frame::standard(0x400, &[]).unwrap(),
    ];
    for f in &probe {
        if who == 1 {
            d1.try_send(f).unwrap();
        } else {
            d2.try_send(f).unwrap();
        }
        for _ in 0..5 {
            run(bus, 200);
            d1.on_interrupt();
            d2.on_interrupt();
        }
        let rx = if who == 1 { d1.receive() } else { d2.receive() };
        let want = filters.iter().position(|x| x.matches(f)).map(|i| i as u16);
        let got = rx.ok().map(|r| {
            assert_eq!(r.frame, *f);
            r.filter
        });
        assert_eq!(got, want, "CAN{who} frame {f:?}");
        while d1.receive().is_ok() {}
        while d2.receive().is_ok() {}
    }
}

/// Issue 14: CAN2's own start bank is checked against the shared block, and CAN1 cannot
/// move `CAN2SB` under filters a driver installed (CAN2's map would go stale: its banks
/// would change owner or number); once CAN2 gives its banks up the split moves, and
/// CAN2's next plan (for its new range) maps frames to the right filters.
#[test]
fn can2_start_bank_is_checked_and_the_split_does_not_move_under_installed_filters() {
    use twocan_core::{Error, Mode};
    let bus = new_bus();
    let (m1, m2) = BxCanModel::can1_can2();
    bus.borrow_mut().attach("can1", m1.clone());
    bus.borrow_mut().attach("can2", m2.clone());
    let r1 = Clocked::new(m1.clone(), &bus);
    let r2 = Clocked::new(m2, &bus);
    let cfg1 = loopback_config(TxPolicy::Fifo).can2_start_bank(10).unwrap();
    let mut init1 = Can::can1(r1, &cfg1).map_err(|f| f.error).unwrap();

    // A CAN2 configuration naming another start bank: refused before any register
    // write (CAN2 is still asleep, as after reset).
    let cfg2 = loopback_config(TxPolicy::Fifo);
    let refused = Can::can2(r2, m1.clone(), &cfg2.can2_start_bank(14).unwrap()).unwrap_err();
    assert_eq!(refused.error, Error::InvalidArgument);
    assert_eq!(refused.value.mode(), Mode::Sleep);
    assert_eq!(refused.value.bank_range(), (10, 28));
    let (r2, _) = refused.value.release();
    let mut init2 = Can::can2(r2, m1.clone(), &cfg2.can2_start_bank(10).unwrap())
        .map_err(|f| f.error)
        .unwrap();

    let f1 = [Filter::standard(0x100), Filter::extended(0x1_0000)];
    let f2 = [
        Filter::extended(0x2_0000),
        Filter::standard(0x200),
        Filter::masked(
            twocan_core::FrameKind::Data,
            twocan_core::Format::Standard,
            0x7F0,
            0x300,
        ),
    ];
    let p1 = init1.can().plan(&f1, FifoPolicy::Fifo0).unwrap();
    let p2 = init2.can().plan(&f2, FifoPolicy::Balanced).unwrap();
    init1.set_filters(&p1).unwrap();
    init2.set_filters(&p2).unwrap();
    let mut d1: D1 = Driver::new(init1.enable().map_err(|f| f.error).unwrap().into_split());
    let mut d2: D2 = Driver::new(init2.enable().map_err(|f| f.error).unwrap().into_split());
    probe_loopback(&bus, &mut d1, &mut d2, 2, &f2);

    // CAN1 (re)configured with another split while CAN2's banks 10.. are active:
    // refused, upwards and downwards, the split unchanged.
    let mut can1 = d1.release().into_can();
    for moved in [20, 5, 28] {
        let e = can1
            .reconfigure(&cfg1.can2_start_bank(moved).unwrap())
            .unwrap_err();
        assert_eq!(e.error, Error::WrongMode, "CAN2SB -> {moved}");
        can1 = e.value;
        assert_eq!(can1.bank_range(), (0, 10));
    }
    // The same split: allowed while CAN2 runs, and CAN2's filters still map right.
    let init1 = can1.reconfigure(&cfg1).map_err(|f| f.error).unwrap();
    d1 = Driver::new(init1.enable().map_err(|f| f.error).unwrap().into_split());
    probe_loopback(&bus, &mut d1, &mut d2, 2, &f2);
    probe_loopback(&bus, &mut d1, &mut d2, 1, &f1);

    // CAN2 gives its banks up (an empty plan deactivates them); now the split moves.
    let empty = d2.hardware().plan(&[], FifoPolicy::Fifo0).unwrap();
    d2.set_filters(&empty).unwrap();
    let can1 = d1.release().into_can();
    let init1 = can1
        .reconfigure(&cfg1.can2_start_bank(20).unwrap())
        .map_err(|f| f.error)
        .unwrap();
    assert_eq!(init1.can().bank_range(), (0, 20));
    d1 = Driver::new(init1.enable().map_err(|f| f.error).unwrap().into_split());
    assert_eq!(d2.hardware().bank_range(), (20, 28));
    // CAN2 plans for its new banks; its map follows the install.
    let p2 = d2.hardware().plan(&f2, FifoPolicy::Balanced).unwrap();
    d2.set_filters(&p2).unwrap();
    probe_loopback(&bus, &mut d1, &mut d2, 2, &f2);
    probe_loopback(&bus, &mut d1, &mut d2, 1, &f1);

    // CAN1's own active banks count too: a split below them is refused.
    let can1 = d1.release().into_can();
    let e = can1
        .reconfigure(&cfg1.can2_start_bank(0).unwrap())
        .unwrap_err();
    assert_eq!(e.error, Error::WrongMode);
    assert_eq!(e.value.bank_range(), (0, 20));
}
