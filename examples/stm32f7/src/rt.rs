//! Target-only start-up: clocks, the CAN singletons and pins for the hand-over, LED,
//! SysTick, panic handler.
//!
//! Clocks are set by `stm32f7xx-hal` (RM0410 §5 "Reset and clock control"): SYSCLK
//! 108 MHz from the PLL, AHB 108 MHz, APB1 54 MHz (its maximum, and bxCAN's clock: the
//! frequency the HAL reports feeds `twocan_bxcan::Config::from_bitrate`). 108 MHz needs
//! no over-drive (RM0410 §4.1.4: only above 180 MHz), which keeps two of the HAL's
//! unbounded waits (`ODRDY`, `ODSWRDY`) out of the start-up.
//!
//! The HAL waits without bound for `HSERDY` when told to use the HSE, so [`boot`] first
//! probes the HSE itself with a bounded wait (RM0410 §5.3.1 `RCC_CR`: `HSEBYP` written
//! while the HSE is off, then `HSEON`, then `HSERDY`) and falls back to the 16 MHz HSI
//! when it does not start — e.g. a NUCLEO whose ST-LINK MCO output is not wired to the
//! target (solder bridges). The HAL's remaining waits (`HSIRDY`, `PLLRDY`, `SWS`) are on
//! on-chip clocks that always start.

use stm32f7xx_hal::gpio::{Alternate, Output, Pin, PushPull};
use stm32f7xx_hal::pac;
use stm32f7xx_hal::prelude::*;
use stm32f7xx_hal::rcc::{HSEClock, HSEClockMode, APB1};

use crate::board::BOARD;

/// Reads of `RCC_CR` allowed for the HSE to become ready: at the 16 MHz HSI of reset and
/// a few cycles per read, tens of milliseconds; HSE start-up is 2 ms typical (data sheet
/// `t_SU(HSE)`).
pub const HSE_POLLS: u32 = 200_000;

/// Blink code of a bxCAN configuration failure.
pub const CAN_BLINKS: u8 = 5;
/// Blink code of a panic.
pub const PANIC_BLINKS: u8 = 6;

/// The LED pin of the board.
#[cfg(feature = "nucleo-f767zi")]
pub type Led = Pin<'B', 0, Output<PushPull>>;
/// The LED pin of the board.
#[cfg(feature = "disco-f746g")]
pub type Led = Pin<'I', 1, Output<PushPull>>;

/// CAN1_RX of the board, in AF9 (see [`crate::board`]).
#[cfg(feature = "nucleo-f767zi")]
pub type Can1Rx = Pin<'D', 0, Alternate<9>>;
/// CAN1_TX of the board, in AF9.
#[cfg(feature = "nucleo-f767zi")]
pub type Can1Tx = Pin<'D', 1, Alternate<9>>;
/// CAN1_RX of the board, in AF9 (see [`crate::board`]).
#[cfg(feature = "disco-f746g")]
pub type Can1Rx = Pin<'B', 8, Alternate<9>>;
/// CAN1_TX of the board, in AF9.
#[cfg(feature = "disco-f746g")]
pub type Can1Tx = Pin<'B', 9, Alternate<9>>;
/// CAN2_RX of the board, in AF9 (NUCLEO-F767ZI only).
#[cfg(feature = "nucleo-f767zi")]
pub type Can2Rx = Pin<'B', 5, Alternate<9>>;
/// CAN2_TX of the board, in AF9.
#[cfg(feature = "nucleo-f767zi")]
pub type Can2Tx = Pin<'B', 6, Alternate<9>>;

/// Starts the HSE (bypass or crystal as the board needs) and waits at most `polls` reads
/// for `HSERDY`. Leaves it off and returns `false` when it does not come.
fn hse_starts(rcc: &pac::RCC, polls: u32) -> bool {
    rcc.cr.modify(|_, w| w.hsebyp().bit(BOARD.hse_bypass));
    rcc.cr.modify(|_, w| w.hseon().set_bit());
    let ready = (0..polls).any(|_| rcc.cr.read().hserdy().bit_is_set());
    if !ready {
        rcc.cr.modify(|_, w| w.hseon().clear_bit());
    }
    ready
}

/// What [`boot`] hands the example.
pub struct Boot {
    /// The Cortex-M core peripherals (SysTick already running).
    pub core: cortex_m::Peripherals,
    /// The clock frequencies the HAL set.
    pub clocks: stm32f7xx_hal::rcc::Clocks,
    /// Whether the HSE runs (else the clocks come from the HSI).
    pub hse: bool,
    /// The user LED, off.
    pub led: Led,
    /// The APB1 bus of RCC: the bxCAN hand-over (`twocan_bxcan::hal`) enables and
    /// resets the CAN clocks through it.
    pub apb1: APB1,
    /// CAN1's PAC singleton, for `twocan_bxcan::hal::can1` or `can1_dual`.
    pub can1: pac::CAN1,
    /// CAN1's pins, in AF9.
    pub can1_pins: (Can1Tx, Can1Rx),
    /// CAN2's PAC singleton, for `twocan_bxcan::hal::can2`.
    #[cfg(feature = "nucleo-f767zi")]
    pub can2: pac::CAN2,
    /// CAN2's pins, in AF9.
    #[cfg(feature = "nucleo-f767zi")]
    pub can2_pins: (Can2Tx, Can2Rx),
}

/// The common start of every example: clocks, SysTick, LED; CAN1's (and CAN2's, where
/// the board has pins for it) PAC singleton and pins in AF9, for the hand-over
/// (`twocan_bxcan::hal`). Call once, first thing in `main`.
pub fn boot() -> Boot {
    let core = cortex_m::Peripherals::take();
    let dp = pac::Peripherals::take();
    let (Some(mut core), Some(dp)) = (core, dp) else {
        halt(PANIC_BLINKS)
    };

    let hse = hse_starts(&dp.RCC, HSE_POLLS);
    let rcc = dp.RCC.constrain();
    let mut cfgr = rcc.cfgr;
    if hse {
        let mode = if BOARD.hse_bypass {
            HSEClockMode::Bypass
        } else {
            HSEClockMode::Oscillator
        };
        cfgr = cfgr.hse(HSEClock::new(BOARD.hse_hz.Hz(), mode));
    }
    let clocks = cfgr
        .sysclk(BOARD.sysclk_hz.Hz())
        .pclk1(BOARD.apb1_hz.Hz())
        .freeze();

    // The CAN pins in AF9; the CAN clocks are enabled by the hand-over
    // (`twocan_bxcan::hal`), which takes the singletons, the pins and `rcc.apb1`.
    #[cfg(feature = "nucleo-f767zi")]
    let (can1_pins, can2_pins, led) = {
        let gpiod = dp.GPIOD.split();
        // PB5/PB6 are CAN2's pins on this board (see `board`).
        let gpiob = dp.GPIOB.split();
        (
            (gpiod.pd1.into_alternate(), gpiod.pd0.into_alternate()),
            (gpiob.pb6.into_alternate(), gpiob.pb5.into_alternate()),
            gpiob.pb0.into_push_pull_output(),
        )
    };
    #[cfg(feature = "disco-f746g")]
    let (can1_pins, led) = {
        let gpiob = dp.GPIOB.split();
        (
            (gpiob.pb9.into_alternate(), gpiob.pb8.into_alternate()),
            dp.GPIOI.split().pi1.into_push_pull_output(),
        )
    };

    crate::time::start(&mut core.SYST, clocks.hclk().raw());
    Boot {
        core,
        clocks,
        hse,
        led,
        apb1: rcc.apb1,
        can1: dp.CAN1,
        can1_pins,
        #[cfg(feature = "nucleo-f767zi")]
        can2: dp.CAN2,
        #[cfg(feature = "nucleo-f767zi")]
        can2_pins,
    }
}

/// Priority of the CAN interrupt lines: one for all (0, the highest, as after reset).
/// Each line runs its own handler cell (`twocan_bxcan::rt`), so the lines could have
/// different priorities; the examples keep one.
pub const CAN_PRIORITY: u8 = 0;

#[cortex_m_rt::exception]
fn SysTick() {
    crate::time::tick();
}

/// Blinks `code` short flashes, pauses, forever: how the examples report a fatal error
/// (5: bxCAN configuration, 6: panic). Interrupts are disabled; delays assume the 16 MHz
/// HSI (the clock after reset) and run faster once the PLL is on.
pub fn halt(code: u8) -> ! {
    crate::error!("halted: blink code {=u8}", code);
    cortex_m::interrupt::disable();
    // SAFETY: interrupts are off and this never returns: nothing else will use the LED's
    // port again, so taking it over here cannot race.
    let dp = unsafe { pac::Peripherals::steal() };
    #[cfg(feature = "nucleo-f767zi")]
    let mut led = dp.GPIOB.split().pb0.into_push_pull_output();
    #[cfg(feature = "disco-f746g")]
    let mut led = dp.GPIOI.split().pi1.into_push_pull_output();
    let ms = 16_000;
    loop {
        for _ in 0..code {
            led.set_high();
            cortex_m::asm::delay(150 * ms);
            led.set_low();
            cortex_m::asm::delay(250 * ms);
        }
        cortex_m::asm::delay(1200 * ms);
    }
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    halt(PANIC_BLINKS)
}
