//! Hand-over from `stm32f7xx-hal` (0.8, feature `hal-stm32f7`; its items are also
//! `twocan_bxcan::hal`'s): the bxCAN instances built from the HAL's PAC singletons, its
//! [`Clocks`] and CAN pins, with no `unsafe` in the program. The handle and what it does
//! are the generic [`crate::hal`]'s; this module has the F7's pins, PAC types and RCC.
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

use crate::hal::{can_pins, pac_can, Can1Filters, DualCan, HalParts, HandedOver, RxPin, TxPin};
use crate::instance::Instance;
use crate::regs::{CanRegs, ControlRegs};

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

pac_can!(pac::CAN1 => CanRegs, pac::CAN2 => ControlRegs);
#[cfg(feature = "hal-stm32f7-can3")]
pac_can!(pac::CAN3 => CanRegs);

/// CAN1 alone (its whole block, filters included), with its singleton and pins.
pub type Can1<TX, RX> = HandedOver<CanRegs, CanRegs, HalParts<pac::CAN1, TX, RX>>;
/// CAN2 of a dual set-up: control registers, CAN1's filter block shared; with its
/// singleton and pins.
pub type Can2<TX, RX> = HandedOver<ControlRegs, Can1Filters, HalParts<pac::CAN2, TX, RX>>;
/// CAN3 (its whole block, with its own 14 filter banks), with its singleton and pins.
#[cfg(feature = "hal-stm32f7-can3")]
pub type Can3<TX, RX> = HandedOver<CanRegs, CanRegs, HalParts<pac::CAN3, TX, RX>>;

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
    pac::CAN1::enable(apb1);
    pac::CAN1::reset(apb1);
    // SAFETY: CAN1's singleton, consumed here; its clock was just enabled.
    unsafe { crate::hal::whole(can1, tx, rx, Instance::Can1, apb1_hz(clocks), None) }
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
    pac::CAN1::enable(apb1);
    pac::CAN1::reset(apb1);
    // SAFETY: CAN1's singleton, consumed here; its clock was just enabled.
    unsafe { crate::hal::dual(can1, tx, rx, apb1_hz(clocks), None) }
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
    pac::CAN2::enable(apb1);
    pac::CAN2::reset(apb1);
    // SAFETY: CAN2's singleton, consumed here; its clock was just enabled.
    unsafe { crate::hal::control(can2, tx, rx, apb1_hz(clocks), None, filters) }
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
    pac::CAN3::enable(apb1);
    pac::CAN3::reset(apb1);
    // SAFETY: CAN3's singleton, consumed here; its clock was just enabled.
    unsafe { crate::hal::whole(can3, tx, rx, Instance::Can3, apb1_hz(clocks), None) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;
    use crate::hal::{HalParts, HandedOver};
    use crate::model::BxCanModel;
    use crate::regs::MSR;
    use crate::regs::{CAN1_BASE, CAN2_BASE, CAN3_BASE};
    use std::{cell::RefCell, rc::Rc};
    use twocan_core::Error;
    use twocan_sim::{Bus, PollClock};

    #[test]
    fn the_pac_addresses_are_the_register_map_s() {
        assert_eq!(pac::CAN1::ptr() as usize, CAN1_BASE);
        assert_eq!(pac::CAN2::ptr() as usize, CAN2_BASE);
        #[cfg(feature = "hal-stm32f7-can3")]
        assert_eq!(pac::CAN3::ptr() as usize, CAN3_BASE);
        let _ = CAN3_BASE;
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
            chip: None,
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
            chip: None,
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
        let bus = Rc::new(RefCell::new(Bus::new(500_000).unwrap()));
        let model = BxCanModel::can1();
        let h = HandedOver {
            regs: PollClock::new(model.clone(), &bus, MSR),
            filters: None::<PollClock<BxCanModel>>,
            instance: Instance::Can1,
            apb1_hz: 54_000_000,
            chip: None,
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
