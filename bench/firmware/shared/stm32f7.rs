//! STM32F7 start-up shared, byte for byte, by the STM32F7 loop-back firmwares (included
//! with `#[path]` as module `startup`), so that their size difference is the CAN driver
//! alone; can-bench leaves this module's code out of the "driver + application" flash
//! figure (`clocks` is never inlined, so its code keeps the module's symbols).
//!
//! Clock tree (RM0410 §5 "Reset and clock control"): HSI (16 MHz) → PLL with M = 8,
//! N = 108, P = 2 → SYSCLK = HCLK = 108 MHz; APB1 = HCLK / 2 = **54 MHz** (the bxCAN
//! kernel clock), APB2 = 108 MHz. 108 MHz needs 3 flash wait states (RM0410 table
//! "Number of wait states according to CPU clock frequency", 2.7–3.6 V) and no
//! over-drive. Then CAN1's clock is enabled (RCC_APB1ENR.CAN1EN). Loop-back needs no pins.

const RCC: usize = 0x4002_3800;
const RCC_CR: usize = RCC;
const RCC_PLLCFGR: usize = RCC + 0x04;
const RCC_CFGR: usize = RCC + 0x08;
const RCC_APB1ENR: usize = RCC + 0x40;
const FLASH_ACR: usize = 0x4002_3C00;

const CR_PLLON: u32 = 1 << 24;
const CR_PLLRDY: u32 = 1 << 25;
/// PLLM [5:0], PLLN [14:6], PLLP [17:16], PLLSRC [22].
const PLLCFGR_MNP_SRC: u32 = 0x3F | (0x1FF << 6) | (0b11 << 16) | (1 << 22);
const PLLCFGR_VALUE: u32 = 8 | (108 << 6); // P = 2 (0b00), source HSI (0)
const CFGR_SW: u32 = 0b11;
const CFGR_SW_PLL: u32 = 0b10;
const CFGR_SWS_SHIFT: u32 = 2;
const CFGR_HPRE_PPRE: u32 = (0xF << 4) | (0b111 << 10) | (0b111 << 13);
const CFGR_PPRE1_DIV2: u32 = 0b100 << 10;
const ACR_LATENCY: u32 = 0xF;
const ACR_LATENCY_3WS: u32 = 3;
const APB1ENR_CAN1EN: u32 = 1 << 25;

/// Bound on each clock wait (register reads).
const WAIT: u32 = 1_000_000;

fn read(addr: usize) -> u32 {
    // SAFETY: `addr` is one of the RCC / FLASH registers above, always readable.
    unsafe { core::ptr::read_volatile(addr as *const u32) }
}

fn write(addr: usize, value: u32) {
    // SAFETY: `addr` is one of the RCC / FLASH registers above; the values written are
    // those of RM0410 for the clock tree documented in the module docs.
    unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
}

fn wait(mut done: impl FnMut() -> bool) -> Result<(), ()> {
    for _ in 0..WAIT {
        if done() {
            return Ok(());
        }
    }
    Err(())
}

/// SYSCLK 108 MHz from the PLL, APB1 54 MHz, CAN1 clocked. `Err` if a clock never
/// becomes ready.
#[inline(never)]
pub fn clocks() -> Result<(), ()> {
    write(
        FLASH_ACR,
        (read(FLASH_ACR) & !ACR_LATENCY) | ACR_LATENCY_3WS,
    );
    wait(|| read(FLASH_ACR) & ACR_LATENCY == ACR_LATENCY_3WS)?;
    write(
        RCC_PLLCFGR,
        (read(RCC_PLLCFGR) & !PLLCFGR_MNP_SRC) | PLLCFGR_VALUE,
    );
    write(RCC_CR, read(RCC_CR) | CR_PLLON);
    wait(|| read(RCC_CR) & CR_PLLRDY != 0)?;
    write(
        RCC_CFGR,
        (read(RCC_CFGR) & !CFGR_HPRE_PPRE) | CFGR_PPRE1_DIV2,
    );
    write(RCC_CFGR, (read(RCC_CFGR) & !CFGR_SW) | CFGR_SW_PLL);
    wait(|| (read(RCC_CFGR) >> CFGR_SWS_SHIFT) & 0b11 == CFGR_SW_PLL)?;
    write(RCC_APB1ENR, read(RCC_APB1ENR) | APB1ENR_CAN1EN);
    // A read back lets the clock enable take effect before CAN1's registers are accessed
    // (ST errata sheets: "delay after an RCC peripheral clock enabling").
    let _ = read(RCC_APB1ENR);
    Ok(())
}
