//! The RAM stand-in of `ram_can.rs` as an instance of the `bxcan` crate 0.8, and the
//! crate's configuration on it: shared by `insn-count` (the bare crate) and
//! `insn-count-equiv` (the feature-equivalent service), which measure them in separate
//! images so that each keeps the crate's code inlined as a firmware using it alone
//! would. Included with `#[path]`, next to `qemu.rs` and `ram_can.rs`.

use bxcan::filter::Mask32;

use crate::qemu::check;
use crate::ram_can::REGS;

/// The RAM stand-in as a `bxcan` instance.
pub struct RamCan1;

// SAFETY: `REGISTERS` points to the RAM block at `REGS`, laid out as bxCAN's register
// block (0x320 bytes, aligned), used by one driver at a time.
unsafe impl bxcan::Instance for RamCan1 {
    const REGISTERS: *mut bxcan::RegisterBlock = REGS as *mut _;
}

// SAFETY: the stand-in has CAN1's 28 filter banks.
unsafe impl bxcan::FilterOwner for RamCan1 {
    const NUM_FILTER_BANKS: u8 = 28;
}

// SAFETY: the stand-in is CAN1, the master instance.
unsafe impl bxcan::MasterInstance for RamCan1 {}

/// The crate's configuration as its documentation shows it: bit timing `btr`,
/// loop-back, one accept-all bank to FIFO 0, enabled. With `ttcm`, `CAN_MCR.TTCM` is
/// set for the time stamps (the crate has no switch for it).
#[inline(never)]
pub fn configure(btr: u32, ttcm: bool) -> bxcan::Can<RamCan1> {
    let mut can = bxcan::Can::builder(RamCan1)
        .set_bit_timing(btr)
        .set_loopback(true)
        .leave_disabled();
    can.modify_filters()
        .enable_bank(0, bxcan::Fifo::Fifo0, Mask32::accept_all());
    if ttcm {
        // SAFETY: `CAN_MCR` of the stand-in (offset 0), in initialization mode
        // (`leave_disabled`): TTCM is bit 7.
        unsafe {
            let mcr = REGS as *mut u32;
            mcr.write_volatile(mcr.read_volatile() | (1 << 7));
        }
    }
    check(
        nb::block!(can.enable_non_blocking()).is_ok(),
        "bxcan enable",
    );
    can
}
