//! The connectivity line (STM32F105/F107; feature `hal-stm32f1-connectivity`, the
//! program's `stm32f1xx-hal` on `stm32f105` or `stm32f107`): CAN1 and CAN2, sharing
//! CAN1's 28 filter banks split at `CAN_FMR.CAN2SB` (RM0008 §24.2 "Dual CAN"), as the
//! F4's and F7's. The handles configure for [`chip::STM32F105_F107`].
//!
//! Pins (RM0008 §9.3.3 Tables 36 and 37), routed by `AFIO_MAPR.CAN1_REMAP` (bits 14:13)
//! and `CAN2_REMAP` (bit 22; RM0008 §9.4.2), which the hand-over writes; TX in
//! alternate-function push-pull, RX an input, floating or pull-up:
//!
//! | instance | remap | RX   | TX   |
//! |----------|-------|------|------|
//! | CAN1     | 00    | PA11 | PA12 |
//! | CAN1     | 10    | PB8  | PB9  |
//! | CAN1     | 11    | PD0  | PD1  |
//! | CAN2     | 0     | PB12 | PB13 |
//! | CAN2     | 1     | PB5  | PB6  |
//!
//! The connectivity line's USB (OTG FS) has its own SRAM: no USB singleton is taken.
//!
//! These examples are cross-built for `thumbv7m-none-eabi` (STM32F107) by
//! `tools/hal-doctests/run.sh`, as the module's others. CAN1 and CAN2 together:
//!
//! ```ignore
//! # use stm32f1xx_hal::{pac, prelude::*, rcc};
//! # use twocan_bxcan::hal::f1;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let mut flash = dp.FLASH.constrain();
//! let mut rcc = dp.RCC.freeze(rcc::Config::hse(25.MHz()).sysclk(72.MHz()).pclk1(36.MHz()), &mut flash.acr);
//! let mut afio = dp.AFIO.constrain(&mut rcc);
//! let mut gpioa = dp.GPIOA.split(&mut rcc);
//! let mut gpiob = dp.GPIOB.split(&mut rcc);
//! let rx1 = gpioa.pa11.into_floating_input(&mut gpioa.crh);
//! let tx1 = gpioa.pa12.into_alternate_push_pull(&mut gpioa.crh);
//! let (can1, filters) = f1::can1_dual(dp.CAN1, tx1, rx1, &mut afio.mapr, &mut rcc);
//! let rx2 = gpiob.pb12.into_floating_input(&mut gpiob.crh);
//! let tx2 = gpiob.pb13.into_alternate_push_pull(&mut gpiob.crh);
//! let can2 = f1::can2(dp.CAN2, tx2, rx2, &mut afio.mapr, &mut rcc, filters);
//! let config = can1.config(500_000).unwrap().can2_start_bank(14).unwrap();
//! let init1 = can1.configure(&config).map_err(|f| f.error).unwrap();
//! let config2 = can2.config(500_000).unwrap();
//! let init2 = can2.configure(&config2).map_err(|f| f.error).unwrap();
//! ```
//!
//! CAN1 alone, on the whole block (then CAN2 cannot be built):
//!
//! ```ignore
//! # use stm32f1xx_hal::{pac, prelude::*, rcc};
//! # use twocan_bxcan::hal::f1;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let mut flash = dp.FLASH.constrain();
//! # let mut rcc = dp.RCC.freeze(rcc::Config::hsi(), &mut flash.acr);
//! # let mut afio = dp.AFIO.constrain(&mut rcc);
//! let mut gpiob = dp.GPIOB.split(&mut rcc);
//! let rx = gpiob.pb8.into_pull_up_input(&mut gpiob.crh);
//! let tx = gpiob.pb9.into_alternate_push_pull(&mut gpiob.crh);
//! let can1 = f1::can1(dp.CAN1, tx, rx, &mut afio.mapr, &mut rcc);
//! ```
//!
//! CAN2's pins given to CAN1 do not compile (`compile_fail`):
//!
//! ```ignore,compile_fail,E0277
//! # use stm32f1xx_hal::{pac, prelude::*, rcc};
//! # use twocan_bxcan::hal::f1;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let mut flash = dp.FLASH.constrain();
//! # let mut rcc = dp.RCC.freeze(rcc::Config::hsi(), &mut flash.acr);
//! # let mut afio = dp.AFIO.constrain(&mut rcc);
//! let mut gpiob = dp.GPIOB.split(&mut rcc);
//! let rx = gpiob.pb12.into_floating_input(&mut gpiob.crh);
//! let tx = gpiob.pb13.into_alternate_push_pull(&mut gpiob.crh);
//! let (can1, filters) = f1::can1_dual(dp.CAN1, tx, rx, &mut afio.mapr, &mut rcc);
//! ```
//!
//! Nor CAN1's given to CAN2 (`compile_fail`):
//!
//! ```ignore,compile_fail,E0277
//! # use stm32f1xx_hal::{pac, prelude::*, rcc};
//! # use twocan_bxcan::hal::f1;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let mut flash = dp.FLASH.constrain();
//! # let mut rcc = dp.RCC.freeze(rcc::Config::hsi(), &mut flash.acr);
//! # let mut afio = dp.AFIO.constrain(&mut rcc);
//! let mut gpioa = dp.GPIOA.split(&mut rcc);
//! let mut gpiob = dp.GPIOB.split(&mut rcc);
//! let rx1 = gpioa.pa11.into_floating_input(&mut gpioa.crh);
//! let tx1 = gpioa.pa12.into_alternate_push_pull(&mut gpioa.crh);
//! let (can1, filters) = f1::can1_dual(dp.CAN1, tx1, rx1, &mut afio.mapr, &mut rcc);
//! let rx2 = gpiob.pb8.into_floating_input(&mut gpiob.crh);
//! let tx2 = gpiob.pb9.into_alternate_push_pull(&mut gpiob.crh);
//! let can2 = f1::can2(dp.CAN2, tx2, rx2, &mut afio.mapr, &mut rcc, filters);
//! ```

use stm32f1xx_hal::afio::MAPR;
use stm32f1xx_hal::gpio::{Alternate, Floating, Input, Pin, PullUp, PushPull};
use stm32f1xx_hal::pac;
use stm32f1xx_hal::rcc::{Enable, Rcc, Reset};

use super::{can_pin_pairs, CanPins};
use crate::chip;
use crate::hal::{pac_can, sealed, Can1Filters, DualCan, HalParts, HandedOver};
use crate::instance::Instance;
use crate::regs::{CanRegs, ControlRegs};

// RM0008 §9.3.3 Table 37 "CAN2 alternate function remapping" (`CAN2_REMAP`).
can_pin_pairs! {
    pac::CAN2:
    0: ('B', 13), ('B', 12);
    1: ('B', 6), ('B', 5);
}

pac_can!(pac::CAN1 => CanRegs, pac::CAN2 => ControlRegs);

/// CAN1 alone (its whole block, all 28 banks' registers), with its singleton and pins.
pub type Can1<TX, RX> = HandedOver<CanRegs, CanRegs, HalParts<pac::CAN1, TX, RX>>;
/// CAN2 of a dual set-up: control registers, CAN1's filter block shared; with its
/// singleton and pins.
pub type Can2<TX, RX> = HandedOver<ControlRegs, Can1Filters, HalParts<pac::CAN2, TX, RX>>;

/// Routes CAN1 to its pair (`CAN1_REMAP`), enables and resets its clock
/// (`RCC_APB1ENR.CAN1EN` bit 25, `RCC_APB1RSTR.CAN1RST`; RM0008 §7.3.8, §7.3.5); the
/// APB1 frequency.
fn can1_on<TX, RX>(mapr: &mut MAPR, rcc: &mut Rcc) -> u32
where
    (TX, RX): CanPins<pac::CAN1>,
{
    let remap = <(TX, RX) as CanPins<pac::CAN1>>::REMAP;
    // SAFETY: `CAN1_REMAP` is a 2-bit field; the values come from the pairs' table
    // (RM0008 §9.4.2).
    mapr.modify_mapr(|_, w| unsafe { w.can1_remap().bits(remap) });
    pac::CAN1::enable(rcc);
    pac::CAN1::reset(rcc);
    rcc.clocks.pclk1().raw()
}

/// Hands CAN1 over alone: its whole register block (filters included), so CAN2 cannot
/// be built (use [`can1_dual`] for both); routed, clocked and reset.
pub fn can1<TX, RX>(can1: pac::CAN1, tx: TX, rx: RX, mapr: &mut MAPR, rcc: &mut Rcc) -> Can1<TX, RX>
where
    (TX, RX): CanPins<pac::CAN1>,
{
    let apb1_hz = can1_on::<TX, RX>(mapr, rcc);
    let chip = Some(&chip::STM32F105_F107);
    // SAFETY: CAN1's singleton, consumed here; its clock was just enabled.
    unsafe { crate::hal::whole(can1, tx, rx, Instance::Can1, apb1_hz, chip) }
}

/// Hands CAN1 over as the master of a dual set-up: its control and mailbox registers,
/// and the [`Can1Filters`] handle of the filter block it shares with CAN2 (give it to
/// [`can2`]); routed, clocked and reset (CAN2's filters need CAN1's clock, RM0008 §24.2).
pub fn can1_dual<TX, RX>(
    can1: pac::CAN1,
    tx: TX,
    rx: RX,
    mapr: &mut MAPR,
    rcc: &mut Rcc,
) -> (DualCan, Can1Filters)
where
    (TX, RX): CanPins<pac::CAN1>,
{
    let apb1_hz = can1_on::<TX, RX>(mapr, rcc);
    // SAFETY: CAN1's singleton, consumed here; its clock was just enabled.
    unsafe { crate::hal::dual(can1, tx, rx, apb1_hz, Some(&chip::STM32F105_F107)) }
}

/// Hands CAN2 over: its control and mailbox registers, and CAN1's filter block through
/// `filters` (which only [`can1_dual`] gives); routed (`CAN2_REMAP`), clocked and reset
/// (`RCC_APB1ENR.CAN2EN` bit 26, `RCC_APB1RSTR.CAN2RST`).
pub fn can2<TX, RX>(
    can2: pac::CAN2,
    tx: TX,
    rx: RX,
    mapr: &mut MAPR,
    rcc: &mut Rcc,
    filters: Can1Filters,
) -> Can2<TX, RX>
where
    (TX, RX): CanPins<pac::CAN2>,
{
    let remap = <(TX, RX) as CanPins<pac::CAN2>>::REMAP;
    mapr.modify_mapr(|_, w| w.can2_remap().bit(remap != 0));
    pac::CAN2::enable(rcc);
    pac::CAN2::reset(rcc);
    let apb1_hz = rcc.clocks.pclk1().raw();
    let chip = Some(&chip::STM32F105_F107);
    // SAFETY: CAN2's singleton, consumed here; its clock was just enabled.
    unsafe { crate::hal::control(can2, tx, rx, apb1_hz, chip, filters) }
}
