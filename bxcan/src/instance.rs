//! The STM32F7 bxCAN instances and the share of filter banks each one gets.
//!
//! | instance | base          | filter registers | banks                      |
//! |----------|---------------|------------------|----------------------------|
//! | CAN1     | `0x4000_6400` | its own          | `0..CAN2SB` (of 28)        |
//! | CAN2     | `0x4000_6800` | CAN1's           | `CAN2SB..28`               |
//! | CAN3     | `0x4000_3400` | its own          | `0..14` (F76x/F77x only)   |
//!
//! (RM0410 §40.2 "bxCAN main features", §40.3 "dual CAN"; addresses RM0410 §2.2.2; the
//! register map is [`crate::regs`].)
//!
//! # What the firmware does before [`crate::Can::can1`] & co. (not this crate's job)
//!
//! - enable the peripheral clock in RCC: `RCC_APB1ENR.CAN1EN` (bit 25), `CAN2EN` (bit 26,
//!   and CAN1EN too: CAN2's filters live in CAN1), `CAN3EN` (bit 13), e.g. with
//!   `stm32f7xx-hal`'s `rcc` API, and know the APB1 clock it runs on (the `apb1_hz` of
//!   [`crate::Config::from_bitrate`]);
//! - route the pins to the peripheral: alternate function **AF9** for CAN1 (RX/TX on
//!   PA11/PA12, PB8/PB9, PD0/PD1, PI9/PH13) and CAN2 (PB12/PB13, PB5/PB6); CAN3 (PA8/PA15,
//!   PB3/PB4) uses **AF11** on F76x/F77x — check the data sheet's alternate-function
//!   table for the pin chosen;
//! - build the register access. With `stm32f7xx-hal`, the `hal` module (feature
//!   `hal-stm32f7`) does the three steps above with no `unsafe` in the program: it takes
//!   the PAC singleton, the pins (typed: only the table's pins in their alternate
//!   function) and RCC's `APB1` and `Clocks`. Without it: `regs::CanRegs::new(regs::CAN1_BASE)`
//!   (an `unsafe` promise that nothing else touches the peripheral; the handle reaches the
//!   block's registers and nothing else). With CAN2, no register has two owners: CAN1 and
//!   CAN2 each get their control registers (`regs::ControlRegs`, `0x000..0x200`) and both
//!   borrow CAN1's filter registers (`0x200..0x320`: `hal::Can1Filters`, or a `static`
//!   `regs::FilterRegs`): `Can::can1_dual` and `Can::can2`.
//! - CAN2 alone: CAN1 must be clocked, but need not be enabled on the bus, for its filter
//!   block to take the configuration.

pub use crate::regs::Instance;
use crate::regs::{FILTER_BANKS, FILTER_BANKS_SINGLE};

/// The banks (`start..end`, hardware numbering) of the filter block that `instance`
/// owns, given the `CAN2SB` value of the dual block (clamped to 28; RM0410
/// `CAN_FMR.CAN2SB`).
pub const fn bank_range(instance: Instance, can2sb: u32) -> (usize, usize) {
    let split = if can2sb as usize > FILTER_BANKS {
        FILTER_BANKS
    } else {
        can2sb as usize
    };
    match instance {
        Instance::Can1 => (0, split),
        Instance::Can2 => (split, FILTER_BANKS),
        Instance::Can3 => (0, FILTER_BANKS_SINGLE),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split() {
        assert_eq!(bank_range(Instance::Can1, 14), (0, 14));
        assert_eq!(bank_range(Instance::Can2, 14), (14, 28));
        assert_eq!(bank_range(Instance::Can1, 40), (0, 28));
        assert_eq!(bank_range(Instance::Can3, 3), (0, 14));
    }
}
