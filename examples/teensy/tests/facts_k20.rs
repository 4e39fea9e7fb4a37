//! The hand-written register addresses, bit positions and interrupt numbers of
//! `twocan-teensy`, checked against the vendor SVD data of the MK20D7 (Teensy 3.2) as
//! `svd2rust` generated it (`facts_k66.rs`: the MK66F18, Teensy 3.6; the two PACs cannot
//! be linked into one test binary). The PACs are used only here, as a
//! fact source: their `rt` vector tables are not usable with cortex-m-rt 0.7 (the MK66F18
//! crate links cortex-m-rt 0.6) and there is no K64 PAC, so `src/rt.rs` builds the table.
//!
//! The K64 (Teensy 3.5) numbers are not in either SVD: its CAN0 vectors are IRQ 75–80 as
//! on the K66, and it has 86 vectors (IRQ 85 = ENET_Error is the last), per the
//! K64P144M120SF5RM interrupt channel table / the MK64F12 device header.

#![allow(deprecated)] // `cortex_m::interrupt::Nr`, the trait mk20d7 0.1 implements

use core::mem::offset_of;
use twocan_flexcan::Instance;
use twocan_teensy::board::Board;
use twocan_teensy::regs::*;

#[test]
fn k20_interrupt_numbers() {
    use cortex_m::interrupt::Nr;
    use mk20d7::Interrupt as I;
    let can0 = [
        I::CAN0_ORED_MESSAGE_BUFFER,
        I::CAN0_BUS_OFF,
        I::CAN0_ERROR,
        I::CAN0_TX_WARNING,
        I::CAN0_RX_WARNING,
        I::CAN0_WAKE_UP,
    ];
    for (i, irq) in can0.iter().enumerate() {
        assert_eq!(
            irq.nr() as u16,
            Board::TEENSY32.can_irq_base(Instance::Can0).unwrap() + i as u16
        );
    }
    // PORTE is the last vector of the MK20D7 SVD.
    assert_eq!(I::PORTE.nr() as usize + 1, Board::TEENSY32.irq_count);
}

#[test]
fn k20_register_addresses() {
    use mk20d7 as pac;
    let at = |p: *const (), off: usize| p as usize + off;
    let wdog = pac::WDOG::ptr() as *const ();
    assert_eq!(
        at(wdog, offset_of!(pac::wdog::RegisterBlock, stctrlh)),
        WDOG_STCTRLH
    );
    assert_eq!(
        at(wdog, offset_of!(pac::wdog::RegisterBlock, unlock)),
        WDOG_UNLOCK
    );
    let mcg = pac::MCG::ptr() as *const ();
    assert_eq!(at(mcg, offset_of!(pac::mcg::RegisterBlock, c1)), MCG_C1);
    assert_eq!(at(mcg, offset_of!(pac::mcg::RegisterBlock, c2)), MCG_C2);
    assert_eq!(at(mcg, offset_of!(pac::mcg::RegisterBlock, c6)), MCG_C6);
    assert_eq!(at(mcg, offset_of!(pac::mcg::RegisterBlock, s)), MCG_S);
    let osc = pac::OSC::ptr() as *const ();
    assert_eq!(at(osc, offset_of!(pac::osc::RegisterBlock, cr)), OSC0_CR);
    let sim = pac::SIM::ptr() as *const ();
    assert_eq!(
        at(sim, offset_of!(pac::sim::RegisterBlock, scgc5)),
        SIM_SCGC5
    );
    assert_eq!(
        at(sim, offset_of!(pac::sim::RegisterBlock, clkdiv1)),
        SIM_CLKDIV1
    );
    let portc = pac::PORTC::ptr() as *const ();
    assert_eq!(
        at(portc, offset_of!(pac::portc::RegisterBlock, pcr)),
        PORTC_PCR0
    );
    let ptc = pac::PTC::ptr() as *const ();
    assert_eq!(at(ptc, 0), GPIOC_BASE);
    assert_eq!(
        at(ptc, offset_of!(pac::ptc::RegisterBlock, psor)),
        GPIOC_PSOR
    );
    assert_eq!(
        at(ptc, offset_of!(pac::ptc::RegisterBlock, pcor)),
        GPIOC_PCOR
    );
    assert_eq!(
        at(ptc, offset_of!(pac::ptc::RegisterBlock, ptor)),
        GPIOC_PTOR
    );
    assert_eq!(
        at(ptc, offset_of!(pac::ptc::RegisterBlock, pddr)),
        GPIOC_PDDR
    );
    let fc = pac::FTFL_FLASHCONFIG::ptr() as *const ();
    use pac::ftfl_flash_config::RegisterBlock as Fc;
    assert_eq!(at(fc, 0), 0x400);
    assert_eq!(at(fc, offset_of!(Fc, fsec)), 0x40C);
    assert_eq!(at(fc, offset_of!(Fc, fopt)), 0x40D);
    assert_eq!(at(fc, offset_of!(Fc, feprot)), 0x40E);
    assert_eq!(at(fc, offset_of!(Fc, fdprot)), 0x40F);
}
