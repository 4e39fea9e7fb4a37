//! The FlexCAN controller as the portable split driver uses it
//! ([`twocan_core::split`]): [`FlexCanHw`], built from a started [`FlexCan`] with
//! [`FlexCan::into_split`].
//!
//! Interrupt lines (Kinetis RM, FlexCAN "Interrupts"): the ORed message-buffer vector
//! runs both the transmit handler ([`twocan_core::split::TxIrq`]: settle the data mailbox (MB15 in the Kinetis layout) and the
//! remote-frame mailboxes, refill) and the receive handler
//! ([`twocan_core::split::Rx0Irq`]: the Rx FIFO); the bus-off, error,
//! Tx/Rx-warning and wake-up vectors run the status handler
//! ([`twocan_core::split::StatusIrq`]). Who touches which register:
//! - transmit half and transmit handler: `IFLAG1` read, the words of one transmit
//!   mailbox that is inactive and settled (code `INACTIVE`, its `IFLAG1` bit clear);
//! - transmit handler: `IFLAG1` write-1-to-clear of the transmit mailboxes' bits;
//! - in the quiet transmit mode (`State::QUIET_TX`: no completions, see
//!   [`Hardware::QUIET_TX`] below): the transmit half and the transmit handler's refill
//!   write `IFLAG1` write-1-to-clear of the one mailbox they load, before loading it
//!   (Kinetis RM, "Transmit process", step 1); the transmit handler (inside the
//!   driver's critical section) writes `IMASK1` (`IMASK2` above MB31), as `begin`
//!   configured it, with or without the data mailbox's bit;
//!
//! (With the RT1062 layout, [`crate::layout::Imxrt1062`], the transmit mailboxes of the
//! tables from RFFN 8 on are MB32–MB46: what is said here of their `IFLAG1` bits holds
//! of their `IFLAG2` bits, IMXRT1060RM "Interrupt Flags 2 register (IFLAG2)"; the Rx
//! FIFO's flags stay in `IFLAG1`. That layout also writes the control/status word of
//! the ERR005829 reserved mailbox, INACTIVE twice, after each activation: transmit
//! half and transmit handler alike, the same value, [`Hardware::load`].)
//! - transmit half (`abort`) and transmit handler (`settle`), inside the driver's critical
//!   section: `ESR1` read for `TX` before an ABORT write (its clear-on-read error bits
//!   are kept for the status handler, as every state read does), ABORT into the control
//!   word of a pending transmit mailbox;
//! - receive handler: MB0–MB3 (the Rx FIFO output), `RXFIR`, `IFLAG1` write-1-to-clear
//!   of `BUF5I`/`BUF6I`/`BUF7I`;
//! - status handler: `ESR1` write-1-to-clear of exactly the bits it read, `ECR` read;
//! - any context, inside the driver's critical section: `TIMER` read (time stamp
//!   widening, [`Hardware::timer_now`]). The read unlocks a locked mailbox (Kinetis RM,
//!   "Message buffer lock mechanism"): no context relies on a lock, since the Rx FIFO
//!   output changes only when `BUF5I` is written and transmit mailboxes are not locked
//!   for reception.
//! - receive half (`install_filters`, in Freeze mode): the ID table, `RXIMR`,
//!   `RXFGMASK`, `MCR.IDAM`, and `IFLAG1.BUF5I` to discard the old list's frames;
//! - control (the receive half's context; stopped): `CTRL1` timing fields, `LOM`, `LPB`,
//!   `MCR.SRXDIS`; `CTRL1.BOFFREC` (`recover`, any mode); `MCR` mode requests.
//!
//! A raw received frame is the Rx FIFO output's four words (control/status,
//! identifier, data) and `RXFIR.IDHIT`; the thread side decodes it and maps the hit
//! to the user's filter ([`crate::FilterTable::filter_index`]).

use core::marker::PhantomData;
use core::sync::atomic::{AtomicBool, AtomicU32, AtomicU8, Ordering};

use twocan_core::hardware::{
    sort_by_token, Completion, FifoEvents, ReceiveContext, Settled, StatusEvents, Token,
};
use twocan_core::timing::{Limits, Timing, FLEXCAN_CTRL1_TIMING_MASK};
use twocan_core::{
    AtomicLastError, BusMode, BusOffRecovery, Capabilities, Error, ErrorCounters, ErrorState,
    ErrorStatus, Frame, Hardware, LastErrorCode, Mode, ModeSupport, Registers, RxFrame, Timestamp,
    TxOutcome, TxPolicy,
};
use twocan_core::{MailboxId, MailboxState};

use crate::begin::{last_mailbox, tx_flag_base, RX_FIFO_IMASK};
use crate::configuration::Configuration;
use crate::controller::FlexCan;
use crate::filters::{OwnedTable, UNKNOWN_FILTER};
use crate::handshake;
use crate::installed::{InstalledTable, Unresolved};
use crate::instance::Target;
use crate::layout::Layout;
use crate::message_buffer::MbWords;
use crate::options::{Full, Options};
use crate::regs::{
    self, code, cs, ctrl1, esr1, iflag1, rxfir, ECR, ESR1, IFLAG1, IFLAG2, IMASK1, IMASK2, RXFIR,
};
use crate::status;
use crate::system::LayoutSystem;

/// One received frame: the Rx FIFO output's control/status, identifier and two data
/// words, and `RXFIR.IDHIT`.
pub type RawFrame = [u32; 5];

/// Frames the Rx FIFO holds (Kinetis RM, "Rx FIFO": six deep).
const RX_FIFO_DEPTH: usize = 6;

/// Marks a mailbox number given by the quiet mode's [`Hardware::free_mailbox_quiet`] or
/// [`Hardware::free_mailbox_now_quiet`] (message buffers are numbered below 64): the
/// mailbox may have ended without its flag being acknowledged, so [`Hardware::load`]
/// clears the flag before it writes the mailbox (Kinetis RM, "Transmit process", step
/// 1: "check whether the respective interrupt bit is set and clear it"). The mailboxes
/// of [`Hardware::free_mailbox`] are settled (flag clear): nothing to clear.
const QUIET_LOAD: u8 = 0x80;

/// Transmit mailboxes at most (the data mailbox, MB15 in ACAN's configurations in the Kinetis layout, MB16 in the RT1062 layout, and up
/// to seven remote-frame mailboxes: [`Configuration::data_mailbox`]).
const MAX_TX: usize = 8;

const MODE_NORMAL: u8 = 0;
const MODE_STOPPED: u8 = 1;
const MODE_SLEEP: u8 = 2;

const fn bus_mode_code(m: BusMode) -> u8 {
    match m {
        BusMode::Normal => 0,
        BusMode::ListenOnly => 1,
        BusMode::LoopBack => 2,
    }
}

/// Whether the transmit half is refused in bus mode `bus_mode` and mode `mode` (codes):
/// listen-only, or sleep.
const fn tx_refused(bus_mode: u8, mode: u8) -> bool {
    bus_mode == bus_mode_code(BusMode::ListenOnly) || mode == MODE_SLEEP
}

/// Position of the filter generation in a raw frame's last word (`IDHIT` below it).
const GENERATION_SHIFT: u32 = 16;

fn mode_code(m: Mode) -> u8 {
    match m {
        Mode::Normal => MODE_NORMAL,
        Mode::Stopped => MODE_STOPPED,
        Mode::Sleep => MODE_SLEEP,
    }
}

/// A FlexCAN instance shared by the halves and handlers of the split driver.
///
/// `O` chooses at compile time what each frame pays for ([`crate::options`]): time
/// stamps and filter switches with [`Full`] (the default), neither with
/// [`crate::options::Lean`] ([`FlexCan::into_split_with`]).
pub struct FlexCanHw<R: Registers, O: Options = Full> {
    regs: R,
    target: Target,
    /// The transmit mailboxes' bits in their flag register (remote-frame mailboxes and
    /// the data mailbox; `IFLAG1`, or `IFLAG2` above MB31: [`FlexCanHw::tx_flags`]),
    /// from the configuration.
    tx_mask: u32,
    /// The interrupt mask register of the transmit mailboxes (`IMASK1`, or `IMASK2` above
    /// MB31) as `begin` writes it: the Rx FIFO's enables and every transmit mailbox's
    /// ([`RX_FIFO_IMASK`] | `tx_mask`), or the transmit mailboxes' alone in `IMASK2`.
    /// The quiet transmit mode writes it with or without the data mailbox's bit
    /// ([`Hardware::set_tx_interrupt`]).
    tx_imask: u32,
    /// The installed filter table (ID table, masks, map from `IDHIT` to the user's
    /// index): touched only from the receive half's context (`decode`,
    /// `install_filters`), so one copy.
    table: core::cell::UnsafeCell<O::Table>,
    /// The table's message-buffer configuration (read from every context).
    configuration: Configuration,
    /// The [`BusMode`] (`CTRL1.LOM`/`LPB`) as its code (read by the transmit half).
    bus_mode: AtomicU8,
    /// `MCR.SRXDIS` outside loop-back (loop-back needs self reception).
    srxdis: bool,
    recovery: BusOffRecovery,
    /// Acknowledge wait bound (grows when a slower bit rate is set).
    polls: AtomicU32,
    irq_priority: u8,
    mode: AtomicU8,
    /// Whether the transmit half is refused ([`Error::WrongMode`]): listen-only or
    /// sleep, from `bus_mode` and `mode` (one load on the transmit path). Written
    /// after each of them, by the control context only.
    tx_refused: AtomicBool,
    /// Filter list generation (low 16 bits), stamped on each raw frame by `read_rx`
    /// and compared by `decode`: frames read before the last `install_filters` are
    /// dropped. Written by `install_filters` only.
    generation: AtomicU32,
    /// Token of the frame in each transmit mailbox, indexed by `data mailbox - MB`.
    tokens: [AtomicU32; MAX_TX],
    last_error: AtomicLastError,
    /// Written by the receive half's `decode` only.
    unresolved: AtomicU32,
    /// Transmit mailboxes loaded and not settled yet (bit per MB): a flag raised by a
    /// remote-frame mailbox that became a receive mailbox is not a completion.
    ///
    /// In the quiet transmit mode (no completions; [`Hardware::acknowledge_ended`]) a bit
    /// is cleared when the mailbox's end is acknowledged, and the data mailbox may be
    /// loaded again before that: the bits are then the mailboxes loaded since their last
    /// acknowledged end, a superset of the pending ones. Every reader that needs
    /// "pending" confirms it with the mailbox (flag clear and code `DATA`):
    /// `abort_mailboxes` (so `request_abort`, `abort_all_mailboxes`, `retry_aborts`),
    /// `pending_among` (the quiet mode's request order); `mailbox_state` reads the
    /// mailbox alone; `prepare_abort` at worst polls `ESR1[TX]` for a frame already
    /// sent, which reads 0 at once unless another of ours is on the wire.
    loaded: AtomicU32,
    /// Transmit mailboxes whose abort was requested while the module was transmitting
    /// (bit per MB), written inside the driver's critical section only
    /// (`abort_mailboxes`, `retry_aborts`).
    abort_wanted: AtomicU32,
    /// The clock gate and pins `begin` set up (for [`FlexCanHw::into_controller`]): the
    /// layout's chip family's plan only.
    system: <O::Layout as Layout>::System,
    /// Frames caught by remote-frame mailboxes turned receive mailboxes (written by the
    /// transmit interrupt's `settle` only).
    caught: AtomicU32,
    /// `ESR1` error bits (clear-on-read) read by a state read (`status_now`) and not yet
    /// reported: the status handler reports them with its own read, so an error that
    /// a state read took out of `ESR1` (for example one raised between the handler's
    /// read and its write-back, whose `ERRINT` the write-back cleared) is still counted.
    unreported: AtomicU32,
    /// The peripheral (bus) clock `begin` checked the timing against
    /// ([`crate::Settings::bus_clock_hz`]); [`Hardware::set_timing`] and
    /// [`Hardware::capabilities`] apply the Kinetis manual's rule with it.
    bus_clock_hz: u32,
    /// Rx FIFO frames discarded by `install_filters` and not yet taken (receive half
    /// only).
    discarded: AtomicU32,
    options: PhantomData<O>,
}

impl<R: Registers, L: Layout> FlexCan<R, L> {
    /// The controller for the split driver (`twocan_core::split::State::split`); the
    /// installed filter table comes along. Every feature ([`Full`]); see
    /// [`FlexCan::into_split_with`] for a leaner choice.
    pub fn into_split(self) -> FlexCanHw<R, Full<L>> {
        self.into_split_with::<Full<L>>()
    }

    /// The controller for the split driver with the compile-time choices `O`
    /// ([`crate::options`]: [`Full`], [`crate::options::Lean`]) of the same layout.
    pub fn into_split_with<O: Options<Layout = L, Table = L::Table>>(self) -> FlexCanHw<R, O> {
        let last_error = self.last_error.get();
        FlexCanHw::from_parts(
            self.regs,
            self.target,
            self.table,
            Parts {
                bus_mode: self.bus_mode,
                recovery: self.recovery,
                polls: self.polls,
                irq_priority: self.irq_priority,
                mode: self.mode,
                last_error,
                system: self.system,
                bus_clock_hz: self.bus_clock_hz,
            },
        )
    }
}

/// The small values a split controller starts from (a started [`FlexCan`]'s, or
/// `begin_planned`'s).
pub(crate) struct Parts<Sys> {
    pub(crate) bus_mode: BusMode,
    pub(crate) recovery: BusOffRecovery,
    pub(crate) polls: u32,
    pub(crate) irq_priority: u8,
    pub(crate) mode: Mode,
    pub(crate) last_error: LastErrorCode,
    pub(crate) system: Sys,
    pub(crate) bus_clock_hz: u32,
}

impl<R: Registers, O: Options> FlexCanHw<R, O> {
    /// The split controller over `regs` with `table` installed.
    #[inline(always)]
    pub(crate) fn from_parts(
        regs: R,
        target: Target,
        table: O::Table,
        p: Parts<<O::Layout as Layout>::System>,
    ) -> Self {
        let configuration = table.configuration();
        let first = if O::Layout::E5829 {
            configuration.first_remote_mailbox_in(true)
        } else {
            configuration.first_remote_mailbox()
        } as u32;
        let tx_mask = if O::Layout::IFLAG2 {
            // The transmit mailboxes `first..=data` as bits of their flag register.
            let data = last_mailbox::<O::Layout>(configuration) as u32;
            let base = tx_flag_base::<O::Layout>(data as usize) as u32;
            (u32::MAX >> (31 - (data - base))) >> (first - base) << (first - base)
        } else {
            (0xFFFF_u32 >> first << first) & 0xFFFF
        };
        let tx_imask = if tx_flag_base::<O::Layout>(last_mailbox::<O::Layout>(configuration)) == 0 {
            RX_FIFO_IMASK | tx_mask
        } else {
            tx_mask
        };
        let srxdis =
            p.bus_mode != BusMode::LoopBack && regs.read32(regs::MCR) & regs::mcr::SRXDIS != 0;
        FlexCanHw {
            regs,
            target,
            tx_mask,
            tx_imask,
            configuration,
            table: core::cell::UnsafeCell::new(table),
            bus_mode: AtomicU8::new(bus_mode_code(p.bus_mode)),
            srxdis,
            recovery: p.recovery,
            polls: AtomicU32::new(p.polls),
            generation: AtomicU32::new(0),
            irq_priority: p.irq_priority,
            mode: AtomicU8::new(mode_code(p.mode)),
            tx_refused: AtomicBool::new(tx_refused(bus_mode_code(p.bus_mode), mode_code(p.mode))),
            tokens: [const { AtomicU32::new(0) }; MAX_TX],
            last_error: AtomicLastError::new(p.last_error),
            unresolved: AtomicU32::new(0),
            loaded: AtomicU32::new(0),
            abort_wanted: AtomicU32::new(0),
            system: p.system,
            bus_clock_hz: p.bus_clock_hz,
            discarded: AtomicU32::new(0),
            caught: AtomicU32::new(0),
            unreported: AtomicU32::new(0),
            options: PhantomData,
        }
    }
}

/// FlexCAN's receive-side method, on the receive half's context
/// ([`ReceiveContext`]: `Rx::receive_context`, `Driver::receive_context`), where no
/// filter switch can rewrite the table while it is read.
///
/// ```
/// use twocan_core::{Driver, Registers};
/// use twocan_flexcan::{FlexCanHw, InstalledFilters};
///
/// fn show<R: Registers>(driver: &mut Driver<FlexCanHw<R>, 8, 4>) -> usize {
///     driver.receive_context().filters().elements().len()
/// }
/// ```
///
/// The table is the layout's ([`crate::layout::Layout::Table`]): a
/// [`crate::LargeFilterTable`] with [`crate::layout::Imxrt1062`].
///
/// Any other context has only `&FlexCanHw` (`State::hardware`, `Tx::hardware`), which
/// does not offer the table, so a copy is never torn by a concurrent `set_filters`:
///
/// ```compile_fail,E0599
/// # fn show<R: twocan_core::Registers + Sync + Send>(
/// #     state: &twocan_core::State<twocan_flexcan::FlexCanHw<R>, 8>,
/// # ) {
/// let table = state.hardware().unwrap().filters();
/// # }
/// ```
pub trait InstalledFilters {
    /// The table's type ([`crate::FilterTable`] with the default layout).
    type Table;
    /// A copy of the filter table in force.
    fn filters(&self) -> Self::Table;
}

impl<R: Registers, L: Layout, O: Options<Layout = L, Table = L::Table>> InstalledFilters
    for ReceiveContext<'_, FlexCanHw<R, O>>
{
    type Table = L::Table;
    fn filters(&self) -> L::Table {
        // SAFETY: the table is written only by `install_filters`, which the receive
        // half calls with `&mut self`; a `ReceiveContext` borrows that half (or the
        // one-struct driver) exclusively for its lifetime, so no write overlaps.
        unsafe { (*self.hardware().table.get()).clone() }
    }
}

impl<R: Registers, O: Options> FlexCanHw<R, O> {
    /// Which instance of which chip.
    pub const fn target(&self) -> Target {
        self.target
    }

    /// The message-buffer configuration.
    pub const fn configuration(&self) -> Configuration {
        self.configuration
    }

    /// `mMessageIRQPriority` of the settings `begin` took.
    pub const fn message_irq_priority(&self) -> u8 {
        self.irq_priority
    }

    /// The registers (for inspection).
    pub fn registers(&self) -> &R {
        &self.regs
    }

    /// The registers, mutably (a host harness moving a model to another bus; writing
    /// them behind the driver's back voids its bookkeeping).
    pub fn registers_mut(&mut self) -> &mut R {
        &mut self.regs
    }

    /// The free-running timer (`TIMER`, one tick per bit time).
    pub fn timer(&self) -> u16 {
        regs::timer::TIMER.get(self.regs.read32(regs::TIMER)) as u16
    }

    /// Frames whose `RXFIR.IDHIT` mapped to no filter (reported with
    /// [`UNKNOWN_FILTER`]); the hardware never produces one for the installed table.
    pub fn unresolved_filter_hits(&self) -> u32 {
        self.unresolved.load(Ordering::Relaxed)
    }

    /// Frames a remote-frame mailbox caught after sending its remote frame (Kinetis RM
    /// "Transmit process": a remote frame's mailbox becomes a receive mailbox with the
    /// same identifier, its mask the exact one `begin` writes, so it takes a frame of
    /// that identifier and kind that the Rx FIFO — matched first, `CTRL2[MRP] = 0` —
    /// did not accept). Such a frame passed none of the user's filters: like ACAN, the
    /// driver does not deliver it and makes the mailbox inactive again; unlike ACAN,
    /// which overwrites it silently on the next remote frame, it is counted here (a
    /// mailbox found `OVERRUN` counts 2, the least it held).
    pub fn remote_mailbox_catches(&self) -> u32 {
        self.caught.load(Ordering::Relaxed)
    }

    /// The register handle back (to run `begin` again).
    pub fn into_registers(self) -> R {
        self.regs
    }

    /// The register handle and the installed table back ([`FlexCanHw::end`]).
    pub(crate) fn into_registers_and_table(self) -> (R, O::Table) {
        (self.regs, self.table.into_inner())
    }

    /// The handshake bound `begin` (or a later bit rate) set.
    pub(crate) fn handshake_polls(&self) -> u32 {
        self.polls.load(Ordering::Relaxed)
    }

    /// The clock gate and pins `begin` set up.
    pub(crate) fn system_plan(&self) -> &<O::Layout as Layout>::System {
        &self.system
    }
}

impl<R: Registers, L: Layout, O: Options<Layout = L, Table = L::Table>> FlexCanHw<R, O> {
    /// The controller back, as `begin` gave it (the reverse of
    /// [`FlexCan::into_split`]): for [`FlexCan::end`] after
    /// [`twocan_core::Driver::release`].
    pub fn into_controller(self) -> FlexCan<R, L> {
        let mode = match self.mode() {
            MODE_STOPPED => Mode::Stopped,
            MODE_SLEEP => Mode::Sleep,
            _ => Mode::Normal,
        };
        let last_error = self.last_error();
        let bus_mode = Hardware::bus_mode(&self);
        let mut controller = FlexCan::configured(
            self.regs,
            self.target,
            self.table.into_inner(),
            bus_mode,
            self.recovery,
            self.polls.load(Ordering::Relaxed),
            self.irq_priority,
            self.system,
            self.bus_clock_hz,
        );
        controller.mode = mode;
        controller.last_error.set(last_error);
        controller
    }
}

impl<R: Registers, O: Options> FlexCanHw<R, O> {
    fn mode(&self) -> u8 {
        self.mode.load(Ordering::Relaxed)
    }

    /// The data mailbox: MB15 (a constant) with a layout of 16 buffers, else the
    /// configuration's ([`Configuration::data_mailbox`]).
    #[inline(always)]
    fn data_mb(&self) -> usize {
        last_mailbox::<O::Layout>(self.configuration)
    }

    /// The first remote-frame mailbox: after the Rx FIFO area, and with
    /// [`Layout::E5829`] after the reserved mailbox too
    /// ([`Configuration::first_remote_mailbox_in`]).
    #[inline(always)]
    fn first_remote(&self) -> usize {
        if O::Layout::E5829 {
            self.configuration.first_remote_mailbox_in(true) as usize
        } else {
            self.configuration.first_remote_mailbox() as usize
        }
    }

    /// The first MB of the flag register holding the transmit mailboxes' flags: 0, or
    /// 32 when they lie above MB31 (a constant 0 with a layout of 16 buffers).
    #[inline(always)]
    fn tx_base(&self) -> usize {
        tx_flag_base::<O::Layout>(self.data_mb())
    }

    /// The flag register of the transmit mailboxes: `IFLAG1`, or `IFLAG2` for MB32–MB63
    /// (IMXRT1060RM, "Interrupt Flags 2 register (IFLAG2)").
    #[inline(always)]
    fn tx_flags(&self) -> usize {
        if self.tx_base() == 0 {
            IFLAG1
        } else {
            IFLAG2
        }
    }

    /// Transmit mailbox `mb`'s bit in [`FlexCanHw::tx_flags`] (and in `loaded`,
    /// `abort_wanted`, `tx_mask`).
    #[inline(always)]
    fn tx_bit(&self, mb: usize) -> u32 {
        iflag1::buf(mb - self.tx_base())
    }

    /// Refused with [`Error::WrongMode`] in listen-only mode and while disabled (sleep).
    #[inline(always)]
    fn check_can_send(&self) -> Result<(), Error> {
        if self.tx_refused.load(Ordering::Relaxed) {
            return Err(Error::WrongMode);
        }
        Ok(())
    }

    /// `tx_refused` from `bus_mode` and `mode` (after a store to either; the control
    /// context, their one writer).
    fn note_tx_refused(&self) {
        let refused = tx_refused(
            self.bus_mode.load(Ordering::Relaxed),
            self.mode.load(Ordering::Relaxed),
        );
        self.tx_refused.store(refused, Ordering::Relaxed);
    }

    /// The data mailbox (MB15 in ACAN's configurations in the Kinetis layout, MB16 in the RT1062 layout) for a data frame, the first free
    /// remote-frame mailbox for a remote frame.
    #[inline(always)]
    fn free_now(&self, frame: &Frame) -> Result<Option<u8>, Error> {
        // The control word first, then the flag: a mailbox reading INACTIVE stays so
        // until someone loads it, so a clear flag read after it means "settled". (Read
        // the other way round, a frame ending between the two reads would look free
        // with its completion unsettled, and the load would overwrite its token.)
        let free = |mb: usize| {
            cs::CODE.get(self.regs.read32(regs::mb_cs(mb))) == code::TX_INACTIVE
                && self.regs.read32(self.tx_flags()) & self.tx_bit(mb) == 0
        };
        let data = self.data_mb();
        if !frame.is_remote() {
            return Ok(free(data).then_some(data as u8));
        }
        let first = self.first_remote();
        Ok((first..data).find(|&mb| free(mb)).map(|mb| mb as u8))
    }

    /// The quiet mode's data mailbox (MB15 in ACAN's configurations in the Kinetis layout, MB16 in the RT1062 layout), tagged
    /// [`QUIET_LOAD`]: free when its code reads `INACTIVE` — never loaded, or its frame
    /// sent (Kinetis RM, "Transmit process": after a successful transmission the code
    /// goes back to INACTIVE and the flag is set) — or `ABORT` with its flag set (aborted,
    /// "Transmission abort mechanism"), whether or not the flag was acknowledged. The
    /// control word first: a mailbox that reads INACTIVE or ABORT stays so until
    /// software writes it, and `ABORT` with the flag clear is an abort still waiting
    /// for the frame on the wire (not free).
    #[inline(always)]
    fn data_free_quiet(&self) -> Option<u8> {
        let data = self.data_mb();
        let c = cs::CODE.get(self.regs.read32(regs::mb_cs(data)));
        let free = c == code::TX_INACTIVE
            || (c == code::TX_ABORT && self.regs.read32(self.tx_flags()) & self.tx_bit(data) != 0);
        free.then_some(data as u8 | QUIET_LOAD)
    }

    /// Whether a transmit mailbox among `mask` (bits of [`FlexCanHw::tx_flags`]) holds a
    /// frame that has not ended: flag clear and code `DATA`, as `abort_mailboxes` and
    /// `mailbox_state` judge (a transmit mailbox ends with its flag set and its code
    /// INACTIVE, ABORT, or Rx EMPTY for a remote frame: Kinetis RM, "Transmit process",
    /// "Transmission abort mechanism"). The quiet mode's slow path (`loaded` keeps
    /// mailboxes whose end was not acknowledged): the flags once, then the control
    /// word of each mailbox of `mask` whose flag is clear.
    #[cold]
    #[inline(never)]
    fn pending_among(&self, mask: u32) -> bool {
        let flags = self.regs.read32(self.tx_flags());
        (self.tx_base()..=self.data_mb()).any(|mb| {
            mask & !flags & self.tx_bit(mb) != 0
                && cs::CODE.get(self.regs.read32(regs::mb_cs(mb))) == code::TX_DATA
        })
    }

    /// The quiet mode's acknowledgement of the transmit mailboxes `ended` (their flags
    /// read set; inside the driver's critical section): as [`FlexCanHw::settle_one`]
    /// without the completion — the `loaded` bit cleared, a frame caught by a
    /// remote-frame mailbox turned receive mailbox counted, the flag acknowledged (write
    /// 1 to clear, Kinetis RM "Interrupt Flags 1 register"), the mailbox made INACTIVE
    /// again unless it is. A mailbox that reads `DATA` was loaded again after the end its
    /// flag reported (`load` cleared that flag before activating it; only a context
    /// running beside this one, not one it preempts, can get there between the two
    /// reads): it is pending, and left as it is — a stale flag never deactivates a
    /// newly loaded mailbox.
    fn acknowledge(&self, ended: u32) {
        let mut rest = ended;
        while rest != 0 {
            let mb = self.tx_base() + rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let c = cs::CODE.get(self.regs.read32(regs::mb_cs(mb)));
            if c == code::TX_DATA {
                continue;
            }
            self.unload(mb, c);
            self.deactivate(mb, c);
        }
    }

    /// First half of settling the ended transmit mailbox `mb` (code `c`): its `loaded`
    /// bit cleared, and a frame caught by a remote-frame mailbox turned receive mailbox
    /// counted. Whether it was loaded.
    #[inline(always)]
    fn unload(&self, mb: usize, c: u32) -> bool {
        let bit = self.tx_bit(mb);
        let was_loaded = self.loaded.fetch_and(!bit, Ordering::Relaxed) & bit != 0;
        if c == code::RX_FULL || c == code::RX_OVERRUN {
            self.count_caught(c);
        }
        was_loaded
    }

    /// Second half: the flag acknowledged (write 1 to clear, Kinetis RM "Interrupt Flags
    /// 1 register"), after which the transmit half may load `mb` again, and the mailbox
    /// made INACTIVE unless it is.
    #[inline(always)]
    fn deactivate(&self, mb: usize, c: u32) {
        self.regs.write32(self.tx_flags(), self.tx_bit(mb));
        if c != code::TX_INACTIVE {
            self.regs
                .write32(regs::mb_cs(mb), cs::CODE.val(code::TX_INACTIVE));
        }
    }

    /// Requests the abort of the pending mailboxes among `mask` (transmit half or
    /// transmit interrupt, inside the driver's critical section): code `ABORT` (0b1001)
    /// into their control word (Kinetis RM, "Transmission abort mechanism", `MCR[AEN]`
    /// set by `begin`). Pending: code `DATA` and `IFLAG1` bit clear (a mailbox whose
    /// flag is set ended; its completion is `settle`'s).
    ///
    /// The write must not race the end of a transmission: written over a mailbox that
    /// has just ended (code `INACTIVE`, flag set), `ABORT` is taken as written — the
    /// manual blocks the write only for a mailbox being transmitted or moved out to the
    /// serial message buffer — and the mailbox would read aborted although its frame
    /// was sent (see `docs/models.md`). So the driver reads `ESR1[TX]` first and
    /// writes only while the module transmits nothing: no frame of ours can then end
    /// before the write lands (a frame lasts at least 44 bit times; these are a few
    /// instructions with interrupts off), and a frame that starts meanwhile is in the
    /// case the manual covers (the abort waits for its outcome). The transmit half
    /// waits for `ESR1[TX]` to read 0 first (`prepare_abort`); should a transmission
    /// start in between, the aborts wait in `abort_wanted` and `settle` tries again
    /// (the message-buffer interrupt after that transmission, or the transmit half's
    /// next call that settles: `try_send` with a queue, `poll`, `abort`). Returns the
    /// mailboxes of `mask` found pending (aborted or waiting to be).
    fn abort_mailboxes(&self, mask: u32) -> u32 {
        let esr = self.regs.read32(ESR1);
        // ESR1's error bits clear on read: kept for the status handler.
        self.keep_unreported(esr);
        let transmitting = esr & esr1::TX != 0;
        let flags = self.regs.read32(self.tx_flags());
        let mut pending = 0;
        for mb in (self.tx_base()..=self.data_mb()).filter(|&mb| mask & self.tx_bit(mb) != 0) {
            if flags & self.tx_bit(mb) != 0 {
                continue;
            }
            let control = self.regs.read32(regs::mb_cs(mb));
            if cs::CODE.get(control) != code::TX_DATA {
                continue;
            }
            pending |= self.tx_bit(mb);
            if !transmitting {
                self.regs
                    .write32(regs::mb_cs(mb), cs::CODE.replace(control, code::TX_ABORT));
            }
        }
        // Plain load and store: only the critical section's holder touches it.
        let wanted = self.abort_wanted.load(Ordering::Relaxed);
        let wanted = if transmitting {
            wanted | pending
        } else {
            wanted & !pending
        };
        self.abort_wanted.store(wanted, Ordering::Relaxed);
        pending
    }

    /// The aborts that waited for the end of a transmission (`abort_mailboxes`), for
    /// the mailboxes still loaded.
    #[inline(always)]
    fn retry_aborts(&self) {
        let wanted = self.abort_wanted.load(Ordering::Relaxed);
        if wanted == 0 {
            return;
        }
        let still = wanted & self.loaded.load(Ordering::Relaxed);
        self.abort_wanted.store(still, Ordering::Relaxed);
        if still != 0 {
            self.abort_mailboxes(still);
        }
    }

    /// Settles transmit mailbox `mb`, whose `IFLAG1` bit is set (inside the driver's
    /// critical section): its completion when it held a frame of ours (code `ABORT`:
    /// aborted; anything else: sent, with the TIME STAMP the hardware wrote). The flag
    /// is acknowledged and the mailbox made `INACTIVE` again (a remote-frame mailbox
    /// became a receive mailbox for the answer; an aborted one shows `ABORT`).
    #[inline(always)]
    fn settle_one(&self, mb: usize) -> Option<Completion> {
        // Every configuration's transmit mailboxes fit the token slots (`data - mb` < 8).
        const {
            let mut i = 0;
            while i < Configuration::EVERY.len() {
                let c = Configuration::EVERY[i];
                assert!(((c.data_mailbox() - c.first_remote_mailbox()) as usize) < MAX_TX);
                assert!(
                    ((c.data_mailbox_in(true) - c.first_remote_mailbox_in(true)) as usize) < MAX_TX
                );
                i += 1;
            }
        };
        let control = self.regs.read32(regs::mb_cs(mb));
        let c = cs::CODE.get(control);
        let was_loaded = self.unload(mb, c);
        // The token before the flag is acknowledged: once it is, the transmit half may
        // load the mailbox with the next frame and its token. Transmit mailboxes are the
        // data mailbox and at most seven before it in every configuration, so
        // `data - mb` is below 8.
        let token = was_loaded.then(|| {
            Token(
                self.tokens[self.data_mb().wrapping_sub(mb) & (MAX_TX - 1)].load(Ordering::Acquire),
            )
        });
        self.deactivate(mb, c);
        // Without a frame of ours (an answer caught by a remote-frame mailbox turned
        // receive mailbox): acknowledged, deactivated, no completion.
        let token = token?;
        let (outcome, timestamp) = if c == code::TX_ABORT {
            (TxOutcome::Aborted, None)
        } else {
            // The 16-bit TIME STAMP: the driver widens it.
            let stamp = cs::TIME_STAMP.get(control) as u16;
            (
                TxOutcome::Sent,
                O::STAMPS.then(|| Timestamp::from_parts(0, stamp)),
            )
        };
        Some(Completion {
            token,
            outcome,
            cause: None,
            timestamp,
        })
    }

    /// A frame caught by a remote-frame mailbox turned receive mailbox (code `FULL`: 1,
    /// `OVERRUN`: 2, the least it held), counted before the mailbox is made inactive
    /// ([`FlexCanHw::remote_mailbox_catches`]). The transmit interrupt's rare case.
    #[cold]
    #[inline(never)]
    fn count_caught(&self, c: u32) {
        let caught = if c == code::RX_OVERRUN { 2 } else { 1 };
        let n = self.caught.load(Ordering::Relaxed);
        self.caught.store(n.wrapping_add(caught), Ordering::Relaxed);
    }

    /// Several transmit mailboxes ended in one interrupt (`ended`, their `IFLAG1`
    /// bits): their completions in token order (the request order). Out of line: with
    /// one frame in a mailbox at a time (`free_mailbox`), only `try_send_now`'s remote
    /// frames come here.
    #[cold]
    #[inline(never)]
    fn settle_many<G: FnMut(Settled)>(&self, ended: u32, f: &mut G) {
        let mut out = [(
            0u32,
            Completion {
                token: Token(0),
                outcome: TxOutcome::Sent,
                cause: None,
                timestamp: None,
            },
        ); MAX_TX];
        let mut n = 0;
        for mb in (self.tx_base()..=self.data_mb()).filter(|&mb| ended & self.tx_bit(mb) != 0) {
            if let Some(c) = self.settle_one(mb) {
                if let Some(slot) = out.get_mut(n) {
                    *slot = (c.token.0, c);
                    n += 1;
                }
            }
        }
        let out = &mut out[..n];
        sort_by_token(out);
        for (_, c) in out.iter() {
            f(Settled::Done(*c));
        }
    }

    fn latch(&self, esr: u32) -> Option<LastErrorCode> {
        let code = status::last_error(esr);
        if let Some(c) = code {
            self.last_error.store(c);
        }
        code
    }

    fn last_error(&self) -> LastErrorCode {
        self.last_error.load()
    }

    fn status_now(&self) -> ErrorStatus {
        if self.mode() == MODE_SLEEP {
            return ErrorStatus {
                state: ErrorState::Sleeping,
                counters: ErrorCounters::default(),
                last_error: self.last_error(),
            };
        }
        let esr = self.regs.read32(ESR1);
        self.keep_unreported(esr);
        self.status_of(esr)
    }

    /// Error bits of an `ESR1` value read outside the status handler's own read (the
    /// read cleared them): latched as the last error and kept for the handler to count.
    fn keep_unreported(&self, esr: u32) {
        self.latch(esr);
        if esr & esr1::ERROR_BITS != 0 {
            self.unreported
                .fetch_or(esr & esr1::ERROR_BITS, Ordering::Relaxed);
        }
    }

    /// The status from an `ESR1` value just read, and `ECR`.
    fn status_of(&self, esr: u32) -> ErrorStatus {
        let (state, counters) = status::decode(esr, self.regs.read32(ECR));
        let state = if self.mode() == MODE_STOPPED {
            ErrorState::Stopped
        } else {
            state
        };
        ErrorStatus {
            state,
            counters,
            last_error: self.last_error(),
        }
    }

    /// Puts the module in Freeze mode for a filter switch from `mode` (the mode
    /// recorded, which stays as it is: see `install_filters`). On a timeout the freeze
    /// request is withdrawn and the module left as it was.
    fn freeze_for_switch(&self, mode: u8) -> Result<(), Error> {
        let polls = self.polls.load(Ordering::Relaxed);
        if mode == MODE_STOPPED {
            return Ok(());
        }
        if mode == MODE_SLEEP {
            handshake::enable(&self.regs, polls)?;
        }
        if let Err(e) = handshake::freeze(&self.regs, polls) {
            let _ = self.resume_after_switch(mode);
            return Err(e);
        }
        Ok(())
    }

    /// Back to `mode` after a filter switch: leaves Freeze mode and waits until the
    /// module is synchronised to the bus (normal), or disables it again (sleep).
    fn resume_after_switch(&self, mode: u8) -> Result<(), Error> {
        let polls = self.polls.load(Ordering::Relaxed);
        match mode {
            MODE_NORMAL => {
                handshake::leave_freeze(&self.regs, polls)?;
                handshake::wait_synch(&self.regs, polls, |esr| {
                    self.latch(esr);
                })
            }
            MODE_SLEEP => handshake::disable(&self.regs, polls),
            _ => Ok(()),
        }
    }

    fn mode_change(&self, mode: Mode) -> Result<(), Error> {
        let polls = self.polls.load(Ordering::Relaxed);
        // From the hardware, not from the last request: a timed-out change may have
        // completed since.
        let disabled = self.regs.read32(regs::MCR) & (regs::mcr::MDIS | regs::mcr::LPMACK) != 0;
        if disabled && mode != Mode::Sleep {
            handshake::enable(&self.regs, polls)?;
        }
        match mode {
            Mode::Normal => {
                handshake::leave_freeze(&self.regs, polls)?;
                self.mode.store(MODE_NORMAL, Ordering::Relaxed);
                self.note_tx_refused();
                return handshake::wait_synch(&self.regs, polls, |esr| {
                    self.latch(esr);
                });
            }
            Mode::Stopped => handshake::freeze(&self.regs, polls)?,
            Mode::Sleep => handshake::disable(&self.regs, polls)?,
        }
        self.mode.store(mode_code(mode), Ordering::Relaxed);
        self.note_tx_refused();
        Ok(())
    }
}

// SAFETY: what each field needs to be shared between contexts:
// - `regs`: every context reads and writes registers through `&R` (`R: Sync`), each
//   its own registers or write-1-to-clear bits (module docs, the `Hardware` contract);
// - `table`: touched only by `decode` and `install_filters` (both `unsafe`, called from
//   the receive half's one context: the `Hardware` contract, upheld by
//   `twocan_core::split::Rx`) and by `filters`, which takes the receive half's proof of
//   context ([`ReceiveContext`]); the context may move between threads with the
//   receive half, so the table must be `Send` (the `where` clause);
// - `target`, `configuration`, `srxdis`, `recovery`, `irq_priority`, `system`,
//   `bus_clock_hz`: read only; everything else is atomic.
// `FlexCanHw` itself is `Send` (moved into the driver's state) exactly when `R` is.
unsafe impl<R: Registers + Sync, O: Options> Sync for FlexCanHw<R, O> {}

// SAFETY: as for `Sync`: each method stays within its context's registers.
unsafe impl<R: Registers, O: Options> Hardware for FlexCanHw<R, O> {
    type Raw = RawFrame;
    type FilterMap = ();
    type Filters = <O::Layout as Layout>::Table;

    /// One data mailbox (MB15 in ACAN's configurations in the Kinetis layout, MB16 in the RT1062 layout): request order (ACAN §3
    /// "sequentiality").
    fn tx_policy(&self) -> TxPolicy {
        TxPolicy::Fifo
    }

    /// As [`Hardware::free_mailbox_now`], but only while no transmit mailbox is loaded
    /// or unsettled: the request order holds across the data mailbox and the
    /// remote-frame mailboxes, among which the module picks by identifier, ties lowest
    /// mailbox first (Kinetis RM, "Arbitration process", `CTRL1[LBUF]` = 0), so one
    /// frame of the request order is in a mailbox at a time — as data frames always
    /// were, MB15 being their one mailbox. Refused with [`Error::WrongMode`] in
    /// listen-only mode and while disabled (sleep).
    #[inline(always)]
    fn free_mailbox(&self, frame: &Frame) -> Result<Option<u8>, Error> {
        self.check_can_send()?;
        if self.loaded.load(Ordering::Relaxed) != 0 {
            return Ok(None);
        }
        self.free_now(frame)
    }

    /// Data frames: the data mailbox (MB15 in ACAN's configurations in the Kinetis layout, MB16 in the RT1062 layout); remote frames: the first free remote-frame mailbox (ACAN §9),
    /// whatever else is loaded. Free means code `INACTIVE` and its `IFLAG1` bit clear
    /// (settled). Refused with [`Error::WrongMode`] in listen-only mode and while
    /// disabled (sleep).
    fn free_mailbox_now(&self, frame: &Frame) -> Result<Option<u8>, Error> {
        self.check_can_send()?;
        self.free_now(frame)
    }

    /// The quiet transmit mode is offered (Kinetis RM, FlexCAN "Interrupts": a message
    /// buffer raises the ORed message-buffer interrupt only while its `IMASK1` bit is
    /// set, and "setting or clearing a bit in the IMASK1 register can assert or negate
    /// an interrupt request, if the corresponding IFLAG1 bit is set", CANx_IMASK1; a
    /// mailbox may be written again once inactive, its flag cleared first, "Transmit
    /// process"). The data mailbox's interrupt is enabled only while frames are queued
    /// ([`Hardware::set_tx_interrupt`]); the remote-frame mailboxes keep theirs, so that a
    /// remote frame's mailbox, which becomes a receive mailbox once its frame is sent
    /// ("Transmit process"), is still made inactive again at once, as without the quiet
    /// mode. FlexCAN's transmit order is the request order ([`Hardware::tx_policy`]), as
    /// the quiet mode needs.
    const QUIET_TX: bool = true;

    /// The quiet mode's [`Hardware::free_mailbox`]: in request order, only while no other
    /// transmit mailbox holds a frame that has not ended (the module picks among loaded
    /// mailboxes by identifier, Kinetis RM "Arbitration process", so one frame of the
    /// request order is in a mailbox at a time). `loaded` is checked first (a superset
    /// of the pending mailboxes in this mode); the mailboxes it names other than the one
    /// wanted are confirmed from their flag and code (`pending_among`). A data frame
    /// takes the data mailbox once it has ended, its flag acknowledged or not (`load`
    /// clears it first); a remote frame takes a free remote-frame mailbox as
    /// [`Hardware::free_mailbox_now`] picks it (INACTIVE and settled: their interrupt stays
    /// on). Refused with [`Error::WrongMode`] in listen-only mode and while disabled
    /// (sleep), as [`Hardware::free_mailbox`] is.
    #[inline(always)]
    fn free_mailbox_quiet(&self, frame: &Frame) -> Result<Option<u8>, Error> {
        self.check_can_send()?;
        let loaded = self.loaded.load(Ordering::Relaxed);
        if !frame.is_remote() {
            let others = loaded & !self.tx_bit(self.data_mb());
            if others != 0 && self.pending_among(others) {
                return Ok(None);
            }
            return Ok(self.data_free_quiet());
        }
        if loaded != 0 && self.pending_among(loaded) {
            return Ok(None);
        }
        self.free_now(frame)
    }

    /// The quiet mode's [`Hardware::free_mailbox_now`], keeping its difference (ACAN's
    /// path, which may overtake): a data frame takes the data mailbox once it has ended
    /// (acknowledged or not), a remote frame the first free remote-frame mailbox,
    /// whatever else is loaded. Refused as [`Hardware::free_mailbox_now`] is.
    #[inline(always)]
    fn free_mailbox_now_quiet(&self, frame: &Frame) -> Result<Option<u8>, Error> {
        self.check_can_send()?;
        if frame.is_remote() {
            self.free_now(frame)
        } else {
            Ok(self.data_free_quiet())
        }
    }

    /// Acknowledges every transmit mailbox whose flag is set, without a report
    /// (`acknowledge`: flag written back, remote-frame mailboxes made inactive, caught
    /// frames counted), then retries the aborts that waited (as [`Hardware::settle`]).
    /// Nothing while disabled (sleep).
    unsafe fn acknowledge_ended(&self) {
        if self.mode() == MODE_SLEEP {
            return;
        }
        let ended = self.regs.read32(self.tx_flags()) & self.tx_mask;
        if ended != 0 {
            self.acknowledge(ended);
        }
        self.retry_aborts();
    }

    /// Writes the transmit mailboxes' interrupt mask register (`IMASK1`, or `IMASK2`
    /// with them above MB31, IMXRT1060RM "Interrupt Masks 2 register") as `begin`
    /// configured it, the data mailbox's bit cleared when `on` is false: the Rx FIFO's
    /// bits (`BUF5I`, `BUF7I`) and the remote-frame mailboxes' bits are written as
    /// configured, never changed (the register is written by `begin`, by `end`, and once
    /// split only here, inside the driver's critical section). Nothing while disabled
    /// (sleep: the driver touches no register but `MCR` then); the mask stays as it was
    /// and the transmit service after waking writes it again.
    unsafe fn set_tx_interrupt(&self, on: bool) {
        if self.mode() == MODE_SLEEP {
            return;
        }
        let reg = if self.tx_base() == 0 { IMASK1 } else { IMASK2 };
        let data = self.tx_bit(self.data_mb());
        self.regs.write32(
            reg,
            if on {
                self.tx_imask
            } else {
                self.tx_imask & !data
            },
        );
    }
    /// Identifier and data first, the control word (CODE `DATA`) last (Kinetis RM,
    /// "Transmit process"). With [`Layout::E5829`] (the RT1062 layout), the workaround
    /// of i.MX RT1060 chip errata, ERR005829 (a mailbox activated at a specific moment
    /// of the arbitration process is not transmitted in it): after the control word,
    /// INACTIVE is written twice into the control/status word of the reserved mailbox
    /// ([`Configuration::reserved_mailbox`], the first valid mailbox after the Rx FIFO
    /// area, INACTIVE since `begin`). Two contexts may do it at once (the transmit half
    /// and the transmit interrupt's refill); both write the same value.
    ///
    /// A mailbox of the quiet mode (tagged `QUIET_LOAD`) may have ended without its flag
    /// being acknowledged: its flag is cleared first (write 1 to clear; Kinetis RM,
    /// "Transmit process", step 1), before its `loaded` bit is set and its words are
    /// written, so that a transmit handler preempting the load sees either the old end
    /// (and acknowledges it before the bit is set) or no flag at all — never a stale
    /// flag on the newly activated mailbox.
    #[inline(always)]
    unsafe fn load(&self, mailbox: u8, frame: &Frame, token: Token) {
        let mb = (mailbox & !QUIET_LOAD) as usize;
        self.tokens[self.data_mb() - mb].store(token.0, Ordering::Release);
        if mailbox & QUIET_LOAD != 0 {
            self.regs.write32(self.tx_flags(), self.tx_bit(mb));
        }
        self.loaded.fetch_or(self.tx_bit(mb), Ordering::Relaxed);
        MbWords::transmit(frame).write(&self.regs, mb);
        if O::Layout::E5829 {
            let reserved = regs::mb_cs(self.configuration.reserved_mailbox() as usize);
            let inactive = cs::CODE.val(code::TX_INACTIVE);
            self.regs.write32(reserved, inactive);
            self.regs.write32(reserved, inactive);
        }
    }

    /// Each transmit mailbox with its `IFLAG1` bit set ended: code `ABORT` means
    /// aborted, anything else sent (with the TIME STAMP the hardware wrote). The flag
    /// is acknowledged and the mailbox made `INACTIVE` again (a remote-frame mailbox
    /// became a receive mailbox for the answer; an aborted one shows `ABORT`).
    unsafe fn settle<G: FnMut(Settled)>(&self, mut f: G) {
        if self.mode() == MODE_SLEEP {
            return;
        }
        let ended = self.regs.read32(self.tx_flags()) & self.tx_mask;
        if ended & ended.wrapping_sub(1) != 0 {
            // Several mailboxes ended (remote frames beside the data mailbox): out of line.
            self.settle_many(ended, &mut f);
        } else if ended != 0 {
            // One mailbox: no sorting, no list.
            if let Some(c) = self.settle_one(self.tx_base() + ended.trailing_zeros() as usize) {
                f(Settled::Done(c));
            }
        }
        self.retry_aborts();
    }

    /// The data mailbox and the remote-frame mailboxes (the ERR005829 reserved mailbox
    /// of the RT1062 layout is not one: it is never loaded).
    fn mailbox_count(&self) -> u8 {
        (1 + self.data_mb() - self.first_remote()) as u8
    }

    /// `MailboxId(0)` is the data mailbox (MB15 in ACAN's configurations in the Kinetis layout, MB16 in the RT1062 layout), `MailboxId(1..=n)` the remote-frame mailboxes in
    /// increasing MB order: `Pending` while loaded (code `DATA`, flag clear), else
    /// `Empty` (FlexCAN shows no scheduled or transmitting state per mailbox).
    fn mailbox_state(&self, mailbox: MailboxId) -> MailboxState {
        let mb = match mailbox.0 {
            0 => self.data_mb(),
            k if (k as usize) < 1 + self.data_mb() - self.first_remote() => {
                self.first_remote() + k as usize - 1
            }
            _ => return MailboxState::Empty,
        };
        if self.mode() == MODE_SLEEP {
            return MailboxState::Empty;
        }
        let done = self.regs.read32(self.tx_flags()) & self.tx_bit(mb) != 0;
        let code = cs::CODE.get(self.regs.read32(regs::mb_cs(mb)));
        if !done && code == code::TX_DATA {
            MailboxState::Pending
        } else {
            MailboxState::Empty
        }
    }

    /// Aborts the pending mailbox holding `token` ([`FlexCanHw`]'s `abort_mailboxes`:
    /// code `ABORT`, Kinetis RM "Transmission abort mechanism", written only while the
    /// module transmits nothing, which [`Hardware::prepare_abort`] waited for); the
    /// outcome comes with its `IFLAG1` bit. `false` when
    /// no mailbox holds it pending (never loaded, or ended: its completion comes from
    /// `settle`).
    unsafe fn request_abort(&self, token: Token) -> bool {
        if self.mode() == MODE_SLEEP {
            return false;
        }
        let loaded = self.loaded.load(Ordering::Relaxed);
        let first = self.first_remote();
        let data = self.data_mb();
        let holder = (first..=data).find(|&mb| {
            loaded & self.tx_bit(mb) != 0
                && self.tokens[data - mb].load(Ordering::Acquire) == token.0
        });
        match holder {
            Some(mb) => self.abort_mailboxes(self.tx_bit(mb)) != 0,
            None => false,
        }
    }

    /// When a transmit mailbox holding `token` (any, for `None`) is loaded: polls
    /// `ESR1[TX]` until the module transmits nothing, at most the acknowledge bound
    /// (the time of a frame in flight at the bit rate in force), so that the abort
    /// written next cannot race the end of a transmission (`abort_mailboxes`). Its error
    /// bits are kept for the status handler.
    fn prepare_abort(&self, token: Option<Token>) {
        if self.mode() == MODE_SLEEP {
            return;
        }
        let loaded = self.loaded.load(Ordering::Relaxed);
        let ours = match token {
            None => loaded != 0,
            Some(t) => (self.tx_base()..=self.data_mb()).any(|mb| {
                loaded & self.tx_bit(mb) != 0
                    && self.tokens[self.data_mb() - mb].load(Ordering::Acquire) == t.0
            }),
        };
        if !ours {
            return;
        }
        for _ in 0..self.polls.load(Ordering::Relaxed) {
            let esr = self.regs.read32(ESR1);
            self.keep_unreported(esr);
            if esr & esr1::TX == 0 {
                return;
            }
        }
    }

    /// Aborts every pending transmit mailbox (see `request_abort`).
    unsafe fn abort_all_mailboxes(&self) {
        if self.mode() == MODE_SLEEP {
            return;
        }
        self.abort_mailboxes(self.loaded.load(Ordering::Relaxed) & self.tx_mask);
    }

    /// `IFLAG1.BUF5I`: reads the Rx FIFO output (control/status first, Kinetis RM "Rx
    /// FIFO"), `RXFIR.IDHIT`, then pops it (write 1 to `BUF5I`). `BUF7I` (overflow:
    /// frames lost) and `BUF6I` (warning: 5 unread frames) are acknowledged and reported.
    #[inline(always)]
    unsafe fn read_rx(&self, queue: usize, events: &mut FifoEvents) -> Option<RawFrame> {
        if queue != 0 || self.mode() == MODE_SLEEP {
            return None;
        }
        let flags = self.regs.read32(IFLAG1);
        let fifo_acks = flags & (iflag1::BUF6I | iflag1::BUF7I);
        if fifo_acks != 0 {
            events.overrun |= flags & iflag1::BUF7I != 0;
            events.warning |= flags & iflag1::BUF6I != 0;
            self.regs.write32(IFLAG1, fifo_acks);
        }
        if flags & iflag1::BUF5I == 0 {
            return None;
        }
        // The generation before the frame: a frame of the old list read while
        // `install_filters` drains the FIFO carries the old generation (never the new).
        let generation = if O::FILTER_SWITCH {
            self.generation.load(Ordering::Acquire) << GENERATION_SHIFT
        } else {
            0
        };
        let w = MbWords::read(&self.regs, 0);
        let raw = [
            w.cs,
            w.id,
            w.word0,
            w.word1,
            rxfir::IDHIT.get(self.regs.read32(RXFIR)) | generation,
        ];
        self.regs.write32(IFLAG1, iflag1::BUF5I);
        Some(raw)
    }

    /// The frame and the user's filter for `IDHIT` ([`crate::FilterTable::filter_index`];
    /// [`UNKNOWN_FILTER`] when it maps to none). The driver adds the time stamp, widened
    /// from [`Hardware::raw_timestamp`] on the interrupt side.
    #[inline]
    unsafe fn decode(&self, raw: &RawFrame, _map: &()) -> Option<RxFrame> {
        // SAFETY: the receive half's context, the only one touching the table.
        let table = unsafe { &*self.table.get() };
        let [control, id, word0, word1, tagged] = *raw;
        if O::FILTER_SWITCH
            && tagged >> GENERATION_SHIFT != self.generation.load(Ordering::Relaxed) & 0xFFFF
        {
            // Accepted by a filter list replaced since: dropped (counted by the driver).
            return None;
        }
        let hit = tagged & ((1 << GENERATION_SHIFT) - 1);
        let frame = MbWords {
            cs: control,
            id,
            word0,
            word1,
        }
        .frame();
        let filter = match table.resolve(hit as usize, &frame) {
            Ok(i) => i,
            // A superset element's extra identifier: dropped and counted by the driver.
            Err(Unresolved::Superset) => return None,
            // An IDHIT the table does not produce (stale, corrupted): kept, flagged.
            Err(Unresolved::Unknown) => {
                let n = self.unresolved.load(Ordering::Relaxed);
                self.unresolved
                    .store(n.saturating_add(1), Ordering::Relaxed);
                UNKNOWN_FILTER
            }
        };
        Some(RxFrame {
            frame,
            filter,
            timestamp: None,
            hw_match: hit as u16,
        })
    }

    /// The `TIME STAMP` field of the Rx FIFO output's C/S word: the free-running timer
    /// at the start of the identifier field (Kinetis RM, "Message buffer structure");
    /// `None` without [`Options::STAMPS`] (no stamp to widen).
    #[inline(always)]
    fn raw_timestamp(&self, raw: &RawFrame) -> Option<u16> {
        O::STAMPS.then(|| MbWords::timestamp_of(raw[0]))
    }

    /// `TIMER` (Kinetis RM, "Free Running Timer (CANx_TIMER)": readable at any time,
    /// one count per bit time). `None` while disabled (sleep), where the driver touches
    /// no register but `MCR`. The read also unlocks a locked mailbox (RM "Message buffer
    /// lock mechanism"); the driver reads it only after the frame's words were read.
    fn timer_now(&self) -> Option<u16> {
        (self.mode() != MODE_SLEEP).then(|| self.timer())
    }

    /// Freeze (no frame enters the Rx FIFO; the ID table is writable only in Freeze
    /// mode, Kinetis RM "Rx FIFO"), write the table, pop and discard what the old table
    /// accepted into the FIFO, then switch the thread-side table and the generation
    /// together, and come back to the mode it was in (the table must be compiled for the
    /// configuration `begin` chose). Frames of the old list still in the driver's ring
    /// carry the old generation: `decode` drops them.
    ///
    /// The switch is not a mode change for the other contexts: the mode they read
    /// (`on_bus`, the state `error_status` reports, what `free_mailbox` allows) stays the
    /// one the application set, so a transmit half waiting for room keeps waiting and
    /// the status handler records no `Stopped` change. A mailbox loaded meanwhile is
    /// sent once the module leaves Freeze mode.
    ///
    /// Refused with [`Error::Unsupported`] without [`Options::FILTER_SWITCH`]
    /// ([`crate::options::Lean`]).
    unsafe fn install_filters(&self, filters: &Self::Filters) -> Result<(), Error> {
        if !O::FILTER_SWITCH
            || !<O::Table as InstalledTable<<O::Layout as Layout>::Table>>::REPLACEABLE
        {
            return Err(Error::Unsupported);
        }
        if filters.table_configuration() != self.configuration() {
            return Err(Error::InvalidArgument);
        }
        let mode = self.mode();
        self.freeze_for_switch(mode)?;
        FlexCan::<R, O::Layout>::write_filters(&self.regs, filters);
        // The FIFO holds at most its depth; the receive interrupt may pop some too.
        // Each frame popped here is counted (`take_filter_switch_discards`). The test
        // of BUF5I and its acknowledgement run in one critical section: a receive
        // interrupt popping the last frame between them would leave the write with
        // nothing to pop and the count one too high.
        let mut popped = 0;
        for _ in 0..2 * RX_FIFO_DEPTH {
            let did_pop = critical_section::with(|_| {
                let pending = self.regs.read32(IFLAG1) & iflag1::BUF5I != 0;
                if pending {
                    self.regs.write32(IFLAG1, iflag1::BUF5I);
                }
                pending
            });
            if !did_pop {
                break;
            }
            popped += 1;
        }
        self.discarded.fetch_add(popped, Ordering::Relaxed);
        // SAFETY: the receive half's context, the only one touching the table
        // (`ReceiveContext` borrows that half, so no copy is being read).
        unsafe { (*self.table.get()).replace(filters)? };
        let next = (self.generation.load(Ordering::Relaxed) + 1) & 0xFFFF;
        self.generation.store(next, Ordering::Release);
        self.resume_after_switch(mode)
    }

    unsafe fn filter_map(&self) {}

    /// The Rx FIFO frames `install_filters` popped in Freeze mode (writing `BUF5I`).
    unsafe fn take_filter_switch_discards(&self) -> u32 {
        self.discarded.swap(0, Ordering::Relaxed)
    }

    /// `ESR1`: the error code latched, the write-1-to-clear interrupt bits read
    /// acknowledged (exactly those), wake-up; the state from `FLTCONF` and `ECR`.
    ///
    /// An error raised between the read and the write-back sets `ERRINT` again, which
    /// the write-back clears (the flag was set when read); its error bits stay in `ESR1`
    /// and the read after the write-back takes them into `unreported`, so the caller's
    /// next call (the split driver calls again while errors are reported) counts it.
    /// `ESR1` is read once more only after a write-back, so a call with nothing to
    /// acknowledge reads it once (never twice in a row: a polled-register simulation
    /// clock would take that for a wait loop).
    unsafe fn take_status(&self) -> StatusEvents {
        if self.mode() == MODE_SLEEP {
            return StatusEvents {
                bus_error: None,
                status: self.status_now(),
                wakeup: false,
            };
        }
        let read = self.regs.read32(ESR1);
        // Error bits a state read took out of ESR1 since the last report count now.
        let esr = read | self.unreported.swap(0, Ordering::Relaxed);
        let bus_error = self.latch(esr);
        let mut now = read;
        if read & esr1::W1C_BITS != 0 {
            // Exactly the flags read: one raised after the read stays set.
            self.regs.write32(ESR1, read & esr1::W1C_BITS);
            // An error raised between the read and the write-back lost its ERRINT to
            // the write-back if ERRINT was already set; its error bits are still
            // there: read them (the next call reports them) and the state after it.
            now = self.regs.read32(ESR1);
            self.keep_unreported(now);
        }
        StatusEvents {
            bus_error,
            status: self.status_of(now),
            wakeup: read & esr1::WAKINT != 0,
        }
    }

    fn error_status(&self) -> ErrorStatus {
        self.status_now()
    }

    fn on_bus(&self) -> bool {
        self.mode() == MODE_NORMAL
    }

    unsafe fn set_mode(&self, mode: Mode) -> Result<(), Error> {
        self.mode_change(mode)
    }

    /// [`BusOffRecovery::Automatic`] (`CTRL1.BOFFREC` = 0, as ACAN): nothing to start,
    /// refused with [`Error::WrongMode`]. [`BusOffRecovery::Manual`] (`BOFFREC` = 1):
    /// when bus-off, negates `BOFFREC` — recovery begins (Kinetis RM, CTRL1 BOFFREC:
    /// before 128 × 11 recessive bits were seen it proceeds "as if the BOFFREC bit had
    /// never been asserted"; after them the module re-synchronises, 11 recessive bits,
    /// and joins the bus) — and asserts it again at once, which "will be effective only
    /// the next time the module enters Bus Off". `CTRL1.BOFFREC` is writable in any
    /// mode. Not bus-off: nothing to do, `Ok`.
    unsafe fn recover(&self) -> Result<(), Error> {
        if self.recovery == BusOffRecovery::Automatic {
            return Err(Error::WrongMode);
        }
        if self.mode() == MODE_SLEEP {
            return Ok(());
        }
        let esr = self.regs.read32(ESR1);
        self.latch(esr);
        if esr1::FLTCONF.get(esr) < esr1::FLTCONF_BUS_OFF {
            return Ok(());
        }
        self.regs.modify32(regs::CTRL1, |v| v & !ctrl1::BOFFREC);
        self.regs.modify32(regs::CTRL1, |v| v | ctrl1::BOFFREC);
        Ok(())
    }

    /// The driver's one bit-timing rule ([`crate::begin::timing_rule_in`] with the CAN
    /// clock and the bus clock `begin` was given): [`Limits::FLEXCAN_KINETIS`] (8..=25
    /// quanta per bit) and 16 bus clocks per CAN bit (Kinetis RM, FlexCAN chapter,
    /// "Arbitration and matching timing"; 1 Mbit/s from a 16 MHz bus clock, 2 Mbit/s
    /// from 32 MHz and above; with the RT1062 layout's larger tables 17 or 30 for
    /// `MCR[MAXMB]` + 1 buffers, IMXRT1060RM same section); one ID table element per exact
    /// filter of either format (format A), as many as the configuration's primary and
    /// secondary elements (ACAN §11, table 4; up to 128 with the RT1062 layout); the data
    /// mailbox and the remote-frame mailboxes;
    /// the 6-frame Rx FIFO; the 16-bit free-running timer (Kinetis RM, TIMER).
    /// No one-shot mode on these modules. No wake-up events as configured: `MCR.WAKMSK`
    /// and `MCR.SLFWAK` are never set (Kinetis RM, MCR field descriptions), so the module
    /// never raises `ESR1.WAKINT`.
    fn capabilities(&self) -> Capabilities {
        let c = self.configuration();
        let filters = (c.primary_filter_capacity() + c.secondary_filter_capacity()) as u16;
        Capabilities::new(
            self.system.can_clock_hz(),
            Limits::FLEXCAN_KINETIS,
            ModeSupport {
                loop_back: true,
                listen_only: true,
                one_shot: false,
                triple_sampling: true,
                manual_recovery: true,
                timestamps: O::STAMPS,
            },
            filters,
            filters,
            self.mailbox_count(),
            1,
            RX_FIFO_DEPTH as u8,
            Some(16),
        )
        .with_timing_rule(crate::begin::rule_in::<O::Layout>(
            self.system.can_clock_hz(),
            Some(self.bus_clock_hz),
            c,
        ))
    }

    fn bus_mode(&self) -> BusMode {
        match self.bus_mode.load(Ordering::Relaxed) {
            1 => BusMode::ListenOnly,
            2 => BusMode::LoopBack,
            _ => BusMode::Normal,
        }
    }

    fn bus_off_recovery(&self) -> BusOffRecovery {
        self.recovery
    }

    /// In Freeze mode ([`Mode::Stopped`]): the `CTRL1` timing fields (PRESDIV, RJW,
    /// PSEG1, PSEG2, SMP, PROPSEG: writable in Freeze mode only, Kinetis RM CTRL1);
    /// the acknowledge bound grows for a slower rate.
    ///
    /// The timing is judged by the rule `begin` applies and the capabilities report
    /// ([`twocan_core::hardware::check_timing_for`] with [`Hardware::capabilities`]: the
    /// register ranges, 8 quanta per bit and 16 bus clocks per CAN bit with the bus clock
    /// `begin` was given):
    /// [`TimingError::ForbiddenByManual`](twocan_core::timing::TimingError::ForbiddenByManual)
    /// when the manual's rule is broken, nothing written.
    unsafe fn set_timing(&self, timing: &Timing) -> Result<(), Error> {
        let stopped = self.mode() == MODE_STOPPED;
        twocan_core::hardware::check_timing_for(&self.capabilities(), timing, stopped)?;
        let bits = timing.flexcan_ctrl1().map_err(Error::Timing)?;
        self.regs
            .modify32(regs::CTRL1, |v| (v & !FLEXCAN_CTRL1_TIMING_MASK) | bits);
        let polls = crate::settings::handshake_polls_for(timing.actual_bitrate());
        self.polls.fetch_max(polls, Ordering::Relaxed);
        Ok(())
    }

    /// In Freeze mode ([`Mode::Stopped`]): `CTRL1.LOM` and `CTRL1.LPB` (Freeze mode
    /// only); loop-back also clears `MCR.SRXDIS` ("In this mode, MCR\[SRXDIS\] cannot
    /// be asserted"), the other modes restore it.
    unsafe fn set_bus_mode(&self, mode: BusMode) -> Result<(), Error> {
        if self.mode() != MODE_STOPPED {
            return Err(Error::WrongMode);
        }
        let (lom, lpb) = match mode {
            BusMode::Normal => (0, 0),
            BusMode::ListenOnly => (ctrl1::LOM, 0),
            BusMode::LoopBack => (0, ctrl1::LPB),
        };
        self.regs.modify32(regs::CTRL1, |v| {
            (v & !(ctrl1::LOM | ctrl1::LPB)) | lom | lpb
        });
        let srxdis = if mode != BusMode::LoopBack && self.srxdis {
            regs::mcr::SRXDIS
        } else {
            0
        };
        self.regs
            .modify32(regs::MCR, |v| (v & !regs::mcr::SRXDIS) | srxdis);
        self.bus_mode.store(bus_mode_code(mode), Ordering::Relaxed);
        self.note_tx_refused();
        Ok(())
    }
}
