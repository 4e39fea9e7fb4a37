//! Board facts: the part, oscillator, clocks, CAN pins and LED of each board, in one
//! place. The part's own facts (instances, banks, lines, APB1 limit, pins it can route)
//! are `twocan_bxcan::chip`'s; a board picks among them.
//!
//! Sources: RM0008 §9.3.3 (F1 CAN remap), DS5319 (STM32F103x8) pinout; DS10693
//! (STM32F446) Table 11, AF9; the boards' user manuals (UM1724 for the NUCLEO-64; the
//! Blue Pill's schematic: 8 MHz crystal, LED on PC13 to 3.3 V, USB on PA11/PA12).

use twocan_bxcan::chip::{self, CanPins, Chip, Pin};

/// One board.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Board {
    /// Feature name.
    pub name: &'static str,
    /// The microcontroller, as probe-rs names it (`--chip`).
    pub probe_chip: &'static str,
    /// The part's bxCAN facts.
    pub chip: &'static Chip,
    /// HSE frequency.
    pub hse_hz: u32,
    /// HSE is an external clock (bypass) rather than a crystal.
    pub hse_bypass: bool,
    /// SYSCLK the examples ask for.
    pub sysclk_hz: u32,
    /// APB1 clock (bxCAN's clock) the examples ask for: the part's maximum.
    pub apb1_hz: u32,
    /// CAN1's pins (the F103's `CAN`).
    pub can1: CanPins,
    /// CAN2's pins, on a dual-CAN part.
    pub can2: Option<CanPins>,
    /// The user LED.
    pub led: Pin,
    /// The LED lights when its pin is low (the Blue Pill's PC13 drives its cathode).
    pub led_active_low: bool,
    /// The `app` example's node number and its peer's (`twocan_app::App::new`): the
    /// three-board bus of `docs/firmware.md` has the Teensy `app` as node 1, the
    /// NUCLEO-F446RE as node 2 (peer 1) and the Blue Pill as node 3 (peer 2), so that no
    /// two boards send the same identifiers.
    pub app: (u8, u8),
}

/// The pin pair of `instance` on `chip` that a board uses, by index into the part's
/// table (`chip::CanInstance::pins`).
const fn pins(chip: &Chip, instance: twocan_bxcan::regs::Instance, index: usize) -> CanPins {
    match chip.instance(instance) {
        Some(c) => c.pins[index],
        None => panic!("the part has no such instance"),
    }
}

impl Board {
    /// Blue Pill (STM32F103C8T6, 48 pins): 8 MHz crystal; SYSCLK 72 MHz (HSE × 9), APB1
    /// 36 MHz (RM0008 §7.2: its maximum). CAN on PB8 (RX) / PB9 (TX), `CAN_REMAP` = 10
    /// (RM0008 §9.3.3): PA11/PA12 are the USB connector's D−/D+, and PD0/PD1 are not
    /// bonded out on the 48-pin package. LED on PC13, lit when low. USB is not used:
    /// CAN and USB share their SRAM (RM0008 §24.2), and the start-up takes the USB
    /// singleton out of the program's reach.
    pub const BLUEPILL: Board = Board {
        name: "bluepill",
        probe_chip: "STM32F103C8",
        chip: &chip::STM32F103,
        hse_hz: 8_000_000,
        hse_bypass: false,
        sysclk_hz: 72_000_000,
        apb1_hz: 36_000_000,
        can1: pins(&chip::STM32F103, twocan_bxcan::regs::Instance::Can1, 1),
        can2: None,
        led: Pin {
            port: 'C',
            number: 13,
        },
        led_active_low: true,
        app: (3, 2),
    };

    /// NUCLEO-F446RE (MB1136): HSE = the ST-LINK's 8 MHz MCO output, in bypass (UM1724
    /// §6.7.1, default solder bridges); SYSCLK 90 MHz, APB1 45 MHz (DS10693 §6.3.1: its
    /// maximum; 90 MHz needs no over-drive). CAN1 on PA11 (RX) / PA12 (TX) (morpho CN10
    /// pins 14 and 12), CAN2 on PB12 (RX) / PB13 (TX) (CN10 pins 16 and 30), both AF9.
    /// LD2 on PA5, lit when high.
    pub const NUCLEO_F446RE: Board = Board {
        name: "nucleo-f446re",
        probe_chip: "STM32F446RETx",
        chip: &chip::STM32F446,
        hse_hz: 8_000_000,
        hse_bypass: true,
        sysclk_hz: 90_000_000,
        apb1_hz: 45_000_000,
        can1: pins(&chip::STM32F446, twocan_bxcan::regs::Instance::Can1, 0),
        can2: Some(pins(
            &chip::STM32F446,
            twocan_bxcan::regs::Instance::Can2,
            0,
        )),
        led: Pin {
            port: 'A',
            number: 5,
        },
        led_active_low: false,
        app: (2, 1),
    };

    /// Every board.
    pub const ALL: [Board; 2] = [Board::BLUEPILL, Board::NUCLEO_F446RE];

    /// The examples' configuration at `bitrate` from the APB1 clock `apb1_hz` the HAL
    /// set, for this board's part (its APB1 limit, its instances and banks:
    /// [`twocan_bxcan::Config::chip`]).
    pub const fn config(
        &self,
        apb1_hz: u32,
        bitrate: u32,
    ) -> Result<twocan_bxcan::Config, twocan_bxcan::ConfigError> {
        match twocan_bxcan::Config::from_bitrate(apb1_hz, bitrate) {
            Ok(c) => c.chip(self.chip),
            Err(e) => Err(e),
        }
    }
}

/// The board this firmware is built for.
#[cfg(feature = "bluepill")]
pub const BOARD: Board = Board::BLUEPILL;
/// The board this firmware is built for.
#[cfg(feature = "nucleo-f446re")]
pub const BOARD: Board = Board::NUCLEO_F446RE;

/// Planner options for CAN1's banks as the examples find them: 14 on both parts — the
/// F103's whole block, and the F446's banks below `CAN2SB` at its reset value 14 (RM0390
/// §30.9.4; `can1-can2` keeps that split). The examples plan at build time
/// (`twocan_bxcan::const_plan!`): the run-time planner's working memory (about 90 KB)
/// does not fit the F103C8's 20 KiB of RAM.
pub const CAN1_BANKS: twocan_bxcan::PlanOptions =
    twocan_bxcan::PlanOptions::new(twocan_bxcan::chip::SINGLE_BLOCK_BANKS as u8);

/// Bit rate of the examples that talk over a bus (as the other families' `app`).
#[cfg(not(feature = "bus-250k"))]
pub const BIT_RATE: u32 = 500_000;
/// Bit rate of the examples that talk over a bus: 250 kbit/s with the `bus-250k`
/// feature (a board at the wrong rate for `can-fil`'s negative test).
#[cfg(feature = "bus-250k")]
pub const BIT_RATE: u32 = 250_000;

#[cfg(test)]
mod tests {
    use super::*;
    use twocan_bxcan::chip::PinMux;
    use twocan_bxcan::regs::Instance;

    #[test]
    fn each_board_s_clock_and_pins_fit_its_part() {
        for b in Board::ALL {
            assert!(b.chip.clock_allowed(b.apb1_hz), "{}", b.name);
            assert_eq!(b.sysclk_hz % b.apb1_hz, 0, "{}", b.name);
            for rate in [125_000, 250_000, BIT_RATE, 1_000_000] {
                assert!(b.config(b.apb1_hz, rate).is_ok(), "{} {rate}", b.name);
            }
            // Above the part's APB1 limit the configuration is refused.
            assert_eq!(
                b.config(2 * b.chip.apb1_max_hz, 500_000),
                Err(twocan_bxcan::ConfigError::ClockAboveChipLimit)
            );
            assert_eq!(b.can2.is_some(), b.chip.has(Instance::Can2), "{}", b.name);
        }
        assert_eq!(Board::BLUEPILL.can1.mux, PinMux::F1CanRemap(0b10));
        assert_eq!(Board::NUCLEO_F446RE.can1.mux, PinMux::Af(9));
        assert_eq!(
            Board::NUCLEO_F446RE.can2.map(|p| p.mux),
            Some(PinMux::Af(9))
        );
        assert_eq!(
            (Board::BLUEPILL.can1.rx.port, Board::BLUEPILL.can1.rx.number),
            ('B', 8)
        );
        assert!(Board::BLUEPILL.chip.sram_shared_with_usb);
    }
}
