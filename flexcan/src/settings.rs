//! Driver settings: ACAN's `ACANSettings` (ACAN §16, table 7).
//!
//! [`Settings::new`] computes the bit timing for a wished bit rate from the 16 MHz
//! oscillator clock with twocan-core's solver ([`twocan_core::timing::solve`]) and
//! fills every other property with its table-7 default. Every field is public: change
//! what you need, then hand the settings to `begin`, which checks them all before it
//! touches the hardware.
//!
//! **One bit-timing rule.** [`crate::begin::timing_rule_in`] is what this driver
//! accepts: the CTRL1 field ranges with at least 8 quanta per bit, and the bus clocks per
//! CAN bit the message buffers in matching and arbitration need — 16 with the Kinetis
//! layout's 16 buffers, 17 or 30 with the RT1062 layout's larger tables
//! ([`twocan_core::timing::flexcan_rules::rule`], Kinetis RM and IMXRT1060RM
//! "Arbitration and matching timing"). [`Settings::new`] solves within its limits,
//! `begin` and [`crate::check`] judge the settings by it (with the settings' CAN and bus
//! clocks), and the running controller reports it in its capabilities and applies it to
//! `set_timing` and `set_bitrate`: a rate or a timing one entry point takes, they all
//! take.
//!
//! Two table-7 properties are not fields: the receive and transmit buffer sizes
//! (`mReceiveBufferSize` 32, `mTransmitBufferSize` 16) are the `RX` and `TX` const
//! generics of [`twocan_core::Driver`] ([`RECEIVE_BUFFER_SIZE`] and
//! [`TRANSMIT_BUFFER_SIZE`] are ACAN's defaults, [`crate::AcanDriver`] uses them).

use twocan_core::timing::{
    flexcan_rules, solve, Consistency, Timing, TimingRule, DEFAULT_TOLERANCE_PPM,
};
use twocan_core::BusOffRecovery;

use crate::can_clock::CanClock;
use crate::configuration::{Configuration, MESSAGE_BUFFERS};

/// The FlexCAN engine clock ACAN uses: the 16 MHz crystal oscillator of every
/// Teensy 3.x, selected by `CTRL1.CLKSRC = 0` (ACAN §16.1 bit-rate formula).
pub const CAN_CLOCK_HZ: u32 = 16_000_000;

/// The bit-timing formula behind [`crate::begin::timing_rule_in`] for the CAN clock
/// `can_clock_hz` (16 MHz on a Teensy 3.x, the clock root on the RT1062,
/// [`CanClock::hz`]) with the 16 message buffers of the Kinetis layout (`MCR.MAXMB` =
/// 15): the CTRL1 ranges, 16 bus clocks per CAN bit. `None` as bus clock: the CAN clock
/// itself.
pub(crate) const fn timing_rule_for(can_clock_hz: u32, bus_clock_hz: Option<u32>) -> TimingRule {
    timing_rule_for_buffers(can_clock_hz, bus_clock_hz, MESSAGE_BUFFERS as usize)
}

/// The formula for a module whose first `message_buffers` message buffers take part in
/// matching and arbitration (`MCR[MAXMB]` + 1): 16 bus clocks per CAN bit up to 16
/// buffers, 17 up to 32 with the Rx FIFO, 30 above (IMXRT1060RM, FlexCAN "Arbitration and
/// matching timing", table "Minimum ratio between peripheral clock frequency and CAN bit
/// rate").
pub(crate) const fn timing_rule_for_buffers(
    can_clock_hz: u32,
    bus_clock_hz: Option<u32>,
    message_buffers: usize,
) -> TimingRule {
    let bus = match bus_clock_hz {
        Some(hz) => hz,
        None => can_clock_hz,
    };
    let mbs = if message_buffers > 64 {
        64
    } else {
        message_buffers as u8
    };
    flexcan_rules::rule(can_clock_hz, bus, mbs, true)
}

/// The bit rate of the default settings (ACAN table 7: `mWhishedBitRate` 250,000).
pub const DEFAULT_BIT_RATE: u32 = 250_000;

/// The sample point the solver aims at, in per mille.
///
/// ACAN's own bit settings put the sample point at 68.75 % of a 16-quantum bit
/// (table 7: 1 + 5 + 5 of 16 quanta) and at 12 of 18 quanta for 440 kbit/s (§16.1).
/// Aiming at 687 ‰ makes the solver reproduce both decompositions exactly; it also
/// lies in the 65–80 % band §16.6 recommends.
pub const SAMPLE_POINT_PERMILLE: u16 = 687;

/// ACAN's default driver receive buffer size (table 7 `mReceiveBufferSize`, §10.1).
pub const RECEIVE_BUFFER_SIZE: usize = 32;

/// ACAN's default driver transmit buffer size (table 7 `mTransmitBufferSize`, §8.2).
pub const TRANSMIT_BUFFER_SIZE: usize = 16;

/// ACAN's default message interrupt priority (table 7 `mMessageIRQPriority`).
pub const DEFAULT_IRQ_PRIORITY: u8 = 64;

/// Default bound of every acknowledge wait (`FRZACK`, `LPMACK`, `NOTRDY`,
/// `SOFTRST`, and `ESR1.SYNCH` after leaving freeze), in register polls. At 180 MHz
/// one poll is a few tens of nanoseconds; the longest legitimate wait (freeze at the
/// end of a frame, or synchronisation after one, at 2.5 kbit/s, about 60 ms) is
/// covered with margin.
pub const DEFAULT_HANDSHAKE_POLLS: u32 = 2_000_000;

/// The fastest peripheral bus clock of the Teensy 3.x chips (K64/K66: 60 MHz): one
/// register poll lasts at least one of its cycles, so a poll count scaled by it lasts at
/// least the time it stands for.
const MAX_BUS_CLOCK_HZ: u32 = 60_000_000;

/// The acknowledge wait bound for `bit_rate`: [`DEFAULT_HANDSHAKE_POLLS`], or more when
/// a frame in flight at that rate (which a freeze request waits for) lasts longer than
/// that many polls: twice the longest frame in flight, counted in bus-clock polls.
pub const fn handshake_polls_for(bit_rate: u32) -> u32 {
    match twocan_core::timing::frame_time::frame_in_flight_wait(bit_rate, MAX_BUS_CLOCK_HZ, 2) {
        Ok(polls) if polls > DEFAULT_HANDSHAKE_POLLS as u64 => {
            if polls > u32::MAX as u64 {
                u32::MAX
            } else {
                polls as u32
            }
        }
        _ => DEFAULT_HANDSHAKE_POLLS,
    }
}

/// The driver settings (ACAN `ACANSettings`, §16; table 7 gives the defaults).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settings {
    /// The bit timing: wished bit rate (`mWhishedBitRate`), prescaler
    /// (`mBitRatePrescaler`), propagation segment (`mPropagationSegment`), phase
    /// segments 1 and 2 (`mPhaseSegment1`, `mPhaseSegment2`), resynchronisation jump
    /// width (`mRJW`) and triple sampling (`mTripleSampling`) — ACAN §16.1. Any count
    /// may be changed; [`Settings::consistency`] checks them (§16.2).
    pub timing: Timing,
    /// Largest accepted distance of the actual from the wished bit rate, in ppm
    /// (ACAN §16.1: 1,000 by default, the constructor's second argument; 0 asks for
    /// the exact rate). See [`Settings::bit_rate_close_to_wished`].
    pub tolerance_ppm: u32,
    /// Listen-only mode: `CTRL1.LOM` (ACAN §16.7.1). Default `false`.
    pub listen_only: bool,
    /// Self reception: the complement of `MCR.SRXDIS` (ACAN §16.7.2). Default `false`.
    pub self_reception: bool,
    /// Loop-back mode: `CTRL1.LPB` (ACAN §16.7.3). Default `false`.
    pub loop_back: bool,
    /// The message buffer partition (ACAN §11). Default [`Configuration::Filters12_12`].
    pub configuration: Configuration,
    /// Use the alternate Tx pin (ACAN §7, table 3). Default `false`.
    pub use_alternate_tx_pin: bool,
    /// Use the alternate Rx pin (ACAN §7, table 3). Default `false`.
    pub use_alternate_rx_pin: bool,
    /// Priority of the message interrupt, 0 highest, 255 lowest (ACAN §16.7.4,
    /// default 64). With the `rt` feature, `IrqState::start` writes it to the NVIC for
    /// every line of the instance — message, bus-off, error and the two warnings of
    /// [`crate::Irqs`] — before it unmasks them; without it the firmware sets the
    /// priorities itself ([`crate::FlexCan::message_irq_priority`] gives the value). The
    /// Kinetis NVIC implements the 4 upper bits of the byte, so 64 is level 4.
    pub message_irq_priority: u8,
    /// The Tx pin is open-drain: recessive leaves it Hi-Z (`PORTx_PCRn.ODE`, ACAN
    /// §16.7.5). Default `false`.
    pub tx_pin_open_collector: bool,
    /// The Rx pin gets its internal pull-up (`PORTx_PCRn.PE | PS`, ACAN §16.7.6).
    /// Default `false`.
    pub rx_pin_pull_up: bool,
    /// Bound of every acknowledge wait, in register polls (not in ACAN: a controller
    /// that never acknowledges, or never synchronises to the bus, ends in
    /// [`twocan_core::Error::Timeout`]). `0` (the default) derives it from the bit rate
    /// of [`Settings::timing`] as it is when `begin` runs, so a timing changed after
    /// [`Settings::new`] cannot leave a bound computed for another rate; see
    /// [`Settings::handshake_bound`].
    pub handshake_polls: u32,
    /// Also interrupt on bus errors, bus-off and the warning levels (`CTRL1.ERRMSK`,
    /// `BOFFMSK`, `TWRNMSK`, `RWRNMSK`, `MCR.WRNEN`), so that the driver's error
    /// statistics and state tracking see every event. Not in ACAN, which services the
    /// message interrupt only; default `true`. The firmware routes the error, bus-off
    /// and warning vectors of [`crate::Irqs`] to the same handler.
    pub error_interrupts: bool,
    /// The peripheral (bus) clock the module runs on, for the Kinetis manual's
    /// clocks-per-bit rule ([`twocan_core::timing::flexcan_rules`]; not in ACAN).
    /// `None` (the default) assumes the least the manual allows, the 16 MHz
    /// oscillator clock ("the peripheral clock frequency can not be smaller than the
    /// oscillator clock frequency"), which admits up to 1 Mbit/s; give the real bus
    /// clock (e.g. 48 or 60 MHz under the usual Teensy start-up code) for up to
    /// 2 Mbit/s. `begin` refuses a timing below the rule with
    /// [`crate::ConfigErrors::BIT_TIMING_FORBIDDEN`].
    pub bus_clock_hz: Option<u32>,
    /// How the module leaves bus-off (not in ACAN, which leaves `CTRL1.BOFFREC` = 0):
    /// [`BusOffRecovery::Automatic`] (default) after 128 × 11 recessive bits by itself;
    /// [`BusOffRecovery::Manual`] sets `CTRL1.BOFFREC` (Kinetis RM, CTRL1 field
    /// descriptions: "automatic recovering from Bus Off state disabled") and the module
    /// stays bus-off until [`twocan_core::Hardware::recover`].
    pub bus_off_recovery: BusOffRecovery,
    /// The protocol engine clock the timing is computed for (not in ACAN, whose boards
    /// all run on 16 MHz): [`CanClock::Oscillator16MHz`] on a Teensy 3.x (the
    /// default), the CCM clock root on a Teensy 4.x ([`Settings::with_clock`]). `begin`
    /// refuses a clock the target's chip cannot give with
    /// [`crate::ConfigErrors::CLOCK_NOT_ON_CHIP`], and on the RT1062 sets the root.
    pub can_clock: CanClock,
}

impl Default for Settings {
    /// The table-7 defaults: 250 kbit/s.
    fn default() -> Self {
        Settings::new(DEFAULT_BIT_RATE)
    }
}

impl Settings {
    /// Settings for `bit_rate` with the default tolerance of 1,000 ppm (ACAN §16.1,
    /// `ACANSettings (bitRate)`). Usable in `const` items.
    ///
    /// The timing is solved within the limits the driver accepts
    /// ([`twocan_core::timing::Limits::FLEXCAN_KINETIS`]: at least 8 quanta per bit, where ACAN's field
    /// ranges allow 5). The computation never fails: a wished rate the 16 MHz clock
    /// cannot reach within them (1 bit/s, 0, above 2 Mbit/s) gives the closest
    /// consistent timing, and [`Settings::bit_rate_close_to_wished`] is then `false` —
    /// `begin` reports it (and refuses a rate outside the range of
    /// [`crate::begin::timing_rule_in`] first).
    pub const fn new(bit_rate: u32) -> Self {
        Self::with_tolerance(bit_rate, DEFAULT_TOLERANCE_PPM)
    }

    /// Settings for `bit_rate` accepted within `tolerance_ppm` (ACAN §16.1,
    /// `ACANSettings (bitRate, tolerance)`: the tolerance does not change the
    /// computation, only the acceptance test).
    pub const fn with_tolerance(bit_rate: u32, tolerance_ppm: u32) -> Self {
        Self::with_clock_and_tolerance(bit_rate, CanClock::Oscillator16MHz, tolerance_ppm)
    }

    /// Settings for `bit_rate` from `can_clock` (a Teensy 4.x: [`CanClock::Imxrt`], e.g.
    /// [`CanClock::IMXRT_24MHZ`]), default tolerance. Usable in `const` items.
    pub const fn with_clock(bit_rate: u32, can_clock: CanClock) -> Self {
        Self::with_clock_and_tolerance(bit_rate, can_clock, DEFAULT_TOLERANCE_PPM)
    }

    /// Settings for `bit_rate` from `can_clock` accepted within `tolerance_ppm`.
    pub const fn with_clock_and_tolerance(
        bit_rate: u32,
        can_clock: CanClock,
        tolerance_ppm: u32,
    ) -> Self {
        Settings {
            can_clock,
            timing: timing_for(bit_rate, can_clock.hz()),
            tolerance_ppm,
            listen_only: false,
            self_reception: false,
            loop_back: false,
            configuration: Configuration::Filters12_12,
            use_alternate_tx_pin: false,
            use_alternate_rx_pin: false,
            message_irq_priority: DEFAULT_IRQ_PRIORITY,
            tx_pin_open_collector: false,
            rx_pin_pull_up: false,
            handshake_polls: 0,
            error_interrupts: true,
            bus_clock_hz: None,
            bus_off_recovery: BusOffRecovery::Automatic,
        }
    }

    /// The wished bit rate (ACAN `mWhishedBitRate`).
    pub const fn wished_bit_rate(&self) -> u32 {
        self.timing.bitrate
    }

    /// Whether the actual bit rate is within [`Settings::tolerance_ppm`] of the wished
    /// one (ACAN `mBitConfigurationClosedToWishedRate`, §16.1; §15.2.1 when false).
    ///
    /// ACAN stores this flag when the settings are built; here it follows the current
    /// counts, so hand-changed segments are judged too.
    pub const fn bit_rate_close_to_wished(&self) -> bool {
        self.timing.within_tolerance(self.tolerance_ppm)
    }

    /// The actual bit rate, `16 MHz / (prescaler × quanta)` rounded down (ACAN §16.3).
    /// Irrelevant when [`Settings::consistency`] reports an error.
    pub const fn actual_bit_rate(&self) -> u32 {
        self.timing.actual_bitrate()
    }

    /// The acknowledge-wait bound `begin` uses: [`Settings::handshake_polls`] when set
    /// (non-zero), else [`handshake_polls_for`] the actual bit rate of the current
    /// [`Settings::timing`] (computed here, from the final timing, never stored).
    pub const fn handshake_bound(&self) -> u32 {
        if self.handshake_polls != 0 {
            self.handshake_polls
        } else {
            handshake_polls_for(self.actual_bit_rate())
        }
    }

    /// Whether the actual bit rate is exactly the wished one (ACAN §16.4).
    pub const fn exact_bit_rate(&self) -> bool {
        self.timing.is_exact()
    }

    /// Distance of the actual from the wished bit rate in ppm (ACAN §16.5).
    pub const fn ppm_from_wished_bit_rate(&self) -> u64 {
        self.timing.ppm_from_wished()
    }

    /// Sample point in per cent of the bit from its start, the first of three samples
    /// with triple sampling (ACAN §16.6).
    pub const fn sample_point_from_bit_start(&self) -> u16 {
        self.timing.first_sample_point() / 10
    }

    /// Every violated bit-timing rule (ACAN §16.2, table 6; empty means consistent).
    /// Bits 0–10 are table 6; bits 11–13 add the rules table 6 does not list (RJW ≤
    /// phase segment 1, triple sampling with phase segment 1 ≥ 2), see
    /// [`Consistency`].
    pub const fn consistency(&self) -> Consistency {
        self.timing.consistency()
    }
}

/// The timing ACAN §16.1 describes for `bit_rate`, within the limits the driver accepts
/// ([`timing_rule_for`]'s): the closest rate from the 16 MHz clock, always consistent. Rates
/// the solver refuses (0, above 2 Mbit/s) get the slowest or fastest timing, still
/// carrying the wished rate so that the distance shows.
const fn timing_for(bit_rate: u32, clock_hz: u32) -> Timing {
    let limits = timing_rule_for(clock_hz, None).limits;
    let solvable = if bit_rate == 0 {
        1
    } else if bit_rate as u64 * limits.min_quanta() as u64 > clock_hz as u64 {
        clock_hz / limits.min_quanta()
    } else {
        bit_rate
    };
    let mut t = match solve(clock_hz, solvable, &limits, SAMPLE_POINT_PERMILLE) {
        Ok(t) => t,
        // Unreachable with the FlexCAN limits and a rate in range; keep ACAN's
        // table-7 timing rather than panic.
        Err(_) => Timing {
            clock_hz,
            bitrate: DEFAULT_BIT_RATE,
            limits,
            prescaler: 4,
            prop_seg: 5,
            phase_seg1: 5,
            phase_seg2: 5,
            sjw: 4,
            triple_sampling: false,
        },
    };
    t.bitrate = bit_rate;
    t
}

#[cfg(test)]
mod tests {
    #[test]
    fn handshake_polls_cover_a_frame_in_flight_at_slow_rates() {
        use twocan_core::timing::frame_time::MAX_FRAME_IN_FLIGHT_BITS;
        let s = Settings::new(2_500);
        let frame_ms = MAX_FRAME_IN_FLIGHT_BITS as u64 * 1000 / 2_500;
        let polls_ms = s.handshake_bound() as u64 * 1000 / MAX_BUS_CLOCK_HZ as u64;
        assert!(
            polls_ms >= 2 * frame_ms - 1,
            "{polls_ms} ms for {frame_ms} ms"
        );
        assert_eq!(
            Settings::new(500_000).handshake_bound(),
            DEFAULT_HANDSHAKE_POLLS
        );
    }

    #[test]
    fn handshake_bound_follows_a_timing_changed_after_new() {
        // Built for 500 kbit/s, then given the 2.5 kbit/s timing: the bound is the slow
        // rate's (2 × 191 bits × 60 MHz / 2,500 = 9,168,000 polls), not the default.
        let mut s = Settings::new(500_000);
        assert_eq!(s.handshake_bound(), DEFAULT_HANDSHAKE_POLLS);
        s.timing = Settings::new(2_500).timing;
        assert_eq!(s.actual_bit_rate(), 2_500);
        assert_eq!(s.handshake_bound(), 9_168_000);
        // A bound set by hand is kept whatever the timing.
        s.handshake_polls = 1_000;
        assert_eq!(s.handshake_bound(), 1_000);
    }

    use super::*;

    #[test]
    fn table_7_defaults() {
        let s = Settings::default();
        assert_eq!(s.wished_bit_rate(), 250_000);
        let t = s.timing;
        assert_eq!(
            (t.prescaler, t.prop_seg, t.phase_seg1, t.phase_seg2, t.sjw),
            (4, 5, 5, 5, 4)
        );
        assert!(!t.triple_sampling);
        assert!(s.bit_rate_close_to_wished());
        assert!(!s.listen_only && !s.self_reception && !s.loop_back);
        assert_eq!(s.configuration, Configuration::Filters12_12);
        assert!(!s.use_alternate_tx_pin && !s.use_alternate_rx_pin);
        assert_eq!(s.message_irq_priority, 64);
        assert!(!s.tx_pin_open_collector && !s.rx_pin_pull_up);
        // Not in table 7: ACAN leaves CTRL1.BOFFREC = 0.
        assert_eq!(s.bus_off_recovery, BusOffRecovery::Automatic);
    }

    #[test]
    fn out_of_range_rates_do_not_panic() {
        for rate in [0, 1, 2_100_000, 3_200_000, 10_000_000, u32::MAX] {
            let s = Settings::new(rate);
            assert!(s.consistency().is_ok(), "{rate}");
            assert!(!s.bit_rate_close_to_wished(), "{rate}");
        }
        // The fastest exact rate within 8 quanta per bit, and the slowest.
        assert!(Settings::new(2_000_000).exact_bit_rate());
        assert!(Settings::new(2_500).exact_bit_rate());
    }

    #[test]
    fn settings_solve_within_the_rule_the_driver_applies() {
        use twocan_core::timing::Limits;
        // Every timing `new` computes has at least 8 quanta (ACAN's ranges would take 5
        // for 3.2 Mbit/s and for 15,166 bit/s, 1,055 = 211 × 5 clocks).
        for rate in [
            15_166, 125_000, 440_000, 842_000, 1_000_000, 1_600_000, 2_000_000,
        ] {
            let s = Settings::new(rate);
            assert!(s.timing.quanta() >= 8, "{rate}: {:?}", s.timing);
            assert_eq!(s.timing.limits, Limits::FLEXCAN_KINETIS);
        }
        // With a 60 MHz bus clock every one of them is accepted.
        let mut s = Settings::new(15_166);
        s.bus_clock_hz = Some(60_000_000);
        assert_eq!(
            crate::begin::timing_rule_in::<crate::layout::Kinetis>(&s, s.configuration)
                .accept(&s.timing, s.tolerance_ppm),
            Ok(())
        );
    }
}
