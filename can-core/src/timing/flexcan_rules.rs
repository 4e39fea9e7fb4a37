//! The Kinetis FlexCAN rules on bit timing that the CTRL1 field ranges do not express
//! (K20/K64/K66 reference manuals, FlexCAN chapter, "Arbitration and matching timing"):
//!
//! - "A valid CAN bit timing must be programmed" and, as its "direct consequence", "the
//!   minimum number of time quanta per CAN bit must be 8" — the CTRL1 fields alone allow
//!   1 + 1 + 1 + 2 = 5;
//! - "There must be a minimum ratio between the peripheral clock frequency and the CAN bit
//!   rate" (table "Minimum Ratio Between Peripheral Clock Frequency and CAN Bit Rate"): the
//!   module scans every message buffer during arbitration and matching and needs that many
//!   peripheral clocks per CAN bit: 16 for 16 message buffers, with or without the Rx FIFO
//!   (17 for 32 MBs with the FIFO, 25 / 30 for 64 MBs).
//!
//! - "The peripheral clock frequency can not be smaller than the oscillator clock
//!   frequency" (the CAN clock of `CTRL1.CLKSRC = 0`, the timing's `clock_hz`).
//!
//! ACAN (§16.1) checks only the field ranges, so it accepts 5 quanta per bit (its "fastest
//! exact bit rate" of 3.2 Mbit/s from the 16 MHz clock is 5 quanta, which it reports
//! working in loop-back and self-reception mode only). [`Limits::FLEXCAN`] keeps ACAN's
//! ranges so that the solver reproduces ACAN's figures; [`rule`] is the reference
//! manual's stricter rule as a [`TimingRule`] ([`Limits::FLEXCAN_KINETIS`] and the
//! peripheral-clock ratio), which every FlexCAN entry point applies (`Settings`,
//! `begin`/`check`, `set_timing`, `set_bitrate`, the capabilities, the `can-timing`
//! tool; `docs/bit-timing.md`).

use super::limits::Limits;
use super::rule::{ManualViolation, PeripheralClockRule, TimingRule};
use super::Timing;

/// The least number of time quanta per bit the manual allows
/// ([`Limits::FLEXCAN_KINETIS`]).
pub const MIN_QUANTA_PER_BIT: u32 = Limits::FLEXCAN_KINETIS.quanta.min as u32;

/// The least number of peripheral clocks per CAN bit for `mailboxes` message buffers
/// (16, 32 or 64; other counts are rounded up to the next of these) with the Rx FIFO on
/// or off.
pub const fn min_peripheral_clocks_per_bit(mailboxes: u8, rx_fifo: bool) -> u32 {
    match (mailboxes, rx_fifo) {
        (0..=16, _) => 16,
        (17..=32, false) => 16,
        (17..=32, true) => 17,
        (_, false) => 25,
        (_, true) => 30,
    }
}

/// What a FlexCAN module with `mailboxes` message buffers, the Rx FIFO on or off, and a
/// peripheral (bus) clock of `peripheral_hz` accepts from the CAN clock `can_clock_hz`:
/// [`Limits::FLEXCAN_KINETIS`] (the CTRL1 fields, at least 8 quanta per bit) and at least
/// [`min_peripheral_clocks_per_bit`] peripheral clocks per CAN bit, the peripheral clock
/// not below the CAN clock.
pub const fn rule(
    can_clock_hz: u32,
    peripheral_hz: u32,
    mailboxes: u8,
    rx_fifo: bool,
) -> TimingRule {
    TimingRule::new(can_clock_hz, Limits::FLEXCAN_KINETIS).with_peripheral_clock(
        PeripheralClockRule {
            peripheral_hz,
            min_clocks_per_bit: min_peripheral_clocks_per_bit(mailboxes, rx_fifo),
        },
    )
}

/// The fastest bit rate the manual's rules allow from the CAN clock `can_clock_hz` and
/// the peripheral clock `peripheral_hz`: the bit rate of [`rule`]'s fastest timing
/// ([`TimingRule::max_bitrate`]), a rate the CAN clock reaches. 0 when no rate is
/// allowed (a peripheral clock below the CAN clock, or a clock of 0).
pub const fn max_bitrate(
    can_clock_hz: u32,
    peripheral_hz: u32,
    mailboxes: u8,
    rx_fifo: bool,
) -> u32 {
    rule(can_clock_hz, peripheral_hz, mailboxes, rx_fifo).max_bitrate()
}

/// The manual's rules beyond the register ranges that `timing` breaks, for a module with
/// `mailboxes` message buffers, the Rx FIFO on or off, and a peripheral (bus) clock of
/// `peripheral_hz` ([`rule`] with the timing's own clock,
/// [`TimingRule::manual_violation`]).
pub const fn check(
    timing: &Timing,
    peripheral_hz: u32,
    mailboxes: u8,
    rx_fifo: bool,
) -> Result<(), ManualViolation> {
    match rule(timing.clock_hz, peripheral_hz, mailboxes, rx_fifo).manual_violation(timing) {
        None => Ok(()),
        Some(v) => Err(v),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timing::{cia_sample_point, solve, Limits};

    fn flexcan(bitrate: u32) -> Timing {
        solve(
            16_000_000,
            bitrate,
            &Limits::FLEXCAN,
            cia_sample_point(bitrate),
        )
        .unwrap()
    }

    #[test]
    fn acan_fastest_exact_rate_breaks_the_manual_rules() {
        let t = flexcan(3_200_000);
        assert_eq!(t.quanta(), 5);
        assert_eq!(
            check(&t, 60_000_000, 16, true),
            Err(ManualViolation::TooFewQuanta { quanta: 5, min: 8 })
        );
    }

    #[test]
    fn one_megabit_needs_a_fast_enough_bus_clock() {
        let t = flexcan(1_000_000);
        assert!(t.quanta() >= 8);
        // Teensy 3.2 bus clock 48 MHz, 3.6 60 MHz: 48 and 60 clocks per bit.
        assert_eq!(check(&t, 48_000_000, 16, true), Ok(()));
        // A 16 MHz peripheral clock (the least: not below the oscillator) gives 16
        // clocks per bit, the edge; at 2 Mbit/s (8 quanta) 8, below 16.
        assert_eq!(check(&t, 16_000_000, 16, true), Ok(()));
        let two = flexcan(2_000_000);
        assert_eq!(two.quanta(), 8);
        assert_eq!(
            check(&two, 16_000_000, 16, true),
            Err(ManualViolation::TooFewPeripheralClocks {
                clocks_per_bit: 8,
                min: 16
            })
        );
        assert_eq!(check(&two, 32_000_000, 16, true), Ok(()));
        // A peripheral clock below the oscillator clock is refused first.
        assert_eq!(
            check(&t, 15_000_000, 16, true),
            Err(ManualViolation::PeripheralClockBelowCanClock {
                peripheral_hz: 15_000_000,
                can_clock_hz: 16_000_000
            })
        );
        extern crate std;
        use std::string::ToString;
        assert!(check(&two, 16_000_000, 16, true)
            .unwrap_err()
            .to_string()
            .contains("8 peripheral clocks per CAN bit"));
        assert_eq!(check(&t, 0, 16, true), Err(ManualViolation::Zero));
    }

    #[test]
    fn table_of_minimum_clocks() {
        assert_eq!(min_peripheral_clocks_per_bit(16, false), 16);
        assert_eq!(min_peripheral_clocks_per_bit(16, true), 16);
        assert_eq!(min_peripheral_clocks_per_bit(32, false), 16);
        assert_eq!(min_peripheral_clocks_per_bit(32, true), 17);
        assert_eq!(min_peripheral_clocks_per_bit(64, false), 25);
        assert_eq!(min_peripheral_clocks_per_bit(64, true), 30);
    }

    #[test]
    fn fastest_allowed_rate() {
        // 16 MHz bus: 16 clocks per bit → 1 Mbit/s (below 16 MHz / 8 quanta = 2 Mbit/s).
        assert_eq!(max_bitrate(16_000_000, 16_000_000, 16, true), 1_000_000);
        // 60 MHz bus: 3.75 Mbit/s by clocks, 2 Mbit/s by quanta.
        assert_eq!(max_bitrate(16_000_000, 60_000_000, 16, true), 2_000_000);
        // 24 MHz bus: 16 clocks allow 1.5 Mbit/s, which 16 MHz does not reach: the
        // fastest reachable is 11 CAN clocks per bit (11 × 24 ≥ 16 × 16), 1,454,545 bit/s;
        // 64 MBs with the FIFO: 30 clocks → 20 CAN clocks, 800 kbit/s.
        assert_eq!(max_bitrate(16_000_000, 24_000_000, 16, true), 1_454_545);
        assert_eq!(max_bitrate(16_000_000, 24_000_000, 64, true), 800_000);
        // A bus clock below the CAN clock allows nothing.
        assert_eq!(max_bitrate(16_000_000, 8_000_000, 16, true), 0);
        assert_eq!(max_bitrate(0, 8_000_000, 16, true), 0);
    }
}
