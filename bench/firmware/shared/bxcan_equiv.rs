//! The **feature-equivalent** service around the `bxcan` crate 0.8: what a careful
//! application author adds to the crate to get what our driver's lean or full variant
//! gives (feature `lean` or `full` of the firmware crate, as for `bxcan_variant.rs`).
//! Included with `#[path]` by `insn-count` (QEMU, RAM stand-in) and
//! `loopback-bxcan-equiv` (STM32F7), so the instruction counts and the flash figures are
//! of the same code.
//!
//! The crate is split once (`Can::split`): the thread owns the transmit half, the RX0
//! interrupt the FIFO 0 half; the rings are `heapless::spsc` queues (lock-free, one
//! producer and one consumer, as ours). What the crate does not expose is read from its
//! register block (`Instance::REGISTERS`, offsets of RM0410 §40.9): `CAN_TSR` for the
//! completions, the FIFO 0 output mailbox's `CAN_RDT0R` for the filter match index
//! (and the time stamp), `CAN_ESR` for the error state.
//!
//! Both variants:
//! - **transmit**: `Tx::transmit`;
//! - **RX0 interrupt**: one loop — the output mailbox's `CAN_RDT0R` (the crate's
//!   `receive` releases the mailbox and returns neither the filter match index nor the
//!   time stamp, so it is read first), `Rx0::receive`, the frame and its `FMI` into the
//!   ring; hardware overruns and ring overflows counted; until `WouldBlock`;
//! - **thread side**: the frame from the ring with the user's filter index, from `FMI`
//!   through a table ([`FILTER_OF_FMI`]).
//!
//! Full adds what our full variant offers:
//! - transmit completions: the transmit half stores a token per mailbox, the TX
//!   interrupt handler reads `CAN_TSR` once and, in **one loop** over the mailboxes whose
//!   `RQCPx` it saw, pushes (token, outcome, time stamp) into a completion ring, then
//!   acknowledges exactly those `RQCPx` with one write-1-to-clear store; the thread
//!   takes completions from the ring;
//! - receive time stamps (`CAN_RDT0R.TIME`, with `CAN_MCR.TTCM` set by the firmware) in
//!   the ring;
//! - traffic statistics: frames sent, failed and received;
//! - the error state: a status (SCE) handler reading `CAN_ESR`.
//!
//! Lean is fire-and-forget: no token, no TX interrupt (the crate needs none to send).

// Each firmware that includes this module uses a part of it.
#![allow(dead_code)]

#[cfg(all(feature = "lean", feature = "full"))]
compile_error!("features `lean` and `full` are exclusive");
#[cfg(not(any(feature = "lean", feature = "full")))]
compile_error!("enable feature `lean` or `full`");

use core::convert::Infallible;
use core::marker::PhantomData;
use core::ptr::read_volatile;
#[cfg(feature = "full")]
use core::ptr::write_volatile;
use core::sync::atomic::{AtomicU32, Ordering};

use bxcan::{Frame, Instance};
use heapless::spsc::{Consumer, Producer, Queue};

/// The variant's name in the bench output.
#[cfg(feature = "lean")]
pub const VARIANT: &str = "lean";
#[cfg(feature = "full")]
pub const VARIANT: &str = "full";

/// Receive ring capacity (frames), as our driver's.
pub const RX: usize = 8;
/// Completion ring capacity, as our full variant's.
pub const DONE: usize = 8;

/// The user's filter index for each FIFO 0 filter match index the firmware's banks
/// produce (bank 0, one 32-bit mask filter: FMI 0 is the user's filter 0).
pub const FILTER_OF_FMI: [u16; 1] = [0];
/// A match index the table does not know.
pub const UNKNOWN_FILTER: u16 = u16::MAX;

// RM0410 §40.9: offsets in the register block and their fields.
const TSR: usize = 0x08;
const ESR: usize = 0x18;
const RDT0R: usize = 0x1B4;
const fn tdtr(mailbox: usize) -> usize {
    0x184 + 0x10 * mailbox
}
const fn rqcp(mailbox: usize) -> u32 {
    1 << (8 * mailbox)
}
const fn txok(mailbox: usize) -> u32 {
    2 << (8 * mailbox)
}
const RQCP_ALL: u32 = rqcp(0) | rqcp(1) | rqcp(2);
const FMI_SHIFT: u32 = 8;
const TIME_SHIFT: u32 = 16;

fn read<I: Instance>(offset: usize) -> u32 {
    // SAFETY: `offset` is one of the registers above, inside the instance's block; a
    // read of these has no side effect.
    unsafe { read_volatile((I::REGISTERS as *const u8).add(offset) as *const u32) }
}

/// A counter written by one context and read by any (no read-modify-write atomics).
pub struct Count(AtomicU32);

impl Count {
    pub const fn new() -> Self {
        Count(AtomicU32::new(0))
    }
    #[inline(always)]
    fn inc(&self) {
        self.0.store(
            self.0.load(Ordering::Relaxed).wrapping_add(1),
            Ordering::Relaxed,
        );
    }
    pub fn get(&self) -> u32 {
        self.0.load(Ordering::Relaxed)
    }
}

/// The counters the service keeps.
pub struct Counts {
    /// FIFO 0 overruns the hardware reported.
    pub overruns: Count,
    /// Frames lost because the ring was full.
    pub ring_overflows: Count,
    /// Frames received (full).
    #[cfg(feature = "full")]
    pub received: Count,
    /// Frames sent (full).
    #[cfg(feature = "full")]
    pub sent: Count,
    /// Frames that failed (full).
    #[cfg(feature = "full")]
    pub failed: Count,
    /// Completions lost because the completion ring was full (full).
    #[cfg(feature = "full")]
    pub completion_overflows: Count,
}

impl Counts {
    pub const fn new() -> Self {
        Counts {
            overruns: Count::new(),
            ring_overflows: Count::new(),
            #[cfg(feature = "full")]
            received: Count::new(),
            #[cfg(feature = "full")]
            sent: Count::new(),
            #[cfg(feature = "full")]
            failed: Count::new(),
            #[cfg(feature = "full")]
            completion_overflows: Count::new(),
        }
    }
}

/// A frame as the RX0 handler stores it.
#[derive(Clone)]
pub struct Received {
    pub frame: Frame,
    pub fmi: u8,
    #[cfg(feature = "full")]
    pub time: u16,
}

/// A frame as the thread side takes it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Taken {
    pub frame: Frame,
    /// The user's filter index.
    pub filter: u16,
    /// `CAN_RDT0R.TIME` (full).
    #[cfg(feature = "full")]
    pub time: u16,
}

/// A transmit completion (full).
#[cfg(feature = "full")]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Completion {
    pub token: u32,
    pub sent: bool,
    pub time: u16,
}

/// The receive ring.
pub type RxRing = Queue<Received, { RX + 1 }>;
/// The completion ring (full).
#[cfg(feature = "full")]
pub type DoneRing = Queue<Completion, { DONE + 1 }>;

/// The token of the frame in each transmit mailbox (full): written by the transmit half,
/// read by the TX interrupt.
#[cfg(feature = "full")]
pub struct Tokens([AtomicU32; 3]);

#[cfg(feature = "full")]
impl Tokens {
    pub const fn new() -> Self {
        Tokens([const { AtomicU32::new(0) }; 3])
    }
}

/// The transmit half (thread).
pub struct Sender<'a, I: Instance> {
    tx: bxcan::Tx<I>,
    #[cfg(feature = "full")]
    tokens: &'a Tokens,
    #[cfg(feature = "full")]
    next: u32,
    _a: PhantomData<&'a ()>,
}

impl<I: Instance> Sender<'_, I> {
    /// Puts `frame` in a mailbox; full: returns its token, which its completion carries.
    #[inline(always)]
    pub fn send(&mut self, frame: &Frame) -> nb::Result<u32, Infallible> {
        let status = self.tx.transmit(frame)?;
        #[cfg(feature = "full")]
        {
            // After the mailbox is loaded (the crate picks it): its completion interrupt
            // comes a whole frame later (tens of µs), long after this store.
            let token = self.next;
            self.next = token.wrapping_add(1);
            self.tokens.0[status.mailbox() as usize].store(token, Ordering::Release);
            Ok(token)
        }
        #[cfg(feature = "lean")]
        {
            let _ = status;
            Ok(0)
        }
    }
}

/// The TX interrupt handler (full).
#[cfg(feature = "full")]
pub struct TxHandler<'a, I: Instance> {
    done: Producer<'a, Completion>,
    tokens: &'a Tokens,
    counts: &'a Counts,
    _i: PhantomData<I>,
}

#[cfg(feature = "full")]
impl<I: Instance> TxHandler<'_, I> {
    /// `CAN_TSR` read once; one loop over the mailboxes whose request completed; those
    /// `RQCPx` acknowledged with one store.
    #[inline(always)]
    pub fn on_interrupt(&mut self) {
        let tsr = read::<I>(TSR);
        let done = tsr & RQCP_ALL;
        if done == 0 {
            return;
        }
        for mailbox in 0..3 {
            if done & rqcp(mailbox) == 0 {
                continue;
            }
            let sent = tsr & txok(mailbox) != 0;
            if sent {
                self.counts.sent.inc();
            } else {
                self.counts.failed.inc();
            }
            let c = Completion {
                token: self.tokens.0[mailbox].load(Ordering::Acquire),
                sent,
                time: (read::<I>(tdtr(mailbox)) >> TIME_SHIFT) as u16,
            };
            if self.done.enqueue(c).is_err() {
                self.counts.completion_overflows.inc();
            }
        }
        // SAFETY: `CAN_TSR`; writing 1 to `RQCPx` acknowledges exactly the completions
        // handled above (write-1-to-clear; the other bits ignore a 0).
        unsafe { write_volatile((I::REGISTERS as *mut u8).add(TSR) as *mut u32, done) };
    }
}

/// The thread side of the completions (full).
#[cfg(feature = "full")]
pub struct Completions<'a> {
    done: Consumer<'a, Completion>,
}

#[cfg(feature = "full")]
impl Completions<'_> {
    #[inline(always)]
    pub fn take(&mut self) -> Option<Completion> {
        self.done.dequeue()
    }
}

/// The RX0 interrupt handler.
pub struct RxHandler<'a, I: Instance> {
    rx0: bxcan::Rx0<I>,
    ring: Producer<'a, Received>,
    counts: &'a Counts,
}

impl<I: Instance> RxHandler<'_, I> {
    /// FIFO 0 into the ring until `WouldBlock`, with each frame's `FMI` (and time).
    #[inline(always)]
    pub fn on_interrupt(&mut self) {
        loop {
            // The output mailbox's FMI and TIME, before `receive` releases it.
            let rdt = read::<I>(RDT0R);
            match self.rx0.receive() {
                Ok(frame) => {
                    #[cfg(feature = "full")]
                    self.counts.received.inc();
                    let r = Received {
                        frame,
                        fmi: (rdt >> FMI_SHIFT) as u8,
                        #[cfg(feature = "full")]
                        time: (rdt >> TIME_SHIFT) as u16,
                    };
                    if self.ring.enqueue(r).is_err() {
                        self.counts.ring_overflows.inc();
                    }
                }
                Err(nb::Error::Other(_)) => self.counts.overruns.inc(),
                Err(nb::Error::WouldBlock) => break,
            }
        }
    }
}

/// The receive half (thread).
pub struct Receiver<'a> {
    ring: Consumer<'a, Received>,
}

impl Receiver<'_> {
    /// The next frame with the user's filter index.
    #[inline(always)]
    pub fn take(&mut self) -> Option<Taken> {
        let r = self.ring.dequeue()?;
        Some(Taken {
            filter: FILTER_OF_FMI
                .get(r.fmi as usize)
                .copied()
                .unwrap_or(UNKNOWN_FILTER),
            frame: r.frame,
            #[cfg(feature = "full")]
            time: r.time,
        })
    }
}

/// The error state the status handler records (full): `CAN_ESR`.
#[cfg(feature = "full")]
pub struct ErrorState(AtomicU32);

#[cfg(feature = "full")]
impl ErrorState {
    pub const fn new() -> Self {
        ErrorState(AtomicU32::new(0))
    }
    /// The status (SCE) interrupt: `CAN_ESR` recorded (error counters, passive, bus-off,
    /// last error code).
    #[inline(never)]
    pub fn on_status<I: Instance>(&self) {
        self.0.store(read::<I>(ESR), Ordering::Relaxed);
    }
    pub fn esr(&self) -> u32 {
        self.0.load(Ordering::Relaxed)
    }
}

/// What `split` hands out.
pub struct Service<'a, I: Instance> {
    pub sender: Sender<'a, I>,
    pub rx_irq: RxHandler<'a, I>,
    pub receiver: Receiver<'a>,
    #[cfg(feature = "full")]
    pub tx_irq: TxHandler<'a, I>,
    #[cfg(feature = "full")]
    pub completions: Completions<'a>,
    /// The counters (any context reads them).
    pub counts: &'a Counts,
}

/// The storage the service lives in (a `static` or a local of `main`).
pub struct Storage {
    pub rx: RxRing,
    #[cfg(feature = "full")]
    pub done: DoneRing,
    #[cfg(feature = "full")]
    pub tokens: Tokens,
    pub counts: Counts,
}

impl Storage {
    pub const fn new() -> Self {
        Storage {
            rx: Queue::new(),
            #[cfg(feature = "full")]
            done: Queue::new(),
            #[cfg(feature = "full")]
            tokens: Tokens::new(),
            counts: Counts::new(),
        }
    }
}

/// Splits the enabled `can` and `storage` into the handles of each context.
pub fn split<I: Instance>(can: bxcan::Can<I>, storage: &mut Storage) -> Service<'_, I> {
    let (tx, rx0, _rx1) = can.split();
    let (rx_prod, rx_cons) = storage.rx.split();
    #[cfg(feature = "full")]
    let (done_prod, done_cons) = storage.done.split();
    let counts = &storage.counts;
    Service {
        sender: Sender {
            tx,
            #[cfg(feature = "full")]
            tokens: &storage.tokens,
            #[cfg(feature = "full")]
            next: 0,
            _a: PhantomData,
        },
        rx_irq: RxHandler {
            rx0,
            ring: rx_prod,
            counts,
        },
        receiver: Receiver { ring: rx_cons },
        #[cfg(feature = "full")]
        tx_irq: TxHandler {
            done: done_prod,
            tokens: &storage.tokens,
            counts,
            _i: PhantomData,
        },
        #[cfg(feature = "full")]
        completions: Completions { done: done_cons },
        counts,
    }
}
