//! The NUCLEO-F446RE's STM32F446RE with `stm32f4xx-hal` (0.23): clocks (RM0390 §6.2,
//! §6.3): HSE = the ST-LINK's 8 MHz MCO in bypass, SYSCLK 90 MHz from the PLL, APB1
//! 45 MHz (its maximum, DS10693 §6.3.1, and bxCAN's clock); 90 MHz needs no over-drive
//! (RM0390 §5.1.4: only above 168 MHz). Without the HSE: the 16 MHz HSI, same targets.
//! CAN1 on PA11/PA12, CAN2 on PB12/PB13, alternate function 9 (DS10693 Table 11). LED
//! LD2 on PA5.
//!
//! The HAL waits without bound for `HSERDY` when told to use the HSE, so [`boot`] first
//! probes the HSE with a bounded wait (RM0390 §6.3.1 `RCC_CR`: `HSEBYP` written while the
//! HSE is off, then `HSEON`, then `HSERDY`).

use stm32f4xx_hal::gpio::{Alternate, GpioExt, Output, PushPull, PA11, PA12, PA5, PB12, PB13};
use stm32f4xx_hal::rcc::{Config, Enable, RccExt, Reset};
use stm32f4xx_hal::time::Hertz;
use twocan_bxcan::regs::{ControlRegs, FilterRegs, Instance};

pub use stm32f4xx_hal::pac;
/// The device interrupt numbers (`crate::can::start` takes the instance's four).
pub use stm32f4xx_hal::pac::Interrupt;

use super::{base, halt, Can1, HSE_POLLS, PANIC_BLINKS};
use crate::board::BOARD;

/// The LED pin of the board (LD2, PA5, lit when high).
pub type Led = PA5<Output<PushPull>>;

/// What [`Can1`] holds on the F446: CAN1's singleton and its pins in AF9.
pub struct Can1Parts {
    _can: pac::CAN1,
    _rx: PA11<Alternate<9>>,
    _tx: PA12<Alternate<9>>,
}

/// CAN2 handed over by [`boot`]: its singleton and pins in AF9.
pub struct Can2 {
    _can: pac::CAN2,
    _rx: PB12<Alternate<9>>,
    _tx: PB13<Alternate<9>>,
}

/// CAN1's filter registers (`CAN_FMR` .. `CAN_F27R2`), the block CAN1 and CAN2 share
/// (RM0390 §30.9.4), reached only through [`Can1::dual`].
// SAFETY: offsets 0x200..0x320 from CAN1's base are CAN1's filter registers (RM0390
// §30.9.5), 32-bit accessible. A reference to this value is created only by `Can1::dual`,
// which consumes CAN1's singleton, and gives CAN1 the control window below 0x200 only.
static CAN1_FILTERS: FilterRegs = unsafe { FilterRegs::new(twocan_bxcan::regs::CAN1_BASE) };

impl Can1 {
    /// CAN1 as the master of a dual set-up: its control and mailbox registers, and the
    /// filter block it shares with CAN2 (lend the reference to CAN2 too).
    pub fn dual(self) -> (ControlRegs, &'static FilterRegs) {
        // SAFETY: CAN1's control and mailbox registers (below 0x200 of the part's CAN1
        // block); its singleton is consumed with this value; the filter registers above
        // go to `CAN1_FILTERS` only.
        let control = unsafe { ControlRegs::new(base(Instance::Can1)) };
        (control, &CAN1_FILTERS)
    }
}

impl Can2 {
    /// CAN2's control and mailbox registers (CAN2 has no filter registers of its own:
    /// it uses CAN1's block, RM0390 §30.2).
    pub fn control(self) -> ControlRegs {
        // SAFETY: CAN2's block at the part's base address; its singleton is consumed with
        // this value, so no other handle to these registers exists.
        unsafe { ControlRegs::new(base(Instance::Can2)) }
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
    /// The APB1 clock the HAL set: bxCAN's clock.
    pub apb1_hz: u32,
    /// Whether the HSE runs (else the clocks come from the HSI).
    pub hse: bool,
    /// The user LED, off.
    pub led: Led,
    /// CAN1, clocked and reset, its pins in AF9.
    pub can1: Can1,
    /// CAN2, clocked and reset, its pins in AF9.
    pub can2: Can2,
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
/// singletons taken, their clocks enabled and reset, their pins in AF9. Call once,
/// first thing in `main`.
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
    let apb1_hz = rcc.clocks.pclk1().raw();
    let hclk = rcc.clocks.hclk().raw();

    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);
    let mut led = gpioa.pa5.into_push_pull_output();
    led.set_low();
    let (rx1, tx1) = (gpioa.pa11.into_alternate(), gpioa.pa12.into_alternate());
    let (rx2, tx2) = (gpiob.pb12.into_alternate(), gpiob.pb13.into_alternate());
    // CAN2 works through CAN1's filters and message RAM (RM0390 §30.2): both clocks on.
    pac::CAN1::enable(&mut rcc);
    pac::CAN1::reset(&mut rcc);
    pac::CAN2::enable(&mut rcc);
    pac::CAN2::reset(&mut rcc);

    crate::time::start(&mut core.SYST, hclk);
    Boot {
        core,
        apb1_hz,
        hse,
        led,
        can1: Can1 {
            _parts: Can1Parts {
                _can: dp.CAN1,
                _rx: rx1,
                _tx: tx1,
            },
        },
        can2: Can2 {
            _can: dp.CAN2,
            _rx: rx2,
            _tx: tx2,
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
