//! What differs between the FlexCAN modules the model covers, as data: one [`Variant`]
//! per chip (and, on the i.MX RT1062, per instance), read by the rest of the model. A new
//! part of a supported family is a new table entry, not a copy of the model.
//!
//! Sources:
//! - Kinetis: K20P64M72SF1RM, K64P144M120SF5RM, K66P144M180SF5RMV2, chapter "FlexCAN"
//!   (16 message buffers, MCR reset 0xD890_000F: Disable mode).
//! - i.MX RT1062: IMXRT1060RM, chapter "Flexible Controller Area Network (FLEXCAN)"
//!   (CAN1, CAN2) and the CAN FD capable CAN3 (same chapter layout plus `CBT`, `FDCTRL`,
//!   `FDCBT`, `FDCRC`): 64 message buffers (section "Message buffer structure"), MCR reset
//!   0x5980_000F (the module leaves reset enabled, in Freeze mode), IMASK2/IFLAG2 for
//!   MB32–MB63, RXIMR0–63, `RFFN` up to 0xF (table "Rx FIFO filter: possible
//!   structures"), `DBG1`/`DBG2`/`GFWR` on CAN1/CAN2 only, `CTRL1[CLKSRC]` on CAN3 only.
//!   Reset values and offsets cross-checked with the `imxrt-ral` register blocks
//!   (`flexcan/tests/model_imxrt_ral.rs`) and the NXP MCUXpresso `MIMXRT1062_features.h`
//!   feature list (errata, per-instance features).

/// A FlexCAN erratum that concerns the module's behaviour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Erratum {
    /// e5829: "FlexCAN does not transmit a message that is enabled to be transmitted in a
    /// specific moment during the arbitration process". Work-around: keep the first
    /// mailbox after the Rx FIFO area inactive (reserved) and never use it, and write
    /// INACTIVE into it twice after each transmit activation (the driver's RT1062 layout
    /// does, `Layout::E5829`). The model does not reproduce the erratum.
    E5829,
    /// e6032: "A frame with wrong ID or payload is transmitted into the CAN bus when the
    /// Message Buffer under transmission is either aborted or deactivated while the CAN
    /// bus is in the Bus Idle state". Work-around: abort or deactivate only with the
    /// procedure of the erratum sheet.
    E6032,
    /// e9595: "Corrupt frame possible if the Freeze Mode or the Low-Power Mode are entered
    /// during a Bus-Off state". Work-around: do not request Freeze or Disable mode while
    /// `ESR1[FLTCONF]` reads bus-off.
    E9595,
}

/// Registers a module has beyond the set every variant has (MCR, CTRL1, TIMER,
/// RXMGMASK, RX14MASK, RX15MASK, ECR, ESR1, IMASK1, IFLAG1, CTRL2, ESR2, CRCR, RXFGMASK,
/// RXFIR, the message buffers and their RXIMR).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Extras {
    /// `DBG1` (0x58) and `DBG2` (0x5C), read-only debug registers (RT1062 CAN1/CAN2).
    pub debug: bool,
    /// `GFWR` (0x9E0), the wake-up glitch filter width (RT1062 CAN1/CAN2).
    pub gfwr: bool,
    /// `CBT` (0x50), the extended bit timing register (RT1062 CAN3).
    pub cbt: bool,
    /// `FDCTRL` (0xC00), `FDCBT` (0xC04), `FDCRC` (0xC08) and `MCR[FDEN]` (RT1062 CAN3).
    /// The model is classic CAN only: they read their reset values and `FDEN` stays 0.
    pub can_fd: bool,
}

/// One FlexCAN module's differences, as the model reads them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Variant {
    /// Name in reports (`MK66FX1M0 FlexCAN`, `i.MX RT1062 CAN3`).
    pub name: &'static str,
    /// Number of message buffers: 16 (Kinetis) or 64 (RT1062).
    pub message_buffers: usize,
    /// `MCR` out of reset (status bits included).
    pub reset_mcr: u32,
    /// `CTRL2` out of reset.
    pub reset_ctrl2: u32,
    /// `RXMGMASK`, `RX14MASK`, `RX15MASK` and `RXFGMASK` out of reset.
    pub reset_masks: u32,
    /// `MCR[WAKSRC]` (wake-up glitch filter) is implemented.
    pub waksrc: bool,
    /// `CTRL1[CLKSRC]` (engine clock selection) is implemented; where it is not, the bit
    /// reads 0 and the engine clock is the chip's CAN clock root.
    pub clksrc: bool,
    /// Registers this module has beyond the common set.
    pub extras: Extras,
    /// Errata of this module's silicon that a driver must work around (data only: the
    /// model does not reproduce them). The Kinetis entries list none; they have not been
    /// checked against the Kinetis errata sheets.
    pub errata: &'static [Erratum],
}

/// `MCR` out of reset on the Kinetis parts: MDIS, FRZ, HALT, NOTRDY, SUPV, LPMACK,
/// MAXMB = 0xF (Disable mode).
const KINETIS_RESET_MCR: u32 = 0xD890_000F;
/// `MCR` out of reset on the RT1062: FRZ, HALT, NOTRDY, FRZACK, SUPV, MAXMB = 0xF
/// (enabled, in Freeze mode; IMXRT1060RM "Module Configuration Register (MCR)").
const RT1062_RESET_MCR: u32 = 0x5980_000F;

const KINETIS_EXTRAS: Extras = Extras {
    debug: false,
    gfwr: false,
    cbt: false,
    can_fd: false,
};

/// FlexCAN0 of the MK20DX256 (Teensy 3.1/3.2). `MCR[WAKSRC]` is not implemented on it.
pub const MK20DX256: Variant = Variant {
    name: "MK20DX256 FlexCAN",
    message_buffers: 16,
    reset_mcr: KINETIS_RESET_MCR,
    reset_ctrl2: crate::regs::ctrl2::RESET,
    reset_masks: u32::MAX,
    waksrc: false,
    clksrc: true,
    extras: KINETIS_EXTRAS,
    errata: &[],
};

/// FlexCAN0 of the MK64FX512 (Teensy 3.5).
pub const MK64FX512: Variant = Variant {
    name: "MK64FX512 FlexCAN",
    waksrc: true,
    ..MK20DX256
};

/// FlexCAN0 and FlexCAN1 of the MK66FX1M0 (Teensy 3.6).
pub const MK66FX1M0: Variant = Variant {
    name: "MK66FX1M0 FlexCAN",
    waksrc: true,
    ..MK20DX256
};

/// Errata of the RT1062's FlexCAN modules, as NXP's `MIMXRT1062_features.h` flags them
/// ("is affected by errata": 5829, 6032 and 9595, not 5641; the errata sheet IMXRT1060CE
/// itself not checked).
const RT1062_ERRATA: &[Erratum] = &[Erratum::E5829, Erratum::E6032, Erratum::E9595];

/// CAN1 and CAN2 of the i.MX RT1062 (Teensy 4.0/4.1): 64 message buffers, classic CAN,
/// no engine clock selection (the CAN clock root feeds the protocol engine).
pub const IMXRT1062_CAN1: Variant = Variant {
    name: "i.MX RT1062 CAN1",
    message_buffers: 64,
    reset_mcr: RT1062_RESET_MCR,
    reset_ctrl2: 0,
    reset_masks: u32::MAX,
    waksrc: true,
    clksrc: false,
    extras: Extras {
        debug: true,
        gfwr: true,
        cbt: false,
        can_fd: false,
    },
    errata: RT1062_ERRATA,
};

/// CAN2 of the i.MX RT1062: as CAN1.
pub const IMXRT1062_CAN2: Variant = Variant {
    name: "i.MX RT1062 CAN2",
    ..IMXRT1062_CAN1
};

/// CAN3 of the i.MX RT1062: the CAN FD capable module, modelled in classic CAN. It has
/// `CBT`, the FD registers and `CTRL1[CLKSRC]`; its masks and `CTRL2` reset differently
/// (masks 0, `CTRL2[TASD]` = 0x10).
pub const IMXRT1062_CAN3: Variant = Variant {
    name: "i.MX RT1062 CAN3",
    message_buffers: 64,
    reset_mcr: RT1062_RESET_MCR,
    reset_ctrl2: 0x0080_0000,
    reset_masks: 0,
    waksrc: true,
    clksrc: true,
    extras: Extras {
        debug: false,
        gfwr: false,
        cbt: true,
        can_fd: true,
    },
    errata: RT1062_ERRATA,
};

/// `FDCTRL` out of reset on CAN3 (`FDRATE` = 1, `TDCOFF` = 1).
pub const FDCTRL_RESET: u32 = 0x8000_0100;
/// `GFWR` out of reset on CAN1/CAN2.
pub const GFWR_RESET: u32 = 0x7F;
/// `DBG1` out of reset on CAN1/CAN2.
pub const DBG1_RESET: u32 = 0x0001_0000;

/// The Rx FIFO and its ID filter table, per `CTRL2[RFFN]` (table "Rx FIFO filter:
/// possible structures", the same rule on both families).
impl Variant {
    /// Filter table elements: 8 × (RFFN + 1).
    pub const fn rx_fifo_filters(rffn: u32) -> usize {
        8 * (rffn as usize + 1)
    }

    /// Message buffers the FIFO engine (MB0–MB5) and its table occupy: 6 + 2 × (RFFN + 1)
    /// (each message buffer holds four table elements).
    pub const fn rx_fifo_occupied_mbs(rffn: u32) -> usize {
        6 + 2 * (rffn as usize + 1)
    }

    /// The largest `RFFN` whose FIFO and table fit in this module's message buffers
    /// (4 with 16, 15 with 64). Larger values are stored; the elements beyond the RAM
    /// never match and no mailbox is left.
    pub const fn max_rffn(&self) -> u32 {
        let mut r = 15;
        while r > 0 && Self::rx_fifo_occupied_mbs(r) > self.message_buffers {
            r -= 1;
        }
        r
    }

    /// Leading table elements masked by the individual masks (`RXIMR[n]`, or `RXMGMASK`
    /// with `MCR[IRMQ]` = 0); the rest use `RXFGMASK`. The table gives "elements 0 to
    /// (occupied − 1)" and never more than 32 (RFFN ≥ 0xC: "elements 0–31").
    pub fn rx_fifo_individually_masked(&self, rffn: u32) -> usize {
        Self::rx_fifo_occupied_mbs(rffn)
            .min(self.message_buffers)
            .min(32)
            .min(Self::rx_fifo_filters(rffn))
    }

    /// `IMASK1`/`IFLAG1` bits that exist (MB0–MB31 or fewer).
    pub const fn flags1_implemented(&self) -> u32 {
        if self.message_buffers >= 32 {
            u32::MAX
        } else {
            (1u32 << self.message_buffers) - 1
        }
    }

    /// `IMASK2`/`IFLAG2` bits that exist (MB32–MB63); 0 where the registers are absent.
    pub const fn flags2_implemented(&self) -> u32 {
        if self.message_buffers <= 32 {
            0
        } else if self.message_buffers >= 64 {
            u32::MAX
        } else {
            (1u32 << (self.message_buffers - 32)) - 1
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fifo_table_matches_the_manual_table() {
        // (RFFN, filters, last occupied MB, last individually masked element)
        let rows = [
            (0, 8, 7, 7),
            (1, 16, 9, 9),
            (3, 32, 13, 13),
            (7, 64, 21, 21),
            (0xB, 96, 29, 29),
            (0xC, 104, 31, 31),
            (0xD, 112, 33, 31),
            (0xF, 128, 37, 31),
        ];
        for (rffn, filters, last_mb, last_masked) in rows {
            assert_eq!(Variant::rx_fifo_filters(rffn), filters);
            assert_eq!(Variant::rx_fifo_occupied_mbs(rffn), last_mb + 1);
            assert_eq!(
                IMXRT1062_CAN1.rx_fifo_individually_masked(rffn),
                last_masked + 1
            );
        }
        assert_eq!(MK66FX1M0.max_rffn(), 4);
        assert_eq!(IMXRT1062_CAN3.max_rffn(), 15);
        assert_eq!(MK20DX256.rx_fifo_individually_masked(3), 14);
        assert_eq!(MK20DX256.flags1_implemented(), 0xFFFF);
        assert_eq!(MK20DX256.flags2_implemented(), 0);
        assert_eq!(IMXRT1062_CAN2.flags2_implemented(), u32::MAX);
    }
}
