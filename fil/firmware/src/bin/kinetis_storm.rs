//! Negative test of the livelock detector: an interrupt storm interleaved with SysTick.
//! IRQ 75's handler sets IRQ 75 pending again before it returns (as a line whose cause
//! is never cleared), and SysTick runs at about 1 kHz at the same priority: every
//! SysTick entry breaks the run of IRQ 75 entries, so a detector counting consecutive
//! entries of one exception never fires, but thread mode never runs again. No CAN
//! register is touched. Kinetis K66 (Teensy 3.6).
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
        print(c"kinetis-storm: SysTick running; pending IRQ 75\n");
        // SAFETY: IRQ 75 has its handler below.
        unsafe { nvic_pend(75, 0) };
        print(c"kinetis-storm: back in thread mode (wrong)\n");
        idle()
    }

    #[no_mangle]
    extern "C" fn systick() {
        TICKS.fetch_add(1, Ordering::Relaxed);
    }

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"kinetis-storm: fault\n");
        idle()
    }

    /// Pends itself again: thread mode never gets the core back.
    #[no_mangle]
    extern "C" fn irq75() {
        // SAFETY: IRQ 75 again, same priority.
        unsafe { nvic_pend(75, 0) };
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
