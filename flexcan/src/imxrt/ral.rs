//! Hand-over from `imxrt-ral` and `imxrt-iomuxc` (feature `imxrt-ral` with `teensy40` or
//! `teensy41`): a Teensy 4 FlexCAN module begun from what a program already owns — as
//! `imxrt-hal` and `teensy4-bsp` programs do (`board::instances()`, the board's pins) —
//! with no `unsafe` in the program, and given back by `free`.
//!
//! [`hand_over`] takes **by value** the module's RAL instance (`imxrt_ral::can::CAN1`,
//! `CAN2` or `imxrt_ral::can3::CAN3`) and its two pads as `imxrt-iomuxc` 0.3 types (the
//! ones `teensy4-bsp` 0.6 hands out as `pins.p22`/`p23`, `p1`/`p0`, `p31`/`p30`; the
//! types are [`RalCan::Tx`] and [`RalCan::Rx`], so another pad does not compile): owning
//! them is the proof that nothing else reaches the module's registers or the pads'
//! `SW_MUX_CTL_PAD_*`/`SW_PAD_CTL_PAD_*` registers, which `begin` writes
//! ([`crate::imxrt::pads`]). The CCM is only **borrowed** (`&mut imxrt_ral::ccm::CCM`)
//! by `begin` and `free`, the two moments that write its shared registers — the CAN clock
//! root in `CCM_CSCMR2` and the module's gates in `CCM_CCGR0`/`CCM_CCGR7` (IMXRT1060RM
//! "Clock Controller Module (CCM)") — so the program keeps its CCM for the rest of its
//! clock set-up. The module's Rx daisy select (`*_SELECT_INPUT`) belongs to no pad
//! type; `begin` writes it, as `imxrt-iomuxc`'s own `prepare` does.
//!
//! - before `begin`, [`HandOver::free`] gives the instance and the pads back;
//! - `HandOver::begin` configures the module as `Can1::begin` does — in the RT1062
//!   layout ([`Imxrt1062`]: the ERR005829 workaround, tables up to RFFN 0xF), refusing
//!   to switch the clock root under another running module
//!   ([`crate::ConfigErrors::CLOCK_ROOT_IN_USE`]) — and returns the controller with a
//!   [`Parked`] value holding the instance and the pads;
//! - when the controller comes back (from [`crate::FlexCanHw::into_controller`] after
//!   the driver, or unsplit), `Parked::free` ends it ([`crate::FlexCan::end`]: module
//!   stopped, pads back to their reset function, gates released) and gives the instance
//!   and the pads back — only in exchange for the controller of that module, so the
//!   driver can no longer reach it.
//!
//! The board is the one the board feature selects ([`Board::DEFAULT`]): CAN1 on pins
//! 22/23, CAN2 on 1/0, CAN3 on 31/30 of a Teensy 4.0 or 4.1. Each pad type's register
//! addresses (from `imxrt-iomuxc`) are checked at compile time against the driver's pad
//! table ([`crate::imxrt::pads`]).
//!
//! # With `teensy4-bsp`
//!
//! `teensy4-bsp`'s `board::t41` takes every RAL instance and keeps the CAN ones, so a
//! program that uses CAN prepares the board with the BSP's own steps and keeps the
//! instances it needs (`tools/hal-doctests/run.sh` cross-builds this example with
//! `teensy4-bsp` 0.6):
//!
//! ```ignore
//! use teensy4_bsp::{board, hal, pins};
//! use twocan_core::Filter;
//! use twocan_flexcan::imxrt::ral;
//! use twocan_flexcan::{CanClock, Settings};
//!
//! let mut instances = board::instances();
//! board::prepare_clocks_and_power(
//!     &mut instances.CCM,
//!     &mut instances.CCM_ANALOG,
//!     &mut instances.DCDC,
//! );
//! let pins = pins::t41::from_pads(hal::iomuxc::into_pads(instances.IOMUXC));
//! let settings = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
//! // CAN1's instance and its pads (pins 22, 23) by value; the CCM only borrowed.
//! let can = ral::hand_over(instances.CAN1, pins.p22, pins.p23);
//! let Ok((controller, parked)) =
//!     can.begin(&mut instances.CCM, &settings, &[Filter::pass_all()], &[])
//! else {
//!     return;
//! };
//! // ... the driver (`into_split`, `rt::IrqState::start`); when the controller is back:
//! let Ok(ral::Owned { can, tx, rx }) = parked.free(controller, &mut instances.CCM) else {
//!     return;
//! };
//! // `tx` and `rx` are pins 22 and 23 again, free for another use.
//! # let _ = (can, tx, rx);
//! ```
//!
//! Another module's pads, or the two pads swapped, do not compile:
//!
//! ```ignore,compile_fail,E0308
//! # use teensy4_bsp::{board, hal, pins};
//! # use twocan_flexcan::imxrt::ral;
//! # let instances = board::instances();
//! # let pins = pins::t41::from_pads(hal::iomuxc::into_pads(instances.IOMUXC));
//! let can = ral::hand_over(instances.CAN1, pins.p23, pins.p22);
//! ```
//!
//! On the host (no `target_os = "none"`), [`HandOver::begin_over`] and
//! [`Parked::free_over`] run the same steps over given registers (the behavioural
//! model), for tests; `begin` and `free` reach the chip's registers and exist on the
//! target only.

use imxrt_iomuxc::imxrt1060::{gpio_ad_b0, gpio_ad_b1, gpio_emc};
use imxrt_ral as ral;
use twocan_core::{Error, Filter, Registers};

use super::pads::{ImxPin, CAN1_RX, CAN1_TX, CAN2_RX, CAN2_TX, CAN3_RX, CAN3_TX};
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

/// The IOMUXC registers of an `imxrt-iomuxc` pad type (`imxrt_iomuxc::Pad<MUX, PAD>`
/// carries their absolute addresses as parameters).
pub trait PadRegisters {
    /// The address of the pad's `SW_MUX_CTL_PAD_*` register.
    const MUX: usize;
    /// The address of the pad's `SW_PAD_CTL_PAD_*` register.
    const PAD: usize;
}

impl<const MUX: u32, const PAD: u32> PadRegisters for imxrt_iomuxc::Pad<MUX, PAD> {
    const MUX: usize = MUX as usize;
    const PAD: usize = PAD as usize;
}

/// Whether the pad type `P` is the pad `pin` of the driver's table: both registers.
const fn is_pin<P: PadRegisters>(pin: ImxPin) -> bool {
    P::MUX == pin.mux && P::PAD == pin.pad_ctl
}

/// A RAL FlexCAN instance of the i.MX RT1062 (`imxrt_ral::can::CAN1`, `CAN2`,
/// `imxrt_ral::can3::CAN3`) and the `imxrt-iomuxc` types of its Teensy 4 pads.
pub trait RalCan: sealed::Sealed {
    /// The module.
    const INSTANCE: Instance;
    /// The Tx pad on a Teensy 4.0 / 4.1 (pin 22, 1, 31).
    type Tx: PadRegisters;
    /// The Rx pad on a Teensy 4.0 / 4.1 (pin 23, 0, 30).
    type Rx: PadRegisters;

    /// The address of the instance's register block (the RAL's pointer).
    fn address(&self) -> usize;
}

macro_rules! ral_can {
    ($ty:ty, $instance:ident, $tx:ty = $tx_pin:expr, $rx:ty = $rx_pin:expr) => {
        impl sealed::Sealed for $ty {}
        impl RalCan for $ty {
            const INSTANCE: Instance = Instance::$instance;
            type Tx = $tx;
            type Rx = $rx;
            fn address(&self) -> usize {
                core::ptr::from_ref::<<$ty as core::ops::Deref>::Target>(self) as usize
            }
        }
        const _: () = assert!(
            is_pin::<$tx>($tx_pin) && is_pin::<$rx>($rx_pin),
            "the pad types are the pads the driver writes"
        );
    };
}

ral_can!(
    ral::can::CAN1,
    Can1,
    gpio_ad_b1::GPIO_AD_B1_08 = CAN1_TX,
    gpio_ad_b1::GPIO_AD_B1_09 = CAN1_RX
);
ral_can!(
    ral::can::CAN2,
    Can2,
    gpio_ad_b0::GPIO_AD_B0_02 = CAN2_TX,
    gpio_ad_b0::GPIO_AD_B0_03 = CAN2_RX
);
ral_can!(
    ral::can3::CAN3,
    Can3,
    gpio_emc::GPIO_EMC_36 = CAN3_TX,
    gpio_emc::GPIO_EMC_37 = CAN3_RX
);

/// The CCM's RAL instance, borrowed by `begin` and `free`.
pub type Ccm = ral::ccm::CCM;

/// The controller a hand-over begins: the module in the RT1062 layout ([`Imxrt1062`]:
/// the ERR005829 workaround, tables up to RFFN 0xF).
pub type Controller<R = crate::regs::FlexCanRegs> = FlexCan<R, Imxrt1062>;

/// What a hand-over holds and gives back: the module's RAL instance and its two pads.
pub struct Owned<C: RalCan> {
    /// The module's RAL instance.
    pub can: C,
    /// Its Tx pad.
    pub tx: C::Tx,
    /// Its Rx pad.
    pub rx: C::Rx,
}

/// A module handed over, not begun yet.
pub struct HandOver<C: RalCan> {
    owned: Owned<C>,
}

/// Takes the module's RAL instance and its two pads by value (see the module notes).
pub fn hand_over<C: RalCan>(can: C, tx: C::Tx, rx: C::Rx) -> HandOver<C> {
    HandOver {
        owned: Owned { can, tx, rx },
    }
}

impl<C: RalCan> HandOver<C> {
    /// The module on [`Board::DEFAULT`].
    pub const fn target(&self) -> Target {
        Target::new(Board::DEFAULT, C::INSTANCE)
    }

    /// Gives the instance and the pads back.
    pub fn free(self) -> Owned<C> {
        self.owned
    }

    /// ACAN's `begin` (§15) on the module: clock root, gates, pads, then the module,
    /// as `Can1::begin` (`Can2`, `Can3`), with the CCM borrowed for its writes; the
    /// controller and the parked instance and pads, or the hand-over back with the
    /// reason.
    #[cfg(target_os = "none")]
    #[allow(clippy::result_large_err)]
    pub fn begin(
        self,
        _ccm: &mut Ccm,
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
        debug_assert_eq!(base, self.owned.can.address());
        // SAFETY: the module's RAL instance is owned by value here and kept in the
        // `Parked` value until the controller comes back: this is the only access to
        // the module's registers, at the reference-manual base (equal to the RAL's).
        let regs = unsafe { crate::regs::FlexCanRegs::new(base) };
        // The CCM and pad registers: the CCM borrowed exclusively (`_ccm`), the pads
        // owned by value.
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
            Ok(controller) => Ok((controller, Parked { owned: self.owned })),
            Err(e) => Err((self, e)),
        }
    }
}

/// The instance and pads of a begun module, given back for its controller
/// (`Parked::free`).
pub struct Parked<C: RalCan> {
    owned: Owned<C>,
}

impl<C: RalCan> Parked<C> {
    /// Ends `controller` ([`FlexCan::end`]: stopped, pads back to their reset function,
    /// gates released; the CCM borrowed for the gates) and gives the instance and the
    /// pads back. A controller of another module is [`Error::InvalidArgument`]; either
    /// error gives both back.
    #[cfg(target_os = "none")]
    #[allow(clippy::result_large_err, clippy::type_complexity)]
    pub fn free(
        self,
        controller: Controller,
        _ccm: &mut Ccm,
    ) -> Result<Owned<C>, (Self, Controller, Error)> {
        self.free_over(controller, &mut super::firmware::system())
            .map(|(owned, _)| owned)
    }

    /// `Parked::free` with `sys` for the CCM and IOMUXC; also gives the module's
    /// registers back (the model on the host).
    #[allow(clippy::result_large_err, clippy::type_complexity)]
    pub fn free_over<R: Registers, S: Registers>(
        self,
        controller: Controller<R>,
        sys: &mut S,
    ) -> Result<(Owned<C>, R), (Self, Controller<R>, Error)> {
        if controller.target() != Target::new(Board::DEFAULT, C::INSTANCE) {
            return Err((self, controller, Error::InvalidArgument));
        }
        match controller.end(sys) {
            Ok(regs) => Ok((self.owned, regs)),
            Err((controller, e)) => Err((self, controller, e)),
        }
    }
}

#[cfg(all(test, feature = "model"))]
mod tests {
    use super::*;
    use crate::can_clock::CanClock;
    use crate::imxrt::ccm::{ClockRoot, CCM_CSCMR2};
    use crate::model::FlexCanModel;
    use crate::regs::{self, mcr};
    use crate::{ConfigErrors, HostSystem, IdleClocked};

    /// What a program owns: the three modules' instances with their pads (host test:
    /// the instances and pads are never dereferenced, the model stands for them).
    fn owned() -> (
        Owned<ral::can::CAN1>,
        Owned<ral::can::CAN2>,
        Owned<ral::can3::CAN3>,
    ) {
        // SAFETY: host test; each instance and pad is created once per call and the
        // model stands for the registers.
        unsafe {
            (
                Owned {
                    can: ral::can::CAN1::instance(),
                    tx: imxrt_iomuxc::Pad::new(),
                    rx: imxrt_iomuxc::Pad::new(),
                },
                Owned {
                    can: ral::can::CAN2::instance(),
                    tx: imxrt_iomuxc::Pad::new(),
                    rx: imxrt_iomuxc::Pad::new(),
                },
                Owned {
                    can: ral::can3::CAN3::instance(),
                    tx: imxrt_iomuxc::Pad::new(),
                    rx: imxrt_iomuxc::Pad::new(),
                },
            )
        }
    }

    fn give<C: RalCan>(o: Owned<C>) -> HandOver<C> {
        hand_over(o.can, o.tx, o.rx)
    }

    #[test]
    fn the_ral_addresses_are_the_register_map_s() {
        let (can1, can2, can3) = owned();
        for (address, instance) in [
            (can1.can.address(), Instance::Can1),
            (can2.can.address(), Instance::Can2),
            (can3.can.address(), Instance::Can3),
        ] {
            assert_eq!(
                Some(address),
                Target::new(Board::DEFAULT, instance).base(),
                "{instance:?}"
            );
        }
        // SAFETY: host test, never dereferenced.
        let ccm = unsafe { ral::ccm::CCM::instance() };
        let block: &ral::ccm::RegisterBlock = &ccm;
        assert_eq!(
            core::ptr::from_ref(block) as usize,
            crate::imxrt::ccm::CCM_BASE
        );
    }

    /// The pads `imxrt-iomuxc` gives FlexCAN functions to (CAN1 and CAN2; it lists no
    /// CAN3 pad) select them with the ALT numbers of the driver's table.
    #[test]
    fn the_pad_table_agrees_with_imxrt_iomuxc() {
        use imxrt_iomuxc::flexcan::Pin;
        fn alt<P: Pin>() -> u32 {
            P::ALT
        }
        type C1 = ral::can::CAN1;
        type C2 = ral::can::CAN2;
        assert_eq!(alt::<<C1 as RalCan>::Tx>(), CAN1_TX.alt);
        assert_eq!(alt::<<C1 as RalCan>::Rx>(), CAN1_RX.alt);
        assert_eq!(alt::<<C2 as RalCan>::Tx>(), CAN2_TX.alt);
        assert_eq!(alt::<<C2 as RalCan>::Rx>(), CAN2_RX.alt);
        for (pin, teensy) in [
            (CAN1_TX, 22),
            (CAN1_RX, 23),
            (CAN2_TX, 1),
            (CAN2_RX, 0),
            (CAN3_TX, 31),
            (CAN3_RX, 30),
        ] {
            assert_eq!(pin.teensy_pin, teensy, "{}", pin.pad);
        }
        assert!(is_pin::<<C1 as RalCan>::Tx>(CAN1_TX));
        assert!(!is_pin::<<C1 as RalCan>::Tx>(CAN1_RX));
    }

    #[test]
    fn begin_then_free_gives_the_instance_and_pads_back_and_stops_the_module() {
        let (can1, can2, _) = owned();
        // Before begin.
        let can1 = give(can1).free();
        let model = FlexCanModel::new(Target::new(Board::DEFAULT, Instance::Can1).model_chip());
        let settings = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
        let mut sys = HostSystem::new();
        let (controller, parked) = give(can1)
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
        // The pads the hand-over holds are muxed to CAN1 (ALT2), the daisy select set.
        assert_eq!(sys.read32(CAN1_TX.mux), 2);
        assert_eq!(sys.read32(CAN1_RX.mux), 2);
        assert_eq!(sys.read32(CAN1_RX.daisy.unwrap().0), 2);
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

        // CAN2's parked instance refuses CAN1's controller, and gives both back.
        let other = Parked { owned: can2 };
        let (_other, controller, e) = other
            .free_over(controller, &mut sys)
            .map(|_| ())
            .unwrap_err();
        assert_eq!(e, Error::InvalidArgument);

        // Its own: the module stopped (Disable mode), gates off, pads back to GPIO,
        // the instance and pads back.
        let (can1, _regs) = parked
            .free_over(controller, &mut sys)
            .map_err(|(_, _, e)| e)
            .unwrap();
        assert_ne!(model.read32(regs::MCR) & mcr::MDIS, 0, "disabled");
        assert_eq!(sys.read32(gate) & bits, 0, "gates off");
        assert_eq!(sys.read32(CAN1_TX.mux), crate::imxrt::pads::MUX_RESET);
        assert_eq!(sys.read32(CAN1_RX.mux), crate::imxrt::pads::MUX_RESET);
        assert_eq!(
            Some(can1.can.address()),
            Target::new(Board::DEFAULT, Instance::Can1).base()
        );
    }

    #[test]
    fn a_refused_begin_gives_the_hand_over_back() {
        let (can1, _, _) = owned();
        let model = FlexCanModel::new(Target::new(Board::DEFAULT, Instance::Can1).model_chip());
        // A Kinetis clock on the RT1062.
        let (back, e) = give(can1)
            .begin_over(
                IdleClocked::new(model),
                &mut HostSystem::new(),
                &Settings::new(500_000),
                &[],
                &[],
            )
            .map(|_| ())
            .unwrap_err();
        assert!(matches!(e, BeginError::Config(c) if c.contains(ConfigErrors::CLOCK_NOT_ON_CHIP)));
        assert_eq!(back.free().can.address(), crate::imxrt::CAN1_BASE);
    }

    /// One `HostSystem` for the CCM, IOMUXC and the other modules' `MCR`: CAN2 begun
    /// on the 24 MHz root — running, frozen (a filter switch) or asleep (Disable
    /// mode) — holds the root: CAN1 asked on 60 MHz is refused with nothing written;
    /// on CAN2's root it begins; once CAN2 ended (gated off), 60 MHz is taken. A
    /// module left out of reset (`MCR` 0x5980_000F, gate on) does not hold the root.
    #[test]
    fn the_clock_root_is_not_switched_under_a_begun_module() {
        use crate::imxrt::plan::MCR_RESET;
        let (can1, can2, _) = owned();
        let chip = Target::new(Board::DEFAULT, Instance::Can2).model_chip();
        let model2 = FlexCanModel::new(chip);
        let model1 = FlexCanModel::new(chip);
        assert_eq!(
            model1.read32(regs::MCR),
            MCR_RESET,
            "the model's reset value"
        );
        let mut sys = HostSystem::new();
        let on_24 = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
        let on_60 = Settings::with_clock(500_000, CanClock::Imxrt(ClockRoot::PLL3_60MHZ));
        let (c2, parked2) = give(can2)
            .begin_over(IdleClocked::new(model2.clone()), &mut sys, &on_24, &[], &[])
            .unwrap_or_else(|(_, e)| panic!("{e:?}"));
        let cscmr2 = sys.read32(CCM_CSCMR2);
        assert_eq!(ClockRoot::from_cscmr2(cscmr2), Some(ClockRoot::OSC_24MHZ));
        // CAN2's MCR as it reads through the system window (the host system stands for
        // the CAN2 block's first word here): running, then frozen, then asleep.
        let running = model2.read32(regs::MCR);
        assert_eq!(running & mcr::NOTRDY, 0);
        let can2_mcr = crate::imxrt::CAN2_BASE + regs::MCR;
        let mut can1 = Some(can1);
        for mcr in [
            running,
            running | mcr::FRZ | mcr::HALT | mcr::FRZACK | mcr::NOTRDY,
            running | mcr::MDIS | mcr::LPMACK | mcr::NOTRDY,
        ] {
            sys.write32(can2_mcr, mcr);
            let before: std::vec::Vec<_> = sys.written().to_vec();
            let (back, e) = give(can1.take().unwrap())
                .begin_over(IdleClocked::new(model1.clone()), &mut sys, &on_60, &[], &[])
                .map(|_| ())
                .unwrap_err();
            assert!(
                matches!(e, BeginError::Config(c) if c == ConfigErrors::CLOCK_ROOT_IN_USE),
                "MCR {mcr:#x}: {e:?}"
            );
            assert_eq!(*sys.written(), *before, "MCR {mcr:#x}: nothing written");
            assert_eq!(model1.read32(regs::MCR), MCR_RESET, "CAN1 untouched");
            can1 = Some(back.free());
        }
        sys.write32(can2_mcr, running);
        // On CAN2's root, CAN1 begins.
        let (c1, parked1) = give(can1.take().unwrap())
            .begin_over(IdleClocked::new(model1.clone()), &mut sys, &on_24, &[], &[])
            .unwrap_or_else(|(_, e)| panic!("{e:?}"));
        let (can1, _) = parked1
            .free_over(c1, &mut sys)
            .map_err(|(_, _, e)| e)
            .unwrap();
        // CAN2 ended (its gates off): the root may change.
        let (_can2, _) = parked2
            .free_over(c2, &mut sys)
            .map_err(|(_, _, e)| e)
            .unwrap();
        // CAN3 gated on, straight out of reset: not in use.
        let (gate3, bits3) = Target::new(Board::DEFAULT, Instance::Can3)
            .clock_gate()
            .unwrap();
        sys.write32(gate3, bits3);
        sys.write32(crate::imxrt::CAN3_BASE + regs::MCR, MCR_RESET);
        let (c1, _parked1) = give(can1)
            .begin_over(IdleClocked::new(model1), &mut sys, &on_60, &[], &[])
            .unwrap_or_else(|(_, e)| panic!("{e:?}"));
        assert_eq!(
            ClockRoot::from_cscmr2(sys.read32(CCM_CSCMR2)),
            Some(ClockRoot::PLL3_60MHZ)
        );
        drop(c1);
    }
}
