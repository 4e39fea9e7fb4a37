//! Mode handshakes, freeze-only registers, soft reset and bus synchronisation
//! (reference manual: "Modes of operation", "Freeze mode", "Module disable mode",
//! MCR/CTRL1/CTRL2 field descriptions), on every module of `support::CHIPS`; reset
//! values and the fields a module has or lacks come from `support::Manual`.

#[path = "model_support.rs"]
mod support;

use support::*;
use twocan_core::registers::Registers;
use twocan_flexcan::model::layout;
use twocan_flexcan::model::{Chip, FlexCanModel, ModelMode};
use twocan_flexcan::regs::{self, code, ctrl1, ctrl2, ecr, esr1, mcr};
use twocan_sim::BusNode;

on_every_chip!(
    reset_state_per_the_manual,
    enable_enters_freeze_then_normal_after_eleven_recessive_bits,
    freeze_needs_both_frz_and_halt,
    freeze_only_fields_ignore_writes_outside_freeze,
    status_bits_are_read_only_and_waksrc_only_where_implemented,
    soft_reset_resets_the_listed_registers_only,
    soft_reset_requested_while_disabled_completes_when_enabled,
    stuck_freeze_acknowledge_never_comes,
    any_write_anywhere_is_accepted,
    scrambled_ram_must_be_initialised_by_software,
);

/// Out of reset (reset values of "Module Configuration Register (MCR)", "Control 2
/// register (CTRL2)" and the mask registers, per module in [`Manual`]): the Kinetis
/// modules in Disable mode with Freeze already requested (MCR 0xD890_000F), the RT1062's
/// enabled and in Freeze mode (IMXRT1060RM MCR 0x5980_000F); not on the bus either way.
fn reset_state_per_the_manual(chip: Chip) {
    let want = Manual::of(chip);
    let m = FlexCanModel::new(chip);
    assert_eq!(m.chip(), chip);
    assert_eq!(m.read32(regs::MCR), want.reset_mcr);
    assert_eq!(m.mode(), want.reset_mode);
    assert_eq!(m.read32(regs::CTRL1), 0);
    assert_eq!(m.read32(regs::CTRL2), want.reset_ctrl2);
    for mask in [
        regs::RXMGMASK,
        regs::RX14MASK,
        regs::RX15MASK,
        regs::RXFGMASK,
    ] {
        assert_eq!(m.read32(mask), want.reset_masks, "0x{mask:X}");
    }
    assert_eq!(m.read32(regs::ECR), 0);
    assert_eq!(m.read32(regs::ESR1), 0);
    assert_eq!(m.read32(regs::IMASK1), 0);
    assert_eq!(m.read32(layout::IMASK2), 0);
    assert_eq!(m.message_buffers(), want.message_buffers);
    assert!(!m.listens() && !m.acknowledges());
}

/// From Disable mode (the RT1062 gets there first: [`Rig::enter_disable`]), negating MDIS
/// with FRZ and HALT set enters Freeze mode.
fn enable_enters_freeze_then_normal_after_eleven_recessive_bits(chip: Chip) {
    let mut r = Rig::on(chip);
    r.enter_disable();
    r.clear_bits(regs::MCR, mcr::MDIS);
    let v = r.rd(regs::MCR);
    assert_eq!(v & (mcr::LPMACK | mcr::MDIS), 0);
    assert_ne!(v & mcr::FRZACK, 0);
    assert_ne!(v & mcr::NOTRDY, 0);
    assert_eq!(r.m.mode(), ModelMode::Freeze);

    r.clear_bits(regs::MCR, mcr::HALT);
    let v = r.rd(regs::MCR);
    assert_eq!(
        v & (mcr::FRZACK | mcr::NOTRDY),
        0,
        "NOTRDY negated once freeze is left"
    );
    assert_eq!(r.m.mode(), ModelMode::Normal);
    // Not yet synchronised: ESR1[SYNCH] clear, no part in bus traffic.
    assert_eq!(r.rd(regs::ESR1) & esr1::SYNCH, 0);
    assert!(!r.m.listens());
    r.idle(10);
    assert!(!r.m.is_synchronised());
    r.busy(5); // a dominant bit restarts the count
    r.idle(10);
    assert!(!r.m.is_synchronised());
    r.idle(1);
    assert!(r.m.is_synchronised());
    assert_ne!(r.rd(regs::ESR1) & (esr1::SYNCH | esr1::IDLE), 0);
    assert!(r.m.listens() && r.m.acknowledges() && r.m.error_active());

    // Back to freeze and to disable.
    r.freeze();
    assert!(!r.m.listens());
    r.set_bits(regs::MCR, mcr::MDIS);
    let v = r.rd(regs::MCR);
    assert_ne!(v & mcr::LPMACK, 0);
    assert_eq!(v & mcr::FRZACK, 0);
    assert_ne!(v & mcr::NOTRDY, 0);
}

fn freeze_needs_both_frz_and_halt(chip: Chip) {
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    r.start();
    r.set_bits(regs::MCR, mcr::HALT);
    r.clear_bits(regs::MCR, mcr::FRZ);
    assert_eq!(
        r.rd(regs::MCR) & mcr::FRZACK,
        0,
        "HALT without FRZ does not freeze"
    );
    r.set_bits(regs::MCR, mcr::FRZ);
    assert_ne!(r.rd(regs::MCR) & mcr::FRZACK, 0);
    r.clear_bits(regs::MCR, mcr::FRZ);
    assert_eq!(
        r.rd(regs::MCR) & mcr::FRZACK,
        0,
        "negating FRZ leaves freeze"
    );
}

/// Reset values and the reserved bits of CTRL2 per module ([`Manual`]); CTRL1\[CLKSRC\]
/// only where it exists (reserved on the RT1062's CAN1/CAN2).
fn freeze_only_fields_ignore_writes_outside_freeze(chip: Chip) {
    let want = Manual::of(chip);
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    r.start();
    // Normal mode: protected fields keep their values.
    let before = r.rd(regs::MCR);
    r.wr(
        regs::MCR,
        before | mcr::RFEN | mcr::IRMQ | mcr::AEN | mcr::SRXDIS,
    );
    assert_eq!(
        r.rd(regs::MCR) & (mcr::RFEN | mcr::IRMQ | mcr::AEN | mcr::SRXDIS),
        0
    );
    r.wr(
        regs::CTRL1,
        ctrl1::PRESDIV.val(3) | ctrl1::LPB | ctrl1::LOM | ctrl1::BOFFMSK | ctrl1::BOFFREC,
    );
    assert_eq!(
        r.rd(regs::CTRL1),
        ctrl1::BOFFMSK | ctrl1::BOFFREC,
        "only the any-time bits"
    );
    r.wr(regs::CTRL2, ctrl2::RFFN.val(3) | ctrl2::RRS);
    assert_eq!(r.rd(regs::CTRL2), want.reset_ctrl2);
    r.wr(regs::RXMGMASK, 0x1234);
    r.wr(regs::RXFGMASK, 0x1234);
    r.wr(regs::rximr(3), 0x1234);
    r.wr(regs::ECR, 0x0505);
    assert_eq!(r.rd(regs::RXMGMASK), want.reset_masks);
    assert_eq!(r.rd(regs::RXFGMASK), want.reset_masks);
    assert_eq!(r.rd(regs::rximr(3)), 0);
    assert_eq!(r.rd(regs::ECR), 0);
    // CLKSRC only in Disable mode.
    r.freeze();
    r.set_bits(regs::CTRL1, ctrl1::CLKSRC);
    assert_eq!(r.rd(regs::CTRL1) & ctrl1::CLKSRC, 0);
    // Freeze mode: writable.
    r.wr(
        regs::MCR,
        r.rd(regs::MCR) | mcr::RFEN | mcr::IRMQ | mcr::AEN,
    );
    assert_ne!(r.rd(regs::MCR) & mcr::RFEN, 0);
    r.wr(regs::CTRL1, ctrl1::PRESDIV.val(3) | ctrl1::LPB);
    assert_eq!(r.rd(regs::CTRL1), ctrl1::PRESDIV.val(3) | ctrl1::LPB);
    r.wr(regs::CTRL2, ctrl2::RFFN.val(3) | ctrl2::RRS | 0x0000_FFFF);
    let c2 = r.rd(regs::CTRL2);
    assert_eq!(c2 & 0xFFFF_0000, ctrl2::RFFN.val(3) | ctrl2::RRS);
    assert_eq!(c2 & want.ctrl2_reserved_low, 0, "reserved bits read 0");
    r.wr(regs::rximr(3), 0x1234);
    assert_eq!(r.rd(regs::rximr(3)), 0x1234);
    r.wr(regs::ECR, ecr::TXERRCNT.val(100) | ecr::RXERRCNT.val(7));
    assert_eq!(
        r.rd(regs::ECR),
        ecr::TXERRCNT.val(100) | ecr::RXERRCNT.val(7)
    );
    // Disable mode: CLKSRC, where the module has it.
    r.enter_disable();
    r.set_bits(regs::CTRL1, ctrl1::CLKSRC);
    assert_eq!(r.rd(regs::CTRL1) & ctrl1::CLKSRC != 0, want.clksrc);
}

/// FRZACK, LPMACK and NOTRDY are read-only; MCR\[WAKSRC\] is written in Freeze mode
/// where it exists ([`Manual::waksrc`]: reserved on the MK20DX256, K20P64M72SF1RM MCR).
fn status_bits_are_read_only_and_waksrc_only_where_implemented(chip: Chip) {
    let want = Manual::of(chip);
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    r.wr(
        regs::MCR,
        r.rd(regs::MCR) & !(mcr::FRZACK | mcr::NOTRDY) | mcr::LPMACK | mcr::WAKSRC,
    );
    let v = r.rd(regs::MCR);
    assert_eq!(v & (mcr::FRZACK | mcr::NOTRDY), mcr::FRZACK | mcr::NOTRDY);
    assert_eq!(v & mcr::LPMACK, 0);
    assert_eq!(v & mcr::WAKSRC != 0, want.waksrc);
}

/// "Soft reset" (MCR\[SOFTRST\]): MCR back to its reset configuration (here in Freeze
/// mode: [`Manual::frozen_mcr`], 0x5980_000F on both families), IMASK1/IMASK2 (IMXRT1060RM
/// lists IMASK2 and IFLAG2 with them), ECR and TIMER cleared; CTRL1, CTRL2, the masks and
/// the message buffers (the last one: MB15 or MB63) kept.
fn soft_reset_resets_the_listed_registers_only(chip: Chip) {
    let want = Manual::of(chip);
    let last = want.message_buffers - 1;
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    r.wr(
        regs::MCR,
        r.rd(regs::MCR) | mcr::RFEN | mcr::SRXDIS | mcr::AEN,
    );
    r.wr(
        regs::CTRL1,
        ctrl1::PRESDIV.val(4) | ctrl1::LPB | ctrl1::ERRMSK,
    );
    r.wr(regs::CTRL2, ctrl2::RFFN.val(2));
    r.wr(regs::RXMGMASK, 0x55);
    r.wr(regs::RXFGMASK, 0x66);
    r.wr(regs::rximr(2), 0x77);
    r.wr(regs::IMASK1, u32::MAX);
    r.wr(layout::IMASK2, u32::MAX);
    assert_eq!(r.rd(regs::IMASK1), want.flags1);
    assert_eq!(r.rd(layout::IMASK2), want.flags2);
    r.wr(regs::ECR, ecr::TXERRCNT.val(40));
    r.wr(regs::mb_word0(last), 0xCAFE_F00D);
    r.wr(regs::TIMER, 1234);
    r.wr(regs::MCR, r.rd(regs::MCR) | mcr::SOFTRST);
    assert_eq!(r.rd(regs::MCR) & mcr::SOFTRST, 0, "self-clearing");
    assert_eq!(r.rd(regs::MCR), want.frozen_mcr());
    assert_eq!(r.rd(regs::IMASK1), 0);
    assert_eq!(r.rd(layout::IMASK2), 0);
    assert_eq!(r.rd(regs::ECR), 0);
    assert_eq!(r.rd(regs::TIMER), 0);
    // Not affected.
    assert_eq!(
        r.rd(regs::CTRL1),
        ctrl1::PRESDIV.val(4) | ctrl1::LPB | ctrl1::ERRMSK
    );
    assert_eq!(r.rd(regs::CTRL2), ctrl2::RFFN.val(2));
    assert_eq!(r.rd(regs::RXMGMASK), 0x55);
    assert_eq!(r.rd(regs::RXFGMASK), 0x66);
    assert_eq!(r.rd(regs::rximr(2)), 0x77);
    assert_eq!(r.rd(regs::mb_word0(last)), 0xCAFE_F00D);
}

fn soft_reset_requested_while_disabled_completes_when_enabled(chip: Chip) {
    let mut r = Rig::on(chip);
    r.enter_disable();
    r.set_bits(regs::MCR, mcr::SOFTRST);
    assert_ne!(
        r.rd(regs::MCR) & mcr::SOFTRST,
        0,
        "pending while the clocks are off"
    );
    r.clear_bits(regs::MCR, mcr::MDIS);
    assert_eq!(r.rd(regs::MCR) & mcr::SOFTRST, 0);
    assert_eq!(r.m.mode(), ModelMode::Freeze);
}

fn stuck_freeze_acknowledge_never_comes(chip: Chip) {
    let mut r = Rig::on(chip);
    r.enter_disable();
    r.m.set_freeze_ack_stuck(true);
    r.clear_bits(regs::MCR, mcr::MDIS);
    for _ in 0..1000 {
        assert_eq!(r.rd(regs::MCR) & mcr::FRZACK, 0);
    }
    assert_ne!(
        r.rd(regs::MCR) & mcr::LPMACK,
        0,
        "no clock: nothing acknowledges"
    );
    r.m.set_freeze_ack_stuck(false);
    assert_ne!(r.rd(regs::MCR) & mcr::FRZACK, 0);
    // Stuck in freeze: leaving is never acknowledged either.
    r.m.set_freeze_ack_stuck(true);
    r.clear_bits(regs::MCR, mcr::HALT);
    assert_ne!(r.rd(regs::MCR) & mcr::FRZACK, 0);
}

/// Every offset of the largest register map (the RT1062's ends with CAN3's FDCRC at
/// 0xC08) and beyond.
fn any_write_anywhere_is_accepted(chip: Chip) {
    let mbs = Manual::of(chip).message_buffers;
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    for offset in (0..0x1000).step_by(4).chain([1, 2, 3, 0x87D, 0x10_0000]) {
        for v in [0, u32::MAX, 0xA5A5_5A5A] {
            r.wr(offset, v);
            let _ = r.rd(offset);
        }
    }
    r.clear_bits(regs::MCR, mcr::HALT | mcr::MDIS);
    r.idle(20);
    let _ = r.transmit_all();
    r.m.scramble_ram(42);
    r.freeze();
    for n in 0..mbs {
        r.wr(regs::mb_cs(n), code::TX_INACTIVE << 24);
    }
    assert_eq!(r.rd(3), 0, "unaligned reads 0");
}

fn scrambled_ram_must_be_initialised_by_software(chip: Chip) {
    let mbs = Manual::of(chip).message_buffers;
    let r = Rig::on(chip);
    r.m.scramble_ram(7);
    let words: Vec<u32> = (0..mbs).map(|n| r.m.peek32(regs::mb_word0(n))).collect();
    assert!(words.iter().any(|&w| w != 0));
    assert_ne!(r.m.peek32(regs::rximr(0)), r.m.peek32(regs::rximr(1)));
}
