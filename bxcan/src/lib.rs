//! bxCAN backend of `twocan` for the STM32F7 (RM0410 chapter 40): configuration,
//! filter banks and an automatic filter planner, and the [`twocan_core::Hardware`]
//! implementation ([`BxCan`]) behind the portable split driver of
//! [`twocan_core::split`] and the one-struct [`twocan_core::Driver`].
//!
//! **Transmit order:** the hardware resets to identifier priority (`CAN_MCR.TXFP = 0`,
//! RM0410 §40.9.2); this driver's default is request order (FIFO, `TXFP = 1`), the same
//! portable order as the FlexCAN backend. Choose identifier priority with
//! [`Config::tx_policy`]`(`[`twocan_core::TxPolicy::Priority`]`)` and a
//! [`twocan_core::PriorityQueue`] as the software transmit queue.
//!
//! # Quick start
//!
//! On the host, over the behavioural model of CAN1 (feature `model`) in loop-back mode;
//! firmware runs the same code over the registers the HAL hand-over gives. The same
//! text is compiled and run by the workspace test `tests/tests/first_program.rs`:
//!
#![doc = concat!("```\n", include_str!("../doc/quick_start.rs"), "```")]
//!
//! In firmware, the `hal` module (feature `hal-stm32f7`) takes `stm32f7xx-hal`'s PAC singleton,
//! its `Clocks` and the pins in their CAN alternate function, and builds the register
//! handle ([`regs::CanRegs`], a [`twocan_core::Mmio`] window over the instance's block:
//! safe code reaches no other address) with no `unsafe` in the program; the state is a
//! `static`, and the handlers go to the TX, RX0, RX1 and SCE vectors before those are
//! unmasked: with feature `rt` the library defines those vectors and does it
//! (`rt::IrqState::start`, and `stop` for the way back; see
//! `examples/stm32f7/src/can.rs`). Compiled by the same test:
//!
#![cfg_attr(
    feature = "hal-stm32f7",
    doc = concat!("```no_run\n", include_str!("../doc/firmware_quick_start.rs"), "```")
)]
#![cfg_attr(
    not(feature = "hal-stm32f7"),
    doc = concat!("```ignore\n", include_str!("../doc/firmware_quick_start.rs"), "```")
)]
//!
//! Without the HAL, a register handle is built from the instance's base address with an
//! `unsafe` promise that nothing else reaches it: `unsafe { CanRegs::new(regs::CAN1_BASE) }`
//! (CAN1 and CAN2 sharing the filter block: [`regs::ControlRegs`] each, and one
//! [`regs::FilterRegs`] lent to both, see [`Can::can1_dual`]).
//!
//! Modules:
//! - [`config`]: the builder ([`Config`]): bit timing (solver or raw `CAN_BTR`), loop-back
//!   and silent, TXFP, NART, ABOM, RFLM, TTCM, AWUM, DBF, interrupts, CAN2 start bank;
//! - [`controller`]: [`Can`] (`can1`/`can2`/`can3` → [`Init`] → `enable` → [`Can`]);
//! - [`split`]: [`BxCan`] (`Can::into_split`), the [`twocan_core::Hardware`]
//!   implementation: who touches which register from which context;
//! - [`filters`]: banks ([`Bank`]), direct configuration, match-index numbering, the
//!   compiled [`FilterPlan`]; [`planner`]: portable filters → fewest banks, exactly;
//! - [`chip`]: the STM32 parts as data ([`Chip`]: instances, bank counts, APB1 limits,
//!   interrupt numbers, pins), chosen with [`Config::chip`];
//! - [`instance`]: CAN1/CAN2/CAN3 and what the firmware must do (RCC, AF9);
//! - `hal` (features `hal-stm32f7`, `hal-stm32f4`, `hal-stm32f1`): the hand-over from
//!   `stm32f7xx-hal`, `stm32f4xx-hal` or `stm32f1xx-hal` (singletons,
//!   clocks, typed pins; CAN2 only with CAN1's filter-block handle);
//! - `rt` (feature `rt`): the interrupt entry points `CAN1_TX` ... in the library, the
//!   handlers installed before the lines are unmasked, priorities applied, and the way
//!   back (`IrqState::start`, `IrqState::stop`);
//! - [`regs`]: the register map.
//!
//! # Critical sections
//!
//! Firmware must link one `critical-section` implementation: on the single-core
//! Cortex-M4/M7 of these boards, `cortex-m`'s `critical-section-single-core` feature
//! (otherwise linking fails on `_critical_section_1_0_acquire`); see
//! [`twocan_core`'s crate documentation](twocan_core#critical-sections).
#![cfg_attr(not(feature = "model"), no_std)]
// docs.rs (nightly rustdoc): mark feature-gated items with the feature they need.
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]
#![deny(unsafe_code)]

pub mod regs;

pub mod chip;

#[cfg(feature = "model")]
pub mod model;

pub mod config;
pub mod controller;
mod error;
pub mod filter_block;
pub mod filters;
pub mod fmi;
// The hand-over from an STM32 HAL: the one `unsafe` turning a consumed PAC singleton
// into a register window.
#[cfg(any(
    feature = "hal-stm32f7",
    feature = "hal-stm32f4",
    feature = "hal-stm32f1"
))]
#[allow(unsafe_code)]
pub mod hal;
pub mod instance;
mod mailbox;
mod mode;
pub mod planner;
// The library's interrupt entry points and their handler slots (feature `rt`): the
// `unsafe` of a slot written once and of the NVIC calls.
#[cfg(feature = "rt")]
#[cfg_attr(docsrs, doc(cfg(feature = "rt")))]
#[allow(unsafe_code)]
pub mod rt;
// Interrupt-shared state: the `Hardware` contract and the per-mailbox frame cell.
#[allow(unsafe_code)]
pub mod split;
pub mod types;

pub use chip::Chip;
pub use config::{Config, ConfigError, Recovery};
pub use controller::{Can, Failed, Init};
pub use filters::{Bank, BankError, BankKind, Fifo, FilterPlan, PlanError, PlanRef, SizedPlan};
pub use fmi::fmi;
pub use instance::Instance;
pub use planner::{plan, plan_dual, DualPlan, FifoPolicy, PlanOptions};
pub use split::{BxCan, RawFrame};
