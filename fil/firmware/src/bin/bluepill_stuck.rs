//! Negative test for the Blue Pill (STM32F103C8): the CAN transmit interrupt enabled while
//! its cause is pending, with a handler that does not clear it. The CAN in loop-back +
//! silent mode sends one frame from mailbox 0 (`TSR.RQCP0`, with `IER.TMEIE`); once it is
//! set, line 19 (`USB_HP_CAN_TX`, RM0008 §10.1.2) is enabled. The handler returns at once:
//! the line stays asserted and the harness must report a stuck interrupt. Also enables
//! the USB clock with the CAN's (RM0008 §24.2: they share one SRAM), which the profile
//! must report.
#![no_std]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod image {
    use twocan_fil_firmware::bxcan::{self, BTR, IER, MCR, TSR};
    use twocan_fil_firmware::{idle, print, read32, set_bits, vector_table, wait, write32};

    vector_table!(reset, fault, 19, can_tx);

    const RCC_APB1ENR: u32 = 0x4002_101C;
    const CAN: u32 = 0x4000_6400;
    const NVIC_ISER0: u32 = 0xE000_E100;

    #[no_mangle]
    extern "C" fn reset() -> ! {
        // SAFETY: registers of the STM32F103, in the order RM0008 §24.4 gives; the CAN
        // runs on the 8 MHz HSI (APB1 = 8 MHz).
        let ok = unsafe {
            set_bits(RCC_APB1ENR, (1 << 25) | (1 << 23)); // CANEN and USBEN
            let init = bxcan::enter_init(CAN);
            // Silent loop-back; BRP 0, TS1 12, TS2 1 (the rate does not matter here).
            write32(CAN + BTR, (1 << 31) | (1 << 30) | (1 << 20) | (12 << 16));
            write32(CAN + IER, 1); // TMEIE
            write32(CAN + MCR, read32(CAN + MCR) & !1);
            let normal = wait(CAN + 0x04, 1, false);
            bxcan::send(CAN, 0x123, [0; 8], 0);
            init && normal && wait(CAN + TSR, 1, true) // RQCP0
        };
        if !ok {
            print(c"bluepill-stuck: handshake timeout\n");
            idle()
        }
        print(c"bluepill-stuck: RQCP0 set; enabling IRQ 19\n");
        // SAFETY: NVIC_ISER0 bit 19 = USB_HP_CAN_TX.
        unsafe { write32(NVIC_ISER0, 1 << 19) };
        print(c"bluepill-stuck: back in thread mode (wrong)\n");
        idle()
    }

    /// Does not clear RQCP0: the line stays asserted.
    #[no_mangle]
    extern "C" fn can_tx() {}

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"bluepill-stuck: fault\n");
        idle()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
