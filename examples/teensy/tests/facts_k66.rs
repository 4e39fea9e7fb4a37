//! The hand-written register addresses, bit positions and interrupt numbers of
//! `twocan-teensy`, checked against the vendor SVD data of the MK66F18 (Teensy 3.6) as
//! `svd2rust` generated it (`facts_k20.rs`: the MK20D7, Teensy 3.2). The PACs are used only here, as a
//! fact source: their `rt` vector tables are not usable with cortex-m-rt 0.7 (the MK66F18
//! crate links cortex-m-rt 0.6) and there is no K64 PAC, so `src/rt.rs` builds the table.
//!
//! The K64 (Teensy 3.5) numbers are not in either SVD: its CAN0 vectors are IRQ 75–80 as
//! on the K66, and it has 86 vectors (IRQ 85 = ENET_Error is the last), per the
//! K64P144M120SF5RM interrupt channel table / the MK64F12 device header.

use core::mem::offset_of;
use twocan_flexcan::Instance;
use twocan_teensy::board::{Board, CAN_VECTORS_PER_INSTANCE};
use twocan_teensy::regs::*;

#[test]
fn k66_interrupt_numbers() {
    use bare_metal::Nr;
    use mk66f18::Interrupt as I;
    let can: [[I; CAN_VECTORS_PER_INSTANCE]; 2] = [
        [
            I::CAN0_ORED_MESSAGE_BUFFER,
            I::CAN0_BUS_OFF,
            I::CAN0_ERROR,
            I::CAN0_TX_WARNING,
            I::CAN0_RX_WARNING,
            I::CAN0_WAKE_UP,
        ],
        [
            I::CAN1_ORED_MESSAGE_BUFFER,
            I::CAN1_BUS_OFF,
            I::CAN1_ERROR,
            I::CAN1_TX_WARNING,
            I::CAN1_RX_WARNING,
            I::CAN1_WAKE_UP,
        ],
    ];
    for (instance, irqs) in [Instance::Can0, Instance::Can1].into_iter().zip(&can) {
        let base = Board::TEENSY36.can_irq_base(instance).unwrap();
        for (i, irq) in irqs.iter().enumerate() {
            assert_eq!(irq.nr() as u16, base + i as u16);
        }
    }
    // CAN1_WAKE_UP is the last vector of the MK66F18 SVD.
    assert_eq!(I::CAN1_WAKE_UP.nr() as usize + 1, Board::TEENSY36.irq_count);
    // The K64 shares the K66's CAN0 numbers; it has no CAN1.
    assert_eq!(Board::TEENSY35.can_irq_base(Instance::Can0), Some(75));
    assert_eq!(Board::TEENSY35.can_irq_base(Instance::Can1), None);
}

#[test]
fn k66_register_addresses() {
    use mk66f18 as pac;
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
        at(portc, offset_of!(pac::portc::RegisterBlock, pcr5)),
        PORTC_PCR0 + 4 * 5
    );
    let gpioc = pac::GPIOC::ptr() as *const ();
    assert_eq!(
        at(gpioc, offset_of!(pac::gpioc::RegisterBlock, psor)),
        GPIOC_PSOR
    );
    assert_eq!(
        at(gpioc, offset_of!(pac::gpioc::RegisterBlock, pcor)),
        GPIOC_PCOR
    );
    assert_eq!(
        at(gpioc, offset_of!(pac::gpioc::RegisterBlock, ptor)),
        GPIOC_PTOR
    );
    assert_eq!(
        at(gpioc, offset_of!(pac::gpioc::RegisterBlock, pddr)),
        GPIOC_PDDR
    );
    let fc = pac::FTFE_FLASHCONFIG::ptr() as *const ();
    use pac::ftfe_flash_config::RegisterBlock as Fc;
    assert_eq!(at(fc, 0), 0x400);
    assert_eq!(at(fc, offset_of!(Fc, fsec)), 0x40C);
    assert_eq!(at(fc, offset_of!(Fc, fopt)), 0x40D);
}

/// A register block of the MK66F18 PAC in host memory, to decode values with the PAC's
/// field readers (bit positions from the SVD).
fn block<T>() -> Box<T> {
    // SAFETY: svd2rust register blocks are `repr(C)` structs of `VolatileCell`s of
    // integers (and reserved byte arrays), for which all-zero bytes are a valid value.
    Box::new(unsafe { core::mem::zeroed() })
}

#[test]
fn k66_bit_positions() {
    use mk66f18 as pac;
    use twocan_teensy::clock::{MCG_C1_FBE, MCG_C2_VALUE, OSC_CR_VALUE, SIM_CLKDIV1_FBE};
    use twocan_teensy::flash_config::FLASH_CONFIG_BYTES;

    let wdog = block::<pac::wdog::RegisterBlock>();
    wdog.stctrlh
        .write(|w| unsafe { w.bits(WDOG_STCTRLH_DISABLED) });
    let r = wdog.stctrlh.read();
    assert!(r.wdogen().bit_is_clear() && r.allowupdate().bit_is_set());
    assert_eq!(
        r.bits() & !(WDOG_STCTRLH_WDOGEN | WDOG_STCTRLH_ALLOWUPDATE),
        0
    );

    let osc = block::<pac::osc::RegisterBlock>();
    osc.cr.write(|w| unsafe { w.bits(OSC_CR_VALUE) });
    let r = osc.cr.read();
    assert!(r.erclken().bit_is_set() && r.sc8p().bit_is_set() && r.sc2p().bit_is_set());
    assert!(r.sc4p().bit_is_clear() && r.sc16p().bit_is_clear() && r.erefsten().bit_is_clear());

    let mcg = block::<pac::mcg::RegisterBlock>();
    mcg.c2
        .write(|w| unsafe { w.bits(MCG_C2_VALUE | MCG_C2_FCFTRIM) });
    let r = mcg.c2.read();
    assert_eq!(r.range().bits(), 2, "very high frequency range");
    assert!(r.erefs().bit_is_set() && r.hgo().bit_is_clear() && r.lp().bit_is_clear());
    assert!(r.fcftrim().bit_is_set() && r.locre0().bit_is_clear());
    mcg.c1.write(|w| unsafe { w.bits(MCG_C1_FBE) });
    let r = mcg.c1.read();
    assert_eq!((r.clks().bits(), r.frdiv().bits()), (2, 4));
    assert!(r.irefs().bit_is_clear());
    mcg.s
        .write(|w| unsafe { w.bits(MCG_S_OSCINIT0 | (2 << MCG_S_CLKST_SHIFT)) });
    let r = mcg.s.read();
    assert!(r.oscinit0().bit_is_set() && r.irefst().bit_is_clear());
    assert_eq!(r.clkst().bits(), 2);
    mcg.s.write(|w| unsafe { w.bits(MCG_S_IREFST) });
    assert!(mcg.s.read().irefst().bit_is_set());

    let sim = block::<pac::sim::RegisterBlock>();
    sim.scgc5.write(|w| unsafe { w.bits(SIM_SCGC5_PORTC) });
    let r = sim.scgc5.read();
    assert!(r.portc().bit_is_set() && r.portb().bit_is_clear() && r.portd().bit_is_clear());
    sim.clkdiv1.write(|w| unsafe { w.bits(SIM_CLKDIV1_FBE) });
    let r = sim.clkdiv1.read();
    assert_eq!(
        [
            r.outdiv1().bits(),
            r.outdiv2().bits(),
            r.outdiv3().bits(),
            r.outdiv4().bits()
        ],
        [0; 4]
    );
    sim.clkdiv1.write(|w| unsafe { w.bits(0x1234_0000) });
    let r = sim.clkdiv1.read();
    assert_eq!(
        [
            r.outdiv1().bits(),
            r.outdiv2().bits(),
            r.outdiv3().bits(),
            r.outdiv4().bits()
        ],
        [1, 2, 3, 4],
        "OUTDIV1 is bits 31:28 ... OUTDIV4 bits 19:16"
    );

    let portc = block::<pac::portc::RegisterBlock>();
    portc
        .pcr5
        .write(|w| unsafe { w.bits(twocan_teensy::led::PCR_VALUE) });
    let r = portc.pcr5.read();
    assert_eq!(r.mux().bits(), 1, "GPIO");
    assert!(r.dse().bit_is_set() && r.sre().bit_is_set() && r.ode().bit_is_clear());

    // FSEC and FOPT are read-only in the PAC: put the bytes in place, then decode.
    use pac::ftfe_flash_config::RegisterBlock as Fc;
    let mut fc = block::<Fc>();
    let raw = &mut *fc as *mut Fc as *mut u8;
    // SAFETY: `raw` points to the 16-byte `repr(C)` block owned by `fc`; FSEC and FOPT
    // are the byte fields at these offsets.
    unsafe {
        raw.add(offset_of!(Fc, fsec)).write(FLASH_CONFIG_BYTES[12]);
        raw.add(offset_of!(Fc, fopt)).write(FLASH_CONFIG_BYTES[13]);
    }
    let r = fc.fsec.read();
    assert!(r.sec().is_10(), "unsecured");
    assert!(!r.meen().is_10(), "mass erase enabled");
    assert!(!r.keyen().is_10(), "backdoor key disabled");
    let r = fc.fopt.read();
    assert!(r.lpboot().is_01(), "normal boot");
    assert!(r.ezport_dis().is_00(), "EzPort disabled");
    assert!(r.nmi_dis().is_00(), "NMI disabled");
}
