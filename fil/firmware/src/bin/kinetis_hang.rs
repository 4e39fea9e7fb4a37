//! Negative test of the livelock detector: a handler that never returns. IRQ 75 is set
//! pending at a priority below SysTick's (0x80; SysTick keeps 0, the reset value), and
//! its handler loops forever: SysTick still preempts it and returns about every
//! millisecond, thread mode never runs again. No CAN register is touched. Kinetis K66
//! (Teensy 3.6).
#![no_std]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod image {
    use core::sync::atomic::{AtomicU32, Ordering};
    use twocan_fil_firmware::{
        idle, kinetis_watchdog_off, nvic_pend, print, systick_start, vector_table_systick,
    };

    vector_table_systick!(reset, fault, systick, 75, irq75);

    #[link_section = ".flash_config"]
    #[no_mangle]
    #[used]
    static FLASH_CONFIG: [u8; 16] = [
        0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFE, 0xFF, 0xFF,
        0xFF,
    ];

    /// SysTick entries (read by nobody: the harness counts them too).
    static TICKS: AtomicU32 = AtomicU32::new(0);

    #[no_mangle]
    extern "C" fn reset() -> ! {
        // SAFETY: the K66's watchdog first, then the core's SysTick and NVIC.
        unsafe {
            kinetis_watchdog_off();
            // About 1 kHz at the reset clock (FEI, ~21 MHz).
            systick_start(20_970);
        }
        print(c"kinetis-hang: SysTick running; pending IRQ 75\n");
        // SAFETY: IRQ 75 has its handler below.
        unsafe { nvic_pend(75, 0x80) };
        print(c"kinetis-hang: back in thread mode (wrong)\n");
        idle()
    }

    #[no_mangle]
    extern "C" fn systick() {
        TICKS.fetch_add(1, Ordering::Relaxed);
    }

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"kinetis-hang: fault\n");
        idle()
    }

    /// Never returns.
    #[no_mangle]
    extern "C" fn irq75() {
        print(c"kinetis-hang: in the IRQ 75 handler, for good\n");
        loop {
            // SAFETY: SYST_CVR, read only (a volatile access the loop cannot drop).
            let _ = unsafe { twocan_fil_firmware::read32(0xE000_E018) };
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
