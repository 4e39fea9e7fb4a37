//! The Blue Pill's STM32F103C8 with `stm32f1xx-hal` (0.11): clocks (RM0008 §7.2, §7.3):
//! HSE 8 MHz crystal × 9 = 72 MHz SYSCLK, APB1 = 36 MHz (its maximum, and bxCAN's clock);
//! without the crystal the HSI (8 MHz / 2 × 16 = 64 MHz, APB1 32 MHz). Flash wait states
//! by the HAL (RM0008 §3.3.3). CAN on PB8 (RX, floating input) / PB9 (TX, alternate
//! push-pull), `AFIO_MAPR.CAN_REMAP` = 10 (RM0008 §9.3.3, §9.1.11 Table 27), routed,
//! clocked and reset by the hand-over (`twocan_bxcan::hal::f1::can`). LED PC13.
//!
//! The HAL waits without bound for `HSERDY` when told to use the HSE, so [`boot`] first
//! probes the HSE with a bounded wait (RM0008 §7.3.1 `RCC_CR`).

use stm32f1xx_hal::afio::{AfioExt, MAPR};
use stm32f1xx_hal::flash::FlashExt;
use stm32f1xx_hal::gpio::{Alternate, Floating, GpioExt, Input, Output, PushPull, PB8, PB9, PC13};
use stm32f1xx_hal::rcc::{self, Rcc, RccExt};
use stm32f1xx_hal::time::{Hz, MHz};
use twocan_bxcan::hal::f1;

pub use stm32f1xx_hal::pac;
/// The device interrupt numbers (`crate::can::start` takes the instance's four).
pub use stm32f1xx_hal::pac::Interrupt;

use super::{halt, HSE_POLLS, PANIC_BLINKS};
use crate::board::BOARD;

/// The LED pin of the board (PC13, lit when low).
pub type Led = PC13<Output<PushPull>>;

/// The CAN handed over alone ([`CanParts::can1`]): its whole block, with the CAN and USB
/// singletons and the pins (given back by `free`, `park`).
pub type Can1 = f1::Can<PB9<Alternate<PushPull>>, PB8<Input<Floating>>>;

/// What the hand-over of the F103's CAN takes (`twocan_bxcan::hal::f1::can`): the CAN
/// singleton, the USB singleton (CAN and USB share their SRAM, RM0008 §24.2: USB stays
/// off while the program holds CAN), the pins in their CAN function, and the AFIO remap
/// register and RCC it writes.
pub struct CanParts {
    can: pac::CAN,
    usb: pac::USB,
    tx: PB9<Alternate<PushPull>>,
    rx: PB8<Input<Floating>>,
    mapr: MAPR,
    rcc: Rcc,
}

impl CanParts {
    /// The CAN alone, handed over: routed to PB8/PB9 (`CAN_REMAP` = 10), clocked and
    /// reset, for the STM32F103 (its bit timing from the HAL's APB1 clock).
    pub fn can1(self) -> Can1 {
        let CanParts {
            can,
            usb,
            tx,
            rx,
            mut mapr,
            mut rcc,
        } = self;
        f1::can(can, usb, tx, rx, &mut mapr, &mut rcc)
    }
}

/// CAN's interrupts (RM0008 §10.1.2: TX and RX0 share their lines with the USB device).
pub const CAN1_IRQS: [Interrupt; 4] = [
    Interrupt::USB_HP_CAN_TX,
    Interrupt::USB_LP_CAN_RX0,
    Interrupt::CAN_RX1,
    Interrupt::CAN_SCE,
];

/// What [`boot`] hands the example.
pub struct Boot {
    /// The Cortex-M core peripherals (SysTick already running).
    pub core: cortex_m::Peripherals,
    /// Whether the HSE runs (else the clocks come from the HSI).
    pub hse: bool,
    /// The user LED, off.
    pub led: Led,
    /// What the CAN's hand-over takes ([`CanParts::can1`]).
    pub can: CanParts,
}

/// Starts the HSE crystal and waits at most `polls` reads for `HSERDY`; leaves it off
/// and returns `false` when it does not come.
fn hse_starts(rcc: &pac::RCC, polls: u32) -> bool {
    rcc.cr().modify(|_, w| w.hsebyp().bit(BOARD.hse_bypass));
    rcc.cr().modify(|_, w| w.hseon().set_bit());
    let ready = (0..polls).any(|_| rcc.cr().read().hserdy().bit_is_set());
    if !ready {
        rcc.cr().modify(|_, w| w.hseon().clear_bit());
    }
    ready
}

/// The common start of every example: clocks, SysTick, LED; CAN's singleton (and USB's)
/// and its pins (PB9 alternate push-pull, PB8 floating input) for the hand-over, which
/// routes, clocks and resets it. Call once, first thing in `main`.
pub fn boot() -> Boot {
    let (Some(mut core), Some(dp)) = (cortex_m::Peripherals::take(), pac::Peripherals::take())
    else {
        halt(PANIC_BLINKS)
    };
    let hse = hse_starts(&dp.RCC, HSE_POLLS);
    let mut flash = dp.FLASH.constrain();
    let cfg = if hse {
        rcc::Config::hse(Hz(BOARD.hse_hz))
            .sysclk(Hz(BOARD.sysclk_hz))
            .pclk1(Hz(BOARD.apb1_hz))
    } else {
        rcc::Config::hsi()
            .sysclk(MHz(64).convert())
            .pclk1(MHz(32).convert())
    };
    let mut rcc = dp.RCC.freeze(cfg, &mut flash.acr);
    let hclk = rcc.clocks.hclk().raw();

    let afio = dp.AFIO.constrain(&mut rcc);
    let mut gpiob = dp.GPIOB.split(&mut rcc);
    let rx = gpiob.pb8.into_floating_input(&mut gpiob.crh);
    let tx = gpiob.pb9.into_alternate_push_pull(&mut gpiob.crh);
    let mut gpioc = dp.GPIOC.split(&mut rcc);
    let mut led = gpioc.pc13.into_push_pull_output(&mut gpioc.crh);
    led.set_high();

    crate::time::start(&mut core.SYST, hclk);
    Boot {
        core,
        hse,
        led,
        can: CanParts {
            can: dp.CAN,
            usb: dp.USB,
            tx,
            rx,
            mapr: afio.mapr,
            rcc,
        },
    }
}

/// Drives the LED from [`super::halt`] (PC13, lit when low), by `GPIOC_BSRR` alone.
pub(super) fn led_raw(on: bool) {
    // SAFETY: called with interrupts off from `halt`, which never returns: nothing else
    // uses GPIOC again. `BSRR` is write-only and touches only the pin written.
    let dp = unsafe { pac::Peripherals::steal() };
    dp.GPIOC.bsrr().write(|w| {
        if on {
            w.br13().set_bit()
        } else {
            w.bs13().set_bit()
        }
    });
}

/// The four CAN vectors of the F103 (`USB_HP_CAN_TX`, `USB_LP_CAN_RX0`, `CAN_RX1`,
/// `CAN_SCE`; RM0008 §10.1.2), each running its line of CAN's `crate::can::CanState`
/// (`twocan_bxcan::rt::dispatch`). Invoke once in the firmware.
#[macro_export]
macro_rules! can1_vectors {
    () => {
        $crate::__can_vectors!(can1_lines, Can1: USB_HP_CAN_TX, USB_LP_CAN_RX0, CAN_RX1, CAN_SCE);
    };
}
