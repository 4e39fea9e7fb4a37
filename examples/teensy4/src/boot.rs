//! The FlexSPI NOR configuration block the boot ROM reads at offset 0 of the flash
//! (IMXRT1060RM, "System Boot", "FlexSPI NOR Configuration Block", 512 bytes): how to read
//! the Teensy 4's quad SPI NOR to execute in place. `memory/boot.x` places it at
//! 0x6000_0000 and the image vector table and boot data after it.
//!
//! The fields set (offsets within the block): tag "FCFB" (0x000), version 1.4.0 (0x004),
//! `readSampleClkSrc` 1 = loopback from the DQS pad (0x00C), `csHoldTime` and
//! `csSetupTime` 3 cycles (0x00D, 0x00E), `deviceType` 1 = serial NOR (0x044),
//! `sflashPadType` 4 = quad (0x045), `serialClkFreq` 1 = 30 MHz (0x046),
//! `sflashA1Size` the board's flash (0x050), the look-up table's sequence 0 = fast read
//! quad I/O, 0xEB, 24-bit address and 6 dummy cycles on 4 pads (0x080), `pageSize` 256
//! (0x1C0), `sectorSize` 4 KiB (0x1C4). The rest is 0 (ROM defaults).

/// The board's flash size (Teensy 4.1: 8 MiB; 4.0: 2 MiB).
pub const FLASH_BYTES: u32 = if cfg!(feature = "teensy40") {
    2 << 20
} else {
    8 << 20
};

/// The configuration block for a flash of `flash_bytes`.
pub const fn flexspi_configuration_block(flash_bytes: u32) -> [u8; 512] {
    let mut b = [0u8; 512];
    b = word(b, 0x000, 0x4246_4346);
    b = word(b, 0x004, 0x5601_0400);
    b[0x00C] = 1;
    b[0x00D] = 3;
    b[0x00E] = 3;
    b[0x044] = 1;
    b[0x045] = 4;
    b[0x046] = 1;
    b = word(b, 0x050, flash_bytes);
    // LUT sequence 0: CMD_SDR 1 pad 0xEB, RADDR_SDR 4 pads 24 bits; DUMMY_SDR 4 pads 6,
    // READ_SDR 4 pads.
    b = word(b, 0x080, 0x0A18_04EB);
    b = word(b, 0x084, 0x2604_3206);
    b = word(b, 0x1C0, 256);
    b = word(b, 0x1C4, 4096);
    b
}

const fn word(mut b: [u8; 512], at: usize, v: u32) -> [u8; 512] {
    let le = v.to_le_bytes();
    b[at] = le[0];
    b[at + 1] = le[1];
    b[at + 2] = le[2];
    b[at + 3] = le[3];
    b
}

/// The block itself, in `.fcb` (`memory/boot.x` keeps it at 0x6000_0000).
#[cfg(target_os = "none")]
#[link_section = ".fcb"]
#[no_mangle]
#[used]
pub static FLEXSPI_CONFIGURATION_BLOCK: [u8; 512] = flexspi_configuration_block(FLASH_BYTES);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tag_version_and_size() {
        let b = flexspi_configuration_block(8 << 20);
        assert_eq!(&b[0..4], b"FCFB");
        assert_eq!(u32::from_le_bytes(b[4..8].try_into().unwrap()), 0x5601_0400);
        assert_eq!(
            u32::from_le_bytes(b[0x50..0x54].try_into().unwrap()),
            8 << 20
        );
        assert_eq!(b[0x80], 0xEB, "fast read quad I/O");
    }
}
