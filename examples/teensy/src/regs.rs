//! Addresses and bits of the Kinetis system registers the start-up code touches.
//!
//! The addresses and bit positions are the same on the K20 (K20P64M72SF1RM), the K64
//! (K64P144M120SF5RM) and the K66 (K66P144M180SF5RMV2); `tests/facts_k20.rs` and
//! `tests/facts_k66.rs` check each one against the MK20D7 and MK66F18 SVD files. Chapter names below are those of the
//! reference manuals ("WDOG", "MCG", "OSC", "SIM", "PORT", "GPIO").

/// Watchdog (WDOG chapter, "Memory map and register definition"): base address.
pub const WDOG_BASE: usize = 0x4005_2000;
/// `WDOG_STCTRLH`, 16-bit status and control register high.
pub const WDOG_STCTRLH: usize = WDOG_BASE;
/// `WDOG_UNLOCK`, 16-bit unlock register.
pub const WDOG_UNLOCK: usize = WDOG_BASE + 0x0E;
/// First word of the unlock sequence (WDOG "Unlocking and updating the watchdog").
pub const WDOG_UNLOCK_KEY1: u16 = 0xC520;
/// Second word of the unlock sequence.
pub const WDOG_UNLOCK_KEY2: u16 = 0xD928;
/// `STCTRLH.WDOGEN`, bit 0: watchdog enable.
pub const WDOG_STCTRLH_WDOGEN: u16 = 1 << 0;
/// `STCTRLH.ALLOWUPDATE`, bit 4: the write-once registers may be unlocked again.
pub const WDOG_STCTRLH_ALLOWUPDATE: u16 = 1 << 4;
/// The value written to disable the watchdog: `WDOGEN = 0`, `ALLOWUPDATE = 1`, every
/// other field 0 (as PJRC's Teensy start-up does).
pub const WDOG_STCTRLH_DISABLED: u16 = WDOG_STCTRLH_ALLOWUPDATE;

/// Multipurpose clock generator (MCG chapter): base address. 8-bit registers.
pub const MCG_BASE: usize = 0x4006_4000;
/// `MCG_C1`: CLKS, FRDIV, IREFS.
pub const MCG_C1: usize = MCG_BASE;
/// `MCG_C2`: LOCRE0, (K64/K66: FCFTRIM), RANGE0, HGO0, EREFS0, LP, IRCS.
pub const MCG_C2: usize = MCG_BASE + 0x01;
/// `MCG_C6`: LOLIE0, PLLS, CME0, VDIV0.
pub const MCG_C6: usize = MCG_BASE + 0x05;
/// `MCG_S`: LOLS0, LOCK0, PLLST, IREFST, CLKST, OSCINIT0, IRCST.
pub const MCG_S: usize = MCG_BASE + 0x06;

/// `C1.CLKS` field position (bits 7:6): 0 = FLL/PLL, 1 = internal, 2 = external reference.
pub const MCG_C1_CLKS_SHIFT: u8 = 6;
/// `C1.FRDIV` field position (bits 5:3): FLL external reference divider.
pub const MCG_C1_FRDIV_SHIFT: u8 = 3;
/// `C1.IREFS`, bit 2: FLL reference is the slow internal clock.
pub const MCG_C1_IREFS: u8 = 1 << 2;
/// `C2.RANGE0` field position (bits 5:4): 0 low, 1 high, 2 or 3 very high frequency.
pub const MCG_C2_RANGE0_SHIFT: u8 = 4;
/// `C2.EREFS0`, bit 2: external reference is an oscillator (crystal), not a clock input.
pub const MCG_C2_EREFS0: u8 = 1 << 2;
/// `C2.HGO0`, bit 3: high-gain oscillator.
pub const MCG_C2_HGO0: u8 = 1 << 3;
/// `C2` bit 6: K64/K66 `FCFTRIM` (a factory trim loaded at reset, preserved by the
/// start-up code); reserved on the K20.
pub const MCG_C2_FCFTRIM: u8 = 1 << 6;
/// `C6.PLLS`, bit 6: PLL selected.
pub const MCG_C6_PLLS: u8 = 1 << 6;
/// `S.OSCINIT0`, bit 1: the crystal oscillator completed its start-up cycles.
pub const MCG_S_OSCINIT0: u8 = 1 << 1;
/// `S.CLKST` field position (bits 3:2): clock mode status, same encoding as `C1.CLKS`.
pub const MCG_S_CLKST_SHIFT: u8 = 2;
/// `S.IREFST`, bit 4: the FLL reference is the internal clock.
pub const MCG_S_IREFST: u8 = 1 << 4;

/// System oscillator (OSC chapter): `OSC0_CR`, 8-bit control register.
pub const OSC0_CR: usize = 0x4006_5000;
/// `OSC_CR.ERCLKEN`, bit 7: OSCERCLK (the FlexCAN oscillator clock) enabled.
pub const OSC_CR_ERCLKEN: u8 = 1 << 7;
/// `OSC_CR.SC2P`, bit 3: add 2 pF load.
pub const OSC_CR_SC2P: u8 = 1 << 3;
/// `OSC_CR.SC4P`, bit 2: add 4 pF load.
pub const OSC_CR_SC4P: u8 = 1 << 2;
/// `OSC_CR.SC8P`, bit 1: add 8 pF load.
pub const OSC_CR_SC8P: u8 = 1 << 1;
/// `OSC_CR.SC16P`, bit 0: add 16 pF load.
pub const OSC_CR_SC16P: u8 = 1 << 0;

/// System integration module (SIM chapter): `SIM_SCGC5`, clock gates of the ports.
pub const SIM_SCGC5: usize = 0x4004_8038;
/// `SCGC5.PORTC`, bit 11.
pub const SIM_SCGC5_PORTC: u32 = 1 << 11;
/// `SIM_CLKDIV1`: OUTDIV1 (core, bits 31:28), OUTDIV2 (bus, 27:24), OUTDIV3 (FlexBus,
/// 23:20), OUTDIV4 (flash, 19:16); each divides MCGOUTCLK by value + 1.
pub const SIM_CLKDIV1: usize = 0x4004_8044;

/// Port C (PORT chapter): `PORTC_PCR0`; `PCRn` is at `+ 4 × n`.
pub const PORTC_PCR0: usize = 0x4004_B000;
/// `PCR.MUX` field position (bits 10:8): 1 = GPIO.
pub const PORT_PCR_MUX_SHIFT: u32 = 8;
/// `PCR.DSE`, bit 6: high drive strength.
pub const PORT_PCR_DSE: u32 = 1 << 6;
/// `PCR.SRE`, bit 2: slow slew rate.
pub const PORT_PCR_SRE: u32 = 1 << 2;

/// GPIO port C (GPIO chapter): base address (`GPIOC_PDOR`).
pub const GPIOC_BASE: usize = 0x400F_F080;
/// `GPIOC_PSOR`: set output bits.
pub const GPIOC_PSOR: usize = GPIOC_BASE + 0x04;
/// `GPIOC_PCOR`: clear output bits.
pub const GPIOC_PCOR: usize = GPIOC_BASE + 0x08;
/// `GPIOC_PTOR`: toggle output bits.
pub const GPIOC_PTOR: usize = GPIOC_BASE + 0x0C;
/// `GPIOC_PDDR`: data direction (1 = output).
pub const GPIOC_PDDR: usize = GPIOC_BASE + 0x14;
