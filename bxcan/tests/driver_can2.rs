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
