//! Negative test: CAN1 without a protocol-engine clock. The CAN clock root is off out of
//! reset (`CCM_CSCMR2[CAN_CLK_SEL]` = 3) and this firmware leaves it so: the register
//! gate is open (registers answer), but leaving Freeze mode (HALT negated) is never
//! acknowledged. A bounded wait must time out; the firmware reports it and sleeps.
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

    const MCR: u32 = 0x401D_0000;

    #[no_mangle]
    extern "C" fn reset() -> ! {
        // SAFETY: first thing after reset; then CAN1's MCR.
        unsafe {
            imxrt_init_memory();
            write32(MCR, read32(MCR) & !(1 << 28)); // negate HALT: leave Freeze
        }
        for _ in 0..10_000 {
            // SAFETY: CAN1's MCR; bounded poll of FRZACK.
            if unsafe { read32(MCR) } & (1 << 24) == 0 {
                print(c"imxrt-no-can-clock: freeze left (wrong: no CAN clock)\n");
                idle()
            }
        }
        print(c"imxrt-no-can-clock: FRZACK still set: timeout\n");
        idle()
    }

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"imxrt-no-can-clock: fault\n");
        idle()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
