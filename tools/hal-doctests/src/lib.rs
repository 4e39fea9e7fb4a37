//! The examples of `twocan_bxcan::hal::f1` and `twocan_bxcan::hal::f4`, compiled for the
//! target one at a time by `run.sh` (see there): the HALs of those families cannot be
//! built on the host next to the tests' `critical-section/std`, so rustdoc cannot run
//! these examples; `run.sh` cross-builds each instead, and checks that the ones marked
//! `compile_fail` fail with their error code, and on the pin traits.
#![no_std]
#![allow(unused)]

include!(env!("TWOCAN_HAL_DOCTEST_FILE"));
