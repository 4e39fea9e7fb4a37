//! The NUCLEO-F446RE's STM32F446RE with `stm32f4xx-hal` (0.23): clocks (RM0390 §6.2,
//! §6.3): HSE = the ST-LINK's 8 MHz MCO in bypass, SYSCLK 90 MHz from the PLL, APB1
//! 45 MHz (its maximum, DS10693 §6.3.1, and bxCAN's clock); 90 MHz needs no over-drive
//! (RM0390 §5.1.4: only above 168 MHz). Without the HSE: the 16 MHz HSI, same targets.
//! CAN1 on PA11/PA12, CAN2 on PB12/PB13, alternate function 9 (DS10693 Table 11), clocked
//! and reset by the hand-over (`twocan_bxcan::hal::f4`). LED LD2 on PA5.
//!
//! The HAL waits without bound for `HSERDY` when told to use the HSE, so [`boot`] first
//! probes the HSE with a bounded wait (RM0390 §6.3.1 `RCC_CR`: `HSEBYP` written while the
//! HSE is off, then `HSEON`, then `HSERDY`).

use stm32f4xx_hal::gpio::{Alternate, GpioExt, Output, PushPull, PA11, PA12, PA5, PB12, PB13};
use stm32f4xx_hal::rcc::{Config, Rcc, RccExt};
use stm32f4xx_hal::time::Hertz;
use twocan_bxcan::hal::{f4, DualCan};

pub use stm32f4xx_hal::pac;
/// The device interrupt numbers (`crate::can::start` takes the instance's four).
pub use stm32f4xx_hal::pac::Interrupt;

use super::{halt, HSE_POLLS, PANIC_BLINKS};
use crate::board::BOARD;

/// The LED pin of the board (LD2, PA5, lit when high).
pub type Led = PA5<Output<PushPull>>;

/// CAN1 handed over alone ([`CanParts::can1`]): its whole block, with its singleton and
/// pins (given back by `free`, `park`).
pub type Can1 = f4::Can1<PA12<Alternate<9>>, PA11<Alternate<9>>>;
/// CAN2 handed over ([`CanParts::dual`]): its control block and CAN1's filter block.
pub type Can2 = f4::Can2<PB13<Alternate<9>>, PB12<Alternate<9>>>;

/// What the hand-overs of CAN1 and CAN2 take (`twocan_bxcan::hal::f4`): their PAC
/// singletons, their pins in AF9, and the RCC that enables and resets them.
pub struct CanParts {
    can1: pac::CAN1,
    can1_pins: (PA12<Alternate<9>>, PA11<Alternate<9>>),
    can2: pac::CAN2,
    can2_pins: (PB13<Alternate<9>>, PB12<Alternate<9>>),
    rcc: Rcc,
}

impl CanParts {
    /// CAN1 alone, handed over (`f4::can1`: its whole block, filters included; CAN2 is
    /// not built), clocked and reset, for the STM32F446 (its bit timing from the HAL's
    /// APB1 clock).
    pub fn can1(self) -> Can1 {
        let CanParts {
            can1,
            can1_pins: (tx, rx),
            mut rcc,
            ..
        } = self;
        f4::can1(can1, tx, rx, &mut rcc).with_chip(BOARD.chip)
    }

    /// CAN1 and CAN2, handed over (`f4::can1_dual`, `f4::can2`): each its control block,
    /// CAN1's filter block shared through the `Can1Filters` handle CAN1's hand-over gives
    /// CAN2 (CAN2 has no filters of its own, RM0390 §30.2); both clocked and reset.
    pub fn dual(self) -> (DualCan, Can2) {
        let CanParts {
            can1,
            can1_pins: (tx1, rx1),
            can2,
            can2_pins: (tx2, rx2),
            mut rcc,
        } = self;
        let (can1, filters) = f4::can1_dual(can1, tx1, rx1, &mut rcc);
        let can2 = f4::can2(can2, tx2, rx2, &mut rcc, filters);
        (can1.with_chip(BOARD.chip), can2.with_chip(BOARD.chip))
    }
}

/// CAN1's interrupts (RM0390 §10.2).
pub const CAN1_IRQS: [Interrupt; 4] = [
    Interrupt::CAN1_TX,
    Interrupt::CAN1_RX0,
    Interrupt::CAN1_RX1,
    Interrupt::CAN1_SCE,
];

/// CAN2's interrupts (RM0390 §10.2).
pub const CAN2_IRQS: [Interrupt; 4] = [
    Interrupt::CAN2_TX,
    Interrupt::CAN2_RX0,
    Interrupt::CAN2_RX1,
    Interrupt::CAN2_SCE,
];

/// What [`boot`] hands the example.
pub struct Boot {
    /// The Cortex-M core peripherals (SysTick already running).
    pub core: cortex_m::Peripherals,
    /// Whether the HSE runs (else the clocks come from the HSI).
    pub hse: bool,
    /// The user LED, off.
    pub led: Led,
    /// What the CAN hand-overs take ([`CanParts::can1`], [`CanParts::dual`]).
    pub can: CanParts,
}

/// Starts the HSE (bypass or crystal as the board needs) and waits at most `polls` reads
/// for `HSERDY`. Leaves it off and returns `false` when it does not come.
fn hse_starts(rcc: &pac::RCC, polls: u32) -> bool {
    rcc.cr().modify(|_, w| w.hsebyp().bit(BOARD.hse_bypass));
    rcc.cr().modify(|_, w| w.hseon().set_bit());
    let ready = (0..polls).any(|_| rcc.cr().read().hserdy().bit_is_set());
    if !ready {
        rcc.cr().modify(|_, w| w.hseon().clear_bit());
    }
    ready
}

/// The common start of every example: clocks, SysTick, LED; CAN1's and CAN2's
/// singletons and their pins in AF9 for the hand-over, which clocks and resets them.
/// Call once, first thing in `main`.
pub fn boot() -> Boot {
    let (Some(mut core), Some(dp)) = (cortex_m::Peripherals::take(), pac::Peripherals::take())
    else {
        halt(PANIC_BLINKS)
    };
    let hse = hse_starts(&dp.RCC, HSE_POLLS);
    let cfg = if hse {
        Config::hse(Hertz::from_raw(BOARD.hse_hz)).bypass_hse_oscillator()
    } else {
        Config::hsi()
    };
    let mut rcc = dp.RCC.freeze(
        cfg.sysclk(Hertz::from_raw(BOARD.sysclk_hz))
            .pclk1(Hertz::from_raw(BOARD.apb1_hz)),
    );
    let hclk = rcc.clocks.hclk().raw();

    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);
    let mut led = gpioa.pa5.into_push_pull_output();
    led.set_low();
    let can1_pins = (gpioa.pa12.into_alternate(), gpioa.pa11.into_alternate());
    let can2_pins = (gpiob.pb13.into_alternate(), gpiob.pb12.into_alternate());

    crate::time::start(&mut core.SYST, hclk);
    Boot {
        core,
        hse,
        led,
        can: CanParts {
            can1: dp.CAN1,
            can1_pins,
            can2: dp.CAN2,
            can2_pins,
            rcc,
        },
    }
}

/// Drives the LED from [`super::halt`] (PA5, lit when high), by `GPIOA_BSRR` alone.
pub(super) fn led_raw(on: bool) {
    // SAFETY: called with interrupts off from `halt`, which never returns: nothing else
    // uses GPIOA again. `BSRR` is write-only and touches only the pin written.
    let dp = unsafe { pac::Peripherals::steal() };
    dp.GPIOA.bsrr().write(|w| {
        if on {
            w.bs5().set_bit()
        } else {
            w.br5().set_bit()
        }
    });
}

/// The four CAN1 vectors of the F446 (`CAN1_TX`, `CAN1_RX0`, `CAN1_RX1`, `CAN1_SCE`;
/// RM0390 §10.2), each running its line of CAN1's `crate::can::CanState`
/// (`twocan_bxcan::rt::dispatch`). Invoke once in the firmware.
#[macro_export]
macro_rules! can1_vectors {
    () => {
        $crate::__can_vectors!(can1_lines, Can1: CAN1_TX, CAN1_RX0, CAN1_RX1, CAN1_SCE);
    };
}

/// The four CAN2 vectors of the F446 (`CAN2_TX` … `CAN2_SCE`, lines 63..=66).
#[macro_export]
macro_rules! can2_vectors {
    () => {
        $crate::__can_vectors!(can2_lines, Can2: CAN2_TX, CAN2_RX0, CAN2_RX1, CAN2_SCE);
    };
}
