//! Profile test for the Blue Pill (STM32F103C8, Cortex-M3, built for `thumbv7m-none-eabi`):
//! the start-up a firmware does and its CAN on the bus, by raw register writes.
//!
//! 1. Clocks (RM0008 §7.2, §7.3): two flash wait states first (§3.3.3), HSE on (the 8 MHz
//!    crystal) and wait for `HSERDY`, PLL = HSE × 9 = 72 MHz, wait for `PLLRDY`, APB1 =
//!    HCLK / 2 = 36 MHz (its maximum), SYSCLK = PLL, wait for `SWS`.
//! 2. Pins (§9.1.11, §9.3.3): AFIO, GPIOA and CAN clocks on; `CAN_REMAP` = 00: PA12
//!    (CAN_TX) alternate-function push-pull, PA11 (CAN_RX) floating input.
//! 3. CAN (§24.4, §24.7, §24.9): initialization mode, 500 kbit/s from the 36 MHz APB1
//!    (BRP + 1 = 6, 1 + 9 + 2 = 12 quanta), one filter bank accepting everything into FIFO
//!    0, `TMEIE` and `FMPIE0` with their NVIC lines 19 (`USB_HP_CAN_TX`) and 20
//!    (`USB_LP_CAN_RX0`), normal mode, one frame 0x123 sent.
//!
//! The handlers count frames sent (`SENT`) and received (`RECEIVED`, last identifier in
//! `LAST_ID`); `FAILED` holds the number of the step whose wait timed out (0: none).
#![no_std]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod image {
    use core::sync::atomic::{AtomicU32, Ordering};
    use twocan_fil_firmware::bxcan::{self, IER};
    use twocan_fil_firmware::{idle, print, read32, set_bits, wait, write32};

    core::arch::global_asm!(
        ".section .vectors,\"a\",%progbits",
        ".word __stack_top",
        ".word reset",
        ".rept 14",
        ".word fault",
        ".endr",
        ".rept 19",
        ".word fault",
        ".endr",
        ".word can_tx",  // 19: USB_HP_CAN_TX
        ".word can_rx0", // 20: USB_LP_CAN_RX0
        ".word fault",   // 21: CAN_RX1
        ".word fault",   // 22: CAN_SCE
    );

    const RCC_CR: u32 = 0x4002_1000;
    const RCC_CFGR: u32 = 0x4002_1004;
    const RCC_APB2ENR: u32 = 0x4002_1018;
    const RCC_APB1ENR: u32 = 0x4002_101C;
    const FLASH_ACR: u32 = 0x4002_2000;
    const GPIOA_CRH: u32 = 0x4001_0804;
    const CAN: u32 = 0x4000_6400;
    const NVIC_ISER0: u32 = 0xE000_E100;

    #[no_mangle]
    static SENT: AtomicU32 = AtomicU32::new(0);
    #[no_mangle]
    static RECEIVED: AtomicU32 = AtomicU32::new(0);
    #[no_mangle]
    static LAST_ID: AtomicU32 = AtomicU32::new(0);
    #[no_mangle]
    static FAILED: AtomicU32 = AtomicU32::new(0);

    fn check(ok: bool, step: u32) {
        if !ok {
            FAILED.store(step, Ordering::SeqCst);
            print(c"bluepill-can: a wait timed out\n");
            idle()
        }
    }

    #[no_mangle]
    extern "C" fn reset() -> ! {
        // SAFETY: registers of the STM32F103, in the order RM0008 gives.
        unsafe {
            write32(FLASH_ACR, 0x30 | 2); // prefetch on, LATENCY = 2
            set_bits(RCC_CR, 1 << 16); // HSEON
            check(wait(RCC_CR, 1 << 17, true), 1); // HSERDY
                                                   // PLLSRC = HSE, PLLMUL = ×9, PPRE1 = /2.
            write32(RCC_CFGR, (7 << 18) | (1 << 16) | (4 << 8));
            set_bits(RCC_CR, 1 << 24); // PLLON
            check(wait(RCC_CR, 1 << 25, true), 2); // PLLRDY
            set_bits(RCC_CFGR, 2); // SW = PLL
            check(wait(RCC_CFGR, 2 << 2, true), 3); // SWS = PLL
        }
        print(c"bluepill-can: SYSCLK 72 MHz, APB1 36 MHz\n");
        // SAFETY: as above (§9.2.2 GPIOx_CRH: 4 bits per pin, CNF[1:0] MODE[1:0]).
        unsafe {
            set_bits(RCC_APB2ENR, 1 | (1 << 2)); // AFIOEN, IOPAEN
            set_bits(RCC_APB1ENR, 1 << 25); // CANEN
            let crh = read32(GPIOA_CRH) & !0x000F_F000;
            write32(GPIOA_CRH, crh | (0xB << 16) | (0x4 << 12)); // PA12 AF PP 50 MHz, PA11 input
            check(bxcan::enter_init(CAN), 4);
            write32(CAN + bxcan::BTR, (1 << 20) | (8 << 16) | 5);
            bxcan::accept_all(CAN, 0, 0);
            write32(CAN + IER, 1 | (1 << 1)); // TMEIE, FMPIE0
            write32(NVIC_ISER0, (1 << 19) | (1 << 20));
            check(bxcan::leave_init(CAN), 5);
        }
        print(c"bluepill-can: CAN on the bus at 500 kbit/s\n");
        // SAFETY: mailbox 0 is empty after reset.
        unsafe { bxcan::send(CAN, 0x123, [1, 2, 3, 4, 0, 0, 0, 0], 4) };
        idle()
    }

    /// `USB_HP_CAN_TX`: mailbox 0 completed.
    #[no_mangle]
    extern "C" fn can_tx() {
        // SAFETY: the CAN's status register.
        if let Some(true) = unsafe { bxcan::take_tx0(CAN) } {
            SENT.fetch_add(1, Ordering::SeqCst);
        }
    }

    /// `USB_LP_CAN_RX0`: frames in FIFO 0.
    #[no_mangle]
    extern "C" fn can_rx0() {
        // SAFETY: the CAN's FIFO 0 registers.
        while let Some((id, _)) = unsafe { bxcan::receive(CAN, 0) } {
            LAST_ID.store(id, Ordering::SeqCst);
            RECEIVED.fetch_add(1, Ordering::SeqCst);
        }
    }

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"bluepill-can: fault\n");
        idle()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
