//! Trait mock tests: the generic driver over the in-memory mock controller.

use twocan_core::mock::{MockController, MockFilters};
use twocan_core::{
    Dispatcher, Driver, Error, ErrorState, Filter, Format, Frame, FrameKind, LastErrorCode,
    MailboxId, MailboxState, Mode, RxFrame, TxPolicy,
};

type Mock = MockController<3, 3>;

fn frame(id: u16, byte: u8) -> Frame {
    Frame::standard(id, &[byte]).unwrap()
}

fn drain(driver: &mut Driver<Mock, 32, 8>) -> Vec<Frame> {
    let mut out = Vec::new();
    loop {
        driver.on_interrupt();
        match driver.controller_mut().complete() {
            Some(f) => out.push(f),
            None => {
                driver.on_interrupt();
                if driver.tx_stats().count == 0 {
                    return out;
                }
            }
        }
    }
}

#[test]
fn fifo_order_is_kept_through_the_ring() {
    let mut d: Driver<Mock, 32, 8> = Driver::new(Mock::new(TxPolicy::Fifo));
    // Descending identifiers: a priority-ordered path would reverse them.
    for i in 0..8u8 {
        d.try_send(&frame(0x700 - i as u16, i)).unwrap();
    }
    // 3 in mailboxes, 5 in the ring
    assert_eq!(d.tx_stats().count, 5);
    let sent = drain(&mut d);
    let bytes: Vec<u8> = sent.iter().map(|f| f.data()[0]).collect();
    assert_eq!(bytes, (0..8).collect::<Vec<_>>());
    assert_eq!(d.traffic().sent, 8);
}

#[test]
fn interleaved_fifo_order_over_many_frames() {
    let mut d: Driver<Mock, 32, 8> = Driver::new(Mock::new(TxPolicy::Fifo));
    let mut sent = Vec::new();
    let mut next = 0u32;
    while next < 1000 || d.tx_stats().count > 0 || sent.len() < 1000 {
        while next < 1000 {
            let id = ((next * 7919) % 0x7FF) as u16;
            match d.try_send(&Frame::standard(id, &next.to_le_bytes()).unwrap()) {
                Ok(()) => next += 1,
                Err(nb::Error::WouldBlock) => break,
                Err(e) => panic!("{e:?}"),
            }
        }
        if let Some(f) = d.controller_mut().complete() {
            sent.push(f.data_u32(0).unwrap());
            let c = d.controller_mut();
            if c.sent.is_full() {
                c.sent.clear();
            }
        }
        d.on_interrupt();
    }
    assert_eq!(sent, (0..1000).collect::<Vec<_>>());
}

#[test]
fn priority_policy_has_no_inversion() {
    let mut d: Driver<Mock, 32, 8> = Driver::new(Mock::new(TxPolicy::Priority));
    for i in 0..3 {
        d.try_send(&frame(0x600 + i, i as u8)).unwrap();
    }
    d.try_send(&frame(0x500, 10)).unwrap();
    d.try_send(&frame(0x010, 11)).unwrap();
    let sent = drain(&mut d);
    let ids: Vec<u32> = sent.iter().map(|f| f.raw_id()).collect();
    assert_eq!(ids, vec![0x010, 0x500, 0x600, 0x601, 0x602]);
}

#[test]
fn overflow_is_counted_exactly() {
    let mut d: Driver<Mock, 32, 8> = Driver::new(Mock::new(TxPolicy::Fifo));
    // Fill the 3 mailboxes and the ring of 8 without letting anything leave.
    for i in 0..11 {
        d.try_send(&frame(0x100, i)).unwrap();
    }
    let stats = d.tx_stats();
    assert_eq!(
        (stats.size, stats.count, stats.peak, stats.overflows),
        (8, 8, 8, 0)
    );
    let mut rejected = 0;
    for i in 0..3 {
        if let Err(nb::Error::WouldBlock) = d.try_send(&frame(0x200, i)) {
            rejected += 1;
        }
    }
    assert_eq!(rejected, 3);
    let stats = d.tx_stats();
    assert_eq!((stats.count, stats.peak, stats.overflows), (8, 9, 3));
    assert_eq!(d.traffic().queued, 11);
}

#[test]
fn receive_ring_overflow_is_counted() {
    let mut c = Mock::new(TxPolicy::Fifo);
    c.loopback = true;
    let mut d: Driver<Mock, 4, 8> = Driver::new(c);
    for i in 0..6u8 {
        d.try_send(&frame(0x10, i)).unwrap();
        d.controller_mut().complete();
        d.on_interrupt();
    }
    let rx = d.rx_stats();
    assert_eq!((rx.size, rx.count, rx.peak, rx.overflows), (4, 4, 5, 2));
    assert_eq!(d.traffic().rx_ring_overflows, 2);
    assert_eq!(d.traffic().received, 6);
    let first: Vec<u8> = std::iter::from_fn(|| d.receive().ok())
        .map(|r| r.frame.data()[0])
        .collect();
    assert_eq!(first, vec![0, 1, 2, 3]);
}

#[test]
fn hardware_overrun_reaches_the_statistics() {
    let mut d: Driver<Mock, 8, 8> = Driver::new(Mock::new(TxPolicy::Fifo));
    for i in 0..5 {
        d.controller_mut().deliver(frame(1, i));
    }
    d.on_interrupt();
    assert_eq!(d.error_stats().hardware_overruns, 2);
    assert_eq!(d.rx_stats().count, 3);
}

#[test]
fn nothing_received_is_would_block() {
    let mut d: Driver<Mock, 8, 8> = Driver::new(Mock::new(TxPolicy::Fifo));
    assert_eq!(d.receive(), Err(nb::Error::WouldBlock));
    assert_eq!(
        embedded_can::nb::Can::receive(&mut d),
        Err(nb::Error::WouldBlock)
    );
    let mut table: Dispatcher<u32, 4> = Dispatcher::new();
    assert!(!d.dispatch(&mut table, &mut 0));
}

#[test]
fn dispatch_counts_frames_without_call_back() {
    let mut c = Mock::new(TxPolicy::Fifo);
    let filters: MockFilters = [
        Filter::standard(0x10),
        Filter::masked(FrameKind::Data, Format::Standard, 0x700, 0x200),
        Filter::kind_format(FrameKind::Remote, Format::Any),
    ]
    .into_iter()
    .collect();
    c.install_filters_for_test(&filters);
    let mut d: Driver<Mock, 8, 8> = Driver::new(c);
    struct Seen {
        f0: u32,
        remote: u32,
        hooks: Vec<u16>,
    }
    let mut table: Dispatcher<Seen, 3> = Dispatcher::new();
    table.set(0, |s, _| s.f0 += 1).unwrap();
    table
        .set(2, |s, rx: &RxFrame| {
            assert!(rx.frame.is_remote());
            s.remote += 1
        })
        .unwrap();
    table.set_match_hook(Some(|s: &mut Seen, i| s.hooks.push(i)));
    let mut seen = Seen {
        f0: 0,
        remote: 0,
        hooks: vec![],
    };
    d.controller_mut().deliver(frame(0x10, 0));
    d.controller_mut().deliver(frame(0x234, 0)); // filter 1: no call-back
    d.controller_mut()
        .deliver(Frame::remote(0x55, false, 0).unwrap());
    d.controller_mut().deliver(frame(0x555, 0)); // matches nothing: dropped by hardware
    d.on_interrupt();
    assert_eq!(d.rx_stats().count, 3);
    while d.dispatch(&mut table, &mut seen) {}
    assert_eq!((seen.f0, seen.remote), (1, 1));
    assert_eq!(seen.hooks, vec![0, 1, 2]);
    assert_eq!(table.unhandled(), 1);
    assert_eq!(table.handled(), 2);
}

#[test]
fn error_state_transitions_are_tracked() {
    let mut d: Driver<Mock, 8, 8> = Driver::new(Mock::new(TxPolicy::Fifo));
    assert_eq!(d.state(), ErrorState::Active);
    d.controller_mut()
        .set_status(ErrorState::Passive, 128, 0, LastErrorCode::Acknowledge);
    d.on_interrupt();
    assert_eq!(d.take_state_change(), Some(ErrorState::Passive));
    assert_eq!(d.take_state_change(), None);
    assert_eq!(d.error_stats().acknowledge, 1);
    d.controller_mut()
        .set_status(ErrorState::BusOff, 256, 0, LastErrorCode::BitDominant);
    d.on_interrupt();
    assert_eq!(d.state(), ErrorState::BusOff);
    assert_eq!(d.counters().tec, 256);
    assert_eq!(d.error_stats().bus_off, 1);
    assert_eq!(
        d.try_send(&frame(1, 1)),
        Err(nb::Error::Other(Error::BusOff))
    );
    d.recover().unwrap();
    assert_eq!(d.state(), ErrorState::Active);
    assert_eq!(d.traffic().state_changes, 3);
    d.set_mode(Mode::Stopped).unwrap();
    assert_eq!(d.state(), ErrorState::Stopped);
    assert_eq!(
        d.try_send(&frame(1, 1)),
        Err(nb::Error::Other(Error::WrongMode))
    );
}

#[test]
fn abort_all_drops_queue_and_mailboxes() {
    let mut d: Driver<Mock, 8, 8> = Driver::new(Mock::new(TxPolicy::Fifo));
    for i in 0..5 {
        d.try_send(&frame(0x100, i)).unwrap();
    }
    assert_eq!(d.mailbox_state(MailboxId(0)), MailboxState::Scheduled);
    assert_eq!(d.mailbox_state(MailboxId(1)), MailboxState::Pending);
    assert_eq!(d.abort_all(), 2);
    d.on_interrupt();
    assert_eq!(d.traffic().aborted, 5);
    assert_eq!(d.mailbox_state(MailboxId(0)), MailboxState::Empty);
    assert_eq!(d.mailbox_state(MailboxId(9)), MailboxState::Empty);
}

#[test]
fn blocking_can_round_trip() {
    use embedded_can::blocking::Can as _;
    let mut c = Mock::new(TxPolicy::Fifo);
    c.loopback = true;
    let mut d: Driver<Mock, 8, 8> = Driver::new(c);
    d.transmit(&frame(0x42, 7)).unwrap();
    d.controller_mut().complete();
    let got = embedded_can::blocking::Can::receive(&mut d).unwrap();
    assert_eq!(got, frame(0x42, 7));
}

#[test]
fn try_send_sees_a_recovery_that_raised_no_interrupt() {
    let mut d: Driver<Mock, 8, 8> = Driver::new(Mock::new(TxPolicy::Fifo));
    d.controller_mut()
        .set_status(ErrorState::BusOff, 256, 0, LastErrorCode::BitDominant);
    d.on_interrupt();
    assert_eq!(
        d.try_send(&frame(1, 1)),
        Err(nb::Error::Other(Error::BusOff))
    );
    // The controller recovers by itself; no interrupt is serviced.
    d.controller_mut()
        .set_status(ErrorState::Active, 0, 0, LastErrorCode::None);
    assert_eq!(d.try_send(&frame(1, 1)), Ok(()));
}

#[test]
fn polling_try_send_progresses_without_interrupts() {
    let mut d: Driver<Mock, 8, 8> = Driver::new(Mock::new(TxPolicy::Fifo));
    for i in 0..11 {
        d.try_send(&frame(0x100, i)).unwrap();
    }
    assert_eq!(d.try_send(&frame(0x100, 11)), Err(nb::Error::WouldBlock));
    // The bus sends one mailbox; nobody runs the interrupt handler.
    d.controller_mut().complete();
    assert_eq!(d.try_send(&frame(0x100, 11)), Ok(()));
    assert_eq!(d.tx_stats().overflows, 1);
}
