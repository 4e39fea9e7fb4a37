//! Negative test: the CAN1 interrupt (IRQ 36) enabled while its cause is pending, with
//! a handler that does not clear it. CAN1 in loop-back, CAN clock root on the 24 MHz
//! oscillator (`CSCMR2[CAN_CLK_SEL]` = 1), sends one frame from MB8 (IFLAG1 bit 8,
//! unmasked by IMASK1); once the flag is set IRQ 36 is enabled and its handler returns at
//! once: the harness must report a stuck interrupt.
//!
//! Register rules: IMXRT1060RM "FLEXCAN" — the module leaves reset in Freeze mode (MCR
//! 0x5980_000F), CTRL1 (LPB, timing) and the mailboxes written in Freeze mode, HALT
//! negated to leave it; CCM `CSCMR2`.
#![no_std]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod image {
    use twocan_fil_firmware::{
        idle, imxrt_fcb, imxrt_init_memory, print, read32, vector_table, write32,
    };

    #[link_section = ".fcb"]
    #[no_mangle]
    #[used]
    static FLEXSPI_CONFIGURATION_BLOCK: [u8; 512] = imxrt_fcb();

    vector_table!(reset, fault, 36, can1);

    const CSCMR2: u32 = 0x400F_C020;
    const CAN1: u32 = 0x401D_0000;
    const MCR: u32 = CAN1;
    const CTRL1: u32 = CAN1 + 0x04;
    const IMASK1: u32 = CAN1 + 0x28;
    const IFLAG1: u32 = CAN1 + 0x30;
    const MB8_CS: u32 = CAN1 + 0x80 + 8 * 16;
    const MB8_ID: u32 = MB8_CS + 4;
    const NVIC_ISER1: u32 = 0xE000_E104;

    fn wait(addr: u32, mask: u32, set: bool) {
        for _ in 0..100_000 {
            // SAFETY: a FlexCAN register; bounded poll.
            if (unsafe { read32(addr) } & mask != 0) == set {
                return;
            }
        }
        print(c"imxrt-stuck: handshake timeout\n");
        idle()
    }

    #[no_mangle]
    extern "C" fn reset() -> ! {
        // SAFETY: registers of the RT1062 in the order the FLEXCAN chapter gives.
        unsafe {
            imxrt_init_memory();
            // CAN clock root: the 24 MHz oscillator, ÷1.
            write32(CSCMR2, (read32(CSCMR2) & !(0xFF << 2)) | (1 << 8));
            wait(MCR, 1 << 24, true); // FRZACK: in Freeze mode out of reset
                                      // Loop-back, 24 MHz, 16 tq: PRESDIV 2 (÷3 → 500 kbit/s), PROPSEG 7, PSEG1 3, PSEG2 3.
            write32(CTRL1, (2 << 24) | (3 << 19) | (3 << 16) | (1 << 12) | 6);
            for n in 0..16 {
                write32(CAN1 + 0x80 + n * 16, 0);
            }
            write32(MB8_CS, 0x8 << 24);
            write32(IMASK1, 1 << 8);
            // Leave Freeze.
            write32(MCR, read32(MCR) & !(1 << 28));
            wait(MCR, 1 << 24, false);
            wait(MCR, 1 << 27, false); // NOTRDY
            write32(MB8_ID, 0x123 << 18);
            write32(MB8_CS, 0xC << 24); // TX data frame, DLC 0
            wait(IFLAG1, 1 << 8, true);
        }
        print(c"imxrt-stuck: IFLAG1 set; enabling IRQ 36\n");
        // SAFETY: NVIC_ISER1 bit 4 = IRQ 36.
        unsafe { write32(NVIC_ISER1, 1 << 4) };
        print(c"imxrt-stuck: back in thread mode (wrong)\n");
        idle()
    }

    /// Does not clear IFLAG1: the line stays asserted.
    #[no_mangle]
    extern "C" fn can1() {}

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"imxrt-stuck: fault\n");
        idle()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
