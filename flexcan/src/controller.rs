//! The FlexCAN controller after `begin` ([`FlexCan`]); [`FlexCan::into_split`] makes it
//! the [`twocan_core::Hardware`] the portable driver uses (ACAN §3 data flow, §8–§10,
//! §17).
//!
//! # Mailboxes and transmit order
//!
//! Data frames go through the one data mailbox — MB15 in the Kinetis layout (ACAN §3
//! table 1), the layout's [`crate::layout::Layout::data_mailbox`] in the RT1062 layout
//! (MB16 for ACAN's four configurations, up to MB46 for the larger tables): the
//! driver's transmit queue is first-in first-out ([`twocan_core::TxPolicy::Fifo`]) and
//! holds the next frame until the data mailbox is free again, so data frames leave
//! strictly in the order given to `try_send` (ACAN §3 "sequentiality"). Remote frames
//! go to the first free remote-frame mailbox of the configuration (7, 5, 3 or 1 of them,
//! ACAN §9), just below the data mailbox. The module picks
//! among pending mailboxes by identifier priority, ties lowest mailbox first
//! (`CTRL1.LBUF` = 0), so `try_send` keeps remote frames in the request order with
//! data frames by loading one frame at a time, whatever its kind;
//! `try_send_now` (ACAN's path) loads any free remote-frame mailbox at once, and such
//! frames compete with the pending ones by identifier.
//!
//! After sending a remote frame the hardware turns its mailbox into a receive mailbox
//! for the answer (Kinetis RM, "Tx CODE 1100 with RTR = 1"); the Rx FIFO is matched
//! first (`CTRL2.MRP` = 0) and the driver deactivates the mailbox when it settles the
//! transmission, so answers reach the application through the filters only.
//!
//! # Receiving
//!
//! The receive handler reads the Rx FIFO output (MB0) and the `RXFIR.IDHIT` of the
//! element that accepted it, then pops the FIFO by writing 1 to `IFLAG1.BUF5I` (the
//! reading order of the reference manual). On the thread side `IDHIT` becomes the
//! user's filter index through [`crate::FilterTable::filter_index`] (an `IDHIT` that maps to
//! no filter gives [`crate::UNKNOWN_FILTER`]); the TIME STAMP field becomes the
//! frame's time stamp. A FIFO overflow (`IFLAG1.BUF7I`: at least one frame lost, the
//! hardware does not count them) is counted as one overrun occurrence.

use core::cell::Cell;

use twocan_core::{BusMode, BusOffRecovery, LastErrorCode, Mode, Registers};

use crate::configuration::Configuration;
use crate::filters::OwnedTable;
use crate::instance::Target;
use crate::layout::{Kinetis, Layout};
use crate::regs::{self, TIMER};
use crate::system::{LayoutSystem, SystemPlan};

/// A FlexCAN instance configured by `begin` (see [`crate::instance`]), over its
/// registers `R`, in the message-buffer layout `L` ([`crate::layout`]: [`Kinetis`],
/// MB0–MB15, by default; [`crate::layout::Imxrt1062`] for the RT1062's larger Rx FIFO
/// tables). Give it to the portable driver with [`FlexCan::into_split`].
#[derive(Debug)]
pub struct FlexCan<R: Registers, L: Layout = Kinetis> {
    pub(crate) regs: R,
    pub(crate) target: Target,
    pub(crate) table: L::Table,
    pub(crate) bus_mode: BusMode,
    pub(crate) recovery: BusOffRecovery,
    pub(crate) polls: u32,
    pub(crate) irq_priority: u8,
    pub(crate) mode: Mode,
    /// The newest error `ESR1` reported.
    pub(crate) last_error: Cell<LastErrorCode>,
    /// The clock gate and pins `begin` set up, which [`FlexCan::end`] releases.
    pub(crate) system: L::System,
    /// The peripheral (bus) clock `begin` checked the timing against
    /// ([`crate::Settings::bus_clock_hz`], the oscillator clock when not given): the
    /// Kinetis manual's clocks-per-bit rule is applied with it on every re-timing.
    pub(crate) bus_clock_hz: u32,
}

impl<R: Registers, L: Layout> FlexCan<R, L> {
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn configured(
        regs: R,
        target: Target,
        table: L::Table,
        bus_mode: BusMode,
        recovery: BusOffRecovery,
        polls: u32,
        irq_priority: u8,
        system: L::System,
        bus_clock_hz: u32,
    ) -> Self {
        FlexCan {
            system,
            bus_clock_hz,
            regs,
            target,
            table,
            bus_mode,
            recovery,
            polls,
            irq_priority,
            mode: Mode::Normal,
            last_error: Cell::new(LastErrorCode::None),
        }
    }

    /// The module and board this controller drives.
    pub const fn target(&self) -> Target {
        self.target
    }

    /// The message-buffer partition (ACAN §11).
    pub fn configuration(&self) -> Configuration {
        self.table.table_configuration()
    }

    /// The installed filters (ACAN §12–§13), with the filter numbering.
    pub const fn filters(&self) -> &L::Table {
        &self.table
    }

    /// The message interrupt priority of the settings (ACAN §16.7.4), for the NVIC.
    pub const fn message_irq_priority(&self) -> u8 {
        self.irq_priority
    }

    /// The clock gate and the Tx and Rx pins `begin` set up (ACAN §7).
    pub fn system(&self) -> SystemPlan {
        self.system.to_plan()
    }

    /// The mode the controller was last put in.
    pub const fn mode(&self) -> Mode {
        self.mode
    }

    /// The registers (for the model's inspection methods in tests).
    pub const fn registers(&self) -> &R {
        &self.regs
    }

    /// The registers, mutably (for the model's bus and fault-injection methods).
    pub fn registers_mut(&mut self) -> &mut R {
        &mut self.regs
    }

    /// Gives the registers back.
    pub fn into_registers(self) -> R {
        self.regs
    }

    /// The free-running timer (`TIMER`, one count per bit time): the time base of
    /// [`twocan_core::RxFrame::timestamp`].
    pub fn timer(&self) -> u16 {
        regs::timer::TIMER.get(self.regs.read32(TIMER)) as u16
    }

    /// Writes the ID table, the masks and `MCR.IDAM` (format A, or format D "all frames
    /// rejected" for an empty list): Freeze mode only (Kinetis RM, MCR: IDAM is
    /// writable in Freeze mode only).
    pub(crate) fn write_filters<T: OwnedTable>(regs: &R, table: &T) {
        Self::write_table(
            regs,
            table.table_rejects_all(),
            table.table_elements(),
            table.table_individual_masks(),
            table.table_global_mask(),
        );
    }

    /// [`FlexCan::write_filters`] from the table's parts (a [`crate::FilterTable`] or a
    /// [`crate::installed::PlannedTable`]).
    pub(crate) fn write_table(
        regs: &R,
        reject_all: bool,
        elements: &[u32],
        individual_masks: &[u32],
        global_mask: u32,
    ) {
        let idam = if reject_all {
            regs::mcr::IDAM_FORMAT_D
        } else {
            regs::mcr::IDAM_FORMAT_A
        };
        regs.modify32(regs::MCR, |v| regs::mcr::IDAM.replace(v, idam));
        for (i, e) in elements.iter().enumerate() {
            regs.write32(regs::rx_fifo_filter(i), *e);
        }
        for (i, m) in individual_masks.iter().enumerate() {
            regs.write32(regs::rximr(i), *m);
        }
        regs.write32(regs::RXFGMASK, global_mask);
    }
}
