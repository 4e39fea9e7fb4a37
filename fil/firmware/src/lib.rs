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

/// The i.MX RT1062's FlexSPI configuration block (IMXRT1060RM, "System Boot",
/// "FlexSPI NOR configuration block"), 512 bytes at offset 0 of the flash, for the
/// Teensy 4.1's quad SPI NOR: tag "FCFB", version V1.4.0, read sample clock from the
/// DQS loopback, CS hold/setup 3 cycles, serial NOR, quad pads, 8 MiB, page 256 B,
/// sector 4 KiB, and look-up table sequence 0 = fast read quad I/O (0xEB, 24-bit
/// address on 4 pads, 6 dummy cycles, read on 4 pads). The harness checks the tag and
/// version; the rest follows the table for real parts and is not exercised by it.
pub const fn imxrt_fcb() -> [u8; 512] {
    let mut b = [0u8; 512];
    b = put(b, 0x000, 0x4246_4346); // tag "FCFB"
    b = put(b, 0x004, 0x5601_0400); // version
    b[0x00C] = 1; // readSampleClkSrc: loopback from DQS pad
    b[0x00D] = 3; // csHoldTime
    b[0x00E] = 3; // csSetupTime
    b[0x044] = 1; // deviceType: serial NOR
    b[0x045] = 4; // sflashPadType: quad
    b[0x046] = 1; // serialClkFreq: 30 MHz
    b = put(b, 0x050, 8 << 20); // sflashA1Size
                                // LUT sequence 0: CMD_SDR(1 pad, 0xEB) RADDR_SDR(4 pads, 24); DUMMY_SDR(4 pads, 6)
                                // READ_SDR(4 pads, 4).
    b = put(b, 0x080, 0x0A18_04EB);
    b = put(b, 0x084, 0x2604_3206);
    b = put(b, 0x1C0, 256); // pageSize
    b = put(b, 0x1C4, 4096); // sectorSize
    b
}

const fn put(mut b: [u8; 512], at: usize, v: u32) -> [u8; 512] {
    let le = v.to_le_bytes();
    b[at] = le[0];
    b[at + 1] = le[1];
    b[at + 2] = le[2];
    b[at + 3] = le[3];
    b
}

/// Copies `.itcm` and `.data` from the flash to ITCM and DTCM, zeroes `.bss` and
/// `.ocram`, and sets VTOR to the vector table in the flash (the i.MX RT1062's reset
/// handler work; symbols from `imxrt1062.ld`).
///
/// # Safety
/// i.MX RT1062 images linked with `imxrt1062.ld` only, first thing after reset, before
/// any static is used.
#[cfg(target_os = "none")]
pub unsafe fn imxrt_init_memory() {
    unsafe extern "C" {
        static __sitcm: u32;
        static __eitcm: u32;
        static __litcm: u32;
        static __sdata: u32;
        static __edata: u32;
        static __ldata: u32;
        static __sbss: u32;
        static __ebss: u32;
        static __socram: u32;
        static __eocram: u32;
        static __vectors_flash: u32;
    }
    // SAFETY: the linker script places these symbols word-aligned with start ≤ end; the
    // regions are RAM this code does not run from nor use yet.
    unsafe {
        let words = |s: *const u32, e: *const u32| (e as usize - s as usize) / 4;
        let copy = |from: *const u32, to: *const u32, end: *const u32| {
            for i in 0..words(to, end) {
                core::ptr::write_volatile((to as *mut u32).add(i), from.add(i).read_volatile());
            }
        };
        let zero = |s: *const u32, e: *const u32| {
            for i in 0..words(s, e) {
                core::ptr::write_volatile((s as *mut u32).add(i), 0);
            }
        };
        copy(&raw const __litcm, &raw const __sitcm, &raw const __eitcm);
        copy(&raw const __ldata, &raw const __sdata, &raw const __edata);
        zero(&raw const __sbss, &raw const __ebss);
        zero(&raw const __socram, &raw const __eocram);
        write32(0xE000_ED08, &raw const __vectors_flash as u32); // SCB VTOR
        core::arch::asm!("dsb", "isb", options(nostack));
    }
}

#[cfg(target_os = "none")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    idle()
}
