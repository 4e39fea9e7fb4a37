//! Board facts: oscillator, CAN pins and LED of each board, in one place.
//!
//! Pins and alternate functions: STM32F767xx/STM32F746xx data sheets, "Alternate
//! function mapping" (CAN1_RX/TX and CAN2_RX/TX are AF9 on every pin used here), as also
//! listed by stm32f7xx-hal's `can` module (PA11/PA12, PB8/PB9, PB5/PB6, PB12/PB13) and
//! RM0410 §40 / twocan-bxcan's `instance` docs (PD0/PD1). Board routing: the boards'
//! user manuals (UM1974 NUCLEO-144, UM1907 32F746G-DISCOVERY).

/// A GPIO pin: port letter and number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pin {
    /// Port letter (`'A'` ... `'K'`).
    pub port: char,
    /// Pin number 0–15.
    pub number: u8,
}

const fn pin(port: char, number: u8) -> Pin {
    Pin { port, number }
}

/// The RX and TX pins of one bxCAN instance and their alternate function.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CanPins {
    /// CANx_RX.
    pub rx: Pin,
    /// CANx_TX.
    pub tx: Pin,
    /// Alternate function number (AF9 for CAN1 and CAN2).
    pub af: u8,
}

/// One board.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Board {
    /// Feature name.
    pub name: &'static str,
    /// The microcontroller, as probe-rs names it (`--chip`).
    pub probe_chip: &'static str,
    /// HSE frequency.
    pub hse_hz: u32,
    /// HSE is an external clock (bypass) rather than a crystal.
    pub hse_bypass: bool,
    /// SYSCLK the examples ask for.
    pub sysclk_hz: u32,
    /// APB1 clock (bxCAN's clock) the examples ask for: 54 MHz is the maximum.
    pub apb1_hz: u32,
    /// CAN1 pins.
    pub can1: CanPins,
    /// CAN2 pins, where the board has two free pins for it.
    pub can2: Option<CanPins>,
    /// The user LED (active high).
    pub led: Pin,
}

impl Board {
    /// NUCLEO-F767ZI (MB1137): HSE = the ST-LINK's 8 MHz MCO output, in bypass mode
    /// (UM1974 §6.7.1, default solder bridges); LD1 (green) on PB0. CAN1 on PD0/PD1 (Zio
    /// connector CN9, marked CAN); CAN2 on PB5/PB6 — PB13 (the other CAN2_TX) carries
    /// RMII_TXD1 to the Ethernet PHY on this board.
    pub const NUCLEO_F767ZI: Board = Board {
        name: "nucleo-f767zi",
        probe_chip: "STM32F767ZITx",
        hse_hz: 8_000_000,
        hse_bypass: true,
        sysclk_hz: 108_000_000,
        apb1_hz: 54_000_000,
        can1: CanPins {
            rx: pin('D', 0),
            tx: pin('D', 1),
            af: 9,
        },
        can2: Some(CanPins {
            rx: pin('B', 5),
            tx: pin('B', 6),
            af: 9,
        }),
        led: pin('B', 0),
    };

    /// 32F746G-DISCOVERY (MB1191): HSE = 25 MHz crystal X2; LD1 (green, also Arduino
    /// D13) on PI1. CAN1 on PB8 (RX) / PB9 (TX) = Arduino D15 / D14 (CN7). No CAN2:
    /// PB12, PB13 and PB5 are ULPI data lines of the USB HS PHY and PB6 is QUADSPI_NCS.
    pub const DISCO_F746G: Board = Board {
        name: "disco-f746g",
        probe_chip: "STM32F746NGHx",
        hse_hz: 25_000_000,
        hse_bypass: false,
        sysclk_hz: 108_000_000,
        apb1_hz: 54_000_000,
        can1: CanPins {
            rx: pin('B', 8),
            tx: pin('B', 9),
            af: 9,
        },
        can2: None,
        led: pin('I', 1),
    };

    /// Every board.
    pub const ALL: [Board; 2] = [Board::NUCLEO_F767ZI, Board::DISCO_F746G];
}

/// The board this firmware is built for.
#[cfg(feature = "nucleo-f767zi")]
pub const BOARD: Board = Board::NUCLEO_F767ZI;
/// The board this firmware is built for.
#[cfg(feature = "disco-f746g")]
pub const BOARD: Board = Board::DISCO_F746G;

/// Bit rate of the examples that talk over a bus (the `app` examples of both families
/// use the same).
#[cfg(not(feature = "bus-250k"))]
pub const BIT_RATE: u32 = 500_000;
/// Bit rate of the examples that talk over a bus: 250 kbit/s with the `bus-250k`
/// feature, a board at the wrong rate on the others' 500 kbit/s bus (`can-fil`'s
/// negative test; never flash it on a real 500 kbit/s bus).
#[cfg(feature = "bus-250k")]
pub const BIT_RATE: u32 = 250_000;

#[cfg(test)]
mod tests {
    use super::*;
    use twocan_bxcan::Config;

    #[test]
    fn the_apb1_clock_reaches_the_example_bit_rates() {
        for b in Board::ALL {
            assert!(b.apb1_hz <= 54_000_000, "RM0410 §5: APB1 ≤ 54 MHz");
            assert_eq!(b.sysclk_hz % b.apb1_hz, 0);
            for rate in [125_000, 250_000, BIT_RATE, 1_000_000] {
                assert!(
                    Config::from_bitrate(b.apb1_hz, rate).is_ok(),
                    "{} {rate}",
                    b.name
                );
            }
            assert_eq!(b.can1.af, 9);
        }
    }
}
