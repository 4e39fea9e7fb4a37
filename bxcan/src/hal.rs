//! Hand-over from `stm32f7xx-hal` (0.8, feature `hal-stm32f7`): the bxCAN instances
//! built from the HAL's PAC singletons, its [`Clocks`] and CAN pins, with no `unsafe` in
//! the program.
//!
//! The program owns `stm32f7xx_hal::pac::CAN1` (and `CAN2`, `CAN3`) once, from
//! `pac::Peripherals::take()`. Giving the singleton **by value** to [`can1`],
//! [`can1_dual`], [`can2`] or `can3` is the proof that nothing else reaches that
//! instance's registers; the constructor turns it into the bounded register window of
//! [`crate::regs`] (the one `unsafe` of the hand-over is here, in this crate). It also:
//!
//! - enables and resets the instance's clock in RCC (`RCC_APB1ENR.CAN1EN`/`CAN2EN`/
//!   `CAN3EN`, `RCC_APB1RSTR`, RM0410 §5.3.13, §5.3.8) through the HAL's `APB1`;
//! - keeps the APB1 frequency of the HAL's [`Clocks`] (bxCAN's clock, RM0410 §40.7.7:
//!   tq = (BRP + 1) × tPCLK): [`HandedOver::config`] solves the bit timing from it, and
//!   [`HandedOver::configure`] refuses a [`Config`] whose timing was computed for another
//!   clock (`Error::InvalidArgument`, the handle handed back);
//! - takes the TX and RX pins, already in their CAN alternate function: the pin types
//!   carry the alternate function number (`Pin<'D', 1, Alternate<9>>`), and only the
//!   pins of the data sheets' alternate-function tables implement [`TxPin`]/[`RxPin`]
//!   for an instance — a wrong pin, or the right pin in the wrong function, does not
//!   compile.
//!
//! # Giving the singleton and the pins back
//!
//! [`can1`], [`can2`] and `can3` (feature `hal-stm32f7-can3`) keep the PAC singleton and the two pins in the
//! handle ([`HalParts`]), as HAL peripherals do:
//!
//! - before configuring, [`HandedOver::free`] returns `(CANx, tx, rx)`;
//! - to get them back after the driver has run, take them out first with
//!   [`HandedOver::park`] (a [`Parked`] value), configure and run the controller, and
//!   when its register handle comes back ([`Init::release`], [`Can::release`]), give
//!   that handle to [`Parked::free`]: the singleton is only returned in exchange for
//!   the one register window of that instance, so the driver can no longer reach it.
//!
//! ```no_run
//! # use stm32f7xx_hal::{pac, prelude::*};
//! # use twocan_bxcan::hal;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let rcc = dp.RCC.constrain();
//! # let clocks = rcc.cfgr.freeze();
//! # let mut apb1 = rcc.apb1;
//! let gpiob = dp.GPIOB.split();
//! let (rx, tx) = (gpiob.pb8.into_alternate::<9>(), gpiob.pb9.into_alternate::<9>());
//! let (can1, parked) = hal::can1(dp.CAN1, tx, rx, &mut apb1, &clocks).park();
//! let config = can1.config(500_000).unwrap();
//! let init = can1.configure(&config).map_err(|f| f.error).unwrap();
//! // ... filters, `enable`, traffic; then back to initialization mode ...
//! let (regs, _) = init.release();
//! let (can1_pac, tx, rx) = parked.free(regs).ok().unwrap();
//! // `can1_pac`, `tx` and `rx` are the program's again (e.g. `tx.into_push_pull_output()`).
//! ```
//!
//! [`HandedOver::configure`] on a handle that still holds its parts drops them (the
//! pins stay in their CAN function, the singleton is gone for good), as before. CAN1
//! handed over with [`can1_dual`] keeps nothing: CAN2 may still reach CAN1's filter
//! block through a [`Can1Filters`] copy, so CAN1's singleton must never come back.
//!
//! # CAN2 and the shared filter block
//!
//! CAN2 has no filter registers: its reception goes through CAN1's filter block
//! (RM0410 §40.3 "dual CAN", §40.9.4). [`can1_dual`] gives CAN1 its control and mailbox
//! registers and returns a [`Can1Filters`] handle to the filter block; [`can2`] takes one.
//! So CAN2 cannot be built without CAN1's singleton having been handed over in dual mode
//! (which also keeps CAN1 clocked, as CAN2's filters need), and no register has two
//! owners: CAN1's control block belongs to CAN1, CAN2's to CAN2, the filter block to
//! both through [`Can1Filters`], whose writes the driver makes in critical sections
//! (see [`crate::filter_block`]). [`can1`] hands the whole CAN1 block to CAN1 and gives
//! no filter handle: then CAN2 cannot be built at all.
//!
//! CAN3 (F76x/F77x, feature `hal-stm32f7-can3`) has its own 14-bank filter block.
//!
//! # Chip
//!
//! The chip is the one the program's own `stm32f7xx-hal` dependency selects (one of its
//! chip features, e.g. `stm32f767`, `stm32f746`): this crate uses the same HAL and adds
//! no chip of its own. `hal-stm32f7-can3` needs a chip with CAN3 (`stm32f765`,
//! `stm32f767`, `stm32f769`, `stm32f777`, `stm32f778`, `stm32f779`).
//!
//! # Pins
//!
//! From the alternate-function mapping tables of the STM32F745xx/STM32F746xx data sheet
//! (DS10916) and the STM32F765xx/STM32F767xx/STM32F768Ax/STM32F769xx data sheet
//! (DS11532), table "Alternate function mapping", columns AF9 and AF11:
//!
//! | instance | function | RX                   | TX                    |
//! |----------|----------|----------------------|-----------------------|
//! | CAN1     | AF9      | PA11, PB8, PD0, PI9  | PA12, PB9, PD1, PH13  |
//! | CAN2     | AF9      | PB5, PB12            | PB6, PB13             |
//! | CAN3     | AF11     | PA8, PB3             | PA15, PB4             |
//!
//! A pin a package lacks (PH13, PI9 on the 100- and 144-pin packages) cannot be split
//! from the HAL's GPIO port there, so it cannot be passed either.
//!
//! The pins are checked by the compiler. CAN1 on PB8 (RX) and PB9 (TX), in AF9:
//!
//! ```no_run
//! # use stm32f7xx_hal::{pac, prelude::*};
//! # use twocan_bxcan::hal;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let rcc = dp.RCC.constrain();
//! # let clocks = rcc.cfgr.freeze();
//! # let mut apb1 = rcc.apb1;
//! let gpiob = dp.GPIOB.split();
//! let (rx, tx) = (gpiob.pb8.into_alternate::<9>(), gpiob.pb9.into_alternate::<9>());
//! let can1 = hal::can1(dp.CAN1, tx, rx, &mut apb1, &clocks);
//! ```
//!
//! CAN2's pins (PB5, PB6) given to CAN1 do not compile:
//!
//! ```compile_fail
//! # use stm32f7xx_hal::{pac, prelude::*};
//! # use twocan_bxcan::hal;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let rcc = dp.RCC.constrain();
//! # let clocks = rcc.cfgr.freeze();
//! # let mut apb1 = rcc.apb1;
//! let gpiob = dp.GPIOB.split();
//! let (rx, tx) = (gpiob.pb5.into_alternate::<9>(), gpiob.pb6.into_alternate::<9>());
//! let can1 = hal::can1(dp.CAN1, tx, rx, &mut apb1, &clocks);
//! ```
//!
//! Nor does the right pin in another alternate function (PB9 in AF8):
//!
//! ```compile_fail
//! # use stm32f7xx_hal::{pac, prelude::*};
//! # use twocan_bxcan::hal;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let rcc = dp.RCC.constrain();
//! # let clocks = rcc.cfgr.freeze();
//! # let mut apb1 = rcc.apb1;
//! let gpiob = dp.GPIOB.split();
//! let (rx, tx) = (gpiob.pb8.into_alternate::<9>(), gpiob.pb9.into_alternate::<8>());
//! let can1 = hal::can1(dp.CAN1, tx, rx, &mut apb1, &clocks);
//! ```
//!
//! Nor TX and RX swapped:
//!
//! ```compile_fail
//! # use stm32f7xx_hal::{pac, prelude::*};
//! # use twocan_bxcan::hal;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let rcc = dp.RCC.constrain();
//! # let clocks = rcc.cfgr.freeze();
//! # let mut apb1 = rcc.apb1;
//! let gpiob = dp.GPIOB.split();
//! let (rx, tx) = (gpiob.pb8.into_alternate::<9>(), gpiob.pb9.into_alternate::<9>());
//! let can1 = hal::can1(dp.CAN1, rx, tx, &mut apb1, &clocks);
//! ```
//!
//! And CAN2 takes a [`Can1Filters`], which only [`can1_dual`] makes; CAN1 handed over
//! alone ([`can1`]) leaves no way to build one:
//!
//! ```compile_fail
//! # use stm32f7xx_hal::{pac, prelude::*};
//! # use twocan_bxcan::hal;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let rcc = dp.RCC.constrain();
//! # let clocks = rcc.cfgr.freeze();
//! # let mut apb1 = rcc.apb1;
//! let gpiob = dp.GPIOB.split();
//! let (rx, tx) = (gpiob.pb8.into_alternate::<9>(), gpiob.pb9.into_alternate::<9>());
//! let can1 = hal::can1(dp.CAN1, tx, rx, &mut apb1, &clocks);
//! let (rx2, tx2) = (gpiob.pb5.into_alternate::<9>(), gpiob.pb6.into_alternate::<9>());
//! let filters = hal::Can1Filters::default();
//! let can2 = hal::can2(dp.CAN2, tx2, rx2, &mut apb1, &clocks, filters);
//! ```
//!
//! The same with [`can1_dual`], which gives the handle:
//!
//! ```no_run
//! # use stm32f7xx_hal::{pac, prelude::*};
//! # use twocan_bxcan::hal;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let rcc = dp.RCC.constrain();
//! # let clocks = rcc.cfgr.freeze();
//! # let mut apb1 = rcc.apb1;
//! let gpiob = dp.GPIOB.split();
//! let (rx, tx) = (gpiob.pb8.into_alternate::<9>(), gpiob.pb9.into_alternate::<9>());
//! let (can1, filters) = hal::can1_dual(dp.CAN1, tx, rx, &mut apb1, &clocks);
//! let (rx2, tx2) = (gpiob.pb5.into_alternate::<9>(), gpiob.pb6.into_alternate::<9>());
//! let can2 = hal::can2(dp.CAN2, tx2, rx2, &mut apb1, &clocks, filters);
//! ```

use stm32f7xx_hal::gpio::{Alternate, Pin};
use stm32f7xx_hal::pac;
use stm32f7xx_hal::rcc::{Clocks, Enable, Reset, APB1};
use twocan_core::{Error, Registers};

use crate::config::{Config, ConfigError};
use crate::controller::{Can, Failed, Init};
use crate::instance::Instance;
use crate::regs::{CanRegs, ControlRegs, FilterRegs};

mod sealed {
    /// Keeps [`super::TxPin`] and [`super::RxPin`] to the pins listed in this module.
    pub trait Sealed {}
}

/// A pin that carries the TX signal of the bxCAN instance `CAN` (the PAC singleton's
/// type) in its current mode. Implemented for the pins of the module's table only.
pub trait TxPin<CAN>: sealed::Sealed {}

/// A pin that carries the RX signal of the bxCAN instance `CAN`. Implemented for the pins
/// of the module's table only.
pub trait RxPin<CAN>: sealed::Sealed {}

macro_rules! can_pins {
    ($can:ty, $af:literal, $role:ident: $(($port:literal, $n:literal)),+ $(,)?) => {
        $(
            impl sealed::Sealed for Pin<$port, $n, Alternate<$af>> {}
            impl $role<$can> for Pin<$port, $n, Alternate<$af>> {}
        )+
    };
}

// DS10916 / DS11532, "Alternate function mapping", AF9: CAN1_RX, CAN1_TX.
can_pins!(pac::CAN1, 9, RxPin: ('A', 11), ('B', 8), ('D', 0), ('I', 9));
can_pins!(pac::CAN1, 9, TxPin: ('A', 12), ('B', 9), ('D', 1), ('H', 13));
// AF9: CAN2_RX, CAN2_TX.
can_pins!(pac::CAN2, 9, RxPin: ('B', 5), ('B', 12));
can_pins!(pac::CAN2, 9, TxPin: ('B', 6), ('B', 13));
// DS11532 only (F76x/F77x), AF11: CAN3_RX, CAN3_TX.
#[cfg(feature = "hal-stm32f7-can3")]
can_pins!(pac::CAN3, 11, RxPin: ('A', 8), ('B', 3));
#[cfg(feature = "hal-stm32f7-can3")]
can_pins!(pac::CAN3, 11, TxPin: ('A', 15), ('B', 4));

/// CAN1's filter registers (`CAN_FMR` .. `CAN_F27R2`, CAN1's block + `0x200..0x320`),
/// reached only through the [`Can1Filters`] handles that [`can1_dual`] gives out.
// SAFETY: offsets 0x200..0x320 from CAN1's base (RM0410 §2.2.2, §40.9.5) are CAN1's
// filter registers, 32-bit accessible. A reference to this value is created only by
// `can1_dual`, which consumes the `pac::CAN1` singleton (handed out once per program by
// the PAC), and then gives CAN1 the control window below 0x200 only.
static CAN1_FILTERS: FilterRegs = unsafe { FilterRegs::new(crate::regs::CAN1_BASE) };

/// A handle to CAN1's filter block, shared by CAN1 and CAN2 in dual mode: from
/// [`can1_dual`] only (the proof that CAN1's singleton was handed over and its block
/// split), and required by [`can2`]. Copying it shares the one block; the drivers program
/// it in critical sections.
#[derive(Debug, Clone, Copy)]
pub struct Can1Filters {
    regs: &'static FilterRegs,
}

impl Registers for Can1Filters {
    #[inline(always)]
    fn read32(&self, offset: usize) -> u32 {
        self.regs.read32(offset)
    }

    #[inline(always)]
    fn write32(&self, offset: usize, value: u32) {
        self.regs.write32(offset, value)
    }
}

/// A bxCAN instance handed over by the HAL, clocked, not yet configured: its register
/// handles, the APB1 frequency and (`P`) the PAC singleton and pins it was built from
/// ([`HalParts`], or `()` when they were parked or, for [`can1_dual`], not kept).
/// [`HandedOver::configure`] puts it in initialization mode ([`Init`]).
///
/// - [`Can1`] (from [`can1`]) and `Can3` (from `can3`) own a whole register block;
/// - [`DualCan`] (from [`can1_dual`]) and [`Can2`] (from [`can2`]) own a control block
///   and share CAN1's filter block.
#[derive(Debug)]
pub struct HandedOver<R: Registers, F: Registers = R, P = ()> {
    regs: R,
    filters: Option<F>,
    instance: Instance,
    apb1_hz: u32,
    parts: P,
}

/// The PAC singleton of a bxCAN instance and its TX and RX pins, as handed over.
#[derive(Debug)]
pub struct HalParts<CAN, TX, RX> {
    can: CAN,
    tx: TX,
    rx: RX,
}

/// The singleton and pins taken out of a [`HandedOver`] by [`HandedOver::park`]: given
/// back by [`Parked::free`] in exchange for the instance's register window.
#[derive(Debug)]
pub struct Parked<CAN, TX, RX> {
    parts: HalParts<CAN, TX, RX>,
}

/// A PAC singleton type of a bxCAN instance handed over with its parts kept: the
/// register window the hand-over made of it, and that window's address.
pub trait PacCan: sealed::Sealed {
    /// The window [`can1`], [`can2`] or `can3` built: the whole block for CAN1 alone
    /// and CAN3, the control block for CAN2.
    type Window;
    /// Whether `window` is this instance's (its base address is the PAC's).
    fn is_window(window: &Self::Window) -> bool;
}

impl sealed::Sealed for pac::CAN1 {}
impl PacCan for pac::CAN1 {
    type Window = CanRegs;
    fn is_window(window: &CanRegs) -> bool {
        window.base() == pac::CAN1::ptr() as usize
    }
}
impl sealed::Sealed for pac::CAN2 {}
impl PacCan for pac::CAN2 {
    type Window = ControlRegs;
    fn is_window(window: &ControlRegs) -> bool {
        window.base() == pac::CAN2::ptr() as usize
    }
}
#[cfg(feature = "hal-stm32f7-can3")]
impl sealed::Sealed for pac::CAN3 {}
#[cfg(feature = "hal-stm32f7-can3")]
impl PacCan for pac::CAN3 {
    type Window = CanRegs;
    fn is_window(window: &CanRegs) -> bool {
        window.base() == pac::CAN3::ptr() as usize
    }
}

impl<CAN: PacCan, TX, RX> Parked<CAN, TX, RX> {
    /// Gives back `(CANx, tx, rx)` for the instance's register window `regs` (from
    /// [`Init::release`] or [`Can::release`]), which it consumes: the window is not
    /// `Clone`, and its type is the whole window the hand-over made (not a part split
    /// off it), so once it is here the driver reaches the instance no more.
    ///
    /// Errors: the window of another instance is refused and handed back with this
    /// value.
    #[allow(clippy::result_large_err)]
    pub fn free(self, regs: CAN::Window) -> Result<(CAN, TX, RX), (Self, CAN::Window)> {
        if !CAN::is_window(&regs) {
            return Err((self, regs));
        }
        let HalParts { can, tx, rx } = self.parts;
        Ok((can, tx, rx))
    }
}

/// CAN1 alone (its whole block, filters included), with its singleton and pins.
pub type Can1<TX, RX> = HandedOver<CanRegs, CanRegs, HalParts<pac::CAN1, TX, RX>>;
/// CAN2 of a dual set-up: control registers, CAN1's filter block shared; with its
/// singleton and pins.
pub type Can2<TX, RX> = HandedOver<ControlRegs, Can1Filters, HalParts<pac::CAN2, TX, RX>>;
/// CAN3 (its whole block, with its own 14 filter banks), with its singleton and pins.
#[cfg(feature = "hal-stm32f7-can3")]
pub type Can3<TX, RX> = HandedOver<CanRegs, CanRegs, HalParts<pac::CAN3, TX, RX>>;
/// CAN1 of a dual set-up: control registers, and CAN1's filter block shared (its
/// singleton and pins are not kept: see the module notes).
pub type DualCan = HandedOver<ControlRegs, Can1Filters>;

/// The APB1 frequency the HAL set (Hz).
fn apb1_hz(clocks: &Clocks) -> u32 {
    clocks.pclk1().raw()
}

/// Hands CAN1 over alone: the whole register block (filters included), so CAN2 cannot
/// be built (see the module notes; use [`can1_dual`] for both). Enables and resets
/// CAN1's clock.
pub fn can1<TX, RX>(
    can1: pac::CAN1,
    tx: TX,
    rx: RX,
    apb1: &mut APB1,
    clocks: &Clocks,
) -> Can1<TX, RX>
where
    TX: TxPin<pac::CAN1>,
    RX: RxPin<pac::CAN1>,
{
    let base = pac::CAN1::ptr() as usize;
    pac::CAN1::enable(apb1);
    pac::CAN1::reset(apb1);
    HandedOver {
        // SAFETY: `base` is CAN1's register block (the PAC's address), whose singleton
        // this function took (kept in `parts`, given back only for this window): no
        // other handle to these registers exists.
        regs: unsafe { CanRegs::new(base) },
        filters: None,
        instance: Instance::Can1,
        apb1_hz: apb1_hz(clocks),
        parts: HalParts { can: can1, tx, rx },
    }
}

/// Hands CAN1 over as the master of a dual set-up: CAN1 gets its control and mailbox
/// registers, and the returned [`Can1Filters`] reaches the filter block it shares with
/// CAN2 (pass a copy to [`can2`]). Enables and resets CAN1's clock (which CAN2's
/// filters need too).
pub fn can1_dual<TX, RX>(
    can1: pac::CAN1,
    tx: TX,
    rx: RX,
    apb1: &mut APB1,
    clocks: &Clocks,
) -> (DualCan, Can1Filters)
where
    TX: TxPin<pac::CAN1>,
    RX: RxPin<pac::CAN1>,
{
    let base = pac::CAN1::ptr() as usize;
    let _ = (can1, tx, rx);
    pac::CAN1::enable(apb1);
    pac::CAN1::reset(apb1);
    let filters = Can1Filters {
        regs: &CAN1_FILTERS,
    };
    let handle = HandedOver {
        // SAFETY: CAN1's control and mailbox registers (offsets below 0x200 of the PAC's
        // CAN1 block), whose singleton this function consumed; the filter registers
        // above go to `CAN1_FILTERS` only.
        regs: unsafe { ControlRegs::new(base) },
        filters: Some(filters),
        instance: Instance::Can1,
        apb1_hz: apb1_hz(clocks),
        parts: (),
    };
    (handle, filters)
}

/// Hands CAN2 over: its control and mailbox registers, and CAN1's filter block through
/// `filters` (which only [`can1_dual`] gives). Enables and resets CAN2's clock.
pub fn can2<TX, RX>(
    can2: pac::CAN2,
    tx: TX,
    rx: RX,
    apb1: &mut APB1,
    clocks: &Clocks,
    filters: Can1Filters,
) -> Can2<TX, RX>
where
    TX: TxPin<pac::CAN2>,
    RX: RxPin<pac::CAN2>,
{
    let base = pac::CAN2::ptr() as usize;
    pac::CAN2::enable(apb1);
    pac::CAN2::reset(apb1);
    HandedOver {
        // SAFETY: CAN2's control and mailbox registers (the PAC's CAN2 block; CAN2 has
        // no filter registers of its own), whose singleton this function took (kept in
        // `parts`, given back only for this window).
        regs: unsafe { ControlRegs::new(base) },
        filters: Some(filters),
        instance: Instance::Can2,
        apb1_hz: apb1_hz(clocks),
        parts: HalParts { can: can2, tx, rx },
    }
}

/// Hands CAN3 over (F76x/F77x): its whole block, with its own 14 filter banks. Enables
/// and resets CAN3's clock.
#[cfg(feature = "hal-stm32f7-can3")]
pub fn can3<TX, RX>(
    can3: pac::CAN3,
    tx: TX,
    rx: RX,
    apb1: &mut APB1,
    clocks: &Clocks,
) -> Can3<TX, RX>
where
    TX: TxPin<pac::CAN3>,
    RX: RxPin<pac::CAN3>,
{
    let base = pac::CAN3::ptr() as usize;
    pac::CAN3::enable(apb1);
    pac::CAN3::reset(apb1);
    HandedOver {
        // SAFETY: `base` is CAN3's register block (the PAC's address), whose singleton
        // this function took (kept in `parts`, given back only for this window).
        regs: unsafe { CanRegs::new(base) },
        filters: None,
        instance: Instance::Can3,
        apb1_hz: apb1_hz(clocks),
        parts: HalParts { can: can3, tx, rx },
    }
}

impl<R: Registers, F: Registers, CAN, TX, RX> HandedOver<R, F, HalParts<CAN, TX, RX>> {
    /// Gives the PAC singleton and the pins back, before configuring (the clock stays
    /// enabled; the pins stay in their CAN function).
    pub fn free(self) -> (CAN, TX, RX) {
        let HalParts { can, tx, rx } = self.parts;
        (can, tx, rx)
    }

    /// Takes the singleton and the pins out, to be given back later by [`Parked::free`]
    /// in exchange for this instance's register window.
    pub fn park(self) -> (HandedOver<R, F>, Parked<CAN, TX, RX>) {
        let HandedOver {
            regs,
            filters,
            instance,
            apb1_hz,
            parts,
        } = self;
        (
            HandedOver {
                regs,
                filters,
                instance,
                apb1_hz,
                parts: (),
            },
            Parked { parts },
        )
    }
}

impl<R: Registers, F: Registers, P> HandedOver<R, F, P> {
    /// The instance.
    pub fn instance(&self) -> Instance {
        self.instance
    }

    /// The APB1 clock (Hz) the HAL reported: bxCAN's clock.
    pub fn apb1_hz(&self) -> u32 {
        self.apb1_hz
    }

    /// A configuration for `bitrate` on this APB1 clock ([`Config::from_bitrate`]),
    /// to adjust with the builder before [`HandedOver::configure`].
    pub fn config(&self, bitrate: u32) -> Result<Config, ConfigError> {
        Config::from_bitrate(self.apb1_hz, bitrate)
    }

    /// Whether `config`'s bit timing fits this clock: computed from this APB1 frequency,
    /// or a raw `CAN_BTR` value ([`Config::from_btr`], clock unknown: the caller's word).
    pub fn accepts(&self, config: &Config) -> bool {
        let hz = config.get_clock_hz();
        hz == 0 || hz == self.apb1_hz
    }

    fn refuse(self, error: Error) -> Failed<Self> {
        Failed { error, value: self }
    }

    fn from_can(can: Can<R, F>, apb1_hz: u32, parts: P) -> Self {
        let instance = can.instance();
        let (regs, filters) = can.release();
        HandedOver {
            regs,
            filters,
            instance,
            apb1_hz,
            parts,
        }
    }
}

// The error values hand the whole handle back (nothing is lost).
#[allow(clippy::result_large_err)]
impl<P> HandedOver<CanRegs, CanRegs, P> {
    /// Configures the instance ([`Can::can1`] or [`Can::can3`]): initialization mode,
    /// options, bit timing.
    ///
    /// Errors, with this handle back in [`Failed::value`]: [`Error::InvalidArgument`]
    /// when `config` was computed for another clock ([`HandedOver::accepts`]);
    /// [`Error::Timeout`] when the controller does not acknowledge initialization mode.
    pub fn configure(self, config: &Config) -> Result<Init<CanRegs>, Failed<Self>> {
        self.configure_single(config)
    }
}

#[allow(clippy::result_large_err)]
impl<P> HandedOver<ControlRegs, Can1Filters, P> {
    /// Configures CAN1 ([`Can::can1_dual`]: `CAN2SB` is written when `config` sets
    /// [`Config::can2_start_bank`]) or CAN2 ([`Can::can2`]); errors as for a whole
    /// block's `configure`.
    pub fn configure(
        self,
        config: &Config,
    ) -> Result<Init<ControlRegs, Can1Filters>, Failed<Self>> {
        self.configure_dual(config)
    }
}

// The register types stay generic below, so that the host tests run the same code over
// the behavioural model.
#[allow(clippy::result_large_err)]
impl<R: Registers, P> HandedOver<R, R, P> {
    fn configure_single(self, config: &Config) -> Result<Init<R, R>, Failed<Self>> {
        if !self.accepts(config) {
            return Err(self.refuse(Error::InvalidArgument));
        }
        let HandedOver {
            regs,
            instance,
            apb1_hz,
            parts,
            ..
        } = self;
        let made = match instance {
            Instance::Can3 => Can::can3(regs, config),
            _ => Can::can1(regs, config),
        };
        made.map_err(|f| Failed {
            error: f.error,
            value: Self::from_can(f.value, apb1_hz, parts),
        })
    }
}

#[allow(clippy::result_large_err)]
impl<R: Registers, F: Registers, P> HandedOver<R, F, P> {
    fn configure_dual(self, config: &Config) -> Result<Init<R, F>, Failed<Self>> {
        let accepted = self.accepts(config);
        let HandedOver {
            regs,
            filters,
            instance,
            apb1_hz,
            parts,
        } = self;
        let filters = match filters {
            Some(f) if accepted => f,
            // Another clock, or no filter handle (not built by this module, whose dual
            // handles always have one).
            filters => {
                return Err(Failed {
                    error: Error::InvalidArgument,
                    value: HandedOver {
                        regs,
                        filters,
                        instance,
                        apb1_hz,
                        parts,
                    },
                })
            }
        };
        let made = match instance {
            Instance::Can2 => Can::can2(regs, filters, config),
            _ => Can::can1_dual(regs, filters, config),
        };
        made.map_err(|f| Failed {
            error: f.error,
            value: Self::from_can(f.value, apb1_hz, parts),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regs::{CAN1_BASE, CAN2_BASE, CAN3_BASE};

    #[test]
    fn the_pac_addresses_are_the_register_map_s() {
        assert_eq!(pac::CAN1::ptr() as usize, CAN1_BASE);
        assert_eq!(pac::CAN2::ptr() as usize, CAN2_BASE);
        #[cfg(feature = "hal-stm32f7-can3")]
        assert_eq!(pac::CAN3::ptr() as usize, CAN3_BASE);
        let _ = CAN3_BASE;
    }

    // `configure` over the behavioural model (the same generic code as on target).
    use crate::model::BxCanModel;
    use crate::regs::{BTR, FMR, MCR, MSR};
    use std::{cell::RefCell, rc::Rc};
    use twocan_core::Mode;
    use twocan_sim::{Bus, PollClock};

    type Regs = PollClock<BxCanModel>;

    fn bus() -> Rc<RefCell<Bus>> {
        Rc::new(RefCell::new(Bus::new(500_000).unwrap()))
    }

    fn handed<F: Registers>(
        regs: Regs,
        filters: Option<F>,
        instance: Instance,
    ) -> HandedOver<Regs, F> {
        HandedOver {
            regs,
            filters,
            instance,
            apb1_hz: 54_000_000,
            parts: (),
        }
    }

    #[test]
    fn a_config_for_another_clock_is_refused_before_any_register_is_written() {
        let bus = bus();
        let model = BxCanModel::can1();
        let regs = PollClock::new(model.clone(), &bus, MSR);
        let mcr_at_reset = model.read32(MCR);
        let h = handed::<Regs>(regs, None, Instance::Can1);
        assert_eq!(h.config(500_000).unwrap().get_clock_hz(), 54_000_000);
        let other = Config::from_bitrate(48_000_000, 500_000).unwrap();
        assert!(!h.accepts(&other));
        let back = h.configure_single(&other).unwrap_err();
        assert_eq!(back.error, Error::InvalidArgument);
        assert_eq!(
            (back.value.instance(), back.value.apb1_hz()),
            (Instance::Can1, 54_000_000)
        );
        assert_eq!(model.read32(MCR), mcr_at_reset);
        // The handle handed back configures with a config for its clock.
        let config = back.value.config(500_000).unwrap();
        let init = back
            .value
            .configure_single(&config)
            .map_err(|f| f.error)
            .unwrap();
        assert_eq!(init.can().mode(), Mode::Stopped);
        assert_eq!(
            model.read32(BTR) & 0x03FF_03FF,
            config.btr_value() & 0x03FF_03FF
        );
    }

    #[test]
    fn a_raw_btr_config_is_the_caller_s_word() {
        let bus = bus();
        let model = BxCanModel::can3();
        let h = handed::<Regs>(
            PollClock::new(model.clone(), &bus, MSR),
            None,
            Instance::Can3,
        );
        let raw = Config::from_btr(0x001C_0005).unwrap();
        assert!(h.accepts(&raw));
        let init = h.configure_single(&raw).map_err(|f| f.error).unwrap();
        assert_eq!(init.can().instance(), Instance::Can3);
        assert_eq!(init.can().bank_range(), (0, 14));
    }

    #[test]
    fn dual_handles_share_can1_s_filter_block() {
        let bus = bus();
        let (m1, m2) = BxCanModel::can1_can2();
        let can1 = handed(
            PollClock::new(m1.clone(), &bus, MSR),
            Some(m1.clone()),
            Instance::Can1,
        );
        let can2 = handed(
            PollClock::new(m2.clone(), &bus, MSR),
            Some(m1.clone()),
            Instance::Can2,
        );
        let config1 = can1.config(500_000).unwrap().can2_start_bank(10).unwrap();
        let init1 = can1.configure_dual(&config1).map_err(|f| f.error).unwrap();
        let init2 = can2
            .configure_dual(&Config::from_bitrate(54_000_000, 500_000).unwrap())
            .map_err(|f| f.error)
            .unwrap();
        assert_eq!(crate::regs::fmr::CAN2SB.get(m1.read32(FMR)), 10);
        assert_eq!(init1.can().bank_range(), (0, 10));
        assert_eq!(init2.can().bank_range(), (10, 28));
        assert_eq!(init2.can().instance(), Instance::Can2);
    }

    #[test]
    fn a_dual_handle_without_filters_or_for_another_clock_is_handed_back() {
        let bus = bus();
        let (_m1, m2) = BxCanModel::can1_can2();
        let no_filters =
            handed::<BxCanModel>(PollClock::new(m2.clone(), &bus, MSR), None, Instance::Can2);
        let config = Config::from_bitrate(54_000_000, 500_000).unwrap();
        let back = no_filters.configure_dual(&config).unwrap_err();
        assert_eq!(back.error, Error::InvalidArgument);
        assert_eq!(back.value.instance(), Instance::Can2);
        let (m1, m2) = BxCanModel::can1_can2();
        let other_clock = handed(PollClock::new(m2, &bus, MSR), Some(m1), Instance::Can2);
        let config = Config::from_bitrate(27_000_000, 500_000).unwrap();
        let back = other_clock.configure_dual(&config).unwrap_err();
        assert_eq!(back.error, Error::InvalidArgument);
        assert!(
            back.value.filters.is_some(),
            "the filter handle comes back too"
        );
    }

    // Pins stand-ins (real pins come from splitting a GPIO port, which writes its
    // registers); the singleton is a zero-sized token.
    #[derive(Debug, PartialEq)]
    struct TxStub(u8);
    #[derive(Debug, PartialEq)]
    struct RxStub(u8);

    fn can1_parts() -> HalParts<pac::CAN1, TxStub, RxStub> {
        // SAFETY: a zero-sized token; these tests touch no register through it.
        let dp = unsafe { pac::Peripherals::steal() };
        HalParts {
            can: dp.CAN1,
            tx: TxStub(9),
            rx: RxStub(8),
        }
    }

    fn window(base: usize) -> CanRegs {
        // SAFETY: never read or written in these tests (host addresses).
        unsafe { CanRegs::new(base) }
    }

    #[test]
    fn free_gives_the_singleton_and_pins_back_before_configuring() {
        let h = HandedOver {
            regs: window(CAN1_BASE),
            filters: None::<CanRegs>,
            instance: Instance::Can1,
            apb1_hz: 54_000_000,
            parts: can1_parts(),
        };
        let (_can1, tx, rx) = h.free();
        assert_eq!((tx, rx), (TxStub(9), RxStub(8)));
    }

    #[test]
    fn parked_parts_come_back_only_for_the_instance_s_window() {
        let h = HandedOver {
            regs: window(CAN1_BASE),
            filters: None::<CanRegs>,
            instance: Instance::Can1,
            apb1_hz: 54_000_000,
            parts: can1_parts(),
        };
        let (h, parked) = h.park();
        assert_eq!(h.instance(), Instance::Can1);
        // The driver would run here; its register window comes back by value.
        let HandedOver { regs, .. } = h;
        // Another instance's window is refused, and both are handed back.
        let (parked, other) = parked.free(window(CAN3_BASE)).unwrap_err();
        assert_eq!(other.base(), CAN3_BASE);
        let (_can1, tx, rx) = parked.free(regs).map_err(|_| "refused").unwrap();
        assert_eq!((tx, rx), (TxStub(9), RxStub(8)));
    }

    #[test]
    fn a_failed_configure_hands_the_parts_back_too() {
        let bus = bus();
        let model = BxCanModel::can1();
        let h = HandedOver {
            regs: PollClock::new(model.clone(), &bus, MSR),
            filters: None::<Regs>,
            instance: Instance::Can1,
            apb1_hz: 54_000_000,
            parts: can1_parts(),
        };
        let other = Config::from_bitrate(48_000_000, 500_000).unwrap();
        let back = h.configure_single(&other).unwrap_err();
        assert_eq!(back.error, Error::InvalidArgument);
        let (_can1, tx, rx) = back.value.free();
        assert_eq!((tx, rx), (TxStub(9), RxStub(8)));
    }

    fn tx<CAN, P: TxPin<CAN>>() {}
    fn rx<CAN, P: RxPin<CAN>>() {}

    #[test]
    fn the_table_s_pins_implement_the_traits() {
        rx::<pac::CAN1, Pin<'D', 0, Alternate<9>>>();
        tx::<pac::CAN1, Pin<'D', 1, Alternate<9>>>();
        rx::<pac::CAN1, Pin<'I', 9, Alternate<9>>>();
        tx::<pac::CAN1, Pin<'H', 13, Alternate<9>>>();
        rx::<pac::CAN2, Pin<'B', 12, Alternate<9>>>();
        tx::<pac::CAN2, Pin<'B', 6, Alternate<9>>>();
        #[cfg(feature = "hal-stm32f7-can3")]
        {
            rx::<pac::CAN3, Pin<'A', 8, Alternate<11>>>();
            tx::<pac::CAN3, Pin<'B', 4, Alternate<11>>>();
        }
    }
}
