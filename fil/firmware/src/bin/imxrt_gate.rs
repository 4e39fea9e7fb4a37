//! Negative test: reads CAN1's `MCR` after closing its register clock gate
//! (`CCM_CCGR0` CG7, `can1_clk`; open out of reset). The access must end in a bus error
//! the harness reports with this read's PC.
#![no_std]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod image {
    use twocan_fil_firmware::{
        idle, imxrt_fcb, imxrt_init_memory, print, read32, vector_table, write32,
    };

    #[link_section = ".fcb"]
    #[no_mangle]
    #[used]
    static FLEXSPI_CONFIGURATION_BLOCK: [u8; 512] = imxrt_fcb();

    vector_table!(reset, fault, 0, fault);

    const CCM_CCGR0: u32 = 0x400F_C068;

    #[no_mangle]
    extern "C" fn reset() -> ! {
        // SAFETY: first thing after reset; then CCM_CCGR0 and CAN1's MCR.
        unsafe {
            imxrt_init_memory();
            write32(CCM_CCGR0, read32(CCM_CCGR0) & !(3 << 14));
        }
        print(c"imxrt-gate: reading CAN1_MCR with CCM_CCGR0.CG7 = 0\n");
        // SAFETY: a register of the chip; the bus error is the point of this firmware.
        let mcr = unsafe { read32(0x401D_0000) };
        core::hint::black_box(mcr);
        print(c"imxrt-gate: no fault (wrong)\n");
        idle()
    }

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"imxrt-gate: fault handler\n");
        idle()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
