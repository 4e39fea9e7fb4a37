//! Checks `twocan_bxcan::regs` against the vendor SVD data as published in the `stm32f7`
//! PAC (chip STM32F767, which has CAN1, CAN2 and CAN3):
//! - every register offset equals the address of the PAC's register in a CAN1 register
//!   block minus the block's address;
//! - every bit and field has the PAC's position and width: a PAC register block is placed
//!   in host memory, the raw register word is set to our mask (the PAC's field reader
//!   must read all ones) and to its complement (the reader must read 0);
//! - base addresses and reset values agree (with the one documented SVD/RM0410
//!   difference: `CAN_BTR`).

use std::mem::size_of;

use stm32f7::stm32f767 as pac;
use stm32f7::{Readable, Reg, RegisterSpec, Resettable};
use twocan_bxcan::regs::{self, Field, Instance};

use pac::can1::RegisterBlock;

/// A zeroed CAN register block in host memory.
fn block() -> &'static RegisterBlock {
    assert_eq!(size_of::<RegisterBlock>() % 4, 0);
    let words = size_of::<RegisterBlock>() / 4;
    let mem: &'static mut [u32] = Box::leak(vec![0u32; words].into_boxed_slice());
    // SAFETY: `mem` is a fresh, initialised, u32-aligned allocation exactly the size of
    // `RegisterBlock` (a `repr(C)` struct of `u32` volatile cells, 4-byte aligned, for
    // which every bit pattern is valid). It is leaked, so it lives for `'static`, and the
    // mutable borrow is given up here: from now on it is reached only through the
    // returned reference, whose cells allow interior mutation. It is host memory, never a
    // device address.
    unsafe { &*(mem.as_mut_ptr() as *const RegisterBlock) }
}

/// Byte offset of register `r` inside `rb`.
fn offset<T>(rb: &RegisterBlock, r: &T) -> usize {
    r as *const T as usize - rb as *const RegisterBlock as usize
}

/// Sets the raw word of a register of the host-memory block.
fn poke<REG: RegisterSpec<Ux = u32>>(reg: &Reg<REG>, value: u32) {
    // SAFETY: `reg` lies in the allocation made by `block()`; `as_ptr` is the pointer of
    // its `UnsafeCell`, valid and aligned for a `u32` write through a shared reference;
    // the test is single-threaded and holds no other reference into the cell's content.
    unsafe { reg.as_ptr().write_volatile(value) }
}

/// Asserts that the PAC field read by `get` occupies exactly the bits of `mask`.
fn check<REG>(name: &str, reg: &Reg<REG>, get: impl Fn(&Reg<REG>) -> u32, mask: u32)
where
    REG: RegisterSpec<Ux = u32> + Readable,
{
    let all_ones = mask >> mask.trailing_zeros();
    poke(reg, mask);
    assert_eq!(
        get(reg),
        all_ones,
        "{name}: PAC field does not read all ones at {mask:#010x}"
    );
    poke(reg, !mask);
    assert_eq!(
        get(reg),
        0,
        "{name}: PAC field reads bits outside {mask:#010x}"
    );
    poke(reg, 0);
}

/// Single bits: `PAC reader method => our mask`.
macro_rules! bits {
    ($reg:expr, $($f:ident => $mask:expr),+ $(,)?) => {
        $( check(stringify!($f), $reg, |r| r.read().$f().bit() as u32, $mask); )+
    };
}

/// Multi-bit fields: `PAC reader method => our Field`.
macro_rules! fields {
    ($reg:expr, $($f:ident => $field:expr),+ $(,)?) => {
        $( {
            let field: Field = $field;
            assert_eq!(field.mask().trailing_zeros(), field.pos);
            check(stringify!($f), $reg, |r| r.read().$f().bits() as u32, field.mask());
        } )+
    };
}

#[test]
fn base_addresses_match_the_pac() {
    assert_eq!(pac::CAN1::PTR as usize, regs::CAN1_BASE);
    assert_eq!(pac::CAN2::PTR as usize, regs::CAN2_BASE);
    assert_eq!(pac::CAN3::PTR as usize, regs::CAN3_BASE);
    assert_eq!(Instance::Can1.base(), regs::CAN1_BASE);
    assert_eq!(Instance::Can2.base(), regs::CAN2_BASE);
    assert_eq!(Instance::Can3.base(), regs::CAN3_BASE);
    // CAN2 has no filter block: it uses CAN1's.
    assert_eq!(Instance::Can2.filter_base(), regs::CAN1_BASE);
    assert_eq!(Instance::Can3.filter_base(), regs::CAN3_BASE);
    assert!(!Instance::Can2.has_own_filters());
    assert_eq!(Instance::Can1.filter_banks(), 28);
    assert_eq!(Instance::Can3.filter_banks(), 14);
}

/// The window of a fixed-base register type: (base, start, end).
fn window<const B: usize, const E: usize, const S: usize>(
    _: std::marker::PhantomData<twocan_core::Fixed<B, E, S>>,
) -> (usize, usize, usize) {
    (B, S, E)
}

#[test]
fn fixed_register_types_are_at_the_pac_s_addresses() {
    use std::marker::PhantomData as T;
    let (whole, control) = (regs::BLOCK_END, regs::FILTERS_START);
    assert_eq!(
        window(T::<regs::Can1At>),
        (pac::CAN1::PTR as usize, 0, whole)
    );
    assert_eq!(
        window(T::<regs::Can1ControlAt>),
        (pac::CAN1::PTR as usize, 0, control)
    );
    assert_eq!(
        window(T::<regs::Can2At>),
        (pac::CAN2::PTR as usize, 0, control)
    );
    assert_eq!(
        window(T::<regs::Can3At>),
        (pac::CAN3::PTR as usize, 0, whole)
    );
}

#[test]
fn register_offsets_match_the_pac() {
    let rb = block();
    assert_eq!(offset(rb, rb.mcr()), regs::MCR);
    assert_eq!(offset(rb, rb.msr()), regs::MSR);
    assert_eq!(offset(rb, rb.tsr()), regs::TSR);
    assert_eq!(offset(rb, rb.rf0r()), regs::RF0R);
    assert_eq!(offset(rb, rb.rf1r()), regs::RF1R);
    assert_eq!(offset(rb, rb.ier()), regs::IER);
    assert_eq!(offset(rb, rb.esr()), regs::ESR);
    assert_eq!(offset(rb, rb.btr()), regs::BTR);
    for x in 0..regs::RX_FIFOS {
        assert_eq!(offset(rb, rb.rfr(x)), regs::rfxr(x));
        assert_eq!(offset(rb, rb.rx(x).rir()), regs::rixr(x));
        assert_eq!(offset(rb, rb.rx(x).rdtr()), regs::rdtxr(x));
        assert_eq!(offset(rb, rb.rx(x).rdlr()), regs::rdlxr(x));
        assert_eq!(offset(rb, rb.rx(x).rdhr()), regs::rdhxr(x));
    }
    for x in 0..regs::TX_MAILBOXES {
        assert_eq!(offset(rb, rb.tx(x).tir()), regs::tixr(x));
        assert_eq!(offset(rb, rb.tx(x).tdtr()), regs::tdtxr(x));
        assert_eq!(offset(rb, rb.tx(x).tdlr()), regs::tdlxr(x));
        assert_eq!(offset(rb, rb.tx(x).tdhr()), regs::tdhxr(x));
    }
    assert_eq!(offset(rb, rb.fmr()), regs::FMR);
    assert_eq!(offset(rb, rb.fm1r()), regs::FM1R);
    assert_eq!(offset(rb, rb.fs1r()), regs::FS1R);
    assert_eq!(offset(rb, rb.ffa1r()), regs::FFA1R);
    assert_eq!(offset(rb, rb.fa1r()), regs::FA1R);
    assert_eq!(rb.fb_iter().count(), regs::FILTER_BANKS);
    for i in 0..regs::FILTER_BANKS {
        assert_eq!(offset(rb, rb.fb(i).fr1()), regs::fir1(i));
        assert_eq!(offset(rb, rb.fb(i).fr2()), regs::fir2(i));
    }
    assert_eq!(
        size_of::<RegisterBlock>(),
        regs::fir2(regs::FILTER_BANKS - 1) + 4
    );
}

#[test]
fn control_and_status_bits_match_the_pac() {
    use regs::{btr, esr, ier, mcr, msr, rfxr, tsr};
    let rb = block();
    bits!(rb.mcr(),
        inrq => mcr::INRQ, sleep => mcr::SLEEP, txfp => mcr::TXFP, rflm => mcr::RFLM,
        nart => mcr::NART, awum => mcr::AWUM, abom => mcr::ABOM, ttcm => mcr::TTCM,
        reset => mcr::RESET, dbf => mcr::DBF);
    bits!(rb.msr(),
        inak => msr::INAK, slak => msr::SLAK, erri => msr::ERRI, wkui => msr::WKUI,
        slaki => msr::SLAKI, txm => msr::TXM, rxm => msr::RXM, samp => msr::SAMP,
        rx => msr::RX);
    bits!(rb.tsr(),
        rqcp0 => tsr::RQCP0, txok0 => tsr::TXOK0, alst0 => tsr::ALST0, terr0 => tsr::TERR0,
        abrq0 => tsr::ABRQ0, rqcp1 => tsr::RQCP1, txok1 => tsr::TXOK1, alst1 => tsr::ALST1,
        terr1 => tsr::TERR1, abrq1 => tsr::ABRQ1, rqcp2 => tsr::RQCP2, txok2 => tsr::TXOK2,
        alst2 => tsr::ALST2, terr2 => tsr::TERR2, abrq2 => tsr::ABRQ2, tme0 => tsr::TME0,
        tme1 => tsr::TME1, tme2 => tsr::TME2, low0 => tsr::LOW0, low1 => tsr::LOW1,
        low2 => tsr::LOW2);
    fields!(rb.tsr(), code => tsr::CODE);
    // The indexed helpers agree with the named bits.
    let named = [
        [
            tsr::RQCP0,
            tsr::TXOK0,
            tsr::ALST0,
            tsr::TERR0,
            tsr::ABRQ0,
            tsr::TME0,
            tsr::LOW0,
        ],
        [
            tsr::RQCP1,
            tsr::TXOK1,
            tsr::ALST1,
            tsr::TERR1,
            tsr::ABRQ1,
            tsr::TME1,
            tsr::LOW1,
        ],
        [
            tsr::RQCP2,
            tsr::TXOK2,
            tsr::ALST2,
            tsr::TERR2,
            tsr::ABRQ2,
            tsr::TME2,
            tsr::LOW2,
        ],
    ];
    for (x, n) in named.iter().enumerate() {
        let f = [
            tsr::rqcp,
            tsr::txok,
            tsr::alst,
            tsr::terr,
            tsr::abrq,
            tsr::tme,
            tsr::low,
        ];
        for (bit, f) in n.iter().zip(f) {
            assert_eq!(*bit, f(x));
        }
    }
    for x in 0..regs::RX_FIFOS {
        fields!(rb.rfr(x), fmp => rfxr::FMP);
        bits!(rb.rfr(x), full => rfxr::FULL, fovr => rfxr::FOVR, rfom => rfxr::RFOM);
    }
    bits!(rb.ier(),
        tmeie => ier::TMEIE, fmpie0 => ier::FMPIE0, ffie0 => ier::FFIE0,
        fovie0 => ier::FOVIE0, fmpie1 => ier::FMPIE1, ffie1 => ier::FFIE1,
        fovie1 => ier::FOVIE1, ewgie => ier::EWGIE, epvie => ier::EPVIE, bofie => ier::BOFIE,
        lecie => ier::LECIE, errie => ier::ERRIE, wkuie => ier::WKUIE, slkie => ier::SLKIE);
    for x in 0..regs::RX_FIFOS {
        assert_eq!(
            [ier::fmpie(x), ier::ffie(x), ier::fovie(x)],
            [
                [ier::FMPIE0, ier::FMPIE1][x],
                [ier::FFIE0, ier::FFIE1][x],
                [ier::FOVIE0, ier::FOVIE1][x],
            ]
        );
    }
    bits!(rb.esr(), ewgf => esr::EWGF, epvf => esr::EPVF, boff => esr::BOFF);
    fields!(rb.esr(), lec => esr::LEC, tec => esr::TEC, rec => esr::REC);
    fields!(rb.btr(), brp => btr::BRP, ts1 => btr::TS1, ts2 => btr::TS2, sjw => btr::SJW);
    bits!(rb.btr(), lbkm => btr::LBKM, silm => btr::SILM);
}

#[test]
fn mailbox_bits_match_the_pac() {
    use regs::{rdhxr, rdlxr, rdtxr, rixr, tdhxr, tdlxr, tdtxr, tixr};
    let rb = block();
    for x in 0..regs::TX_MAILBOXES {
        let tx = rb.tx(x);
        bits!(tx.tir(), txrq => tixr::TXRQ, rtr => tixr::RTR, ide => tixr::IDE);
        fields!(tx.tir(), exid => tixr::EXID, stid => tixr::STID);
        fields!(tx.tdtr(), dlc => tdtxr::DLC, time => tdtxr::TIME);
        bits!(tx.tdtr(), tgt => tdtxr::TGT);
        fields!(tx.tdlr(),
            data0 => tdlxr::DATA0, data1 => tdlxr::DATA1, data2 => tdlxr::DATA2,
            data3 => tdlxr::DATA3);
        fields!(tx.tdhr(),
            data4 => tdhxr::DATA4, data5 => tdhxr::DATA5, data6 => tdhxr::DATA6,
            data7 => tdhxr::DATA7);
    }
    for x in 0..regs::RX_FIFOS {
        let rx = rb.rx(x);
        bits!(rx.rir(), rtr => rixr::RTR, ide => rixr::IDE);
        fields!(rx.rir(), exid => rixr::EXID, stid => rixr::STID);
        fields!(rx.rdtr(), dlc => rdtxr::DLC, fmi => rdtxr::FMI, time => rdtxr::TIME);
        fields!(rx.rdlr(),
            data0 => rdlxr::DATA0, data1 => rdlxr::DATA1, data2 => rdlxr::DATA2,
            data3 => rdlxr::DATA3);
        fields!(rx.rdhr(),
            data4 => rdhxr::DATA4, data5 => rdhxr::DATA5, data6 => rdhxr::DATA6,
            data7 => rdhxr::DATA7);
    }
}

#[test]
fn filter_bits_match_the_pac() {
    use regs::{fa1r, ffa1r, fm1r, fmr, fs1r};
    let rb = block();
    bits!(rb.fmr(), finit => fmr::FINIT);
    fields!(rb.fmr(), can2sb => fmr::CAN2SB);
    for i in 0..regs::FILTER_BANKS {
        let n = i as u8;
        check(
            "FBM",
            rb.fm1r(),
            |r| r.read().fbm(n).bit() as u32,
            fm1r::fbm(i),
        );
        check(
            "FSC",
            rb.fs1r(),
            |r| r.read().fsc(n).bit() as u32,
            fs1r::fsc(i),
        );
        check(
            "FFA",
            rb.ffa1r(),
            |r| r.read().ffa(n).bit() as u32,
            ffa1r::ffa(i),
        );
        check(
            "FACT",
            rb.fa1r(),
            |r| r.read().fact(n).bit() as u32,
            fa1r::fact(i),
        );
        check("FiR1", rb.fb(i).fr1(), |r| r.read().fb().bits(), u32::MAX);
        check("FiR2", rb.fb(i).fr2(), |r| r.read().fb().bits(), u32::MAX);
    }
}

#[test]
fn filter_bank_layout_matches_the_mailbox_identifier_layout() {
    // RM0410 40.7.4: a 32-bit filter register has the layout of CAN_TIxR / CAN_RIxR.
    use regs::{firx, rixr, tixr};
    assert_eq!(firx::STID, tixr::STID);
    assert_eq!(firx::EXID, tixr::EXID);
    assert_eq!((firx::IDE, firx::RTR), (tixr::IDE, tixr::RTR));
    assert_eq!(
        (rixr::STID, rixr::EXID, rixr::IDE, rixr::RTR),
        (tixr::STID, tixr::EXID, tixr::IDE, tixr::RTR)
    );
    // 16-bit layout STID[10:0] RTR IDE EXID[17:15] fills the half-word exactly.
    let half = firx::STID16.mask() | firx::RTR16 | firx::IDE16 | firx::EXID16.mask();
    assert_eq!(half, 0xFFFF);
    assert_eq!(firx::LOW_HALF.mask() | firx::HIGH_HALF.mask(), u32::MAX);
}

#[test]
fn reset_values_match_the_pac() {
    use pac::can1::{btr, esr, fa1r, ffa1r, fm1r, fmr, fs1r, ier, mcr, msr, rfr, tsr};
    assert_eq!(
        <mcr::MCRrs as Resettable>::RESET_VALUE,
        regs::mcr::RESET_VALUE
    );
    assert_eq!(
        <msr::MSRrs as Resettable>::RESET_VALUE,
        regs::msr::RESET_VALUE
    );
    assert_eq!(
        <tsr::TSRrs as Resettable>::RESET_VALUE,
        regs::tsr::RESET_VALUE
    );
    assert_eq!(
        <fmr::FMRrs as Resettable>::RESET_VALUE,
        regs::fmr::RESET_VALUE
    );
    for zero in [
        <rfr::RFRrs as Resettable>::RESET_VALUE,
        <ier::IERrs as Resettable>::RESET_VALUE,
        <esr::ESRrs as Resettable>::RESET_VALUE,
        <fm1r::FM1Rrs as Resettable>::RESET_VALUE,
        <fs1r::FS1Rrs as Resettable>::RESET_VALUE,
        <ffa1r::FFA1Rrs as Resettable>::RESET_VALUE,
        <fa1r::FA1Rrs as Resettable>::RESET_VALUE,
    ] {
        assert_eq!(zero, 0);
    }
    // The SVD gives CAN_BTR a reset value of 0; RM0410 (40.9.2, "CAN bit timing
    // register") gives 0x0123 0000 (SJW = 1, TS2 = 2, TS1 = 3). regs.rs follows RM0410.
    assert_eq!(<btr::BTRrs as Resettable>::RESET_VALUE, 0);
    assert_eq!(regs::btr::RESET_VALUE, 0x0123_0000);
}

#[test]
fn field_helpers() {
    let f = regs::tsr::CODE;
    assert_eq!(f.mask(), 0x0300_0000);
    assert_eq!(f.max(), 3);
    assert_eq!(f.get(0xFFFF_FFFF), 3);
    assert_eq!(f.set(0, 2), 0x0200_0000);
    assert_eq!(f.set(0xFFFF_FFFF, 0), 0xFCFF_FFFF);
    assert_eq!(f.val(7), 0x0300_0000, "bits beyond the width are dropped");
    assert_eq!(Field::new(0, 32).mask(), u32::MAX);
    assert_eq!(regs::rfxr(1), regs::RF1R);
}
