//! Hand-over from `stm32f1xx-hal` (0.11, on `stm32f1` 0.16; feature `hal-stm32f1`): the
//! CAN of an STM32F103 (low- to XL-density performance line; the Blue Pill's F103C8)
//! built from the HAL's PAC singletons, its `Rcc`, its `AFIO_MAPR` and the CAN pins, with
//! no `unsafe` in the program. The handle and what it does are the generic
//! [`crate::hal`]'s; this module has the F103's pins, remap and RCC.
//!
//! The connectivity line (STM32F105/F107: CAN1 + CAN2 sharing 28 banks, no USB SRAM
//! sharing) takes feature `hal-stm32f1-connectivity` with the program's HAL on
//! `stm32f105` or `stm32f107`: then this module has `can1`, `can1_dual` and `can2`
//! (`AFIO_MAPR.CAN1_REMAP`, `CAN2_REMAP`; module `connectivity`) instead of `can`.
//!
//! # USB
//!
//! The F103's CAN and USB share a dedicated 512-byte SRAM and "cannot be used
//! concurrently" (RM0008 §24.2, note): `can` takes the USB singleton with the CAN's, so
//! a program that holds the CAN cannot start the USB peripheral through the HAL. They
//! come back together ([`crate::hal::HandedOver::free`], [`crate::hal::Parked::free`]).
//!
//! # Pins
//!
//! The F1 has no alternate-function numbers: the CAN's pins are chosen by
//! `AFIO_MAPR.CAN_REMAP` (RM0008 §9.3.3, §9.4.2), which `can` writes for the pair it is
//! given; TX must be an alternate-function push-pull output, RX an input, floating or
//! pull-up (RM0008 §9.1.11 Table 27):
//!
//! | `CAN_REMAP` | RX   | TX   |
//! |-------------|------|------|
//! | 00          | PA11 | PA12 |
//! | 10          | PB8  | PB9  |
//! | 11          | PD0  | PD1  |
//!
//! Only these pairs implement [`CanPins`]: a pin of another pair, RX and TX swapped, or
//! TX not in alternate push-pull mode does not compile. (PD0/PD1: 100- and 144-pin
//! packages; the 48-pin F103C8 has no PD0/PD1 to split from the HAL's ports.)
//!
//! The examples below are fenced `ignore` for rustdoc, for the reason given in the `f4`
//! module's notes (the HAL cannot share a host build with the tests'
//! `critical-section/std`); `tools/hal-doctests/run.sh` (CI) cross-builds each for
//! `thumbv7m-none-eabi` instead: the first must build, the others must fail on
//! [`CanPins`] (`compile_fail,E0277`).
//!
//! ```ignore
//! # use stm32f1xx_hal::{pac, prelude::*, rcc};
//! # use twocan_bxcan::hal::f1;
//! # let dp = pac::Peripherals::take().unwrap();
//! let mut flash = dp.FLASH.constrain();
//! let mut rcc = dp.RCC.freeze(rcc::Config::hse(8.MHz()).sysclk(72.MHz()).pclk1(36.MHz()), &mut flash.acr);
//! let mut afio = dp.AFIO.constrain(&mut rcc);
//! let mut gpiob = dp.GPIOB.split(&mut rcc);
//! let rx = gpiob.pb8.into_floating_input(&mut gpiob.crh);
//! let tx = gpiob.pb9.into_alternate_push_pull(&mut gpiob.crh);
//! let can = f1::can(dp.CAN, dp.USB, tx, rx, &mut afio.mapr, &mut rcc);
//! let config = can.config(500_000).unwrap(); // for the STM32F103: 14 banks, APB1 ≤ 36 MHz
//! let init = can.configure(&config).map_err(|f| f.error).unwrap();
//! ```
//!
//! RX and TX of different pairs do not compile (`compile_fail`):
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
//! let tx = gpioa.pa12.into_alternate_push_pull(&mut gpioa.crh);
//! let rx = gpiob.pb8.into_floating_input(&mut gpiob.crh);
//! let can = f1::can(dp.CAN, dp.USB, tx, rx, &mut afio.mapr, &mut rcc);
//! ```
//!
//! Nor the right pins in the wrong mode: TX as an open-drain alternate function, or as
//! a plain output (`compile_fail`):
//!
//! ```ignore,compile_fail,E0277
//! # use stm32f1xx_hal::{pac, prelude::*, rcc};
//! # use twocan_bxcan::hal::f1;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let mut flash = dp.FLASH.constrain();
//! # let mut rcc = dp.RCC.freeze(rcc::Config::hsi(), &mut flash.acr);
//! # let mut afio = dp.AFIO.constrain(&mut rcc);
//! let mut gpiob = dp.GPIOB.split(&mut rcc);
//! let rx = gpiob.pb8.into_floating_input(&mut gpiob.crh);
//! let tx = gpiob.pb9.into_alternate_open_drain(&mut gpiob.crh);
//! let can = f1::can(dp.CAN, dp.USB, tx, rx, &mut afio.mapr, &mut rcc);
//! ```
//!
//! ```ignore,compile_fail,E0277
//! # use stm32f1xx_hal::{pac, prelude::*, rcc};
//! # use twocan_bxcan::hal::f1;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let mut flash = dp.FLASH.constrain();
//! # let mut rcc = dp.RCC.freeze(rcc::Config::hsi(), &mut flash.acr);
//! # let mut afio = dp.AFIO.constrain(&mut rcc);
//! let mut gpiob = dp.GPIOB.split(&mut rcc);
//! let rx = gpiob.pb8.into_floating_input(&mut gpiob.crh);
//! let tx = gpiob.pb9.into_push_pull_output(&mut gpiob.crh);
//! let can = f1::can(dp.CAN, dp.USB, tx, rx, &mut afio.mapr, &mut rcc);
//! ```
//!
//! Nor TX and RX swapped (`compile_fail`):
//!
//! ```ignore,compile_fail,E0277
//! # use stm32f1xx_hal::{pac, prelude::*, rcc};
//! # use twocan_bxcan::hal::f1;
//! # let dp = pac::Peripherals::take().unwrap();
//! # let mut flash = dp.FLASH.constrain();
//! # let mut rcc = dp.RCC.freeze(rcc::Config::hsi(), &mut flash.acr);
//! # let mut afio = dp.AFIO.constrain(&mut rcc);
//! let mut gpiob = dp.GPIOB.split(&mut rcc);
//! let rx = gpiob.pb8.into_floating_input(&mut gpiob.crh);
//! let tx = gpiob.pb9.into_alternate_push_pull(&mut gpiob.crh);
//! let can = f1::can(dp.CAN, dp.USB, rx, tx, &mut afio.mapr, &mut rcc);
//! ```

#[cfg(not(feature = "hal-stm32f1-connectivity"))]
use stm32f1xx_hal::afio::MAPR;
use stm32f1xx_hal::gpio::{Alternate, Floating, Input, Pin, PullUp, PushPull};
use stm32f1xx_hal::pac;
#[cfg(not(feature = "hal-stm32f1-connectivity"))]
use stm32f1xx_hal::rcc::{Enable, Rcc, Reset};

#[cfg(not(feature = "hal-stm32f1-connectivity"))]
use crate::chip;
use crate::hal::sealed;
#[cfg(not(feature = "hal-stm32f1-connectivity"))]
use crate::hal::{HalParts, HandedOver, PacCan};
#[cfg(not(feature = "hal-stm32f1-connectivity"))]
use crate::instance::Instance;
#[cfg(not(feature = "hal-stm32f1-connectivity"))]
use crate::regs::CanRegs;

#[cfg(feature = "hal-stm32f1-connectivity")]
#[path = "f1_connectivity.rs"]
pub mod connectivity;
#[cfg(feature = "hal-stm32f1-connectivity")]
pub use connectivity::*;

/// A (TX, RX) pin pair of the instance `CAN` (its PAC singleton's type: `pac::CAN` on the
/// F103, `pac::CAN1`/`pac::CAN2` on the connectivity line), with its `AFIO_MAPR` remap
/// value.
pub trait CanPins<CAN>: sealed::Sealed {
    /// The `CAN_REMAP` (`CAN1_REMAP`) or `CAN2_REMAP` value that routes the instance to
    /// this pair (RM0008 §9.3.3).
    const REMAP: u8;
}

macro_rules! can_pin_pairs {
    ($can:ty: $($remap:literal: ($tp:literal, $tn:literal), ($rp:literal, $rn:literal);)+) => {
        $(
            can_pin_pairs!(@one $can, $remap, $tp, $tn, $rp, $rn, Floating);
            can_pin_pairs!(@one $can, $remap, $tp, $tn, $rp, $rn, PullUp);
        )+
    };
    (@one $can:ty, $remap:literal, $tp:literal, $tn:literal, $rp:literal, $rn:literal, $pull:ty) => {
        impl sealed::Sealed
            for (Pin<$tp, $tn, Alternate<PushPull>>, Pin<$rp, $rn, Input<$pull>>)
        {
        }
        impl CanPins<$can>
            for (Pin<$tp, $tn, Alternate<PushPull>>, Pin<$rp, $rn, Input<$pull>>)
        {
            const REMAP: u8 = $remap;
        }
    };
}
#[cfg(feature = "hal-stm32f1-connectivity")]
use can_pin_pairs;

/// The PAC's CAN1: `CAN` on the F103, `CAN1` on the connectivity line.
#[cfg(not(feature = "hal-stm32f1-connectivity"))]
type Can1Pac = pac::CAN;
#[cfg(feature = "hal-stm32f1-connectivity")]
type Can1Pac = pac::CAN1;

// RM0008 §9.3.3 Table 36 "CAN alternate function remapping" (`CAN_REMAP`, `CAN1_REMAP`
// on the connectivity line: the same pins).
can_pin_pairs! {
    Can1Pac:
    0b00: ('A', 12), ('A', 11);
    0b10: ('B', 9), ('B', 8);
    0b11: ('D', 1), ('D', 0);
}

#[cfg(not(feature = "hal-stm32f1-connectivity"))]
impl sealed::Sealed for (pac::CAN, pac::USB) {}
#[cfg(not(feature = "hal-stm32f1-connectivity"))]
impl PacCan for (pac::CAN, pac::USB) {
    type Window = CanRegs;
    fn base() -> usize {
        pac::CAN::ptr() as usize
    }
}

/// The F103's CAN (its whole block, 14 filter banks), with its singleton, USB's, and the
/// pins.
#[cfg(not(feature = "hal-stm32f1-connectivity"))]
pub type Can<TX, RX> = HandedOver<CanRegs, CanRegs, HalParts<(pac::CAN, pac::USB), TX, RX>>;

/// Hands the F103's CAN over: routes it to the pin pair (`AFIO_MAPR.CAN_REMAP`), enables
/// and resets its clock (`RCC_APB1ENR.CANEN`, `RCC_APB1RSTR.CANRST`; RM0008 §7.3.8,
/// §7.3.5), and keeps the USB singleton out of the program's reach while it holds the
/// CAN. The handle configures for [`chip::STM32F103`] ([`HandedOver::config`]).
#[cfg(not(feature = "hal-stm32f1-connectivity"))]
pub fn can<TX, RX>(
    can: pac::CAN,
    usb: pac::USB,
    tx: TX,
    rx: RX,
    mapr: &mut MAPR,
    rcc: &mut Rcc,
) -> Can<TX, RX>
where
    (TX, RX): CanPins<pac::CAN>,
{
    let remap = <(TX, RX) as CanPins<pac::CAN>>::REMAP;
    // SAFETY: `CAN_REMAP` is a 2-bit field; the values come from the pairs' table above
    // (RM0008 §9.4.2).
    mapr.modify_mapr(|_, w| unsafe { w.can_remap().bits(remap) });
    pac::CAN::enable(rcc);
    pac::CAN::reset(rcc);
    let apb1_hz = rcc.clocks.pclk1().raw();
    // SAFETY: the CAN's singleton, consumed here (with USB's, the other user of its
    // SRAM); its clock was just enabled.
    unsafe {
        crate::hal::whole(
            (can, usb),
            tx,
            rx,
            Instance::Can1,
            apb1_hz,
            Some(&chip::STM32F103),
        )
    }
}
