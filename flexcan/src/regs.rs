//! FlexCAN register map for the Kinetis K20 (MK20DX256, Teensy 3.1/3.2), K64 (MK64FX512,
//! Teensy 3.5) and K66 (MK66FX1M0, Teensy 3.6), plus the SIM clock gates and PORT pin
//! control registers the backend touches.
//!
//! Every name is the one of the reference manuals (K20P64M72SF1RM and K66P144M180SF5RM,
//! chapter "CAN (FlexCAN)", section "Memory map/register definition"; chapter "System
//! Integration Module (SIM)"; chapter "Port control and interrupts (PORT)").
//!
//! Naming scheme:
//! - register offsets from the module base are `usize` constants named after the register
//!   ([`MCR`], [`CTRL1`], ...); the message buffers and the individual masks have `const fn`
//!   address helpers ([`mb_cs`], [`mb_id`], [`mb_word0`], [`mb_word1`], [`rximr`],
//!   [`rx_fifo_filter`]);
//! - each register has a module of the same name in lower case ([`mcr`], [`ctrl1`], ...)
//!   holding its fields: a one-bit field is a `u32` mask (`mcr::MDIS`), a wider field is a
//!   [`Field`] (`mcr::MAXMB`) that extracts, builds and replaces the value;
//! - enumerated field values are constants in the register module (`mcr::IDAM_FORMAT_A`,
//!   `esr1::FLTCONF_BUS_OFF`), message-buffer codes are in [`code`].
//!
//! `tests/regmap.rs` checks every offset and bit position against the vendor SVD data
//! (the `mk20d7` and `mk66f18` peripheral access crates).

/// A bit field of a 32-bit register: `width` bits starting at bit `shift`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Field {
    /// Position of the least significant bit.
    pub shift: u32,
    /// Number of bits.
    pub width: u32,
}

impl Field {
    /// A field of `width` bits at bit `shift`.
    pub const fn new(shift: u32, width: u32) -> Self {
        Field { shift, width }
    }

    /// The field's bits in place within the register.
    pub const fn mask(self) -> u32 {
        let ones = if self.width >= 32 {
            u32::MAX
        } else {
            (1u32 << self.width) - 1
        };
        ones << self.shift
    }

    /// The largest value the field holds.
    pub const fn max(self) -> u32 {
        self.mask() >> self.shift
    }

    /// The field's value in register value `reg`.
    pub const fn get(self, reg: u32) -> u32 {
        (reg & self.mask()) >> self.shift
    }

    /// `value` shifted into place (bits beyond the width are dropped).
    pub const fn val(self, value: u32) -> u32 {
        (value << self.shift) & self.mask()
    }

    /// `reg` with the field replaced by `value`.
    pub const fn replace(self, reg: u32, value: u32) -> u32 {
        (reg & !self.mask()) | self.val(value)
    }
}

// ---------------------------------------------------------------------------------------
// Base addresses and module geometry
// ---------------------------------------------------------------------------------------

/// FlexCAN0 base address (K20, K64, K66; memory map "CAN0").
pub const CAN0_BASE: usize = 0x4002_4000;

/// End of the module's registers (the last is `RXIMR15` at 0x8BC).
pub const BLOCK_END: usize = 0x8C0;

/// End of an i.MX RT1062 module's registers as the driver uses them: `RXIMR0`–`RXIMR63`
/// at 0x880–0x97C (IMXRT1060RM, FlexCAN memory map; 64 message buffers, so 64 individual
/// masks, of which the RT1062 layout writes those of its up to 32 primary filters and
/// of its transmit mailboxes, up to MB46). The glitch filter register beyond
/// (`GFWR`, 0x9E0) is not used.
pub const IMXRT_BLOCK_END: usize = 0x980;

/// The register window of the board's modules ([`FlexCanRegs`]): [`IMXRT_BLOCK_END`]
/// with the feature `teensy40` or `teensy41` (the RT1062's `Can1`–`Can3`, whose
/// layout, [`crate::layout::Imxrt1062`], writes `RXIMR16` and above), [`BLOCK_END`]
/// otherwise (the Kinetis modules).
#[cfg(any(feature = "teensy40", feature = "teensy41"))]
pub const BOARD_BLOCK_END: usize = IMXRT_BLOCK_END;
/// The register window of the board's modules ([`FlexCanRegs`]): [`IMXRT_BLOCK_END`]
/// with the feature `teensy40` or `teensy41`, [`BLOCK_END`] otherwise (the Kinetis
/// modules).
#[cfg(not(any(feature = "teensy40", feature = "teensy41")))]
pub const BOARD_BLOCK_END: usize = BLOCK_END;

/// Volatile access to one FlexCAN module's registers (offsets `0..BOARD_BLOCK_END`: the
/// Kinetis block, or with a Teensy 4 feature the RT1062's, whose `RXIMR16`–`RXIMR63`
/// lie beyond the Kinetis one). An access outside the window is dropped (a read gives
/// 0; debug builds assert), so the window must cover every register the board's
/// layout writes.
pub type FlexCanRegs = twocan_core::Mmio<BOARD_BLOCK_END>;

/// [`twocan_core::Mmio`] with the base address a constant (`twocan_core::Fixed`): the
/// FlexCAN module whose registers start at `BASE`, offsets `0..END` ([`BLOCK_END`], the
/// Kinetis block, unless named; [`IMXRT_BLOCK_END`] for the RT1062's modules,
/// [`crate::imxrt::Can1At`] ...). The value is empty and every access is one load or
/// store at `BASE + offset`, without reading a base address first (issue 21). The window
/// check of [`twocan_core::Mmio`] stays: an offset outside the module's registers reads 0
/// and writes nothing (a `debug_assert` in debug builds).
///
/// A token gives its own module's handle, with no `unsafe` in the program: its
/// `begin_planned_in_place` / `begin_in_place` into a state whose register type is the
/// module's (`Can0At` for `Can0` ..., the tokens' `TokenRegisters`); otherwise
/// `Fixed::new` (`unsafe`, the promise of [`twocan_core::Mmio::new`]).
///
/// ```
/// use twocan_flexcan::regs::{Can0At, FlexCanAt, BLOCK_END, CAN0_BASE};
/// assert_eq!(core::mem::size_of::<Can0At>(), 0);
/// let _: Option<FlexCanAt<CAN0_BASE, BLOCK_END>> = None::<Can0At>;
/// ```
pub type FlexCanAt<const BASE: usize, const END: usize = BLOCK_END> = twocan_core::Fixed<BASE, END>;

/// FlexCAN0 at its compile-time address ([`CAN0_BASE`]), the Kinetis window.
pub type Can0At = FlexCanAt<CAN0_BASE, BLOCK_END>;
/// FlexCAN1 at its compile-time address ([`CAN1_BASE`], K66 only), the Kinetis window.
pub type Can1At = FlexCanAt<CAN1_BASE, BLOCK_END>;

/// Volatile access to the SIM and PORT registers `begin` writes, by absolute address
/// (base 0; the window from the SIM to the end of PORTE).
pub type SystemRegs = twocan_core::Mmio<0x4004_E000, 0x4004_7000>;
/// FlexCAN1 base address (K66 only; memory map "CAN1").
pub const CAN1_BASE: usize = 0x400A_4000;

/// Number of message buffers of FlexCAN on K20, K64 and K66 ("FlexCAN configuration":
/// 16 MBs, MAXMB reset value 0x0F).
pub const NUM_MB: usize = 16;

// ---------------------------------------------------------------------------------------
// Register offsets ("FlexCAN memory map")
// ---------------------------------------------------------------------------------------

/// Module Configuration Register.
pub const MCR: usize = 0x00;
/// Control 1 register.
pub const CTRL1: usize = 0x04;
/// Free Running Timer.
pub const TIMER: usize = 0x08;
/// Rx Mailboxes Global Mask Register.
pub const RXMGMASK: usize = 0x10;
/// Rx 14 Mask register.
pub const RX14MASK: usize = 0x14;
/// Rx 15 Mask register.
pub const RX15MASK: usize = 0x18;
/// Error Counter.
pub const ECR: usize = 0x1C;
/// Error and Status 1 register.
pub const ESR1: usize = 0x20;
/// Interrupt Masks 2 register (MB32–MB63; modules of more than 32 message buffers, the
/// i.MX RT1062's: IMXRT1060RM, FlexCAN memory map).
pub const IMASK2: usize = 0x24;
/// Interrupt Masks 1 register.
pub const IMASK1: usize = 0x28;
/// Interrupt Flags 2 register (MB32–MB63; i.MX RT1062).
pub const IFLAG2: usize = 0x2C;
/// Interrupt Flags 1 register.
pub const IFLAG1: usize = 0x30;
/// Control 2 register.
pub const CTRL2: usize = 0x34;
/// Error and Status 2 register.
pub const ESR2: usize = 0x38;
/// CRC Register.
pub const CRCR: usize = 0x44;
/// Rx FIFO Global Mask register.
pub const RXFGMASK: usize = 0x48;
/// Rx FIFO Information Register.
pub const RXFIR: usize = 0x4C;

/// First message buffer ("Message buffer structure": MB n occupies 0x80 + 16·n).
pub const MB_BASE: usize = 0x80;
/// Size of one message buffer in bytes.
pub const MB_STRIDE: usize = 16;
/// First Rx Individual Mask Register (RXIMR0).
pub const RXIMR_BASE: usize = 0x880;

/// Control and Status word of message buffer `n`.
pub const fn mb_cs(n: usize) -> usize {
    MB_BASE + MB_STRIDE * n
}
/// Identifier word of message buffer `n`.
pub const fn mb_id(n: usize) -> usize {
    MB_BASE + MB_STRIDE * n + 4
}
/// Data word 0 (bytes 0..=3) of message buffer `n`.
pub const fn mb_word0(n: usize) -> usize {
    MB_BASE + MB_STRIDE * n + 8
}
/// Data word 1 (bytes 4..=7) of message buffer `n`.
pub const fn mb_word1(n: usize) -> usize {
    MB_BASE + MB_STRIDE * n + 12
}
/// Rx Individual Mask Register `n` (RXIMRn).
pub const fn rximr(n: usize) -> usize {
    RXIMR_BASE + 4 * n
}

/// Rx FIFO output: the message-buffer-shaped window at MB0 ("Rx FIFO structure").
pub const RX_FIFO_OUTPUT: usize = MB_BASE;
/// Start of the Rx FIFO ID filter table (MB6, "Rx FIFO structure").
pub const RX_FIFO_FILTER_BASE: usize = 0xE0;
/// Rx FIFO ID filter table element `n`.
pub const fn rx_fifo_filter(n: usize) -> usize {
    RX_FIFO_FILTER_BASE + 4 * n
}
/// Rx FIFO depth in frames ("Rx FIFO": six frames deep).
pub const RX_FIFO_DEPTH: usize = 6;

/// Number of Rx FIFO ID filter table elements for CTRL2\[RFFN\] = `rffn`: 8 × (RFFN + 1)
/// ("Control 2 register (CTRL2)", table "Rx FIFO filter: possible structures").
pub const fn rx_fifo_filter_count(rffn: u32) -> usize {
    8 * (rffn as usize + 1)
}

/// Number of message buffers occupied by the Rx FIFO and its ID filter table for
/// CTRL2\[RFFN\] = `rffn` (the FIFO engine takes MB0–MB5, each 8 filters take two MBs).
pub const fn rx_fifo_occupied_mbs(rffn: u32) -> usize {
    6 + 2 * (rffn as usize + 1)
}

// ---------------------------------------------------------------------------------------
// Fields
// ---------------------------------------------------------------------------------------

/// MCR fields ("Module Configuration Register (CANx_MCR)").
pub mod mcr {
    use super::Field;
    /// Module Disable.
    pub const MDIS: u32 = 1 << 31;
    /// Freeze Enable.
    pub const FRZ: u32 = 1 << 30;
    /// Rx FIFO Enable.
    pub const RFEN: u32 = 1 << 29;
    /// Halt FlexCAN.
    pub const HALT: u32 = 1 << 28;
    /// FlexCAN Not Ready (read-only).
    pub const NOTRDY: u32 = 1 << 27;
    /// Wake Up Interrupt Mask.
    pub const WAKMSK: u32 = 1 << 26;
    /// Soft Reset (self-clearing).
    pub const SOFTRST: u32 = 1 << 25;
    /// Freeze Mode Acknowledge (read-only).
    pub const FRZACK: u32 = 1 << 24;
    /// Supervisor Mode.
    pub const SUPV: u32 = 1 << 23;
    /// Self Wake Up.
    pub const SLFWAK: u32 = 1 << 22;
    /// Warning Interrupt Enable.
    pub const WRNEN: u32 = 1 << 21;
    /// Low-Power Mode Acknowledge (read-only).
    pub const LPMACK: u32 = 1 << 20;
    /// Wake Up Source (K66 only; reserved on K20).
    pub const WAKSRC: u32 = 1 << 19;
    /// Self Reception Disable.
    pub const SRXDIS: u32 = 1 << 17;
    /// Individual Rx Masking And Queue Enable.
    pub const IRMQ: u32 = 1 << 16;
    /// Local Priority Enable.
    pub const LPRIOEN: u32 = 1 << 13;
    /// Abort Enable.
    pub const AEN: u32 = 1 << 12;
    /// ID Acceptance Mode (format of the Rx FIFO ID filter table elements).
    pub const IDAM: Field = Field::new(8, 2);
    /// Number Of The Last Message Buffer.
    pub const MAXMB: Field = Field::new(0, 7);

    /// IDAM: format A, one full ID (standard or extended) per element.
    pub const IDAM_FORMAT_A: u32 = 0b00;
    /// IDAM: format B, two full standard IDs or two partial 14-bit extended IDs per element.
    pub const IDAM_FORMAT_B: u32 = 0b01;
    /// IDAM: format C, four partial 8-bit IDs per element.
    pub const IDAM_FORMAT_C: u32 = 0b10;
    /// IDAM: format D, all frames rejected.
    pub const IDAM_FORMAT_D: u32 = 0b11;

    /// Reset value: disabled (MDIS, LPMACK), freeze requested (FRZ, HALT), NOTRDY,
    /// SUPV, MAXMB = 15.
    pub const RESET: u32 = 0xD890_000F;
}

/// CTRL1 fields ("Control 1 register (CANx_CTRL1)").
pub mod ctrl1 {
    use super::Field;
    /// Prescaler Division Factor (Sclock = PE clock / (PRESDIV + 1)).
    pub const PRESDIV: Field = Field::new(24, 8);
    /// Resync Jump Width (RJW + 1 time quanta).
    pub const RJW: Field = Field::new(22, 2);
    /// Phase Segment 1 (PSEG1 + 1 time quanta).
    pub const PSEG1: Field = Field::new(19, 3);
    /// Phase Segment 2 (PSEG2 + 1 time quanta).
    pub const PSEG2: Field = Field::new(16, 3);
    /// Bus Off Mask (bus-off interrupt enable).
    pub const BOFFMSK: u32 = 1 << 15;
    /// Error Mask (error interrupt enable).
    pub const ERRMSK: u32 = 1 << 14;
    /// CAN Engine Clock Source (0: oscillator clock, 1: peripheral clock).
    pub const CLKSRC: u32 = 1 << 13;
    /// Loop Back Mode.
    pub const LPB: u32 = 1 << 12;
    /// Tx Warning Interrupt Mask.
    pub const TWRNMSK: u32 = 1 << 11;
    /// Rx Warning Interrupt Mask.
    pub const RWRNMSK: u32 = 1 << 10;
    /// CAN Bit Sampling (1: three samples).
    pub const SMP: u32 = 1 << 7;
    /// Bus Off Recovery (1: automatic recovery disabled).
    pub const BOFFREC: u32 = 1 << 6;
    /// Timer Sync.
    pub const TSYN: u32 = 1 << 5;
    /// Lowest Buffer Transmitted First.
    pub const LBUF: u32 = 1 << 4;
    /// Listen-Only Mode.
    pub const LOM: u32 = 1 << 3;
    /// Propagation Segment (PROPSEG + 1 time quanta).
    pub const PROPSEG: Field = Field::new(0, 3);
    /// Reset value.
    pub const RESET: u32 = 0;
}

/// TIMER fields ("Free Running Timer (CANx_TIMER)").
pub mod timer {
    use super::Field;
    /// Timer Value (16 bits, counts bit times).
    pub const TIMER: Field = Field::new(0, 16);
}

/// ECR fields ("Error Counter (CANx_ECR)").
pub mod ecr {
    use super::Field;
    /// Transmit Error Counter.
    pub const TXERRCNT: Field = Field::new(0, 8);
    /// Receive Error Counter.
    pub const RXERRCNT: Field = Field::new(8, 8);
}

/// ESR1 fields ("Error and Status 1 register (CANx_ESR1)").
pub mod esr1 {
    use super::Field;
    /// Wake-Up Interrupt (write 1 to clear).
    pub const WAKINT: u32 = 1 << 0;
    /// Error Interrupt (write 1 to clear).
    pub const ERRINT: u32 = 1 << 1;
    /// Bus Off Interrupt (write 1 to clear).
    pub const BOFFINT: u32 = 1 << 2;
    /// FlexCAN In Reception.
    pub const RX: u32 = 1 << 3;
    /// Fault Confinement State.
    pub const FLTCONF: Field = Field::new(4, 2);
    /// FlexCAN In Transmission.
    pub const TX: u32 = 1 << 6;
    /// CAN bus is IDLE.
    pub const IDLE: u32 = 1 << 7;
    /// Rx Error Warning (RXERRCNT ≥ 96).
    pub const RXWRN: u32 = 1 << 8;
    /// Tx Error Warning (TXERRCNT ≥ 96).
    pub const TXWRN: u32 = 1 << 9;
    /// Stuffing Error (cleared by reading ESR1).
    pub const STFERR: u32 = 1 << 10;
    /// Form Error (cleared by reading ESR1).
    pub const FRMERR: u32 = 1 << 11;
    /// Cyclic Redundancy Check Error (cleared by reading ESR1).
    pub const CRCERR: u32 = 1 << 12;
    /// Acknowledge Error (cleared by reading ESR1).
    pub const ACKERR: u32 = 1 << 13;
    /// Bit0 Error: a bit sent dominant was received recessive (cleared by reading ESR1).
    pub const BIT0ERR: u32 = 1 << 14;
    /// Bit1 Error: a bit sent recessive was received dominant (cleared by reading ESR1).
    pub const BIT1ERR: u32 = 1 << 15;
    /// Rx Warning Interrupt Flag (write 1 to clear).
    pub const RWRNINT: u32 = 1 << 16;
    /// Tx Warning Interrupt Flag (write 1 to clear).
    pub const TWRNINT: u32 = 1 << 17;
    /// CAN Synchronization Status.
    pub const SYNCH: u32 = 1 << 18;

    /// All error bits STFERR..BIT1ERR.
    pub const ERROR_BITS: u32 = STFERR | FRMERR | CRCERR | ACKERR | BIT0ERR | BIT1ERR;
    /// All write-1-to-clear interrupt flags.
    pub const W1C_BITS: u32 = WAKINT | ERRINT | BOFFINT | RWRNINT | TWRNINT;

    /// FLTCONF: error active.
    pub const FLTCONF_ERROR_ACTIVE: u32 = 0b00;
    /// FLTCONF: error passive.
    pub const FLTCONF_ERROR_PASSIVE: u32 = 0b01;
    /// FLTCONF: bus off (`1x`).
    pub const FLTCONF_BUS_OFF: u32 = 0b10;
}

/// IMASK1 fields ("Interrupt Masks 1 register (CANx_IMASK1)"): bit n enables MB n.
pub mod imask1 {
    use super::Field;
    /// Buffer MB i Mask, one bit per MB (the register has 32; 16 MBs exist on these parts).
    pub const BUFLM: Field = Field::new(0, 32);
    /// The bits of the 16 message buffers that exist.
    pub const IMPLEMENTED: u32 = 0xFFFF;
}

/// IFLAG1 fields ("Interrupt Flags 1 register (CANx_IFLAG1)"): bit n flags MB n; with the
/// Rx FIFO enabled, bits 5–7 are the FIFO flags and bits 0–4 are unused.
pub mod iflag1 {
    /// Buffer MB5 Interrupt, or "Frames available in Rx FIFO" (write 1 to pop the output).
    pub const BUF5I: u32 = 1 << 5;
    /// Buffer MB6 Interrupt, or "Rx FIFO Warning" (the FIFO went from 4 to 5 frames).
    pub const BUF6I: u32 = 1 << 6;
    /// Buffer MB7 Interrupt, or "Rx FIFO Overflow" (a frame was lost, FIFO full).
    pub const BUF7I: u32 = 1 << 7;
    /// Alias of [`BUF5I`] when the Rx FIFO is enabled.
    pub const RX_FIFO_FRAMES_AVAILABLE: u32 = BUF5I;
    /// Alias of [`BUF6I`] when the Rx FIFO is enabled.
    pub const RX_FIFO_WARNING: u32 = BUF6I;
    /// Alias of [`BUF7I`] when the Rx FIFO is enabled.
    pub const RX_FIFO_OVERFLOW: u32 = BUF7I;
    /// Flag of message buffer `n`.
    pub const fn buf(n: usize) -> u32 {
        1 << n
    }
}

/// CTRL2 fields ("Control 2 register (CANx_CTRL2)").
pub mod ctrl2 {
    use super::Field;
    /// Write-Access To Memory In Freeze Mode.
    pub const WRMFRZ: u32 = 1 << 28;
    /// Number Of Rx FIFO Filters (8 × (RFFN + 1) filter elements).
    pub const RFFN: Field = Field::new(24, 4);
    /// Tx Arbitration Start Delay.
    pub const TASD: Field = Field::new(19, 5);
    /// Mailboxes Reception Priority (1: matching starts from the mailboxes).
    pub const MRP: u32 = 1 << 18;
    /// Remote Request Storing (1: remote request frames are stored, not answered).
    pub const RRS: u32 = 1 << 17;
    /// Entire Frame Arbitration Field Comparison Enable For Rx Mailboxes.
    pub const EACEN: u32 = 1 << 16;
    /// Reset value (TASD = 0x16).
    pub const RESET: u32 = 0x00B0_0000;
}

/// ESR2 fields ("Error and Status 2 register (CANx_ESR2)").
pub mod esr2 {
    use super::Field;
    /// Inactive Mailbox.
    pub const IMB: u32 = 1 << 13;
    /// Valid Priority Status.
    pub const VPS: u32 = 1 << 14;
    /// Lowest Priority Tx Mailbox.
    pub const LPTM: Field = Field::new(16, 7);
}

/// CRCR fields ("CRC Register (CANx_CRCR)").
pub mod crcr {
    use super::Field;
    /// CRC of the last transmitted frame.
    pub const TXCRC: Field = Field::new(0, 15);
    /// CRC Mailbox: the MB whose frame the CRC belongs to.
    pub const MBCRC: Field = Field::new(16, 7);
}

/// RXFIR fields ("Rx FIFO Information Register (CANx_RXFIR)").
pub mod rxfir {
    use super::Field;
    /// Identifier Acceptance Filter Hit Indicator: the lowest-numbered filter that matched
    /// the frame at the FIFO output (valid while IFLAG1\[BUF5I\] is set).
    pub const IDHIT: Field = Field::new(0, 9);
}

/// Message buffer Control and Status word ("Message buffer structure").
pub mod cs {
    use super::Field;
    /// Message Buffer Code (see [`super::code`]).
    pub const CODE: Field = Field::new(24, 4);
    /// Substitute Remote Request (extended frames: 1).
    pub const SRR: u32 = 1 << 22;
    /// ID Extended Bit.
    pub const IDE: u32 = 1 << 21;
    /// Remote Transmission Request.
    pub const RTR: u32 = 1 << 20;
    /// Length of Data in Bytes.
    pub const DLC: Field = Field::new(16, 4);
    /// Free-Running Counter Time Stamp (TIMER at the start of the identifier field).
    pub const TIME_STAMP: Field = Field::new(0, 16);
}

/// Message buffer identifier word ("Message buffer structure").
pub mod id {
    use super::Field;
    /// Local priority (used for Tx arbitration when MCR\[LPRIOEN\] = 1; not transmitted).
    pub const PRIO: Field = Field::new(29, 3);
    /// Standard identifier, bits 28–18.
    pub const STD: Field = Field::new(18, 11);
    /// Extended-only part of the identifier, bits 17–0.
    pub const EXT: Field = Field::new(0, 18);
    /// The whole 29-bit extended identifier (STD:EXT), bits 28–0.
    pub const EXT_ID: Field = Field::new(0, 29);
}

/// Message buffer data word 0: data bytes 0..=3, byte 0 most significant.
pub mod word0 {
    use super::Field;
    /// Data byte 0.
    pub const DATA_BYTE_0: Field = Field::new(24, 8);
    /// Data byte 1.
    pub const DATA_BYTE_1: Field = Field::new(16, 8);
    /// Data byte 2.
    pub const DATA_BYTE_2: Field = Field::new(8, 8);
    /// Data byte 3.
    pub const DATA_BYTE_3: Field = Field::new(0, 8);
}

/// Message buffer data word 1: data bytes 4..=7, byte 4 most significant.
pub mod word1 {
    use super::Field;
    /// Data byte 4.
    pub const DATA_BYTE_4: Field = Field::new(24, 8);
    /// Data byte 5.
    pub const DATA_BYTE_5: Field = Field::new(16, 8);
    /// Data byte 6.
    pub const DATA_BYTE_6: Field = Field::new(8, 8);
    /// Data byte 7.
    pub const DATA_BYTE_7: Field = Field::new(0, 8);
}

/// Message buffer codes ("Message buffer code for Rx buffers", "Message buffer code for Tx
/// buffers"): values of [`cs::CODE`].
pub mod code {
    /// Rx: MB is not active.
    pub const RX_INACTIVE: u32 = 0b0000;
    /// Rx: MB is active and empty.
    pub const RX_EMPTY: u32 = 0b0100;
    /// Rx: MB is full.
    pub const RX_FULL: u32 = 0b0010;
    /// Rx: a frame was overwritten into a full buffer.
    pub const RX_OVERRUN: u32 = 0b0110;
    /// Rx: MB recognises a remote request frame and transmits a response (CTRL2\[RRS\] = 0).
    pub const RX_RANSWER: u32 = 0b1010;
    /// Rx: BUSY bit, FlexCAN is updating the MB (code bit 0).
    pub const RX_BUSY: u32 = 0b0001;
    /// Tx: MB does not participate in arbitration.
    pub const TX_INACTIVE: u32 = 0b1000;
    /// Tx: transmission aborted (MCR\[AEN\] = 1).
    pub const TX_ABORT: u32 = 0b1001;
    /// Tx: transmit a data frame once (RTR = 0), then INACTIVE.
    pub const TX_DATA: u32 = 0b1100;
    /// Tx: transmit a remote frame once (RTR = 1), then Rx EMPTY with the same ID.
    pub const TX_REMOTE: u32 = 0b1100;
    /// Tx: transmit the response to a matched remote request once, then RANSWER.
    pub const TX_TANSWER: u32 = 0b1110;
}

/// Rx FIFO ID filter table element, format A ("Rx FIFO structure", MCR\[IDAM\] = 0).
pub mod filter_a {
    use super::Field;
    /// Remote frame: 1 accepts remote frames and rejects data frames.
    pub const RTR: u32 = 1 << 31;
    /// Extended frame: 1 accepts extended frames and rejects standard frames.
    pub const IDE: u32 = 1 << 30;
    /// Rx Frame Identifier, bits 29–1 (extended: all 29 bits).
    pub const RXIDA: Field = Field::new(1, 29);
    /// Standard identifier within RXIDA, bits 29–19.
    pub const RXIDA_STD: Field = Field::new(19, 11);
}

/// Rx FIFO ID filter table element, format B (MCR\[IDAM\] = 1): two filters per element.
pub mod filter_b {
    use super::Field;
    /// RTR of filter 0.
    pub const RTR0: u32 = 1 << 31;
    /// IDE of filter 0.
    pub const IDE0: u32 = 1 << 30;
    /// RXIDB_0, bits 29–16 (standard: 29–19; extended: the 14 MSBs of the ID).
    pub const RXIDB_0: Field = Field::new(16, 14);
    /// RTR of filter 1.
    pub const RTR1: u32 = 1 << 15;
    /// IDE of filter 1.
    pub const IDE1: u32 = 1 << 14;
    /// RXIDB_1, bits 13–0 (standard: 13–3; extended: the 14 MSBs of the ID).
    pub const RXIDB_1: Field = Field::new(0, 14);
}

/// Rx FIFO ID filter table element, format C (MCR\[IDAM\] = 2): four 8-bit ID slices (the 8
/// most significant bits of the identifier).
pub mod filter_c {
    use super::Field;
    /// RXIDC_0, bits 31–24.
    pub const RXIDC_0: Field = Field::new(24, 8);
    /// RXIDC_1, bits 23–16.
    pub const RXIDC_1: Field = Field::new(16, 8);
    /// RXIDC_2, bits 15–8.
    pub const RXIDC_2: Field = Field::new(8, 8);
    /// RXIDC_3, bits 7–0.
    pub const RXIDC_3: Field = Field::new(0, 8);
}

// ---------------------------------------------------------------------------------------
// SIM clock gates ("System Integration Module (SIM)")
// ---------------------------------------------------------------------------------------

/// SIM clock-gate registers and bits.
pub mod sim {
    /// SIM base address (SIM_SOPT1).
    pub const SIM_BASE: usize = 0x4004_7000;
    /// System Clock Gating Control Register 3 (FlexCAN1 on K66).
    pub const SIM_SCGC3: usize = 0x4004_8030;
    /// System Clock Gating Control Register 5 (PORT clocks).
    pub const SIM_SCGC5: usize = 0x4004_8038;
    /// System Clock Gating Control Register 6 (FlexCAN0).
    pub const SIM_SCGC6: usize = 0x4004_803C;
    /// SIM_SCGC6: FlexCAN0 Clock Gate Control.
    pub const SCGC6_FLEXCAN0: u32 = 1 << 4;
    /// SIM_SCGC3: FlexCAN1 Clock Gate Control (K66 only).
    pub const SCGC3_FLEXCAN1: u32 = 1 << 4;
    /// SIM_SCGC5: Port A Clock Gate Control.
    pub const SCGC5_PORTA: u32 = 1 << 9;
    /// SIM_SCGC5: Port B Clock Gate Control.
    pub const SCGC5_PORTB: u32 = 1 << 10;
    /// SIM_SCGC5: Port C Clock Gate Control.
    pub const SCGC5_PORTC: u32 = 1 << 11;
    /// SIM_SCGC5: Port D Clock Gate Control.
    pub const SCGC5_PORTD: u32 = 1 << 12;
    /// SIM_SCGC5: Port E Clock Gate Control.
    pub const SCGC5_PORTE: u32 = 1 << 13;
}

// ---------------------------------------------------------------------------------------
// PORT pin control ("Port control and interrupts (PORT)")
// ---------------------------------------------------------------------------------------

/// PORT pin-control registers.
pub mod port {
    use super::Field;

    /// A GPIO port.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum Port {
        /// PORTA.
        A,
        /// PORTB.
        B,
        /// PORTC.
        C,
        /// PORTD.
        D,
        /// PORTE.
        E,
    }

    impl Port {
        /// Base address of the port's PORT module (PORTx_PCR0).
        pub const fn base(self) -> usize {
            match self {
                Port::A => 0x4004_9000,
                Port::B => 0x4004_A000,
                Port::C => 0x4004_B000,
                Port::D => 0x4004_C000,
                Port::E => 0x4004_D000,
            }
        }

        /// The port's clock-gate bit in SIM_SCGC5.
        pub const fn scgc5_bit(self) -> u32 {
            match self {
                Port::A => super::sim::SCGC5_PORTA,
                Port::B => super::sim::SCGC5_PORTB,
                Port::C => super::sim::SCGC5_PORTC,
                Port::D => super::sim::SCGC5_PORTD,
                Port::E => super::sim::SCGC5_PORTE,
            }
        }

        /// Address of PORTx_PCRn.
        pub const fn pcr(self, n: u8) -> usize {
            self.base() + 4 * n as usize
        }
    }

    /// Pull Select (1: pull-up, with PE).
    pub const PCR_PS: u32 = 1 << 0;
    /// Pull Enable.
    pub const PCR_PE: u32 = 1 << 1;
    /// Slew Rate Enable.
    pub const PCR_SRE: u32 = 1 << 2;
    /// Passive Filter Enable.
    pub const PCR_PFE: u32 = 1 << 4;
    /// Open Drain Enable.
    pub const PCR_ODE: u32 = 1 << 5;
    /// Drive Strength Enable.
    pub const PCR_DSE: u32 = 1 << 6;
    /// Pin Mux Control (ALTn).
    pub const PCR_MUX: Field = Field::new(8, 3);
    /// Lock Register.
    pub const PCR_LK: u32 = 1 << 15;
    /// Interrupt Configuration.
    pub const PCR_IRQC: Field = Field::new(16, 4);
    /// Interrupt Status Flag.
    pub const PCR_ISF: u32 = 1 << 24;
}

/// Teensy pin → port pin and mux alternative of the CAN signals (Teensy schematics and
/// the K20/K66 "Signal Multiplexing" tables: CAN0_TX/CAN0_RX and CAN1_TX/CAN1_RX are
/// ALT2 on every pin listed).
pub mod pins {
    use super::port::Port;

    /// A CAN signal on a Teensy pin.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub struct CanPin {
        /// The Teensy (Arduino) pin number.
        pub teensy_pin: u8,
        /// The MCU port.
        pub port: Port,
        /// The pin number within the port (PCR index).
        pub pin: u8,
        /// The PORTx_PCRn\[MUX\] alternative selecting the CAN signal.
        pub alt: u32,
    }

    impl CanPin {
        /// Address of the pin's PORTx_PCRn register.
        pub const fn pcr(self) -> usize {
            self.port.pcr(self.pin)
        }
    }

    const fn alt2(teensy_pin: u8, port: Port, pin: u8) -> CanPin {
        CanPin {
            teensy_pin,
            port,
            pin,
            alt: 2,
        }
    }

    /// Teensy 3.1/3.2 CAN0_TX default: pin 3 = PTA12 ALT2.
    pub const TEENSY31_CAN0_TX: CanPin = alt2(3, Port::A, 12);
    /// Teensy 3.1/3.2 CAN0_RX default: pin 4 = PTA13 ALT2.
    pub const TEENSY31_CAN0_RX: CanPin = alt2(4, Port::A, 13);
    /// Teensy 3.1/3.2 CAN0_TX alternate: pin 32 = PTB18 ALT2.
    pub const TEENSY31_CAN0_TX_ALT: CanPin = alt2(32, Port::B, 18);
    /// Teensy 3.1/3.2 CAN0_RX alternate: pin 25 = PTB19 ALT2.
    pub const TEENSY31_CAN0_RX_ALT: CanPin = alt2(25, Port::B, 19);

    /// Teensy 3.5/3.6 CAN0_TX default: pin 3 = PTA12 ALT2.
    pub const TEENSY35_CAN0_TX: CanPin = alt2(3, Port::A, 12);
    /// Teensy 3.5/3.6 CAN0_RX default: pin 4 = PTA13 ALT2.
    pub const TEENSY35_CAN0_RX: CanPin = alt2(4, Port::A, 13);
    /// Teensy 3.5/3.6 CAN0_TX alternate: pin 29 = PTB18 ALT2.
    pub const TEENSY35_CAN0_TX_ALT: CanPin = alt2(29, Port::B, 18);
    /// Teensy 3.5/3.6 CAN0_RX alternate: pin 30 = PTB19 ALT2.
    pub const TEENSY35_CAN0_RX_ALT: CanPin = alt2(30, Port::B, 19);

    /// Teensy 3.6 CAN1_TX: pin 33 = PTE24 ALT2 (no alternate pin is broken out).
    pub const TEENSY36_CAN1_TX: CanPin = alt2(33, Port::E, 24);
    /// Teensy 3.6 CAN1_RX: pin 34 = PTE25 ALT2 (no alternate pin is broken out).
    pub const TEENSY36_CAN1_RX: CanPin = alt2(34, Port::E, 25);
}
