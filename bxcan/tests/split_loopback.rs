//! The split driver (`twocan_core::split`) over the bxCAN model in loop-back mode:
//! direct-path sends, the queue when the mailboxes are full, per-line handlers, tokens
//! and completions in order, priority displacement, abort of queued and loaded frames.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_bxcan::BxCan;
use twocan_core::split::State;
use twocan_core::{AbortRequest, FifoQueue, Frame, PriorityQueue, TxOutcome, TxPolicy};

type Hw = BxCan<Clocked>;

#[test]
fn split_halves_move_frames_with_tokens_and_completions_in_order() {
    let (can, _regs, bus) = can1_with(&loopback_config(TxPolicy::Fifo), &pass_all());
    let state: State<Hw, 16, FifoQueue<8>, 0, 16> = State::new();
    let mut p = state.split(can.into_split()).ok().unwrap();
    let frames: Vec<Frame> = (0..10u16)
        .map(|i| Frame::standard(0x100 + i, &[i as u8; 3]).unwrap())
        .collect();
    let mut tokens = Vec::new();
    for f in &frames {
        tokens.push(p.tx.try_send(f).unwrap());
    }
    // Three went straight to the mailboxes, seven wait in the queue.
    assert_eq!(p.tx.stats().count, 7);
    let mut got = Vec::new();
    let mut done = Vec::new();
    for _ in 0..100 {
        run(&bus, 100);
        p.tx_irq.on_interrupt();
        p.rx0_irq.on_interrupt();
        while let Ok(rx) = p.rx.receive() {
            assert_eq!(rx.filter, 0);
            got.push(rx.frame);
        }
        while let Some(c) = p.tx.take_completion() {
            done.push(c);
        }
    }
    assert_eq!(got, frames, "request order kept (TXFP = 1)");
    let done_tokens: Vec<_> = done.iter().map(|c| c.token).collect();
    assert_eq!(done_tokens, tokens, "one completion per token, in order");
    assert!(done.iter().all(|c| c.outcome == TxOutcome::Sent));
    let t = state.traffic();
    assert_eq!((t.queued, t.sent, t.received), (10, 10, 10));
    assert_eq!(state.tx_stats().peak, 7);
}

#[test]
fn priority_queue_displaces_a_lower_mailbox_and_accounts_exactly() {
    let cfg = loopback_config(TxPolicy::Priority);
    let (can, _regs, bus) = can1_with(&cfg, &pass_all());
    let state: State<Hw, 16, PriorityQueue<8>, 0, 16> = State::new();
    let mut p = state.split(can.into_split()).ok().unwrap();
    let low: Vec<Frame> = (0..3u16)
        .map(|i| Frame::standard(0x700 + i, &[]).unwrap())
        .collect();
    for f in &low {
        p.tx.try_send(f).unwrap();
    }
    let urgent = Frame::standard(0x001, &[1]).unwrap();
    let t_urgent = p.tx.try_send(&urgent).unwrap();
    // The urgent frame asked for the lowest mailbox (0x702) to be aborted.
    let mut order = Vec::new();
    let mut done = Vec::new();
    for _ in 0..200 {
        p.tx_irq.on_interrupt();
        run(&bus, 50);
        p.rx0_irq.on_interrupt();
        while let Ok(rx) = p.rx.receive() {
            order.push(rx.frame.raw_id());
        }
        while let Some(c) = p.tx.take_completion() {
            done.push(c);
        }
    }
    assert_eq!(order.len(), 4, "{order:x?}");
    assert_eq!(done.len(), 4, "one completion per accepted frame: {done:?}");
    assert!(done.iter().all(|c| c.outcome == TxOutcome::Sent));
    assert!(done.iter().any(|c| c.token == t_urgent));
    // The urgent frame left before at least the displaced one.
    let pos = order.iter().position(|&id| id == 0x001).unwrap();
    assert!(pos < 3, "{order:x?}");
}

#[test]
fn abort_removes_queued_frames_and_requests_loaded_ones() {
    let (can, _regs, bus) = can1_with(&loopback_config(TxPolicy::Fifo), &pass_all());
    let state: State<Hw, 16, FifoQueue<8>, 0, 16> = State::new();
    let mut p = state.split(can.into_split()).ok().unwrap();
    let tokens: Vec<_> = (0..5u16)
        .map(|i| {
            p.tx.try_send(&Frame::standard(0x10 + i, &[]).unwrap())
                .unwrap()
        })
        .collect();
    assert_eq!(p.tx.abort(tokens[4]), AbortRequest::Dequeued);
    assert_eq!(p.tx.abort(tokens[2]), AbortRequest::Requested);
    let first = p.tx.take_completion().unwrap();
    assert_eq!(
        (first.token, first.outcome),
        (tokens[4], TxOutcome::Aborted)
    );
    let mut done = vec![first];
    for _ in 0..50 {
        run(&bus, 100);
        p.tx_irq.on_interrupt();
        p.rx0_irq.on_interrupt();
        while p.rx.receive().is_ok() {}
        while let Some(c) = p.tx.take_completion() {
            done.push(c);
        }
    }
    assert_eq!(done.len(), 5, "{done:?}");
    let aborted: Vec<_> = done
        .iter()
        .filter(|c| c.outcome == TxOutcome::Aborted)
        .map(|c| c.token)
        .collect();
    assert!(aborted.contains(&tokens[4]));
    let t = state.traffic();
    assert_eq!(t.sent + t.aborted + t.failed, t.queued);
    assert_eq!(p.tx.abort(tokens[0]), AbortRequest::NotFound);
}

#[test]
fn a_second_split_is_refused() {
    let (can, _regs, _bus) = can1_with(&loopback_config(TxPolicy::Fifo), &pass_all());
    let (can2, _r2, _b2) = can1_with(&loopback_config(TxPolicy::Fifo), &pass_all());
    let state: State<Hw, 4> = State::new();
    let _p = state.split(can.into_split()).ok().unwrap();
    assert!(state.split(can2.into_split()).is_err());
}

#[test]
fn a_queue_of_the_wrong_order_is_refused() {
    let (can, _regs, _bus) = can1_with(&loopback_config(TxPolicy::Priority), &pass_all());
    let state: State<Hw, 4, FifoQueue<4>> = State::new();
    assert!(state.split(can.into_split()).is_err());
}
