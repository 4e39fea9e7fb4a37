//! Negative test: a Kinetis firmware that never unlocks the watchdog. The WDOG chapter
//! of the K20/K64/K66 manuals: the first unlock word must come within the WCT (256 bus
//! clocks) after reset, else the watchdog resets the chip. The harness must report it.
#![no_std]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod image {
    use twocan_fil_firmware::{idle, print, vector_table};

    vector_table!(reset, fault, 0, fault);

    #[link_section = ".flash_config"]
    #[no_mangle]
    #[used]
    static FLASH_CONFIG: [u8; 16] = [
        0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFE, 0xFF, 0xFF,
        0xFF,
    ];

    #[no_mangle]
    extern "C" fn reset() -> ! {
        print(c"kinetis-no-wdog: running with the watchdog untouched\n");
        idle()
    }

    #[no_mangle]
    extern "C" fn fault() -> ! {
        idle()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
