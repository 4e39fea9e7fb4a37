//! Profile test for the NUCLEO-F446RE (STM32F446RE, Cortex-M4F): the start-up a firmware
//! does and both CAN controllers, by raw register writes.
//!
//! 1. Clocks (RM0390 §5.1.4 "Entering Over-drive mode", §6.3): HSE in bypass (the
//!    ST-LINK's 8 MHz MCO) and wait for `HSERDY`; PLL M = 4, N = 180, P = 2 from HSE
//!    (VCO 360 MHz, 180 MHz out), `PLLON`; PWR clock, over-drive `ODEN` → `ODRDY`,
//!    `ODSWEN` → `ODSWRDY`; five flash wait states (§3.4 Table 5); APB1 = HCLK / 4 =
//!    45 MHz, APB2 = HCLK / 2 = 90 MHz (their maxima); wait for `PLLRDY`; SYSCLK = PLL,
//!    wait for `SWS`.
//! 2. Pins (§7, DS10693 Table 11): GPIOA clock, PA11/PA12 in alternate function 9
//!    (CAN1_RX/CAN1_TX).
//! 3. CAN1 (§30): 500 kbit/s from 45 MHz (BRP + 1 = 5, 1 + 13 + 4 = 18 quanta), bank 0 of
//!    the shared block accepting everything into FIFO 0, lines 19 (CAN1_TX) and 20
//!    (CAN1_RX0), one frame 0x123 sent.
//! 4. CAN2, clocked with CAN1 (it uses CAN1's filters, §30.2), in loop-back + silent mode:
//!    bank 14 (its first, `CAN2SB` = 14 at reset) accepting everything into FIFO 1, lines
//!    63 (CAN2_TX) and 65 (CAN2_RX1), one frame 0x2AA sent to itself.
//!
//! Counters: `SENT1`, `RECEIVED1` (last identifier `LAST_ID1`), `SENT2`, `RECEIVED2`
//! (`LAST_ID2`); `FAILED` holds the step whose wait timed out (0: none).
#![no_std]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod image {
    use core::sync::atomic::{AtomicU32, Ordering};
    use twocan_fil_firmware::bxcan::{self, BTR, IER};
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
        ".word can1_tx",  // 19
        ".word can1_rx0", // 20
        ".rept 42",       // 21..=62
        ".word fault",
        ".endr",
        ".word can2_tx",  // 63
        ".word fault",    // 64: CAN2_RX0
        ".word can2_rx1", // 65
        ".word fault",    // 66: CAN2_SCE
    );

    const RCC_CR: u32 = 0x4002_3800;
    const RCC_PLLCFGR: u32 = 0x4002_3804;
    const RCC_CFGR: u32 = 0x4002_3808;
    const RCC_AHB1ENR: u32 = 0x4002_3830;
    const RCC_APB1ENR: u32 = 0x4002_3840;
    const FLASH_ACR: u32 = 0x4002_3C00;
    const PWR_CR: u32 = 0x4000_7000;
    const PWR_CSR: u32 = 0x4000_7004;
    const GPIOA: u32 = 0x4002_0000;
    const CAN1: u32 = 0x4000_6400;
    const CAN2: u32 = 0x4000_6800;
    const NVIC_ISER0: u32 = 0xE000_E100;
    const NVIC_ISER1: u32 = 0xE000_E104;
    const NVIC_ISER2: u32 = 0xE000_E108;

    #[no_mangle]
    static SENT1: AtomicU32 = AtomicU32::new(0);
    #[no_mangle]
    static RECEIVED1: AtomicU32 = AtomicU32::new(0);
    #[no_mangle]
    static LAST_ID1: AtomicU32 = AtomicU32::new(0);
    #[no_mangle]
    static SENT2: AtomicU32 = AtomicU32::new(0);
    #[no_mangle]
    static RECEIVED2: AtomicU32 = AtomicU32::new(0);
    #[no_mangle]
    static LAST_ID2: AtomicU32 = AtomicU32::new(0);
    #[no_mangle]
    static FAILED: AtomicU32 = AtomicU32::new(0);

    fn check(ok: bool, step: u32) {
        if !ok {
            FAILED.store(step, Ordering::SeqCst);
            print(c"nucleo-f446re-can: a wait timed out\n");
            idle()
        }
    }

    #[no_mangle]
    extern "C" fn reset() -> ! {
        // SAFETY: registers of the STM32F446, in the order RM0390 §5.1.4 gives.
        unsafe {
            set_bits(RCC_CR, (1 << 18) | (1 << 16)); // HSEBYP, HSEON
            check(wait(RCC_CR, 1 << 17, true), 1); // HSERDY
                                                   // PLLR = 2, PLLQ = 4 (reset), PLLSRC = HSE, PLLP = /2, PLLN = 180, PLLM = 4.
            write32(
                RCC_PLLCFGR,
                (2 << 28) | (4 << 24) | (1 << 22) | (180 << 6) | 4,
            );
            set_bits(RCC_CR, 1 << 24); // PLLON
            set_bits(RCC_APB1ENR, 1 << 28); // PWREN
            set_bits(PWR_CR, 1 << 16); // ODEN
            check(wait(PWR_CSR, 1 << 16, true), 2); // ODRDY
            set_bits(PWR_CR, 1 << 17); // ODSWEN
            check(wait(PWR_CSR, 1 << 17, true), 3); // ODSWRDY
            write32(FLASH_ACR, (1 << 9) | (1 << 8) | 5); // ICEN, PRFTEN, LATENCY = 5
            write32(RCC_CFGR, (4 << 13) | (5 << 10)); // PPRE2 = /2, PPRE1 = /4
            check(wait(RCC_CR, 1 << 25, true), 4); // PLLRDY
            set_bits(RCC_CFGR, 2); // SW = PLL
            check(wait(RCC_CFGR, 2 << 2, true), 5); // SWS = PLL
        }
        print(c"nucleo-f446re-can: SYSCLK 180 MHz, APB1 45 MHz\n");
        // SAFETY: GPIOA and bxCAN registers of the STM32F446 (RM0390 §7.4, §30.9).
        unsafe {
            set_bits(RCC_AHB1ENR, 1); // GPIOAEN
            set_bits(RCC_APB1ENR, (1 << 25) | (1 << 26)); // CAN1EN, CAN2EN
            let moder = read32(GPIOA) & !(0xF << 22);
            write32(GPIOA, moder | (0b1010 << 22)); // PA11, PA12: alternate function
            let afrh = read32(GPIOA + 0x24) & !0x000F_F000;
            write32(GPIOA + 0x24, afrh | 0x0009_9000); // AF9
            check(bxcan::enter_init(CAN1), 6);
            check(bxcan::enter_init(CAN2), 7);
            write32(CAN1 + BTR, (3 << 20) | (12 << 16) | 4);
            write32(
                CAN2 + BTR,
                (1 << 31) | (1 << 30) | (3 << 20) | (12 << 16) | 4,
            );
            bxcan::accept_all(CAN1, 0, 0);
            bxcan::accept_all(CAN1, 14, 1);
            write32(CAN1 + IER, 1 | (1 << 1)); // TMEIE, FMPIE0
            write32(CAN2 + IER, 1 | (1 << 4)); // TMEIE, FMPIE1
            write32(NVIC_ISER0, (1 << 19) | (1 << 20));
            write32(NVIC_ISER1, 1 << (63 - 32));
            write32(NVIC_ISER2, 1 << (65 - 64));
            check(bxcan::leave_init(CAN1), 8);
            check(bxcan::leave_init(CAN2), 9);
        }
        print(c"nucleo-f446re-can: CAN1 on the bus at 500 kbit/s, CAN2 in loop-back\n");
        // SAFETY: mailbox 0 of each controller is empty after reset.
        unsafe {
            bxcan::send(CAN1, 0x123, [1, 2, 3, 4, 0, 0, 0, 0], 4);
            bxcan::send(CAN2, 0x2AA, [5, 6, 0, 0, 0, 0, 0, 0], 2);
        }
        idle()
    }

    fn sent(can: u32, counter: &AtomicU32) {
        // SAFETY: the controller's status register.
        if let Some(true) = unsafe { bxcan::take_tx0(can) } {
            counter.fetch_add(1, Ordering::SeqCst);
        }
    }

    fn received(can: u32, fifo: u32, counter: &AtomicU32, last: &AtomicU32) {
        // SAFETY: the controller's FIFO registers.
        while let Some((id, _)) = unsafe { bxcan::receive(can, fifo) } {
            last.store(id, Ordering::SeqCst);
            counter.fetch_add(1, Ordering::SeqCst);
        }
    }

    #[no_mangle]
    extern "C" fn can1_tx() {
        sent(CAN1, &SENT1);
    }

    #[no_mangle]
    extern "C" fn can1_rx0() {
        received(CAN1, 0, &RECEIVED1, &LAST_ID1);
    }

    #[no_mangle]
    extern "C" fn can2_tx() {
        sent(CAN2, &SENT2);
    }

    #[no_mangle]
    extern "C" fn can2_rx1() {
        received(CAN2, 1, &RECEIVED2, &LAST_ID2);
    }

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"nucleo-f446re-can: fault\n");
        idle()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
