//! Part descriptors for the model: the driver's chip table ([`crate::chip`]), so that the
//! model, the driver and the firmware-in-the-loop board profiles read one set of facts.
//!
//! [`Part`] is [`Chip`]; the descriptors are the same values (`part::STM32F103` is
//! [`crate::chip::STM32F103`]). What the model does with them (bank count of CAN1's
//! block, `CAN2SB` present only where CAN2 is, CAN3's own block) is in
//! [`super::BxCanModel::of_part`] and `docs/models.md`.

pub use crate::chip::{
    CanInstance, CanPins, Chip, Pin, PinMux, STM32F103, STM32F105_F107, STM32F405_F407,
    STM32F413_F423, STM32F446, STM32F74X_F75X, STM32F76X_F77X,
};

/// The bxCAN facts of one STM32 part: the driver's [`Chip`].
pub type Part = Chip;
