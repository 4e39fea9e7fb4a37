//! Writing a [`FilterPlan`] to the filter registers (notes "Filter bank scale and mode
//! configuration"; RM0410 §40.7.4, §40.9.4):
//!
//! 1. `CAN_FMR.FINIT = 1` (filter initialization mode: reception through the block stops,
//!    the CAN's operating mode is untouched);
//! 2. deactivate the instance's banks (`FACTi = 0`) — a bank is configured deactivated;
//! 3. write `FSCi`, `FBMi`, `FFAi` and `FiR1`/`FiR2` of every bank of the plan;
//! 4. activate the plan's active banks; the instance's other banks stay deactivated;
//! 5. `FINIT = 0`.

use twocan_core::Registers;

use crate::filters::FilterPlan;
use crate::instance::{bank_range, Instance};
use crate::regs::{fa1r, ffa1r, fir1, fir2, fm1r, fmr, fs1r, FA1R, FFA1R, FM1R, FMR, FS1R};

/// The `CAN2SB` value of the dual filter block behind `regs`.
pub(crate) fn can2sb<F: Registers>(regs: &F) -> u32 {
    fmr::CAN2SB.get(regs.read32(FMR))
}

/// The banks `instance` owns in the block behind `regs`.
pub(crate) fn banks_of<F: Registers>(regs: &F, instance: Instance) -> (usize, usize) {
    bank_range(instance, can2sb(regs))
}

/// Sets `CAN2SB` (in filter initialization mode, as RM0410 requires).
pub(crate) fn set_can2sb<F: Registers>(regs: &mut F, start: u8) {
    let fmr_value = regs.read32(FMR);
    regs.write32(FMR, fmr_value | fmr::FINIT);
    let with = fmr::CAN2SB.set(fmr_value | fmr::FINIT, start as u32);
    regs.write32(FMR, with);
    regs.write32(FMR, with & !fmr::FINIT);
}

/// Error: the plan has more banks than the instance owns.
pub(crate) struct TooManyBanks;

/// Writes `plan` to the banks `instance` owns.
pub(crate) fn program<F: Registers>(
    regs: &mut F,
    instance: Instance,
    plan: &FilterPlan,
) -> Result<(), TooManyBanks> {
    let (start, end) = banks_of(regs, instance);
    if plan.bank_count() > end - start {
        return Err(TooManyBanks);
    }
    let ours = ((1u32 << (end - start)) - 1) << start;
    regs.modify32(FMR, |v| v | fmr::FINIT);
    regs.modify32(FA1R, |v| v & !ours);
    let mut fs = regs.read32(FS1R);
    let mut fm = regs.read32(FM1R);
    let mut ffa = regs.read32(FFA1R);
    let mut fa = 0u32;
    for (k, bank) in plan.banks().iter().enumerate() {
        let i = start + k;
        fs = if bank.kind.is_32bit() {
            fs | fs1r::fsc(i)
        } else {
            fs & !fs1r::fsc(i)
        };
        fm = if bank.kind.is_list() {
            fm | fm1r::fbm(i)
        } else {
            fm & !fm1r::fbm(i)
        };
        ffa = if bank.fifo.index() == 1 {
            ffa | ffa1r::ffa(i)
        } else {
            ffa & !ffa1r::ffa(i)
        };
        if bank.active {
            fa |= fa1r::fact(i);
        }
    }
    regs.write32(FS1R, fs);
    regs.write32(FM1R, fm);
    regs.write32(FFA1R, ffa);
    for (k, bank) in plan.banks().iter().enumerate() {
        regs.write32(fir1(start + k), bank.fr1);
        regs.write32(fir2(start + k), bank.fr2);
    }
    regs.modify32(FA1R, |v| v | fa);
    regs.modify32(FMR, |v| v & !fmr::FINIT);
    Ok(())
}
