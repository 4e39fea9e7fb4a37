//! bxCAN backend of `twocan` for the STM32F7 (RM0410 chapter 40): configuration,
//! filter banks and an automatic filter planner, and the [`twocan_core::Hardware`]
//! implementation ([`BxCan`]) behind the portable split driver of
//! [`twocan_core::split`] and the one-struct [`twocan_core::Driver`].
//!
//! Quick start on the host, over the behavioural model of CAN1 (feature `model`) in
//! loop-back mode; firmware runs the same code over [`regs::CanRegs`]:
//!
//! ```
//! # #[cfg(feature = "model")] {
//! use twocan_bxcan::model::BxCanModel;
//! use twocan_bxcan::{BxCan, Can, Config, FifoPolicy};
//! use twocan_core::split::State;
//! use twocan_core::{FifoQueue, Filter, Frame, TxOutcome};
//!
//! // The state the halves share: a `static` in firmware (zero-initialised, `.bss`);
//! // here a local, as the model's handle is not `Sync`.
//! let state: State<BxCan<PollClock<BxCanModel>>, 16, FifoQueue<8>, 16> = State::new();
//!
//! use std::{cell::RefCell, rc::Rc};
//! use twocan_core::sim::{Bus, PollClock};
//!
//! let model = BxCanModel::can1();
//! let bus = Rc::new(RefCell::new(Bus::new(500_000).unwrap()));
//! bus.borrow_mut().attach("can1", model.clone());
//! // Bus time passes while the driver polls CAN_MSR for an acknowledge.
//! let regs = PollClock::new(model.clone(), &bus, twocan_bxcan::regs::MSR);
//! let config = Config::from_bitrate(54_000_000, 500_000).unwrap().loopback(true);
//! let mut init = Can::can1(regs, &config).map_err(|f| f.error).unwrap();
//! let plan = init.can().plan(&[Filter::standard(0x123)], FifoPolicy::Fifo0).unwrap();
//! init.set_filters(&plan).unwrap();
//! let can = init.enable().map_err(|f| f.error).unwrap(); // on the bus
//!
//! let mut parts = state.split(can.into_split()).ok().unwrap();
//! let token = parts.tx.try_send(&Frame::standard(0x123, &[1, 2, 3]).unwrap()).unwrap();
//! bus.borrow_mut().run_for(200); // the frame goes round the loop-back
//! // The interrupt lines' handlers (TX, RX0) — in firmware, the vectors run them.
//! parts.tx_irq.on_interrupt();
//! parts.rx0_irq.on_interrupt();
//! let rx = parts.rx.receive().unwrap();
//! assert_eq!((rx.frame.raw_id(), rx.filter), (0x123, 0)); // the user's filter index
//! let done = parts.tx.take_completion().unwrap();
//! assert_eq!((done.token, done.outcome), (token, TxOutcome::Sent));
//! # }
//! ```
//!
//! In firmware the register handle is [`regs::CanRegs`] (a [`twocan_core::Mmio`] window
//! over the instance's block: safe code reaches no other address) at its base, the
//! state a `static`, and the handlers go to the TX, RX0, RX1 and SCE vectors before those
//! are unmasked (see `examples/stm32f7/src/can.rs`):
//!
//! ```no_run
//! use twocan_bxcan::regs::{self, CanRegs};
//! use twocan_bxcan::{BxCan, Can, Config, FifoPolicy, Recovery};
//! use twocan_core::split::State;
//! use twocan_core::{FifoQueue, Filter};
//!
//! static CAN1: State<BxCan<CanRegs>, 32, FifoQueue<16>, 32> = State::new();
//!
//! fn start() -> Result<(), twocan_core::Error> {
//!     // Firmware first: RCC_APB1ENR.CAN1EN = 1, PD0/PD1 in AF9 (see `instance`).
//!     // SAFETY: CAN1's registers, clocked, used by nothing else.
//!     let regs = unsafe { CanRegs::new(regs::CAN1_BASE) };
//!     let config = Config::from_bitrate(54_000_000, 500_000)
//!         .map_err(|_| twocan_core::Error::InvalidArgument)?
//!         .recovery(Recovery::Automatic);
//!     let mut init = Can::can1(regs, &config)?; // initialization mode, #[must_use]
//!     let filters = [Filter::standard(0x100), Filter::extended(0x1234_5678)];
//!     let plan = init.can().plan(&filters, FifoPolicy::Fifo0)?;
//!     init.set_filters(&plan)?;
//!     let can = init.enable()?; // on the bus (bounded wait on INAK)
//!     let parts = CAN1.split(can.into_split()).map_err(|(e, _)| e)?;
//!     // Move parts.tx_irq / rx0_irq / rx1_irq / status_irq to the four vectors, then
//!     // unmask them; parts.tx and parts.rx belong to thread code or tasks.
//!     # let _ = parts;
//!     Ok(())
//! }
//! ```
//!
//! Modules:
//! - [`config`]: the builder ([`Config`]): bit timing (solver or raw `CAN_BTR`), loop-back
//!   and silent, TXFP, NART, ABOM, RFLM, TTCM, AWUM, DBF, interrupts, CAN2 start bank;
//! - [`controller`]: [`Can`] (`can1`/`can2`/`can3` → [`Init`] → `enable` → [`Can`]);
//! - [`split`]: [`BxCan`] (`Can::into_split`), the [`twocan_core::Hardware`]
//!   implementation: who touches which register from which context;
//! - [`filters`]: banks ([`Bank`]), direct configuration, match-index numbering, the
//!   compiled [`FilterPlan`]; [`planner`]: portable filters → fewest banks, exactly;
//! - [`instance`]: CAN1/CAN2/CAN3 and what the firmware must do (RCC, AF9);
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

#[cfg(feature = "model")]
pub mod model;

pub mod config;
pub mod controller;
mod error;
pub mod filter_block;
pub mod filters;
pub mod instance;
mod mailbox;
mod mode;
pub mod planner;
// Interrupt-shared state: the `Hardware` contract and the per-mailbox frame cell.
#[allow(unsafe_code)]
pub mod split;

pub use config::{Config, ConfigError, Recovery};
pub use controller::{Can, Failed, Init};
pub use filters::{Bank, BankError, BankKind, Fifo, FilterPlan, PlanError};
pub use instance::Instance;
pub use planner::{plan, plan_dual, DualPlan, FifoPolicy, PlanOptions};
pub use split::{BxCan, RawFrame};
