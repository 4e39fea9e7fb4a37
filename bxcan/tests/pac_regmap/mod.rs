//! Checks shared by the register-map tests of the F1 and F4 families (`regmap_f1.rs`,
//! `regmap_f4.rs`; `regmap.rs` does the same for the F7 with its own copy): macros that
//! expand against one svd2rust 0.16 PAC crate, whose register blocks all have the same
//! method names.
//!
//! - [`pac_helpers!`]: a zeroed register block in host memory, register offsets, raw
//!   pokes and a field check (the PAC's reader must read all ones on our mask and 0 on
//!   its complement);
//! - [`can_layout_matches!`]: every offset, bit and field of `twocan_bxcan::regs` against
//!   one PAC CAN register block, for the bank count the PAC gives;
//! - [`model_matches_pac!`]: the model of a part, read at the PAC's offsets: its reset
//!   values are the PAC's (or, where the vendor SVD has none, the manual's, given), and
//!   its filter registers are exactly as wide as the PAC's field arrays.
#![allow(unused_macros, dead_code)]

/// Host-memory register blocks and the field check for the PAC crate `$pac`.
macro_rules! pac_helpers {
    ($pac:ident) => {
        use $pac::{Readable, Reg, RegisterSpec, Resettable};

        /// A zeroed register block of type `T` in host memory.
        fn block<T>() -> &'static T {
            assert_eq!(std::mem::size_of::<T>() % 4, 0);
            let words = std::mem::size_of::<T>() / 4;
            let mem: &'static mut [u32] = Box::leak(vec![0u32; words].into_boxed_slice());
            // SAFETY: `mem` is a fresh, initialised, u32-aligned allocation exactly the size
            // of `T`, a PAC register block (a `repr(C)` struct of `u32` volatile cells,
            // 4-byte aligned, for which every bit pattern is valid). It is leaked, so it
            // lives for `'static`, and the mutable borrow is given up here: from now on it
            // is reached only through the returned reference, whose cells allow interior
            // mutation. It is host memory, never a device address.
            unsafe { &*(mem.as_mut_ptr() as *const T) }
        }

        /// Byte offset of register `r` inside the block `rb`.
        fn offset<B, T>(rb: &B, r: &T) -> usize {
            r as *const T as usize - rb as *const B as usize
        }

        /// Sets the raw word of a register of a host-memory block.
        fn poke<REG: RegisterSpec<Ux = u32>>(reg: &Reg<REG>, value: u32) {
            // SAFETY: `reg` lies in an allocation made by `block()`; `as_ptr` is the
            // pointer of its `UnsafeCell`, valid and aligned for a `u32` write through a
            // shared reference; the test is single-threaded and holds no other reference
            // into the cell's content.
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

        /// The reset value the PAC (the vendor SVD) gives register `reg`.
        fn reset_of<REG: RegisterSpec<Ux = u32> + Resettable>(_reg: &Reg<REG>) -> u32 {
            REG::RESET_VALUE
        }
    };
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
            let field: twocan_bxcan::regs::Field = $field;
            assert_eq!(field.mask().trailing_zeros(), field.pos);
            check(stringify!($f), $reg, |r| r.read().$f().bits() as u32, field.mask());
        } )+
    };
}

/// Checks every offset, bit and field of `twocan_bxcan::regs` against the PAC CAN
/// register block `$rb` (a host-memory block of the PAC's type). Returns the number of
/// filter banks the PAC gives the block.
macro_rules! can_layout_matches {
    ($rb:expr) => {{
        use twocan_bxcan::regs::{
            self, btr, esr, fa1r, ffa1r, fm1r, fmr, fs1r, ier, mcr, msr, rdhxr, rdlxr, rdtxr,
            rfxr, rixr, tdhxr, tdlxr, tdtxr, tixr, tsr,
        };
        let rb = $rb;
        // Offsets.
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
        let banks = rb.fb_iter().count();
        assert!(banks <= regs::FILTER_BANKS);
        for i in 0..banks {
            assert_eq!(offset(rb, rb.fb(i).fr1()), regs::fir1(i));
            assert_eq!(offset(rb, rb.fb(i).fr2()), regs::fir2(i));
        }
        assert_eq!(std::mem::size_of_val(rb), regs::fir2(banks - 1) + 4);

        // Control and status bits.
        bits!(rb.mcr(),
            inrq => mcr::INRQ, sleep => mcr::SLEEP, txfp => mcr::TXFP, rflm => mcr::RFLM,
            nart => mcr::NART, awum => mcr::AWUM, abom => mcr::ABOM, ttcm => mcr::TTCM,
            reset => mcr::RESET, dbf => mcr::DBF);
        bits!(rb.msr(),
            inak => msr::INAK, slak => msr::SLAK, erri => msr::ERRI, wkui => msr::WKUI,
            slaki => msr::SLAKI, txm => msr::TXM, rxm => msr::RXM, samp => msr::SAMP,
            rx => msr::RX);
        bits!(rb.tsr(),
            rqcp0 => tsr::RQCP0, txok0 => tsr::TXOK0, alst0 => tsr::ALST0,
            terr0 => tsr::TERR0, abrq0 => tsr::ABRQ0, rqcp1 => tsr::RQCP1,
            txok1 => tsr::TXOK1, alst1 => tsr::ALST1, terr1 => tsr::TERR1,
            abrq1 => tsr::ABRQ1, rqcp2 => tsr::RQCP2, txok2 => tsr::TXOK2,
            alst2 => tsr::ALST2, terr2 => tsr::TERR2, abrq2 => tsr::ABRQ2,
            tme0 => tsr::TME0, tme1 => tsr::TME1, tme2 => tsr::TME2, low0 => tsr::LOW0,
            low1 => tsr::LOW1, low2 => tsr::LOW2);
        fields!(rb.tsr(), code => tsr::CODE);
        for x in 0..regs::RX_FIFOS {
            fields!(rb.rfr(x), fmp => rfxr::FMP);
            bits!(rb.rfr(x), full => rfxr::FULL, fovr => rfxr::FOVR, rfom => rfxr::RFOM);
        }
        bits!(rb.ier(),
            tmeie => ier::TMEIE, fmpie0 => ier::FMPIE0, ffie0 => ier::FFIE0,
            fovie0 => ier::FOVIE0, fmpie1 => ier::FMPIE1, ffie1 => ier::FFIE1,
            fovie1 => ier::FOVIE1, ewgie => ier::EWGIE, epvie => ier::EPVIE,
            bofie => ier::BOFIE, lecie => ier::LECIE, errie => ier::ERRIE,
            wkuie => ier::WKUIE, slkie => ier::SLKIE);
        bits!(rb.esr(), ewgf => esr::EWGF, epvf => esr::EPVF, boff => esr::BOFF);
        fields!(rb.esr(), lec => esr::LEC, tec => esr::TEC, rec => esr::REC);
        // CAN_BTR: the same field widths on every family (BRP 10, TS1 4, TS2 3, SJW 2).
        fields!(rb.btr(), brp => btr::BRP, ts1 => btr::TS1, ts2 => btr::TS2, sjw => btr::SJW);
        bits!(rb.btr(), lbkm => btr::LBKM, silm => btr::SILM);

        // Mailboxes.
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

        // Filter registers, for the banks the PAC has.
        bits!(rb.fmr(), finit => fmr::FINIT);
        for i in 0..banks {
            let n = i as u8;
            check("FBM", rb.fm1r(), |r| r.read().fbm(n).bit() as u32, fm1r::fbm(i));
            check("FSC", rb.fs1r(), |r| r.read().fsc(n).bit() as u32, fs1r::fsc(i));
            check("FFA", rb.ffa1r(), |r| r.read().ffa(n).bit() as u32, ffa1r::ffa(i));
            check("FACT", rb.fa1r(), |r| r.read().fact(n).bit() as u32, fa1r::fact(i));
            check("FiR1", rb.fb(i).fr1(), |r| r.read().fb().bits(), u32::MAX);
            check("FiR2", rb.fb(i).fr2(), |r| r.read().fb().bits(), u32::MAX);
        }
        // The PAC's bit arrays have one field per bank.
        for (name, count) in [
            ("FBM", rb.fm1r().read().fbm_iter().count()),
            ("FSC", rb.fs1r().read().fsc_iter().count()),
            ("FFA", rb.ffa1r().read().ffa_iter().count()),
            ("FACT", rb.fa1r().read().fact_iter().count()),
        ] {
            assert_eq!(count, banks, "{name}");
        }
        banks
    }};
}

/// The model `$model` (a CAN1 or CAN3 with its filter block) read at the offsets of the
/// PAC block `$rb`: reset values (`$reset` maps each PAC register to the value the model
/// must show: the PAC's where the SVD has it), filter registers as wide as `$banks`, bank
/// registers beyond the count read 0 and ignore writes.
macro_rules! model_matches_pac {
    ($model:expr, $rb:expr, $banks:expr, $reset:expr) => {{
        use twocan_core::Registers;
        let m: &twocan_bxcan::model::BxCanModel = $model;
        let rb = $rb;
        let banks: usize = $banks;
        let reset = $reset;
        for (name, off, pac_value) in [
            ("MCR", offset(rb, rb.mcr()), reset_of(rb.mcr())),
            ("MSR", offset(rb, rb.msr()), reset_of(rb.msr())),
            ("TSR", offset(rb, rb.tsr()), reset_of(rb.tsr())),
            ("RF0R", offset(rb, rb.rf0r()), reset_of(rb.rf0r())),
            ("RF1R", offset(rb, rb.rf1r()), reset_of(rb.rf1r())),
            ("IER", offset(rb, rb.ier()), reset_of(rb.ier())),
            ("ESR", offset(rb, rb.esr()), reset_of(rb.esr())),
            ("BTR", offset(rb, rb.btr()), reset_of(rb.btr())),
            ("FMR", offset(rb, rb.fmr()), reset_of(rb.fmr())),
            ("FM1R", offset(rb, rb.fm1r()), reset_of(rb.fm1r())),
            ("FS1R", offset(rb, rb.fs1r()), reset_of(rb.fs1r())),
            ("FFA1R", offset(rb, rb.ffa1r()), reset_of(rb.ffa1r())),
            ("FA1R", offset(rb, rb.fa1r()), reset_of(rb.fa1r())),
        ] {
            let want: u32 = reset(name, pac_value);
            assert_eq!(m.read32(off), want, "{name} at 0x{off:03X} out of reset");
        }
        // FINIT = 1 (reset): the mode, scale and assignment registers are writable; every
        // bit the PAC names is kept, none above.
        let width = (1u32 << banks) - 1;
        for (name, off) in [
            ("FM1R", offset(rb, rb.fm1r())),
            ("FS1R", offset(rb, rb.fs1r())),
            ("FFA1R", offset(rb, rb.ffa1r())),
            ("FA1R", offset(rb, rb.fa1r())),
        ] {
            m.write32(off, u32::MAX);
            assert_eq!(m.read32(off), width, "{name}: one bit per PAC bank");
            m.write32(off, 0);
        }
        let last = offset(rb, rb.fb(banks - 1).fr2());
        m.write32(last, 0xA5A5_5A5A);
        assert_eq!(m.read32(last), 0xA5A5_5A5A, "the PAC's last bank register");
        for beyond in
            (last + 4..=twocan_bxcan::regs::fir2(twocan_bxcan::regs::FILTER_BANKS - 1)).step_by(4)
        {
            m.write32(beyond, 0xFFFF_FFFF);
            assert_eq!(
                m.read32(beyond),
                0,
                "0x{beyond:03X}: beyond the PAC's banks"
            );
        }
    }};
}
