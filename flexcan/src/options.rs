//! Compile-time choices of the split driver's FlexCAN controller ([`crate::FlexCanHw`]'s
//! second type parameter): what each frame pays for is chosen when the firmware is
//! built, not tested while it runs.
//!
//! | choice | [`Full`] (the default) | [`Lean`] |
//! |---|---|---|
//! | receive and transmit time stamps ([`Options::STAMPS`]) | the 16-bit `TIME STAMP` of the message buffer, widened by the driver | none: no `TIMER` read, no critical section in the receive handler |
//! | filter lists replaced while running ([`Options::FILTER_SWITCH`]) | `set_filters`; each raw frame carries the filter generation, and frames of a replaced list are dropped | `set_filters` refused with [`twocan_core::Error::Unsupported`]: no generation word per frame |
//! | the message-buffer layout ([`Options::Layout`], [`crate::layout`]) | the type parameter `L` of `Full<L>`, `FullInSlot<L>`, `Lean<L>`: [`Kinetis`] by default (MB0–MB15), [`crate::layout::Imxrt1062`] for the RT1062's tables up to 128 elements | the same |
//! | the filter table kept ([`Options::Table`]) | an owned [`crate::FilterTable`] (about 1 KB, compiled by `begin` at run time) | a [`PlannedTable`]: a few words pointing into a `static` plan made at compile time ([`crate::const_plan!`]) |
//!
//! ```
//! use twocan_flexcan::options::{Full, Lean, Options};
//! assert!(<Full>::STAMPS && <Full>::FILTER_SWITCH);
//! assert!(!<Lean>::STAMPS && !<Lean>::FILTER_SWITCH);
//! ```
//!
//! A controller with an owned table comes from [`crate::FlexCan::into_split_with`]
//! (`into_split` is `into_split_with::<Full>`); one with a planned table from
//! [`crate::FlexCan::begin_planned`] (see its example). A firmware may implement
//! [`Options`] for a mix of its own (time stamps with a planned table, say).

use core::convert::Infallible;
use core::marker::PhantomData;

use crate::installed::{InstalledTable, PlannedTable};
use crate::layout::{Kinetis, Layout};

/// The compile-time choices (implemented by [`Full`] and [`Lean`]; a firmware may
/// implement it for a mix of its own).
pub trait Options: 'static {
    /// The message-buffer layout ([`crate::layout`]): [`Kinetis`] (MB0–MB15, the
    /// default of [`Full`], [`FullInSlot`] and [`Lean`]) or
    /// [`crate::layout::Imxrt1062`] (64 message buffers, Rx FIFO tables up to RFFN 0xF).
    type Layout: Layout;
    /// The filter table the controller keeps ([`crate::installed`]): an owned
    /// [`crate::FilterTable`] or a [`PlannedTable`] read from a `static` plan.
    type Table: InstalledTable<<Self::Layout as Layout>::Table>;
    /// Received frames and transmit completions carry the message buffer's `TIME STAMP`
    /// (Kinetis RM, "Message buffer structure"), widened by the driver
    /// ([`twocan_core::Hardware::raw_timestamp`]); capabilities report `timestamps`.
    const STAMPS: bool;
    /// The filter list may be replaced while the controller runs
    /// ([`twocan_core::split::Rx::set_filters`]): every raw frame carries the list's
    /// generation so that frames the old list accepted are dropped.
    const FILTER_SWITCH: bool;
}

/// Every feature: time stamps, filter switches, the owned table `begin` compiles (the
/// default), on the layout `L` ([`Kinetis`] by default).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Full<L: Layout = Kinetis>(Infallible, PhantomData<L>);

impl<L: Layout> Options for Full<L> {
    type Layout = L;
    type Table = L::Table;
    const STAMPS: bool = true;
    const FILTER_SWITCH: bool = true;
}

/// As [`Full`], the table in a `static` [`crate::filters::TableSlot`] that `begin`
/// compiles into ([`crate::FlexCan::begin_in`]): no table-sized value moves through
/// the configuration, and the driver state holds a reference instead of the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FullInSlot<L: Layout = Kinetis>(Infallible, PhantomData<L>);

impl<L: Layout> Options for FullInSlot<L> {
    type Layout = L;
    type Table = &'static mut L::Table;
    const STAMPS: bool = true;
    const FILTER_SWITCH: bool = true;
}

/// Neither time stamps nor filter switches while running; the filter table planned at
/// compile time, read from its `static` ([`crate::FlexCan::begin_planned`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Lean<L: Layout = Kinetis>(Infallible, PhantomData<L>);

impl<L: Layout> Options for Lean<L> {
    type Layout = L;
    type Table = PlannedTable;
    const STAMPS: bool = false;
    const FILTER_SWITCH: bool = false;
}
