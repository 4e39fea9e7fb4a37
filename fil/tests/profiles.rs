//! The `bluepill` (STM32F103C8) and `nucleo-f446re` (STM32F446RE) board profiles with the
//! test programs of `fil/firmware` (raw register writes from RM0008 / RM0390, no twocan
//! API): the clock set-ups the manuals allow run clean and leave the CAN clock the bit
//! timing was computed for; the interrupt numbers of the vector tables are the lines the
//! controllers raise; the clock gate, a stuck line and the F103's USB/CAN SRAM sharing
//! are reported.

mod common;

use common::*;
use twocan_core::Frame;
use twocan_fil::world::World;
use twocan_sim::SimNode;

/// A world with `board` running `elf` and a plain peer sending standard 0x321 every 2 ms.
fn with_peer(
    board: &str,
    elf: &str,
) -> Option<(World<'static>, std::rc::Rc<std::cell::RefCell<SimNode>>)> {
    let mut w = world(500_000, &[(board, elf)])?;
    let traffic = vec![Frame::standard(0x321, &[9, 8]).unwrap()];
    let peer = w.add_node("peer", SimNode::new(), 500_000, traffic, 2_000_000_000);
    Some((w, peer))
}

fn taken(w: &World<'_>, irq: u32) -> u64 {
    let b = w.machines[0].board();
    b.irq_taken(irq)
}

fn static_u32(w: &World<'_>, name: &str) -> u32 {
    w.machines[0].read_u32_static(name).expect(name)
}

#[test]
fn bluepill_runs_at_72_mhz_and_its_can_talks_on_lines_19_and_20() {
    let Some((mut w, peer)) = with_peer("bluepill", "bluepill-can") else {
        return;
    };
    w.run_for(secs(0.02));
    // No fault, no unknown register, no clock or pin rule violated (RM0008 §3.3.3, §7.2,
    // §9.1.11, §9.3.3): the manual's set-up passes the profile's rules.
    assert_clean(&w);
    let b = w.machines[0].board();
    assert_eq!(b.profile.core_hz(), 72_000_000);
    assert_eq!(b.profile.can_clock_hz(&b.cans[0].instance), 36_000_000);
    assert_eq!(
        w.attached[0].bit_rate,
        Some(500_000),
        "BTR decoded from APB1"
    );
    assert_eq!(static_u32(&w, "FAILED"), 0);
    // One frame sent and acknowledged, the peer's frames received, through the vector
    // table's lines 19 (USB_HP_CAN_TX) and 20 (USB_LP_CAN_RX0).
    assert_eq!(static_u32(&w, "SENT"), 1);
    let received = static_u32(&w, "RECEIVED");
    assert!(received >= 8, "{received}");
    assert_eq!(static_u32(&w, "LAST_ID"), 0x321);
    assert_eq!(taken(&w, 19), 1);
    assert!(taken(&w, 20) >= 1 && taken(&w, 20) <= u64::from(received));
    let got = peer.borrow().received_frames();
    assert_eq!(got, [Frame::standard(0x123, &[1, 2, 3, 4]).unwrap()]);
    assert!(b.console.contains("CAN on the bus at 500 kbit/s"));
}

#[test]
fn nucleo_f446re_runs_at_180_mhz_with_can1_on_the_bus_and_can2_in_loop_back() {
    let Some((mut w, peer)) = with_peer("nucleo-f446re", "nucleo-f446re-can") else {
        return;
    };
    w.run_for(secs(0.02));
    // Over-drive entered before 180 MHz, five wait states, APB1 45 MHz (RM0390 §5.1.4,
    // Table 5; DS10693): nothing reported. The pins are in AF9.
    assert_clean(&w);
    let b = w.machines[0].board();
    assert_eq!(b.profile.core_hz(), 180_000_000);
    assert_eq!(b.profile.can_clock_hz(&b.cans[0].instance), 45_000_000);
    assert_eq!(static_u32(&w, "FAILED"), 0);
    let can1 = w
        .attached
        .iter()
        .find(|a| a.name.ends_with("/CAN1"))
        .unwrap();
    assert_eq!(can1.bit_rate, Some(500_000));
    // CAN1: lines 19 (CAN1_TX) and 20 (CAN1_RX0).
    assert_eq!(static_u32(&w, "SENT1"), 1);
    assert!(static_u32(&w, "RECEIVED1") >= 8);
    assert_eq!(static_u32(&w, "LAST_ID1"), 0x321);
    assert_eq!(taken(&w, 19), 1);
    assert!(taken(&w, 20) >= 1);
    // CAN2: its own frame back through bank 14 of CAN1's block into FIFO 1, lines 63
    // (CAN2_TX) and 65 (CAN2_RX1); nothing on the wire from it.
    assert_eq!(static_u32(&w, "SENT2"), 1);
    assert_eq!(static_u32(&w, "RECEIVED2"), 1);
    assert_eq!(static_u32(&w, "LAST_ID2"), 0x2AA);
    assert_eq!((taken(&w, 63), taken(&w, 65)), (1, 1));
    assert_eq!(taken(&w, 64) + taken(&w, 66), 0);
    assert_eq!(
        peer.borrow().received_frames(),
        [Frame::standard(0x123, &[1, 2, 3, 4]).unwrap()]
    );
    assert_eq!(b.cans[0].model.counters(), (0, 0), "TEC, REC of CAN1");
}

#[test]
fn touching_the_can_with_its_clock_gated_is_reported_on_both_boards() {
    for (board, elf) in [
        ("bluepill", "bluepill-gate"),
        ("nucleo-f446re", "../negative/stm32-gate"),
    ] {
        let Some(mut w) = world(500_000, &[(board, elf)]) else {
            return;
        };
        w.run_for(secs(0.005));
        assert!(!w.clean(), "{board}");
        let b = w.machines[0].board();
        assert_eq!(b.faults.len(), 1, "{board}: {:?}", b.faults);
        let f = &b.faults[0];
        assert_eq!(f.address, Some(0x4000_6400), "{board}");
        assert!(f.kind.contains("clock gated"), "{board}: {}", f.kind);
        // STM32: no bus error, the read gives 0 and the firmware goes on.
        assert!(f.silent && f.taken_as.is_none(), "{board}");
        let reset = w.machines[0].image.symbol("reset").expect("reset");
        let start = reset.address & !1;
        assert!(
            (start..start + reset.size as u32).contains(&f.pc),
            "{board}"
        );
        assert!(b.console.contains("the read returned"), "{board}");
    }
}

#[test]
fn a_can_line_whose_cause_is_never_cleared_is_reported_stuck_on_both_boards() {
    for (board, elf) in [
        ("bluepill", "bluepill-stuck"),
        ("nucleo-f446re", "../negative/stm32-stuck"),
    ] {
        let Some(mut w) = world(500_000, &[(board, elf)]) else {
            return;
        };
        w.run_for(secs(0.01));
        let b = w.machines[0].board();
        assert!(b.faults.is_empty(), "{board}: {:?}", b.faults);
        assert_eq!(b.stuck.len(), 1, "{board}");
        assert_eq!(b.stuck[0].exception, 16 + 19, "{board}: the CAN TX line");
        assert!(!b.console.contains("back in thread mode"), "{board}");
    }
}

#[test]
fn the_f103_usb_and_can_sharing_their_sram_is_reported() {
    // bluepill-stuck turns the USB clock on with the CAN's (RM0008 §24.2 note).
    let Some(mut w) = world(500_000, &[("bluepill", "bluepill-stuck")]) else {
        return;
    };
    w.run_for(secs(0.002));
    let b = w.machines[0].board();
    let shared: Vec<&String> = b
        .findings
        .iter()
        .filter(|f| f.contains("512-byte SRAM"))
        .collect();
    assert_eq!(shared.len(), 1, "{:?}", b.findings);
    // A firmware that turns on the CAN alone is not reported.
    let Some((mut w, _)) = with_peer("bluepill", "bluepill-can") else {
        return;
    };
    w.run_for(secs(0.005));
    assert!(w.machines[0].board().findings.is_empty());
}

#[test]
fn the_bluepill_profile_is_a_cortex_m3_with_64_kib_of_flash_and_20_kib_of_sram() {
    // RM0008 §3.3 memory map; DS5319: the STM32F103C8 has 64 KiB of flash and 20 KiB of
    // SRAM; no FPU (Cortex-M3), so the images are built for thumbv7m-none-eabi.
    let profile = twocan_fil::profile::by_name("bluepill").unwrap();
    let regions: Vec<(u32, u32, bool)> = profile
        .memory()
        .iter()
        .map(|m| (m.base, m.size, m.writable))
        .collect();
    assert_eq!(
        regions,
        [
            (0, 64 << 10, false),
            (0x0800_0000, 64 << 10, false),
            (0x2000_0000, 20 << 10, true)
        ]
    );
    assert_eq!(
        profile.cpu_model(),
        unicorn_engine::ArmCpuModel::CORTEX_M3 as i32
    );
    let f446 = twocan_fil::profile::by_name("nucleo-f446re").unwrap();
    assert_eq!(
        f446.cpu_model(),
        unicorn_engine::ArmCpuModel::CORTEX_M4 as i32
    );
    assert_eq!(f446.irq_count(), 97);
}
