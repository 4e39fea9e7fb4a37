//! What one controller instance can do, as the portable API reports it
//! ([`crate::Hardware::capabilities`], [`crate::Driver::capabilities`]), and the portable
//! settings that both backends take: the bus mode ([`BusMode`]) and the bus-off recovery
//! ([`BusOffRecovery`]).
//!
//! Every figure is the one of the instance *as configured now*: the clock its bit timing
//! is computed from, the filter capacity of its current message-buffer or filter-bank
//! partition, its receive FIFO depth, whether it records time stamps.
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
//! ```

use crate::timing::{solve, Limits, Timing, TimingError, DEFAULT_TOLERANCE_PPM};

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
    /// The register ranges of the bit timing.
    pub timing_limits: Limits,
    /// Slowest bit rate reachable from [`Capabilities::clock_hz`]
    /// ([`Limits::min_bitrate`]).
    pub min_bitrate: u32,
    /// Fastest bit rate the controller accepts: reachable from
    /// [`Capabilities::clock_hz`] ([`Limits::max_bitrate`]) and, where the controller's
    /// manual has a stricter rule, allowed by it ([`Capabilities::with_max_bitrate`];
    /// FlexCAN: [`crate::timing::flexcan_rules::max_bitrate`] with the bus clock in use).
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
    /// Capabilities with the bit-rate range computed from `clock_hz` and `limits`; the
    /// other fields as given.
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
        Capabilities {
            clock_hz,
            timing_limits,
            min_bitrate: timing_limits.min_bitrate(clock_hz),
            max_bitrate: timing_limits.max_bitrate(clock_hz),
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

    /// The same capabilities with [`Capabilities::max_bitrate`] lowered to `max` (a rule
    /// of the controller's manual beyond the register ranges); a higher `max` changes
    /// nothing.
    pub const fn with_max_bitrate(mut self, max: u32) -> Self {
        if max < self.max_bitrate {
            self.max_bitrate = max;
        }
        self
    }

    /// Whether `bitrate` lies in [`Capabilities::min_bitrate`] ..=
    /// [`Capabilities::max_bitrate`].
    pub const fn bitrate_in_range(&self, bitrate: u32) -> bool {
        bitrate >= self.min_bitrate && bitrate <= self.max_bitrate
    }

    /// A bit timing for `bitrate` from this controller's clock and limits, aiming at
    /// `sample_point_permille`: [`Limits::check_bitrate`]'s errors,
    /// [`TimingError::BitrateTooHigh`] above [`Capabilities::max_bitrate`], the
    /// solver's, and [`TimingError::TooFarFromWishedBitrate`] beyond
    /// [`DEFAULT_TOLERANCE_PPM`].
    pub const fn timing_for(
        &self,
        bitrate: u32,
        sample_point_permille: u16,
    ) -> Result<Timing, TimingError> {
        if let Err(e) = self.timing_limits.check_bitrate(self.clock_hz, bitrate) {
            return Err(e);
        }
        if bitrate > self.max_bitrate {
            return Err(TimingError::BitrateTooHigh);
        }
        match solve(
            self.clock_hz,
            bitrate,
            &self.timing_limits,
            sample_point_permille,
        ) {
            Ok(t) if t.within_tolerance(DEFAULT_TOLERANCE_PPM) => Ok(t),
            Ok(_) => Err(TimingError::TooFarFromWishedBitrate),
            Err(e) => Err(e),
        }
    }
}
