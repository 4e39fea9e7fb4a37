//! Time stamps extended beyond the controllers' 16-bit counters.
//!
//! Both controllers stamp frames with a 16-bit counter that counts **one per nominal bit
//! time** and wraps around:
//! - FlexCAN: the free-running timer `CANx_TIMER`, "clocked by the FlexCAN bit-clock"
//!   (Kinetis RM, FlexCAN "Free Running Timer (CANx_TIMER)"), copied into the message
//!   buffer's `TIME STAMP` field "at the start of the identifier field" of a received or
//!   transmitted frame (RM, "Message buffer structure"); software can read the timer at
//!   any time.
//! - bxCAN with time-triggered communication mode (`CAN_MCR.TTCM`): an internal counter
//!   "incremented by each CAN bit time", captured "on the sample point of the Start Of
//!   Frame bit in both reception and transmission" into `CAN_RDTxR.TIME` /
//!   `CAN_TDTxR.TIME` (RM0410 §40.7.2 "Time triggered communication mode"). Software
//!   cannot read the counter itself. Without TTCM bxCAN records no time stamp: the
//!   driver then reports `None` (the hardware time stamp has 0 bits).
//!
//! The split driver ([`crate::split`]) widens every 16-bit value to a [`Timestamp`] on the
//! interrupt side, with one [`Extender`] per controller, shared by the receive and
//! transmit handlers (see `docs/architecture.md`, "Time stamps", for the guarantee).
//!
//! ```
//! use twocan_core::timestamp::{bit_times_to_micros, Timestamp};
//!
//! // Two frames' stamps (`RxFrame::timestamp`), the counter having wrapped between them.
//! let a = Timestamp::from_parts(0, 65_000);
//! let b = Timestamp::from_parts(1, 500);
//! let bits = b.bit_times_since(a).unwrap();
//! assert_eq!(bits, 1_036);
//! assert_eq!(bit_times_to_micros(bits, 500_000)?, 2_072); // 2 µs a bit
//! # Ok::<(), twocan_core::Error>(())
//! ```

use crate::error::Error;
use core::num::NonZeroU64;

/// Bits of the controllers' hardware time stamp counters (FlexCAN `TIMER`, bxCAN TTCM).
pub const COUNTER_BITS: u32 = 16;

/// Bit times between two wraps of the 16-bit counter (65,536: 131.072 ms at
/// 500 kbit/s).
pub const COUNTER_PERIOD: u64 = 1 << COUNTER_BITS;

/// The time of a frame on the bus, in nominal bit times, extended beyond the hardware's
/// 16-bit counter (48 bits: 8.9 years at 1 Mbit/s).
///
/// Its origin is fixed when the driver starts and is otherwise arbitrary: compare stamps
/// of one driver with each other ([`Timestamp::bit_times_since`]), or convert a
/// difference to microseconds ([`bit_times_to_micros`]). The low 16 bits are the
/// hardware's own value ([`Timestamp::counter`]). An `Option<Timestamp>` takes 8 bytes.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Timestamp(NonZeroU64);

impl core::fmt::Debug for Timestamp {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_tuple("Timestamp").field(&self.ticks()).finish()
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for Timestamp {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(f, "Timestamp({=u64})", self.ticks())
    }
}

impl Timestamp {
    /// The largest tick count a time stamp holds (2^48 − 1).
    pub const MAX_TICKS: u64 = (1 << 48) - 1;

    /// A time stamp of `ticks` bit times; [`Error::InvalidArgument`] beyond
    /// [`Timestamp::MAX_TICKS`].
    pub const fn from_ticks(ticks: u64) -> Result<Self, Error> {
        if ticks > Self::MAX_TICKS {
            return Err(Error::InvalidArgument);
        }
        Ok(Self::from_masked(ticks))
    }

    /// A time stamp from the number of counter wraps and the 16-bit counter value.
    pub const fn from_parts(wraps: u32, counter: u16) -> Self {
        Self::from_masked(((wraps as u64) << COUNTER_BITS) | counter as u64)
    }

    const fn from_masked(ticks: u64) -> Self {
        match NonZeroU64::new((ticks & Self::MAX_TICKS) + 1) {
            Some(v) => Timestamp(v),
            // Unreachable: a masked value plus one is never zero.
            None => Timestamp(NonZeroU64::MIN),
        }
    }

    /// Bit times since the driver's origin.
    pub const fn ticks(self) -> u64 {
        self.0.get() - 1
    }

    /// The hardware's 16-bit value (the low bits).
    pub const fn counter(self) -> u16 {
        self.ticks() as u16
    }

    /// How many times the 16-bit counter wrapped since the origin (the high bits).
    pub const fn wraps(self) -> u32 {
        (self.ticks() >> COUNTER_BITS) as u32
    }

    /// Bit times from `earlier` to `self`; `None` when `earlier` is later.
    pub const fn bit_times_since(self, earlier: Timestamp) -> Option<u64> {
        self.ticks().checked_sub(earlier.ticks())
    }

    /// [`Timestamp::ticks`] in microseconds at `bit_rate` bit/s (rounded down): see
    /// [`bit_times_to_micros`].
    pub const fn as_micros(self, bit_rate: u32) -> Result<u64, Error> {
        bit_times_to_micros(self.ticks(), bit_rate)
    }
}

/// `bits` nominal bit times in microseconds at `bit_rate` bit/s, rounded down (the
/// counters count bit times, so the time base is the nominal bit rate in force:
/// `actual_bit_rate` of the timing the controller runs). [`Error::InvalidArgument`] for
/// a bit rate of 0 or a result beyond `u64`.
pub const fn bit_times_to_micros(bits: u64, bit_rate: u32) -> Result<u64, Error> {
    if bit_rate == 0 {
        return Err(Error::InvalidArgument);
    }
    let rate = bit_rate as u64;
    // Whole seconds and the rest apart, so that nothing overflows before the result
    // does: the rest is below 2^32, times 10^6 below 2^52.
    let (secs, rest) = (bits / rate, bits % rate);
    match secs.checked_mul(1_000_000) {
        Some(whole) => match whole.checked_add(rest * 1_000_000 / rate) {
            Some(us) => Ok(us),
            None => Err(Error::InvalidArgument),
        },
        None => Err(Error::InvalidArgument),
    }
}

/// Receive queues whose order the extender keeps (bxCAN's two FIFOs).
pub const RX_QUEUES: usize = 2;

/// Widens 16-bit counter values to [`Timestamp`]s relative to a reference it keeps (the
/// latest extended value it saw). All zeros is a valid start (`const`), so that a
/// `static` driver state holds one in `.bss`.
///
/// Two ways, by what the hardware offers:
/// - the counter can be read ([`Extender::observe`], then [`Extender::extend_before`]):
///   each reading moves the reference forward by its distance from the previous one
///   (assumed less than one period, 65,536 bit times), and a stamp taken at or before
///   the latest reading is placed less than one period before it. Exact when readings
///   are less than 65,536 bit times apart and each stamp is widened less than 65,536 bit
///   times after it was taken;
/// - it cannot ([`Extender::extend_received`], [`Extender::extend_sent`]): a stamp is
///   placed after the reference (less than one period after it, moving the reference)
///   unless it may be older than the reference, and then within ±32,767 bit times of
///   it. A received frame may be older than the reference only when its receive queue
///   held a frame (not read yet) at the last time the reference moved and has not been
///   found empty since: the extender keeps that per queue, from the hardware's "frame
///   pending" flags read when it widens a stamp (`pending`). So a frame read after a
///   quiet bus of any length is placed after every frame read before it — never before
///   a frame it followed on the bus — and its stamp is off by whole periods only. A
///   transmit stamp is placed within ±32,767 bit times of the reference (the hardware
///   does not tell whether an older completion is pending).
///
/// The first reading (or, without readings, the first stamp) lands one period above the
/// origin, at one period plus its counter value, so that a stamp from up to one period
/// before it (a frame that waited in the hardware while the driver started, or an older
/// frame of another receive FIFO) is still placed exactly, without going below the
/// origin.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Extender {
    /// The extended reference, less one period (0 at the start).
    reference: u64,
    /// A stamp or reading set the reference ([`Extender::extend_near`] places its first
    /// stamp at its counter value, one period above the origin).
    primed: bool,
    /// Bit `q`: receive queue `q` held a frame not read yet when the reference last
    /// moved, and was not found empty since, so its next frames may be older than the
    /// reference.
    maybe_older: u8,
}

impl Extender {
    /// Reference at the origin's first wrap (counter value 0).
    pub const fn new() -> Self {
        Extender {
            reference: 0,
            primed: false,
            maybe_older: 0,
        }
    }

    /// The reference (the latest extended counter reading or stamp).
    pub const fn reference(&self) -> Timestamp {
        Timestamp::from_masked(self.reference + COUNTER_PERIOD)
    }

    /// A reading of the free-running counter, made at or after the reference and less
    /// than one period later: the reference moves forward to it. Returns the reading
    /// extended.
    pub fn observe(&mut self, counter: u16) -> Timestamp {
        let ahead = counter.wrapping_sub(self.reference as u16);
        self.reference = (self.reference + u64::from(ahead)) & Timestamp::MAX_TICKS;
        self.primed = true;
        self.reference()
    }

    /// A stamp taken at or before the latest [`Extender::observe`] reading and less than
    /// one period before it.
    pub fn extend_before(&self, stamp: u16) -> Timestamp {
        let back = (self.reference as u16).wrapping_sub(stamp);
        Timestamp::from_masked(self.reference + COUNTER_PERIOD - u64::from(back))
    }

    /// A stamp within ±32,767 bit times of the reference (no counter reading): placed
    /// there, and the reference moves forward to it when it is later. Without what the
    /// hardware holds, every receive queue may then hold older frames (see
    /// [`Extender::extend_received`]).
    pub fn extend_near(&mut self, stamp: u16) -> Timestamp {
        self.extend_sent(stamp, |_| true)
    }

    /// The stamp of a completed transmission (no counter reading): placed within
    /// ±32,767 bit times of the reference, which moves forward to it when it is later.
    /// `pending(q)`: whether receive queue `q` holds a frame not read yet, read now
    /// (`true` when unknown).
    pub fn extend_sent(&mut self, stamp: u16, pending: impl Fn(usize) -> bool) -> Timestamp {
        let (at, moved) = self.place(stamp, true);
        self.note_queues(None, moved, pending);
        at
    }

    /// The stamp of a frame just read from receive queue `queue` (`< RX_QUEUES`; no
    /// counter reading). `pending(q)`: whether receive queue `q` holds a frame not read
    /// yet, read now, after the frame was taken (`true` when unknown).
    ///
    /// Placed after the reference (less than one period after it, the reference moving
    /// forward to it), unless `queue` may hold frames older than the reference: then
    /// within ±32,767 bit times of it, as [`Extender::extend_near`]. Queue `q` may hold
    /// older frames when `pending(q)` was true as the reference last moved and has not
    /// been false since (its frames read after it was found empty arrived after the
    /// reference's frame was read, so after the reference).
    pub fn extend_received(
        &mut self,
        queue: usize,
        stamp: u16,
        pending: impl Fn(usize) -> bool,
    ) -> Timestamp {
        let near = queue < RX_QUEUES && self.maybe_older & (1 << queue) != 0;
        let (at, moved) = self.place(stamp, near);
        self.note_queues(Some(queue), moved, pending);
        at
    }

    /// Places `stamp` after the reference, or (`near`) within ±32,767 bit times of it;
    /// moves the reference forward to it when it is later. Whether it moved.
    fn place(&mut self, stamp: u16, near: bool) -> (Timestamp, bool) {
        if !self.primed {
            self.primed = true;
            self.reference = u64::from(stamp);
            return (self.reference(), true);
        }
        let ahead = stamp.wrapping_sub(self.reference as u16);
        if near && (ahead as i16) < 0 {
            // Behind the reference, which stays: never below the origin (the
            // reference is one period above it).
            let back = u64::from(ahead.wrapping_neg());
            return (
                Timestamp::from_masked(self.reference + COUNTER_PERIOD - back),
                false,
            );
        }
        self.reference = (self.reference + u64::from(ahead)) & Timestamp::MAX_TICKS;
        (self.reference(), ahead != 0)
    }

    /// After a stamp from `source` (a receive queue, or `None` for a transmission) was
    /// placed: which queues may hold frames older than the reference now.
    fn note_queues(&mut self, source: Option<usize>, moved: bool, pending: impl Fn(usize) -> bool) {
        for q in 0..RX_QUEUES {
            let bit = 1u8 << q;
            let older = if moved && source == Some(q) {
                // The frame that moved the reference came from this queue: the queue's
                // later frames follow it.
                false
            } else if moved {
                // Frames of this queue not read yet may be older than the new reference.
                pending(q)
            } else {
                // A queue found empty now: its later frames arrive after this moment,
                // so after the reference.
                self.maybe_older & bit != 0 && pending(q)
            };
            if older {
                self.maybe_older |= bit;
            } else {
                self.maybe_older &= !bit;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const P: u64 = COUNTER_PERIOD;

    #[test]
    fn parts_ticks_and_limits() {
        let t = Timestamp::from_parts(3, 0x1234);
        assert_eq!(t.ticks(), 3 * P + 0x1234);
        assert_eq!((t.wraps(), t.counter()), (3, 0x1234));
        assert_eq!(Timestamp::from_ticks(t.ticks()), Ok(t));
        assert_eq!(
            Timestamp::from_ticks(Timestamp::MAX_TICKS + 1),
            Err(Error::InvalidArgument)
        );
        let max = Timestamp::from_ticks(Timestamp::MAX_TICKS).unwrap();
        assert_eq!(max, Timestamp::from_parts(u32::MAX, u16::MAX));
        assert_eq!(Timestamp::from_ticks(0).unwrap().ticks(), 0);
        assert_eq!(core::mem::size_of::<Option<Timestamp>>(), 8);
        let a = Timestamp::from_ticks(100).unwrap();
        assert_eq!(t.bit_times_since(a), Some(3 * P + 0x1234 - 100));
        assert_eq!(a.bit_times_since(t), None);
        assert!(a < t);
    }

    #[test]
    fn micros_from_the_bit_rate() {
        // 500 kbit/s: 2 µs a bit; one period is 131,072 µs.
        assert_eq!(bit_times_to_micros(P, 500_000), Ok(131_072));
        assert_eq!(bit_times_to_micros(1, 1_000_000), Ok(1));
        // 125 kbit/s: 8 µs a bit; 842,105 bit/s (ACAN's 842 kbit/s): 1.1875 µs a bit,
        // rounded down.
        assert_eq!(bit_times_to_micros(3, 125_000), Ok(24));
        assert_eq!(bit_times_to_micros(842_105, 842_105), Ok(1_000_000));
        assert_eq!(bit_times_to_micros(842_106, 842_105), Ok(1_000_001));
        assert_eq!(bit_times_to_micros(10, 842_105), Ok(11));
        assert_eq!(Timestamp::from_parts(1, 0).as_micros(250_000), Ok(262_144));
        // The largest stamp at the slowest exact FlexCAN rate (2.5 kbit/s) still fits.
        assert_eq!(
            bit_times_to_micros(Timestamp::MAX_TICKS, 2_500),
            Ok(Timestamp::MAX_TICKS / 2_500 * 1_000_000 + Timestamp::MAX_TICKS % 2_500 * 400)
        );
        assert_eq!(bit_times_to_micros(5, 0), Err(Error::InvalidArgument));
        assert_eq!(
            bit_times_to_micros(u64::MAX, 1),
            Err(Error::InvalidArgument)
        );
    }

    #[test]
    fn readings_widen_stamps_across_wraps() {
        let mut e = Extender::new();
        // First reading: 40,000 (no wrap seen yet) lands one period above the origin.
        assert_eq!(e.observe(40_000).ticks(), P + 40_000);
        // A frame stamped 1,000 bit times before the reading.
        assert_eq!(e.extend_before(39_000).ticks(), P + 39_000);
        // A frame stamped before the driver started, across the counter's wrap: exact.
        assert_eq!(e.extend_before(60_000).ticks(), 60_000);
        // Readings every 50,000 bit times, 4 wraps in all.
        let mut true_time = 40_000u64;
        for _ in 0..6 {
            true_time += 50_000;
            let r = e.observe(true_time as u16);
            assert_eq!(r.ticks(), P + true_time);
        }
        // A stamp taken 65,535 bit times before the reading (the most a late handler
        // may be behind) is still exact.
        let stamp = true_time - 65_535;
        assert_eq!(e.extend_before(stamp as u16).ticks(), P + stamp);
        // The stamp of the reading's own bit time.
        assert_eq!(e.extend_before(true_time as u16).ticks(), P + true_time);
    }

    #[test]
    fn a_missed_reading_loses_exactly_whole_periods() {
        let mut e = Extender::new();
        e.observe(0);
        // 70,000 bit times without a reading: one period is lost, never a fraction.
        assert_eq!(e.observe(70_000u64 as u16).ticks(), P + 70_000 - P);
    }

    #[test]
    fn received_stamps_after_a_quiet_bus_are_placed_after_the_reference() {
        let empty = |_: usize| false;
        let mut e = Extender::new();
        assert_eq!(e.extend_received(0, 1_000, empty).ticks(), P + 1_000);
        // A quiet bus of 40,000 bit times, then a frame of the other FIFO, which was
        // empty when the reference moved: after it (the old rule put it 25,536 before).
        assert_eq!(e.extend_received(1, 41_000, empty).ticks(), P + 41_000);
        // 65,535 after, either FIFO: still exact.
        let t = 41_000 + 65_535;
        assert_eq!(e.extend_received(0, t as u16, empty).ticks(), P + t);
        // Longer: off by whole periods, never placed before the reference.
        let r = e.reference().ticks();
        let t = e
            .extend_received(1, (41_000 + 65_535 + 70_000) as u16, empty)
            .ticks();
        assert!(t > r && (P + 41_000 + 65_535 + 70_000 - t).is_multiple_of(P));
    }

    #[test]
    fn an_older_frame_of_a_pending_fifo_is_placed_before_the_reference() {
        // FIFO 1 holds a frame while FIFO 0's newer frame is read first.
        let fifo1_pending = |q: usize| q == 1;
        let mut e = Extender::new();
        assert_eq!(
            e.extend_received(0, 10_000, fifo1_pending).ticks(),
            P + 10_000
        );
        // FIFO 1's frame, stamped 300 bit times earlier and read now (FIFO 1 empty
        // after it): before the reference, which stays.
        assert_eq!(e.extend_received(1, 9_700, |_| false).ticks(), P + 9_700);
        assert_eq!(e.reference().ticks(), P + 10_000);
        // FIFO 1 was found empty: its next frame, 50,000 later, is placed after.
        assert_eq!(e.extend_received(1, 60_000, |_| false).ticks(), P + 60_000);
        // A transmit stamp moves the reference while FIFO 0 holds a frame: FIFO 0's
        // older frame is placed before it.
        assert_eq!(e.extend_sent(60_500, |q| q == 0).ticks(), P + 60_500);
        assert_eq!(e.extend_received(0, 60_400, |_| false).ticks(), P + 60_400);
        // Without what the hardware holds (`extend_near`), every queue may be older.
        assert_eq!(e.extend_near(61_000).ticks(), P + 61_000);
        assert_eq!(e.extend_received(1, 60_900, |_| true).ticks(), P + 60_900);
    }

    #[test]
    fn near_stamps_without_a_counter_reading() {
        let mut e = Extender::new();
        // The first stamp lands one period above the origin; an older one (up to 32,768
        // back, across the counter's wrap) below it.
        assert_eq!(e.extend_near(20_000).ticks(), P + 20_000);
        assert_eq!(e.reference().ticks(), P + 20_000);
        assert_eq!(e.extend_near(60_000).ticks(), 60_000);
        assert_eq!(e.reference().ticks(), P + 20_000);
        // Forward steps of up to 32,767 bit times, across wraps.
        let mut t = P + 20_000;
        for _ in 0..10 {
            t += 32_767;
            assert_eq!(e.extend_near(t as u16).ticks(), t);
        }
        // An older stamp (another FIFO, handled later) up to 32,768 back: placed before,
        // the reference stays.
        let back = t - 32_768;
        assert_eq!(e.extend_near(back as u16).ticks(), back);
        assert_eq!(e.reference().ticks(), t);
        // More than 32,767 ahead reads as behind: the documented limit.
        assert_eq!(e.extend_near((t + 40_000) as u16).ticks(), t + 40_000 - P);
    }
}
