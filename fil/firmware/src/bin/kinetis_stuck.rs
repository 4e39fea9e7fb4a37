//! Negative test: the CAN interrupt enabled while its cause is pending, with a handler
//! that does not clear it — as firmware that unmasks the FlexCAN interrupt before its
//! driver is installed. FlexCAN0 in loop-back sends one frame from message buffer 0
//! (IFLAG1 bit 0, unmasked by IMASK1); once the flag is set, IRQ 75 ("CAN0 ORed message
//! buffer", K66) is enabled. The handler returns at once: the line stays asserted and
//! the harness must report a stuck interrupt.
//!
//! Register rules: K66 RM chapter "FlexCAN" — MCR (MDIS, FRZ, HALT, FRZACK, NOTRDY),
//! CTRL1 (LPB, CLKSRC, timing), message buffer CS codes (0x8 TX inactive, 0xC TX data).
#![no_std]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod image {
    use twocan_fil_firmware::{idle, kinetis_watchdog_off, print, read32, vector_table, write32};

    vector_table!(reset, fault, 75, can0_message);

    #[link_section = ".flash_config"]
    #[no_mangle]
    #[used]
    static FLASH_CONFIG: [u8; 16] = [
        0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFE, 0xFF, 0xFF,
        0xFF,
    ];

    const SIM_SCGC6: u32 = 0x4004_803C;
    const CAN0: u32 = 0x4002_4000;
    const MCR: u32 = CAN0;
    const CTRL1: u32 = CAN0 + 0x04;
    const IMASK1: u32 = CAN0 + 0x28;
    const IFLAG1: u32 = CAN0 + 0x30;
    const MB0_CS: u32 = CAN0 + 0x80;
    const MB0_ID: u32 = CAN0 + 0x84;
    const NVIC_ISER2: u32 = 0xE000_E108;

    fn wait(addr: u32, mask: u32, set: bool) {
        // SAFETY: a FlexCAN register; bounded poll.
        for _ in 0..100_000 {
            if (unsafe { read32(addr) } & mask != 0) == set {
                return;
            }
        }
        print(c"kinetis-stuck: handshake timeout\n");
        idle()
    }

    #[no_mangle]
    extern "C" fn reset() -> ! {
        // SAFETY: registers of the K66, in the order the FlexCAN chapter gives.
        unsafe {
            kinetis_watchdog_off();
            write32(SIM_SCGC6, read32(SIM_SCGC6) | (1 << 4));
            // Leave Disable mode into Freeze (FRZ and HALT are set out of reset).
            write32(MCR, read32(MCR) & !(1 << 31));
            wait(MCR, 1 << 24, true); // FRZACK
                                      // Loop-back, bus clock, 16 tq: PRESDIV 1, PROPSEG 7, PSEG1 3, PSEG2 3.
            write32(
                CTRL1,
                (1 << 24) | (3 << 19) | (3 << 16) | (1 << 13) | (1 << 12) | 6,
            );
            write32(MB0_CS, 0x8 << 24);
            write32(IMASK1, 1);
            // Leave Freeze.
            write32(MCR, read32(MCR) & !((1 << 30) | (1 << 28)));
            wait(MCR, 1 << 24, false);
            wait(MCR, 1 << 27, false); // NOTRDY
            write32(MB0_ID, 0x123 << 18);
            write32(MB0_CS, 0xC << 24); // TX data frame, DLC 0
            wait(IFLAG1, 1, true);
        }
        print(c"kinetis-stuck: IFLAG1 set; enabling IRQ 75\n");
        // SAFETY: NVIC_ISER2 bit 11 = IRQ 75.
        unsafe { write32(NVIC_ISER2, 1 << 11) };
        print(c"kinetis-stuck: back in thread mode (wrong)\n");
        idle()
    }

    /// Does not clear IFLAG1: the line stays asserted.
    #[no_mangle]
    extern "C" fn can0_message() {}

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"kinetis-stuck: fault\n");
        idle()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
