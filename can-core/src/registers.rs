//! The register seam: the only way a backend touches its peripheral.
//!
//! On target it is volatile memory-mapped I/O ([`Mmio`]); on the host it is a
//! behavioural model of the peripheral. Writes take `&self`: a register write needs no
//! exclusive borrow (volatile access on target, interior mutability in a model), so the
//! split driver's contexts can share one register handle, each touching only its own
//! registers (see [`crate::hardware`]).

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

/// Volatile access to the registers at byte offsets `START..END` from a peripheral's
/// base address: the window of a register block that this handle owns.
///
/// Safe code cannot reach anything else: an offset outside the window or not 32-bit
/// aligned is never accessed (a read gives 0, a write is dropped; debug builds assert).
/// Backends use offsets that are constants of their register map, so the check is
/// folded away at compile time. The one promise is made once, `unsafe`ly, in
/// [`Mmio::new`].
///
/// A window can be split ([`Mmio::split`]) so that two owners hold disjoint parts of
/// one block — bxCAN's CAN1 control registers and the filter block it shares with CAN2.
#[derive(Debug)]
pub struct Mmio<const END: usize = 0x400, const START: usize = 0> {
    base: usize,
}

impl<const END: usize, const START: usize> Mmio<END, START> {
    /// Access to the registers `START..END` of the peripheral at `base`.
    ///
    /// # Safety
    /// `base + START .. base + END` must be registers of one peripheral that may be
    /// read and written with 32-bit accesses, and nothing else may access them while
    /// this value lives (the backends' singletons take care of that).
    pub const unsafe fn new(base: usize) -> Self {
        const {
            assert!(
                START < END && START.is_multiple_of(4) && END.is_multiple_of(4),
                "empty window"
            )
        };
        Mmio { base }
    }

    /// The base address (offsets count from it).
    pub const fn base(&self) -> usize {
        self.base
    }

    /// Whether `offset` is an aligned register of this window.
    #[inline(always)]
    pub const fn owns(offset: usize) -> bool {
        offset.is_multiple_of(4) && offset >= START && offset < END
    }

    /// Splits the window at `MID` into two owners of disjoint parts.
    pub fn split<const MID: usize>(self) -> (Mmio<MID, START>, Mmio<END, MID>) {
        const {
            assert!(
                START < MID && MID < END && MID.is_multiple_of(4),
                "split inside the window"
            )
        };
        (Mmio { base: self.base }, Mmio { base: self.base })
    }

    /// The same window with its base a constant ([`Fixed`]), when `BASE` is this
    /// window's base: the promise of [`Mmio::new`] moves to the zero-sized handle, and
    /// this value is consumed, so the registers still have one owner (a HAL hand-over
    /// that built the window from a consumed singleton gives a firmware the fixed
    /// registers this way, with no `unsafe` in the program).
    ///
    /// Errors: the window back when its base is not `BASE`.
    pub fn into_fixed<const BASE: usize>(self) -> Result<Fixed<BASE, END, START>, Self> {
        if self.base != BASE {
            return Err(self);
        }
        // SAFETY: `self` carried `Mmio::new`'s promise for `BASE + START .. BASE + END`
        // (its base is `BASE`, checked above) and is consumed here: the promise passes
        // to the one value returned.
        Ok(unsafe { Fixed::new() })
    }
}

impl<const END: usize, const START: usize> Registers for Mmio<END, START> {
    #[inline(always)]
    fn read32(&self, offset: usize) -> u32 {
        if !Self::owns(offset) {
            debug_assert!(
                false,
                "register offset {offset:#x} outside {START:#x}..{END:#x}"
            );
            return 0;
        }
        // SAFETY: `Mmio::new`'s contract covers every aligned offset of `START..END`,
        // checked just above.
        unsafe { core::ptr::read_volatile((self.base + offset) as *const u32) }
    }

    #[inline(always)]
    fn write32(&self, offset: usize, value: u32) {
        if !Self::owns(offset) {
            debug_assert!(
                false,
                "register offset {offset:#x} outside {START:#x}..{END:#x}"
            );
            return;
        }
        // SAFETY: as for `read32`; writes go to a register of the owned window.
        unsafe { core::ptr::write_volatile((self.base + offset) as *mut u32, value) }
    }
}

/// [`Mmio`] with the base address a constant (`BASE`): a zero-sized handle, so that
/// per-frame code reaches each register at an address known at compile time, with no
/// base to load (issue 21). The same window (`START..END`) and the same bounds: an
/// offset outside it or not aligned is never accessed.
#[derive(Debug)]
pub struct Fixed<const BASE: usize, const END: usize = 0x400, const START: usize = 0> {
    _owned: (),
}

impl<const BASE: usize, const END: usize, const START: usize> Fixed<BASE, END, START> {
    /// Access to the registers `START..END` of the peripheral at `BASE`.
    ///
    /// # Safety
    /// As [`Mmio::new`] with `base` = `BASE`.
    pub const unsafe fn new() -> Self {
        const {
            assert!(
                START < END && START.is_multiple_of(4) && END.is_multiple_of(4),
                "empty window"
            )
        };
        Fixed { _owned: () }
    }
}

impl<const BASE: usize, const END: usize, const START: usize> Registers
    for Fixed<BASE, END, START>
{
    #[inline(always)]
    fn read32(&self, offset: usize) -> u32 {
        if !Mmio::<END, START>::owns(offset) {
            debug_assert!(
                false,
                "register offset {offset:#x} outside {START:#x}..{END:#x}"
            );
            return 0;
        }
        // SAFETY: `Fixed::new`'s contract covers every aligned offset of `START..END`
        // from `BASE`, checked just above.
        unsafe { core::ptr::read_volatile((BASE + offset) as *const u32) }
    }

    #[inline(always)]
    fn write32(&self, offset: usize, value: u32) {
        if !Mmio::<END, START>::owns(offset) {
            debug_assert!(
                false,
                "register offset {offset:#x} outside {START:#x}..{END:#x}"
            );
            return;
        }
        // SAFETY: as for `read32`; writes go to a register of the owned window.
        unsafe { core::ptr::write_volatile((BASE + offset) as *mut u32, value) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_aligned_offsets_of_the_window_are_owned() {
        type W = Mmio<0x320, 0x200>;
        assert!(W::owns(0x200) && W::owns(0x31C));
        assert!(!W::owns(0x1FC) && !W::owns(0x320) && !W::owns(0x202));
    }

    #[test]
    fn a_window_reaches_only_its_own_memory() {
        let mut block = [0u32; 8];
        let base = block.as_mut_ptr() as usize;
        // SAFETY: the window covers the 32 bytes of `block`, used by nothing else here.
        let all: Mmio<32> = unsafe { Mmio::new(base) };
        let (low, high) = all.split::<16>();
        low.write32(4, 7);
        high.write32(20, 9);
        assert_eq!((low.read32(4), high.read32(20)), (7, 9));
        assert_eq!(block[1], 7);
        assert_eq!(block[5], 9);
    }

    #[test]
    fn a_window_becomes_fixed_only_at_its_own_base() {
        const AT: usize = 0x4000_6400;
        // SAFETY: never read or written here (a device address on the host).
        let w: Mmio<0x200> = unsafe { Mmio::new(AT) };
        let w = w.into_fixed::<0x4000_6800>().unwrap_err();
        assert_eq!(w.base(), AT, "another base: the window comes back");
        let fixed: Fixed<AT, 0x200> = w.into_fixed().map_err(|w| w.base()).unwrap();
        assert_eq!(core::mem::size_of_val(&fixed), 0);
    }
}
