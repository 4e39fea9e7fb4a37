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

/// As [`vector_table!`], with SysTick (exception 15) on `$systick`.
#[macro_export]
macro_rules! vector_table_systick {
    ($reset:ident, $fault:ident, $systick:ident, $irq:literal, $handler:ident) => {
        core::arch::global_asm!(
            ".section .vectors,\"a\",%progbits",
            ".word __stack_top",
            concat!(".word ", stringify!($reset)),
            ".rept 13",
            concat!(".word ", stringify!($fault)),
            ".endr",
            concat!(".word ", stringify!($systick)),
            concat!(".rept ", stringify!($irq)),
            concat!(".word ", stringify!($fault)),
            ".endr",
            concat!(".word ", stringify!($handler)),
        );
    };
}

/// SysTick at `reload + 1` core clocks per period, its interrupt enabled (ARMv7-M
/// B3.3.3: `SYST_RVR`, `SYST_CVR`, `SYST_CSR` ENABLE | TICKINT | CLKSOURCE).
///
/// # Safety
/// Changes the SysTick configuration.
pub unsafe fn systick_start(reload: u32) {
    // SAFETY: the SysTick registers of every ARMv7-M core.
    unsafe {
        write32(0xE000_E014, reload);
        write32(0xE000_E018, 0);
        write32(0xE000_E010, 0b111);
    }
}

/// Sets device interrupt `irq` pending and enabled in the NVIC at priority byte
/// `priority` (ARMv7-M B3.4: `NVIC_IPRn`, `NVIC_ISPRn`, `NVIC_ISERn`).
///
/// # Safety
/// The handler of `irq` runs as soon as the priorities allow.
pub unsafe fn nvic_pend(irq: u32, priority: u8) {
    let word = 0xE000_E400 + (irq & !3);
    let shift = 8 * (irq & 3);
    // SAFETY: the NVIC registers of every ARMv7-M core.
    unsafe {
        write32(
            word,
            (read32(word) & !(0xFF << shift)) | (u32::from(priority) << shift),
        );
        write32(0xE000_E200 + 4 * (irq / 32), 1 << (irq % 32));
        write32(0xE000_E100 + 4 * (irq / 32), 1 << (irq % 32));
    }
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

/// A bounded poll: whether `addr & mask` became non-zero (`set`) or zero (`!set`) within
/// 1,000,000 reads (several quanta of the harness at any clock the boards run).
///
/// # Safety
/// `addr` must be a readable register of the chip.
pub unsafe fn wait(addr: u32, mask: u32, set: bool) -> bool {
    for _ in 0..1_000_000 {
        // SAFETY: the caller names a register.
        if (unsafe { read32(addr) } & mask != 0) == set {
            return true;
        }
    }
    false
}

/// Sets the bits `bits` of a register (read-modify-write).
///
/// # Safety
/// `addr` must be a readable and writable register of the chip.
pub unsafe fn set_bits(addr: u32, bits: u32) {
    // SAFETY: the caller names a register.
    unsafe { write32(addr, read32(addr) | bits) }
}

/// The bxCAN register sequences the profile tests need, written from the reference
/// manuals (RM0008 §24, RM0390 §30: the same registers on the F1 and the F4). No twocan
/// API: these images stay valid whatever the driver becomes.
pub mod bxcan {
    use super::{read32, set_bits, wait, write32};

    /// `CAN_MCR`.
    pub const MCR: u32 = 0x000;
    /// `CAN_MSR`.
    pub const MSR: u32 = 0x004;
    /// `CAN_TSR`.
    pub const TSR: u32 = 0x008;
    /// `CAN_RF0R` (`CAN_RF1R` at +4).
    pub const RF0R: u32 = 0x00C;
    /// `CAN_IER`.
    pub const IER: u32 = 0x014;
    /// `CAN_BTR`.
    pub const BTR: u32 = 0x01C;
    /// `CAN_TI0R`.
    pub const TI0R: u32 = 0x180;
    /// `CAN_RI0R` (FIFO 1 at +0x10).
    pub const RI0R: u32 = 0x1B0;
    /// `CAN_FMR`.
    pub const FMR: u32 = 0x200;

    /// Initialization mode from reset or sleep (`INRQ` = 1, `SLEEP` = 0; waits for `INAK`
    /// and `SLAK` = 0, RM0008 §24.4.1). False on time-out.
    ///
    /// # Safety
    /// `can` must be the base of a clocked bxCAN.
    pub unsafe fn enter_init(can: u32) -> bool {
        // SAFETY: bxCAN registers of the caller's controller.
        unsafe {
            write32(can + MCR, (read32(can + MCR) | 1) & !2);
            wait(can + MSR, 1, true) && wait(can + MSR, 2, false)
        }
    }

    /// Leaves initialization mode (`INRQ` = 0) and waits for `INAK` = 0, which takes 11
    /// recessive bits on CANRX (RM0008 §24.4.2). False on time-out.
    ///
    /// # Safety
    /// `can` must be the base of a clocked bxCAN in initialization mode.
    pub unsafe fn leave_init(can: u32) -> bool {
        // SAFETY: as above.
        unsafe {
            write32(can + MCR, read32(can + MCR) & !1);
            wait(can + MSR, 1, false)
        }
    }

    /// Filter bank `bank` of the block at `filters` (CAN1's) as a 32-bit mask filter that
    /// accepts every frame into FIFO `fifo`, active (RM0008 §24.7.4, §24.9.4).
    ///
    /// # Safety
    /// `filters` must be the base of a clocked bxCAN that owns a filter block with `bank`.
    pub unsafe fn accept_all(filters: u32, bank: u32, fifo: u32) {
        let bit = 1 << bank;
        // SAFETY: filter registers of the caller's block, in the order §24.7.4 gives.
        unsafe {
            set_bits(filters + FMR, 1); // FINIT
            set_bits(filters + 0x20C, bit); // FS1R: 32-bit
            write32(filters + 0x204, read32(filters + 0x204) & !bit); // FM1R: mask mode
            let ffa = read32(filters + 0x214) & !bit;
            write32(filters + 0x214, ffa | if fifo == 1 { bit } else { 0 });
            write32(filters + 0x240 + 8 * bank, 0);
            write32(filters + 0x244 + 8 * bank, 0);
            set_bits(filters + 0x21C, bit); // FA1R
            write32(filters + FMR, read32(filters + FMR) & !1);
        }
    }

    /// Loads transmit mailbox 0 with a standard data frame and requests it (RM0008
    /// §24.7.1).
    ///
    /// # Safety
    /// `can` must be the base of a clocked bxCAN whose mailbox 0 is empty.
    pub unsafe fn send(can: u32, id: u32, data: [u8; 8], dlc: u32) {
        // SAFETY: mailbox 0 registers of the caller's controller.
        unsafe {
            write32(can + TI0R + 4, dlc);
            write32(
                can + TI0R + 8,
                u32::from_le_bytes([data[0], data[1], data[2], data[3]]),
            );
            write32(
                can + TI0R + 12,
                u32::from_le_bytes([data[4], data[5], data[6], data[7]]),
            );
            write32(can + TI0R, (id << 21) | 1);
        }
    }

    /// The oldest frame of FIFO `fifo`, released: (standard identifier, first data word).
    ///
    /// # Safety
    /// `can` must be the base of a clocked bxCAN.
    pub unsafe fn receive(can: u32, fifo: u32) -> Option<(u32, u32)> {
        let rfr = can + RF0R + 4 * fifo;
        // SAFETY: FIFO registers of the caller's controller.
        unsafe {
            if read32(rfr) & 3 == 0 {
                return None;
            }
            let id = read32(can + RI0R + 0x10 * fifo) >> 21;
            let data = read32(can + RI0R + 0x10 * fifo + 8);
            write32(rfr, 1 << 5); // RFOM
            Some((id, data))
        }
    }

    /// Acknowledges mailbox 0's request-completed flag; whether it was sent (`TXOK0`).
    ///
    /// # Safety
    /// `can` must be the base of a clocked bxCAN.
    pub unsafe fn take_tx0(can: u32) -> Option<bool> {
        // SAFETY: CAN_TSR of the caller's controller (RQCP0 is rc_w1).
        unsafe {
            let tsr = read32(can + TSR);
            if tsr & 1 == 0 {
                return None;
            }
            write32(can + TSR, 1);
            Some(tsr & 2 != 0)
        }
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
