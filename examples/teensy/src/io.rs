//! Register access by absolute address, so that the clock, LED and start-up sequences are
//! written once and run on the chip ([`Mmio`]) or against a host fake in the tests.

/// 8-, 16- and 32-bit register access at absolute addresses.
pub trait Io {
    /// Reads an 8-bit register.
    fn read8(&mut self, addr: usize) -> u8;
    /// Writes an 8-bit register.
    fn write8(&mut self, addr: usize, value: u8);
    /// Writes a 16-bit register.
    fn write16(&mut self, addr: usize, value: u16);
    /// Reads a 32-bit register.
    fn read32(&mut self, addr: usize) -> u32;
    /// Writes a 32-bit register.
    fn write32(&mut self, addr: usize, value: u32);

    /// Read-modify-write of a 32-bit register (not atomic).
    fn modify32(&mut self, addr: usize, f: impl FnOnce(u32) -> u32) {
        let v = self.read32(addr);
        self.write32(addr, f(v));
    }
}

/// Volatile access to the memory-mapped registers of the chip.
#[derive(Debug)]
pub struct Mmio {
    _private: (),
}

impl Mmio {
    /// Access to the system registers of [`crate::regs`].
    ///
    /// # Safety
    /// Only on a Kinetis K20/K64/K66, and only the start-up code of this crate may use the
    /// registers of [`crate::regs`] (clock generator, oscillator, SIM dividers and clock
    /// gates, port C pin 5): nothing else may write them while this value lives.
    pub const unsafe fn new() -> Self {
        Mmio { _private: () }
    }
}

impl Io for Mmio {
    #[inline(always)]
    fn read8(&mut self, addr: usize) -> u8 {
        // SAFETY: `Mmio::new`'s contract: `addr` is one of the byte registers of
        // `crate::regs`, readable at any time.
        unsafe { core::ptr::read_volatile(addr as *const u8) }
    }

    #[inline(always)]
    fn write8(&mut self, addr: usize, value: u8) {
        // SAFETY: as for `read8`; this value owns the register.
        unsafe { core::ptr::write_volatile(addr as *mut u8, value) }
    }

    #[inline(always)]
    fn write16(&mut self, addr: usize, value: u16) {
        // SAFETY: as for `read8`; `addr` is a 16-bit aligned register (WDOG).
        unsafe { core::ptr::write_volatile(addr as *mut u16, value) }
    }

    #[inline(always)]
    fn read32(&mut self, addr: usize) -> u32 {
        // SAFETY: as for `read8`; `addr` is a 32-bit aligned register.
        unsafe { core::ptr::read_volatile(addr as *const u32) }
    }

    #[inline(always)]
    fn write32(&mut self, addr: usize, value: u32) {
        // SAFETY: as for `read32`; this value owns the register.
        unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
    }
}
