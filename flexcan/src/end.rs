//! `end`: stop the module and give back what `begin` took (ACAN's `end`, which frees
//! the driver so that `begin` can run again).
//!
//! The sequence, from the Kinetis reference manuals (FlexCAN "Modes of operation",
//! "Freeze mode", "Module disable mode"; SIM "Clock gating"; PORT "Pin Control
//! Register n"):
//!
//! 1. (a module put to sleep, `MCR.MDIS` = 1, is enabled first: clear `MDIS`, wait for
//!    `LPMACK` to clear), freeze (`MCR.FRZ` = `HALT` = 1, wait `FRZACK`): a frame on the wire is finished
//!    first, so the wait is bounded by one frame time ([`crate::Settings::handshake_polls`]
//!    covers a frame in flight at the slowest rates);
//! 2. in freeze: `IMASK1` = 0, the error and warning interrupt masks of `CTRL1`
//!    cleared, `IFLAG1` and the interrupt flags of `ESR1` cleared (write 1), so no
//!    FlexCAN interrupt line stays asserted;
//! 3. module disabled (`MCR.MDIS` = 1, wait `LPMACK`);
//! 4. the Tx and Rx pins back to `MUX` = 0 and the module's SIM clock gate cleared
//!    ([`crate::system::SystemPlan::release`]).
//!
//! `end` takes the un-split [`FlexCan`]: no interrupt handler can reach a controller
//! the caller holds by value. The way back to it (issue 22 item 11):
//!
//! - from the one-struct [`twocan_core::Driver`]: [`twocan_core::Driver::release`],
//!   then [`crate::FlexCanHw::into_controller`];
//! - from the split driver under the library's interrupts (feature `rt`):
//!   `rt::IrqState::stop` masks the lines, takes the handlers back and returns the
//!   controller, then [`crate::FlexCanHw::into_controller`] and `Can0::end`;
//! - from a `static` [`twocan_core::split::State`] whose handlers the application runs
//!   itself: mask the lines, take the handlers back (`IrqCell::take`), and give them
//!   with the halves to [`twocan_core::split::State::unsplit`].
//!
//! The state is empty again afterwards: the same `static` takes the controller begun
//! anew.

use crate::system::LayoutSystem;
use twocan_core::{Error, Registers};

use crate::controller::FlexCan;
use crate::handshake;
use crate::instance::Target;
use crate::layout::Layout;
use crate::options::Options;
use crate::regs::{ctrl1, esr1, mcr, CTRL1, ESR1, IFLAG1, IFLAG2, IMASK1, IMASK2, MCR};
use crate::split::FlexCanHw;

/// `CTRL1`'s interrupt masks `begin` may set.
const CTRL1_IRQ_MASKS: u32 = ctrl1::ERRMSK | ctrl1::BOFFMSK | ctrl1::TWRNMSK | ctrl1::RWRNMSK;
/// `ESR1`'s write-1-to-clear interrupt flags.
const ESR1_IRQ_FLAGS: u32 =
    esr1::WAKINT | esr1::ERRINT | esr1::BOFFINT | esr1::RWRNINT | esr1::TWRNINT;

impl<R: Registers, L: Layout> FlexCan<R, L> {
    /// Stops the module and releases its pins and clock gate (see the [module
    /// documentation](crate::end)); gives the registers back, so that
    /// [`FlexCan::begin`] can run again. `sys` reaches the SIM and PORT registers as
    /// for `begin`.
    ///
    /// A missing acknowledge (freeze or disable, each bounded by the settings'
    /// `handshake_polls`) is [`Error::Timeout`], with the controller given back: nothing
    /// of the chip level was released then, and the module may be left frozen. Firmware
    /// uses `Can0::end` / `Can1::end`, which also give the instance token back.
    // The controller comes back by value on error (no allocator to box it in).
    #[allow(clippy::result_large_err)]
    pub fn end<S: Registers>(self, sys: &mut S) -> Result<R, (Self, Error)> {
        if let Err(e) = self.stop() {
            return Err((self, e));
        }
        self.system.release(sys);
        Ok(self.regs)
    }

    /// Steps 1–3 of the module documentation ([`crate::system::SystemPlan::release`] is step 4).
    fn stop(&self) -> Result<(), Error> {
        stop(&self.regs, self.polls, upper_flags::<L>(self.target))
    }
}

impl<R: Registers, O: Options> FlexCanHw<R, O> {
    /// [`FlexCan::end`] for a split controller taken back out of its state
    /// (`rt::IrqState::stop`, [`twocan_core::split::State::unsplit`]) whatever its
    /// table ([`crate::options`]): stops the module, releases its pins and clock gate,
    /// and gives the registers and the table back (for a `FullInSlot` controller, the
    /// `static` table to begin into again). On a missing acknowledge the controller
    /// comes back with [`Error::Timeout`], nothing of the chip level released.
    #[allow(clippy::result_large_err)]
    pub fn end<S: Registers>(self, sys: &mut S) -> Result<(R, O::Table), (Self, Error)> {
        let upper = upper_flags::<O::Layout>(self.target());
        if let Err(e) = stop(self.registers(), self.handshake_polls(), upper) {
            return Err((self, e));
        }
        self.system_plan().release(sys);
        Ok(self.into_registers_and_table())
    }
}

/// Whether `begin` may have enabled interrupts in `IMASK2` (the transmit mailboxes above
/// MB31 of the RT1062 layout): a layout with `IFLAG2` on a module of more than 32
/// message buffers (a constant `false` with [`crate::layout::Kinetis`]).
#[inline(always)]
fn upper_flags<L: Layout>(target: Target) -> bool {
    L::IFLAG2 && target.board.chip().message_buffers() > 32
}

/// Steps 1–3 of the module documentation on `regs`, each wait bounded by `polls`; with
/// `upper`, `IMASK2` and `IFLAG2` too (IMXRT1060RM "Interrupt Masks 2 register").
fn stop<R: Registers>(regs: &R, polls: u32, upper: bool) -> Result<(), Error> {
    // A module put to sleep (disabled) is enabled first: freeze is requested and
    // acknowledged only while the module is enabled ("Freeze mode"), and the
    // interrupt registers are written in freeze.
    if regs.read32(MCR) & (mcr::MDIS | mcr::LPMACK) != 0 {
        handshake::enable(regs, polls)?;
    }
    handshake::freeze(regs, polls)?;
    regs.write32(IMASK1, 0);
    regs.modify32(CTRL1, |v| v & !CTRL1_IRQ_MASKS);
    regs.write32(IFLAG1, u32::MAX);
    if upper {
        regs.write32(IMASK2, 0);
        regs.write32(IFLAG2, u32::MAX);
    }
    regs.write32(ESR1, ESR1_IRQ_FLAGS);
    handshake::disable(regs, polls)
}

#[cfg(all(
    target_os = "none",
    any(feature = "teensy32", feature = "teensy35", feature = "teensy36"),
    not(any(feature = "teensy40", feature = "teensy41"))
))]
mod firmware {
    use super::*;
    #[cfg(feature = "teensy36")]
    use crate::instance::Can1;
    use crate::instance::{Can0, Instance};
    use crate::regs::{FlexCanRegs, SystemRegs};

    #[allow(clippy::result_large_err)]
    fn end(
        controller: FlexCan<FlexCanRegs>,
        instance: Instance,
    ) -> Result<(), (FlexCan<FlexCanRegs>, Error)> {
        if controller.target().instance != instance {
            return Err((controller, Error::InvalidArgument));
        }
        // SAFETY: as in `begin`: base 0 with absolute offsets, the window SIM..PORTE;
        // `end` touches SIM_SCGC3/6 (read-modify-write in a critical section) and the
        // PCRs of this instance's pins, which the controller (from `begin`) owns.
        let mut sys = unsafe { SystemRegs::new(0) };
        controller.end(&mut sys).map(drop)
    }

    impl Can0 {
        /// ACAN `ACAN::can0.end ()`: stops FlexCAN0, releases its pins and clock gate
        /// ([`FlexCan::end`]) and gives the token back, so that [`Can0::begin`] can run
        /// again. A controller of another instance is [`Error::InvalidArgument`];
        /// either error gives the controller back.
        #[allow(clippy::result_large_err)]
        pub fn end(
            controller: FlexCan<FlexCanRegs>,
        ) -> Result<Can0, (FlexCan<FlexCanRegs>, Error)> {
            end(controller, Instance::Can0).map(|()| Can0::returned())
        }
    }

    #[cfg(feature = "teensy36")]
    impl Can1 {
        /// ACAN `ACAN::can1.end ()`: as [`Can0::end`], for FlexCAN1 (Teensy 3.6).
        #[allow(clippy::result_large_err)]
        pub fn end(
            controller: FlexCan<FlexCanRegs>,
        ) -> Result<Can1, (FlexCan<FlexCanRegs>, Error)> {
            end(controller, Instance::Can1).map(|()| Can1::returned())
        }
    }
}
