//! Firmware in the loop for twocan: the example firmware ELFs run on an emulated
//! Cortex-M (Unicorn) with their CAN controllers routed to the project's behavioural
//! models on one simulated bus. See README.md.

pub mod can;
pub mod elf;
pub mod machine;
pub mod nvic;
pub mod profile;
pub mod report;
pub mod rtt;
pub mod stack;
pub mod world;
