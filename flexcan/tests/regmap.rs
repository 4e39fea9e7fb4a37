//! Checks `twocan_flexcan::regs` against the vendor SVD data, as generated into the
//! `mk20d7` (MK20D7, Teensy 3.1/3.2) and `mk66f18` (MK66F18, Teensy 3.6) peripheral access
//! crates.
//!
//! - Offsets: the offset of each register in the PAC's `#[repr(C)]` register block
//!   (`offset_of!`) equals ours. Base addresses come from `mk66f18`'s `const fn ptr()`;
//!   calling `mk20d7`'s (non-inline) `ptr()` would link the object that defines its
//!   `#[no_mangle] DEVICE_PERIPHERALS`, which `mk66f18` defines too (duplicate symbol), so
//!   the K20 addresses (CAN0 0x4002_4000, SIM 0x4004_7000, PORTA..E 0x4004_9000..0x4004_D000,
//!   the same Kinetis memory map) were checked by reading the `mk20d7` source instead.
//! - Bit positions: a register block is placed in host memory; for each bit k the raw
//!   register is set to `1 << k` and the PAC's field reader tells whether the field sees
//!   it. The bits a field sees are its mask, compared with our constant.

use core::mem::{offset_of, size_of};

use twocan_flexcan::regs::{
    self, code, crcr, cs, ctrl1, ctrl2, ecr, esr1, esr2, id, iflag1, imask1, mcr, pins, port,
    rxfir, sim, timer, word0, word1, Field,
};

/// A register block of type `T` in zeroed host memory (leaked: the test process ends soon).
fn host_block<T>() -> &'static T {
    let words = size_of::<T>().div_ceil(4);
    let mem: &'static mut [u32] = Box::leak(vec![0u32; words].into_boxed_slice());
    // SAFETY: the PAC register blocks are `#[repr(C)]` structs of `VolatileCell<u32>`
    // registers (interior mutability) and `u8` padding arrays, so any bit pattern is a
    // valid value; the buffer is at least `size_of::<T>()` bytes, 4-byte aligned (the
    // blocks' alignment), zero-initialised and never used through `mem` again.
    unsafe { &*(mem.as_mut_ptr() as *const T) }
}

/// Writes `value` to the 32-bit register at `offset` in the host block `block`.
fn poke<T>(block: &T, offset: usize, value: u32) {
    assert!(offset + 4 <= size_of::<T>());
    let p = (block as *const T as *const u8).wrapping_add(offset) as *mut u32;
    // SAFETY: `offset` is the `offset_of!` of a register (a `VolatileCell<u32>`, i.e. an
    // `UnsafeCell<u32>` of size 4, so the cell sits at offset 0 of the register) within the
    // block, checked in bounds above and 4-aligned; writing through a pointer derived from a
    // shared reference is allowed inside an `UnsafeCell`, and nothing else accesses the
    // memory concurrently.
    unsafe { p.write_volatile(value) }
}

/// The bits of the raw register at `offset` that the PAC field reader `get` sees.
fn field_mask<T>(block: &T, offset: usize, get: impl Fn() -> u32) -> u32 {
    let mut mask = 0;
    for k in 0..32 {
        poke(block, offset, 1 << k);
        if get() != 0 {
            mask |= 1 << k;
        }
    }
    poke(block, offset, 0);
    mask
}

/// One-bit field: `$bit` must be the PAC field's mask.
macro_rules! bit {
    ($rb:expr, $ty:ty, $reg:ident . $f:ident, $bit:expr) => {{
        let off = offset_of!($ty, $reg);
        let m = field_mask($rb, off, || u32::from($rb.$reg.read().$f().bit()));
        assert_eq!(
            m,
            $bit,
            "{}.{} (PAC mask {:#010x})",
            stringify!($reg),
            stringify!($f),
            m
        );
    }};
}

/// Multi-bit field: `$field` (a `Field`) must have the PAC field's mask.
macro_rules! field {
    ($rb:expr, $ty:ty, $reg:ident . $f:ident, $field:expr) => {{
        let off = offset_of!($ty, $reg);
        let m = field_mask($rb, off, || $rb.$reg.read().$f().bits() as u32);
        let ours: Field = $field;
        assert_eq!(
            m,
            ours.mask(),
            "{}.{} (PAC mask {:#010x})",
            stringify!($reg),
            stringify!($f),
            m
        );
    }};
}

/// The FlexCAN checks shared by both PACs (same SVD field names).
macro_rules! flexcan_common {
    ($pac:ident, $block:ident) => {{
        type Rb = $pac::$block::RegisterBlock;
        let rb: &Rb = host_block::<Rb>();

        // Offsets.
        assert_eq!(offset_of!(Rb, mcr), regs::MCR);
        assert_eq!(offset_of!(Rb, ctrl1), regs::CTRL1);
        assert_eq!(offset_of!(Rb, timer), regs::TIMER);
        assert_eq!(offset_of!(Rb, rxmgmask), regs::RXMGMASK);
        assert_eq!(offset_of!(Rb, rx14mask), regs::RX14MASK);
        assert_eq!(offset_of!(Rb, rx15mask), regs::RX15MASK);
        assert_eq!(offset_of!(Rb, ecr), regs::ECR);
        assert_eq!(offset_of!(Rb, esr1), regs::ESR1);
        assert_eq!(offset_of!(Rb, imask1), regs::IMASK1);
        assert_eq!(offset_of!(Rb, iflag1), regs::IFLAG1);
        assert_eq!(offset_of!(Rb, ctrl2), regs::CTRL2);
        assert_eq!(offset_of!(Rb, esr2), regs::ESR2);
        assert_eq!(offset_of!(Rb, crcr), regs::CRCR);
        assert_eq!(offset_of!(Rb, rxfgmask), regs::RXFGMASK);
        assert_eq!(offset_of!(Rb, rxfir), regs::RXFIR);
        macro_rules! mb {
            ($n:expr, $cs:ident, $id:ident, $w0:ident, $w1:ident) => {
                assert_eq!(offset_of!(Rb, $cs), regs::mb_cs($n), "CS{}", $n);
                assert_eq!(offset_of!(Rb, $id), regs::mb_id($n), "ID{}", $n);
                assert_eq!(offset_of!(Rb, $w0), regs::mb_word0($n), "WORD0{}", $n);
                assert_eq!(offset_of!(Rb, $w1), regs::mb_word1($n), "WORD1{}", $n);
            };
        }
        mb!(0, cs0, id0, word00, word10);
        mb!(1, cs1, id1, word01, word11);
        mb!(2, cs2, id2, word02, word12);
        mb!(3, cs3, id3, word03, word13);
        mb!(4, cs4, id4, word04, word14);
        mb!(5, cs5, id5, word05, word15);
        mb!(6, cs6, id6, word06, word16);
        mb!(7, cs7, id7, word07, word17);
        mb!(8, cs8, id8, word08, word18);
        mb!(9, cs9, id9, word09, word19);
        mb!(10, cs10, id10, word010, word110);
        mb!(11, cs11, id11, word011, word111);
        mb!(12, cs12, id12, word012, word112);
        mb!(13, cs13, id13, word013, word113);
        mb!(14, cs14, id14, word014, word114);
        mb!(15, cs15, id15, word015, word115);
        for n in 0..regs::NUM_MB {
            let rximr0 = offset_of!(Rb, rximr);
            assert_eq!(rximr0 + 4 * n, regs::rximr(n), "RXIMR{}", n);
        }
        assert_eq!(regs::mb_cs(6), regs::rx_fifo_filter(0));
        assert_eq!(regs::RX_FIFO_OUTPUT, regs::mb_cs(0));

        // MCR.
        bit!(rb, Rb, mcr.mdis, mcr::MDIS);
        bit!(rb, Rb, mcr.frz, mcr::FRZ);
        bit!(rb, Rb, mcr.rfen, mcr::RFEN);
        bit!(rb, Rb, mcr.halt, mcr::HALT);
        bit!(rb, Rb, mcr.notrdy, mcr::NOTRDY);
        bit!(rb, Rb, mcr.wakmsk, mcr::WAKMSK);
        bit!(rb, Rb, mcr.softrst, mcr::SOFTRST);
        bit!(rb, Rb, mcr.frzack, mcr::FRZACK);
        bit!(rb, Rb, mcr.supv, mcr::SUPV);
        bit!(rb, Rb, mcr.slfwak, mcr::SLFWAK);
        bit!(rb, Rb, mcr.wrnen, mcr::WRNEN);
        bit!(rb, Rb, mcr.lpmack, mcr::LPMACK);
        bit!(rb, Rb, mcr.srxdis, mcr::SRXDIS);
        bit!(rb, Rb, mcr.irmq, mcr::IRMQ);
        bit!(rb, Rb, mcr.lprioen, mcr::LPRIOEN);
        bit!(rb, Rb, mcr.aen, mcr::AEN);
        field!(rb, Rb, mcr.idam, mcr::IDAM);
        field!(rb, Rb, mcr.maxmb, mcr::MAXMB);

        // CTRL1.
        field!(rb, Rb, ctrl1.presdiv, ctrl1::PRESDIV);
        field!(rb, Rb, ctrl1.rjw, ctrl1::RJW);
        field!(rb, Rb, ctrl1.pseg1, ctrl1::PSEG1);
        field!(rb, Rb, ctrl1.pseg2, ctrl1::PSEG2);
        bit!(rb, Rb, ctrl1.boffmsk, ctrl1::BOFFMSK);
        bit!(rb, Rb, ctrl1.errmsk, ctrl1::ERRMSK);
        bit!(rb, Rb, ctrl1.clksrc, ctrl1::CLKSRC);
        bit!(rb, Rb, ctrl1.lpb, ctrl1::LPB);
        bit!(rb, Rb, ctrl1.twrnmsk, ctrl1::TWRNMSK);
        bit!(rb, Rb, ctrl1.rwrnmsk, ctrl1::RWRNMSK);
        bit!(rb, Rb, ctrl1.smp, ctrl1::SMP);
        bit!(rb, Rb, ctrl1.boffrec, ctrl1::BOFFREC);
        bit!(rb, Rb, ctrl1.tsyn, ctrl1::TSYN);
        bit!(rb, Rb, ctrl1.lbuf, ctrl1::LBUF);
        bit!(rb, Rb, ctrl1.lom, ctrl1::LOM);
        field!(rb, Rb, ctrl1.propseg, ctrl1::PROPSEG);

        // TIMER, ECR.
        field!(rb, Rb, timer.timer, timer::TIMER);
        field!(rb, Rb, ecr.txerrcnt, ecr::TXERRCNT);
        field!(rb, Rb, ecr.rxerrcnt, ecr::RXERRCNT);

        // ESR1.
        bit!(rb, Rb, esr1.wakint, esr1::WAKINT);
        bit!(rb, Rb, esr1.errint, esr1::ERRINT);
        bit!(rb, Rb, esr1.boffint, esr1::BOFFINT);
        bit!(rb, Rb, esr1.rx, esr1::RX);
        field!(rb, Rb, esr1.fltconf, esr1::FLTCONF);
        bit!(rb, Rb, esr1.tx, esr1::TX);
        bit!(rb, Rb, esr1.idle, esr1::IDLE);
        bit!(rb, Rb, esr1.rxwrn, esr1::RXWRN);
        bit!(rb, Rb, esr1.txwrn, esr1::TXWRN);
        bit!(rb, Rb, esr1.stferr, esr1::STFERR);
        bit!(rb, Rb, esr1.frmerr, esr1::FRMERR);
        bit!(rb, Rb, esr1.crcerr, esr1::CRCERR);
        bit!(rb, Rb, esr1.ackerr, esr1::ACKERR);
        bit!(rb, Rb, esr1.bit0err, esr1::BIT0ERR);
        bit!(rb, Rb, esr1.bit1err, esr1::BIT1ERR);
        bit!(rb, Rb, esr1.rwrnint, esr1::RWRNINT);
        bit!(rb, Rb, esr1.twrnint, esr1::TWRNINT);
        bit!(rb, Rb, esr1.synch, esr1::SYNCH);

        // IFLAG1 (bits 5–7 are the Rx FIFO flags).
        bit!(rb, Rb, iflag1.buf5i, iflag1::BUF5I);
        bit!(rb, Rb, iflag1.buf6i, iflag1::BUF6I);
        bit!(rb, Rb, iflag1.buf7i, iflag1::BUF7I);

        // CTRL2.
        bit!(rb, Rb, ctrl2.wrmfrz, ctrl2::WRMFRZ);
        field!(rb, Rb, ctrl2.rffn, ctrl2::RFFN);
        field!(rb, Rb, ctrl2.tasd, ctrl2::TASD);
        bit!(rb, Rb, ctrl2.mrp, ctrl2::MRP);
        bit!(rb, Rb, ctrl2.rrs, ctrl2::RRS);
        bit!(rb, Rb, ctrl2.eacen, ctrl2::EACEN);

        // ESR2, CRCR, RXFIR.
        bit!(rb, Rb, esr2.imb, esr2::IMB);
        bit!(rb, Rb, esr2.vps, esr2::VPS);
        field!(rb, Rb, esr2.lptm, esr2::LPTM);
        field!(rb, Rb, crcr.txcrc, crcr::TXCRC);
        field!(rb, Rb, crcr.mbcrc, crcr::MBCRC);
        field!(rb, Rb, rxfir.idhit, rxfir::IDHIT);

        // Message buffer words (MB0 and MB15: same layout for all).
        field!(rb, Rb, cs0.code, cs::CODE);
        bit!(rb, Rb, cs0.srr, cs::SRR);
        bit!(rb, Rb, cs0.ide, cs::IDE);
        bit!(rb, Rb, cs0.rtr, cs::RTR);
        field!(rb, Rb, cs0.dlc, cs::DLC);
        field!(rb, Rb, cs0.time_stamp, cs::TIME_STAMP);
        field!(rb, Rb, cs15.code, cs::CODE);
        field!(rb, Rb, cs15.time_stamp, cs::TIME_STAMP);
        field!(rb, Rb, id0.prio, id::PRIO);
        field!(rb, Rb, id0.std, id::STD);
        field!(rb, Rb, id0.ext, id::EXT);
        field!(rb, Rb, id15.std, id::STD);
        field!(rb, Rb, word00.data_byte_0, word0::DATA_BYTE_0);
        field!(rb, Rb, word00.data_byte_1, word0::DATA_BYTE_1);
        field!(rb, Rb, word00.data_byte_2, word0::DATA_BYTE_2);
        field!(rb, Rb, word00.data_byte_3, word0::DATA_BYTE_3);
        field!(rb, Rb, word10.data_byte_4, word1::DATA_BYTE_4);
        field!(rb, Rb, word10.data_byte_5, word1::DATA_BYTE_5);
        field!(rb, Rb, word10.data_byte_6, word1::DATA_BYTE_6);
        field!(rb, Rb, word10.data_byte_7, word1::DATA_BYTE_7);
        rb
    }};
}

#[test]
fn register_blocks_are_word_registers() {
    assert_eq!(size_of::<mk20d7::can0::MCR>(), 4);
    assert_eq!(size_of::<mk66f18::can0::MCR>(), 4);
    assert_eq!(size_of::<mk66f18::can1::MCR>(), 4);
}

#[test]
fn base_addresses_match_the_svd() {
    assert_eq!(mk66f18::CAN0::ptr() as usize, regs::CAN0_BASE);
    assert_eq!(mk66f18::CAN1::ptr() as usize, regs::CAN1_BASE);
}

/// The window of a fixed-base register type: (base, start, end).
fn window<const B: usize, const E: usize, const S: usize>(
    _: std::marker::PhantomData<twocan_core::Fixed<B, E, S>>,
) -> (usize, usize, usize) {
    (B, S, E)
}

#[test]
fn fixed_register_types_are_at_the_svd_s_addresses_with_the_kinetis_window() {
    use std::marker::PhantomData as T;
    assert_eq!(
        window(T::<regs::Can0At>),
        (mk66f18::CAN0::ptr() as usize, 0, regs::BLOCK_END)
    );
    assert_eq!(
        window(T::<regs::Can1At>),
        (mk66f18::CAN1::ptr() as usize, 0, regs::BLOCK_END)
    );
    // The window's last register is RXIMR15 (K66 SVD), the end of the block.
    assert_eq!(
        offset_of!(mk66f18::can0::RegisterBlock, rximr) + 16 * 4,
        regs::BLOCK_END
    );
}

#[test]
fn k20_flexcan_matches_mk20d7() {
    let rb = flexcan_common!(mk20d7, can0);
    type Rb = mk20d7::can0::RegisterBlock;
    // The MK20D7 SVD groups IMASK1/IFLAG1 in multi-bit fields.
    field!(rb, Rb, imask1.buflm, imask1::BUFLM);
    field!(rb, Rb, iflag1.buf4to0i, Field::new(0, 5));
    field!(rb, Rb, iflag1.buf31to8i, Field::new(8, 24));
    let m = field_mask(rb, offset_of!(Rb, rximr), || rb.rximr[0].read().mi().bits());
    assert_eq!(m, u32::MAX, "RXIMR0.MI");
    field!(rb, Rb, rxmgmask.mg, Field::new(0, 32));
    field!(rb, Rb, rxfgmask.fgm, Field::new(0, 32));
}

#[test]
fn k66_flexcan0_and_flexcan1_match_mk66f18() {
    let rb = flexcan_common!(mk66f18, can0);
    type Rb = mk66f18::can0::RegisterBlock;
    bit!(rb, Rb, mcr.waksrc, mcr::WAKSRC);
    bit!(rb, Rb, imask1.buflm0, 1 << 0);
    bit!(rb, Rb, imask1.buflm31, 1 << 31);
    assert_eq!(imask1::BUFLM.mask(), u32::MAX);
    flexcan_common!(mk66f18, can1);
}

#[test]
fn sim_clock_gates_match_the_svd() {
    type S20 = mk20d7::sim::RegisterBlock;
    let base20 = sim::SIM_BASE;
    assert_eq!(base20 + offset_of!(S20, scgc5), sim::SIM_SCGC5);
    assert_eq!(base20 + offset_of!(S20, scgc6), sim::SIM_SCGC6);
    let s20: &S20 = host_block::<S20>();
    bit!(s20, S20, scgc6.flexcan0, sim::SCGC6_FLEXCAN0);
    bit!(s20, S20, scgc5.porta, sim::SCGC5_PORTA);
    bit!(s20, S20, scgc5.portb, sim::SCGC5_PORTB);
    bit!(s20, S20, scgc5.portc, sim::SCGC5_PORTC);
    bit!(s20, S20, scgc5.portd, sim::SCGC5_PORTD);
    bit!(s20, S20, scgc5.porte, sim::SCGC5_PORTE);

    type S66 = mk66f18::sim::RegisterBlock;
    let base66 = mk66f18::SIM::ptr() as usize;
    assert_eq!(base66, sim::SIM_BASE);
    assert_eq!(base66 + offset_of!(S66, scgc3), sim::SIM_SCGC3);
    assert_eq!(base66 + offset_of!(S66, scgc5), sim::SIM_SCGC5);
    assert_eq!(base66 + offset_of!(S66, scgc6), sim::SIM_SCGC6);
    let s66: &S66 = host_block::<S66>();
    bit!(s66, S66, scgc3.flexcan1, sim::SCGC3_FLEXCAN1);
    bit!(s66, S66, scgc6.flexcan0, sim::SCGC6_FLEXCAN0);
    bit!(s66, S66, scgc5.porta, sim::SCGC5_PORTA);
    bit!(s66, S66, scgc5.portb, sim::SCGC5_PORTB);
    bit!(s66, S66, scgc5.porte, sim::SCGC5_PORTE);
}

#[test]
fn port_pin_control_matches_the_svd() {
    use port::Port;
    assert_eq!(mk66f18::PORTA::ptr() as usize, Port::A.base());
    assert_eq!(mk66f18::PORTB::ptr() as usize, Port::B.base());
    assert_eq!(mk66f18::PORTC::ptr() as usize, Port::C.base());
    assert_eq!(mk66f18::PORTD::ptr() as usize, Port::D.base());
    assert_eq!(mk66f18::PORTE::ptr() as usize, Port::E.base());

    type P20 = mk20d7::porta::RegisterBlock;
    for n in 0..32u8 {
        assert_eq!(
            Port::A.base() + offset_of!(P20, pcr) + 4 * n as usize,
            Port::A.pcr(n)
        );
    }
    type P66 = mk66f18::porte::RegisterBlock;
    assert_eq!(offset_of!(P66, pcr24), 4 * 24);
    assert_eq!(offset_of!(P66, pcr25), 4 * 25);

    // PCR fields, through PCR0 of each PAC.
    let p20: &P20 = host_block::<P20>();
    macro_rules! pcr20 {
        ($f:ident, bit $ours:expr) => {{
            let m = field_mask(p20, offset_of!(P20, pcr), || {
                u32::from(p20.pcr[0].read().$f().bit())
            });
            assert_eq!(m, $ours, stringify!($f));
        }};
        ($f:ident, field $ours:expr) => {{
            let m = field_mask(p20, offset_of!(P20, pcr), || {
                p20.pcr[0].read().$f().bits() as u32
            });
            assert_eq!(m, ($ours as Field).mask(), stringify!($f));
        }};
    }
    pcr20!(ps, bit port::PCR_PS);
    pcr20!(pe, bit port::PCR_PE);
    pcr20!(sre, bit port::PCR_SRE);
    pcr20!(pfe, bit port::PCR_PFE);
    pcr20!(ode, bit port::PCR_ODE);
    pcr20!(dse, bit port::PCR_DSE);
    pcr20!(mux, field port::PCR_MUX);
    pcr20!(lk, bit port::PCR_LK);
    pcr20!(irqc, field port::PCR_IRQC);
    pcr20!(isf, bit port::PCR_ISF);

    let p66: &P66 = host_block::<P66>();
    bit!(p66, P66, pcr0.ps, port::PCR_PS);
    bit!(p66, P66, pcr0.pe, port::PCR_PE);
    bit!(p66, P66, pcr0.ode, port::PCR_ODE);
    field!(p66, P66, pcr0.mux, port::PCR_MUX);
}

#[test]
fn teensy_can_pins() {
    // Teensy 3.1/3.2 (MK20DX256): pins 3/4, alternates 32/25.
    let t31 = [
        (pins::TEENSY31_CAN0_TX, 3, port::Port::A, 12),
        (pins::TEENSY31_CAN0_RX, 4, port::Port::A, 13),
        (pins::TEENSY31_CAN0_TX_ALT, 32, port::Port::B, 18),
        (pins::TEENSY31_CAN0_RX_ALT, 25, port::Port::B, 19),
        // Teensy 3.5/3.6 (MK64FX512/MK66FX1M0): pins 3/4, alternates 29/30; CAN1 33/34.
        (pins::TEENSY35_CAN0_TX, 3, port::Port::A, 12),
        (pins::TEENSY35_CAN0_RX, 4, port::Port::A, 13),
        (pins::TEENSY35_CAN0_TX_ALT, 29, port::Port::B, 18),
        (pins::TEENSY35_CAN0_RX_ALT, 30, port::Port::B, 19),
        (pins::TEENSY36_CAN1_TX, 33, port::Port::E, 24),
        (pins::TEENSY36_CAN1_RX, 34, port::Port::E, 25),
    ];
    for (p, teensy, prt, n) in t31 {
        assert_eq!((p.teensy_pin, p.port, p.pin, p.alt), (teensy, prt, n, 2));
        assert_eq!(p.pcr(), prt.base() + 4 * n as usize);
    }
    assert_eq!(pins::TEENSY31_CAN0_TX.pcr(), 0x4004_9030);
    assert_eq!(pins::TEENSY36_CAN1_RX.pcr(), 0x4004_D064);
}

#[test]
fn field_helpers_and_geometry() {
    let f = Field::new(4, 3);
    assert_eq!(f.mask(), 0x70);
    assert_eq!(f.max(), 7);
    assert_eq!(f.get(0xFF), 7);
    assert_eq!(f.val(9), 0x10);
    assert_eq!(f.replace(0xFFFF_FFFF, 0), 0xFFFF_FF8F);
    assert_eq!(Field::new(0, 32).mask(), u32::MAX);
    assert_eq!(
        mcr::RESET,
        mcr::MDIS
            | mcr::FRZ
            | mcr::HALT
            | mcr::NOTRDY
            | mcr::SUPV
            | mcr::LPMACK
            | mcr::MAXMB.val(15)
    );
    assert_eq!(ctrl2::TASD.get(ctrl2::RESET), 0x16);
    // RFFN → elements and occupied MBs (ACAN's 8/0, 10/6, 12/12, 14/18 configurations).
    let table: Vec<(usize, usize)> = (0..4)
        .map(|r| (regs::rx_fifo_filter_count(r), regs::rx_fifo_occupied_mbs(r)))
        .collect();
    assert_eq!(table, vec![(8, 8), (16, 10), (24, 12), (32, 14)]);
    assert_eq!(code::TX_DATA, code::TX_REMOTE);
    assert_eq!(regs::filter_a::RXIDA.mask(), 0x3FFF_FFFE);
    assert_eq!(regs::filter_a::RXIDA_STD.mask(), 0x3FF8_0000);
    assert_eq!(
        regs::filter_b::RXIDB_0.mask() | regs::filter_b::RXIDB_1.mask(),
        0x3FFF_3FFF
    );
}
