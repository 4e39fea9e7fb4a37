//! What `begin` writes on the i.MX RT1062 besides the FlexCAN module, and what `end`
//! undoes: the CAN clock root, the module's clock gates, the pads.
//!
//! Order (IMXRT1060RM, CCM "Clock Switching": a clock root's multiplexer and divider are
//! changed while the clocks it feeds are gated off):
//! 1. the module's `CCGR` fields cleared;
//! 2. `CSCMR2[CAN_CLK_SEL, CAN_CLK_PODF]` written, only if they differ from the root
//!    asked for (the root is shared: a module already running on the same root is
//!    left undisturbed);
//! 3. the module's gates set (11: on in run and wait modes);
//! 4. each pad muxed (`SW_MUX_CTL_PAD_*[MUX_MODE]`), its pad control written, and the
//!    Rx signal's daisy-chain input selection pointed at the Rx pad.
//!
//! The read-modify-writes of the shared CCM registers run in a critical section.
//!
//! **The root is shared by CAN1, CAN2 and CAN3.** Beginning one module on another root
//! than a running one changes the running module's bit rate: give every module of a
//! firmware the same [`crate::CanClock`].

use twocan_core::Registers;

use super::ccm::{ClockRoot, CCM_CSCMR2};
use super::pads::{rx_pad, tx_pad, ImxPin, MUX_MODE, MUX_RESET, PAD_RESET};

/// The chip-level writes of one RT1062 FlexCAN module.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImxrtPlan {
    /// The module's clock gates: the `CCGR` register and its bits.
    pub clock_gate: (usize, u32),
    /// The CAN clock root.
    pub root: ClockRoot,
    /// The Tx pin and its pad control value.
    pub tx: (ImxPin, u32),
    /// The Rx pin and its pad control value.
    pub rx: (ImxPin, u32),
}

impl ImxrtPlan {
    /// The plan for these pins, gate and root.
    pub const fn new(
        clock_gate: (usize, u32),
        root: ClockRoot,
        tx: ImxPin,
        rx: ImxPin,
        open_drain: bool,
        pull_up: bool,
    ) -> Self {
        ImxrtPlan {
            clock_gate,
            root,
            tx: (tx, tx_pad(open_drain)),
            rx: (rx, rx_pad(pull_up)),
        }
    }

    /// Steps 1–4 of the module documentation.
    pub fn apply<S: Registers>(&self, sys: &mut S) {
        let (gate, bits) = self.clock_gate;
        critical_section::with(|_| {
            let cscmr2 = sys.read32(CCM_CSCMR2);
            let wanted = self.root.cscmr2(cscmr2);
            if wanted != cscmr2 {
                sys.modify32(gate, |v| v & !bits);
                sys.write32(CCM_CSCMR2, wanted);
            }
            sys.modify32(gate, |v| v | bits);
        });
        for (pin, pad) in [self.tx, self.rx] {
            sys.write32(pin.mux, MUX_MODE.val(pin.alt));
            sys.write32(pin.pad_ctl, pad);
            if let Some((select, value)) = pin.daisy {
                sys.write32(select, value);
            }
        }
    }

    /// Undoes [`ImxrtPlan::apply`] for the module (`end`): the pads back to their reset
    /// function and control (ALT5 GPIO, 0x10B0), then the module's gates cleared (the
    /// module must not be accessed afterwards). The clock root stays: the other modules
    /// may run on it.
    pub fn release<S: Registers>(&self, sys: &mut S) {
        for (pin, _) in [self.tx, self.rx] {
            sys.write32(pin.mux, MUX_RESET);
            sys.write32(pin.pad_ctl, PAD_RESET);
        }
        let (gate, bits) = self.clock_gate;
        critical_section::with(|_| sys.modify32(gate, |v| v & !bits));
    }
}
