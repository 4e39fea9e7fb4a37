//! The bxCAN controller: configuration entry points ([`Can::can1`], [`Can::can2`],
//! [`Can::can3`]), the initialization-mode value [`Init`], and the
//! [`twocan_core::Controller`] implementation the portable [`twocan_core::Driver`] uses.

use core::cell::Cell;

use twocan_core::{
    Controller, Error, ErrorCounters, ErrorState, ErrorStatus, Events, Frame, LastErrorCode,
    MailboxId, MailboxState, Mode, Priority, Registers, RxFrame, TxPolicy,
};

use crate::config::{Config, Recovery};
use crate::filter_block;
use crate::filters::{Fifo, FilterPlan, FmiMap};
use crate::instance::Instance;
use crate::mailbox;
use crate::mode;
use crate::planner::{self, FifoPolicy, PlanOptions};
use crate::regs::{esr, ier, mcr, msr, rfxr, tsr, BTR, ESR, IER, MCR, MSR, TSR, TX_MAILBOXES};

/// Register reads spent waiting for an aborted mailbox to become empty (notes "Abort":
/// a pending or scheduled mailbox is aborted at once; one on the bus finishes first, and
/// is then not waited for).
pub const ABORT_WAIT_ITERATIONS: u32 = 16;

/// An operation that failed, with the value it consumed, so nothing is lost: convert it
/// into [`Error`] with `?` or take [`Failed::value`] back.
#[derive(Debug)]
pub struct Failed<T> {
    /// Why.
    pub error: Error,
    /// What the operation was given back.
    pub value: T,
}

impl<T> From<Failed<T>> for Error {
    fn from(f: Failed<T>) -> Error {
        f.error
    }
}

/// A bxCAN instance over its registers `R` (volatile [`twocan_core::Mmio`] on target, the
/// behavioural model on the host). `F` reaches the filter registers of CAN1 for CAN2
/// (see [`Can::can2`]); CAN1 and CAN3 use their own registers and `F` is unused.
#[derive(Debug)]
pub struct Can<R: Registers, F: Registers = R> {
    pub(crate) regs: R,
    pub(crate) filter_regs: Option<F>,
    pub(crate) instance: Instance,
    pub(crate) config: Config,
    pub(crate) fmi: FmiMap,
    /// Request order of each loaded mailbox (TXFP = 1 scheduling), for `mailbox_state`.
    pub(crate) seq: [u32; TX_MAILBOXES],
    pub(crate) next_seq: u32,
    /// Mailboxes whose abort was requested (to tell an abort from a one-shot failure).
    pub(crate) abort_requested: u8,
    /// Frames read back from mailboxes whose displacement abort was still in flight.
    pub(crate) displaced: [Option<Frame>; TX_MAILBOXES],
    /// Completions noticed outside `take_events` (a reload clears RQCP), reported next.
    pub(crate) pending: Events,
    pub(crate) last_state: ErrorState,
    /// The last error code the hardware latched (`CAN_ESR.LEC`), kept after
    /// `take_events` sets LEC to 0b111 so [`Controller::error_status`] still reports it
    /// until a newer error replaces it (as the FlexCAN backend does). A `Cell` because
    /// `error_status` takes `&self` and may observe a newer LEC first.
    pub(crate) last_error: Cell<LastErrorCode>,
}

/// A controller in initialization mode (RM0410 §40.4.1), configured but off the bus.
/// Install filters with [`Init::set_filters`], then go on the bus with [`Init::enable`].
#[must_use = "the controller stays in initialization mode, off the bus, until `enable` is called"]
#[derive(Debug)]
pub struct Init<R: Registers, F: Registers = R> {
    can: Can<R, F>,
}

// The error values hand the whole controller back (nothing is lost on a timeout); its
// size (mostly the FMI map) only moves on that error path.
#[allow(clippy::result_large_err)]
impl<R: Registers> Can<R, R> {
    /// Configures CAN1 (the master, owner of the dual filter block): requests
    /// initialization mode (leaving sleep), waits for INAK (bounded), writes `CAN_MCR`
    /// options, `CAN_BTR`, `CAN_IER` and, if configured, `CAN_FMR.CAN2SB`.
    ///
    /// Errors: [`Error::Timeout`] when INAK does not come (no clock, stuck peripheral),
    /// with the registers handed back in [`Failed::value`].
    pub fn can1(regs: R, config: &Config) -> Result<Init<R, R>, Failed<Can<R, R>>> {
        Can::new(regs, None, Instance::Can1, config).configure(config)
    }

    /// Configures CAN3 (F76x/F77x: single CAN with its own 14 filter banks); as
    /// [`Can::can1`].
    pub fn can3(regs: R, config: &Config) -> Result<Init<R, R>, Failed<Can<R, R>>> {
        Can::new(regs, None, Instance::Can3, config).configure(config)
    }
}

#[allow(clippy::result_large_err)]
impl<R: Registers, F: Registers> Can<R, F> {
    /// Configures CAN2 (the slave): `regs` are CAN2's registers, `can1_filters` reaches
    /// CAN1's register block, used for the filter registers only (`CAN_FMR` ..
    /// `CAN_F27R2`, RM0410 §40.9.4: CAN2 has none of its own). CAN1 must be clocked;
    /// CAN2 owns banks `CAN2SB..28`.
    pub fn can2(
        regs: R,
        can1_filters: F,
        config: &Config,
    ) -> Result<Init<R, F>, Failed<Can<R, F>>> {
        Can::new(regs, Some(can1_filters), Instance::Can2, config).configure(config)
    }

    fn new(regs: R, filter_regs: Option<F>, instance: Instance, config: &Config) -> Self {
        Can {
            regs,
            filter_regs,
            instance,
            config: *config,
            fmi: FmiMap::empty(),
            seq: [0; TX_MAILBOXES],
            next_seq: 0,
            abort_requested: 0,
            displaced: [None; TX_MAILBOXES],
            pending: Events::default(),
            last_state: ErrorState::Stopped,
            last_error: Cell::new(LastErrorCode::None),
        }
    }

    fn configure(mut self, config: &Config) -> Result<Init<R, F>, Failed<Can<R, F>>> {
        self.config = *config;
        let bound = config.get_wait_iterations();
        if let Err(error) = mode::request(&mut self.regs, Mode::Stopped, bound) {
            return Err(Failed { error, value: self });
        }
        let keep = mcr::INRQ;
        self.regs.write32(MCR, keep | config.mcr_options());
        self.regs.write32(BTR, config.btr_value());
        self.regs.write32(IER, config.get_interrupts());
        if let (Instance::Can1, Some(start)) = (self.instance, config.get_can2_start_bank()) {
            filter_block::set_can2sb(&mut self.regs, start);
        }
        self.last_state = ErrorState::Stopped;
        Ok(Init { can: self })
    }

    /// Re-enters initialization mode with a new configuration (the filters stay).
    pub fn reconfigure(self, config: &Config) -> Result<Init<R, F>, Failed<Can<R, F>>> {
        self.configure(config)
    }

    /// Gives the register handles back (CAN1's for CAN2's filters as the second value).
    pub fn release(self) -> (R, Option<F>) {
        (self.regs, self.filter_regs)
    }

    /// The instance.
    pub fn instance(&self) -> Instance {
        self.instance
    }

    /// The operating mode the acknowledge bits (`CAN_MSR.INAK`, `SLAK`) show now.
    pub fn mode(&self) -> Mode {
        mode::current(&self.regs)
    }

    /// The configuration in force.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The registers (for inspection; writing them behind the driver's back voids its
    /// bookkeeping).
    pub fn registers(&self) -> &R {
        &self.regs
    }

    /// The registers, mutably (see [`Can::registers`]).
    pub fn registers_mut(&mut self) -> &mut R {
        &mut self.regs
    }

    /// The banks (`start..end`, hardware numbering) this instance owns now.
    pub fn bank_range(&self) -> (usize, usize) {
        match &self.filter_regs {
            Some(f) => filter_block::banks_of(f, self.instance),
            None => filter_block::banks_of(&self.regs, self.instance),
        }
    }

    /// Planner options for this instance: its bank count and `fifo`.
    pub fn plan_options(&self, fifo: FifoPolicy) -> PlanOptions {
        let (s, e) = self.bank_range();
        PlanOptions::new((e - s) as u8).fifo(fifo)
    }

    /// Compiles `filters` for this instance's banks ([`planner::plan`]).
    pub fn plan(
        &self,
        filters: &[twocan_core::Filter],
        fifo: FifoPolicy,
    ) -> Result<FilterPlan, crate::filters::PlanError> {
        planner::plan(filters, self.plan_options(fifo))
    }

    /// Clears the last error code by software (`CAN_ESR.LEC = 0b111`, "set by software":
    /// the hardware overwrites it with the next bus event); the driver's sticky copy
    /// ([`Controller::error_status`]'s `last_error`) reads [`LastErrorCode::None`] too.
    pub fn clear_last_error(&mut self) {
        self.regs.write32(ESR, esr::LEC.val(esr::LEC_SOFTWARE));
        self.last_error.set(LastErrorCode::None);
    }

    /// Reads `CAN_ESR.LEC`; a latched error code replaces the sticky copy. Returns the
    /// code just latched (`None` when LEC holds no new error).
    fn latch_last_error(&self, esr_value: u32) -> LastErrorCode {
        let code = lec(esr::LEC.get(esr_value));
        if code != LastErrorCode::None {
            self.last_error.set(code);
        }
        code
    }

    fn bound(&self) -> u32 {
        self.config.get_wait_iterations()
    }

    fn write_filters(&mut self, plan: &FilterPlan) -> Result<(), Error> {
        let instance = self.instance;
        let r = match &mut self.filter_regs {
            Some(f) => filter_block::program(f, instance, plan),
            None => filter_block::program(&mut self.regs, instance, plan),
        };
        r.map_err(|_| Error::InvalidArgument)?;
        self.fmi = plan.fmi_map();
        Ok(())
    }

    /// Counts the completion of mailbox `x` if its RQCP is set, and acknowledges it.
    /// Returns the displaced frame when `x` ended an in-flight displacement abort.
    fn complete(&mut self, x: usize, tsr_value: u32) -> Option<Frame> {
        if tsr_value & tsr::rqcp(x) == 0 {
            return None;
        }
        let bit = 1u8 << x;
        let displaced = self.displaced[x].take();
        let mut give_back = None;
        if tsr_value & tsr::txok(x) != 0 {
            self.pending.sent = self.pending.sent.saturating_add(1);
        } else if self.abort_requested & bit != 0 {
            match displaced {
                Some(f) => give_back = Some(f),
                None => self.pending.aborted = self.pending.aborted.saturating_add(1),
            }
        } else {
            self.pending.failed = self.pending.failed.saturating_add(1);
        }
        self.abort_requested &= !bit;
        self.regs.write32(TSR, tsr::rqcp(x));
        give_back
    }

    fn load(&mut self, x: usize, frame: &Frame) {
        self.seq[x] = self.next_seq;
        self.next_seq = self.next_seq.wrapping_add(1);
        mailbox::load(&mut self.regs, x, frame);
    }

    /// The pending mailbox that is lowest in the hardware's transmit order, by the
    /// policy: largest arbitration key (ties: higher mailbox number, notes "Transmit
    /// priority"), or the latest request (TXFP = 1).
    fn lowest_pending(&self, frames: &[Frame; TX_MAILBOXES]) -> usize {
        let mut low = 0;
        for x in 1..TX_MAILBOXES {
            let worse = match self.config.get_tx_policy() {
                TxPolicy::Priority => !Priority::of(&frames[x]).beats(Priority::of(&frames[low])),
                TxPolicy::Fifo => self.seq[x].wrapping_sub(self.seq[low]) < u32::MAX / 2,
            };
            if worse {
                low = x;
            }
        }
        low
    }

    fn state_now(&self) -> ErrorStatus {
        let e = self.regs.read32(ESR);
        let m = self.regs.read32(MSR);
        let boff = e & esr::BOFF != 0;
        let counters = ErrorCounters {
            tec: if boff { 256 } else { esr::TEC.get(e) as u16 },
            rec: esr::REC.get(e) as u16,
        };
        let state = if m & msr::SLAK != 0 {
            ErrorState::Sleeping
        } else if m & msr::INAK != 0 {
            ErrorState::Stopped
        } else if boff {
            ErrorState::BusOff
        } else if e & esr::EPVF != 0 {
            ErrorState::Passive
        } else if e & esr::EWGF != 0 {
            ErrorState::Warning
        } else {
            ErrorState::from_counters(counters)
        };
        self.latch_last_error(e);
        ErrorStatus {
            state,
            counters,
            last_error: self.last_error.get(),
        }
    }
}

/// Whether 16-bit time stamp `a` is not later than `b`, wrap-aware (the timer wraps
/// every 65,536 ticks: stamps less than half a period apart compare correctly).
fn older_or_same(a: u16, b: u16) -> bool {
    b.wrapping_sub(a) < 0x8000
}

/// `CAN_ESR.LEC` as a last-error code (notes "Error management": 0 none, 1 stuff, 2 form,
/// 3 acknowledgment, 4 bit recessive, 5 bit dominant, 6 CRC, 7 set by software).
pub fn lec(code: u32) -> LastErrorCode {
    match code {
        esr::LEC_STUFF => LastErrorCode::Stuff,
        esr::LEC_FORM => LastErrorCode::Form,
        esr::LEC_ACK => LastErrorCode::Acknowledge,
        esr::LEC_BIT_RECESSIVE => LastErrorCode::BitRecessive,
        esr::LEC_BIT_DOMINANT => LastErrorCode::BitDominant,
        esr::LEC_CRC => LastErrorCode::Crc,
        _ => LastErrorCode::None,
    }
}

#[allow(clippy::result_large_err)]
impl<R: Registers, F: Registers> Init<R, F> {
    /// Installs filters before going on the bus (see [`Controller::install_filters`]).
    pub fn set_filters(&mut self, plan: &FilterPlan) -> Result<(), Error> {
        self.can.write_filters(plan)
    }

    /// The controller, still in initialization mode (to plan filters for its banks).
    pub fn can(&self) -> &Can<R, F> {
        &self.can
    }

    /// The controller, still in initialization mode, mutably.
    pub fn can_mut(&mut self) -> &mut Can<R, F> {
        &mut self.can
    }

    /// Leaves initialization mode: clears INRQ and waits (bounded) for INAK = 0, which the
    /// hardware gives after 11 recessive bits on CANRX (RM0410 §40.4.2).
    ///
    /// Errors: [`Error::Timeout`], with this value handed back in [`Failed::value`].
    pub fn enable(mut self) -> Result<Can<R, F>, Failed<Init<R, F>>> {
        let bound = self.can.bound();
        match mode::request(&mut self.can.regs, Mode::Normal, bound) {
            Ok(()) => {
                self.can.last_state = self.can.state_now().state;
                Ok(self.can)
            }
            Err(error) => Err(Failed { error, value: self }),
        }
    }

    /// Gives the register handles back, leaving the peripheral in initialization mode.
    pub fn release(self) -> (R, Option<F>) {
        self.can.release()
    }
}

impl<R: Registers, F: Registers> Controller for Can<R, F> {
    type Filters = FilterPlan;

    /// Writes the plan to this instance's banks under `CAN_FMR.FINIT` (see
    /// [`crate::filter_block`]); the operating mode (`CAN_MCR`) is not touched. Error
    /// [`Error::InvalidArgument`] when the plan has more banks than the instance owns.
    fn install_filters(&mut self, filters: &FilterPlan) -> Result<(), Error> {
        self.write_filters(filters)
    }

    /// `CAN_MCR.TXFP` set: [`TxPolicy::Fifo`]; clear: [`TxPolicy::Priority`].
    fn tx_policy(&self) -> TxPolicy {
        if self.regs.read32(MCR) & mcr::TXFP != 0 {
            TxPolicy::Fifo
        } else {
            TxPolicy::Priority
        }
    }

    fn mailbox_count(&self) -> u8 {
        TX_MAILBOXES as u8
    }

    /// Loads an empty mailbox (`CAN_TSR.TMEx`), or under [`TxPolicy::Priority`] displaces
    /// the lowest-priority pending mailbox when `frame` beats it: ABRQ, then if the
    /// mailbox emptied without TXOK the frame read back from its registers is returned.
    /// A displacement whose mailbox is on the bus cannot be decided at once:
    /// `WouldBlock`, and the frame comes back from a later call once the abort ends.
    fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, Error> {
        let t = self.regs.read32(TSR);
        // A mailbox whose displacement abort has ended: reuse it, hand the frame back.
        for x in 0..TX_MAILBOXES {
            if self.displaced[x].is_some() && t & tsr::tme(x) != 0 {
                let sent = t & tsr::txok(x) != 0;
                let back = self.complete(x, t);
                let parked = self.displaced[x].take();
                self.abort_requested &= !(1 << x);
                self.load(x, frame);
                return Ok(if sent { None } else { back.or(parked) });
            }
        }
        if let Some(x) = (0..TX_MAILBOXES).find(|&x| t & tsr::tme(x) != 0) {
            let _ = self.complete(x, t);
            self.load(x, frame);
            return Ok(None);
        }
        if self.config.get_tx_policy() != TxPolicy::Priority
            || self.displaced.iter().any(Option::is_some)
        {
            return Err(nb::Error::WouldBlock);
        }
        let mut frames = [*frame; TX_MAILBOXES];
        for (x, f) in frames.iter_mut().enumerate() {
            *f = mailbox::read_tx(&self.regs, x).map_err(|e| nb::Error::Other(Error::Frame(e)))?;
        }
        let low = self.lowest_pending(&frames);
        if !Priority::of(frame).beats(Priority::of(&frames[low])) {
            return Err(nb::Error::WouldBlock);
        }
        self.abort_requested |= 1 << low;
        self.displaced[low] = Some(frames[low]);
        self.regs.write32(TSR, tsr::abrq(low));
        for _ in 0..ABORT_WAIT_ITERATIONS {
            let t = self.regs.read32(TSR);
            if t & tsr::tme(low) != 0 {
                let back = self.complete(low, t);
                self.load(low, frame);
                return Ok(back);
            }
        }
        Err(nb::Error::WouldBlock)
    }

    /// `Empty` when `CAN_TSR.TMEx`; otherwise the highest mailbox in transmit order is
    /// `Transmitting` while `CAN_MSR.TXM` is set and `Scheduled` before, the others
    /// `Pending` (notes "Transmit mailbox states"). An index ≥ 3 reads `Empty`.
    fn mailbox_state(&self, mailbox: MailboxId) -> MailboxState {
        let x = mailbox.0 as usize;
        let t = self.regs.read32(TSR);
        if x >= TX_MAILBOXES || t & tsr::tme(x) != 0 {
            return MailboxState::Empty;
        }
        let mut first = x;
        for y in (0..TX_MAILBOXES).filter(|&y| y != x && t & tsr::tme(y) == 0) {
            let ahead = match self.config.get_tx_policy() {
                TxPolicy::Fifo => self.seq[y].wrapping_sub(self.seq[first]) > u32::MAX / 2,
                TxPolicy::Priority => match (
                    mailbox::read_tx(&self.regs, y),
                    mailbox::read_tx(&self.regs, first),
                ) {
                    (Ok(a), Ok(b)) => {
                        let (pa, pb) = (Priority::of(&a), Priority::of(&b));
                        pa.beats(pb) || (pa == pb && y < first)
                    }
                    _ => false,
                },
            };
            if ahead {
                first = y;
            }
        }
        if first != x {
            MailboxState::Pending
        } else if self.regs.read32(MSR) & msr::TXM != 0 {
            MailboxState::Transmitting
        } else {
            MailboxState::Scheduled
        }
    }

    /// Sets `CAN_TSR.ABRQx` and waits [`ABORT_WAIT_ITERATIONS`] reads for TMEx: `true`
    /// when the mailbox emptied without TXOK (it was pending or scheduled). The abort is
    /// counted in [`Events::aborted`]. An index ≥ 3 returns `false`.
    ///
    /// A displacement of mailbox `x` still in flight or parked (its abort ended, the
    /// frame read back not yet handed back by [`Controller::transmit`]) is dropped: the
    /// frame is never handed back nor sent, and counts as aborted.
    fn abort(&mut self, mailbox: MailboxId) -> bool {
        let x = mailbox.0 as usize;
        if x >= TX_MAILBOXES {
            return false;
        }
        let t = self.regs.read32(TSR);
        // A displacement of this mailbox under way or parked: the abort wins, the frame
        // read back is dropped (not handed back to a later `transmit`), and it is counted
        // as aborted like any other aborted mailbox.
        if self.displaced[x].take().is_some() && t & tsr::tme(x) != 0 {
            if t & tsr::rqcp(x) != 0 {
                // Ended but not yet seen by `take_events`: sent, or now aborted.
                let _ = self.complete(x, t);
                return t & tsr::txok(x) == 0;
            }
            // Parked (RQCPx already acknowledged by `take_events`).
            self.abort_requested &= !(1 << x);
            self.pending.aborted = self.pending.aborted.saturating_add(1);
            return true;
        }
        if t & tsr::tme(x) != 0 {
            return false;
        }
        self.abort_requested |= 1 << x;
        self.regs.write32(TSR, tsr::abrq(x));
        for _ in 0..ABORT_WAIT_ITERATIONS {
            let t = self.regs.read32(TSR);
            if t & tsr::tme(x) != 0 {
                return t & tsr::txok(x) == 0;
            }
        }
        false
    }

    /// Takes the frame at the head of one receive FIFO: reads the output mailbox,
    /// releases it (`RFOMx`), maps the FMI to the user's filter index
    /// ([`crate::filters::NO_FILTER`] if the installed plan has none) and adds the time
    /// stamp when TTCM is on.
    ///
    /// Order: frames of one FIFO come in arrival order (the hardware's). Across the two
    /// FIFOs:
    /// - with time stamps on ([`Config::timestamps`], `CAN_MCR.TTCM`), the older of the
    ///   two heads by `CAN_RDTxR.TIME` (16-bit, compared wrap-aware: heads less than
    ///   32,768 timer ticks apart; ties go to FIFO 0) — arrival order is kept across FIFOs;
    /// - without, FIFO 0 first, then FIFO 1: arrival order across FIFOs is **not**
    ///   preserved (the hardware records none). Keep frames whose relative order matters
    ///   in one FIFO (`FifoPolicy::Fifo0`/`Fifo1`); `FifoPolicy::Balanced` trades that
    ///   order for more room before an overrun.
    fn receive(&mut self) -> nb::Result<RxFrame, Error> {
        let pending = |regs: &R, x: usize| rfxr::FMP.get(regs.read32(crate::regs::rfxr(x))) != 0;
        let (p0, p1) = (pending(&self.regs, 0), pending(&self.regs, 1));
        let x = match (p0, p1) {
            (false, false) => return Err(nb::Error::WouldBlock),
            (true, false) => 0,
            (false, true) => 1,
            (true, true) if self.config.get_timestamps() => {
                let t0 = mailbox::read_rx_time(&self.regs, 0);
                let t1 = mailbox::read_rx_time(&self.regs, 1);
                if older_or_same(t0, t1) {
                    0
                } else {
                    1
                }
            }
            (true, true) => 0,
        };
        let fifo = if x == 0 { Fifo::Fifo0 } else { Fifo::Fifo1 };
        let got = mailbox::read_rx(&self.regs, x);
        self.regs.write32(crate::regs::rfxr(x), rfxr::RFOM);
        let frame = got.frame.map_err(|e| nb::Error::Other(Error::Frame(e)))?;
        Ok(RxFrame {
            frame,
            filter: self.fmi.get(fifo, got.fmi),
            timestamp: if self.config.get_timestamps() {
                Some(got.time)
            } else {
                None
            },
        })
    }

    /// Reads and acknowledges (write 1 to clear): RQCPx (with TXOKx/ALSTx/TERRx) →
    /// sent / failed / aborted; FULLx, FOVRx → one overrun per FOVR occurrence (the
    /// hardware does not count lost frames); ERRI, WKUI, SLAKI; LEC (reported, then set
    /// to 0b111 by software so the next error is seen as new; the code stays readable from
    /// [`Controller::error_status`] until a newer one replaces it).
    fn take_events(&mut self) -> Events {
        let t = self.regs.read32(TSR);
        for x in 0..TX_MAILBOXES {
            // An ended displacement abort: the frame stays parked for `transmit`, which
            // hands it back (or for `abort`, which drops it). RQCPx is acknowledged now
            // all the same, so the transmit interrupt line (TMEIE) is not left asserted
            // while no transmit comes for it.
            let parked =
                self.displaced[x].is_some() && t & tsr::rqcp(x) != 0 && t & tsr::txok(x) == 0;
            if parked {
                self.abort_requested &= !(1 << x);
                self.regs.write32(TSR, tsr::rqcp(x));
            } else {
                let _ = self.complete(x, t);
            }
        }
        let mut ev = core::mem::take(&mut self.pending);
        for x in 0..2 {
            let r = self.regs.read32(crate::regs::rfxr(x));
            if r & rfxr::FOVR != 0 {
                ev.overruns = ev.overruns.saturating_add(1);
            }
            let ack = r & (rfxr::FULL | rfxr::FOVR);
            if ack != 0 {
                self.regs.write32(crate::regs::rfxr(x), ack);
            }
        }
        let m = self.regs.read32(MSR);
        let ack = m & (msr::ERRI | msr::WKUI | msr::SLAKI);
        if ack != 0 {
            self.regs.write32(MSR, ack);
        }
        ev.wakeup = m & msr::WKUI != 0;
        let code = self.latch_last_error(self.regs.read32(ESR));
        if code != LastErrorCode::None {
            ev.bus_error = Some(code);
            // LEC = 0b111 so the next error is seen as new; the sticky copy stays.
            self.regs.write32(ESR, esr::LEC.val(esr::LEC_SOFTWARE));
        }
        let state = self.state_now().state;
        ev.state_changed = m & msr::ERRI != 0 || state != self.last_state;
        self.last_state = state;
        ev
    }

    /// From `CAN_ESR` and `CAN_MSR`: sleeping (SLAK), stopped (INAK), bus-off (BOFF; TEC
    /// reported as 256), passive (EPVF), warning (EWGF), active; last error: the last
    /// code `CAN_ESR.LEC` latched, kept after `take_events` acknowledges it (sticky until
    /// a newer error or [`Can::clear_last_error`]).
    fn error_status(&self) -> ErrorStatus {
        self.state_now()
    }

    /// Normal, stopped (initialization) or sleep, with the bounded acknowledge wait.
    fn set_mode(&mut self, mode: Mode) -> Result<(), Error> {
        let bound = self.bound();
        mode::request(&mut self.regs, mode, bound)
    }

    /// Manual bus-off recovery (`ABOM = 0`, notes "Bus-off recovery"): when `BOFF` is set,
    /// enter and leave initialization mode; the hardware then waits for 128 × 11
    /// recessive bits before it is error-active again. A no-op with automatic recovery
    /// or when not bus-off.
    fn recover(&mut self) -> Result<(), Error> {
        if self.config.get_recovery() == Recovery::Automatic
            || self.regs.read32(ESR) & esr::BOFF == 0
        {
            return Ok(());
        }
        let bound = self.bound();
        mode::request(&mut self.regs, Mode::Stopped, bound)?;
        mode::request(&mut self.regs, Mode::Normal, bound)
    }
}

/// Interrupt enable bits that the driver needs serviced for a FIFO (for firmware that
/// builds its own `CAN_IER` value).
pub const fn fifo_interrupts(fifo: Fifo) -> u32 {
    ier::fmpie(fifo.index()) | ier::fovie(fifo.index())
}

#[cfg(test)]
mod tests {
    use super::older_or_same;

    #[test]
    fn time_stamps_compare_across_the_wrap() {
        assert!(older_or_same(10, 20));
        assert!(!older_or_same(20, 10));
        assert!(older_or_same(7, 7));
        assert!(older_or_same(0xFFF0, 0x0010), "0x0010 is after the wrap");
        assert!(!older_or_same(0x0010, 0xFFF0));
    }
}
