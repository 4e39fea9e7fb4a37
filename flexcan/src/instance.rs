//! FlexCAN instances and their one-time ownership tokens (ACAN §6).
//!
//! ACAN's `ACAN::can0` and `ACAN::can1` are global objects whose constructor is
//! private, so a sketch cannot make a second driver for the same module. Here the
//! same guarantee is a token taken at most once: `Can0::take` (every board) and
//! `Can1::take` (Teensy 3.6) return `Some` the first time only, and `begin`
//! consumes the token. The tokens need no `unsafe`: an atomic flag records the take.
//!
//! On the host, a controller is built over any [`twocan_core::Registers`] (the
//! behavioural model) with [`crate::FlexCan::begin`], naming the instance and the
//! board as a [`Target`].

use crate::board::{Board, Chip};
use crate::regs;

/// A FlexCAN module of the Kinetis parts (ACAN §6 table 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Instance {
    /// FlexCAN0 (`ACAN::can0`): every Teensy 3.x.
    Can0,
    /// FlexCAN1 (`ACAN::can1`): Teensy 3.6 only.
    Can1,
}

/// The interrupt numbers (NVIC IRQ numbers, vector number − 16) of one instance,
/// from the chips' vector tables (K20 and K66 reference manuals, "Interrupt channel
/// assignments"; the K64 shares the K66 numbering for FlexCAN0).
///
/// ACAN services everything from the message interrupt; the firmware enables
/// [`Irqs::message`] with [`crate::Settings::message_irq_priority`] and calls the
/// driver's `on_interrupt` from its handler. With
/// [`crate::Settings::error_interrupts`] (the default), it routes
/// [`Irqs::bus_off`], [`Irqs::error`], [`Irqs::tx_warning`] and [`Irqs::rx_warning`]
/// to the same handler.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Irqs {
    /// ORed message buffer interrupt (Rx FIFO and mailboxes).
    pub message: u16,
    /// Bus-off interrupt.
    pub bus_off: u16,
    /// Error interrupt.
    pub error: u16,
    /// Transmit warning interrupt.
    pub tx_warning: u16,
    /// Receive warning interrupt.
    pub rx_warning: u16,
    /// Wake-up interrupt.
    pub wake_up: u16,
}

impl Irqs {
    const fn from(first: u16) -> Self {
        Irqs {
            message: first,
            bus_off: first + 1,
            error: first + 2,
            tx_warning: first + 3,
            rx_warning: first + 4,
            wake_up: first + 5,
        }
    }
}

impl Instance {
    /// Base address of the module's registers (K20/K64/K66 memory maps).
    pub const fn base(self) -> usize {
        match self {
            Instance::Can0 => regs::CAN0_BASE,
            Instance::Can1 => regs::CAN1_BASE,
        }
    }

    /// The SIM clock-gate register and bit of the module (SIM_SCGC6.FLEXCAN0,
    /// SIM_SCGC3.FLEXCAN1).
    pub const fn clock_gate(self) -> (usize, u32) {
        match self {
            Instance::Can0 => (regs::sim::SIM_SCGC6, regs::sim::SCGC6_FLEXCAN0),
            Instance::Can1 => (regs::sim::SIM_SCGC3, regs::sim::SCGC3_FLEXCAN1),
        }
    }

    /// The interrupt numbers of the module on `chip` (`None` if the chip lacks it).
    pub const fn irqs(self, chip: Chip) -> Option<Irqs> {
        match (self, chip) {
            (Instance::Can0, Chip::Mk20dx256) => Some(Irqs::from(29)),
            (Instance::Can0, Chip::Mk64fx512 | Chip::Mk66fx1m0) => Some(Irqs::from(75)),
            (Instance::Can1, Chip::Mk66fx1m0) => Some(Irqs::from(94)),
            (Instance::Can1, Chip::Mk20dx256 | Chip::Mk64fx512) => None,
        }
    }
}

/// Which module on which board a controller drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Target {
    /// The board (pins, chip).
    pub board: Board,
    /// The FlexCAN module.
    pub instance: Instance,
}

impl Target {
    /// `instance` on `board`.
    pub const fn new(board: Board, instance: Instance) -> Self {
        Target { board, instance }
    }

    /// The interrupt numbers of this module (`None` if the board lacks it).
    pub const fn irqs(self) -> Option<Irqs> {
        if self.board.has(self.instance) {
            self.instance.irqs(self.board.chip())
        } else {
            None
        }
    }
}

#[cfg(any(feature = "teensy32", feature = "teensy35", feature = "teensy36"))]
pub use tokens::*;

#[cfg(any(feature = "teensy32", feature = "teensy35", feature = "teensy36"))]
mod tokens {
    use core::sync::atomic::{AtomicBool, Ordering};

    use super::{Instance, Target};
    use crate::board::Board;

    static CAN0_TAKEN: AtomicBool = AtomicBool::new(false);
    #[cfg(feature = "teensy36")]
    static CAN1_TAKEN: AtomicBool = AtomicBool::new(false);

    /// Ownership of FlexCAN0 on [`Board::DEFAULT`] (ACAN `ACAN::can0`, §6).
    #[derive(Debug)]
    pub struct Can0 {
        _private: (),
    }

    impl Can0 {
        /// The token, the first time only.
        pub fn take() -> Option<Self> {
            (!CAN0_TAKEN.swap(true, Ordering::AcqRel)).then_some(Can0 { _private: () })
        }

        /// The module this token owns.
        pub const fn target(&self) -> Target {
            Target::new(Board::DEFAULT, Instance::Can0)
        }

        /// The token again, for `end`: the controller it comes from was made from the
        /// one taken token (the flag stays set, so `take` still gives `None`).
        #[allow(dead_code)] // used by `Can0::end` on the target only
        pub(crate) const fn returned() -> Self {
            Can0 { _private: () }
        }
    }

    /// Ownership of FlexCAN1 on the Teensy 3.6 (ACAN `ACAN::can1`, §6).
    #[cfg(feature = "teensy36")]
    #[derive(Debug)]
    pub struct Can1 {
        _private: (),
    }

    #[cfg(feature = "teensy36")]
    impl Can1 {
        /// The token, the first time only.
        pub fn take() -> Option<Self> {
            (!CAN1_TAKEN.swap(true, Ordering::AcqRel)).then_some(Can1 { _private: () })
        }

        /// The module this token owns.
        pub const fn target(&self) -> Target {
            Target::new(Board::DEFAULT, Instance::Can1)
        }

        /// The token again, for `end` (see `Can0::returned`).
        #[allow(dead_code)] // used by `Can1::end` on the target only
        pub(crate) const fn returned() -> Self {
            Can1 { _private: () }
        }
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn taken_once() {
            let first = Can0::take();
            assert!(first.is_some());
            assert!(Can0::take().is_none());
            assert_eq!(first.unwrap().target().instance, Instance::Can0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn irq_numbers() {
        assert_eq!(
            Target::new(Board::Teensy32, Instance::Can0)
                .irqs()
                .unwrap()
                .message,
            29
        );
        assert_eq!(
            Target::new(Board::Teensy35, Instance::Can0)
                .irqs()
                .unwrap()
                .message,
            75
        );
        let can1 = Target::new(Board::Teensy36, Instance::Can1).irqs().unwrap();
        assert_eq!((can1.message, can1.wake_up), (94, 99));
        assert!(Target::new(Board::Teensy35, Instance::Can1)
            .irqs()
            .is_none());
    }
}
