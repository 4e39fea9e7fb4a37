//! The Kinetis flash configuration field: the 16 bytes at `0x400..=0x40F` that the flash
//! controller copies into its `FPROT`, `FSEC`, `FOPT`, `FEPROT` and `FDPROT` registers at
//! reset (K20 RM "Flash Configuration Field Description" in the FTFL chapter; K64/K66 RM,
//! same section in the FTFE chapter).
//!
//! | address | field | value | meaning |
//! |---|---|---|---|
//! | 0x400–0x407 | backdoor comparison key | 8 × `0xFF` | no key (and `KEYEN` disables it) |
//! | 0x408–0x40B | `FPROT3..0` | 4 × `0xFF` | no program-flash region protected |
//! | 0x40C | `FSEC` | `0xFE` | `KEYEN` = 0b11 (backdoor key disabled), `MEEN` = 0b11 (mass erase **enabled**), `FSLACC` = 0b11 (factory access granted), `SEC` = 0b10 (**unsecured**) |
//! | 0x40D | `FOPT` | `0xF9` | `LPBOOT` = 1 (normal boot: reset dividers ÷1), `EZPORT_DIS` = 0 (EzPort disabled), `NMI_DIS` = 0 (NMI pin ignored), reserved bits 7:3 = 1 (erased) |
//! | 0x40E | `FEPROT` | `0xFF` | no EEPROM (FlexRAM) region protected |
//! | 0x40F | `FDPROT` | `0xFF` | no data-flash region protected |
//!
//! Why these values:
//! - `FSEC` is the dangerous byte. `SEC` must be `0b10`, the only unsecured encoding;
//!   anything else secures the chip, and with `MEEN = 0b10` a secured chip can never be
//!   mass-erased again — it is lost. `0xFE` keeps every other field at its erased,
//!   permissive value, so the chip can always be mass-erased and reprogrammed (the Teensy
//!   loader chip programs over the debug port).
//! - `FOPT = 0xF9` is the value of PJRC's current Teensyduino start-up code (the early
//!   Teensy 3.0 code left it erased, `0xFF`). `EZPORT_DIS = 0` stops a low level on the
//!   EZP_CS pin at reset from entering EzPort mode instead of running the program;
//!   `NMI_DIS = 0` stops a low level on the NMI pin (a user pin on the Teensy headers)
//!   from raising NMIs; `LPBOOT = 1` selects the normal-boot reset values of the
//!   `SIM_CLKDIV1` dividers (the core clock is not divided by 8), so the start-up code
//!   runs at full speed.
//! - PJRC's current code uses `FSEC = 0xDE`, the early code `0xFE`: they differ only in
//!   `MEEN` (`0b01` / `0b11`), and both mean "mass erase enabled". `0xFE` is the
//!   erased value in every field but `SEC`.
//!
//! The constants are checked at compile time here ([`FlashConfig::check`]), and on the
//! linked ELF by `tests/elf.rs`.

/// The fields of the flash configuration field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FlashConfig {
    /// Backdoor comparison key (0x400–0x407).
    pub backdoor_key: [u8; 8],
    /// Program flash protection bytes `FPROT3`, `FPROT2`, `FPROT1`, `FPROT0` (0x408–0x40B).
    pub fprot: [u8; 4],
    /// Flash security byte (0x40C).
    pub fsec: u8,
    /// Flash nonvolatile option byte (0x40D).
    pub fopt: u8,
    /// EEPROM protection byte (0x40E).
    pub feprot: u8,
    /// Data flash protection byte (0x40F).
    pub fdprot: u8,
}

/// `FSEC.SEC` field (bits 1:0): `0b10` is the only unsecured value.
pub const FSEC_SEC_MASK: u8 = 0b11;
/// `FSEC.SEC = 0b10`: MCU security status unsecure.
pub const FSEC_SEC_UNSECURE: u8 = 0b10;
/// `FSEC.FSLACC` field position (bits 3:2): `0b10` denies factory access, others grant it.
pub const FSEC_FSLACC_SHIFT: u8 = 2;
/// `FSEC.MEEN` field position (bits 5:4): `0b10` disables mass erase, others enable it.
pub const FSEC_MEEN_SHIFT: u8 = 4;
/// `FSEC.KEYEN` field position (bits 7:6): `0b10` enables backdoor key access.
pub const FSEC_KEYEN_SHIFT: u8 = 6;
/// `MEEN`, `KEYEN` and `FSLACC` value that means "disabled" / "denied".
pub const FSEC_FIELD_DISABLED: u8 = 0b10;
/// `FOPT.LPBOOT`, bit 0: 1 = normal boot.
pub const FOPT_LPBOOT: u8 = 1 << 0;
/// `FOPT.EZPORT_DIS`, bit 1: 1 = EzPort enabled at reset when EZP_CS is low.
pub const FOPT_EZPORT_DIS: u8 = 1 << 1;
/// `FOPT.NMI_DIS`, bit 2: 1 = NMI pin/interrupt enabled.
pub const FOPT_NMI_DIS: u8 = 1 << 2;

/// What [`FlashConfig::check`] refuses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlashConfigError {
    /// `FSEC.SEC` is not `0b10`: the chip would be secured.
    Secured,
    /// `FSEC.MEEN` is `0b10`: mass erase disabled (with a secured chip: bricked).
    MassEraseDisabled,
}

impl FlashConfig {
    /// The Teensy configuration described in the [module docs](self).
    pub const TEENSY: FlashConfig = FlashConfig {
        backdoor_key: [0xFF; 8],
        fprot: [0xFF; 4],
        fsec: 0xFE,
        fopt: 0xF9,
        feprot: 0xFF,
        fdprot: 0xFF,
    };

    /// The 16 bytes in address order.
    pub const fn to_bytes(&self) -> [u8; 16] {
        let mut b = [0xFF; 16];
        let mut i = 0;
        while i < 8 {
            b[i] = self.backdoor_key[i];
            i += 1;
        }
        let mut j = 0;
        while j < 4 {
            b[8 + j] = self.fprot[j];
            j += 1;
        }
        b[12] = self.fsec;
        b[13] = self.fopt;
        b[14] = self.feprot;
        b[15] = self.fdprot;
        b
    }

    /// Refuses a configuration that would secure the chip or disable mass erase.
    pub const fn check(&self) -> Result<(), FlashConfigError> {
        if self.fsec & FSEC_SEC_MASK != FSEC_SEC_UNSECURE {
            Err(FlashConfigError::Secured)
        } else if (self.fsec >> FSEC_MEEN_SHIFT) & 0b11 == FSEC_FIELD_DISABLED {
            Err(FlashConfigError::MassEraseDisabled)
        } else {
            Ok(())
        }
    }
}

/// The bytes the firmware places at 0x400 (`src/rt.rs`).
pub const FLASH_CONFIG_BYTES: [u8; 16] = FlashConfig::TEENSY.to_bytes();

// A configuration that could lock the chip does not compile.
const _: () = assert!(FlashConfig::TEENSY.check().is_ok());

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes() {
        assert_eq!(
            FLASH_CONFIG_BYTES,
            [
                0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, // backdoor key
                0xFF, 0xFF, 0xFF, 0xFF, // FPROT3..0
                0xFE, 0xF9, 0xFF, 0xFF, // FSEC FOPT FEPROT FDPROT
            ]
        );
    }

    #[test]
    fn fields() {
        let f = FlashConfig::TEENSY;
        assert_eq!(f.fsec & FSEC_SEC_MASK, FSEC_SEC_UNSECURE);
        assert_eq!(
            (f.fsec >> FSEC_FSLACC_SHIFT) & 3,
            0b11,
            "factory access granted"
        );
        assert_eq!((f.fsec >> FSEC_MEEN_SHIFT) & 3, 0b11, "mass erase enabled");
        assert_eq!(
            (f.fsec >> FSEC_KEYEN_SHIFT) & 3,
            0b11,
            "backdoor key disabled"
        );
        assert_ne!(f.fopt & FOPT_LPBOOT, 0, "normal boot");
        assert_eq!(f.fopt & FOPT_EZPORT_DIS, 0, "EzPort disabled");
        assert_eq!(f.fopt & FOPT_NMI_DIS, 0, "NMI disabled");
    }

    #[test]
    fn dangerous_values_are_refused() {
        for sec in [0b00, 0b01, 0b11] {
            let f = FlashConfig {
                fsec: 0xFC | sec,
                ..FlashConfig::TEENSY
            };
            assert_eq!(f.check(), Err(FlashConfigError::Secured), "SEC = {sec:#b}");
        }
        let f = FlashConfig {
            fsec: 0xEE,
            ..FlashConfig::TEENSY
        };
        assert_eq!(f.check(), Err(FlashConfigError::MassEraseDisabled));
        // MEEN = 0b01 also enables mass erase.
        let f = FlashConfig {
            fsec: 0xDE,
            ..FlashConfig::TEENSY
        };
        assert_eq!(f.check(), Ok(()));
    }
}
