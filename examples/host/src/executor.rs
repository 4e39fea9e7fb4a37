//! A small single-threaded executor for the async API on the simulated boards (feature
//! `async` of twocan-core): [`drive`] interleaves servicing the interrupts, polling the
//! woken futures and stepping the bus (the models are `Rc`-based: one thread). The
//! halves it drives come from [`crate::split`].
//!
//! ```
//! use std::pin::pin;
//! use twocan_core::{Filter, Frame};
//! use twocan_host::executor::drive;
//! use twocan_host::split::{split_bx, split_flex, BxState, FlexState};
//! use twocan_host::{BxNode, FlexNode, Harness};
//!
//! let mut h = Harness::new(500_000).unwrap();
//! let teensy = FlexNode::teensy36_can0(&mut h, &[Filter::pass_all()]).unwrap();
//! let stm32 = BxNode::stm32f767_can1(&mut h, &[Filter::pass_all()]).unwrap();
//! let (fs, bs) = (FlexState::new(), BxState::new());
//! let (mut fi, mut ftx, _frx) = split_flex(&fs, teensy).unwrap();
//! let (mut bi, _btx, mut brx) = split_bx(&bs, stm32).unwrap();
//! let frame = Frame::standard(0x123, &[1, 2, 3]).unwrap();
//! let mut send = pin!(async { ftx.send(&frame).await.map(|_| ()) });
//! let mut recv = pin!(async { brx.recv().await.map(|f| assert_eq!(f.frame, frame)) });
//! let until = h.now() + 1_000;
//! let done = drive(&mut h, &mut [&mut fi, &mut bi], &mut [send.as_mut(), recv.as_mut()], until);
//! assert!(done.iter().all(|r| matches!(r, Some(Ok(())))));
//! ```

use std::future::Future;
use std::pin::Pin;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::task::{Context, Wake, Waker};

use twocan_core::Error;

use crate::{Harness, Serviced};

/// A waker that marks its future to be polled again.
#[derive(Default)]
struct Flag(AtomicBool);

impl Wake for Flag {
    fn wake(self: Arc<Self>) {
        self.0.store(true, Ordering::Release);
    }
    fn wake_by_ref(self: &Arc<Self>) {
        self.0.store(true, Ordering::Release);
    }
}

/// A future of [`drive`].
pub type Task<'f> = Pin<&'f mut dyn Future<Output = Result<(), Error>>>;

/// Runs `futures` with the bus: services `nodes`, polls each future that was woken
/// (each once at the start), steps the bus by one event when no future is woken, until
/// every future is ready or the bus time reaches `until`. Returns each future's
/// output, `None` for one still pending at `until` (the caller drops it: the async API
/// is cancel-safe).
pub fn drive(
    h: &mut Harness,
    nodes: &mut [&mut dyn Serviced],
    futures: &mut [Task<'_>],
    until: u64,
) -> Vec<Option<Result<(), Error>>> {
    let flags: Vec<Arc<Flag>> = futures
        .iter()
        .map(|_| Arc::new(Flag(AtomicBool::new(true))))
        .collect();
    let wakers: Vec<Waker> = flags.iter().map(|f| Waker::from(f.clone())).collect();
    let mut out: Vec<Option<Result<(), Error>>> = futures.iter().map(|_| None).collect();
    let mut at_end = false;
    loop {
        for n in nodes.iter_mut() {
            n.service();
        }
        for (i, fut) in futures.iter_mut().enumerate() {
            if out[i].is_none() && flags[i].0.swap(false, Ordering::AcqRel) {
                if let std::task::Poll::Ready(v) =
                    fut.as_mut().poll(&mut Context::from_waker(&wakers[i]))
                {
                    out[i] = Some(v);
                }
            }
        }
        let woken =
            (0..futures.len()).any(|i| out[i].is_none() && flags[i].0.load(Ordering::Acquire));
        if at_end && !woken || out.iter().all(Option::is_some) {
            return out;
        }
        if !woken && h.bus().borrow_mut().step_until(until).is_none() {
            at_end = true;
        }
    }
}
