//! The exception model against the ARMv7-M rules, through `fil/firmware`'s `core-check`
//! (raw registers, no twocan code): the order of its event log is the order the
//! architecture gives.

mod common;

use common::*;
use twocan_fil::nvic::exc;

#[test]
fn exception_order_follows_the_armv7m_rules() {
    let Some(mut w) = world(500_000, &[("teensy36", "../negative/core-check")]) else {
        return;
    };
    w.run_for(secs(0.01));
    assert_clean(&w);
    let m = &w.machines[0];
    let len = m.read_u32_static("LEN").expect("LEN") as usize;
    let raw = m.read_static("LOG").expect("LOG");
    let log: Vec<u32> = (0..len)
        .map(|i| u32::from_le_bytes(raw[4 * i..4 * i + 4].try_into().unwrap()))
        .collect();
    let expected = [
        // IRQ 0 (0x80) taken at once; it pends IRQ 1 (0x40), which preempts it, and IRQ 3
        // (0xC0), which waits for its return and is tail-chained before thread mode.
        1, 10, 11, 12, 13, 2, // BASEPRI 0x40 holds IRQ 2 (0x40) until cleared.
        3, 14, 4, // PRIMASK holds IRQ 0 until CPSIE; then the same nesting as above.
        5, 10, 11, 12, 13, 6, // SVC.
        20, 7,
        // DWT CYCCNT counted the loop; SysTick COUNTFLAG; SysTick interrupt wakes WFI.
        8, 9, 30, 15,
        // WFE after an exception return and after SEV goes on; with the event register
        // clear it sleeps until the next SysTick interrupt.
        16, 17, 30, 18,
    ];
    assert_eq!(log, expected);
    let b = m.board();
    assert_eq!(b.taken.get(&exc::SVCALL), Some(&1));
    assert_eq!(b.taken.get(&exc::SYSTICK), Some(&2));
    assert_eq!(b.taken.get(&(exc::IRQ0 + 3)), Some(&2));
    assert!(b.console.contains("core-check: done"));
}
