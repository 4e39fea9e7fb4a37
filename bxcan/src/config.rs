//! The configuration builder: bit timing, test modes and the `CAN_MCR` options.
//!
//! Everything here is written while the controller is in initialization mode (RM0410
//! §40.4.1 "Initialization mode": `CAN_BTR` can only be written there; the notes'
//! `CAN_MCR` bit list for TTCM, ABOM, AWUM, NART, RFLM, TXFP, DBF).
//!
//! **One bit-timing rule.** [`timing_rule`] is what this driver accepts from an APB1
//! clock: the `CAN_BTR` field ranges ([`Limits::BXCAN`], RM0410 §40.7.7), nothing more.
//! [`Config::from_bitrate`], [`Config::from_bitrate_with`] and [`Config::from_timing`]
//! judge by it ([`TimingRule::timing_for`], [`TimingRule::accept`]), the running
//! controller reports it in its capabilities and applies it to `set_timing` and
//! `set_bitrate`: the slowest and fastest timings the capabilities name are accepted by
//! all of them, one bit per second beyond is refused by all of them.

use twocan_core::timing::frame_time::{frame_in_flight_wait, MAX_FRAME_IN_FLIGHT_BITS};
use twocan_core::timing::{
    cia_sample_point, Limits, Timing, TimingError, TimingRule, DEFAULT_TOLERANCE_PPM,
};
use twocan_core::TxPolicy;

use crate::chip::{self, Chip};
use crate::regs::{btr, ier, mcr};

/// Why a configuration was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// The bit timing could not be computed, does not fit `CAN_BTR`, or is outside the
    /// tolerance of the wished bit rate.
    Timing(TimingError),
    /// A raw `CAN_BTR` value with bits outside `BRP`, `TS1`, `TS2`, `SJW` (reserved bits,
    /// or the `LBKM`/`SILM` mode bits, which the builder sets with
    /// [`Config::loopback`]/[`Config::silent`]).
    BtrReservedBits,
    /// A CAN2 start bank above 28 (RM0410 `CAN_FMR.CAN2SB`), or one on a part without
    /// CAN2, where `CAN2SB` is reserved (RM0008 §24.9.4: the F103).
    StartBankOutOfRange,
    /// The APB1 clock the timing was computed from is above the part's limit
    /// ([`Chip::apb1_max_hz`], the datasheet's "general operating conditions").
    ClockAboveChipLimit,
}

impl From<TimingError> for ConfigError {
    fn from(e: TimingError) -> Self {
        ConfigError::Timing(e)
    }
}

/// How the controller leaves bus-off (notes "Bus-off recovery"; `CAN_MCR.ABOM`): the
/// portable setting [`twocan_core::BusOffRecovery`]. `Automatic`: `ABOM = 1`, the
/// hardware starts the recovery sequence (128 × 11 recessive bits) by itself. `Manual`
/// (the reset value, and this crate's default): `ABOM = 0`, software starts it by
/// entering and leaving initialization mode ([`twocan_core::Hardware::recover`]).
pub use twocan_core::BusOffRecovery as Recovery;

/// The bit timing rule of every bxCAN entry point (module docs): the APB1 clock
/// `apb1_hz` and the `CAN_BTR` field ranges, [`Limits::BXCAN`] (RM0410 §40.7.7 "Bit
/// timing"; the reference manual adds no rule beyond them).
pub const fn timing_rule(apb1_hz: u32) -> TimingRule {
    TimingRule::new(apb1_hz, Limits::BXCAN)
}

/// The `CAN_BTR` timing fields (BRP, TS1, TS2, SJW).
const BTR_TIMING: u32 = btr::BRP.mask() | btr::TS1.mask() | btr::TS2.mask() | btr::SJW.mask();

/// The interrupts the driver services in [`twocan_core::Driver::on_interrupt`]: mailbox
/// empty, message pending / full / overrun of both FIFOs, error (warning, passive,
/// bus-off, last error code), wake-up (RM0410 §40.8 "bxCAN interrupts").
pub const DEFAULT_INTERRUPTS: u32 = ier::TMEIE
    | ier::FMPIE0
    | ier::FOVIE0
    | ier::FMPIE1
    | ier::FOVIE1
    | ier::EWGIE
    | ier::EPVIE
    | ier::BOFIE
    | ier::LECIE
    | ier::ERRIE
    | ier::WKUIE;

/// Default bound on every wait for an acknowledge bit (`INAK`, `SLAK`): register reads.
///
/// Leaving initialization mode takes 11 consecutive recessive bits on CANRX (RM0410
/// §40.4.1): 11 ms at 1 kbit/s. One read of an APB1 register costs at least 4 CPU cycles,
/// so 1,000,000 reads last at least 18 ms at 216 MHz — longer than that — and end in
/// [`twocan_core::Error::Timeout`] when the acknowledge never comes (no transceiver, no
/// clock). A frame in flight delays the acknowledge too: configurations built from a bit
/// rate ([`Config::from_timing`]) or a raw `CAN_BTR` ([`btr_wait_iterations`]) raise the
/// bound to twice the longest frame in flight at their bit rate when that is longer.
pub const DEFAULT_WAIT_ITERATIONS: u32 = 1_000_000;

/// The acknowledge-wait bound for a raw `CAN_BTR` value, whatever the APB1 clock.
///
/// A bit lasts `(BRP + 1) × (1 + (TS1 + 1) + (TS2 + 1))` APB1 cycles (RM0410 §40.7.7
/// "Bit timing": tq = (BRP + 1) × tPCLK, one bit = SYNC_SEG + BS1 + BS2), and every poll
/// reads an APB1 register, at least one APB1 cycle. Twice the longest frame in flight
/// ([`MAX_FRAME_IN_FLIGHT_BITS`] bits) in APB1 cycles is therefore enough polls at any
/// clock, with no need to know it; never below [`DEFAULT_WAIT_ITERATIONS`]. The largest
/// encodable bit (BRP 1024, 25 tq) gives 2 × 191 × 25,600 = 9,779,200 polls.
pub const fn btr_wait_iterations(btr_value: u32) -> u32 {
    let brp = btr::BRP.get(btr_value) as u64 + 1;
    let tq = 1 + (btr::TS1.get(btr_value) as u64 + 1) + (btr::TS2.get(btr_value) as u64 + 1);
    let polls = 2 * MAX_FRAME_IN_FLIGHT_BITS as u64 * brp * tq;
    if polls > DEFAULT_WAIT_ITERATIONS as u64 {
        // At most 9,779,200 (above): fits.
        polls as u32
    } else {
        DEFAULT_WAIT_ITERATIONS
    }
}

/// Configuration of one bxCAN instance (builder; every setter is `const`).
///
/// ```
/// use twocan_bxcan::{Config, Recovery};
/// use twocan_core::TxPolicy;
/// // APB1 = 54 MHz (216 MHz SYSCLK / 4), 500 kbit/s, CiA sample point, 0.1 % tolerance.
/// const CONFIG: Config = match Config::from_bitrate(54_000_000, 500_000) {
///     Ok(c) => c.tx_policy(TxPolicy::Priority).recovery(Recovery::Automatic),
///     Err(_) => panic!("no timing"),
/// };
/// assert_eq!(CONFIG.btr_value() & 0x3FF, 5); // BRP = 6 - 1
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    btr: u32,
    loopback: bool,
    silent: bool,
    tx_policy: TxPolicy,
    one_shot: bool,
    recovery: Recovery,
    rx_fifo_lock: bool,
    timestamps: bool,
    auto_wakeup: bool,
    debug_freeze: bool,
    interrupts: u32,
    can2_start_bank: Option<u8>,
    wait_iterations: u32,
    /// The APB1 clock the timing was computed from (0: unknown, a raw `CAN_BTR`).
    clock_hz: u32,
    /// The part ([`Config::chip`]).
    chip: &'static Chip,
}

impl Config {
    const fn with_btr(btr: u32) -> Config {
        Config {
            btr,
            loopback: false,
            silent: false,
            tx_policy: TxPolicy::Fifo,
            one_shot: false,
            recovery: Recovery::Manual,
            rx_fifo_lock: false,
            timestamps: false,
            auto_wakeup: false,
            // The reset value of `CAN_MCR.DBF` (RM0410 §40.9.2): CAN frozen while a
            // debugger halts the core.
            debug_freeze: true,
            interrupts: DEFAULT_INTERRUPTS,
            can2_start_bank: None,
            wait_iterations: DEFAULT_WAIT_ITERATIONS,
            clock_hz: 0,
            chip: DEFAULT_CHIP,
        }
    }

    /// A configuration with a raw `CAN_BTR` timing value (RM0410 §40.9.2 "CAN bit timing
    /// register": `BRP[9:0]`, `TS1[19:16]`, `TS2[22:20]`, `SJW[25:24]`). The clock is
    /// unknown, so only the clock-free part of [`timing_rule`] applies: the counts must
    /// be consistent ([`Timing::consistency`]: SJW ≤ TS2), else
    /// [`ConfigError::Timing`]`(`[`TimingError::Inconsistent`]`)`.
    pub const fn from_btr(btr_value: u32) -> Result<Config, ConfigError> {
        if btr_value & !BTR_TIMING != 0 {
            return Err(ConfigError::BtrReservedBits);
        }
        let c = Timing::from_bxcan_btr(0, 0, btr_value).consistency();
        if !c.is_ok() {
            return Err(ConfigError::Timing(TimingError::Inconsistent(c)));
        }
        Ok(Config {
            wait_iterations: btr_wait_iterations(btr_value),
            ..Self::with_btr(btr_value)
        })
    }

    /// A configuration from a [`Timing`] (for example adjusted by hand) on its own clock,
    /// accepted by [`timing_rule`] ([`TimingRule::accept`]): a bxCAN timing consistent
    /// with the `CAN_BTR` ranges, its wished bit rate in the rule's range, within
    /// `tolerance_ppm` of it.
    pub const fn from_timing(timing: Timing, tolerance_ppm: u32) -> Result<Config, ConfigError> {
        if let Err(e) = timing_rule(timing.clock_hz).accept(&timing, tolerance_ppm) {
            return Err(ConfigError::Timing(e));
        }
        Self::from_accepted(timing)
    }

    /// The configuration of a timing [`timing_rule`] accepted.
    const fn from_accepted(t: Timing) -> Result<Config, ConfigError> {
        let clock_hz = t.clock_hz;
        // Each poll reads an APB1 register, at least one APB1 cycle: twice the longest
        // frame in flight at this rate, in APB1 cycles, bounds the waits that a frame on
        // the bus delays (at 10 kbit/s and below, more than the default).
        let wait_iterations = match frame_in_flight_wait(t.bitrate, clock_hz, 2) {
            Ok(polls) if polls > DEFAULT_WAIT_ITERATIONS as u64 => {
                if polls > u32::MAX as u64 {
                    u32::MAX
                } else {
                    polls as u32
                }
            }
            _ => DEFAULT_WAIT_ITERATIONS,
        };
        match t.bxcan_btr() {
            Ok(b) => Ok(Config {
                clock_hz,
                wait_iterations,
                ..Self::with_btr(b)
            }),
            Err(e) => Err(ConfigError::Timing(e)),
        }
    }

    /// Bit timing solved for `bitrate` from the APB1 clock `apb1_hz` (the bxCAN kernel
    /// clock, RM0410 §40.7.7 "Bit timing": tq = (BRP + 1) × tPCLK), CiA sample point,
    /// refused beyond [`DEFAULT_TOLERANCE_PPM`] (0.1 %) from the wished rate.
    ///
    /// A rate outside [`timing_rule`]'s range is refused first, with the same typed
    /// error on every backend ([`TimingRule::check_bitrate`]: `BitrateTooHigh`,
    /// `BitrateTooLow`).
    pub const fn from_bitrate(apb1_hz: u32, bitrate: u32) -> Result<Config, ConfigError> {
        Self::from_bitrate_with(
            apb1_hz,
            bitrate,
            cia_sample_point(bitrate),
            DEFAULT_TOLERANCE_PPM,
        )
    }

    /// Like [`Config::from_bitrate`] with a sample point (per mille) and a tolerance
    /// ([`TimingRule::timing_for`] of [`timing_rule`]).
    pub const fn from_bitrate_with(
        apb1_hz: u32,
        bitrate: u32,
        sample_point_permille: u16,
        tolerance_ppm: u32,
    ) -> Result<Config, ConfigError> {
        match timing_rule(apb1_hz).timing_for(bitrate, sample_point_permille, tolerance_ppm) {
            Ok(t) => Self::from_accepted(t),
            Err(e) => Err(ConfigError::Timing(e)),
        }
    }

    /// Loop-back mode (`CAN_BTR.LBKM`, RM0410 §40.5.2): transmitted frames are received
    /// back and the acknowledge slot is ignored.
    pub const fn loopback(self, on: bool) -> Self {
        Config {
            loopback: on,
            ..self
        }
    }

    /// Silent mode (`CAN_BTR.SILM`, RM0410 §40.5.1): listen only, send recessive bits.
    /// With loop-back: "loop back combined with silent", a self-test that leaves the bus
    /// alone.
    pub const fn silent(self, on: bool) -> Self {
        Config { silent: on, ..self }
    }

    /// Transmit order among loaded mailboxes (`CAN_MCR.TXFP`; notes "Transmit priority"):
    /// [`TxPolicy::Fifo`] sets TXFP (request order), [`TxPolicy::Priority`] clears it
    /// (identifier order).
    pub const fn tx_policy(self, policy: TxPolicy) -> Self {
        Config {
            tx_policy: policy,
            ..self
        }
    }

    /// No automatic retransmission (`CAN_MCR.NART`; notes "Non automatic retransmission
    /// mode"): each frame is tried once; a failure is reported as
    /// a `Failed` completion ([`twocan_core::TxOutcome::Failed`]).
    pub const fn one_shot(self, on: bool) -> Self {
        Config {
            one_shot: on,
            ..self
        }
    }

    /// Bus-off recovery (`CAN_MCR.ABOM`).
    pub const fn recovery(self, recovery: Recovery) -> Self {
        Config { recovery, ..self }
    }

    /// Receive FIFO locked mode (`CAN_MCR.RFLM`; notes "FIFO overrun"): when a FIFO is
    /// full, keep the three oldest frames and drop the new one (else the newest replaces
    /// the last stored).
    pub const fn rx_fifo_lock(self, on: bool) -> Self {
        Config {
            rx_fifo_lock: on,
            ..self
        }
    }

    /// Time-triggered communication mode (`CAN_MCR.TTCM`; notes "Time triggered
    /// communication mode", RM0410 §40.7.2): the bit-time counter is captured at the
    /// start of frame of received and transmitted frames and reported, widened past its
    /// 16 bits, in [`twocan_core::RxFrame::timestamp`] and
    /// [`twocan_core::Completion::timestamp`]. Off: both are `None` (the hardware has no
    /// time stamp). The counter cannot be read by software, so the widening is relative
    /// to the previous stamp ([`twocan_core::timestamp`]; `docs/architecture.md`, "Time
    /// stamps").
    pub const fn timestamps(self, on: bool) -> Self {
        Config {
            timestamps: on,
            ..self
        }
    }

    /// Automatic wake-up on bus activity (`CAN_MCR.AWUM`, RM0410 §40.4.3 "Sleep mode").
    pub const fn auto_wakeup(self, on: bool) -> Self {
        Config {
            auto_wakeup: on,
            ..self
        }
    }

    /// Freeze the controller while the core is halted by a debugger (`CAN_MCR.DBF`, set
    /// at reset and kept by default: RM0410 §40.9.2). Turn it off to keep the bus
    /// traffic going while stepping through firmware.
    pub const fn debug_freeze(self, on: bool) -> Self {
        Config {
            debug_freeze: on,
            ..self
        }
    }

    /// The `CAN_IER` value written at configuration (default [`DEFAULT_INTERRUPTS`]).
    pub const fn interrupts(self, ier_value: u32) -> Self {
        Config {
            interrupts: ier_value,
            ..self
        }
    }

    /// The first filter bank of CAN2 (`CAN_FMR.CAN2SB`): CAN1 gets banks `0..bank`,
    /// CAN2 `bank..28`; 28 gives every bank to CAN1 (the notes' "sets to zero for one
    /// CAN" would give them all to CAN2: see `docs/filters.md`). Unset: the value in the
    /// register is kept (14 after reset).
    ///
    /// CAN1 writes it ([`crate::Can::can1`], [`crate::Can::reconfigure`]); a change is
    /// refused with [`twocan_core::Error::WrongMode`] while a filter bank it would move
    /// or renumber is active (CAN2's filters, or CAN1's above the new split): install
    /// an empty plan on the instance first. CAN2 checks it against the shared block
    /// ([`twocan_core::Error::InvalidArgument`] if it disagrees). Ignored by CAN3.
    pub const fn can2_start_bank(self, bank: u8) -> Result<Self, ConfigError> {
        if !self.chip.start_bank_valid(bank) {
            return Err(ConfigError::StartBankOutOfRange);
        }
        Ok(Config {
            can2_start_bank: Some(bank),
            ..self
        })
    }

    /// The part the controller is on ([`crate::chip`]; default [`DEFAULT_CHIP`], the
    /// STM32F76x/F77x): the driver reads from it which instances exist
    /// ([`crate::Can::can1`] & co. refuse another with
    /// [`twocan_core::Error::InvalidArgument`]), the banks each owns (a single-CAN block
    /// is never split: `CAN2SB` is not written there) and hence the planner's bank count
    /// and the capabilities' filter counts.
    ///
    /// Errors: [`ConfigError::ClockAboveChipLimit`] when the timing's APB1 clock is above
    /// the part's [`Chip::apb1_max_hz`]; [`ConfigError::StartBankOutOfRange`] when a CAN2
    /// start bank was set and the part has no CAN2 (or fewer banks).
    ///
    /// ```
    /// use twocan_bxcan::{chip, Config, ConfigError};
    /// // A Blue Pill: APB1 at 36 MHz (its maximum, RM0008 §7.2), one CAN, 14 banks.
    /// let c = Config::from_bitrate(36_000_000, 500_000).unwrap().chip(&chip::STM32F103);
    /// assert!(c.is_ok());
    /// // 42 MHz is above the F103's APB1 limit.
    /// let c = Config::from_bitrate(42_000_000, 500_000).unwrap().chip(&chip::STM32F103);
    /// assert_eq!(c.unwrap_err(), ConfigError::ClockAboveChipLimit);
    /// ```
    pub const fn chip(self, chip: &'static Chip) -> Result<Self, ConfigError> {
        if !chip.clock_allowed(self.clock_hz) {
            return Err(ConfigError::ClockAboveChipLimit);
        }
        if let Some(bank) = self.can2_start_bank {
            if !chip.start_bank_valid(bank) {
                return Err(ConfigError::StartBankOutOfRange);
            }
        }
        Ok(Config { chip, ..self })
    }

    /// The bound, in register reads, on every wait for an acknowledge bit (default
    /// [`DEFAULT_WAIT_ITERATIONS`]); at least 1.
    pub const fn wait_iterations(self, reads: u32) -> Self {
        Config {
            wait_iterations: if reads == 0 { 1 } else { reads },
            ..self
        }
    }

    /// The `CAN_BTR` value written (timing fields and the LBKM/SILM mode bits).
    pub const fn btr_value(&self) -> u32 {
        let mut v = self.btr;
        if self.loopback {
            v |= btr::LBKM;
        }
        if self.silent {
            v |= btr::SILM;
        }
        v
    }

    /// The `CAN_MCR` option bits (INRQ and SLEEP excluded).
    pub const fn mcr_options(&self) -> u32 {
        let mut v = 0;
        if let TxPolicy::Fifo = self.tx_policy {
            v |= mcr::TXFP;
        }
        if self.rx_fifo_lock {
            v |= mcr::RFLM;
        }
        if self.one_shot {
            v |= mcr::NART;
        }
        if self.auto_wakeup {
            v |= mcr::AWUM;
        }
        if let Recovery::Automatic = self.recovery {
            v |= mcr::ABOM;
        }
        if self.timestamps {
            v |= mcr::TTCM;
        }
        if self.debug_freeze {
            v |= mcr::DBF;
        }
        v
    }

    /// The transmit policy.
    pub const fn get_tx_policy(&self) -> TxPolicy {
        self.tx_policy
    }

    /// The recovery mode.
    pub const fn get_recovery(&self) -> Recovery {
        self.recovery
    }

    /// Whether time stamps are on.
    pub const fn get_timestamps(&self) -> bool {
        self.timestamps
    }

    /// The `CAN_IER` value.
    pub const fn get_interrupts(&self) -> u32 {
        self.interrupts
    }

    /// The CAN2 start bank to write, if any.
    pub const fn get_can2_start_bank(&self) -> Option<u8> {
        self.can2_start_bank
    }

    /// The APB1 clock (Hz) the bit timing was computed from; 0 for a raw `CAN_BTR`
    /// ([`Config::from_btr`]).
    pub const fn get_clock_hz(&self) -> u32 {
        self.clock_hz
    }

    /// Whether `CAN_MCR.DBF` is set: CAN frozen while a debugger halts the core (the
    /// reset value, kept by default).
    pub const fn get_debug_freeze(&self) -> bool {
        self.debug_freeze
    }

    /// Register reads each acknowledge wait may take.
    pub const fn get_wait_iterations(&self) -> u32 {
        self.wait_iterations
    }

    /// The part ([`Config::chip`]).
    pub const fn get_chip(&self) -> &'static Chip {
        self.chip
    }
}

/// The part a [`Config`] describes unless [`Config::chip`] says otherwise: the
/// STM32F76x/F77x (CAN1 + CAN2 sharing 28 banks, CAN3 with 14), the driver's first
/// target.
pub const DEFAULT_CHIP: &Chip = &chip::STM32F76X_F77X;

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 22, item 6: the slowest and the fastest timings of the rule are accepted by
    /// every builder, and one bit per second beyond by none.
    #[test]
    fn the_rule_s_extremes_are_accepted_by_every_builder() {
        let rule = timing_rule(54_000_000);
        for t in [rule.slowest().unwrap(), rule.fastest().unwrap()] {
            let rate = t.actual_bitrate();
            let by_timing = Config::from_timing(t, DEFAULT_TOLERANCE_PPM).unwrap();
            let by_rate = Config::from_bitrate(54_000_000, rate).unwrap();
            assert_eq!(by_rate.btr_value(), by_timing.btr_value(), "{rate}");
            assert_eq!(by_rate.btr_value(), t.bxcan_btr().unwrap());
            assert!(Config::from_btr(t.bxcan_btr().unwrap()).is_ok());
        }
        let (min, max) = (rule.min_bitrate(), rule.max_bitrate());
        assert_eq!((min, max), (2_109, 18_000_000));
        assert_eq!(
            Config::from_bitrate(54_000_000, min - 1),
            Err(ConfigError::Timing(TimingError::BitrateTooLow))
        );
        assert_eq!(
            Config::from_bitrate(54_000_000, max + 1),
            Err(ConfigError::Timing(TimingError::BitrateTooHigh))
        );
        // A hand-made timing wished one bit per second below the slowest rate.
        let mut below = rule.slowest().unwrap();
        below.bitrate = min - 1;
        assert_eq!(
            Config::from_timing(below, DEFAULT_TOLERANCE_PPM),
            Err(ConfigError::Timing(TimingError::BitrateTooLow))
        );
        // A raw BTR with SJW above TS2 breaks the rule's consistency.
        let sjw4_ts2_1 = btr::SJW.val(3) | btr::TS2.val(0) | btr::TS1.val(5);
        assert!(matches!(
            Config::from_btr(sjw4_ts2_1),
            Err(ConfigError::Timing(TimingError::Inconsistent(_)))
        ));
    }

    #[test]
    fn raw_btr_is_checked() {
        assert_eq!(
            Config::from_btr(btr::LBKM),
            Err(ConfigError::BtrReservedBits)
        );
        assert_eq!(Config::from_btr(1 << 23), Err(ConfigError::BtrReservedBits));
        let c = Config::from_btr(0x001C_0005)
            .unwrap()
            .loopback(true)
            .silent(true);
        assert_eq!(c.btr_value(), 0x001C_0005 | btr::LBKM | btr::SILM);
    }

    #[test]
    fn acknowledge_waits_cover_a_frame_in_flight_at_slow_rates() {
        // 2.5 kbit/s: the longest frame in flight lasts ~76 ms; the polls (one APB1
        // cycle at least each) must last longer than that, twice over.
        let slow = Config::from_bitrate(54_000_000, 2_500).unwrap();
        let frame_ms =
            twocan_core::timing::frame_time::MAX_FRAME_IN_FLIGHT_BITS as u64 * 1000 / 2_500;
        let polls_ms = slow.get_wait_iterations() as u64 * 1000 / 54_000_000;
        assert!(
            polls_ms >= 2 * frame_ms - 1,
            "{polls_ms} ms for {frame_ms} ms"
        );
        assert_eq!(
            Config::from_bitrate(54_000_000, 500_000)
                .unwrap()
                .get_wait_iterations(),
            DEFAULT_WAIT_ITERATIONS
        );
    }

    #[test]
    fn raw_btr_waits_cover_a_frame_in_flight_at_its_own_bit_rate() {
        // The slowest encodable bit: BRP = 1024, TS1 = 16 tq, TS2 = 8 tq (25 tq).
        let slowest = btr::BRP.val(1023) | btr::TS1.val(15) | btr::TS2.val(7);
        let c = Config::from_btr(slowest).unwrap();
        assert_eq!(c.get_wait_iterations(), 2 * 191 * 1024 * 25);
        assert_eq!(c.get_wait_iterations(), 9_779_200);
        // At 54 MHz that bit rate is 54e6 / 25,600 = 2,109 bit/s: 191 bits last 90.6 ms,
        // the polls (one APB1 cycle at least each) at least 181 ms.
        let polls_us = c.get_wait_iterations() as u64 * 1_000_000 / 54_000_000;
        let frame_us = 191 * 1_000_000 * 25_600 / 54_000_000;
        assert!(polls_us >= 2 * frame_us, "{polls_us} us for {frame_us} us");
        // The same BTR as a solved 2.5 kbit/s configuration: the same bound as the solver
        // path (the rate is exact, so both count the same APB1 cycles).
        let solved = Config::from_bitrate(54_000_000, 2_500).unwrap();
        let raw = Config::from_btr(solved.btr_value()).unwrap();
        assert_eq!(raw.get_wait_iterations(), solved.get_wait_iterations());
        // A fast raw BTR keeps the default.
        assert_eq!(
            Config::from_btr(0x001C_0005).unwrap().get_wait_iterations(),
            DEFAULT_WAIT_ITERATIONS
        );
    }

    #[test]
    fn options_map_to_mcr_bits() {
        let c = Config::from_btr(0).unwrap();
        // Defaults: request order (TXFP = 1, the portable default), DBF kept as at reset.
        assert_eq!(c.mcr_options(), mcr::TXFP | mcr::DBF);
        assert_eq!(c.debug_freeze(false).mcr_options(), mcr::TXFP);
        let c = c
            .tx_policy(TxPolicy::Priority)
            .one_shot(true)
            .recovery(Recovery::Automatic)
            .rx_fifo_lock(true)
            .timestamps(true)
            .auto_wakeup(true)
            .debug_freeze(true);
        assert_eq!(
            c.mcr_options(),
            mcr::RFLM | mcr::NART | mcr::AWUM | mcr::ABOM | mcr::TTCM | mcr::DBF
        );
    }

    #[test]
    fn timing_out_of_tolerance_is_refused() {
        // 54 MHz / 500 kbit/s = 108 clocks: exact.
        assert!(Config::from_bitrate(54_000_000, 500_000).is_ok());
        // 1 bit/s cannot be reached (BRP ≤ 1024, ≤ 25 quanta): below the slowest rate,
        // the same error as on every backend.
        assert_eq!(
            Config::from_bitrate(54_000_000, 1),
            Err(ConfigError::Timing(TimingError::BitrateTooLow))
        );
        let fastest = timing_rule(54_000_000).max_bitrate();
        assert!(Config::from_bitrate(54_000_000, fastest).is_ok());
        assert_eq!(
            Config::from_bitrate(54_000_000, fastest + 1),
            Err(ConfigError::Timing(TimingError::BitrateTooHigh))
        );
        assert_eq!(
            Config::from_bitrate(54_000_000, 500_000)
                .unwrap()
                .get_clock_hz(),
            54_000_000
        );
        assert_eq!(
            Config::from_bitrate(0, 500_000),
            Err(ConfigError::Timing(TimingError::ClockZero))
        );
        assert_eq!(
            Config::can2_start_bank(Config::from_btr(0).unwrap(), 29),
            Err(ConfigError::StartBankOutOfRange)
        );
    }
}
