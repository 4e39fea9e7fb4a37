//! Shared support for the workspace integration tests.
//!
//! - [`app_bus`]: the portable application on a FlexCAN and a bxCAN node on one bus;
//! - [`backend`]: one trait ([`backend::Backend`], [`backend::Dut`]) over a FlexCAN node
//!   and a bxCAN node of the host harness, so that the cross-controller suites are written
//!   once and run on both controllers;
//! - [`preempt`]: the transmit interrupt (and the others) preempting the thread at every
//!   register access of `try_send` and `abort`, on both controllers;
//! - [`lean`]: the lean split driver of each backend as a firmware example builds it
//!   (`DONE` = 0, `Lean` features, `const` plans), over any registers and on the harness;
//! - [`load`]: the full-load runner (back-to-back frames, interrupt serviced after a
//!   random latency, losses predicted from the FIFO depth and checked exactly);
//! - [`rng`]: a tiny seeded generator;
//! - [`support`]: frame sets, the reference filter semantics, running the bus.

pub mod app_bus;
pub mod backend;
pub mod lean;
pub mod load;
pub mod preempt;
pub mod rng;
pub mod support;

/// The README's snippets, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
pub struct ReadmeDoctests;
