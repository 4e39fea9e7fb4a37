//! The register window of the board's modules with a Teensy 4 feature
//! (`regs::FlexCanRegs`, `0..regs::BOARD_BLOCK_END`) covers every register the RT1062
//! layout ([`Imxrt1062`], what the one calls, the tokens and the examples use there)
//! reaches: `begin` for every configuration with full filter lists, a transmission of a
//! data and a remote frame (with the ERR005829 writes), the filters replaced while
//! running, and `end`. An access outside the window would be dropped on the target (a
//! read gives 0; debug builds assert), so the RT1062's individual masks `RXIMR16` and
//! above, beyond the Kinetis block (`regs::BLOCK_END`), must be inside it.
#![cfg(any(feature = "teensy40", feature = "teensy41"))]

mod common;

use std::cell::RefCell;
use std::rc::Rc;

use common::*;
use twocan_core::{Driver, Filter, Registers};
use twocan_flexcan::layout::{Imxrt1062, LargeFilterTable};
use twocan_flexcan::options::Full;
use twocan_flexcan::regs::{self, FlexCanRegs};
use twocan_flexcan::{
    Board, CanClock, Configuration, FlexCan, FlexCanHw, HostSystem, Instance, Settings, Target,
};

/// The model's registers with every offset read or written recorded.
struct Recorded {
    inner: Ticking,
    offsets: Rc<RefCell<Vec<usize>>>,
}

impl core::fmt::Debug for Recorded {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Recorded").finish_non_exhaustive()
    }
}

impl Registers for Recorded {
    fn read32(&self, offset: usize) -> u32 {
        self.offsets.borrow_mut().push(offset);
        self.inner.read32(offset)
    }
    fn write32(&self, offset: usize, value: u32) {
        self.offsets.borrow_mut().push(offset);
        self.inner.write32(offset, value)
    }
}

fn lists(c: Configuration, base: u16) -> (Vec<Filter>, Vec<Filter>) {
    let primary = (0..c.primary_filter_capacity() as u16)
        .map(|i| Filter::standard(base + i))
        .collect();
    let secondary = (0..c.secondary_filter_capacity() as u16)
        .map(|i| Filter::extended(u32::from(base) << 8 | u32::from(i)))
        .collect();
    (primary, secondary)
}

#[test]
fn the_board_window_covers_every_register_the_rt1062_layout_reaches() {
    assert_eq!(regs::BOARD_BLOCK_END, regs::IMXRT_BLOCK_END);
    assert!(FlexCanRegs::owns(regs::rximr(63)));
    assert!(!FlexCanRegs::owns(regs::IMXRT_BLOCK_END));
    let target = Target::new(Board::DEFAULT, Instance::Can1);
    let mut beyond_kinetis = 0;
    for c in Configuration::EVERY {
        let offsets = Rc::new(RefCell::new(Vec::new()));
        let regs = Recorded {
            inner: Ticking::new(model_of(target)),
            offsets: offsets.clone(),
        };
        let mut settings = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
        settings.configuration = c;
        let (primary, secondary) = lists(c, 0x100);
        let controller = FlexCan::<_, Imxrt1062>::begin_with_layout(
            regs,
            &mut HostSystem::new(),
            target,
            &settings,
            &primary,
            &secondary,
        )
        .unwrap_or_else(|e| panic!("{c:?}: {e:?}"));
        let mut can: Driver<FlexCanHw<Recorded, Full<Imxrt1062>>, 32, 16> =
            Driver::new(controller.into_split());
        // Alone on the bus: both frames stay pending in their mailboxes.
        can.try_send(&std_data(0x123, &[1, 2])).unwrap();
        can.try_send_now(&twocan_core::Frame::remote(0x42, false, 0).unwrap())
            .unwrap();
        can.on_interrupt();
        let (primary, secondary) = lists(c, 0x200);
        let table = LargeFilterTable::compile_for(c, &primary, &secondary)
            .unwrap_or_else(|e| panic!("{c:?}: {e:?}"));
        can.set_filters(&table)
            .unwrap_or_else(|e| panic!("{c:?}: {e:?}"));
        can.release()
            .end(&mut HostSystem::new())
            .map_err(|(_, e)| e)
            .unwrap();
        let offsets = offsets.borrow();
        for &o in offsets.iter() {
            assert!(
                FlexCanRegs::owns(o),
                "{c:?}: offset {o:#x} outside the window"
            );
        }
        beyond_kinetis += offsets.iter().filter(|&&o| o >= regs::BLOCK_END).count();
    }
    // The window matters: the larger tables' individual masks lie beyond the Kinetis
    // block.
    assert!(beyond_kinetis > 0);
}
