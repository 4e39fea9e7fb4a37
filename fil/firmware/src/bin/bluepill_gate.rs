//! Negative test for the Blue Pill (STM32F103C8): reads the CAN's `CAN_MCR` without its
//! clock (`RCC_APB1ENR.CANEN` = 0, RM0008 §7.3.8). The STM32 answers without a bus error
//! (the read gives 0); the harness must report the access as a fault with this read's PC.
#![no_std]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod image {
    use twocan_fil_firmware::{idle, print, read32, vector_table};

    vector_table!(reset, fault, 0, fault);

    #[no_mangle]
    extern "C" fn reset() -> ! {
        print(c"bluepill-gate: reading CAN_MCR with RCC_APB1ENR.CANEN = 0\n");
        // SAFETY: a register of the chip; the gated access is the point of this firmware.
        let mcr = unsafe { read32(0x4000_6400) };
        core::hint::black_box(mcr);
        print(c"bluepill-gate: the read returned (no bus error on the STM32)\n");
        idle()
    }

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"bluepill-gate: fault handler\n");
        idle()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
