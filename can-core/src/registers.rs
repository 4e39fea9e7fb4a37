//! The register seam: the only way a backend touches its peripheral.
//!
//! On target it is volatile memory-mapped I/O at the peripheral's base address
//! ([`Mmio`]); on the host it is a behavioural model of the peripheral.

/// 32-bit register access by byte offset from the peripheral's base.
pub trait Registers {
    /// Reads the register at `offset`.
    fn read32(&self, offset: usize) -> u32;
    /// Writes `value` to the register at `offset`. Takes `&self`: a register write needs
    /// no exclusive borrow (volatile access; models use interior mutability), so the
    /// split driver's contexts can share one register handle.
    fn write32(&self, offset: usize, value: u32);

    /// Read-modify-write (not atomic: callers hold the register exclusively).
    fn modify32(&self, offset: usize, f: impl FnOnce(u32) -> u32) {
        let v = self.read32(offset);
        self.write32(offset, f(v));
    }
}

impl<R: Registers + ?Sized> Registers for &mut R {
    fn read32(&self, offset: usize) -> u32 {
        (**self).read32(offset)
    }
    fn write32(&self, offset: usize, value: u32) {
        (**self).write32(offset, value)
    }
}

impl<R: Registers + ?Sized> Registers for &R {
    fn read32(&self, offset: usize) -> u32 {
        (**self).read32(offset)
    }
    fn write32(&self, offset: usize, value: u32) {
        (**self).write32(offset, value)
    }
}

/// Volatile access to a memory-mapped peripheral.
#[derive(Debug)]
pub struct Mmio {
    base: usize,
}

impl Mmio {
    /// Access to the peripheral at `base`.
    ///
    /// # Safety
    /// `base` must be the address of a peripheral whose registers may be read and written
    /// at every offset the backend uses, and nothing else may access it while this value
    /// lives (the backends' singletons take care of that).
    pub const unsafe fn new(base: usize) -> Self {
        Mmio { base }
    }

    /// The base address.
    pub const fn base(&self) -> usize {
        self.base
    }
}

impl Registers for Mmio {
    #[inline(always)]
    fn read32(&self, offset: usize) -> u32 {
        // SAFETY: `Mmio::new`'s contract: `base + offset` is a readable, aligned register of
        // a peripheral that this value owns.
        unsafe { core::ptr::read_volatile((self.base + offset) as *const u32) }
    }

    #[inline(always)]
    fn write32(&self, offset: usize, value: u32) {
        // SAFETY: as for `read32`; writes go to a register of the owned peripheral.
        unsafe { core::ptr::write_volatile((self.base + offset) as *mut u32, value) }
    }
}
