//! Negative test: reads bxCAN1's `CAN_MCR` without enabling its clock
//! (`RCC_APB1ENR.CAN1EN`). The STM32 answers without a bus error (the read gives 0), so
//! the firmware goes on; the harness must still report the access as a fault, with
//! this read's PC.
#![no_std]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod image {
    use twocan_fil_firmware::{idle, print, read32, vector_table};

    vector_table!(reset, fault, 0, fault);

    #[no_mangle]
    extern "C" fn reset() -> ! {
        print(c"stm32-gate: reading CAN1_MCR with RCC_APB1ENR.CAN1EN = 0\n");
        // SAFETY: a register of the chip; the bus error is the point of this firmware.
        let mcr = unsafe { read32(0x4000_6400) };
        core::hint::black_box(mcr);
        print(c"stm32-gate: the read returned (no bus error on the STM32)\n");
        idle()
    }

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"stm32-gate: fault handler\n");
        idle()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
