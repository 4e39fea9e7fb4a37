//! Behavioural model of the STM32 bxCAN peripheral (feature `model`), written from the
//! rules of RM0410 chapter 40 and the bxCAN lecture notes, for host tests of the driver;
//! the parts whose bxCAN differs (bank count, instances, `CAN2SB`) are described as data
//! in [`part`] from their own manuals (RM0008 for the F1, RM0090/RM0390/RM0430 for the
//! F4, RM0385/RM0410 for the F7).
//!
//! [`BxCanModel`] is a cheap, clonable handle on one controller. It implements
//! [`Registers`] — the driver's side: 32-bit reads and writes at the offsets of
//! [`crate::regs`] — and [`twocan_sim::BusNode`] — the simulated bus's side.
//!
//! - [`BxCanModel::of_part`]: every controller of a [`Part`] out of reset, sharing filter
//!   blocks as on that chip (e.g. [`part::STM32F103`]: one CAN with 14 banks;
//!   [`part::STM32F446`]: CAN1 and CAN2 sharing 28).
//! - [`BxCanModel::can1`]: CAN1 alone on an STM32F76x, with the dual-CAN filter block (CAN1
//!   uses banks `0..CAN2SB` as on the chip; set `CAN2SB = 28` to give it all 28).
//! - [`BxCanModel::can1_can2`]: CAN1 and CAN2 of an STM32F76x sharing CAN1's filter
//!   block, split at `FMR.CAN2SB`; CAN2 has no filter registers of its own.
//! - [`BxCanModel::can3`]: CAN3 of an STM32F76x with its own 14-bank filter block (no
//!   `CAN2SB`).
//!
//! The rules modelled, and the choices made where RM0410 is silent, are documented in
//! each source file: `modes.rs` (operating modes), `tx.rs` (mailboxes, `TSR`), `rx.rs`
//! (FIFOs), `filters.rs` (filter banks and match index), `errors.rs` (`ESR`, bus-off
//! recovery), `timer.rs` (TTCM time stamps), `irq.rs` (interrupt lines), `bus.rs` (test
//! modes, time, the bus contract) and `controller.rs` (register access rules).
//!
//! Frames take bus time: with `Bus::run_bits` software can access the registers while a
//! frame is on the wire (`MSR.TXM`/`RXM`/`RX`/`SAMP` show it; an `ABRQx` then waits for
//! the outcome of the mailbox in transmit state). Debug freeze (`MCR.DBF`) acts on the
//! simulated debug halt input [`BxCanModel::set_debug_halt`].
//!
//! A DLC code of 9..15 is kept as written: it goes on the simulated bus in the four DLC
//! bits with eight data bytes and lands in `RDTxR.DLC` of the receiver unchanged (the
//! bxCAN copies the DLC field; ISO 11898-1 reads such codes as eight bytes).
//!
//! Not modelled: bit timing (`BTR` is stored, the bus runs in bit times). The mailbox "transmit" state is the one `poll_tx` offered until
//! the bus reports the attempt; a mode request is acknowledged at once (after a
//! transmission in progress).
//!
//! Fault injection: [`BxCanModel::set_ack_stuck`]. Inspection without registers:
//! [`BxCanModel::state`], [`BxCanModel::fifo_contents`], [`BxCanModel::irq_lines`].
#![deny(missing_docs)]

extern crate std;

mod bus;
mod controller;
mod errors;
mod filters;
mod irq;
mod modes;
pub mod part;
mod rx;
mod timer;
mod tx;

use std::cell::RefCell;
use std::rc::Rc;
use std::vec::Vec;

use twocan_core::{ErrorCounters, Frame, MailboxState, Registers};

use crate::regs::{Instance, FILTER_BANKS, FILTER_BANKS_SINGLE, RX_FIFOS, TX_MAILBOXES};
use controller::Controller;
use filters::{FilterBlock, Owner};

pub use errors::REC_AFTER_PASSIVE_RECEPTION;
pub use irq::IrqLines;
pub use modes::Mode;
pub use part::Part;

/// A handle on one modelled bxCAN controller; clones share the same controller.
#[derive(Clone)]
pub struct BxCanModel {
    inner: Rc<RefCell<Controller>>,
    part: &'static Part,
}

impl core::fmt::Debug for BxCanModel {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let c = self.inner.borrow();
        f.debug_struct("BxCanModel")
            .field("part", &self.part.name)
            .field("instance", &c.instance)
            .field("mode", &c.mode())
            .finish_non_exhaustive()
    }
}

/// A message waiting in a receive FIFO, as the model holds it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RxEntry {
    /// The frame.
    pub frame: Frame,
    /// Its filter match index (`RDTxR.FMI`).
    pub fmi: u8,
    /// Its time stamp (`RDTxR.TIME`).
    pub time: u16,
}

/// A snapshot of a controller's internal state, for assertions in tests (read without
/// going through the registers).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ModelState {
    /// Which instance this is.
    pub instance: Instance,
    /// The operating mode (`INAK`/`SLAK`).
    pub mode: Mode,
    /// Whether the controller waits for 11 recessive bits to reach normal mode.
    pub syncing: bool,
    /// The state of each transmit mailbox.
    pub mailboxes: [MailboxState; TX_MAILBOXES],
    /// Messages pending in each receive FIFO.
    pub fifo_depth: [usize; RX_FIFOS],
    /// Messages lost by overrun in each FIFO since reset.
    pub overruns: [u64; RX_FIFOS],
    /// Valid frames dropped because no filter accepted them (or `FINIT` was set).
    pub dropped: u64,
    /// The error counters (TEC = 256 while bus-off).
    pub counters: ErrorCounters,
    /// Whether the controller is bus-off.
    pub bus_off: bool,
    /// The TTCM timer value at the latest bus time seen.
    pub timer: u16,
    /// The latest bus time the controller has seen (bit times).
    pub now: u64,
    /// Frames accepted per bank of the filter block this controller uses (shared with
    /// the other controller of a CAN1/CAN2 pair).
    pub filter_hits: [u64; FILTER_BANKS],
    /// Whether the acknowledge-stuck fault is injected.
    pub ack_stuck: bool,
}

impl BxCanModel {
    fn from_controller(c: Controller, part: &'static Part) -> Self {
        BxCanModel {
            inner: Rc::new(RefCell::new(c)),
            part,
        }
    }

    /// Every bxCAN controller of `part`, out of reset, in the order of
    /// [`Part::instances`]: CAN1 owns a block of [`Part::can1_banks`] banks, shared with
    /// CAN2 (split at `CAN2SB`) where the part has CAN2; CAN3 has its own 14 banks.
    pub fn of_part(part: &'static Part) -> Vec<Self> {
        let dual = part.dual();
        let can1_block = Rc::new(RefCell::new(FilterBlock::new(part.can1_banks, dual)));
        part.instances
            .iter()
            .map(|i| {
                let (owner, block) = match i.instance {
                    Instance::Can1 if dual => (Owner::Master, can1_block.clone()),
                    Instance::Can1 => (Owner::Single, can1_block.clone()),
                    Instance::Can2 => (Owner::Slave, can1_block.clone()),
                    Instance::Can3 => (
                        Owner::Single,
                        Rc::new(RefCell::new(FilterBlock::new(FILTER_BANKS_SINGLE, false))),
                    ),
                };
                Self::from_controller(Controller::new(i.instance, owner, block), part)
            })
            .collect()
    }

    /// CAN1 of an STM32F76x alone, out of reset, with the dual-CAN filter block (28 banks
    /// split at `CAN2SB`, 14 at reset); no CAN2 uses the upper banks.
    pub fn can1() -> Self {
        let block = Rc::new(RefCell::new(FilterBlock::new(FILTER_BANKS, true)));
        Self::from_controller(
            Controller::new(Instance::Can1, Owner::Master, block),
            &part::STM32F76X_F77X,
        )
    }

    /// CAN3 of an STM32F76x, out of reset, with its own filter block of 14 banks.
    pub fn can3() -> Self {
        let block = Rc::new(RefCell::new(FilterBlock::new(FILTER_BANKS_SINGLE, false)));
        Self::from_controller(
            Controller::new(Instance::Can3, Owner::Single, block),
            &part::STM32F76X_F77X,
        )
    }

    /// CAN1 and CAN2 of an STM32F76x, out of reset, sharing CAN1's filter block: CAN1 gets
    /// banks `0..CAN2SB`, CAN2 banks `CAN2SB..28` (RM0410 40.2, dual CAN).
    pub fn can1_can2() -> (Self, Self) {
        let block = Rc::new(RefCell::new(FilterBlock::new(FILTER_BANKS, true)));
        let can1 = Controller::new(Instance::Can1, Owner::Master, block.clone());
        let can2 = Controller::new(Instance::Can2, Owner::Slave, block);
        let part = &part::STM32F76X_F77X;
        (
            Self::from_controller(can1, part),
            Self::from_controller(can2, part),
        )
    }

    /// The part this controller belongs to.
    pub fn part(&self) -> &'static Part {
        self.part
    }

    /// Which instance this handle models.
    pub fn instance(&self) -> Instance {
        self.inner.borrow().instance
    }

    /// The levels of the TX, RX0, RX1 and SCE interrupt lines now.
    pub fn irq_lines(&self) -> IrqLines {
        self.inner.borrow().irq_lines()
    }

    /// Fault injection: while `stuck`, the controller never acknowledges a mode request
    /// (`INAK` and `SLAK` keep their values), like a controller without clock or
    /// transceiver. Clearing the fault lets pending requests complete.
    pub fn set_ack_stuck(&self, stuck: bool) {
        let mut c = self.inner.borrow_mut();
        c.ack_stuck = stuck;
        c.settle();
    }

    /// The simulated debugger halts (`true`) or resumes (`false`) the core. With
    /// `MCR.DBF = 1` reception and transmission are frozen while halted (RM0410 40.9.2
    /// `CAN_MCR.DBF`: "CAN reception/transmission frozen during debug. Reception FIFOs can
    /// still be accessed/controlled normally"); with `DBF = 0` the halt changes nothing.
    pub fn set_debug_halt(&self, halted: bool) {
        self.inner.borrow_mut().debug_halt = halted;
    }

    /// A snapshot of the internal state.
    pub fn state(&self) -> ModelState {
        let c = self.inner.borrow();
        let txfp = c.has(crate::regs::mcr::TXFP);
        let filter_hits = c.filters.borrow().hits();
        ModelState {
            instance: c.instance,
            mode: c.mode(),
            syncing: c.modes.syncing(),
            mailboxes: c.tx.states(txfp),
            fifo_depth: [c.rx[0].depth(), c.rx[1].depth()],
            overruns: [c.rx[0].overruns(), c.rx[1].overruns()],
            dropped: c.dropped,
            counters: c.errors.counters(),
            bus_off: c.errors.is_bus_off(),
            timer: c.timer.at(c.now),
            now: c.now,
            filter_hits,
            ack_stuck: c.ack_stuck,
        }
    }

    /// The messages pending in FIFO `fifo` (0 or 1), oldest first; empty for any other
    /// index.
    pub fn fifo_contents(&self, fifo: usize) -> Vec<RxEntry> {
        let c = self.inner.borrow();
        let Some(f) = c.rx.get(fifo) else {
            return Vec::new();
        };
        f.messages()
            .filter_map(|m| m.decode())
            .map(|(frame, fmi, time)| RxEntry { frame, fmi, time })
            .collect()
    }

    /// Whether `self` and `other` are handles on the same controller.
    pub fn same_controller(&self, other: &BxCanModel) -> bool {
        Rc::ptr_eq(&self.inner, &other.inner)
    }
}

impl Registers for BxCanModel {
    fn read32(&self, offset: usize) -> u32 {
        self.inner.borrow().read(offset)
    }

    fn write32(&self, offset: usize, value: u32) {
        self.inner.borrow_mut().write(offset, value);
    }
}
