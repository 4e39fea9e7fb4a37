//! Trait mock tests: the portable driver over the in-memory mock hardware.

use twocan_core::mock::MockHardware;
use twocan_core::{
    AbortRequest, Dispatcher, Driver, Error, ErrorState, Filter, Format, Frame, FrameKind,
    LastErrorCode, MailboxId, MailboxState, Mode, RxFrame, TxOutcome, TxPolicy,
};

type D<const RX: usize> = Driver<MockHardware, RX, 8>;

fn mock(policy: TxPolicy) -> MockHardware {
    MockHardware::new(3).with_policy(policy)
}

fn frame(id: u16, byte: u8) -> Frame {
    Frame::standard(id, &[byte]).unwrap()
}

/// Lets the mock send everything, servicing the driver, until nothing waits (bounded:
/// a test fails, it does not hang).
fn drain<const RX: usize>(driver: &mut D<RX>) -> Vec<Frame> {
    let mut out = Vec::new();
    for _ in 0..100_000 {
        driver.on_interrupt();
        match driver.hardware().complete() {
            Some(f) => out.push(f),
            None => {
                driver.on_interrupt();
                if driver.tx_stats().count == 0 {
                    return out;
                }
            }
        }
    }
    panic!(
        "drain: {} frames still queued after 100,000 services ({} sent)",
        driver.tx_stats().count,
        out.len()
    );
}

#[test]
fn fifo_order_is_kept_through_the_ring() {
    let mut d: D<32> = Driver::new(mock(TxPolicy::Fifo));
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
fn interleaved_fifo_order_and_exact_completions_over_many_frames() {
    let mut d: D<32> = Driver::new(mock(TxPolicy::Fifo));
    let mut sent = Vec::new();
    let mut tokens = Vec::new();
    let mut done = Vec::new();
    let mut next = 0u32;
    let mut rounds = 0u32;
    while next < 1000 || d.tx_stats().count > 0 || sent.len() < 1000 {
        rounds += 1;
        assert!(
            rounds < 100_000,
            "waited 100,000 rounds for 1000 frames sent: {} queued, {} sent",
            next,
            sent.len()
        );
        while next < 1000 {
            let id = ((next * 7919) % 0x7FF) as u16;
            match d.try_send(&Frame::standard(id, &next.to_le_bytes()).unwrap()) {
                Ok(t) => {
                    tokens.push(t);
                    next += 1
                }
                Err(nb::Error::WouldBlock) => break,
                Err(e) => panic!("{e:?}"),
            }
        }
        if let Some(f) = d.hardware().complete() {
            sent.push(f.data_u32(0).unwrap());
            d.hardware().clear_sent();
        }
        d.on_interrupt();
        done.extend(std::iter::from_fn(|| d.take_completion()).map(|c| c.token));
    }
    d.on_interrupt();
    done.extend(std::iter::from_fn(|| d.take_completion()).map(|c| c.token));
    assert_eq!(sent, (0..1000).collect::<Vec<_>>());
    assert_eq!(done, tokens, "one completion per token, in order");
}

#[test]
fn priority_policy_has_no_inversion() {
    let mut d: D<32> = Driver::new(mock(TxPolicy::Priority));
    for i in 0..3 {
        d.try_send(&frame(0x600 + i, i as u8)).unwrap();
    }
    d.try_send(&frame(0x500, 10)).unwrap();
    d.try_send(&frame(0x010, 11)).unwrap();
    let sent = drain(&mut d);
    let ids: Vec<u32> = sent.iter().map(|f| f.raw_id()).collect();
    assert_eq!(ids, vec![0x010, 0x500, 0x600, 0x601, 0x602]);
    let t = d.traffic();
    assert_eq!((t.queued, t.sent, t.aborted), (5, 5, 0));
}

#[test]
fn overflow_is_counted_exactly_and_refused_frames_are_not_accepted() {
    let mut d: D<32> = Driver::new(mock(TxPolicy::Fifo));
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
    assert_eq!(d.next_token().0, 11, "refused frames took no token");
}

#[test]
fn receive_ring_overflow_is_counted() {
    let mut d: D<4> = Driver::new(mock(TxPolicy::Fifo).with_loopback(true));
    for i in 0..6u8 {
        d.try_send(&frame(0x10, i)).unwrap();
        d.hardware().complete();
        d.on_interrupt();
    }
    let rx = d.rx_stats();
    assert_eq!((rx.size, rx.count, rx.peak, rx.overflows), (4, 4, 5, 2));
    assert_eq!(d.traffic().rx_ring_overflows, 2);
    assert_eq!(d.traffic().received, 6);
    assert_eq!(d.available(), 4);
    let first: Vec<u8> = std::iter::from_fn(|| d.receive().ok())
        .map(|r| r.frame.data()[0])
        .collect();
    assert_eq!(first, vec![0, 1, 2, 3]);
    d.reset_peaks();
    assert_eq!(d.rx_stats().peak, 0);
}

#[test]
fn hardware_overrun_reaches_the_statistics() {
    let mut d: D<8> = Driver::new(mock(TxPolicy::Fifo));
    for i in 0..5 {
        d.hardware().deliver(frame(1, i));
    }
    d.on_interrupt();
    assert_eq!(d.error_stats().hardware_overruns, 1, "one occurrence");
    assert_eq!(d.rx_stats().count, 3);
}

#[test]
fn nothing_received_is_would_block() {
    let mut d: D<8> = Driver::new(mock(TxPolicy::Fifo));
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
    let filters = [
        Filter::standard(0x10),
        Filter::masked(FrameKind::Data, Format::Standard, 0x700, 0x200),
        Filter::kind_format(FrameKind::Remote, Format::Any),
    ];
    let mut d: D<8> = Driver::new(mock(TxPolicy::Fifo).with_filters(&filters));
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
    d.hardware().deliver(frame(0x10, 0));
    d.hardware().deliver(frame(0x234, 0)); // filter 1: no call-back
    d.hardware().deliver(Frame::remote(0x55, false, 0).unwrap());
    d.hardware().deliver(frame(0x555, 0)); // matches nothing: dropped by hardware
    d.on_interrupt();
    assert_eq!(d.rx_stats().count, 3);
    while d.dispatch(&mut table, &mut seen) {}
    assert_eq!((seen.f0, seen.remote), (1, 1));
    assert_eq!(seen.hooks, vec![0, 1, 2]);
    assert_eq!(table.unhandled(), 1);
    assert_eq!(table.handled(), 2);
}

#[test]
fn error_state_transitions_are_delivered_in_order() {
    let mut d: D<8> = Driver::new(mock(TxPolicy::Fifo));
    assert_eq!(d.state(), ErrorState::Active);
    d.hardware()
        .set_status(ErrorState::Passive, 128, 0, LastErrorCode::Acknowledge);
    d.on_interrupt();
    d.hardware()
        .set_status(ErrorState::BusOff, 256, 0, LastErrorCode::BitDominant);
    d.on_interrupt();
    let c1 = d.take_state_change().unwrap();
    let c2 = d.take_state_change().unwrap();
    assert_eq!((c1.state, c1.counters.tec), (ErrorState::Passive, 128));
    assert_eq!((c2.state, c2.counters.tec), (ErrorState::BusOff, 256));
    assert_eq!(d.take_state_change(), None);
    assert_eq!(d.error_stats().acknowledge, 1);
    assert_eq!(d.error_stats().bit, 1);
    assert_eq!(d.state(), ErrorState::BusOff);
    assert_eq!(d.counters().tec, 256);
    assert_eq!(d.error_stats().bus_off, 1);
    assert_eq!(
        d.try_send(&frame(1, 1)),
        Err(nb::Error::Other(Error::BusOff))
    );
    d.hardware()
        .set_status(ErrorState::Active, 0, 0, LastErrorCode::None);
    assert_eq!(d.state(), ErrorState::Active);
    assert_eq!(d.traffic().state_changes, 3);
    d.set_mode(Mode::Stopped).unwrap();
    assert_eq!(
        d.try_send(&frame(1, 1)),
        Err(nb::Error::Other(Error::WrongMode))
    );
    assert_eq!(d.traffic().queued, 0, "an error means not accepted");
}

#[test]
fn try_send_errors_mean_not_accepted_even_with_a_queue() {
    // Regression: an error used to be returned for a frame that was queued.
    let mut d: D<8> = Driver::new(mock(TxPolicy::Fifo));
    for i in 0..5 {
        d.try_send(&frame(0x100, i)).unwrap();
    }
    d.set_mode(Mode::Stopped).unwrap();
    let before = d.tx_stats().count;
    assert_eq!(
        d.try_send(&frame(0x100, 9)),
        Err(nb::Error::Other(Error::WrongMode))
    );
    assert_eq!(d.tx_stats().count, before, "not queued");
    assert_eq!(d.traffic().queued, 5);
}

#[test]
fn abort_all_drops_queue_and_mailboxes() {
    let mut d: D<8> = Driver::new(mock(TxPolicy::Fifo));
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
    let done: Vec<_> = std::iter::from_fn(|| d.take_completion()).collect();
    assert_eq!(done.len(), 5);
    assert!(done.iter().all(|c| c.outcome == TxOutcome::Aborted));
}

#[test]
fn abort_by_token_queued_or_loaded() {
    let mut d: D<8> = Driver::new(mock(TxPolicy::Fifo));
    let t: Vec<_> = (0..5)
        .map(|i| d.try_send(&frame(0x100, i)).unwrap())
        .collect();
    assert_eq!(d.abort(t[4]), AbortRequest::Dequeued);
    assert_eq!(d.abort(t[1]), AbortRequest::Requested);
    assert_eq!(d.abort(t[4]), AbortRequest::NotFound);
    let sent = drain(&mut d);
    assert_eq!(
        sent.iter().map(|f| f.data()[0]).collect::<Vec<_>>(),
        [0, 2, 3]
    );
    let done: Vec<_> = std::iter::from_fn(|| d.take_completion()).collect();
    assert_eq!(done.len(), 5);
    let t_ = d.traffic();
    assert_eq!((t_.sent, t_.aborted), (3, 2));
}

#[test]
fn blocking_can_round_trip() {
    use embedded_can::blocking::Can as _;
    let mut d: D<8> = Driver::new(mock(TxPolicy::Fifo).with_loopback(true));
    d.transmit(&frame(0x42, 7)).unwrap();
    d.hardware().complete();
    let got = embedded_can::blocking::Can::receive(&mut d).unwrap();
    assert_eq!(got, frame(0x42, 7));
}

#[test]
fn blocking_transmit_returns_the_error_when_stopped_with_a_full_queue() {
    // Regression: it used to spin for ever, swallowing WrongMode.
    use embedded_can::blocking::Can as _;
    let mut d: D<8> = Driver::new(mock(TxPolicy::Fifo));
    for i in 0..11 {
        d.try_send(&frame(0x100, i)).unwrap();
    }
    d.set_mode(Mode::Stopped).unwrap();
    assert_eq!(d.transmit(&frame(0x100, 99)), Err(Error::WrongMode));
    assert_eq!(
        embedded_can::blocking::Can::receive(&mut d),
        Err(Error::WrongMode)
    );
}

#[test]
fn try_send_sees_a_recovery_that_raised_no_interrupt() {
    let mut d: D<8> = Driver::new(mock(TxPolicy::Fifo));
    d.hardware()
        .set_status(ErrorState::BusOff, 256, 0, LastErrorCode::BitDominant);
    d.on_interrupt();
    assert_eq!(
        d.try_send(&frame(1, 1)),
        Err(nb::Error::Other(Error::BusOff))
    );
    // The controller recovers by itself; no interrupt is serviced.
    d.hardware()
        .set_status(ErrorState::Active, 0, 0, LastErrorCode::None);
    assert!(d.try_send(&frame(1, 1)).is_ok());
}

#[test]
fn polling_try_send_progresses_without_interrupts() {
    let mut d: D<8> = Driver::new(mock(TxPolicy::Fifo));
    for i in 0..11 {
        d.try_send(&frame(0x100, i)).unwrap();
    }
    assert_eq!(d.try_send(&frame(0x100, 11)), Err(nb::Error::WouldBlock));
    // The bus sends one mailbox; nobody runs the interrupt handler.
    d.hardware().complete();
    assert!(d.try_send(&frame(0x100, 11)).is_ok());
    assert_eq!(d.tx_stats().overflows, 1);
}

#[test]
fn frames_are_sixteen_bytes() {
    assert_eq!(core::mem::size_of::<Frame>(), 16);
    assert_eq!(Frame::default(), Frame::standard(0, &[]).unwrap());
}
