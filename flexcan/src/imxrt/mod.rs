//! The i.MX RT1062 (Teensy 4.0 / 4.1) around its three FlexCAN modules: what `begin`
//! writes besides the module itself, as data (IMXRT1060RM, Rev. 3).
//!
//! - [`ccm`]: the CAN clock root (`CCM_CSCMR2[CAN_CLK_SEL, CAN_CLK_PODF]`, chapter "Clock
//!   Controller Module (CCM)") and the per-module clock gates (`CCM_CCGR0`, `CCM_CCGR7`);
//! - [`pads`]: the Teensy 4 pins of CAN1, CAN2 and CAN3 and their IOMUXC registers (mux,
//!   pad control, daisy-chain input selection; chapter "IOMUX Controller (IOMUXC)");
//! - [`plan`]: the register writes of `begin` and `end` for one module, computed before
//!   anything is written.
//!
//! The module bases and interrupt numbers are in [`crate::Instance`] and
//! [`crate::Chip`]; `tests/imxrt_facts.rs` checks every address here against the
//! `imxrt-ral` register blocks (NXP SVD).

pub mod ccm;
#[cfg(all(target_os = "none", any(feature = "teensy40", feature = "teensy41")))]
pub mod firmware;
pub mod pads;
pub mod plan;
#[cfg(all(feature = "imxrt-ral", any(feature = "teensy40", feature = "teensy41")))]
#[cfg_attr(
    docsrs,
    doc(cfg(all(feature = "imxrt-ral", any(feature = "teensy40", feature = "teensy41"))))
)]
pub mod ral;

pub use ccm::{CanClockSource, ClockRoot};
pub use pads::{ImxPin, ImxPins};
pub use plan::ImxrtPlan;

/// CAN1 base address (IMXRT1060RM, "System Memory Map": FLEXCAN1 0x401D_0000).
pub const CAN1_BASE: usize = 0x401D_0000;
/// CAN2 base address (FLEXCAN2 0x401D_4000).
pub const CAN2_BASE: usize = 0x401D_4000;
/// CAN3 base address (FLEXCAN3, CAN FD capable, 0x401D_8000).
pub const CAN3_BASE: usize = 0x401D_8000;

/// CAN1 at its compile-time address ([`CAN1_BASE`]), the RT1062 window
/// ([`crate::regs::IMXRT_BLOCK_END`]): the register type of a state begun from the
/// `Can1` token's fixed path (issue 21, [`crate::regs::FlexCanAt`]).
pub type Can1At = crate::regs::FlexCanAt<CAN1_BASE, { crate::regs::IMXRT_BLOCK_END }>;
/// CAN2 at its compile-time address ([`CAN2_BASE`]), the RT1062 window.
pub type Can2At = crate::regs::FlexCanAt<CAN2_BASE, { crate::regs::IMXRT_BLOCK_END }>;
/// CAN3 at its compile-time address ([`CAN3_BASE`]), the RT1062 window.
pub type Can3At = crate::regs::FlexCanAt<CAN3_BASE, { crate::regs::IMXRT_BLOCK_END }>;

/// Interrupt numbers (IMXRT1060RM, "ARM Cortex M7 domain interrupt summary"): one line per
/// module carries every FlexCAN source (message buffers, bus-off, error, warnings,
/// wake-up).
pub const CAN1_IRQ: u16 = 36;
/// CAN2's interrupt number.
pub const CAN2_IRQ: u16 = 37;
/// CAN3's interrupt number.
pub const CAN3_IRQ: u16 = 154;

/// Number of message buffers of each RT1062 FlexCAN module (IMXRT1060RM, FlexCAN
/// "Message buffer structure": 64 MBs; `IMASK2`/`IFLAG2` cover MB32–MB63).
pub const MESSAGE_BUFFERS: usize = 64;
