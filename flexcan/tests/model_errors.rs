//! Error counters, ESR1, fault confinement, bus-off and its recovery, and the error
//! interrupt lines ("Error Counter (CANx_ECR)", "Error and Status 1 register (CANx_ESR1)",
//! CTRL1[BOFFREC], CTRL1 interrupt masks, MCR[WRNEN]), on every module of
//! `support::CHIPS`.

#[path = "model_support.rs"]
mod support;

use support::*;
use twocan_core::{ErrorCounters, LastErrorCode};
use twocan_flexcan::model::{Chip, FlexCanIrq};
use twocan_flexcan::regs::{self, code, ctrl1, ecr, esr1, mcr};
use twocan_sim::{BusNode, BusTime, TxResult};

on_every_chip!(
    lone_transmitter_goes_passive_with_warning_on_the_way,
    esr1_error_bits_clear_on_read_and_errint_is_write_one_to_clear,
    receive_errors_warning_and_passive,
    warning_interrupts_need_wrnen,
    bus_off_and_automatic_recovery,
    bus_off_recovery_held_by_boffrec,
    error_counters_written_in_freeze,
    soft_reset_clears_the_error_state,
);

fn rig(chip: Chip, wrnen: bool) -> Rig {
    let mut r = Rig::on(chip);
    r.enable_into_freeze();
    let mut m = r.rd(regs::MCR) | mcr::SRXDIS;
    if wrnen {
        m |= mcr::WRNEN;
    }
    r.wr(regs::MCR, m);
    for n in 0..Manual::of(chip).message_buffers {
        r.wr(regs::mb_cs(n), 0);
    }
    r.start();
    r
}

fn fltconf(r: &Rig) -> u32 {
    esr1::FLTCONF.get(r.m.peek32(regs::ESR1))
}

fn lone_transmitter_goes_passive_with_warning_on_the_way(chip: Chip) {
    let mut r = rig(chip, true);
    r.ctrl1(ctrl1::ERRMSK | ctrl1::TWRNMSK | ctrl1::RWRNMSK | ctrl1::BOFFMSK);
    r.load_mb(8, &std(0x100, &[1]), code::TX_DATA);
    for k in 1..=11 {
        r.transmit(TxResult::Error(LastErrorCode::Acknowledge));
        assert_eq!(ecr::TXERRCNT.get(r.rd(regs::ECR)), 8 * k);
    }
    // 88: no warning yet.
    assert_eq!(r.m.peek32(regs::ESR1) & (esr1::TXWRN | esr1::TWRNINT), 0);
    r.transmit(TxResult::Error(LastErrorCode::Acknowledge));
    let v = r.m.peek32(regs::ESR1);
    assert_ne!(v & esr1::TXWRN, 0, "TEC 96");
    assert_ne!(v & esr1::TWRNINT, 0);
    assert_eq!(
        r.m.irq(),
        FlexCanIrq {
            message_buffer: false,
            error: true,
            bus_off: false,
            warning: true
        }
    );
    r.wr(regs::ESR1, esr1::TWRNINT);
    assert!(!r.m.irq().warning);
    for _ in 0..4 {
        r.transmit(TxResult::Error(LastErrorCode::Acknowledge));
    }
    assert_eq!(r.m.error_counters(), ErrorCounters { tec: 128, rec: 0 });
    assert_eq!(fltconf(&r), esr1::FLTCONF_ERROR_PASSIVE);
    assert!(!r.m.error_active());
    // Passive: acknowledge errors no longer count (ISO 11898-1 exception 1).
    r.transmit(TxResult::Error(LastErrorCode::Acknowledge));
    assert_eq!(r.m.error_counters().tec, 128);
    // A success brings TEC down by one.
    r.transmit(TxResult::Acked);
    assert_eq!(ecr::TXERRCNT.get(r.rd(regs::ECR)), 127);
    assert_eq!(fltconf(&r), esr1::FLTCONF_ERROR_ACTIVE);
    assert!(r.m.error_active());
}

fn esr1_error_bits_clear_on_read_and_errint_is_write_one_to_clear(chip: Chip) {
    let mut r = rig(chip, false);
    r.ctrl1(ctrl1::ERRMSK);
    let t = BusTime {
        sof: r.now,
        now: r.now,
    };
    r.m.rx_error(LastErrorCode::Crc, false, t);
    r.m.rx_error(LastErrorCode::Stuff, false, t);
    r.m.rx_error(LastErrorCode::Form, false, t);
    r.m.rx_error(LastErrorCode::BitRecessive, false, t);
    assert_eq!(r.m.error_counters().rec, 4);
    let v = r.rd(regs::ESR1);
    assert_eq!(
        v & (esr1::ERROR_BITS | esr1::ERRINT),
        esr1::CRCERR | esr1::STFERR | esr1::FRMERR | esr1::BIT1ERR | esr1::ERRINT
    );
    let v = r.rd(regs::ESR1);
    assert_eq!(v & esr1::ERROR_BITS, 0, "cleared by the read");
    assert_ne!(v & esr1::ERRINT, 0, "ERRINT stays until written 1");
    assert!(r.m.irq().error);
    r.wr(regs::ESR1, esr1::ERROR_BITS | esr1::FLTCONF.mask());
    assert_ne!(
        r.rd(regs::ESR1) & esr1::ERRINT,
        0,
        "writing other bits changes nothing"
    );
    r.wr(regs::ESR1, esr1::ERRINT);
    assert_eq!(r.rd(regs::ESR1) & esr1::ERRINT, 0);
    assert!(!r.m.irq().error);
    // Transmit side: BIT0ERR (sent dominant, read recessive) and ACKERR.
    r.load_mb(8, &std(0x100, &[1]), code::TX_DATA);
    r.transmit(TxResult::Error(LastErrorCode::BitDominant));
    r.transmit(TxResult::Error(LastErrorCode::Acknowledge));
    assert_eq!(
        r.rd(regs::ESR1) & esr1::ERROR_BITS,
        esr1::BIT0ERR | esr1::ACKERR
    );
}

fn receive_errors_warning_and_passive(chip: Chip) {
    let mut r = rig(chip, true);
    r.ctrl1(ctrl1::RWRNMSK);
    let t = BusTime {
        sof: r.now,
        now: r.now,
    };
    for _ in 0..10 {
        r.m.rx_error(LastErrorCode::Form, true, t); // rules 1 and 2: +9
    }
    for _ in 0..5 {
        r.m.rx_error(LastErrorCode::Stuff, false, t); // rule 1: +1
    }
    assert_eq!(ecr::RXERRCNT.get(r.rd(regs::ECR)), 95);
    assert!(!r.m.irq().warning);
    r.m.rx_error(LastErrorCode::Stuff, false, t);
    assert_eq!(ecr::RXERRCNT.get(r.rd(regs::ECR)), 96);
    let v = r.m.peek32(regs::ESR1);
    assert_ne!(v & (esr1::RXWRN | esr1::RWRNINT), 0);
    assert!(r.m.irq().warning);
    for _ in 0..4 {
        r.m.rx_error(LastErrorCode::Form, true, t);
    }
    assert_eq!(fltconf(&r), esr1::FLTCONF_ERROR_PASSIVE);
    r.deliver(&std(1, &[]));
    assert_eq!(
        r.m.error_counters().rec,
        127,
        "back below 128 after a good frame"
    );
    assert_eq!(fltconf(&r), esr1::FLTCONF_ERROR_ACTIVE);
}

fn warning_interrupts_need_wrnen(chip: Chip) {
    let mut r = rig(chip, false);
    r.ctrl1(ctrl1::RWRNMSK | ctrl1::TWRNMSK);
    let t = BusTime {
        sof: r.now,
        now: r.now,
    };
    for _ in 0..13 {
        r.m.rx_error(LastErrorCode::Form, true, t);
    }
    let v = r.m.peek32(regs::ESR1);
    assert_ne!(v & esr1::RXWRN, 0);
    assert_eq!(v & esr1::RWRNINT, 0);
    assert!(!r.m.irq().warning);
}

/// Drives the module bus-off with 32 bit errors.
fn go_bus_off(r: &mut Rig) {
    r.load_mb(8, &std(0x100, &[1]), code::TX_DATA);
    for _ in 0..32 {
        r.transmit(TxResult::Error(LastErrorCode::BitDominant));
    }
    assert_eq!(fltconf(r), esr1::FLTCONF_BUS_OFF);
    assert_eq!(r.m.error_counters().tec, 256);
}

fn bus_off_and_automatic_recovery(chip: Chip) {
    let mut r = rig(chip, false);
    r.ctrl1(ctrl1::BOFFMSK);
    go_bus_off(&mut r);
    assert_ne!(r.m.peek32(regs::ESR1) & esr1::BOFFINT, 0);
    assert!(r.m.irq().bus_off);
    r.wr(regs::ESR1, esr1::BOFFINT);
    assert!(!r.m.irq().bus_off);
    assert!(
        r.m.poll_tx(r.now).is_none(),
        "no transmission while bus-off"
    );
    assert!(!r.m.listens() && !r.m.acknowledges() && !r.m.error_active());
    // TXERRCNT counts the 11-recessive-bit sequences toward 128.
    assert_eq!(r.rd(regs::ECR) & 0xFF, 0);
    r.idle(11 * 10 + 5);
    assert_eq!(ecr::TXERRCNT.get(r.rd(regs::ECR)), 10);
    r.busy(1); // a dominant bit restarts the current run only
    r.idle(10);
    assert_eq!(ecr::TXERRCNT.get(r.rd(regs::ECR)), 10);
    assert_eq!(r.m.next_wakeup(r.now), Some(r.now + 118 * 11 - 10));
    r.idle(1 + 11 * 116);
    assert_eq!(ecr::TXERRCNT.get(r.rd(regs::ECR)), 127);
    r.idle(10);
    assert_eq!(fltconf(&r), esr1::FLTCONF_BUS_OFF);
    r.idle(1);
    assert_eq!(fltconf(&r), esr1::FLTCONF_ERROR_ACTIVE);
    assert_eq!(r.rd(regs::ECR), 0);
    assert_eq!(
        r.transmit_all(),
        vec![std(0x100, &[1])],
        "the pending frame goes out"
    );
}

fn bus_off_recovery_held_by_boffrec(chip: Chip) {
    let mut r = rig(chip, false);
    r.ctrl1(ctrl1::BOFFREC);
    go_bus_off(&mut r);
    r.idle(128 * 11 + 50);
    assert_eq!(
        fltconf(&r),
        esr1::FLTCONF_BUS_OFF,
        "held until software negates BOFFREC"
    );
    assert_eq!(r.m.next_wakeup(r.now), None);
    r.clear_bits(regs::CTRL1, ctrl1::BOFFREC);
    assert_eq!(fltconf(&r), esr1::FLTCONF_ERROR_ACTIVE);
    assert!(
        !r.m.is_synchronised(),
        "re-synchronises before joining the bus"
    );
    assert!(r.m.poll_tx(r.now).is_none());
    r.idle(11);
    assert_eq!(r.transmit_all().len(), 1);

    // Negated before the 128 sequences: recovery as if automatic.
    let mut r = rig(chip, false);
    r.ctrl1(ctrl1::BOFFREC);
    go_bus_off(&mut r);
    r.idle(50 * 11);
    r.clear_bits(regs::CTRL1, ctrl1::BOFFREC);
    assert_eq!(fltconf(&r), esr1::FLTCONF_BUS_OFF);
    r.idle(78 * 11);
    assert_eq!(fltconf(&r), esr1::FLTCONF_ERROR_ACTIVE);

    // Set after bus-off was entered: effective only the next time.
    let mut r = rig(chip, false);
    go_bus_off(&mut r);
    r.set_bits(regs::CTRL1, ctrl1::BOFFREC);
    r.idle(128 * 11);
    assert_eq!(fltconf(&r), esr1::FLTCONF_ERROR_ACTIVE);
}

fn error_counters_written_in_freeze(chip: Chip) {
    let mut r = rig(chip, true);
    r.freeze();
    r.wr(regs::ECR, ecr::TXERRCNT.val(130) | ecr::RXERRCNT.val(99));
    assert_eq!(
        r.rd(regs::ECR),
        ecr::TXERRCNT.val(130) | ecr::RXERRCNT.val(99)
    );
    assert_eq!(fltconf(&r), esr1::FLTCONF_ERROR_PASSIVE);
    let v = r.m.peek32(regs::ESR1);
    assert_ne!(v & (esr1::TXWRN | esr1::RXWRN), 0);
}

fn soft_reset_clears_the_error_state(chip: Chip) {
    let mut r = rig(chip, false);
    go_bus_off(&mut r);
    r.set_bits(regs::MCR, mcr::SOFTRST);
    assert_eq!(r.rd(regs::ECR), 0);
    assert_eq!(fltconf(&r), esr1::FLTCONF_ERROR_ACTIVE);
    assert_eq!(r.rd(regs::ESR1) & esr1::BOFFINT, 0);
}
