//! Hand-over from `stm32f4xx-hal` (0.23, on `stm32f4` 0.16; feature `hal-stm32f4`): the
//! bxCAN instances of an STM32F4 built from the HAL's PAC singletons, its `Rcc` (clocks
//! and the peripheral enables) and CAN pins, with no `unsafe` in the program. The handle
//! and what it does are the generic [`crate::hal`]'s; this module has the F4's pins, PAC
//! types and RCC.
//!
//! # Chip
//!
//! The chip is the one the program's own `stm32f4xx-hal` dependency selects (one of its
//! chip features, e.g. `stm32f446`, `stm32f407`). The hand-over does not know which:
//! tell it with [`HandedOver::with_chip`] (e.g. `&twocan_bxcan::chip::STM32F446`), and
//! [`HandedOver::config`] then checks the APB1 clock against the part's limit and makes
//! the driver read its instances and banks (`twocan_bxcan::Config::chip`). CAN3 (F413/F423)
//! is not covered here.
//!
//! # Pins
//!
//! From the alternate-function mapping tables of the data sheets (DS10693 STM32F446xx
//! Table 11; DS8626 STM32F405/407), column AF9:
//!
//! | instance | function | RX                   | TX                    |
//! |----------|----------|----------------------|-----------------------|
//! | CAN1     | AF9      | PA11, PB8, PD0, PI9  | PA12, PB9, PD1, PH13  |
//! | CAN2     | AF9      | PB5, PB12            | PB6, PB13             |
//!
//! (PI9/PH13: the 176-pin F405/F407 only; a chip without them has no such pin to split
//! from the HAL's ports.)
//!
//! The examples below are fenced `ignore` for rustdoc: `stm32f4xx-hal` cannot be built on
//! the host next to the tests' `critical-section/std` (see the feature's note in
//! `Cargo.toml`), so `cargo test` cannot compile them. `tools/hal-doctests/run.sh` (CI)
//! cross-builds each for `thumbv7em-none-eabihf` (STM32F446) instead: the plain ones must
//! build; the `compile_fail,E0277` ones must fail, on [`TxPin`]/[`RxPin`]. Checked
//! wherever the module compiles, too: the table's pins implement the traits (a `const`
//! item below).
//!
//! CAN1 on PA11 (RX) and PA12 (TX), in AF9, on a NUCLEO-F446RE:
//!
//! ```ignore
//! # use stm32f4xx_hal::{pac, prelude::*, rcc::Config};
//! # use twocan_bxcan::hal::f4;
//! # let dp = pac::Peripherals::take().unwrap();
//! let mut rcc = dp.RCC.freeze(Config::hsi().sysclk(90.MHz()).pclk1(45.MHz()));
//! let gpioa = dp.GPIOA.split(&mut rcc);
//! let (rx, tx) = (gpioa.pa11.into_alternate::<9>(), gpioa.pa12.into_alternate::<9>());
//! let can1 = f4::can1(dp.CAN1, tx, rx, &mut rcc).with_chip(&twocan_bxcan::chip::STM32F446);
//! let config = can1.config(500_000).unwrap();
//! let init = can1.configure(&config).map_err(|f| f.error).unwrap();
//! ```
//!
//! CAN2's pins (PB12, PB13) given to CAN1 do not compile (`compile_fail`):
//!
//! ```ignore,compile_fail,E0277
//! # use stm32f4xx_hal::{pac, prelude::*, rcc::Config};
//! # use twocan_bxcan::hal::f4;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let mut rcc = dp.RCC.freeze(Config::hsi());
//! let gpiob = dp.GPIOB.split(&mut rcc);
//! let (rx, tx) = (gpiob.pb12.into_alternate::<9>(), gpiob.pb13.into_alternate::<9>());
//! let can1 = f4::can1(dp.CAN1, tx, rx, &mut rcc);
//! ```
//!
//! Nor does the right pin in another alternate function (PB9 in AF4; `compile_fail`):
//!
//! ```ignore,compile_fail,E0277
//! # use stm32f4xx_hal::{pac, prelude::*, rcc::Config};
//! # use twocan_bxcan::hal::f4;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let mut rcc = dp.RCC.freeze(Config::hsi());
//! let gpiob = dp.GPIOB.split(&mut rcc);
//! let (rx, tx) = (gpiob.pb8.into_alternate::<9>(), gpiob.pb9.into_alternate::<4>());
//! let can1 = f4::can1(dp.CAN1, tx, rx, &mut rcc);
//! ```
//!
//! Nor TX and RX swapped (`compile_fail`):
//!
//! ```ignore,compile_fail,E0277
//! # use stm32f4xx_hal::{pac, prelude::*, rcc::Config};
//! # use twocan_bxcan::hal::f4;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let mut rcc = dp.RCC.freeze(Config::hsi());
//! let gpioa = dp.GPIOA.split(&mut rcc);
//! let (rx, tx) = (gpioa.pa11.into_alternate::<9>(), gpioa.pa12.into_alternate::<9>());
//! let can1 = f4::can1(dp.CAN1, rx, tx, &mut rcc);
//! ```
//!
//! CAN1 and CAN2 together: [`can1_dual`] gives the filter-block handle [`can2`] needs.
//!
//! ```ignore
//! # use stm32f4xx_hal::{pac, prelude::*, rcc::Config};
//! # use twocan_bxcan::hal::f4;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let mut rcc = dp.RCC.freeze(Config::hsi().sysclk(90.MHz()).pclk1(45.MHz()));
//! let gpioa = dp.GPIOA.split(&mut rcc);
//! let gpiob = dp.GPIOB.split(&mut rcc);
//! let (rx, tx) = (gpioa.pa11.into_alternate::<9>(), gpioa.pa12.into_alternate::<9>());
//! let (can1, filters) = f4::can1_dual(dp.CAN1, tx, rx, &mut rcc);
//! let (rx2, tx2) = (gpiob.pb12.into_alternate::<9>(), gpiob.pb13.into_alternate::<9>());
//! let can2 = f4::can2(dp.CAN2, tx2, rx2, &mut rcc, filters);
//! ```

use stm32f4xx_hal::gpio::{Alternate, Pin};
use stm32f4xx_hal::pac;
use stm32f4xx_hal::rcc::{Enable, Rcc, Reset};

use crate::hal::{can_pins, pac_can, Can1Filters, DualCan, HalParts, HandedOver, RxPin, TxPin};
use crate::instance::Instance;
use crate::regs::{CanRegs, ControlRegs};

// DS10693 Table 11 / DS8626, "Alternate function mapping", AF9: CAN1_RX, CAN1_TX.
can_pins!(pac::CAN1, 9, RxPin: ('A', 11), ('B', 8), ('D', 0), ('I', 9));
can_pins!(pac::CAN1, 9, TxPin: ('A', 12), ('B', 9), ('D', 1), ('H', 13));
// AF9: CAN2_RX, CAN2_TX.
can_pins!(pac::CAN2, 9, RxPin: ('B', 5), ('B', 12));
can_pins!(pac::CAN2, 9, TxPin: ('B', 6), ('B', 13));

pac_can!(pac::CAN1 => CanRegs, pac::CAN2 => ControlRegs);

/// CAN1 alone (its whole block, filters included), with its singleton and pins.
pub type Can1<TX, RX> = HandedOver<CanRegs, CanRegs, HalParts<pac::CAN1, TX, RX>>;
/// CAN2 of a dual set-up: control registers, CAN1's filter block shared; with its
/// singleton and pins.
pub type Can2<TX, RX> = HandedOver<ControlRegs, Can1Filters, HalParts<pac::CAN2, TX, RX>>;

/// The APB1 frequency the HAL set (Hz): bxCAN's clock (RM0390 §30.7.7).
fn apb1_hz(rcc: &Rcc) -> u32 {
    rcc.clocks.pclk1().raw()
}

/// Hands CAN1 over alone: the whole register block (filters included), so CAN2 cannot
/// be built (use [`can1_dual`] for both). Enables and resets CAN1's clock
/// (`RCC_APB1ENR.CAN1EN`, `RCC_APB1RSTR.CAN1RST`; RM0390 §6.3.13, §6.3.8).
pub fn can1<TX, RX>(can1: pac::CAN1, tx: TX, rx: RX, rcc: &mut Rcc) -> Can1<TX, RX>
where
    TX: TxPin<pac::CAN1>,
    RX: RxPin<pac::CAN1>,
{
    pac::CAN1::enable(rcc);
    pac::CAN1::reset(rcc);
    // SAFETY: CAN1's singleton, consumed here; its clock was just enabled.
    unsafe { crate::hal::whole(can1, tx, rx, Instance::Can1, apb1_hz(rcc), None) }
}

/// Hands CAN1 over as the master of a dual set-up: CAN1 gets its control and mailbox
/// registers, and the returned [`Can1Filters`] reaches the filter block it shares with
/// CAN2 (pass a copy to [`can2`]). Enables and resets CAN1's clock (which CAN2's
/// filters need too, RM0390 §30.2).
pub fn can1_dual<TX, RX>(can1: pac::CAN1, tx: TX, rx: RX, rcc: &mut Rcc) -> (DualCan, Can1Filters)
where
    TX: TxPin<pac::CAN1>,
    RX: RxPin<pac::CAN1>,
{
    pac::CAN1::enable(rcc);
    pac::CAN1::reset(rcc);
    // SAFETY: CAN1's singleton, consumed here; its clock was just enabled.
    unsafe { crate::hal::dual(can1, tx, rx, apb1_hz(rcc), None) }
}

/// Hands CAN2 over: its control and mailbox registers, and CAN1's filter block through
/// `filters` (which only [`can1_dual`] gives). Enables and resets CAN2's clock.
pub fn can2<TX, RX>(
    can2: pac::CAN2,
    tx: TX,
    rx: RX,
    rcc: &mut Rcc,
    filters: Can1Filters,
) -> Can2<TX, RX>
where
    TX: TxPin<pac::CAN2>,
    RX: RxPin<pac::CAN2>,
{
    pac::CAN2::enable(rcc);
    pac::CAN2::reset(rcc);
    // SAFETY: CAN2's singleton, consumed here; its clock was just enabled.
    unsafe { crate::hal::control(can2, tx, rx, apb1_hz(rcc), None, filters) }
}

// The table's pins implement the traits: checked wherever this module compiles (it has
// no host tests, see the module notes).
const _: fn() = || {
    fn tx<CAN, P: TxPin<CAN>>() {}
    fn rx<CAN, P: RxPin<CAN>>() {}
    rx::<pac::CAN1, Pin<'A', 11, Alternate<9>>>();
    tx::<pac::CAN1, Pin<'A', 12, Alternate<9>>>();
    rx::<pac::CAN1, Pin<'B', 8, Alternate<9>>>();
    tx::<pac::CAN1, Pin<'B', 9, Alternate<9>>>();
    rx::<pac::CAN1, Pin<'D', 0, Alternate<9>>>();
    tx::<pac::CAN1, Pin<'D', 1, Alternate<9>>>();
    rx::<pac::CAN2, Pin<'B', 12, Alternate<9>>>();
    tx::<pac::CAN2, Pin<'B', 13, Alternate<9>>>();
    rx::<pac::CAN2, Pin<'B', 5, Alternate<9>>>();
    tx::<pac::CAN2, Pin<'B', 6, Alternate<9>>>();
};
