//! One bxCAN controller: its state and the software side (register reads and writes,
//! RM0410 40.9 "CAN registers").
//!
//! Register rules modelled here (the others are in the unit each register belongs to):
//! - `MCR`: bits `INRQ SLEEP TXFP RFLM NART AWUM ABOM TTCM DBF` read back as written;
//!   `RESET` forces a master reset (every register of the controller to its reset
//!   value, sleep mode, FIFOs emptied, counters cleared; the filter block is a separate
//!   block and keeps its content) and reads 0.
//! - `MCR.DBF` (debug freeze): while the simulated debug halt is asserted
//!   ([`super::BxCanModel::set_debug_halt`]) and `DBF = 1`, "CAN reception/transmission
//!   [are] frozen": the controller starts no transmission and takes no part in the next
//!   frames (no reception, no acknowledge, no error counting); its registers and FIFOs
//!   stay accessible. A frame already on the wire when the halt comes is finished (an
//!   assumption: RM0410 does not say when the freeze takes effect).
//! - `MSR`: `INAK`/`SLAK` from the mode; `ERRI`, `WKUI`, `SLAKI` are `rc_w1`; `SLAKI`
//!   is set on entering sleep mode only when `IER.SLKIE = 1`, and cleared by hardware
//!   when `SLAK` clears. `TXM` (transmitter) from the start of a frame it sends to the end
//!   of that attempt (cleared when arbitration is lost), `RXM` (receiver) from the start
//!   of a frame it receives (or loses arbitration to) to its outcome; `RX` (CANRX level)
//!   and `SAMP` (last sampled bit) show the wire's level where the bus stopped inside a
//!   frame, recessive otherwise (the model samples once per bit, so `SAMP` = `RX`).
//! - `BTR`: written only in initialization mode (`INAK = 1`); reads are always allowed.
//! - `ESR`: only `LEC` is writable. `IER`: the enable bits.
//! - Reserved bits are ignored on write and read as 0 (those of `FMR` read as in its reset
//!   value, 0x2A1C_0000); offsets that name no register, and unaligned offsets, read 0
//!   and ignore writes. CAN2 has no filter registers: its filter window reads 0 and
//!   ignores writes (RM0410 does not say what the slave's window shows).

use super::std::cell::RefCell;
use super::std::rc::Rc;

use super::errors::ErrorUnit;
use super::filters::{FilterBlock, Owner};
use super::irq::IrqLines;
use super::modes::{Mode, ModeMachine, Requests};
use super::rx::RxFifo;
use super::timer::Timer;
use super::tx::TxUnit;
use crate::regs::{self, btr, ier, mcr, msr, Instance, RX_FIFOS};

const MCR_WRITABLE: u32 = mcr::INRQ
    | mcr::SLEEP
    | mcr::TXFP
    | mcr::RFLM
    | mcr::NART
    | mcr::AWUM
    | mcr::ABOM
    | mcr::TTCM
    | mcr::DBF;
const IER_WRITABLE: u32 = ier::TMEIE
    | ier::FMPIE0
    | ier::FFIE0
    | ier::FOVIE0
    | ier::FMPIE1
    | ier::FFIE1
    | ier::FOVIE1
    | ier::EWGIE
    | ier::EPVIE
    | ier::BOFIE
    | ier::LECIE
    | ier::ERRIE
    | ier::WKUIE
    | ier::SLKIE;
const BTR_WRITABLE: u32 =
    btr::BRP.mask() | btr::TS1.mask() | btr::TS2.mask() | btr::SJW.mask() | btr::LBKM | btr::SILM;

const TX_FIRST: usize = regs::tixr(0);
const RX_FIRST: usize = regs::rixr(0);
const RX_END: usize = regs::rixr(RX_FIFOS);

/// The state of one bxCAN controller.
#[derive(Debug)]
pub(crate) struct Controller {
    pub(crate) instance: Instance,
    pub(crate) owner: Owner,
    pub(crate) filters: Rc<RefCell<FilterBlock>>,
    pub(crate) mcr: u32,
    pub(crate) modes: ModeMachine,
    pub(crate) tx: TxUnit,
    pub(crate) rx: [RxFifo; RX_FIFOS],
    pub(crate) ier: u32,
    pub(crate) btr: u32,
    pub(crate) errors: ErrorUnit,
    pub(crate) erri: bool,
    pub(crate) wkui: bool,
    pub(crate) slaki: bool,
    pub(crate) timer: Timer,
    /// The latest bus time seen (bit times).
    pub(crate) now: u64,
    /// Whether the bus has reported a time yet.
    pub(crate) time_known: bool,
    pub(crate) ack_stuck: bool,
    /// Valid frames that no filter accepted (or arrived while `FINIT = 1`).
    pub(crate) dropped: u64,
    /// `MSR.TXM`: the controller is transmitter of the frame on the wire.
    pub(crate) txm: bool,
    /// `MSR.RXM`: the controller is receiver of the frame on the wire.
    pub(crate) rxm: bool,
    /// The wire's level (true = recessive) where the bus stopped inside a frame.
    pub(crate) level: bool,
    /// The simulated debugger halts the core (the input `MCR.DBF` acts on).
    pub(crate) debug_halt: bool,
}

impl Controller {
    /// A controller fresh from reset.
    pub(crate) fn new(instance: Instance, owner: Owner, filters: Rc<RefCell<FilterBlock>>) -> Self {
        Controller {
            instance,
            owner,
            filters,
            mcr: mcr::RESET_VALUE,
            modes: ModeMachine::new(),
            tx: TxUnit::new(),
            rx: [RxFifo::new(), RxFifo::new()],
            ier: 0,
            btr: btr::RESET_VALUE,
            errors: ErrorUnit::new(),
            erri: false,
            wkui: false,
            slaki: false,
            timer: Timer::new(),
            now: 0,
            time_known: false,
            ack_stuck: false,
            dropped: 0,
            txm: false,
            rxm: false,
            level: true,
            debug_halt: false,
        }
    }

    /// Reception and transmission frozen by a debug halt (`MCR.DBF = 1`).
    pub(crate) fn frozen(&self) -> bool {
        self.debug_halt && self.has(mcr::DBF)
    }

    /// `MCR.RESET`: the controller returns to its reset state (the filter block, the bus
    /// time and injected faults stay).
    fn master_reset(&mut self) {
        let fresh = Controller::new(self.instance, self.owner, self.filters.clone());
        *self = Controller {
            now: self.now,
            time_known: self.time_known,
            ack_stuck: self.ack_stuck,
            debug_halt: self.debug_halt,
            ..fresh
        };
    }

    pub(crate) fn has(&self, bits: u32) -> bool {
        self.mcr & bits != 0
    }

    pub(crate) fn lbkm(&self) -> bool {
        self.btr & btr::LBKM != 0
    }

    pub(crate) fn silm(&self) -> bool {
        self.btr & btr::SILM != 0
    }

    pub(crate) fn mode(&self) -> Mode {
        self.modes.mode()
    }

    /// `CAN_MSR` as read.
    pub(crate) fn msr(&self) -> u32 {
        let mut v = 0;
        if self.level {
            v |= msr::SAMP | msr::RX;
        }
        if self.txm {
            v |= msr::TXM;
        }
        if self.rxm {
            v |= msr::RXM;
        }
        match self.mode() {
            Mode::Initialization => v |= msr::INAK,
            Mode::Sleep => v |= msr::SLAK,
            Mode::Normal => {}
        }
        if self.erri {
            v |= msr::ERRI;
        }
        if self.wkui {
            v |= msr::WKUI;
        }
        if self.slaki {
            v |= msr::SLAKI;
        }
        v
    }

    /// The four interrupt lines.
    pub(crate) fn irq_lines(&self) -> IrqLines {
        let txfp = self.has(mcr::TXFP);
        IrqLines::from_registers(
            self.ier,
            self.msr(),
            self.tx.tsr(txfp),
            [self.rx[0].rfr(), self.rx[1].rfr()],
        )
    }

    /// Reads the register at `offset`.
    pub(crate) fn read(&self, offset: usize) -> u32 {
        if !offset.is_multiple_of(4) {
            return 0;
        }
        match offset {
            regs::MCR => self.mcr,
            regs::MSR => self.msr(),
            regs::TSR => self.tx.tsr(self.has(mcr::TXFP)),
            regs::RF0R => self.rx[0].rfr(),
            regs::RF1R => self.rx[1].rfr(),
            regs::IER => self.ier,
            regs::ESR => self.errors.esr(),
            regs::BTR => self.btr,
            o if (TX_FIRST..RX_FIRST).contains(&o) => {
                self.tx.read((o - TX_FIRST) / 16, (o % 16) / 4)
            }
            o if (RX_FIRST..RX_END).contains(&o) => {
                self.rx[(o - RX_FIRST) / 16].output((o % 16) / 4)
            }
            o if (regs::FMR..=regs::fir2(regs::FILTER_BANKS - 1)).contains(&o) => {
                if self.owner == Owner::Slave {
                    0
                } else {
                    self.filters.borrow().read(o)
                }
            }
            _ => 0,
        }
    }

    /// A software write of `value` to the register at `offset`.
    pub(crate) fn write(&mut self, offset: usize, value: u32) {
        if !offset.is_multiple_of(4) {
            return;
        }
        match offset {
            regs::MCR => {
                if value & mcr::RESET != 0 {
                    self.master_reset();
                    return;
                }
                self.mcr = value & MCR_WRITABLE;
            }
            regs::MSR => {
                if value & msr::ERRI != 0 {
                    self.erri = false;
                }
                if value & msr::WKUI != 0 {
                    self.wkui = false;
                }
                if value & msr::SLAKI != 0 {
                    self.slaki = false;
                }
            }
            regs::TSR => self.tx.write_tsr(value),
            regs::RF0R => self.rx[0].write_rfr(value),
            regs::RF1R => self.rx[1].write_rfr(value),
            regs::IER => self.ier = value & IER_WRITABLE,
            regs::ESR => self.errors.write_esr(value),
            regs::BTR if self.mode() == Mode::Initialization => self.btr = value & BTR_WRITABLE,
            o if (TX_FIRST..RX_FIRST).contains(&o) => {
                self.tx.write((o - TX_FIRST) / 16, (o % 16) / 4, value)
            }
            o if (regs::FMR..=regs::fir2(regs::FILTER_BANKS - 1)).contains(&o)
                && self.owner != Owner::Slave =>
            {
                self.filters.borrow_mut().write(o, value)
            }
            _ => {}
        }
        self.settle();
    }

    /// Applies every consequence of the current requests: mode acknowledgements and the
    /// timer's run state.
    pub(crate) fn settle(&mut self) {
        // Each step changes the mode; three steps reach any mode.
        for _ in 0..3 {
            let r = Requests {
                inrq: self.has(mcr::INRQ),
                sleep: self.has(mcr::SLEEP),
                // RM0410 40.4.1 / 40.4.3: initialization and sleep are entered once the
                // current CAN activity (transmission or reception) has completed.
                busy: self.tx.offered().is_some() || self.txm || self.rxm,
            };
            match self.modes.step(r, self.ack_stuck) {
                Some((from, to)) => self.entered(from, to),
                None => break,
            }
        }
        let running = self.has(mcr::TTCM) && self.mode() != Mode::Sleep;
        self.timer.set_running(running, self.now);
    }

    /// Side effects of a mode change.
    pub(crate) fn entered(&mut self, from: Mode, to: Mode) {
        if from == Mode::Sleep {
            self.slaki = false;
        }
        match to {
            Mode::Sleep => {
                if self.ier & ier::SLKIE != 0 {
                    self.slaki = true;
                }
            }
            Mode::Initialization => self.errors.entered_init(),
            Mode::Normal => {
                if from == Mode::Initialization {
                    self.errors.left_init();
                }
            }
        }
    }

    /// Sets `MSR.ERRI` if an enabled error flag is set (called on error detection).
    pub(crate) fn error_detected(&mut self) {
        if self.errors.erri_condition(self.ier) {
            self.erri = true;
        }
    }
}
