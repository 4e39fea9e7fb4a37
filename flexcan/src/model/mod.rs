//! Behavioural model of the FlexCAN module (feature `model`), for host tests: the Kinetis
//! K20/K64/K66 modules (16 message buffers) and the i.MX RT1062's CAN1, CAN2 and CAN3
//! (64 message buffers; CAN3 in classic CAN).
//!
//! Written from the reference manuals' FlexCAN chapter (K20P64M72SF1RM, K66P144M180SF5RM,
//! "CAN (FlexCAN)"; IMXRT1060RM "Flexible Controller Area Network (FLEXCAN)"), never from
//! a driver: each file cites the sections its rules come from. What differs between the
//! modules is data: a [`Variant`] per chip (and RT1062 instance), `variant.rs`.
//!
//! [`FlexCanModel`] is a cheap-to-clone handle on one module's state. Software talks to it
//! through [`Registers`] (offsets of [`crate::regs`]); the simulated bus talks to it
//! through [`BusNode`]. Tests can also act as the bus by calling the `BusNode` methods
//! directly. Time is counted in bit times and only moves when the bus (or the test) says.
//!
//! What is modelled: the module disable / freeze / normal handshakes and bus
//! synchronisation, soft reset, freeze-only registers, the mailbox code state machines
//! (transmit, remote request / answer, receive with lock and overrun, abort), transmit
//! arbitration (lowest ID or lowest buffer), the Rx FIFO with its ID filter table
//! (formats A–D, individual and global masks, IDHIT), self reception, loop-back,
//! listen-only, error counters with ESR1 and bus-off recovery, the free-running timer and
//! time stamps, and the interrupt lines; on the RT1062 the 64 message buffers with
//! IMASK2/IFLAG2, RXIMR0–63, the filter tables up to 128 elements (RFFN = 0xF), reset
//! into Freeze mode, and the registers one instance has and another lacks. Not
//! modelled: ESR2, CRCR, DBG1/DBG2 contents, wake-up, stop and doze modes, DMA, CAN FD
//! (CAN3 stays classic: FDEN reads 0), the BUSY code bit, TASD and bit timing (time is
//! in bit times), and the silicon errata (listed as data in [`Variant::errata`]).

extern crate std;

mod access;
mod bus;
mod codec;
mod errors;
mod id_table;
pub mod layout;
mod mailboxes;
mod modes;
mod reception;
mod rx_fifo;
mod state;
mod timer;
pub mod variant;

pub use errors::REC_AFTER_PASSIVE_RECEPTION;
pub use variant::{Erratum, Variant};

use std::cell::RefCell;
use std::rc::Rc;

use twocan_core::error::{ErrorCounters, LastErrorCode};
use twocan_core::frame::Frame;
use twocan_core::registers::Registers;
use twocan_sim::fault::FaultConfinement;
use twocan_sim::{BusNode, BusTime, ConfinementEvent, TxRequest, TxResult};

use crate::regs::{ctrl1, esr1};

use state::State;

/// The microcontroller the module belongs to (and, where the instances differ, which
/// instance). The Kinetis parts have 16 message buffers, the RT1062 64.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Chip {
    /// MK20DX256 (Teensy 3.1/3.2): FlexCAN0.
    Mk20dx256,
    /// MK64FX512 (Teensy 3.5): FlexCAN0.
    Mk64fx512,
    /// MK66FX1M0 (Teensy 3.6): FlexCAN0 and FlexCAN1 (MCR\[WAKSRC\] exists).
    Mk66fx1m0,
    /// i.MX RT1062 (Teensy 4.0/4.1): one of its three modules.
    Imxrt1062(Rt1062Can),
}

/// A FlexCAN module of the i.MX RT1062.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Rt1062Can {
    /// CAN1 (0x401D_0000).
    Can1,
    /// CAN2 (0x401D_4000).
    Can2,
    /// CAN3 (0x401D_8000), CAN FD capable (modelled in classic CAN).
    Can3,
}

impl Chip {
    /// The module's differences, as data.
    pub const fn variant(self) -> &'static Variant {
        match self {
            Chip::Mk20dx256 => &variant::MK20DX256,
            Chip::Mk64fx512 => &variant::MK64FX512,
            Chip::Mk66fx1m0 => &variant::MK66FX1M0,
            Chip::Imxrt1062(Rt1062Can::Can1) => &variant::IMXRT1062_CAN1,
            Chip::Imxrt1062(Rt1062Can::Can2) => &variant::IMXRT1062_CAN2,
            Chip::Imxrt1062(Rt1062Can::Can3) => &variant::IMXRT1062_CAN3,
        }
    }
}

/// The module's mode as the acknowledge bits show it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ModelMode {
    /// Module Disable mode (MCR\[LPMACK\] = 1).
    Disabled,
    /// Freeze mode (MCR\[FRZACK\] = 1).
    Freeze,
    /// Normal mode (maybe not yet synchronised, maybe bus-off).
    Normal,
}

/// The module's interrupt request lines, as the Kinetis vector table groups them: "CAN0
/// ORed message buffer" (IRQ 29 on K20, 75 on K66), "Bus Off", "Error", "Tx Warning" and
/// "Rx Warning" (the two warning vectors are ORed here). Wake-up is not modelled. The
/// RT1062 has one line per module (CAN1 = IRQ 36, CAN2 = 37, CAN3 = 154), asserted
/// while [`FlexCanIrq::any`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct FlexCanIrq {
    /// (IFLAG2:IFLAG1) & (IMASK2:IMASK1) ≠ 0.
    pub message_buffer: bool,
    /// ESR1\[ERRINT\] with CTRL1\[ERRMSK\].
    pub error: bool,
    /// ESR1\[BOFFINT\] with CTRL1\[BOFFMSK\].
    pub bus_off: bool,
    /// ESR1\[TWRNINT\] with CTRL1\[TWRNMSK\], or ESR1\[RWRNINT\] with CTRL1\[RWRNMSK\].
    pub warning: bool,
}

impl FlexCanIrq {
    /// Whether any line is asserted.
    pub const fn any(&self) -> bool {
        self.message_buffer || self.error || self.bus_off || self.warning
    }
}

/// A FlexCAN module: clone the handle to give one copy to the driver (as [`Registers`])
/// and keep one for the bus and for assertions.
#[derive(Debug, Clone)]
pub struct FlexCanModel {
    inner: Rc<RefCell<State>>,
}

impl FlexCanModel {
    /// A module of `chip`, fresh from power-on reset (Disable mode on the Kinetis parts,
    /// Freeze mode on the RT1062). Message-buffer RAM and RXIMR are undefined after reset
    /// on the real part; the model starts them at 0 (see [`FlexCanModel::scramble_ram`]).
    pub fn new(chip: Chip) -> Self {
        FlexCanModel {
            inner: Rc::new(RefCell::new(State::new(chip))),
        }
    }

    /// FlexCAN0 of the MK20DX256 (Teensy 3.1/3.2).
    pub fn mk20dx256() -> Self {
        Self::new(Chip::Mk20dx256)
    }

    /// FlexCAN0 of the MK64FX512 (Teensy 3.5).
    pub fn mk64fx512() -> Self {
        Self::new(Chip::Mk64fx512)
    }

    /// FlexCAN0 or FlexCAN1 of the MK66FX1M0 (Teensy 3.6).
    pub fn mk66fx1m0() -> Self {
        Self::new(Chip::Mk66fx1m0)
    }

    /// CAN1 (`Rt1062Can::Can1`), CAN2 or CAN3 of the i.MX RT1062 (Teensy 4.0/4.1).
    pub fn imxrt1062(can: Rt1062Can) -> Self {
        Self::new(Chip::Imxrt1062(can))
    }

    /// The chip this module belongs to.
    pub fn chip(&self) -> Chip {
        self.inner.borrow().chip
    }

    /// The module's differences from the other variants.
    pub fn variant(&self) -> &'static Variant {
        self.inner.borrow().variant
    }

    /// Number of message buffers (16 on the Kinetis parts, 64 on the RT1062).
    pub fn message_buffers(&self) -> usize {
        self.inner.borrow().variant.message_buffers
    }

    // --- interrupt lines -------------------------------------------------------------------

    /// The interrupt request lines.
    pub fn irq(&self) -> FlexCanIrq {
        let mut s = self.inner.borrow_mut();
        let iflag1 = s.read(crate::regs::IFLAG1, false);
        let iflag = (s.iflag & !0xFFFF_FFFF) | u64::from(iflag1);
        let esr = s.esr1_value();
        let c = s.ctrl1;
        let on = |flag: u32, mask: u32| esr & flag != 0 && c & mask != 0;
        FlexCanIrq {
            message_buffer: iflag & s.imask != 0,
            error: on(esr1::ERRINT, ctrl1::ERRMSK),
            bus_off: on(esr1::BOFFINT, ctrl1::BOFFMSK),
            warning: on(esr1::TWRNINT, ctrl1::TWRNMSK) || on(esr1::RWRNINT, ctrl1::RWRNMSK),
        }
    }

    /// Whether any interrupt line is asserted.
    pub fn irq_pending(&self) -> bool {
        self.irq().any()
    }

    // --- fault injection -------------------------------------------------------------------

    /// Simulates a module without clock: while `stuck`, no mode handshake completes
    /// (FRZACK and LPMACK keep their value, SOFTRST stays pending). Releasing it lets the
    /// pending requests complete.
    pub fn set_freeze_ack_stuck(&self, stuck: bool) {
        let mut s = self.inner.borrow_mut();
        s.clock_stuck = stuck;
        s.settle_modes();
    }

    /// Fills message-buffer RAM and RXIMR with pseudo-random values from `seed`, as after
    /// a real power-on (their content is undefined: software must initialise them).
    pub fn scramble_ram(&self, seed: u64) {
        let mut s = self.inner.borrow_mut();
        let mut x = seed | 1;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 16) as u32
        };
        for w in s.ram.iter_mut() {
            *w = next();
        }
        for w in s.rximr.iter_mut() {
            *w = next();
        }
    }

    // --- inspection ------------------------------------------------------------------------

    /// Reads a register without its read side effects (ESR1 clear-on-read, mailbox lock and
    /// unlock), for assertions.
    pub fn peek32(&self, offset: usize) -> u32 {
        self.inner.borrow_mut().read(offset, false)
    }

    /// The module's mode.
    pub fn mode(&self) -> ModelMode {
        let s = self.inner.borrow();
        if s.disabled() {
            ModelMode::Disabled
        } else if s.frozen() {
            ModelMode::Freeze
        } else {
            ModelMode::Normal
        }
    }

    /// Whether the module is synchronised to the bus (ESR1\[SYNCH\]).
    pub fn is_synchronised(&self) -> bool {
        self.inner.borrow().on_bus()
    }

    /// Frames waiting in the Rx FIFO (0..=6).
    pub fn fifo_len(&self) -> usize {
        self.inner.borrow().fifo.len()
    }

    /// Frames lost because the Rx FIFO was full.
    pub fn fifo_overflows(&self) -> u64 {
        self.inner.borrow().fifo.overflows
    }

    /// Frames lost by overwriting an unread mailbox (OVERRUN) or the serial message buffer.
    pub fn mailbox_overruns(&self) -> u64 {
        self.inner.borrow().mbx.overruns
    }

    /// All frames lost in hardware: FIFO overflows plus mailbox overruns.
    pub fn frames_lost(&self) -> u64 {
        let s = self.inner.borrow();
        s.fifo.overflows + s.mbx.overruns
    }

    /// Frames received correctly that matched no filter and no mailbox (discarded).
    pub fn frames_discarded(&self) -> u64 {
        self.inner.borrow().discarded
    }

    /// The error counters (TEC 256 while bus-off).
    pub fn error_counters(&self) -> ErrorCounters {
        self.inner.borrow().errors.fc.counters()
    }

    /// The fault-confinement state.
    pub fn fault_confinement(&self) -> FaultConfinement {
        self.inner.borrow().errors.fc
    }

    /// The free-running timer.
    pub fn timer(&self) -> u16 {
        self.inner.borrow().timer.value()
    }

    /// The mailbox locked by a C/S read, if any.
    pub fn locked_mailbox(&self) -> Option<usize> {
        self.inner.borrow().mbx.locked
    }
}

impl Registers for FlexCanModel {
    fn read32(&self, offset: usize) -> u32 {
        self.inner.borrow_mut().read(offset, true)
    }

    fn write32(&self, offset: usize, value: u32) {
        self.inner.borrow_mut().write(offset, value);
    }
}

impl BusNode for FlexCanModel {
    fn poll_tx(&mut self, now: u64) -> Option<TxRequest> {
        self.inner.borrow().poll_tx(now)
    }

    fn acknowledges(&self) -> bool {
        self.inner.borrow().acknowledges()
    }

    fn listens(&self) -> bool {
        self.inner.borrow().listens()
    }

    fn error_active(&self) -> bool {
        self.inner.borrow().error_active()
    }

    fn tx_result(&mut self, frame: &Frame, result: TxResult, time: BusTime) {
        self.inner.borrow_mut().tx_result(frame, result, time);
    }

    fn rx(&mut self, frame: &Frame, own: bool, time: BusTime) {
        self.inner.borrow_mut().rx(frame, own, time);
    }

    fn rx_error(&mut self, code: LastErrorCode, dominant_after_flag: bool, time: BusTime) {
        self.inner
            .borrow_mut()
            .rx_error(code, dominant_after_flag, time);
    }

    fn advance(&mut self, bits: u64, idle: bool, now: u64) {
        self.inner.borrow_mut().advance(bits, idle, now);
    }

    fn next_wakeup(&self, now: u64) -> Option<u64> {
        self.inner.borrow().next_wakeup(now)
    }

    fn tx_attempt_end(&mut self, dominant_in_passive_flag: bool, time: BusTime) {
        self.inner
            .borrow_mut()
            .tx_attempt_end(dominant_in_passive_flag, time);
    }

    fn attempt_started(&mut self, transmitter: bool, time: BusTime) {
        self.inner.borrow_mut().attempt_started(transmitter, time);
    }

    fn confinement_event(&mut self, event: ConfinementEvent, time: BusTime) {
        let mut s = self.inner.borrow_mut();
        s.time_to(time.now);
        match event {
            ConfinementEvent::ArbitrationStuffException => s.arbitration_stuff_exception(),
            ConfinementEvent::FlagPenalties { transmitter, count } => {
                s.flag_penalties(transmitter, count)
            }
        }
    }
}
