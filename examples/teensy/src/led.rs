//! The LED on pin 13 (port C bit 5 on every Teensy 3.x), for life signs and error codes.

use crate::board::LED_PORT_C_BIT;
use crate::io::Io;
use crate::regs::*;

const MASK: u32 = 1 << LED_PORT_C_BIT;

/// `PORTC_PCR5`: GPIO (MUX = 1), high drive strength, slow slew rate (PORT chapter,
/// "Pin Control Register n").
pub const PCR_VALUE: u32 = (1 << PORT_PCR_MUX_SHIFT) | PORT_PCR_DSE | PORT_PCR_SRE;

/// The LED pin, configured as an output.
#[derive(Debug)]
pub struct Led<I: Io> {
    io: I,
}

impl<I: Io> Led<I> {
    /// Gates port C's clock (SIM `SCGC5.PORTC`), muxes PTC5 to GPIO and makes it an
    /// output, LED off.
    pub fn new(mut io: I) -> Self {
        io.modify32(SIM_SCGC5, |v| v | SIM_SCGC5_PORTC);
        io.write32(PORTC_PCR0 + 4 * LED_PORT_C_BIT as usize, PCR_VALUE);
        io.write32(GPIOC_PCOR, MASK);
        io.modify32(GPIOC_PDDR, |v| v | MASK);
        Led { io }
    }

    /// Lights the LED.
    pub fn on(&mut self) {
        self.io.write32(GPIOC_PSOR, MASK);
    }

    /// Switches the LED off.
    pub fn off(&mut self) {
        self.io.write32(GPIOC_PCOR, MASK);
    }

    /// Inverts the LED.
    pub fn toggle(&mut self) {
        self.io.write32(GPIOC_PTOR, MASK);
    }

    /// Sets the LED.
    pub fn set(&mut self, on: bool) {
        if on {
            self.on()
        } else {
            self.off()
        }
    }
}
