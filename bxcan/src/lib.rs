//! bxCAN backend of `twocan` for the STM32F7 (RM0410 chapter 40): configuration,
//! filter banks and an automatic filter planner, and the [`twocan_core::Controller`]
//! implementation behind the portable [`twocan_core::Driver`].
//!
//! ```no_run
//! use twocan_bxcan::{regs, Can, Config, FifoPolicy, Recovery};
//! use twocan_core::{Driver, Filter, Mmio, TxPolicy};
//!
//! fn start() -> Result<(), twocan_core::Error> {
//!     // Firmware first: RCC_APB1ENR.CAN1EN = 1, PD0/PD1 in AF9 (see `instance`).
//!     // SAFETY: CAN1's registers, clocked, used by nothing else.
//!     let regs = unsafe { Mmio::new(regs::CAN1_BASE) };
//!     let config = Config::from_bitrate(54_000_000, 500_000)
//!         .map_err(|_| twocan_core::Error::InvalidArgument)?
//!         .tx_policy(TxPolicy::Priority)
//!         .recovery(Recovery::Automatic);
//!     let mut init = Can::can1(regs, &config)?; // initialization mode, #[must_use]
//!     let filters = [Filter::standard(0x100), Filter::standard(0x101), Filter::extended(0x1234_5678)];
//!     let plan = init.can().plan(&filters, FifoPolicy::Fifo0)?;
//!     init.set_filters(&plan)?;
//!     let can = init.enable()?; // on the bus (bounded wait on INAK)
//!     let mut driver: Driver<_, 32, 16> = Driver::new(can);
//!     driver.try_send(&twocan_core::Frame::standard(0x200, &[1, 2, 3]).unwrap()).ok();
//!     Ok(())
//! }
//! ```
//!
//! On the host the same code runs over the behavioural model (feature `model`) instead
//! of [`twocan_core::Mmio`]; see `tests/driver_*.rs`.
//!
//! Modules:
//! - [`config`]: the builder ([`Config`]): bit timing (solver or raw `CAN_BTR`), loop-back
//!   and silent, TXFP, NART, ABOM, RFLM, TTCM, AWUM, DBF, interrupts, CAN2 start bank;
//! - [`controller`]: [`Can`] (`can1`/`can2`/`can3` → [`Init`] → `enable` → [`Can`]) and
//!   the [`twocan_core::Controller`] implementation;
//! - [`filters`]: banks ([`Bank`]), direct configuration, match-index numbering, the
//!   compiled [`FilterPlan`]; [`planner`]: portable filters → fewest banks, exactly;
//! - [`instance`]: CAN1/CAN2/CAN3 and what the firmware must do (RCC, AF9);
//! - [`regs`]: the register map.
#![cfg_attr(not(feature = "model"), no_std)]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod regs;

#[cfg(feature = "model")]
pub mod model;

pub mod config;
pub mod controller;
pub mod filter_block;
pub mod filters;
pub mod instance;
mod mailbox;
mod mode;
pub mod planner;

pub use config::{Config, ConfigError, Recovery};
pub use controller::{Can, Failed, Init};
pub use filters::{Bank, BankError, BankKind, Fifo, FilterPlan, PlanError};
pub use instance::Instance;
pub use planner::{plan, plan_dual, DualPlan, FifoPolicy, PlanOptions};
