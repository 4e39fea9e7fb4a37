//! The crates' quick starts (twocan-core, twocan-flexcan, twocan-bxcan and its firmware
//! form) as a user's first program: the very text of the crate
//! documentation (each `doc/*.rs` file is included both by the crate root's `#![doc]`
//! and here), compiled in a crate of its own with the dependencies a user would list.
//! When the quick start stops compiling or stops doing what it says, this fails.

/// `twocan-core`'s quick start: the split driver over the mock controller.
mod core_quick_start {
    include!("../../can-core/doc/quick_start.rs");

    #[test]
    fn runs() {
        main().expect("the quick start returns Ok");
        // A second run finds the `static` state split already: the typed error, no panic.
        assert!(CAN.split(MockHardware::new(3)).is_err());
    }
}

/// `twocan-flexcan`'s quick start: ACAN's LoopBackDemo on FlexCAN's model.
mod flexcan_quick_start {
    include!("../../flexcan/doc/quick_start.rs");

    #[test]
    fn runs() {
        main();
    }
}

/// `twocan-bxcan`'s quick start: CAN1's model in loop-back on the simulated bus.
mod bxcan_quick_start {
    include!("../../bxcan/doc/quick_start.rs");

    #[test]
    fn runs() {
        main();
    }
}

/// `twocan-bxcan`'s firmware quick start: the hand-over from `stm32f7xx-hal` (PAC
/// singleton, `Clocks`, pins in AF9), with no `unsafe`. It touches the chip's registers,
/// so on the host it is compiled and type-checked, not run.
mod bxcan_firmware_quick_start {
    include!("../../bxcan/doc/firmware_quick_start.rs");

    #[test]
    fn compiles_as_a_function_of_the_pac_peripherals() {
        let start: fn(pac::Peripherals) -> Result<(), Error> = start;
        // The state is a `static` the program could split: nothing has used it yet.
        assert!(CAN1.hardware().is_none());
        let _ = start;
    }
}
