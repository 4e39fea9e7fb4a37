//! Negative test: the CAN interrupt enabled while its cause is pending, with a handler
//! that does not clear it. bxCAN1 in loop-back + silent sends one frame from mailbox 0
//! (TSR.RQCP0, with IER.TMEIE); once it is set, IRQ 19 (CAN1_TX) is enabled. The handler
//! returns at once: the line stays asserted and the harness must report a stuck
//! interrupt.
//!
//! Register rules: RM0410 §40 (MCR.INRQ/SLEEP, MSR.INAK/SLAK, BTR.LBKM/SILM, TIxR.TXRQ,
//! TSR.RQCP0, IER.TMEIE); §5.3.13 RCC_APB1ENR.CAN1EN.
#![no_std]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod image {
    use twocan_fil_firmware::{idle, print, read32, vector_table, write32};

    vector_table!(reset, fault, 19, can1_tx);

    const RCC_APB1ENR: u32 = 0x4002_3840;
    const CAN1: u32 = 0x4000_6400;
    const MCR: u32 = CAN1;
    const MSR: u32 = CAN1 + 0x04;
    const TSR: u32 = CAN1 + 0x08;
    const IER: u32 = CAN1 + 0x14;
    const BTR: u32 = CAN1 + 0x1C;
    const TI0R: u32 = CAN1 + 0x180;
    const TDT0R: u32 = CAN1 + 0x184;
    const NVIC_ISER0: u32 = 0xE000_E100;

    fn wait(addr: u32, mask: u32, set: bool) {
        // SAFETY: a bxCAN register; bounded poll.
        for _ in 0..100_000 {
            if (unsafe { read32(addr) } & mask != 0) == set {
                return;
            }
        }
        print(c"stm32-stuck: handshake timeout\n");
        idle()
    }

    #[no_mangle]
    extern "C" fn reset() -> ! {
        // SAFETY: registers of the STM32F7, in the order RM0410 §40.4 gives.
        unsafe {
            write32(RCC_APB1ENR, read32(RCC_APB1ENR) | (1 << 25));
            write32(MCR, 1); // INRQ, SLEEP = 0
            wait(MSR, 1, true); // INAK
            wait(MSR, 2, false); // SLAK
                                 // Silent loop-back; BRP 0, TS1 12, TS2 1 (the rate does not matter here).
            write32(BTR, (1 << 31) | (1 << 30) | (1 << 20) | (12 << 16));
            write32(IER, 1); // TMEIE
            write32(MCR, 0);
            wait(MSR, 1, false);
            write32(TDT0R, 0);
            write32(TI0R, (0x123 << 21) | 1); // TXRQ
            wait(TSR, 1, true); // RQCP0
        }
        print(c"stm32-stuck: RQCP0 set; enabling IRQ 19\n");
        // SAFETY: NVIC_ISER0 bit 19 = CAN1_TX.
        unsafe { write32(NVIC_ISER0, 1 << 19) };
        print(c"stm32-stuck: back in thread mode (wrong)\n");
        idle()
    }

    /// Does not clear RQCP0: the line stays asserted.
    #[no_mangle]
    extern "C" fn can1_tx() {}

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"stm32-stuck: fault\n");
        idle()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
