//! What one controller instance can do, as the portable API reports it
//! ([`crate::Hardware::capabilities`], [`crate::Driver::capabilities`]), and the portable
//! settings that both backends take: the bus mode ([`BusMode`]) and the bus-off recovery
//! ([`BusOffRecovery`]).
//!
//! Every figure is the one of the instance *as configured now*: the clock its bit timing
//! is computed from, the filter capacity of its current message-buffer or filter-bank
//! partition, its receive FIFO depth, whether it records time stamps.
//!
//! The bit-timing figures are exactly what the controller accepts: they come from its
//! [`TimingRule`] ([`Capabilities::timing_rule`]), the one rule
//! [`crate::Hardware::set_timing`], [`crate::Driver::set_bitrate`] and the backends'
//! configuration entry points apply. [`Capabilities::fastest_timing`] and
//! [`Capabilities::slowest_timing`] are accepted by all of them, and
//! [`Capabilities::min_bitrate`] ..= [`Capabilities::max_bitrate`] are their bit rates
//! (rounded down); a wished rate one bit per second beyond is refused.
//!
//! ```
//! use twocan_core::mock::MockHardware;
//! use twocan_core::{BusMode, Driver, Hardware};
//!
//! let can: Driver<MockHardware, 8, 4> = Driver::new(MockHardware::new(3));
//! let caps = can.capabilities();
//! assert_eq!(caps.tx_mailboxes, 3);
//! assert!(caps.modes.supports(BusMode::LoopBack));
//! assert!(caps.min_bitrate <= 125_000 && 1_000_000 <= caps.max_bitrate);
//! let fastest = caps.fastest_timing().unwrap();
//! assert_eq!(fastest.actual_bitrate(), caps.max_bitrate);
//! assert_eq!(caps.check_timing(&fastest), Ok(()));
//! ```

use crate::timing::{
    Limits, PeripheralClockRule, Timing, TimingError, TimingRule, DEFAULT_TOLERANCE_PPM,
};

/// The bus modes of a running controller, chosen while it is stopped
/// ([`crate::Hardware::set_bus_mode`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BusMode {
    /// Sends and receives on the bus, acknowledges frames.
    #[default]
    Normal,
    /// Receives only: never drives the bus (no acknowledge, no error flag, no frame);
    /// transmission is refused with [`crate::Error::WrongMode`] (FlexCAN `CTRL1.LOM`,
    /// bxCAN `CAN_BTR.SILM`).
    ListenOnly,
    /// Internal loop-back: the node receives its own frames and acknowledges them itself
    /// (FlexCAN `CTRL1.LPB`, bxCAN `CAN_BTR.LBKM`).
    LoopBack,
}

/// How a controller leaves bus-off. Both need 128 occurrences of 11 consecutive recessive
/// bits on the bus (ISO 11898-1 §12.1.4.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BusOffRecovery {
    /// The controller starts the recovery sequence by itself (FlexCAN `CTRL1.BOFFREC` =
    /// 0, bxCAN `CAN_MCR.ABOM` = 1). [`crate::Hardware::recover`] is refused with
    /// [`crate::Error::WrongMode`].
    #[default]
    Automatic,
    /// The controller stays bus-off until software calls [`crate::Hardware::recover`]
    /// (FlexCAN `CTRL1.BOFFREC` = 1, bxCAN `CAN_MCR.ABOM` = 0).
    Manual,
}

/// The optional modes and features a controller offers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ModeSupport {
    /// [`BusMode::LoopBack`].
    pub loop_back: bool,
    /// [`BusMode::ListenOnly`].
    pub listen_only: bool,
    /// One transmission attempt per frame, no automatic retransmission.
    pub one_shot: bool,
    /// Three samples per bit ([`crate::timing::Timing::triple_sampling`]).
    pub triple_sampling: bool,
    /// [`BusOffRecovery::Manual`].
    pub manual_recovery: bool,
    /// Receive and transmit time stamps.
    pub timestamps: bool,
}

impl ModeSupport {
    /// Whether `mode` can be set ([`BusMode::Normal`] always can).
    pub const fn supports(&self, mode: BusMode) -> bool {
        match mode {
            BusMode::Normal => true,
            BusMode::ListenOnly => self.listen_only,
            BusMode::LoopBack => self.loop_back,
        }
    }
}

/// What one controller instance can do, as configured now.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Capabilities {
    /// The CAN clock the bit timing is computed from, Hz (FlexCAN on a Teensy 3.x: the
    /// 16 MHz oscillator; bxCAN: the APB1 clock it was configured with).
    pub clock_hz: u32,
    /// The register ranges of the bit timing and the quanta per bit the controller
    /// accepts (FlexCAN: [`Limits::FLEXCAN_KINETIS`], 8..=25 quanta, the Kinetis
    /// manual's rule; bxCAN: [`Limits::BXCAN`]).
    pub timing_limits: Limits,
    /// The manual's minimum ratio between a peripheral clock and the bit rate, where
    /// the controller has one (FlexCAN: 16 bus clocks per bit, with the bus clock
    /// `begin` was given, [`crate::timing::flexcan_rules::rule`]); part of
    /// [`Capabilities::timing_rule`].
    pub peripheral_clock: Option<PeripheralClockRule>,
    /// The bit rate of the slowest accepted timing, rounded down
    /// ([`TimingRule::min_bitrate`]): the slowest wished rate accepted.
    pub min_bitrate: u32,
    /// The bit rate of the fastest accepted timing, rounded down
    /// ([`TimingRule::max_bitrate`]): the fastest wished rate accepted (FlexCAN: with
    /// the Kinetis manual's rules and the bus clock in use).
    pub max_bitrate: u32,
    /// The optional modes offered.
    pub modes: ModeSupport,
    /// Filters of one exact standard identifier the current configuration always holds,
    /// whatever the identifiers (the worst case: none merge into a mask entry). More
    /// may fit when identifiers merge; planning the list for the controller is the
    /// exact check (bxCAN `Can::plan`, FlexCAN `planner::plan`: `Ok`, or an error with
    /// the counts).
    pub max_standard_filters: u16,
    /// Filters of one exact extended identifier the current configuration always holds
    /// (the worst case, as [`Capabilities::max_standard_filters`]).
    pub max_extended_filters: u16,
    /// Transmit mailboxes.
    pub tx_mailboxes: u8,
    /// Hardware receive queues (FIFOs).
    pub rx_queues: u8,
    /// Frames one hardware receive FIFO holds.
    pub rx_fifo_depth: u8,
    /// Width of the hardware time stamps in bits, when the controller records them now.
    pub timestamp_bits: Option<u8>,
    /// Whether the controller, as configured, reports a wake-up event (a bus activity
    /// seen while asleep), which the status handler counts
    /// ([`crate::Driver::wakeups`], [`crate::State::wakeups`]). `false` from
    /// [`Capabilities::new`]; [`Capabilities::with_wakeup_events`] sets it.
    /// FlexCAN as this project configures it: no (`MCR.WAKMSK` and `MCR.SLFWAK` are never
    /// set, Kinetis RM MCR field descriptions); bxCAN: yes when `CAN_IER.WKUIE` is
    /// enabled (`CAN_MSR.WKUI`, RM0410 §40.4.3 "Sleep mode", §40.8 "Interrupts").
    pub wakeup_events: bool,
}

impl Capabilities {
    /// Capabilities with the bit-timing rule of `clock_hz` and `timing_limits` (no rule
    /// beyond the limits: [`Capabilities::with_timing_rule`] adds one) and the bit-rate
    /// range it accepts; the other fields as given.
    #[allow(clippy::too_many_arguments)]
    pub const fn new(
        clock_hz: u32,
        timing_limits: Limits,
        modes: ModeSupport,
        max_standard_filters: u16,
        max_extended_filters: u16,
        tx_mailboxes: u8,
        rx_queues: u8,
        rx_fifo_depth: u8,
        timestamp_bits: Option<u8>,
    ) -> Self {
        let rule = TimingRule::new(clock_hz, timing_limits);
        Capabilities {
            clock_hz,
            timing_limits,
            peripheral_clock: None,
            min_bitrate: rule.min_bitrate(),
            max_bitrate: rule.max_bitrate(),
            modes,
            max_standard_filters,
            max_extended_filters,
            tx_mailboxes,
            rx_queues,
            rx_fifo_depth,
            timestamp_bits,
            wakeup_events: false,
        }
    }

    /// The same capabilities with [`Capabilities::wakeup_events`] set to `on`.
    pub const fn with_wakeup_events(mut self, on: bool) -> Self {
        self.wakeup_events = on;
        self
    }

    /// The same capabilities with the bit-timing figures of `rule`: its clock, limits
    /// and peripheral-clock ratio, and the bit-rate range it accepts. A backend passes
    /// the one rule its entry points apply.
    pub const fn with_timing_rule(mut self, rule: TimingRule) -> Self {
        self.clock_hz = rule.clock_hz;
        self.timing_limits = rule.limits;
        self.peripheral_clock = rule.peripheral_clock;
        self.min_bitrate = rule.min_bitrate();
        self.max_bitrate = rule.max_bitrate();
        self
    }

    /// The controller's bit-timing rule: [`Capabilities::clock_hz`],
    /// [`Capabilities::timing_limits`], [`Capabilities::peripheral_clock`].
    pub const fn timing_rule(&self) -> TimingRule {
        TimingRule {
            clock_hz: self.clock_hz,
            limits: self.timing_limits,
            peripheral_clock: self.peripheral_clock,
        }
    }

    /// The fastest timing the controller accepts ([`TimingRule::fastest`]; its bit rate
    /// is [`Capabilities::max_bitrate`]). `None` when nothing is accepted.
    pub const fn fastest_timing(&self) -> Option<Timing> {
        self.timing_rule().fastest()
    }

    /// The slowest timing the controller accepts ([`TimingRule::slowest`]; its bit rate
    /// is [`Capabilities::min_bitrate`]). `None` when nothing is accepted.
    pub const fn slowest_timing(&self) -> Option<Timing> {
        self.timing_rule().slowest()
    }

    /// Whether a wished `bitrate` is in range ([`TimingRule::check_bitrate`]):
    /// [`Capabilities::min_bitrate`] ..= [`Capabilities::max_bitrate`].
    pub const fn bitrate_in_range(&self, bitrate: u32) -> bool {
        self.timing_rule().check_bitrate(bitrate).is_ok()
    }

    /// Whether the controller accepts `timing` ([`TimingRule::check_timing`]): what
    /// [`crate::Hardware::set_timing`] checks besides the mode.
    pub const fn check_timing(&self, timing: &Timing) -> Result<(), TimingError> {
        self.timing_rule().check_timing(timing)
    }

    /// A bit timing for `bitrate` from this controller's rule, aiming at
    /// `sample_point_permille`, within [`DEFAULT_TOLERANCE_PPM`]
    /// ([`TimingRule::timing_for`]): [`TimingError::BitrateTooHigh`] above
    /// [`Capabilities::max_bitrate`], [`TimingError::BitrateTooLow`] below
    /// [`Capabilities::min_bitrate`], the solver's errors, and
    /// [`TimingError::TooFarFromWishedBitrate`].
    pub const fn timing_for(
        &self,
        bitrate: u32,
        sample_point_permille: u16,
    ) -> Result<Timing, TimingError> {
        self.timing_rule()
            .timing_for(bitrate, sample_point_permille, DEFAULT_TOLERANCE_PPM)
    }
}
