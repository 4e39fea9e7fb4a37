//! Clock set-up: start the 16 MHz crystal and run the chip in FBE mode from it.
//!
//! MCG chapter of the K20/K64/K66 reference manuals, "MCG modes of operation" (FEI → FBE
//! transition) and "MCG mode switching"; OSC chapter for the load capacitors and
//! `ERCLKEN`.
//!
//! After reset the chip runs in FEI mode (FLL on the 32 kHz internal reference, about
//! 21 MHz). [`init`] moves it to **FBE** (FLL bypassed, external reference): core, bus,
//! FlexBus and flash clocks all run at the crystal's 16 MHz, and OSCERCLK — the clock
//! FlexCAN uses with `CTRL1.CLKSRC = 0`, as ACAN does — is enabled.
//!
//! Why FBE and not PEE: the CAN bit timing only depends on OSCERCLK, the examples need
//! a few hundred thousand cycles per second at most, and FBE is the same sequence on the
//! three chips, whereas the PLLs differ (K20/K64: 2–4 MHz reference × 24…55; K66:
//! 8–16 MHz reference, VCO ÷ 2, and HSRUN above 120 MHz). 16 MHz also keeps the flash
//! clock (max. 25 MHz on the K20, 28 MHz on the K64/K66) and the bus clock in range with
//! every divider at 1.
//!
//! Every wait is bounded: without a crystal, [`init`] returns an error after
//! `polls` reads of `MCG_S`, switches back to FEI and leaves the caller to report it.

use crate::board::CRYSTAL_HZ;
use crate::io::Io;
use crate::regs::*;

/// `OSC0_CR`: OSCERCLK enabled, 8 pF + 2 pF = 10 pF of internal load capacitance — the
/// value PJRC's start-up code uses for the Teensy 3.x 16 MHz crystal (OSC chapter,
/// `OSC_CR` SCxP bits; the crystal's load capacitance is met with the board's strays).
pub const OSC_CR_VALUE: u8 = OSC_CR_ERCLKEN | OSC_CR_SC8P | OSC_CR_SC2P;

/// `MCG_C2` (its bit 6 is preserved): RANGE0 = 2 (very high frequency range, 8–32 MHz
/// crystals), HGO0 = 0 (low-power oscillator), EREFS0 = 1 (crystal oscillator requested).
pub const MCG_C2_VALUE: u8 = (2 << MCG_C2_RANGE0_SHIFT) | MCG_C2_EREFS0;

/// `MCG_C1` for FBE: CLKS = 2 (external reference), FRDIV = 4 (÷ 512 with RANGE0 ≠ 0:
/// 16 MHz / 512 = 31.25 kHz, inside the FLL's 31.25–39.0625 kHz reference range),
/// IREFS = 0 (FLL reference = external).
pub const MCG_C1_FBE: u8 = (2 << MCG_C1_CLKS_SHIFT) | (4 << MCG_C1_FRDIV_SHIFT);

/// `MCG_C1` reset value (FEI): CLKS = 0, FRDIV = 0, IREFS = 1.
pub const MCG_C1_FEI: u8 = MCG_C1_IREFS;

/// `SIM_CLKDIV1` in FBE: every divider ÷ 1 (core = bus = FlexBus = flash = 16 MHz).
pub const SIM_CLKDIV1_FBE: u32 = 0;

/// Reads of `MCG_S` allowed for each step. One poll is a handful of cycles, so this is
/// tens of milliseconds at the ~21 MHz reset clock: a 16 MHz crystal starts in about a
/// millisecond (data sheet `t_cst`).
pub const DEFAULT_POLLS: u32 = 200_000;

/// A step of the FEI → FBE switch that did not complete in time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClockError {
    /// `MCG_S.OSCINIT0` never set: no crystal, or it did not start.
    OscillatorTimeout,
    /// `MCG_S.IREFST` never cleared: the FLL reference did not move to the crystal.
    ReferenceSwitchTimeout,
    /// `MCG_S.CLKST` never showed the external reference.
    ClockSwitchTimeout,
}

impl ClockError {
    /// The number of blinks the examples show for this error (see `rt::halt`).
    pub const fn blink_code(self) -> u8 {
        match self {
            ClockError::OscillatorTimeout => 2,
            ClockError::ReferenceSwitchTimeout => 3,
            ClockError::ClockSwitchTimeout => 4,
        }
    }
}

/// The clock frequencies after [`init`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Clocks {
    /// Core and system clock (SysTick's clock).
    pub core_hz: u32,
    /// Bus clock.
    pub bus_hz: u32,
    /// Flash clock.
    pub flash_hz: u32,
    /// OSCERCLK: the FlexCAN protocol engine clock.
    pub can_hz: u32,
}

/// FBE from the 16 MHz crystal.
pub const FBE_CLOCKS: Clocks = Clocks {
    core_hz: CRYSTAL_HZ,
    bus_hz: CRYSTAL_HZ,
    flash_hz: CRYSTAL_HZ,
    can_hz: CRYSTAL_HZ,
};

// FlexCAN's engine clock must be the 16 MHz the backend's bit timings are computed for.
const _: () = assert!(FBE_CLOCKS.can_hz == twocan_flexcan::CAN_CLOCK_HZ);

/// A condition on `MCG_S`.
type StatusTest = fn(u8) -> bool;

/// Polls `MCG_S` until `done` holds, at most `polls` times.
fn wait<I: Io>(io: &mut I, polls: u32, done: impl Fn(u8) -> bool) -> bool {
    (0..polls).any(|_| done(io.read8(MCG_S)))
}

/// Starts the crystal and switches the MCG from FEI to FBE (order as in the reference
/// manual's mode-switch example: C2, C1, then wait on OSCINIT0, IREFST, CLKST), then sets
/// every SIM divider to 1.
///
/// On error the MCG is put back in FEI (the reset mode) and the dividers are untouched.
pub fn init<I: Io>(io: &mut I, polls: u32) -> Result<Clocks, ClockError> {
    io.write8(OSC0_CR, OSC_CR_VALUE);
    let c2 = io.read8(MCG_C2);
    io.write8(MCG_C2, (c2 & MCG_C2_FCFTRIM) | MCG_C2_VALUE);
    io.write8(MCG_C1, MCG_C1_FBE);

    let steps: [(StatusTest, ClockError); 3] = [
        (|s| s & MCG_S_OSCINIT0 != 0, ClockError::OscillatorTimeout),
        (
            |s| s & MCG_S_IREFST == 0,
            ClockError::ReferenceSwitchTimeout,
        ),
        (
            |s| (s >> MCG_S_CLKST_SHIFT) & 0b11 == 2,
            ClockError::ClockSwitchTimeout,
        ),
    ];
    for (done, error) in steps {
        if !wait(io, polls, done) {
            io.write8(MCG_C1, MCG_C1_FEI);
            return Err(error);
        }
    }
    io.write32(SIM_CLKDIV1, SIM_CLKDIV1_FBE);
    Ok(FBE_CLOCKS)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::collections::HashMap;

    /// The MCG status rules that matter here: OSCINIT0 follows a running crystal, IREFST
    /// follows C1.IREFS, CLKST follows C1.CLKS once the selected clock runs.
    struct FakeMcg {
        crystal: bool,
        regs: HashMap<usize, u32>,
        status_reads: u32,
    }

    impl FakeMcg {
        fn new(crystal: bool) -> Self {
            let mut regs = HashMap::new();
            regs.insert(MCG_C1, MCG_C1_FEI as u32);
            regs.insert(MCG_C2, 0x80 | MCG_C2_FCFTRIM as u32); // LOCRE0 + a trim bit
            regs.insert(SIM_CLKDIV1, 0x0001_0000);
            FakeMcg {
                crystal,
                regs,
                status_reads: 0,
            }
        }
        fn reg(&self, addr: usize) -> u32 {
            self.regs.get(&addr).copied().unwrap_or(0)
        }
    }

    impl Io for FakeMcg {
        fn read8(&mut self, addr: usize) -> u8 {
            if addr != MCG_S {
                return self.reg(addr) as u8;
            }
            self.status_reads += 1;
            let c1 = self.reg(MCG_C1) as u8;
            let c2 = self.reg(MCG_C2) as u8;
            let osc = self.crystal && c2 & MCG_C2_EREFS0 != 0;
            let mut s = 0;
            if osc {
                s |= MCG_S_OSCINIT0;
            }
            let irefs = c1 & MCG_C1_IREFS != 0;
            if irefs || !osc {
                s |= MCG_S_IREFST;
            }
            let clks = c1 >> MCG_C1_CLKS_SHIFT;
            let clkst = if clks == 2 && !osc { 0 } else { clks };
            s | (clkst << MCG_S_CLKST_SHIFT)
        }
        fn write8(&mut self, addr: usize, value: u8) {
            self.regs.insert(addr, value as u32);
        }
        fn write16(&mut self, addr: usize, value: u16) {
            self.regs.insert(addr, value as u32);
        }
        fn read32(&mut self, addr: usize) -> u32 {
            self.reg(addr)
        }
        fn write32(&mut self, addr: usize, value: u32) {
            self.regs.insert(addr, value);
        }
    }

    #[test]
    fn register_values() {
        assert_eq!(OSC_CR_VALUE, 0x8A);
        assert_eq!(MCG_C2_VALUE, 0x24);
        assert_eq!(MCG_C1_FBE, 0xA0);
        assert_eq!(MCG_C1_FEI, 0x04);
    }

    #[test]
    fn fei_to_fbe_with_a_crystal() {
        let mut io = FakeMcg::new(true);
        assert_eq!(init(&mut io, 10), Ok(FBE_CLOCKS));
        assert_eq!(io.reg(OSC0_CR), 0x8A);
        assert_eq!(
            io.reg(MCG_C2),
            0x24 | MCG_C2_FCFTRIM as u32,
            "LOCRE0 off, trim kept"
        );
        assert_eq!(io.reg(MCG_C1), 0xA0);
        assert_eq!(io.reg(SIM_CLKDIV1), 0);
    }

    #[test]
    fn no_crystal_is_a_bounded_error_and_falls_back_to_fei() {
        let mut io = FakeMcg::new(false);
        assert_eq!(init(&mut io, 1000), Err(ClockError::OscillatorTimeout));
        assert_eq!(io.status_reads, 1000);
        assert_eq!(io.reg(MCG_C1), MCG_C1_FEI as u32);
        assert_eq!(io.reg(SIM_CLKDIV1), 0x0001_0000, "dividers untouched");
    }
}
