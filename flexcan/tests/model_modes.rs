//! Mode handshakes, freeze-only registers, soft reset and bus synchronisation
//! (reference manual: "Modes of operation", "Freeze mode", "Module disable mode",
//! MCR/CTRL1/CTRL2 field descriptions).

#[path = "model_support.rs"]
mod support;

use support::*;
use twocan_core::registers::Registers;
use twocan_flexcan::model::{Chip, FlexCanModel, ModelMode};
use twocan_flexcan::regs::{self, code, ctrl1, ctrl2, ecr, esr1, mcr};
use twocan_sim::BusNode;

#[test]
fn reset_state_is_disabled_with_freeze_requested() {
    for m in [
        FlexCanModel::mk20dx256(),
        FlexCanModel::mk64fx512(),
        FlexCanModel::mk66fx1m0(),
    ] {
        assert_eq!(m.read32(regs::MCR), mcr::RESET);
        assert_eq!(m.read32(regs::MCR), 0xD890_000F);
        assert_eq!(m.read32(regs::CTRL1), 0);
        assert_eq!(m.read32(regs::CTRL2), ctrl2::RESET);
        assert_eq!(m.read32(regs::RXMGMASK), u32::MAX);
        assert_eq!(m.read32(regs::RX14MASK), u32::MAX);
        assert_eq!(m.read32(regs::RX15MASK), u32::MAX);
        assert_eq!(m.read32(regs::RXFGMASK), u32::MAX);
        assert_eq!(m.read32(regs::ECR), 0);
        assert_eq!(m.read32(regs::ESR1), 0);
        assert_eq!(m.mode(), ModelMode::Disabled);
        assert_eq!(m.message_buffers(), 16);
        assert!(!m.listens() && !m.acknowledges());
    }
    assert_eq!(FlexCanModel::mk66fx1m0().chip(), Chip::Mk66fx1m0);
}

#[test]
fn enable_enters_freeze_then_normal_after_eleven_recessive_bits() {
    let mut r = Rig::new();
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

#[test]
fn freeze_needs_both_frz_and_halt() {
    let mut r = Rig::new();
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

#[test]
fn freeze_only_fields_ignore_writes_outside_freeze() {
    let mut r = Rig::new();
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
    assert_eq!(r.rd(regs::CTRL2), ctrl2::RESET);
    r.wr(regs::RXMGMASK, 0x1234);
    r.wr(regs::RXFGMASK, 0x1234);
    r.wr(regs::rximr(3), 0x1234);
    r.wr(regs::ECR, 0x0505);
    assert_eq!(r.rd(regs::RXMGMASK), u32::MAX);
    assert_eq!(r.rd(regs::RXFGMASK), u32::MAX);
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
    assert_eq!(
        r.rd(regs::CTRL2),
        ctrl2::RFFN.val(3) | ctrl2::RRS,
        "reserved bits read 0"
    );
    r.wr(regs::rximr(3), 0x1234);
    assert_eq!(r.rd(regs::rximr(3)), 0x1234);
    r.wr(regs::ECR, ecr::TXERRCNT.val(100) | ecr::RXERRCNT.val(7));
    assert_eq!(
        r.rd(regs::ECR),
        ecr::TXERRCNT.val(100) | ecr::RXERRCNT.val(7)
    );
    // Disable mode: CLKSRC.
    r.set_bits(regs::MCR, mcr::MDIS);
    r.set_bits(regs::CTRL1, ctrl1::CLKSRC);
    assert_ne!(r.rd(regs::CTRL1) & ctrl1::CLKSRC, 0);
}

#[test]
fn status_bits_are_read_only_and_k20_has_no_waksrc() {
    let mut r = Rig::new();
    r.enable_into_freeze();
    r.wr(
        regs::MCR,
        r.rd(regs::MCR) & !(mcr::FRZACK | mcr::NOTRDY) | mcr::LPMACK | mcr::WAKSRC,
    );
    let v = r.rd(regs::MCR);
    assert_ne!(v & mcr::FRZACK, 0);
    assert_eq!(v & (mcr::LPMACK | mcr::WAKSRC), 0);
    let m = FlexCanModel::mk66fx1m0();
    m.modify32(regs::MCR, |v| v & !mcr::MDIS);
    m.modify32(regs::MCR, |v| v | mcr::WAKSRC);
    assert_ne!(m.read32(regs::MCR) & mcr::WAKSRC, 0);
}

#[test]
fn soft_reset_resets_the_listed_registers_only() {
    let mut r = Rig::new();
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
    r.wr(regs::IMASK1, 0xFFFF);
    r.wr(regs::ECR, ecr::TXERRCNT.val(40));
    r.wr(regs::mb_word0(15), 0xCAFE_F00D);
    r.wr(regs::TIMER, 1234);
    r.wr(regs::MCR, r.rd(regs::MCR) | mcr::SOFTRST);
    assert_eq!(r.rd(regs::MCR) & mcr::SOFTRST, 0, "self-clearing");
    assert_eq!(
        r.rd(regs::MCR),
        mcr::RESET & !(mcr::MDIS | mcr::LPMACK) | mcr::FRZACK
    );
    assert_eq!(r.rd(regs::IMASK1), 0);
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
    assert_eq!(r.rd(regs::mb_word0(15)), 0xCAFE_F00D);
}

#[test]
fn soft_reset_requested_while_disabled_completes_when_enabled() {
    let mut r = Rig::new();
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

#[test]
fn stuck_freeze_acknowledge_never_comes() {
    let mut r = Rig::new();
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

#[test]
fn any_write_anywhere_is_accepted() {
    let mut r = Rig::new();
    r.enable_into_freeze();
    for offset in (0..0x900).step_by(4).chain([1, 2, 3, 0x87D, 0x10_0000]) {
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
    for n in 0..16 {
        r.wr(regs::mb_cs(n), code::TX_INACTIVE << 24);
    }
    assert_eq!(r.rd(3), 0, "unaligned reads 0");
}

#[test]
fn scrambled_ram_must_be_initialised_by_software() {
    let r = Rig::new();
    r.m.scramble_ram(7);
    let words: Vec<u32> = (0..16).map(|n| r.m.peek32(regs::mb_word0(n))).collect();
    assert!(words.iter().any(|&w| w != 0));
    assert_ne!(r.m.peek32(regs::rximr(0)), r.m.peek32(regs::rximr(1)));
}
