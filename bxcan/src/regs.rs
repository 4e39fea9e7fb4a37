//! The bxCAN register map of the STM32F7 (RM0410 chapter 40, "Controller area network
//! (bxCAN)", section 40.9 "CAN registers").
//!
//! Every register the driver touches is named here as in RM0410, as a byte offset from
//! the instance's base address (40.9.5 "bxCAN register map"); every bit as a `u32` mask
//! and every multi-bit field as a [`Field`] (position and width).
//!
//! Naming scheme:
//! - fixed registers: `MCR`, `MSR`, `TSR`, `RF0R`, `RF1R`, `IER`, `ESR`, `BTR`, `FMR`,
//!   `FM1R`, `FS1R`, `FFA1R`, `FA1R` (offsets, `usize`);
//! - indexed registers: const fns named after RM0410's register name with its index
//!   letter: [`tixr(x)`](fn@tixr), [`tdtxr(x)`](fn@tdtxr), [`tdlxr(x)`](fn@tdlxr),
//!   [`tdhxr(x)`](fn@tdhxr) (transmit mailbox x = 0..2); [`rfxr(x)`](fn@rfxr),
//!   [`rixr(x)`](fn@rixr), [`rdtxr(x)`](fn@rdtxr), [`rdlxr(x)`](fn@rdlxr),
//!   [`rdhxr(x)`](fn@rdhxr) (receive FIFO x = 0..1); [`fir1(i)`](fn@fir1),
//!   [`fir2(i)`](fn@fir2) (filter bank i = 0..27);
//! - bits and fields: in a lowercase module named after the register (`mcr::INRQ`,
//!   `tsr::CODE`, `tixr::STID`, ...); a module shared by the indexed registers is named
//!   like their const fn (`tixr`, `rfxr`, ...). Per-mailbox and per-bank bits also have
//!   const fns (`tsr::rqcp(x)`, `fa1r::fact(i)`, ...).
//!
//! Instances and filter blocks (40.2 "bxCAN main features", dual and single CAN
//! peripheral configuration, table "CAN implementation"): CAN1
//! (master) and CAN2 (slave) exist on STM32F74x/F75x/F76x/F77x and share the 28 filter
//! banks of CAN1's register block, split at `FMR.CAN2SB`; CAN3 exists on STM32F76x/F77x
//! only ("single CAN") and has its own filter block of 14 banks. See [`Instance`].
//!
//! Checked against the vendor SVD (the `stm32f7` PAC) by `tests/regmap.rs`.
#![deny(missing_docs)]

/// A multi-bit field of a register: the position of its least significant bit and its
/// width in bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Field {
    /// Bit position of the field's least significant bit.
    pub pos: u32,
    /// Width in bits (1..=32).
    pub width: u32,
}

impl Field {
    /// A field of `width` bits starting at bit `pos`.
    pub const fn new(pos: u32, width: u32) -> Self {
        Field { pos, width }
    }

    /// The field's bits in place in the register.
    pub const fn mask(self) -> u32 {
        if self.width >= 32 {
            u32::MAX << self.pos
        } else {
            ((1u32 << self.width) - 1) << self.pos
        }
    }

    /// The largest value the field holds.
    pub const fn max(self) -> u32 {
        self.mask() >> self.pos
    }

    /// The field's value in the register value `reg`.
    pub const fn get(self, reg: u32) -> u32 {
        (reg & self.mask()) >> self.pos
    }

    /// `reg` with the field replaced by `value` (bits of `value` beyond the width are
    /// dropped).
    pub const fn set(self, reg: u32, value: u32) -> u32 {
        (reg & !self.mask()) | ((value << self.pos) & self.mask())
    }

    /// `value` placed in the field, all other bits zero.
    pub const fn val(self, value: u32) -> u32 {
        self.set(0, value)
    }
}

const fn bit(n: u32) -> u32 {
    1 << n
}

// ---------------------------------------------------------------------------------------
// Instances (40.2 "bxCAN main features"; addresses from RM0410 2.2.2 "Memory map and
// register boundary addresses")
// ---------------------------------------------------------------------------------------

/// Base address of CAN1 (master; STM32F74x/F75x/F76x/F77x). The same on the F446
/// (RM0390 §2.2.2 "Memory map") and the F103's `CAN` (RM0008 §3.3 "Memory map": bxCAN1).
pub const CAN1_BASE: usize = 0x4000_6400;
/// Base address of CAN2 (slave of CAN1; STM32F74x/F75x/F76x/F77x; the same on the F446,
/// RM0390 §2.2.2, and the F105/F107, RM0008 §3.3).
pub const CAN2_BASE: usize = 0x4000_6800;
/// Base address of CAN3 (single CAN with its own filters; STM32F76x/F77x only).
pub const CAN3_BASE: usize = 0x4000_3400;

/// End of an instance's registers: the last filter register (`CAN_F27R2`) is at 0x31C.
pub const BLOCK_END: usize = 0x320;
/// Start of the filter registers (`CAN_FMR`).
pub const FILTERS_START: usize = 0x200;

/// Volatile access to a whole bxCAN register block (CAN1 alone, CAN3): control,
/// mailboxes and filters.
pub type CanRegs = twocan_core::Mmio<BLOCK_END>;
/// Volatile access to an instance's control and mailbox registers only (CAN2, which
/// has no filters of its own; CAN1 when it shares its filters with CAN2).
pub type ControlRegs = twocan_core::Mmio<FILTERS_START>;
/// Volatile access to CAN1's filter registers, the block CAN1 and CAN2 share (RM0410
/// §40.9.4): held in one `static` and lent to both (`&'static FilterRegs`), its
/// writes made under a critical section.
pub type FilterRegs = twocan_core::Mmio<BLOCK_END, FILTERS_START>;

/// [`CanRegs`] with the base address a constant (`twocan_core::Fixed`): a zero-sized
/// handle, so the per-frame code reaches each register at an address known at compile
/// time, with no base to load (issue 21). The same window (`0..BLOCK_END`) and bounds.
/// From the HAL hand-over's `into_registers_at` (no `unsafe` in the program), or
/// `Fixed::new` (`unsafe`, the promise of [`twocan_core::Mmio::new`]).
pub type CanRegsAt<const BASE: usize> = twocan_core::Fixed<BASE, BLOCK_END>;
/// [`ControlRegs`] with the base address a constant: CAN2's registers, or CAN1's
/// control and mailbox registers when it shares its filters with CAN2.
pub type ControlRegsAt<const BASE: usize> = twocan_core::Fixed<BASE, FILTERS_START>;

/// CAN1's whole block (CAN1 alone; the F103's `CAN`) at [`CAN1_BASE`].
///
/// ```
/// use twocan_bxcan::regs::Can1At;
/// assert_eq!(core::mem::size_of::<Can1At>(), 0);
/// ```
pub type Can1At = CanRegsAt<CAN1_BASE>;
/// CAN1's control and mailbox registers (dual CAN: the filters shared with CAN2) at
/// [`CAN1_BASE`].
pub type Can1ControlAt = ControlRegsAt<CAN1_BASE>;
/// CAN2's control and mailbox registers (it has no filters of its own) at
/// [`CAN2_BASE`].
pub type Can2At = ControlRegsAt<CAN2_BASE>;
/// CAN3's whole block, with its own filters (STM32F76x/F77x), at [`CAN3_BASE`].
pub type Can3At = CanRegsAt<CAN3_BASE>;

/// Filter banks in the dual-CAN filter block of CAN1, shared by CAN1 and CAN2
/// (RM0410 40.2: "28 filter banks shared between CAN1 and CAN2 for dual CAN").
pub const FILTER_BANKS: usize = 28;
/// Filter banks in CAN3's own filter block (RM0410 40.2: "14 filter banks for single
/// CAN").
pub const FILTER_BANKS_SINGLE: usize = 14;

/// A bxCAN instance of the STM32F7.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Instance {
    /// CAN1, the master of the dual CAN: owns the filter block (banks `0..CAN2SB`).
    Can1,
    /// CAN2, the slave: has no filter registers of its own; uses CAN1's filter block,
    /// banks `CAN2SB..28`.
    Can2,
    /// CAN3 (F76x/F77x): single CAN with its own 14-bank filter block.
    Can3,
}

impl Instance {
    /// The base address of the instance's registers.
    pub const fn base(self) -> usize {
        match self {
            Instance::Can1 => CAN1_BASE,
            Instance::Can2 => CAN2_BASE,
            Instance::Can3 => CAN3_BASE,
        }
    }

    /// The base address of the register block holding the filter registers (`FMR` ..
    /// `FiR2`) this instance's reception goes through: CAN2 uses CAN1's.
    pub const fn filter_base(self) -> usize {
        match self {
            Instance::Can1 | Instance::Can2 => CAN1_BASE,
            Instance::Can3 => CAN3_BASE,
        }
    }

    /// Whether the instance has filter registers in its own register block.
    pub const fn has_own_filters(self) -> bool {
        !matches!(self, Instance::Can2)
    }

    /// The number of banks in the filter block this instance uses (28 shared between
    /// CAN1 and CAN2, or CAN3's 14).
    pub const fn filter_banks(self) -> usize {
        match self {
            Instance::Can1 | Instance::Can2 => FILTER_BANKS,
            Instance::Can3 => FILTER_BANKS_SINGLE,
        }
    }

    /// Whether the `FMR.CAN2SB` split applies (dual CAN: CAN1 and CAN2).
    pub const fn is_dual(self) -> bool {
        !matches!(self, Instance::Can3)
    }
}

// ---------------------------------------------------------------------------------------
// Control and status registers (40.9.2 "CAN control and status registers")
// ---------------------------------------------------------------------------------------

/// CAN master control register (CAN_MCR).
pub const MCR: usize = 0x000;
/// CAN master status register (CAN_MSR).
pub const MSR: usize = 0x004;
/// CAN transmit status register (CAN_TSR).
pub const TSR: usize = 0x008;
/// CAN receive FIFO 0 register (CAN_RF0R).
pub const RF0R: usize = 0x00C;
/// CAN receive FIFO 1 register (CAN_RF1R).
pub const RF1R: usize = 0x010;
/// CAN interrupt enable register (CAN_IER).
pub const IER: usize = 0x014;
/// CAN error status register (CAN_ESR).
pub const ESR: usize = 0x018;
/// CAN bit timing register (CAN_BTR).
pub const BTR: usize = 0x01C;

/// CAN receive FIFO x register (CAN_RFxR), x = 0, 1.
pub const fn rfxr(x: usize) -> usize {
    RF0R + 4 * x
}

/// CAN_MCR bits (40.9.2 "CAN master control register").
pub mod mcr {
    use super::bit;
    /// Initialization request.
    pub const INRQ: u32 = bit(0);
    /// Sleep mode request.
    pub const SLEEP: u32 = bit(1);
    /// Transmit FIFO priority: 0 = by identifier, 1 = by request order.
    pub const TXFP: u32 = bit(2);
    /// Receive FIFO locked mode: 1 = a new message is discarded when the FIFO is full.
    pub const RFLM: u32 = bit(3);
    /// No automatic retransmission.
    pub const NART: u32 = bit(4);
    /// Automatic wakeup mode.
    pub const AWUM: u32 = bit(5);
    /// Automatic bus-off management.
    pub const ABOM: u32 = bit(6);
    /// Time triggered communication mode.
    pub const TTCM: u32 = bit(7);
    /// bxCAN software master reset (set by software, reads 0).
    pub const RESET: u32 = bit(15);
    /// Debug freeze.
    pub const DBF: u32 = bit(16);
    /// Reset value: sleep mode requested, debug freeze.
    pub const RESET_VALUE: u32 = 0x0001_0002;
}

/// CAN_MSR bits (40.9.2 "CAN master status register").
pub mod msr {
    use super::bit;
    /// Initialization acknowledge.
    pub const INAK: u32 = bit(0);
    /// Sleep acknowledge.
    pub const SLAK: u32 = bit(1);
    /// Error interrupt (write 1 to clear).
    pub const ERRI: u32 = bit(2);
    /// Wakeup interrupt (write 1 to clear).
    pub const WKUI: u32 = bit(3);
    /// Sleep acknowledge interrupt (write 1 to clear).
    pub const SLAKI: u32 = bit(4);
    /// Transmit mode.
    pub const TXM: u32 = bit(8);
    /// Receive mode.
    pub const RXM: u32 = bit(9);
    /// Last sample point (value of CANRX).
    pub const SAMP: u32 = bit(10);
    /// CAN Rx signal.
    pub const RX: u32 = bit(11);
    /// Reset value: SLAK, SAMP and RX set.
    pub const RESET_VALUE: u32 = 0x0000_0C02;
}

/// CAN_TSR bits (40.9.2 "CAN transmit status register").
pub mod tsr {
    use super::{bit, Field};
    /// Request completed, mailbox 0 (write 1 to clear; clears TXOK0, ALST0, TERR0 too).
    pub const RQCP0: u32 = bit(0);
    /// Transmission OK, mailbox 0.
    pub const TXOK0: u32 = bit(1);
    /// Arbitration lost, mailbox 0.
    pub const ALST0: u32 = bit(2);
    /// Transmission error, mailbox 0.
    pub const TERR0: u32 = bit(3);
    /// Abort request, mailbox 0 (set by software).
    pub const ABRQ0: u32 = bit(7);
    /// Request completed, mailbox 1.
    pub const RQCP1: u32 = bit(8);
    /// Transmission OK, mailbox 1.
    pub const TXOK1: u32 = bit(9);
    /// Arbitration lost, mailbox 1.
    pub const ALST1: u32 = bit(10);
    /// Transmission error, mailbox 1.
    pub const TERR1: u32 = bit(11);
    /// Abort request, mailbox 1.
    pub const ABRQ1: u32 = bit(15);
    /// Request completed, mailbox 2.
    pub const RQCP2: u32 = bit(16);
    /// Transmission OK, mailbox 2.
    pub const TXOK2: u32 = bit(17);
    /// Arbitration lost, mailbox 2.
    pub const ALST2: u32 = bit(18);
    /// Transmission error, mailbox 2.
    pub const TERR2: u32 = bit(19);
    /// Abort request, mailbox 2.
    pub const ABRQ2: u32 = bit(23);
    /// Mailbox code: the next empty mailbox, or the lowest-priority one when none is
    /// empty.
    pub const CODE: Field = Field::new(24, 2);
    /// Transmit mailbox 0 empty.
    pub const TME0: u32 = bit(26);
    /// Transmit mailbox 1 empty.
    pub const TME1: u32 = bit(27);
    /// Transmit mailbox 2 empty.
    pub const TME2: u32 = bit(28);
    /// Lowest priority flag, mailbox 0.
    pub const LOW0: u32 = bit(29);
    /// Lowest priority flag, mailbox 1.
    pub const LOW1: u32 = bit(30);
    /// Lowest priority flag, mailbox 2.
    pub const LOW2: u32 = bit(31);
    /// Reset value: the three mailboxes empty.
    pub const RESET_VALUE: u32 = 0x1C00_0000;

    /// RQCPx of mailbox `x` (0..2).
    pub const fn rqcp(x: usize) -> u32 {
        RQCP0 << (8 * x)
    }
    /// TXOKx of mailbox `x`.
    pub const fn txok(x: usize) -> u32 {
        TXOK0 << (8 * x)
    }
    /// ALSTx of mailbox `x`.
    pub const fn alst(x: usize) -> u32 {
        ALST0 << (8 * x)
    }
    /// TERRx of mailbox `x`.
    pub const fn terr(x: usize) -> u32 {
        TERR0 << (8 * x)
    }
    /// ABRQx of mailbox `x`.
    pub const fn abrq(x: usize) -> u32 {
        ABRQ0 << (8 * x)
    }
    /// TMEx of mailbox `x`.
    pub const fn tme(x: usize) -> u32 {
        TME0 << x
    }
    /// LOWx of mailbox `x`.
    pub const fn low(x: usize) -> u32 {
        LOW0 << x
    }
}

/// CAN_RFxR bits, x = 0, 1 (40.9.2 "CAN receive FIFO 0 register", "... FIFO 1 ...").
pub mod rfxr {
    use super::{bit, Field};
    /// FIFO message pending: number of messages in the FIFO (0..3).
    pub const FMP: Field = Field::new(0, 2);
    /// FIFO full (write 1 to clear).
    pub const FULL: u32 = bit(3);
    /// FIFO overrun (write 1 to clear).
    pub const FOVR: u32 = bit(4);
    /// Release FIFO output mailbox (set by software).
    pub const RFOM: u32 = bit(5);
}

/// CAN_IER bits (40.9.2 "CAN interrupt enable register").
pub mod ier {
    use super::bit;
    /// Transmit mailbox empty interrupt enable (on RQCPx).
    pub const TMEIE: u32 = bit(0);
    /// FIFO 0 message pending interrupt enable.
    pub const FMPIE0: u32 = bit(1);
    /// FIFO 0 full interrupt enable.
    pub const FFIE0: u32 = bit(2);
    /// FIFO 0 overrun interrupt enable.
    pub const FOVIE0: u32 = bit(3);
    /// FIFO 1 message pending interrupt enable.
    pub const FMPIE1: u32 = bit(4);
    /// FIFO 1 full interrupt enable.
    pub const FFIE1: u32 = bit(5);
    /// FIFO 1 overrun interrupt enable.
    pub const FOVIE1: u32 = bit(6);
    /// Error warning interrupt enable.
    pub const EWGIE: u32 = bit(8);
    /// Error passive interrupt enable.
    pub const EPVIE: u32 = bit(9);
    /// Bus-off interrupt enable.
    pub const BOFIE: u32 = bit(10);
    /// Last error code interrupt enable.
    pub const LECIE: u32 = bit(11);
    /// Error interrupt enable.
    pub const ERRIE: u32 = bit(15);
    /// Wakeup interrupt enable.
    pub const WKUIE: u32 = bit(16);
    /// Sleep interrupt enable.
    pub const SLKIE: u32 = bit(17);

    /// FMPIEx of FIFO `x` (0, 1).
    pub const fn fmpie(x: usize) -> u32 {
        FMPIE0 << (3 * x)
    }
    /// FFIEx of FIFO `x`.
    pub const fn ffie(x: usize) -> u32 {
        FFIE0 << (3 * x)
    }
    /// FOVIEx of FIFO `x`.
    pub const fn fovie(x: usize) -> u32 {
        FOVIE0 << (3 * x)
    }
}

/// CAN_ESR bits (40.9.2 "CAN error status register").
pub mod esr {
    use super::{bit, Field};
    /// Error warning flag (TEC or REC >= 96).
    pub const EWGF: u32 = bit(0);
    /// Error passive flag (TEC or REC > 127).
    pub const EPVF: u32 = bit(1);
    /// Bus-off flag.
    pub const BOFF: u32 = bit(2);
    /// Last error code (see the `LEC_*` values); software may write 7.
    pub const LEC: Field = Field::new(4, 3);
    /// Least significant byte of the 9-bit transmit error counter.
    pub const TEC: Field = Field::new(16, 8);
    /// Receive error counter.
    pub const REC: Field = Field::new(24, 8);

    /// LEC: no error.
    pub const LEC_NO_ERROR: u32 = 0;
    /// LEC: stuff error.
    pub const LEC_STUFF: u32 = 1;
    /// LEC: form error.
    pub const LEC_FORM: u32 = 2;
    /// LEC: acknowledgment error.
    pub const LEC_ACK: u32 = 3;
    /// LEC: bit recessive error.
    pub const LEC_BIT_RECESSIVE: u32 = 4;
    /// LEC: bit dominant error.
    pub const LEC_BIT_DOMINANT: u32 = 5;
    /// LEC: CRC error.
    pub const LEC_CRC: u32 = 6;
    /// LEC: set by software (hardware overwrites it with the next status).
    pub const LEC_SOFTWARE: u32 = 7;
}

/// CAN_BTR bits (40.9.2 "CAN bit timing register"); writable in initialization mode only.
pub mod btr {
    use super::{bit, Field};
    /// Baud rate prescaler (tq = (BRP + 1) × tPCLK).
    pub const BRP: Field = Field::new(0, 10);
    /// Time segment 1 (TS1 + 1 time quanta).
    pub const TS1: Field = Field::new(16, 4);
    /// Time segment 2 (TS2 + 1 time quanta).
    pub const TS2: Field = Field::new(20, 3);
    /// Resynchronization jump width (SJW + 1 time quanta).
    pub const SJW: Field = Field::new(24, 2);
    /// Loop back mode (debug).
    pub const LBKM: u32 = bit(30);
    /// Silent mode (debug).
    pub const SILM: u32 = bit(31);
    /// Reset value: SJW = 1, TS2 = 2, TS1 = 3, BRP = 0.
    pub const RESET_VALUE: u32 = 0x0123_0000;
}

// ---------------------------------------------------------------------------------------
// Mailbox registers (40.9.3 "CAN mailbox registers")
// ---------------------------------------------------------------------------------------

/// Number of transmit mailboxes.
pub const TX_MAILBOXES: usize = 3;
/// Number of receive FIFOs.
pub const RX_FIFOS: usize = 2;
/// Depth of each receive FIFO (messages).
pub const RX_FIFO_DEPTH: usize = 3;

const TX_MAILBOX_BASE: usize = 0x180;
const RX_MAILBOX_BASE: usize = 0x1B0;
const MAILBOX_STRIDE: usize = 0x10;

/// CAN TX mailbox identifier register (CAN_TIxR), mailbox x = 0..2.
pub const fn tixr(x: usize) -> usize {
    TX_MAILBOX_BASE + MAILBOX_STRIDE * x
}
/// CAN mailbox data length control and time stamp register (CAN_TDTxR), x = 0..2.
pub const fn tdtxr(x: usize) -> usize {
    tixr(x) + 0x4
}
/// CAN mailbox data low register (CAN_TDLxR), x = 0..2.
pub const fn tdlxr(x: usize) -> usize {
    tixr(x) + 0x8
}
/// CAN mailbox data high register (CAN_TDHxR), x = 0..2.
pub const fn tdhxr(x: usize) -> usize {
    tixr(x) + 0xC
}
/// CAN receive FIFO mailbox identifier register (CAN_RIxR), FIFO x = 0, 1.
pub const fn rixr(x: usize) -> usize {
    RX_MAILBOX_BASE + MAILBOX_STRIDE * x
}
/// CAN receive FIFO mailbox data length control and time stamp register (CAN_RDTxR).
pub const fn rdtxr(x: usize) -> usize {
    rixr(x) + 0x4
}
/// CAN receive FIFO mailbox data low register (CAN_RDLxR).
pub const fn rdlxr(x: usize) -> usize {
    rixr(x) + 0x8
}
/// CAN receive FIFO mailbox data high register (CAN_RDHxR).
pub const fn rdhxr(x: usize) -> usize {
    rixr(x) + 0xC
}

/// CAN_TIxR bits (40.9.3 "CAN TX mailbox identifier register").
pub mod tixr {
    use super::{bit, Field};
    /// Transmit mailbox request (set by software; cleared by hardware when the mailbox
    /// becomes empty).
    pub const TXRQ: u32 = bit(0);
    /// Remote transmission request (0 = data frame, 1 = remote frame).
    pub const RTR: u32 = bit(1);
    /// Identifier extension (0 = standard, 1 = extended).
    pub const IDE: u32 = bit(2);
    /// Extended identifier `EXID[17:0]` (the low 18 bits of a 29-bit identifier).
    pub const EXID: Field = Field::new(3, 18);
    /// Standard identifier `STID[10:0]`, or `EXID[28:18]` of an extended identifier.
    pub const STID: Field = Field::new(21, 11);
}

/// CAN_TDTxR bits (40.9.3 "CAN mailbox data length control and time stamp register").
pub mod tdtxr {
    use super::{bit, Field};
    /// Data length code.
    pub const DLC: Field = Field::new(0, 4);
    /// Transmit global time: send TIME in data bytes 6 and 7 (TTCM, DLC = 8).
    pub const TGT: u32 = bit(8);
    /// Message time stamp captured at the start of frame (TTCM).
    pub const TIME: Field = Field::new(16, 16);
}

/// CAN_TDLxR / CAN_RDLxR byte fields (data bytes 0..3).
pub mod tdlxr {
    use super::Field;
    /// Data byte 0.
    pub const DATA0: Field = Field::new(0, 8);
    /// Data byte 1.
    pub const DATA1: Field = Field::new(8, 8);
    /// Data byte 2.
    pub const DATA2: Field = Field::new(16, 8);
    /// Data byte 3.
    pub const DATA3: Field = Field::new(24, 8);
}

/// CAN_TDHxR / CAN_RDHxR byte fields (data bytes 4..7).
pub mod tdhxr {
    use super::Field;
    /// Data byte 4.
    pub const DATA4: Field = Field::new(0, 8);
    /// Data byte 5.
    pub const DATA5: Field = Field::new(8, 8);
    /// Data byte 6.
    pub const DATA6: Field = Field::new(16, 8);
    /// Data byte 7.
    pub const DATA7: Field = Field::new(24, 8);
}

/// CAN_RIxR bits (40.9.3 "CAN receive FIFO mailbox identifier register").
pub mod rixr {
    use super::{bit, Field};
    /// Remote transmission request.
    pub const RTR: u32 = bit(1);
    /// Identifier extension.
    pub const IDE: u32 = bit(2);
    /// Extended identifier `EXID[17:0]`.
    pub const EXID: Field = Field::new(3, 18);
    /// Standard identifier, or `EXID[28:18]`.
    pub const STID: Field = Field::new(21, 11);
}

/// CAN_RDTxR bits (40.9.3 "CAN receive FIFO mailbox data length control and time stamp
/// register").
pub mod rdtxr {
    use super::Field;
    /// Data length code.
    pub const DLC: Field = Field::new(0, 4);
    /// Filter match index.
    pub const FMI: Field = Field::new(8, 8);
    /// Message time stamp captured at the start of frame.
    pub const TIME: Field = Field::new(16, 16);
}

/// CAN_RDLxR byte fields (same layout as [`tdlxr`](mod@tdlxr)).
pub mod rdlxr {
    pub use super::tdlxr::{DATA0, DATA1, DATA2, DATA3};
}

/// CAN_RDHxR byte fields (same layout as [`tdhxr`](mod@tdhxr)).
pub mod rdhxr {
    pub use super::tdhxr::{DATA4, DATA5, DATA6, DATA7};
}

// ---------------------------------------------------------------------------------------
// Filter registers (40.9.4 "CAN filter registers")
// ---------------------------------------------------------------------------------------

/// CAN filter master register (CAN_FMR).
pub const FMR: usize = 0x200;
/// CAN filter mode register (CAN_FM1R): 0 = identifier mask, 1 = identifier list.
pub const FM1R: usize = 0x204;
/// CAN filter scale register (CAN_FS1R): 0 = dual 16-bit, 1 = single 32-bit.
pub const FS1R: usize = 0x20C;
/// CAN filter FIFO assignment register (CAN_FFA1R): 0 = FIFO 0, 1 = FIFO 1.
pub const FFA1R: usize = 0x214;
/// CAN filter activation register (CAN_FA1R).
pub const FA1R: usize = 0x21C;

const FILTER_BANK_BASE: usize = 0x240;
const FILTER_BANK_STRIDE: usize = 0x8;

/// Filter bank i register 1 (CAN_FiR1), i = 0..27.
pub const fn fir1(i: usize) -> usize {
    FILTER_BANK_BASE + FILTER_BANK_STRIDE * i
}
/// Filter bank i register 2 (CAN_FiR2), i = 0..27.
pub const fn fir2(i: usize) -> usize {
    fir1(i) + 0x4
}

/// CAN_FMR bits (40.9.4 "CAN filter master register").
pub mod fmr {
    use super::{bit, Field};
    /// Filter initialization mode (1 = the filters can be configured; reception is
    /// deactivated).
    pub const FINIT: u32 = bit(0);
    /// CAN2 start bank: banks `0..CAN2SB` belong to CAN1, `CAN2SB..28` to CAN2 (the
    /// lecture notes call it CANSB). Dual CAN only.
    #[doc(alias = "CANSB")]
    pub const CAN2SB: Field = Field::new(8, 6);
    /// Reset value: FINIT = 1, CAN2SB = 14 (reserved bits read 0x2A1C_0000).
    pub const RESET_VALUE: u32 = 0x2A1C_0E01;
}

/// CAN_FM1R bits (40.9.4 "CAN filter mode register").
pub mod fm1r {
    /// FBMi: mode of filter bank `i` (0 = identifier mask, 1 = identifier list).
    pub const fn fbm(i: usize) -> u32 {
        1 << i
    }
}

/// CAN_FS1R bits (40.9.4 "CAN filter scale register").
pub mod fs1r {
    /// FSCi: scale of filter bank `i` (0 = dual 16-bit, 1 = single 32-bit).
    pub const fn fsc(i: usize) -> u32 {
        1 << i
    }
}

/// CAN_FFA1R bits (40.9.4 "CAN filter FIFO assignment register").
pub mod ffa1r {
    /// FFAi: FIFO of filter bank `i` (0 = FIFO 0, 1 = FIFO 1).
    pub const fn ffa(i: usize) -> u32 {
        1 << i
    }
}

/// CAN_FA1R bits (40.9.4 "CAN filter activation register").
pub mod fa1r {
    /// FACTi: filter bank `i` active.
    pub const fn fact(i: usize) -> u32 {
        1 << i
    }
}

/// Bit mapping of the filter bank registers CAN_FiR1/CAN_FiR2 (40.7.4 "Identifier
/// filtering", figure "Filter bank scale configuration - register organization").
///
/// 32-bit scale: one register holds `STID[10:0] EXID[17:0] IDE RTR 0` (the layout of
/// CAN_TIxR/CAN_RIxR); in mask mode FiR1 is the identifier and FiR2 the mask, in list
/// mode both are identifiers. 16-bit scale: each half-word holds
/// `STID[10:0] RTR IDE EXID[17:15]`; in mask mode the low half of a register is the
/// identifier and its high half the mask (FiR1 = filter n, FiR2 = filter n+1); in list
/// mode the four half-words `FiR1[15:0]`, `FiR1[31:16]`, `FiR2[15:0]`, `FiR2[31:16]` are
/// filters n..n+3.
pub mod firx {
    use super::{bit, Field};
    /// 32-bit scale: `STID[10:0]` / `EXID[28:18]`.
    pub const STID: Field = Field::new(21, 11);
    /// 32-bit scale: `EXID[17:0]`.
    pub const EXID: Field = Field::new(3, 18);
    /// 32-bit scale: IDE.
    pub const IDE: u32 = bit(2);
    /// 32-bit scale: RTR.
    pub const RTR: u32 = bit(1);
    /// 16-bit scale (within a half-word): `STID[10:0]`.
    pub const STID16: Field = Field::new(5, 11);
    /// 16-bit scale: RTR.
    pub const RTR16: u32 = bit(4);
    /// 16-bit scale: IDE.
    pub const IDE16: u32 = bit(3);
    /// 16-bit scale: `EXID[17:15]`.
    pub const EXID16: Field = Field::new(0, 3);
    /// The low half-word of a filter register (16-bit scale).
    pub const LOW_HALF: Field = Field::new(0, 16);
    /// The high half-word of a filter register (16-bit scale).
    pub const HIGH_HALF: Field = Field::new(16, 16);
}
