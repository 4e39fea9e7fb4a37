//! Board facts: chip, memory map and FlexCAN interrupt vectors of each Teensy 3.x.
//!
//! Everything here is plain data so that host tests can check it (against the vendor
//! SVD files: `tests/facts_k20.rs`, `tests/facts_k66.rs`) and the ELF test can check a
//! built image against it (`tests/elf.rs`). The firmware uses `BOARD`, selected by the
//! board feature.

use twocan_flexcan::Instance;

/// One board: the backend's board facts (chip, FlexCAN instances, pins, IRQ numbers)
/// plus what the start-up code needs (memory map, size of the vector table).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Board {
    /// The name printed by tools and used by the cargo feature.
    pub name: &'static str,
    /// The board as `twocan-flexcan` knows it.
    pub can: twocan_flexcan::Board,
    /// Program flash: origin and length in bytes (`memory/<board>.x`).
    pub flash: (u32, u32),
    /// SRAM_L + SRAM_U as one region: origin and length in bytes (`memory/<board>.x`).
    pub ram: (u32, u32),
    /// Number of device interrupt vectors (after the 16 Cortex-M exception entries).
    pub irq_count: usize,
}

/// Number of consecutive interrupt vectors per FlexCAN instance.
pub const CAN_VECTORS_PER_INSTANCE: usize = 6;

/// Offset of the message-buffer (ORed MB / Rx FIFO) vector within an instance's six.
pub const CAN_VECTOR_MESSAGE: usize = 0;

impl Board {
    /// Teensy 3.1 / 3.2: 92 device vectors (K20P64M72SF1RM §3.2.2.3 "Interrupt channel
    /// assignments"; the MK20D7 SVD's last is PORTE, IRQ 91). CAN0 = IRQ 29–34.
    pub const TEENSY32: Board = Board {
        name: "teensy32",
        can: twocan_flexcan::Board::Teensy32,
        flash: (0x0000_0000, 256 * 1024),
        ram: (0x1FFF_8000, 64 * 1024),
        irq_count: 92,
    };

    /// Teensy 3.5: 86 device vectors (K64P144M120SF5RM §3.2.2.3; the last is
    /// ENET_Error, IRQ 85). CAN0 = IRQ 75–80.
    pub const TEENSY35: Board = Board {
        name: "teensy35",
        can: twocan_flexcan::Board::Teensy35,
        flash: (0x0000_0000, 512 * 1024),
        ram: (0x1FFF_0000, 192 * 1024),
        irq_count: 86,
    };

    /// Teensy 3.6: 100 device vectors (K66P144M180SF5RMV2 §3.2.2.3; the MK66F18 SVD's
    /// last is CAN1_Wake_Up, IRQ 99). CAN0 = IRQ 75–80, CAN1 = IRQ 94–99.
    pub const TEENSY36: Board = Board {
        name: "teensy36",
        can: twocan_flexcan::Board::Teensy36,
        flash: (0x0000_0000, 1024 * 1024),
        ram: (0x1FFF_0000, 256 * 1024),
        irq_count: 100,
    };

    /// Every board.
    pub const ALL: [Board; 3] = [Board::TEENSY32, Board::TEENSY35, Board::TEENSY36];

    /// The board of that feature name.
    pub fn by_name(name: &str) -> Option<Board> {
        Board::ALL.into_iter().find(|b| b.name == name)
    }

    /// The FlexCAN instances of the board, in vector-table order.
    pub const fn can_instances(&self) -> &'static [Instance] {
        if self.can.has(Instance::Can1) {
            &[Instance::Can0, Instance::Can1]
        } else {
            &[Instance::Can0]
        }
    }

    /// IRQ number of the first of the six FlexCAN vectors of `instance`
    /// (`CANn_ORed_Message_buffer`), from the backend's interrupt table.
    pub const fn can_irq_base(&self, instance: Instance) -> Option<u16> {
        if !self.can.has(instance) {
            return None;
        }
        match instance.irqs(self.can.chip()) {
            Some(irqs) => Some(irqs.message - CAN_VECTOR_MESSAGE as u16),
            None => None,
        }
    }

    /// Size of the whole vector table in bytes: initial SP, reset and 14 exception
    /// entries, then the device vectors.
    pub const fn vector_table_bytes(&self) -> usize {
        4 * (16 + self.irq_count)
    }

    /// End of RAM: the initial stack pointer.
    pub const fn stack_top(&self) -> u32 {
        self.ram.0 + self.ram.1
    }
}

/// The board this firmware is built for.
#[cfg(feature = "teensy32")]
pub const BOARD: Board = Board::TEENSY32;
/// The board this firmware is built for.
#[cfg(feature = "teensy35")]
pub const BOARD: Board = Board::TEENSY35;
/// The board this firmware is built for.
#[cfg(feature = "teensy36")]
pub const BOARD: Board = Board::TEENSY36;

/// The Teensy crystal: 16 MHz on EXTAL0/XTAL0 (every Teensy 3.x), which is also the
/// FlexCAN clock (`CTRL1.CLKSRC = 0`, oscillator clock) as in ACAN.
pub const CRYSTAL_HZ: u32 = 16_000_000;

/// Pin 13, the orange LED: port C bit 5 on every Teensy 3.x.
pub const LED_PORT_C_BIT: u32 = 5;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vector_tables_end_before_the_flash_configuration_field() {
        for b in Board::ALL {
            assert!(b.vector_table_bytes() <= 0x400, "{}", b.name);
            for &i in b.can_instances() {
                let base = b.can_irq_base(i).unwrap();
                assert!(base as usize + CAN_VECTORS_PER_INSTANCE <= b.irq_count);
                let irqs = i.irqs(b.can.chip()).unwrap();
                assert_eq!(
                    irqs.wake_up as usize,
                    base as usize + CAN_VECTORS_PER_INSTANCE - 1
                );
            }
            assert_eq!(b.stack_top() % 8, 0);
        }
        assert_eq!(Board::by_name("teensy36"), Some(Board::TEENSY36));
        assert_eq!(Board::TEENSY36.can_irq_base(Instance::Can1), Some(94));
        assert_eq!(Board::TEENSY32.can_irq_base(Instance::Can1), None);
        assert_eq!(Board::TEENSY32.can_irq_base(Instance::Can0), Some(29));
    }
}
