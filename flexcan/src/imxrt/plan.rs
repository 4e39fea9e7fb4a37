//! What `begin` writes on the i.MX RT1062 besides the FlexCAN module, and what `end`
//! undoes: the CAN clock root, the module's clock gates, the pads.
//!
//! Order (IMXRT1060RM, CCM "Clock Switching": a clock root's multiplexer and divider are
//! changed while the clocks it feeds are gated off):
//! 0. if the root asked for differs from the one `CSCMR2` selects and another module
//!    is in use — its register-access gate on and its `MCR` no longer the reset value
//!    0x5980_000F (IMXRT1060RM, FlexCAN "Module Configuration Register (MCR)": out of
//!    reset the module is enabled in Freeze mode with `MAXMB` = 0xF and no Rx FIFO; a
//!    begun module differs whether it runs, is frozen for a filter switch or a bit-rate
//!    change, or sleeps in Disable mode, and `end` gates it off) — nothing is written
//!    and `begin` refuses with [`crate::ConfigErrors::CLOCK_ROOT_IN_USE`];
//! 1. the module's `CCGR` fields cleared;
//! 2. `CSCMR2[CAN_CLK_SEL, CAN_CLK_PODF]` written, only if they differ from the root
//!    asked for (the root is shared: a module already running on the same root is
//!    left undisturbed);
//! 3. the module's gates set (11: on in run and wait modes);
//! 4. each pad muxed (`SW_MUX_CTL_PAD_*[MUX_MODE]`), its pad control written, and the
//!    Rx signal's daisy-chain input selection pointed at the Rx pad.
//!
//! The check and the read-modify-writes of the shared CCM registers run in one critical
//! section.
//!
//! **The root is shared by CAN1, CAN2 and CAN3.** Switching it would change the bit
//! rate of a module already running on it, so it is refused (step 0): give every
//! module of a firmware the same [`crate::CanClock`], or end the running modules
//! before beginning one on another root.

use twocan_core::Registers;

use super::ccm::{ClockRoot, CCM_CSCMR2, MODULES_ON_ROOT};
use super::pads::{rx_pad, tx_pad, ImxPin, MUX_MODE, MUX_RESET, PAD_RESET};
use crate::begin_error::ConfigErrors;
use crate::regs::MCR;

/// `MCR` of an RT1062 FlexCAN module out of reset (IMXRT1060RM, FlexCAN "Module
/// Configuration Register (MCR)"): enabled, Freeze mode requested and acknowledged
/// (`FRZ`, `HALT`, `FRZACK`, `NOTRDY`), `SUPV`, `MAXMB` = 0xF.
pub const MCR_RESET: u32 = 0x5980_000F;

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

    /// Whether a module other than this plan's is in use on the root: its
    /// register-access gate on (any `CGn` value but 00) and its `MCR` other than
    /// [`MCR_RESET`]. A gated module is not read (its registers would answer with a bus
    /// error).
    fn another_module_in_use<S: Registers>(&self, sys: &S) -> bool {
        let (own_gate, own_bits) = self.clock_gate;
        MODULES_ON_ROOT.iter().any(|&(gate, bits, base)| {
            let own = gate == own_gate && bits & own_bits != 0;
            !own && sys.read32(gate) & bits != 0 && sys.read32(base + MCR) != MCR_RESET
        })
    }

    /// Steps 0–4 of the module documentation; step 0's refusal is
    /// [`ConfigErrors::CLOCK_ROOT_IN_USE`], with nothing written.
    pub fn apply<S: Registers>(&self, sys: &mut S) -> Result<(), ConfigErrors> {
        let (gate, bits) = self.clock_gate;
        critical_section::with(|_| {
            let cscmr2 = sys.read32(CCM_CSCMR2);
            let wanted = self.root.cscmr2(cscmr2);
            if wanted != cscmr2 {
                if self.another_module_in_use(sys) {
                    return Err(ConfigErrors::CLOCK_ROOT_IN_USE);
                }
                sys.modify32(gate, |v| v & !bits);
                sys.write32(CCM_CSCMR2, wanted);
            }
            sys.modify32(gate, |v| v | bits);
            Ok(())
        })?;
        for (pin, pad) in [self.tx, self.rx] {
            sys.write32(pin.mux, MUX_MODE.val(pin.alt));
            sys.write32(pin.pad_ctl, pad);
            if let Some((select, value)) = pin.daisy {
                sys.write32(select, value);
            }
        }
        Ok(())
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
