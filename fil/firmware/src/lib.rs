//! Helpers of the negative-test firmwares: volatile register access, semihosting
//! output, and the vector table type. No dependencies, no twocan API: these images
//! stay valid whatever the driver becomes.
#![no_std]

/// The vector table: initial SP (`__stack_top` from the linker script), `reset`, every
/// other exception on `fault`, except device interrupt `$irq` (exception 16 + `$irq`)
/// on `$handler`. The linker sets the Thumb bit of each function address.
#[macro_export]
macro_rules! vector_table {
    ($reset:ident, $fault:ident, $irq:literal, $handler:ident) => {
        core::arch::global_asm!(
            ".section .vectors,\"a\",%progbits",
            ".word __stack_top",
            concat!(".word ", stringify!($reset)),
            concat!(".rept 14 + ", stringify!($irq)),
            concat!(".word ", stringify!($fault)),
            ".endr",
            concat!(".word ", stringify!($handler)),
        );
    };
}

/// Reads a 32-bit register.
///
/// # Safety
/// `addr` must be a readable register of the chip.
#[inline(always)]
pub unsafe fn read32(addr: u32) -> u32 {
    // SAFETY: the caller names a register of the chip.
    unsafe { core::ptr::read_volatile(addr as *const u32) }
}

/// Writes a 32-bit register.
///
/// # Safety
/// `addr` must be a writable register of the chip.
#[inline(always)]
pub unsafe fn write32(addr: u32, value: u32) {
    // SAFETY: the caller names a register of the chip.
    unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
}

/// Writes a 16-bit register.
///
/// # Safety
/// `addr` must be a writable 16-bit register of the chip.
#[inline(always)]
pub unsafe fn write16(addr: u32, value: u16) {
    // SAFETY: the caller names a register of the chip.
    unsafe { core::ptr::write_volatile(addr as *mut u16, value) }
}

/// Prints a NUL-terminated string through semihosting `SYS_WRITE0` (ARM semihosting
/// specification: `BKPT 0xAB`, r0 = 0x04, r1 = address).
pub fn print(text: &core::ffi::CStr) {
    #[cfg(target_os = "none")]
    // SAFETY: the semihosting call reads the string and changes only r0.
    unsafe {
        core::arch::asm!("bkpt 0xAB", inout("r0") 0x04u32 => _, in("r1") text.as_ptr(), options(nostack));
    }
    #[cfg(not(target_os = "none"))]
    let _ = text;
}

/// Sleeps forever.
pub fn idle() -> ! {
    loop {
        #[cfg(target_os = "none")]
        // SAFETY: WFI only waits for an interrupt.
        unsafe {
            core::arch::asm!("wfi", options(nomem, nostack));
        }
    }
}

/// The Kinetis watchdog off (WDOG chapter: unlock 0xC520, 0xD928 within 20 bus clocks,
/// then STCTRLH within the window).
///
/// # Safety
/// Kinetis K only, first thing after reset.
pub unsafe fn kinetis_watchdog_off() {
    // SAFETY: the WDOG registers of the K20/K64/K66.
    unsafe {
        write16(0x4005_200E, 0xC520);
        write16(0x4005_200E, 0xD928);
        write16(0x4005_2000, 0x0010);
    }
}

#[cfg(target_os = "none")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    idle()
}
