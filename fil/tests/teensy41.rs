//! The `teensy41` profile (i.MX RT1062) on its own test firmwares (`fil/firmware`,
//! linked with `imxrt1062.ld`): the boot ROM starts a FlexSPI boot image, the reset
//! handler's copies to ITCM/DTCM/OCRAM work, VTOR set by the firmware routes an
//! exception; a closed CAN register gate faults with the PC; no CAN clock root leaves
//! the FlexCAN frozen; an interrupt whose cause is never cleared is reported stuck.

mod common;

use common::*;
use twocan_fil::elf::Image;
use twocan_fil::nvic::exc;
use twocan_fil::profile;
use twocan_fil::world::World;
use twocan_flexcan::model::ModelMode;

fn reset_range(w: &World<'_>) -> std::ops::Range<u32> {
    let s = w.machines[0].image.symbol("reset").expect("reset symbol");
    let start = s.address & !1;
    start..start + s.size as u32
}

#[test]
fn boot_image_starts_and_the_reset_handler_fills_itcm_dtcm_ocram() {
    let Some(mut w) = world(500_000, &[("teensy41", "../negative/imxrt-boot")]) else {
        return;
    };
    w.run_for(secs(0.002));
    let b = w.machines[0].board();
    for line in [
        "started from the IVT entry",
        ".data in DTCM, .bss zeroed",
        "OCRAM written",
        "ran from ITCM",
        "SVCall through the flash vector table",
    ] {
        assert!(b.console.contains(line), "{line}: {:?}", b.console);
    }
    assert!(!b.console.contains("fault"), "{:?}", b.console);
    assert!(
        b.faults.is_empty() && b.halted.is_none(),
        "{:?} {:?}",
        b.faults,
        b.halted
    );
    assert_eq!(b.taken.get(&exc::SVCALL), Some(&1));
    let itcm = w.machines[0].image.symbol("in_itcm").expect("symbol");
    assert!(itcm.address < 0x8_0000, "in_itcm at 0x{:08X}", itcm.address);
}

#[test]
fn an_image_the_boot_rom_refuses_halts_the_board_with_the_reason() {
    let Some(good) = elf("negative", "imxrt-boot") else {
        return;
    };
    // A Kinetis firmware (linked at 0, which the RT1062 maps as ITCM) has no boot image
    // in the FlexSPI flash: the ROM finds no configuration block.
    let mut w = World::new(500_000).expect("bus");
    let kinetis = elf("negative", "kinetis-gate").expect("built with the others");
    w.add_board(profile::by_name("teensy41").unwrap(), kinetis)
        .expect("board");
    w.run_for(secs(0.001));
    let why = w.machines[0].board().halted.clone().unwrap_or_default();
    assert!(why.contains("no FlexSPI configuration block"), "{why}");
    // The boot image with its FCB tag erased.
    let mut w = World::new(500_000).expect("bus");
    let mut broken: Image = good.clone();
    let seg = broken
        .segments
        .iter_mut()
        .find(|s| s.address == 0x6000_0000)
        .expect("boot segment");
    seg.data[0] = 0;
    w.add_board(profile::by_name("teensy41").unwrap(), broken)
        .expect("board");
    w.run_for(secs(0.001));
    let b = w.machines[0].board();
    let why = b.halted.as_deref().unwrap_or("");
    assert!(why.contains("boot ROM") && why.contains("FCFB"), "{why}");
    assert_eq!(b.instructions, 0);
    // An IVT whose self pointer is wrong.
    let mut broken = good.clone();
    let seg = broken
        .segments
        .iter_mut()
        .find(|s| s.address == 0x6000_0000)
        .unwrap();
    seg.data[0x1014] ^= 0x10;
    let mut w = World::new(500_000).expect("bus");
    w.add_board(profile::by_name("teensy41").unwrap(), broken)
        .expect("board");
    w.run_for(secs(0.001));
    let why = w.machines[0].board().halted.clone().unwrap_or_default();
    assert!(why.contains("self pointer"), "{why}");
}

#[test]
fn can1_register_access_with_its_gate_closed_faults_with_the_pc() {
    let Some(mut w) = world(500_000, &[("teensy41", "../negative/imxrt-gate")]) else {
        return;
    };
    w.run_for(secs(0.002));
    let b = w.machines[0].board();
    assert_eq!(b.faults.len(), 1, "{:?}", b.faults);
    let f = &b.faults[0];
    assert_eq!(f.address, Some(0x401D_0000));
    assert!(
        f.kind.contains("clock gated") && f.kind.contains("CG7"),
        "{}",
        f.kind
    );
    assert!(reset_range(&w).contains(&f.pc), "PC 0x{:08X}", f.pc);
    assert_eq!(f.taken_as, Some(exc::HARD_FAULT));
    assert!(b.console.contains("fault handler"), "{:?}", b.console);
    assert!(!b.console.contains("no fault"));
}

#[test]
fn without_the_can_clock_root_the_flexcan_stays_frozen() {
    let Some(mut w) = world(500_000, &[("teensy41", "../negative/imxrt-no-can-clock")]) else {
        return;
    };
    w.run_for(secs(0.005));
    let b = w.machines[0].board();
    assert!(b.console.contains("timeout"), "{:?}", b.console);
    assert!(b.faults.is_empty(), "{:?}", b.faults);
    let twocan_fil::can::Model::FlexCan(m) = &b.cans[0].model else {
        panic!("CAN1 is a FlexCAN");
    };
    assert_eq!(m.mode(), ModelMode::Freeze);
}

#[test]
fn a_can1_interrupt_never_cleared_is_reported_stuck() {
    let Some(mut w) = world(500_000, &[("teensy41", "../negative/imxrt-stuck")]) else {
        return;
    };
    w.run_for(secs(0.01));
    let b = w.machines[0].board();
    assert!(b.console.contains("enabling IRQ 36"), "{:?}", b.console);
    assert!(!b.console.contains("timeout"), "{:?}", b.console);
    assert_eq!(b.stuck.len(), 1, "{:?}", b.stuck);
    assert_eq!(b.stuck[0].exception, exc::IRQ0 + 36);
    assert!(
        !b.console.contains("back in thread mode"),
        "{:?}",
        b.console
    );
}
