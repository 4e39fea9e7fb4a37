//! Hand-over from `imxrt-ral` (feature `imxrt-ral` with `teensy40` or `teensy41`): a
//! Teensy 4 FlexCAN module begun from the RAL instances a program already owns — as
//! `imxrt-hal` and `teensy4-bsp` programs do (`board::instances()`) — with no `unsafe` in
//! the program, and the instances given back by `free`.
//!
//! [`hand_over`] takes the module's RAL instance (`imxrt_ral::can::CAN1`, `CAN2` or
//! `imxrt_ral::can3::CAN3`) and the CCM's (`imxrt_ral::ccm::CCM`) **by value**: owning
//! them is the proof that nothing else reaches the module's registers or the CCM
//! registers `begin` writes (the CAN clock root in `CCM_CSCMR2` and the module's gates in
//! `CCM_CCGR0`/`CCM_CCGR7`, IMXRT1060RM "Clock Controller Module (CCM)"). `begin` also
//! writes the IOMUXC registers of the module's two Teensy pads and its Rx daisy select
//! ([`crate::imxrt::pads`]); the program must not give those pads to another function.
//!
//! - before `begin`, [`HandOver::free`] gives the instances back;
//! - `HandOver::begin` configures the module as `Can1::begin` does — in the RT1062
//!   layout ([`Imxrt1062`]: the ERR005829 workaround, tables up to RFFN 0xF) — and
//!   returns the controller with a [`Parked`] value holding the instances;
//! - when the controller comes back (from [`crate::FlexCanHw::into_controller`] after
//!   the driver, or unsplit), `Parked::free` ends it ([`crate::FlexCan::end`]: module
//!   stopped, pads and gates released) and gives the instances back — only in exchange
//!   for the controller of that module, so the driver can no longer reach it.
//!
//! The board is the one the board feature selects ([`Board::DEFAULT`]): CAN1 on pins
//! 22/23, CAN2 on 1/0, CAN3 on 31/30 of a Teensy 4.0 or 4.1.
//!
//! On the host (no `target_os = "none"`), [`HandOver::begin_over`] and
//! [`Parked::free_over`] run the same steps over given registers (the behavioural
//! model), for tests; `begin` and `free` reach the chip's registers and exist on the
//! target only.

use imxrt_ral as ral;
use twocan_core::{Error, Filter, Registers};

use crate::begin_error::BeginError;
use crate::board::Board;
use crate::controller::FlexCan;
use crate::instance::{Instance, Target};
use crate::layout::Imxrt1062;
use crate::settings::Settings;

mod sealed {
    /// Keeps [`super::RalCan`] to the RAL's three FlexCAN instances.
    pub trait Sealed {}
}

/// A RAL FlexCAN instance of the i.MX RT1062: `imxrt_ral::can::CAN1`, `CAN2`,
/// `imxrt_ral::can3::CAN3`.
pub trait RalCan: sealed::Sealed {
    /// The module.
    const INSTANCE: Instance;

    /// The address of the instance's register block (the RAL's pointer).
    fn address(&self) -> usize;
}

macro_rules! ral_can {
    ($ty:ty, $instance:ident) => {
        impl sealed::Sealed for $ty {}
        impl RalCan for $ty {
            const INSTANCE: Instance = Instance::$instance;
            fn address(&self) -> usize {
                core::ptr::from_ref::<<$ty as core::ops::Deref>::Target>(self) as usize
            }
        }
    };
}

ral_can!(ral::can::CAN1, Can1);
ral_can!(ral::can::CAN2, Can2);
ral_can!(ral::can3::CAN3, Can3);

/// The CCM's RAL instance.
pub type Ccm = ral::ccm::CCM;

/// The controller a hand-over begins: the module in the RT1062 layout ([`Imxrt1062`]:
/// the ERR005829 workaround, tables up to RFFN 0xF).
pub type Controller<R = crate::regs::FlexCanRegs> = FlexCan<R, Imxrt1062>;

/// A module handed over, not begun yet.
pub struct HandOver<C: RalCan> {
    can: C,
    ccm: Ccm,
}

/// Takes the module's RAL instance and the CCM's by value (see the module notes).
pub fn hand_over<C: RalCan>(can: C, ccm: Ccm) -> HandOver<C> {
    HandOver { can, ccm }
}

impl<C: RalCan> HandOver<C> {
    /// The module on [`Board::DEFAULT`].
    pub const fn target(&self) -> Target {
        Target::new(Board::DEFAULT, C::INSTANCE)
    }

    /// Gives the instances back.
    pub fn free(self) -> (C, Ccm) {
        (self.can, self.ccm)
    }

    /// ACAN's `begin` (§15) on the module: clock root, gates, pads, then the module,
    /// as `Can1::begin` (`Can2`, `Can3`); the controller and the parked instances, or
    /// the hand-over back with the reason.
    #[cfg(target_os = "none")]
    #[allow(clippy::result_large_err)]
    pub fn begin(
        self,
        settings: &Settings,
        primary: &[Filter],
        secondary: &[Filter],
    ) -> Result<(Controller, Parked<C>), (Self, BeginError)> {
        let Some(base) = self.target().base() else {
            return Err((
                self,
                BeginError::Config(crate::ConfigErrors::NO_SUCH_INSTANCE),
            ));
        };
        debug_assert_eq!(base, self.can.address());
        // SAFETY: the module's RAL instance is owned by value here and kept in the
        // `Parked` value until the controller comes back: this is the only access to
        // the module's registers, at the reference-manual base (equal to the RAL's).
        let regs = unsafe { crate::regs::FlexCanRegs::new(base) };
        self.begin_over(
            regs,
            &mut super::firmware::system(),
            settings,
            primary,
            secondary,
        )
    }

    /// `HandOver::begin` over `regs` for the module and `sys` for the CCM and
    /// IOMUXC (absolute offsets): on the host, the behavioural model and
    /// [`crate::HostSystem`]. The RT1062 layout, as `HandOver::begin`
    /// ([`FlexCan::begin_with_layout`]).
    #[allow(clippy::result_large_err)]
    pub fn begin_over<R: Registers, S: Registers>(
        self,
        regs: R,
        sys: &mut S,
        settings: &Settings,
        primary: &[Filter],
        secondary: &[Filter],
    ) -> Result<(Controller<R>, Parked<C>), (Self, BeginError)> {
        match FlexCan::<R, Imxrt1062>::begin_with_layout(
            regs,
            sys,
            self.target(),
            settings,
            primary,
            secondary,
        ) {
            Ok(controller) => Ok((
                controller,
                Parked {
                    can: self.can,
                    ccm: self.ccm,
                },
            )),
            Err(e) => Err((self, e)),
        }
    }
}

/// The instances of a begun module, given back for its controller (`Parked::free`).
pub struct Parked<C: RalCan> {
    can: C,
    ccm: Ccm,
}

impl<C: RalCan> Parked<C> {
    /// Ends `controller` ([`FlexCan::end`]: stopped, pads and gates released) and gives
    /// the instances back. A controller of another module is [`Error::InvalidArgument`];
    /// either error gives both back.
    #[cfg(target_os = "none")]
    #[allow(clippy::result_large_err, clippy::type_complexity)]
    pub fn free(self, controller: Controller) -> Result<(C, Ccm), (Self, Controller, Error)> {
        self.free_over(controller, &mut super::firmware::system())
            .map(|(can, ccm, _)| (can, ccm))
    }

    /// `Parked::free` with `sys` for the CCM and IOMUXC; also gives the module's
    /// registers back (the model on the host).
    #[allow(clippy::result_large_err, clippy::type_complexity)]
    pub fn free_over<R: Registers, S: Registers>(
        self,
        controller: Controller<R>,
        sys: &mut S,
    ) -> Result<(C, Ccm, R), (Self, Controller<R>, Error)> {
        if controller.target() != Target::new(Board::DEFAULT, C::INSTANCE) {
            return Err((self, controller, Error::InvalidArgument));
        }
        match controller.end(sys) {
            Ok(regs) => Ok((self.can, self.ccm, regs)),
            Err((controller, e)) => Err((self, controller, e)),
        }
    }
}

#[cfg(all(test, feature = "model"))]
mod tests {
    use super::*;
    use crate::can_clock::CanClock;
    use crate::model::FlexCanModel;
    use crate::regs::{self, mcr};
    use crate::{HostSystem, IdleClocked};

    fn instances() -> (ral::can::CAN1, ral::can::CAN2, ral::can3::CAN3, Ccm) {
        // SAFETY: host test: the instances are pointers never dereferenced here (the
        // model stands for the registers).
        unsafe {
            (
                ral::can::CAN1::instance(),
                ral::can::CAN2::instance(),
                ral::can3::CAN3::instance(),
                ral::ccm::CCM::instance(),
            )
        }
    }

    #[test]
    fn the_ral_addresses_are_the_register_map_s() {
        let (can1, can2, can3, ccm) = instances();
        for (address, instance) in [
            (can1.address(), Instance::Can1),
            (can2.address(), Instance::Can2),
            (can3.address(), Instance::Can3),
        ] {
            assert_eq!(
                Some(address),
                Target::new(Board::DEFAULT, instance).base(),
                "{instance:?}"
            );
        }
        let block: &ral::ccm::RegisterBlock = &ccm;
        assert_eq!(
            core::ptr::from_ref(block) as usize,
            crate::imxrt::ccm::CCM_BASE
        );
    }

    #[test]
    fn begin_then_free_gives_the_instances_back_and_stops_the_module() {
        let (can1, can2, _, ccm) = instances();
        // Before begin.
        let (can1, ccm) = hand_over(can1, ccm).free();
        let model = FlexCanModel::new(Target::new(Board::DEFAULT, Instance::Can1).model_chip());
        let settings = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
        let mut sys = HostSystem::new();
        let (controller, parked) = hand_over(can1, ccm)
            .begin_over(
                IdleClocked::new(model.clone()),
                &mut sys,
                &settings,
                &[Filter::pass_all()],
                &[],
            )
            .unwrap_or_else(|(_, e)| panic!("{e:?}"));
        assert_eq!(controller.target().instance, Instance::Can1);
        assert_eq!(model.read32(regs::MCR) & mcr::MDIS, 0, "running");
        // The RT1062 layout: the ERR005829 reserved mailbox (MB12, the first after the
        // table of the default configuration, RFFN 2) INACTIVE and masked, the data
        // mailbox MB16 = MAXMB (the Kinetis layout's MB12 is a remote-frame mailbox,
        // unmasked, and MAXMB 15).
        let reserved = usize::from(controller.configuration().reserved_mailbox());
        assert_eq!(reserved, 12);
        assert_eq!(
            regs::cs::CODE.get(model.read32(regs::mb_cs(reserved))),
            regs::code::TX_INACTIVE
        );
        assert_eq!(model.read32(regs::IMASK1) & 1 << reserved, 0, "masked");
        assert_eq!(mcr::MAXMB.get(model.read32(regs::MCR)), 16);
        // The module's gates are on in the CCM.
        let (gate, bits) = controller.target().clock_gate().unwrap();
        assert_eq!(sys.read32(gate) & bits, bits);

        // CAN2's parked instances refuse CAN1's controller, and give both back.
        let (_, _, _, ccm2) = instances();
        let other = Parked {
            can: can2,
            ccm: ccm2,
        };
        let (_other, controller, e) = other
            .free_over(controller, &mut sys)
            .map(|_| ())
            .unwrap_err();
        assert_eq!(e, Error::InvalidArgument);

        // Its own: the module stopped (Disable mode), gates off, the instances back.
        let (can1, _ccm, _regs) = parked
            .free_over(controller, &mut sys)
            .map_err(|(_, _, e)| e)
            .unwrap();
        assert_ne!(model.read32(regs::MCR) & mcr::MDIS, 0, "disabled");
        assert_eq!(sys.read32(gate) & bits, 0, "gates off");
        assert_eq!(
            Some(can1.address()),
            Target::new(Board::DEFAULT, Instance::Can1).base()
        );
    }

    #[test]
    fn a_refused_begin_gives_the_hand_over_back() {
        let (can1, _, _, ccm) = instances();
        let model = FlexCanModel::new(Target::new(Board::DEFAULT, Instance::Can1).model_chip());
        // A Kinetis clock on the RT1062.
        let (back, e) = hand_over(can1, ccm)
            .begin_over(
                IdleClocked::new(model),
                &mut HostSystem::new(),
                &Settings::new(500_000),
                &[],
                &[],
            )
            .map(|_| ())
            .unwrap_err();
        assert!(
            matches!(e, BeginError::Config(c) if c.contains(crate::ConfigErrors::CLOCK_NOT_ON_CHIP))
        );
        let (can1, _) = back.free();
        assert_eq!(can1.address(), crate::imxrt::CAN1_BASE);
    }
}
