//! A **hand-written** register-level FlexCAN service for a Teensy 3.x (there is no crate
//! peer): what a careful embedded author writes from the Kinetis K66 reference manual's
//! FlexCAN chapter (K66P144M180SF5RM, "FlexCAN", sections "Memory map/register
//! definition", "Functional description" — transmit process, Rx FIFO, "FlexCAN
//! initialization sequence", "Modes of operation"). Its own register constants; no code
//! of our driver (our `twocan-core` only solves the `CTRL1` bit timing at compile time,
//! a `const`). Included with `#[path]` by `insn-count-flexcan` (QEMU, RAM stand-in) and
//! `loopback-flexcan-hand` (Teensy 3.6); the feature `lean` or `full` of the firmware
//! crate selects what it offers, as for our driver (`flexcan_variant.rs`).
//!
//! The service, both variants:
//! - configuration: module disabled to select the oscillator clock, enabled, soft
//!   reset, freeze; Rx FIFO on with 8 ID filter elements (format A), individual masks,
//!   abort enabled, self reception (loop-back), loop-back mode, the bit timing; MB8–14
//!   inactive, MB15 the transmit mailbox; flags cleared; interrupts of the Rx FIFO
//!   (frames available, overflow) and, full, of MB15; leave freeze and wait until the
//!   module is ready and synchronised. Every wait is bounded;
//! - **transmit** (thread): one frame into MB15 as the manual's "transmit process" says
//!   — not while it is still sending; its flag cleared (lean: nobody else does), the
//!   identifier and data words, then the control word with code `DATA`;
//! - **Rx FIFO interrupt**: one loop — `IFLAG1` read; overflow counted and the
//!   warning/overflow flags acknowledged; while `BUF5I`: the output's control/status,
//!   identifier and data words and `RXFIR.IDHIT` into a ring (`heapless::spsc`,
//!   lock-free), the FIFO popped (write 1 to `BUF5I`); a full ring counted;
//! - **thread side**: the frame decoded from the ring with the user's filter index, from
//!   `IDHIT` through a table ([`FILTER_OF_HIT`]).
//!
//! Full adds what our full variant offers:
//! - completions: a token per frame, MB15's interrupt pushing (token, outcome, time
//!   stamp) into a completion ring and acknowledging the flag; the thread takes them;
//!   transmit waits for the completion to be taken over (flag clear);
//! - receive time stamps (the output's `TIME STAMP`);
//! - traffic statistics: frames sent, received.

// Each firmware that includes this module uses a part of it.
#![allow(dead_code)]

#[cfg(all(feature = "lean", feature = "full"))]
compile_error!("features `lean` and `full` are exclusive");
#[cfg(not(any(feature = "lean", feature = "full")))]
compile_error!("enable feature `lean` or `full`");

use core::marker::PhantomData;
use core::sync::atomic::{AtomicU32, Ordering};

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

/// The user's filter index for each `RXFIR.IDHIT` (filter element) the configuration
/// uses: element 0 is the user's filter 0 (the others are copies of it and never hit).
pub const FILTER_OF_HIT: [u16; 8] = [0; 8];
/// A hit the table does not know.
pub const UNKNOWN_FILTER: u16 = u16::MAX;

/// `CTRL1`'s bit timing fields for 500 kbit/s from the 16 MHz oscillator clock (solved
/// at compile time).
pub const CTRL1_TIMING: u32 = match twocan_core::timing::solve_cia(
    16_000_000,
    500_000,
    &twocan_core::timing::Limits::FLEXCAN,
) {
    Ok(t) => match t.flexcan_ctrl1() {
        Ok(v) => v,
        Err(_) => panic!("timing does not fit CTRL1"),
    },
    Err(_) => panic!("no bit timing for 500 kbit/s from 16 MHz"),
};

/// Bound of every acknowledge wait (register reads).
pub const POLLS: u32 = 100_000;

// K66 RM, FlexCAN memory map: offsets from the module base.
pub const MCR: usize = 0x00;
pub const CTRL1: usize = 0x04;
pub const ESR1: usize = 0x20;
pub const IMASK1: usize = 0x28;
pub const IFLAG1: usize = 0x30;
pub const CTRL2: usize = 0x34;
pub const RXFIR: usize = 0x4C;
pub const fn mb(n: usize) -> usize {
    0x80 + 16 * n
}
/// The Rx FIFO ID filter table (MB6–7 with `RFFN` = 0).
pub const ID_TABLE: usize = 0xE0;
pub const fn rximr(n: usize) -> usize {
    0x880 + 4 * n
}

// MCR bits.
const MDIS: u32 = 1 << 31;
const FRZ: u32 = 1 << 30;
const RFEN: u32 = 1 << 29;
const HALT: u32 = 1 << 28;
const NOTRDY: u32 = 1 << 27;
const SOFTRST: u32 = 1 << 25;
const FRZACK: u32 = 1 << 24;
const SUPV: u32 = 1 << 23;
const LPMACK: u32 = 1 << 20;
const IRMQ: u32 = 1 << 16;
const AEN: u32 = 1 << 12;
const MAXMB_15: u32 = 15;
// CTRL1, CTRL2, ESR1 bits.
const CLKSRC: u32 = 1 << 13;
const LPB: u32 = 1 << 12;
const RFFN_MASK: u32 = 0xF << 24;
const SYNCH: u32 = 1 << 18;
// IFLAG1 / IMASK1 bits.
const BUF5I: u32 = 1 << 5;
const BUF6I: u32 = 1 << 6;
const BUF7I: u32 = 1 << 7;
/// The transmit mailbox.
pub const TX_MB: usize = 15;
const TX_FLAG: u32 = 1 << TX_MB;
// Message buffer control/status word.
const CODE_SHIFT: u32 = 24;
const CODE_MASK: u32 = 0xF << CODE_SHIFT;
const CODE_RX_INACTIVE: u32 = 0;
const CODE_TX_INACTIVE: u32 = 0b1000 << CODE_SHIFT;
const CODE_TX_ABORT: u32 = 0b1001 << CODE_SHIFT;
const CODE_TX_DATA: u32 = 0b1100 << CODE_SHIFT;
const SRR: u32 = 1 << 22;
const IDE: u32 = 1 << 21;
const RTR: u32 = 1 << 20;
const DLC_SHIFT: u32 = 16;
const STD_SHIFT: u32 = 18;
const EXT_MASK: u32 = 0x1FFF_FFFF;

/// Register access to one FlexCAN module (the firmware gives the module, or the RAM
/// stand-in).
pub trait Bus {
    fn read(offset: usize) -> u32;
    fn write(offset: usize, value: u32);
    /// Acknowledges `bits` of a write-1-to-clear register (`IFLAG1`, `ESR1`).
    fn w1c(offset: usize, bits: u32);
}

/// A frame as the application sends and receives it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CanFrame {
    /// Standard (11-bit) or extended (29-bit) identifier.
    pub id: u32,
    pub extended: bool,
    pub remote: bool,
    /// The DLC as sent (9–15 mean 8 bytes).
    pub dlc: u8,
    pub data: [u8; 8],
}

/// A counter written by one context and read by any.
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
    /// Rx FIFO overflows the module reported (`BUF7I`).
    pub overruns: Count,
    /// Frames lost because the ring was full.
    pub ring_overflows: Count,
    #[cfg(feature = "full")]
    pub received: Count,
    #[cfg(feature = "full")]
    pub sent: Count,
    #[cfg(feature = "full")]
    pub aborted: Count,
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
            aborted: Count::new(),
            #[cfg(feature = "full")]
            completion_overflows: Count::new(),
        }
    }
}

/// The Rx FIFO output as the interrupt stores it.
#[derive(Clone, Copy)]
pub struct RawRx {
    cs: u32,
    id: u32,
    word0: u32,
    word1: u32,
    hit: u16,
}

/// A frame as the thread side takes it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Received {
    pub frame: CanFrame,
    /// The user's filter index.
    pub filter: u16,
    /// The frame's `TIME STAMP` (full).
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

/// Why the configuration stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timeout;

fn wait<B: Bus>(offset: usize, bit: u32, set: bool) -> Result<(), Timeout> {
    for _ in 0..POLLS {
        if (B::read(offset) & bit != 0) == set {
            return Ok(());
        }
    }
    Err(Timeout)
}

/// The clock gates of PORTA and FlexCAN0 and the pin mux of Teensy 3.6 pins 3 (PTA12,
/// CAN0_TX) and 4 (PTA13, CAN0_RX), ALT2, the Rx pin pulled up (K66 RM, SIM
/// `SCGC5`/`SCGC6`; "Signal Multiplexing"; PORT `PCRn`).
pub fn system_teensy36() {
    const SIM_SCGC5: usize = 0x4004_8038;
    const SIM_SCGC6: usize = 0x4004_803C;
    const PORTA_PCR12: usize = 0x4004_9030;
    const PORTA_PCR13: usize = 0x4004_9034;
    const SCGC5_PORTA: u32 = 1 << 9;
    const SCGC6_FLEXCAN0: u32 = 1 << 4;
    const MUX_ALT2: u32 = 2 << 8;
    const PE_PS: u32 = 0b11;
    // SAFETY: SIM and PORTA registers of the K66 (read-modify-write of the gates, the
    // two pins' PCRs), touched by nothing else in the firmware.
    unsafe {
        let rmw = |a: usize, bits: u32| {
            let p = a as *mut u32;
            p.write_volatile(p.read_volatile() | bits);
        };
        rmw(SIM_SCGC5, SCGC5_PORTA);
        rmw(SIM_SCGC6, SCGC6_FLEXCAN0);
        (PORTA_PCR12 as *mut u32).write_volatile(MUX_ALT2);
        (PORTA_PCR13 as *mut u32).write_volatile(MUX_ALT2 | PE_PS);
    }
}

/// The "FlexCAN initialization sequence" (module docs), loop-back at 500 kbit/s.
pub fn configure<B: Bus>() -> Result<(), Timeout> {
    // The clock source can only change while the module is disabled.
    B::write(MCR, B::read(MCR) | MDIS);
    wait::<B>(MCR, LPMACK, true)?;
    B::write(CTRL1, B::read(CTRL1) & !CLKSRC);
    B::write(MCR, B::read(MCR) & !MDIS);
    wait::<B>(MCR, LPMACK, false)?;
    B::write(MCR, B::read(MCR) | SOFTRST);
    wait::<B>(MCR, SOFTRST, false)?;
    B::write(MCR, B::read(MCR) | FRZ | HALT);
    wait::<B>(MCR, FRZACK, true)?;

    // In freeze: Rx FIFO, individual masks, abort, 16 MBs (format A, self reception).
    let supv = B::read(MCR) & SUPV;
    B::write(MCR, FRZ | HALT | RFEN | IRMQ | AEN | MAXMB_15 | supv);
    B::write(CTRL1, CTRL1_TIMING | LPB);
    B::write(CTRL2, B::read(CTRL2) & !RFFN_MASK);
    // 8 filter elements, each accepting every frame (mask 0: no bit compared).
    for n in 0..8 {
        B::write(ID_TABLE + 4 * n, 0);
        B::write(rximr(n), 0);
    }
    for n in 8..TX_MB {
        B::write(mb(n), CODE_RX_INACTIVE);
    }
    B::write(mb(TX_MB), CODE_TX_INACTIVE);
    B::w1c(IFLAG1, u32::MAX);
    #[cfg(feature = "lean")]
    B::write(IMASK1, BUF5I | BUF7I);
    #[cfg(feature = "full")]
    B::write(IMASK1, BUF5I | BUF7I | TX_FLAG);

    B::write(MCR, B::read(MCR) & !(FRZ | HALT));
    wait::<B>(MCR, FRZACK, false)?;
    wait::<B>(MCR, NOTRDY, false)?;
    wait::<B>(ESR1, SYNCH, true)
}

/// The transmit half (thread).
pub struct Sender<'a, B: Bus> {
    #[cfg(feature = "full")]
    token: &'a AtomicU32,
    #[cfg(feature = "full")]
    next: u32,
    _b: PhantomData<(&'a (), B)>,
}

/// MB15 still busy (lean: sending; full: sending or its completion not handled yet).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Busy;

impl<B: Bus> Sender<'_, B> {
    /// Loads MB15 with `f` (K66 RM "Transmit process"); full: returns the frame's token.
    #[inline(always)]
    pub fn send(&mut self, f: &CanFrame) -> Result<u32, Busy> {
        if B::read(mb(TX_MB)) & CODE_MASK == CODE_TX_DATA {
            return Err(Busy);
        }
        #[cfg(feature = "lean")]
        {
            // Step 1 of the transmit process: clear the mailbox's flag if it is set.
            if B::read(IFLAG1) & TX_FLAG != 0 {
                B::w1c(IFLAG1, TX_FLAG);
            }
        }
        #[cfg(feature = "full")]
        {
            // The interrupt clears the flag with the completion.
            if B::read(IFLAG1) & TX_FLAG != 0 {
                return Err(Busy);
            }
        }
        let (id, mut cs) = if f.extended {
            (f.id & EXT_MASK, IDE | SRR)
        } else {
            (f.id << STD_SHIFT, 0)
        };
        if f.remote {
            cs |= RTR;
        }
        let d = f.data;
        B::write(mb(TX_MB) + 4, id);
        B::write(mb(TX_MB) + 8, u32::from_be_bytes([d[0], d[1], d[2], d[3]]));
        B::write(mb(TX_MB) + 12, u32::from_be_bytes([d[4], d[5], d[6], d[7]]));
        #[cfg(feature = "full")]
        let token = {
            let t = self.next;
            self.next = t.wrapping_add(1);
            self.token.store(t, Ordering::Release);
            t
        };
        #[cfg(feature = "lean")]
        let token = 0;
        B::write(
            mb(TX_MB),
            CODE_TX_DATA | cs | (u32::from(f.dlc & 0xF) << DLC_SHIFT),
        );
        Ok(token)
    }
}

/// MB15's interrupt (full).
#[cfg(feature = "full")]
pub struct TxHandler<'a, B: Bus> {
    done: Producer<'a, Completion>,
    token: &'a AtomicU32,
    counts: &'a Counts,
    _b: PhantomData<B>,
}

#[cfg(feature = "full")]
impl<B: Bus> TxHandler<'_, B> {
    /// MB15's flag: its outcome and time stamp into the completion ring, the flag
    /// acknowledged.
    #[inline(always)]
    pub fn on_interrupt(&mut self) {
        if B::read(IFLAG1) & TX_FLAG == 0 {
            return;
        }
        let cs = B::read(mb(TX_MB));
        B::w1c(IFLAG1, TX_FLAG);
        let sent = cs & CODE_MASK != CODE_TX_ABORT;
        if sent {
            self.counts.sent.inc();
        } else {
            self.counts.aborted.inc();
        }
        let c = Completion {
            token: self.token.load(Ordering::Acquire),
            sent,
            time: cs as u16,
        };
        if self.done.enqueue(c).is_err() {
            self.counts.completion_overflows.inc();
        }
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

/// The Rx FIFO interrupt.
pub struct RxHandler<'a, B: Bus> {
    ring: Producer<'a, RawRx>,
    counts: &'a Counts,
    _b: PhantomData<B>,
}

impl<B: Bus> RxHandler<'_, B> {
    /// Every frame of the Rx FIFO into the ring (K66 RM "Rx FIFO": read the output, then
    /// write 1 to `BUF5I` to pop it).
    #[inline(always)]
    pub fn on_interrupt(&mut self) {
        loop {
            let flags = B::read(IFLAG1);
            let acks = flags & (BUF6I | BUF7I);
            if acks != 0 {
                if flags & BUF7I != 0 {
                    self.counts.overruns.inc();
                }
                B::w1c(IFLAG1, acks);
            }
            if flags & BUF5I == 0 {
                break;
            }
            let raw = RawRx {
                cs: B::read(mb(0)),
                id: B::read(mb(0) + 4),
                word0: B::read(mb(0) + 8),
                word1: B::read(mb(0) + 12),
                hit: (B::read(RXFIR) & 0x1FF) as u16,
            };
            B::w1c(IFLAG1, BUF5I);
            #[cfg(feature = "full")]
            self.counts.received.inc();
            if self.ring.enqueue(raw).is_err() {
                self.counts.ring_overflows.inc();
            }
        }
    }
}

/// The receive half (thread).
pub struct Receiver<'a> {
    ring: Consumer<'a, RawRx>,
}

impl Receiver<'_> {
    /// The next frame, decoded, with the user's filter index.
    #[inline(always)]
    pub fn take(&mut self) -> Option<Received> {
        let r = self.ring.dequeue()?;
        let extended = r.cs & IDE != 0;
        let w0 = r.word0.to_be_bytes();
        let w1 = r.word1.to_be_bytes();
        Some(Received {
            frame: CanFrame {
                id: if extended {
                    r.id & EXT_MASK
                } else {
                    (r.id >> STD_SHIFT) & 0x7FF
                },
                extended,
                remote: r.cs & RTR != 0,
                dlc: ((r.cs >> DLC_SHIFT) & 0xF) as u8,
                data: [w0[0], w0[1], w0[2], w0[3], w1[0], w1[1], w1[2], w1[3]],
            },
            filter: FILTER_OF_HIT
                .get(r.hit as usize)
                .copied()
                .unwrap_or(UNKNOWN_FILTER),
            #[cfg(feature = "full")]
            time: r.cs as u16,
        })
    }
}

/// What `split` hands out.
pub struct Service<'a, B: Bus> {
    pub sender: Sender<'a, B>,
    pub rx_irq: RxHandler<'a, B>,
    pub receiver: Receiver<'a>,
    #[cfg(feature = "full")]
    pub tx_irq: TxHandler<'a, B>,
    #[cfg(feature = "full")]
    pub completions: Completions<'a>,
    pub counts: &'a Counts,
}

/// The storage the service lives in.
pub struct Storage {
    pub rx: Queue<RawRx, { RX + 1 }>,
    #[cfg(feature = "full")]
    pub done: Queue<Completion, { DONE + 1 }>,
    #[cfg(feature = "full")]
    pub token: AtomicU32,
    pub counts: Counts,
}

impl Storage {
    pub const fn new() -> Self {
        Storage {
            rx: Queue::new(),
            #[cfg(feature = "full")]
            done: Queue::new(),
            #[cfg(feature = "full")]
            token: AtomicU32::new(0),
            counts: Counts::new(),
        }
    }
}

/// The handles of each context, over `storage`.
pub fn split<B: Bus>(storage: &mut Storage) -> Service<'_, B> {
    let (rx_prod, rx_cons) = storage.rx.split();
    #[cfg(feature = "full")]
    let (done_prod, done_cons) = storage.done.split();
    let counts = &storage.counts;
    Service {
        sender: Sender {
            #[cfg(feature = "full")]
            token: &storage.token,
            #[cfg(feature = "full")]
            next: 0,
            _b: PhantomData,
        },
        rx_irq: RxHandler {
            ring: rx_prod,
            counts,
            _b: PhantomData,
        },
        receiver: Receiver { ring: rx_cons },
        #[cfg(feature = "full")]
        tx_irq: TxHandler {
            done: done_prod,
            token: &storage.token,
            counts,
            _b: PhantomData,
        },
        #[cfg(feature = "full")]
        completions: Completions { done: done_cons },
        counts,
    }
}

/// FlexCAN0 of the K20/K64/K66 (module base `0x4002_4000`, K66 RM memory map "CAN0").
pub struct Can0;

impl Bus for Can0 {
    #[inline(always)]
    fn read(offset: usize) -> u32 {
        // SAFETY: a FlexCAN0 register (offsets above), clocked by `system_teensy36`.
        unsafe { ((0x4002_4000 + offset) as *const u32).read_volatile() }
    }
    #[inline(always)]
    fn write(offset: usize, value: u32) {
        // SAFETY: as `read`; FlexCAN0 belongs to this service alone.
        unsafe { ((0x4002_4000 + offset) as *mut u32).write_volatile(value) }
    }
    #[inline(always)]
    fn w1c(offset: usize, bits: u32) {
        Self::write(offset, bits)
    }
}
