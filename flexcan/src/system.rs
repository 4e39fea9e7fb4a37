//! The chip-level registers `begin` writes besides the FlexCAN module: on the Kinetis
//! parts the SIM clock gates and the PORT pin control of the Tx and Rx pins (reference
//! manuals, chapters "SIM" and "PORT"; ACAN §7, §16.7.5, §16.7.6), [`PortPlan`]; on the
//! i.MX RT1062 the CCM clock root and gates and the IOMUXC pads,
//! [`crate::imxrt::ImxrtPlan`]. [`SystemPlan`] is either, chosen by the target's chip.
//!
//! They are reached through a [`Registers`] whose offsets are absolute addresses. On
//! the target that is [`crate::regs::SystemRegs`] at base 0 (see `Can0::begin`); on the host
//! [`HostSystem`] stands in and remembers what was written, so tests can check the
//! pin set-up.

use core::cell::{Ref, RefCell};

use twocan_core::Registers;

use crate::begin_error::ConfigErrors;
use crate::board::InstancePins;
use crate::imxrt::ImxrtPlan;
use crate::regs::pins::CanPin;
use crate::regs::port::{PCR_MUX, PCR_ODE, PCR_PE, PCR_PS};
use crate::regs::sim;

/// Host stand-in for the SIM and PORT registers: reads give back the last value
/// written to an address (0 before any write). It holds up to 16 addresses; writes
/// beyond are dropped, which `begin` (5 addresses) never reaches.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct HostSystem {
    cells: RefCell<([(usize, u32); 16], usize)>,
}

impl HostSystem {
    /// An empty register space.
    pub const fn new() -> Self {
        HostSystem {
            cells: RefCell::new(([(0, 0); 16], 0)),
        }
    }

    /// The addresses written so far, with their values, in first-write order.
    pub fn written(&self) -> Ref<'_, [(usize, u32)]> {
        Ref::map(self.cells.borrow(), |(cells, len)| &cells[..*len])
    }
}

impl Registers for HostSystem {
    fn read32(&self, offset: usize) -> u32 {
        self.written()
            .iter()
            .find(|(a, _)| *a == offset)
            .map_or(0, |(_, v)| *v)
    }

    fn write32(&self, offset: usize, value: u32) {
        let mut guard = self.cells.borrow_mut();
        let (cells, len) = &mut *guard;
        if let Some(cell) = cells[..*len].iter_mut().find(|(a, _)| *a == offset) {
            cell.1 = value;
        } else if let Some(cell) = cells.get_mut(*len) {
            *cell = (offset, value);
            *len += 1;
        }
    }
}

/// The PCR value of the Tx pin: CAN function, open drain if asked (ACAN §16.7.5).
pub const fn tx_pcr(pin: CanPin, open_collector: bool) -> u32 {
    PCR_MUX.val(pin.alt) | if open_collector { PCR_ODE } else { 0 }
}

/// The PCR value of the Rx pin: CAN function, pull-up if asked (ACAN §16.7.6).
pub const fn rx_pcr(pin: CanPin, pull_up: bool) -> u32 {
    PCR_MUX.val(pin.alt) | if pull_up { PCR_PE | PCR_PS } else { 0 }
}

/// What `begin` writes to the chip-level registers, computed before anything is
/// written: the Kinetis or the i.MX RT form.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SystemPlan {
    /// Kinetis: SIM gates and PORT pin control.
    Kinetis(PortPlan),
    /// i.MX RT1062: CCM clock root and gates, IOMUXC pads.
    Imxrt(ImxrtPlan),
}

impl SystemPlan {
    /// The Kinetis plan (`None` on the RT1062).
    pub const fn kinetis(&self) -> Option<&PortPlan> {
        match self {
            SystemPlan::Kinetis(p) => Some(p),
            SystemPlan::Imxrt(_) => None,
        }
    }

    /// The RT1062 plan (`None` on a Kinetis part).
    pub const fn imxrt(&self) -> Option<&ImxrtPlan> {
        match self {
            SystemPlan::Imxrt(p) => Some(p),
            SystemPlan::Kinetis(_) => None,
        }
    }

    /// The Teensy pin numbers of the Tx and Rx pins.
    pub const fn teensy_pins(&self) -> (u8, u8) {
        match self {
            SystemPlan::Kinetis(p) => (p.tx.0.teensy_pin, p.rx.0.teensy_pin),
            SystemPlan::Imxrt(p) => (p.tx.0.teensy_pin, p.rx.0.teensy_pin),
        }
    }

    /// The protocol engine clock in Hz: the 16 MHz oscillator (Kinetis) or the CCM
    /// clock root the plan sets (RT1062).
    pub const fn can_clock_hz(&self) -> u32 {
        match self {
            SystemPlan::Kinetis(_) => crate::settings::CAN_CLOCK_HZ,
            SystemPlan::Imxrt(p) => p.root.hz(),
        }
    }

    /// The module's clock gate (register, bits).
    pub const fn clock_gate(&self) -> (usize, u32) {
        match self {
            SystemPlan::Kinetis(p) => p.clock_gate,
            SystemPlan::Imxrt(p) => p.clock_gate,
        }
    }

    /// Enables the clocks and muxes the pins ([`PortPlan::apply`],
    /// [`ImxrtPlan::apply`]); on the i.MX RT1062, refuses to switch the clock root
    /// under a running module ([`ConfigErrors::CLOCK_ROOT_IN_USE`], nothing written).
    pub fn apply<S: Registers>(&self, sys: &mut S) -> Result<(), ConfigErrors> {
        match self {
            SystemPlan::Kinetis(p) => LayoutSystem::apply(p, sys),
            SystemPlan::Imxrt(p) => LayoutSystem::apply(p, sys),
        }
    }

    /// Releases the pins and the module's clock gate ([`PortPlan::release`],
    /// [`ImxrtPlan::release`]).
    pub fn release<S: Registers>(&self, sys: &mut S) {
        match self {
            SystemPlan::Kinetis(p) => p.release(sys),
            SystemPlan::Imxrt(p) => p.release(sys),
        }
    }
}

/// The chip-level plan a controller of one message-buffer layout keeps for `end`
/// ([`crate::layout::Layout::System`]): the Kinetis [`PortPlan`] or the RT1062's
/// [`ImxrtPlan`]. A controller keeps only its own chip family's plan (issue 21: 32 B on
/// a Kinetis part rather than a [`SystemPlan`] sized for the RT1062's pads).
pub trait LayoutSystem: Copy + core::fmt::Debug + Send + Sync + 'static {
    /// This layout's plan out of `plan` (`None`: a plan of the other chip family, which
    /// `begin` refuses for this layout, [`ConfigErrors::LAYOUT_NOT_FOR_CHIP`]).
    fn from_plan(plan: &SystemPlan) -> Option<Self>;
    /// As a [`SystemPlan`].
    fn to_plan(&self) -> SystemPlan;
    /// Enables the clocks and muxes the pins ([`SystemPlan::apply`]).
    fn apply<S: Registers>(&self, sys: &mut S) -> Result<(), ConfigErrors>;
    /// Releases the pins and the module's clock gate ([`SystemPlan::release`]).
    fn release<S: Registers>(&self, sys: &mut S);
    /// The protocol engine clock in Hz ([`SystemPlan::can_clock_hz`]).
    fn can_clock_hz(&self) -> u32;
}

impl LayoutSystem for PortPlan {
    fn from_plan(plan: &SystemPlan) -> Option<Self> {
        plan.kinetis().copied()
    }
    fn to_plan(&self) -> SystemPlan {
        SystemPlan::Kinetis(*self)
    }
    fn apply<S: Registers>(&self, sys: &mut S) -> Result<(), ConfigErrors> {
        PortPlan::apply(self, sys);
        Ok(())
    }
    fn release<S: Registers>(&self, sys: &mut S) {
        PortPlan::release(self, sys)
    }
    fn can_clock_hz(&self) -> u32 {
        crate::settings::CAN_CLOCK_HZ
    }
}

impl LayoutSystem for ImxrtPlan {
    fn from_plan(plan: &SystemPlan) -> Option<Self> {
        plan.imxrt().copied()
    }
    fn to_plan(&self) -> SystemPlan {
        SystemPlan::Imxrt(*self)
    }
    fn apply<S: Registers>(&self, sys: &mut S) -> Result<(), ConfigErrors> {
        ImxrtPlan::apply(self, sys)
    }
    fn release<S: Registers>(&self, sys: &mut S) {
        ImxrtPlan::release(self, sys)
    }
    fn can_clock_hz(&self) -> u32 {
        self.root.hz()
    }
}

/// The Kinetis chip-level writes: SIM clock gates, PORT pin control.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PortPlan {
    /// The module's clock gate (register, bit).
    pub clock_gate: (usize, u32),
    /// The Tx pin and its PCR value.
    pub tx: (CanPin, u32),
    /// The Rx pin and its PCR value.
    pub rx: (CanPin, u32),
}

impl PortPlan {
    /// The plan for the chosen pins.
    pub const fn new(
        clock_gate: (usize, u32),
        tx: CanPin,
        rx: CanPin,
        open_collector: bool,
        pull_up: bool,
    ) -> Self {
        PortPlan {
            clock_gate,
            tx: (tx, tx_pcr(tx, open_collector)),
            rx: (rx, rx_pcr(rx, pull_up)),
        }
    }

    /// Enables the clocks (ports, then the module: a FlexCAN register access with its
    /// gate closed faults) and muxes the pins. The read-modify-writes of the shared
    /// SIM registers run in a critical section.
    pub fn apply<S: Registers>(&self, sys: &mut S) {
        let ports = self.tx.0.port.scgc5_bit() | self.rx.0.port.scgc5_bit();
        let (gate, bit) = self.clock_gate;
        critical_section::with(|_| {
            sys.modify32(sim::SIM_SCGC5, |v| v | ports);
            sys.modify32(gate, |v| v | bit);
        });
        sys.write32(self.tx.0.pcr(), self.tx.1);
        sys.write32(self.rx.0.pcr(), self.rx.1);
    }
}

impl PortPlan {
    /// Undoes [`PortPlan::apply`] for the module (`end`): the Tx and Rx pins back to
    /// their reset function — `PORTx_PCRn` written 0, `MUX` = 000 "pin disabled
    /// (analog)" with no pull or open drain ("PORT", "Pin Control Register n") — then
    /// the module's clock gate cleared (`SIM_SCGC6.FLEXCAN0` or `SIM_SCGC3.FLEXCAN1`,
    /// "SIM": the module must not be accessed afterwards; call it once the module is
    /// disabled, `MCR.LPMACK` = 1). The port clock gates stay as they are: other pins of
    /// the same ports may be in use. The read-modify-write of SIM runs in a critical
    /// section.
    pub fn release<S: Registers>(&self, sys: &mut S) {
        sys.write32(self.tx.0.pcr(), 0);
        sys.write32(self.rx.0.pcr(), 0);
        let (gate, bit) = self.clock_gate;
        critical_section::with(|_| sys.modify32(gate, |v| v & !bit));
    }
}

/// Picks the pins (ACAN §7). `Err((no_tx, no_rx))` says which alternate was asked
/// for but does not exist.
pub const fn choose_pins(
    pins: InstancePins,
    alternate_tx: bool,
    alternate_rx: bool,
) -> Result<(CanPin, CanPin), (bool, bool)> {
    let tx = match (alternate_tx, pins.alternate_tx) {
        (false, _) => Some(pins.tx),
        (true, alt) => alt,
    };
    let rx = match (alternate_rx, pins.alternate_rx) {
        (false, _) => Some(pins.rx),
        (true, alt) => alt,
    };
    match (tx, rx) {
        (Some(tx), Some(rx)) => Ok((tx, rx)),
        (tx, rx) => Err((tx.is_none(), rx.is_none())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::board::Board;
    use crate::instance::Instance;
    use crate::regs::port::Port;

    #[test]
    fn host_system_remembers() {
        let s = HostSystem::new();
        assert_eq!(s.read32(0x10), 0);
        s.write32(0x10, 5);
        s.modify32(0x10, |v| v | 2);
        assert_eq!(s.read32(0x10), 7);
        for a in 0..20 {
            s.write32(0x100 + a, 1);
        }
        assert_eq!(s.written().len(), 16);
    }

    #[test]
    fn pin_setup() {
        let pins = Board::Teensy36.pins(Instance::Can1).unwrap();
        assert_eq!(choose_pins(pins, true, true), Err((true, true)));
        assert_eq!(choose_pins(pins, false, true), Err((false, true)));
        let (tx, rx) =
            choose_pins(Board::Teensy32.pins(Instance::Can0).unwrap(), true, false).unwrap();
        assert_eq!((tx.teensy_pin, rx.teensy_pin), (32, 4));
        let gate = Instance::Can0.clock_gate(Board::Teensy32.chip()).unwrap();
        let plan = PortPlan::new(gate, tx, rx, true, true);
        let mut sys = HostSystem::new();
        plan.apply(&mut sys);
        assert_eq!(sys.read32(sim::SIM_SCGC6), sim::SCGC6_FLEXCAN0);
        assert_eq!(
            sys.read32(sim::SIM_SCGC5),
            sim::SCGC5_PORTA | sim::SCGC5_PORTB
        );
        assert_eq!(sys.read32(Port::B.pcr(18)), 0x200 | PCR_ODE);
        assert_eq!(sys.read32(Port::A.pcr(13)), 0x200 | PCR_PE | PCR_PS);

        // `end`: pins back to MUX 0, the module's gate cleared, the port gates kept.
        sys.write32(sim::SIM_SCGC6, sim::SCGC6_FLEXCAN0 | 1 << 9);
        plan.release(&mut sys);
        assert_eq!(sys.read32(sim::SIM_SCGC6), 1 << 9);
        assert_eq!(sys.read32(Port::B.pcr(18)), 0);
        assert_eq!(sys.read32(Port::A.pcr(13)), 0);
        assert_eq!(
            sys.read32(sim::SIM_SCGC5),
            sim::SCGC5_PORTA | sim::SCGC5_PORTB
        );
    }
}
