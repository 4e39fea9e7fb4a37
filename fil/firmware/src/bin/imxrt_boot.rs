//! Boot image check for the Teensy 4.1 profile: the ROM finds the FlexSPI configuration
//! block and the image vector table, starts `reset` with the stack from the vector
//! table; `reset` copies code to ITCM and data to DTCM, zeroes `.bss` and an OCRAM
//! buffer, sets VTOR, runs a function from ITCM, and takes an SVCall through the vector
//! table it installed. Each step prints a line (semihosting) the harness test checks.
#![no_std]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod image {
    use core::sync::atomic::{AtomicU32, Ordering};
    use twocan_fil_firmware::{idle, imxrt_fcb, imxrt_init_memory, print, read32};

    #[link_section = ".fcb"]
    #[no_mangle]
    #[used]
    static FLEXSPI_CONFIGURATION_BLOCK: [u8; 512] = imxrt_fcb();

    core::arch::global_asm!(
        ".section .vectors,\"a\",%progbits",
        ".word __stack_top",
        ".word reset",
        ".rept 9",
        ".word fault",
        ".endr",
        ".word svcall",
        ".rept 4",
        ".word fault",
        ".endr",
    );

    /// Initialised data (copied to DTCM by `reset`).
    #[no_mangle]
    static DATA: AtomicU32 = AtomicU32::new(0x1234_5678);
    /// Zeroed data in DTCM.
    #[no_mangle]
    static BSS: AtomicU32 = AtomicU32::new(0);
    /// A buffer in OCRAM (zeroed by `reset`).
    #[link_section = ".ocram"]
    #[no_mangle]
    static OCRAM_WORD: AtomicU32 = AtomicU32::new(0);
    /// Set by the SVCall handler.
    #[no_mangle]
    static SVCALLS: AtomicU32 = AtomicU32::new(0);

    /// Runs from ITCM (placed by the linker, copied by `reset`).
    #[link_section = ".itcm.in_itcm"]
    #[no_mangle]
    #[inline(never)]
    extern "C" fn in_itcm(x: u32) -> u32 {
        x.wrapping_mul(3).wrapping_add(1)
    }

    #[no_mangle]
    extern "C" fn reset() -> ! {
        // SAFETY: first thing after reset, nothing uses a static yet.
        unsafe { imxrt_init_memory() };
        print(c"imxrt-boot: started from the IVT entry\n");
        if DATA.load(Ordering::Relaxed) == 0x1234_5678 && BSS.load(Ordering::Relaxed) == 0 {
            print(c"imxrt-boot: .data in DTCM, .bss zeroed\n");
        }
        OCRAM_WORD.store(7, Ordering::Relaxed);
        if OCRAM_WORD.load(Ordering::Relaxed) == 7 {
            print(c"imxrt-boot: OCRAM written\n");
        }
        let f: extern "C" fn(u32) -> u32 = core::hint::black_box(in_itcm);
        if (f as usize) < 0x8_0000 && f(5) == 16 {
            print(c"imxrt-boot: ran from ITCM\n");
        }
        // SAFETY: SVC 0 enters `svcall` through the table VTOR now points at.
        unsafe { core::arch::asm!("svc 0") };
        // SAFETY: SCB VTOR.
        let vtor = unsafe { read32(0xE000_ED08) };
        if SVCALLS.load(Ordering::Relaxed) == 1 && vtor & 0xFFFF_0000 == 0x6000_0000 {
            print(c"imxrt-boot: SVCall through the flash vector table\n");
        }
        idle()
    }

    #[no_mangle]
    extern "C" fn svcall() {
        SVCALLS.fetch_add(1, Ordering::Relaxed);
    }

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"imxrt-boot: fault\n");
        idle()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
