//! Writing a filter plan ([`crate::FilterPlan`], [`crate::filters::SizedPlan`]) to the filter registers (notes "Filter bank scale and mode
//! configuration"; RM0410 §40.7.4, §40.9.4):
//!
//! 1. `CAN_FMR.FINIT = 1` (filter initialization mode: reception through the block stops,
//!    the CAN's operating mode is untouched);
//! 2. deactivate the instance's banks (`FACTi = 0`) — a bank is configured deactivated;
//! 3. write `FSCi`, `FBMi`, `FFAi` and `FiR1`/`FiR2` of every bank of the plan;
//! 4. activate the plan's active banks; the instance's other banks stay deactivated;
//! 5. `FINIT = 0`.
//!
//! **Shared registers.** On F76x/F77x the filter block of CAN1 also serves CAN2 (its
//! banks `CAN2SB..28`): `CAN_FMR`, `CAN_FM1R`, `CAN_FS1R`, `CAN_FFA1R` and `CAN_FA1R`
//! hold bits of both instances, and the drivers of CAN1 and CAN2 may run in different
//! execution contexts (thread and interrupt, or two interrupt priorities). Every
//! read-modify-write of them — the whole FINIT section of `program` and the `CAN2SB`
//! write of `set_can2sb` — runs inside [`critical_section::with`], so that one
//! instance's programming cannot interleave with the other's and write back stale bits
//! (or clear `FINIT` while the other is still configuring its banks). The sections are
//! short: a fixed number of register accesses, no waiting.

use twocan_core::Registers;

use crate::chip::Chip;
use crate::filters::PlanRef;
use crate::instance::{bank_range, Instance};
use crate::regs::{fa1r, ffa1r, fir1, fir2, fm1r, fmr, fs1r, FA1R, FFA1R, FM1R, FMR, FS1R};

/// The `CAN2SB` value of the dual filter block behind `regs`.
pub(crate) fn can2sb<F: Registers>(regs: &F) -> u32 {
    fmr::CAN2SB.get(regs.read32(FMR))
}

/// The banks `instance` of `chip` owns in the block behind `regs` ([`Chip::bank_range`]:
/// a dual block split at `CAN2SB`, a single-CAN block whole).
pub(crate) fn banks_of<F: Registers>(regs: &F, chip: &Chip, instance: Instance) -> (usize, usize) {
    chip.bank_range(instance, can2sb(regs))
}

/// The FIFOs `instance`'s active banks feed in the block behind `regs`: bit 0 FIFO 0,
/// bit 1 FIFO 1 (`CAN_FA1R.FACTx` and `CAN_FFA1R.FFAx` of its banks, RM0410 §40.9.4).
pub(crate) fn fed_fifos<F: Registers>(regs: &F, chip: &Chip, instance: Instance) -> u8 {
    let (start, end) = banks_of(regs, chip, instance);
    let ours = ((1u32 << (end - start)) - 1) << start;
    let active = regs.read32(FA1R) & ours;
    let to_fifo1 = regs.read32(FFA1R) & active;
    u8::from(active & !to_fifo1 != 0) | (u8::from(to_fifo1 != 0) << 1)
}

/// A `CAN2SB` change refused: bank `bank` is active and the change would give it to
/// the other instance, or renumber it (a CAN2 bank's filter match index counts from
/// `CAN2SB`, see `docs/models.md`), behind the back of the driver that installed it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct StartBankInUse {
    /// The lowest active bank the change would affect.
    pub bank: usize,
}

/// Whether moving the split of the block behind `regs` to `start` leaves every
/// installed filter where its driver put it: the banks from `min(old, new)` up change
/// owner (between the two values) or, above both, stay CAN2's but are numbered from the
/// new `CAN2SB`; none of them may be active (`CAN_FA1R.FACTx`, RM0410 §40.9.4).
/// Banks below both values stay CAN1's with their numbers. An unchanged split (values
/// above 28 read as 28, [`bank_range`]) is always allowed.
pub(crate) fn check_can2sb<F: Registers>(regs: &F, start: u8) -> Result<(), StartBankInUse> {
    let old = bank_range(Instance::Can2, can2sb(regs)).0;
    let new = bank_range(Instance::Can2, start as u32).0;
    if old == new {
        return Ok(());
    }
    let lowest = old.min(new);
    let affected = regs.read32(FA1R) >> lowest;
    if affected == 0 {
        Ok(())
    } else {
        Err(StartBankInUse {
            bank: lowest + affected.trailing_zeros() as usize,
        })
    }
}

/// Sets `CAN2SB` (in filter initialization mode, as RM0410 requires), in a critical
/// section (`CAN_FMR` is shared with CAN2's driver, see the module notes), if
/// [`check_can2sb`] allows it (checked inside the same section, so CAN2's driver cannot
/// activate a bank between the check and the write). An unchanged value is not
/// written (no `FINIT` section: reception through the block goes on).
pub(crate) fn set_can2sb<F: Registers>(regs: &F, start: u8) -> Result<(), StartBankInUse> {
    critical_section::with(|_| {
        check_can2sb(regs, start)?;
        let fmr_value = regs.read32(FMR);
        if bank_range(Instance::Can2, fmr::CAN2SB.get(fmr_value)).0
            == bank_range(Instance::Can2, start as u32).0
        {
            return Ok(());
        }
        regs.write32(FMR, fmr_value | fmr::FINIT);
        let with = fmr::CAN2SB.set(fmr_value | fmr::FINIT, start as u32);
        regs.write32(FMR, with);
        regs.write32(FMR, with & !fmr::FINIT);
        Ok(())
    })
}

/// Error: the plan has more banks than the instance owns.
pub(crate) struct TooManyBanks;

/// Writes `plan` (a run-time [`crate::FilterPlan`] or a `const`
/// [`crate::filters::SizedPlan`], read through their [`PlanRef`]) to the banks
/// `instance` owns, in a critical section (the registers are shared with the other
/// instance's driver, see the module notes; `CAN2SB` is read inside it too, so the bank
/// range cannot change under the programming).
pub(crate) fn program<'p, F: Registers>(
    regs: &F,
    chip: &Chip,
    instance: Instance,
    plan: impl Into<PlanRef<'p>>,
) -> Result<(), TooManyBanks> {
    let plan = plan.into();
    critical_section::with(|_| program_locked(regs, chip, instance, plan))
}

/// As [`program`], running `then` still in filter initialization mode (`FINIT` = 1,
/// nothing enters the FIFOs) after the banks are written.
pub(crate) fn program_then<'p, F: Registers>(
    regs: &F,
    chip: &Chip,
    instance: Instance,
    plan: impl Into<PlanRef<'p>>,
    then: impl FnOnce(),
) -> Result<(), TooManyBanks> {
    let plan = plan.into();
    critical_section::with(|_| program_locked_then(regs, chip, instance, plan, then))
}

fn program_locked<F: Registers>(
    regs: &F,
    chip: &Chip,
    instance: Instance,
    plan: PlanRef<'_>,
) -> Result<(), TooManyBanks> {
    program_locked_then(regs, chip, instance, plan, || {})
}

fn program_locked_then<F: Registers>(
    regs: &F,
    chip: &Chip,
    instance: Instance,
    plan: PlanRef<'_>,
    then: impl FnOnce(),
) -> Result<(), TooManyBanks> {
    let (start, end) = banks_of(regs, chip, instance);
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
    then();
    regs.modify32(FMR, |v| v & !fmr::FINIT);
    Ok(())
}
