//! The portable application shared by firmware, host demo and tests.
#![no_std]
