//! FlexCAN backend of twocan: the ACAN driver's feature set for Teensy 3.1/3.2, 3.5 and
//! 3.6 (ACAN 1.0.5 manual, Pierre Molinaro), in Rust over twocan-core's
//! [`Hardware`](twocan_core::Hardware) seam: [`FlexCan::begin`] configures the module,
//! [`FlexCan::into_split`] hands it to the portable driver — the split halves and
//! interrupt handlers of [`twocan_core::split`] in firmware, or the one-struct
//! [`twocan_core::Driver`] for polling code.
//!
//! An ACAN sketch's `begin` is one call here too (features `rt` and a board feature,
//! target `thumbv7em-none-eabihf`; module `acan`): it takes the module, begins with
//! ACAN's defaults on the board's default pins, puts the driver in the library's
//! `static` state, wires the interrupts and returns the transmit and receive halves.
//! The five steps it runs stay available (see below and `rt`).
//!
#![cfg_attr(
    all(
        feature = "rt",
        any(feature = "teensy32", feature = "teensy35", feature = "teensy36")
    ),
    doc = concat!("```no_run\n", include_str!("../doc/one_call.rs"), "```")
)]
#![cfg_attr(
    not(all(
        feature = "rt",
        any(feature = "teensy32", feature = "teensy35", feature = "teensy36")
    )),
    doc = concat!("```ignore\n", include_str!("../doc/one_call.rs"), "```")
)]
//!
//! ACAN §4's LoopBackDemo, on the host over the behavioural model of the module
//! (feature `model`) and twocan-sim's simulated bus:
//!
#![doc = concat!("```\n", include_str!("../doc/quick_start.rs"), "```")]
//!
//! On a Teensy (feature `teensy32`, `teensy35` or `teensy36`, target
//! `thumbv7em-none-eabihf`), the singleton token gives the controller, typed pins
//! choose its pins (module `pin`), and with feature `rt` the library wires the interrupts
//! as ACAN's `begin` does (`rt::IrqState::start`: handlers installed behind the
//! exported `CAN0_*` entry points, then the lines unmasked at `mMessageIRQPriority`):
//!
//! ```ignore
//! use twocan_flexcan::pin::{Pin3, Pin4};
//! use twocan_flexcan::rt::AcanState;
//! use twocan_flexcan::{Can0, Settings};
//! static CAN0: AcanState = AcanState::new();
//! let settings = Settings::new(500_000);
//! let controller = Can0::take().unwrap().begin_on(Pin3, Pin4, &settings, &[], &[])
//!     .map_err(|(_, e)| e)?;
//! let (mut tx, mut rx) = CAN0.start(controller.into_split(), &mut core.NVIC)
//!     .map_err(|(e, _)| e)?;
//! // The application's vector table names `CAN0_ORED_MESSAGE_BUFFER` ... (see `rt`).
//! ```
//!
//! Without `rt`, [`twocan_core::split::State::split`] gives the interrupt handlers to
//! run from the application's own vectors (RTIC tasks, for instance). An un-split
//! controller is stopped with [`FlexCan::end`] (`Can0::end` on the target gives the
//! token back).
//!
//! # Board features
//!
//! Exactly one of `teensy32` (Teensy 3.1 / 3.2), `teensy35` or `teensy36` should be
//! enabled for firmware: it selects `Board::DEFAULT`, the board of `Can0::take()`
//! (its pins, SIM gates and chip), and `teensy36` alone also provides `Can1`.
//! Conflicting board features are **not** an error (so that `cargo clippy
//! --all-features` and feature unification across a workspace keep building); the
//! precedence is fixed and silent:
//!
//! | features enabled | `Board::DEFAULT` | `Can1` |
//! |---|---|---|
//! | `teensy41` (with or without the others) | `Teensy41` | yes (and `Can2`, `Can3`; no `Can0`) |
//! | `teensy40`, not `teensy41` | `Teensy40` | yes (and `Can2`, `Can3`; no `Can0`) |
//! | `teensy36`, no Teensy 4 feature | `Teensy36` | yes |
//! | `teensy35`, maybe `teensy32`, not `teensy36` | `Teensy35` | no |
//! | `teensy32` alone | `Teensy32` | no |
//!
//! On a Teensy 4.x (i.MX RT1062, [`imxrt`]) the tokens are `Can1`, `Can2`, `Can3` (CAN1 on
//! pins 22/23, CAN2 on 1/0, CAN3 on 31/30), the settings name the CCM clock root
//! (`Settings::with_clock(rate, CanClock::IMXRT_24MHZ)`), and with `rt` the entry points
//! are `CAN1`, `CAN2`, `CAN3` (`rt_imxrt`), one line per module. The message-buffer
//! layout is a type parameter ([`layout`]): [`layout::Kinetis`], the generic default,
//! keeps ACAN's four configurations in MB0–MB15 on both families; [`layout::Imxrt1062`]
//! takes the RT1062's Rx FIFO tables up to 128 elements (32 primary and 96 secondary
//! filters, [`FlexCan::begin_with_layout`], [`LargeFilterTable`]) and works around the
//! chip's erratum ERR005829 ([`layout::Layout::E5829`]), at no cost to a Teensy 3.x
//! firmware. The Teensy 4 paths use [`layout::Imxrt1062`] without being asked
//! ([`layout::BoardLayout`]): the one calls `acan::can1`..`can3`, `Can1::begin` (a
//! `FlexCan<FlexCanRegs, Imxrt1062>`), `begin_on`, the `imxrt-ral` hand-over and
//! `rt::AcanState`; a state for the in-place forms names it, e.g.
//! `rt::IrqState<FlexCanRegs, 32, FifoQueue<16>, 8, options::FullInSlot<Imxrt1062>>` with a
//! `TableSlot::<LargeFilterTable>::new_sized()` and a `BeginPlan::<Imxrt1062>`.
//!
//! So `teensy32` + `teensy36` builds for a Teensy 3.6: firmware for a Teensy 3.2 linked
//! that way would drive the wrong pins. Check `Board::DEFAULT` (or `cargo tree -e
//! features -i twocan-flexcan`) when another crate of the build may enable a board
//! feature. The host build (no board feature) has no `Board::DEFAULT`; pass a
//! [`Target`] to [`FlexCan::begin`] instead.
//!
//! # Map of the ACAN manual
//!
//! | ACAN | here |
//! |---|---|
//! | §4 `ACANSettings`, §16, table 7 | [`Settings`] (bit timing from [`twocan_core::timing`]) |
//! | §6 `ACAN::can0`, `ACAN::can1` | `Can0::take()`, `Can1::take()` ([`instance`]); [`Target`] on the host |
//! | §7 alternate pins, §16.7.5–6 | [`Settings`] fields, [`Board::pins`], [`system`]; typed: `pin` (board features) |
//! | `ACAN::can0.begin (settings)` as one call | `acan::can0` / `acan::can0_with` (features `rt` + board); ACAN_T4 `ACAN_T4::can1.begin`: `acan::can1`..`can3` |
//! | §15 `begin` wiring the interrupt, §16.7.4 `mMessageIRQPriority` | `rt::IrqState::start` (feature `rt`) |
//! | `end` | `acan::end_can0` (`end_can1`..`end_can3` on the Teensy 4.x); [`FlexCan::end`], `Can0::end` / `Can1::end` ([`end`]); `rt::IrqState::stop` |
//! | §8, §9 `tryToSend`, transmit buffer | [`twocan_core::Driver::try_send`], `tx_stats` ([`controller`] explains the mailboxes) |
//! | §10 `receive`, receive buffer | [`twocan_core::Driver::receive`], `rx_stats` |
//! | §11 `mConfiguration` | [`Configuration`] |
//! | §12, §13 primary / secondary filters | [`twocan_core::Filter`] lists, compiled by [`FilterTable`] |
//! | §14 `dispatchReceivedMessage` | [`twocan_core::Driver::dispatch`] with a [`twocan_core::Dispatcher`] |
//! | §15 `begin`, table 5 | [`FlexCan::begin`], [`check`], [`ConfigErrors`], [`BeginError`] |
//! | §17 controller state, REC, TEC | [`twocan_core::Driver::state`], `counters` |
//!
//! # Critical sections
//!
//! Firmware must link one `critical-section` implementation: on the single-core
//! Cortex-M4/M7 of these boards, `cortex-m`'s `critical-section-single-core` feature
//! (otherwise linking fails on `_critical_section_1_0_acquire`); see
//! [`twocan_core`'s crate documentation](twocan_core#critical-sections).
#![cfg_attr(not(any(test, feature = "model")), no_std)]
// docs.rs (nightly rustdoc): mark feature-gated items with the feature they need.
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]

// The one call per module (ACAN's and ACAN_T4's `begin`/`end`): take, begin, state,
// interrupts; `can0`/`can1` on the Teensy 3.x, `can1`..`can3` on the Teensy 4.x.
#[cfg(all(
    feature = "rt",
    any(
        feature = "teensy32",
        feature = "teensy35",
        feature = "teensy36",
        feature = "teensy40",
        feature = "teensy41"
    )
))]
#[cfg_attr(docsrs, doc(cfg(feature = "rt")))]
pub mod acan;
pub mod begin;
pub mod begin_error;
pub mod board;
pub mod can_clock;
pub mod configuration;
pub mod controller;
pub mod end;
pub mod filters;
mod handshake;
pub mod imxrt;
pub mod installed;
pub mod instance;
pub mod layout;
mod message_buffer;
pub mod options;
#[cfg(all(
    any(feature = "teensy32", feature = "teensy35", feature = "teensy36"),
    not(any(feature = "teensy40", feature = "teensy41"))
))]
pub mod pin;
#[cfg(any(feature = "teensy40", feature = "teensy41"))]
#[path = "imxrt/pin.rs"]
pub mod pin;
pub mod planner;
pub mod settings;
pub mod split;
mod status;
pub mod system;
#[allow(unused_macros, unused_imports)]
mod token_begin;
pub mod types;

pub mod regs;
#[cfg(feature = "rt")]
#[cfg_attr(docsrs, doc(cfg(feature = "rt")))]
pub mod rt;

#[cfg(all(feature = "rt", any(feature = "teensy40", feature = "teensy41")))]
#[cfg_attr(
    docsrs,
    doc(cfg(all(feature = "rt", any(feature = "teensy40", feature = "teensy41"))))
)]
pub mod rt_imxrt;

#[cfg(feature = "model")]
pub mod model;

#[cfg(feature = "model")]
mod idle_clock;
#[cfg(feature = "model")]
pub use idle_clock::IdleClocked;

pub use begin::{check, BeginPlan};
pub use begin_error::{BeginError, ConfigErrors};
pub use board::{Board, Chip, InstancePins};
pub use can_clock::CanClock;
pub use configuration::Configuration;
pub use controller::FlexCan;
pub use filters::{FilterTable, SizedTable, UNKNOWN_FILTER};
#[cfg(all(
    any(feature = "teensy32", feature = "teensy35", feature = "teensy36"),
    not(any(feature = "teensy40", feature = "teensy41"))
))]
pub use instance::Can0;
#[cfg(any(feature = "teensy36", feature = "teensy40", feature = "teensy41"))]
pub use instance::Can1;
#[cfg(any(
    feature = "teensy32",
    feature = "teensy35",
    feature = "teensy36",
    feature = "teensy40",
    feature = "teensy41"
))]
pub use instance::TokenRegisters;
#[cfg(any(feature = "teensy40", feature = "teensy41"))]
pub use instance::{Can2, Can3};
pub use instance::{Instance, Irqs, Target};
pub use layout::LargeFilterTable;
pub use settings::{Settings, CAN_CLOCK_HZ, RECEIVE_BUFFER_SIZE, TRANSMIT_BUFFER_SIZE};
pub use split::{FlexCanHw, InstalledFilters};
pub use system::HostSystem;
pub use system::{PortPlan, SystemPlan};

/// The driver with ACAN's default buffer sizes: a receive ring of 32 frames and a
/// transmit ring of 16 (ACAN table 7, §8.2, §10.1). Choose other sizes with
/// `twocan_core::Driver<FlexCanHw<R>, RX, TX>`.
pub type AcanDriver<R> =
    twocan_core::Driver<FlexCanHw<R>, RECEIVE_BUFFER_SIZE, TRANSMIT_BUFFER_SIZE>;
