//! Negative test: reads FlexCAN0's `CAN0_MCR` without opening its clock gate
//! (`SIM_SCGC6.FLEXCAN0`). On the chip this is a bus error: the harness must report a
//! fault at this read's PC, taken as HardFault (BusFault is disabled out of reset).
#![no_std]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod image {
    use twocan_fil_firmware::{idle, kinetis_watchdog_off, print, read32, vector_table};

    vector_table!(reset, fault, 0, fault);

    /// Flash configuration field: no protection, not secured (FSEC = 0xFE).
    #[link_section = ".flash_config"]
    #[no_mangle]
    #[used]
    static FLASH_CONFIG: [u8; 16] = [
        0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFE, 0xFF, 0xFF,
        0xFF,
    ];

    #[no_mangle]
    extern "C" fn reset() -> ! {
        // SAFETY: first thing after reset on a Kinetis.
        unsafe { kinetis_watchdog_off() };
        print(c"kinetis-gate: reading CAN0_MCR with SIM_SCGC6.FLEXCAN0 = 0\n");
        // SAFETY: a register of the chip; the bus error is the point of this firmware.
        let mcr = unsafe { read32(0x4002_4000) };
        core::hint::black_box(mcr);
        print(c"kinetis-gate: no fault (wrong)\n");
        idle()
    }

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"kinetis-gate: fault handler\n");
        idle()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
