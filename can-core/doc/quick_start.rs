// Quick start: the split driver over the mock controller (feature `mock`). This file is
// the crate documentation's quick start and, verbatim, the workspace test
// `tests/tests/first_program.rs`.
use twocan_core::mock::MockHardware;
use twocan_core::{Dispatcher, FifoQueue, Filter, Frame, RxFrame, State};

static CAN: State<MockHardware, 16, FifoQueue<8>> = State::new();

fn main() -> Result<(), twocan_core::Error> {
    let hw = MockHardware::new(3)
        .with_loopback(true)
        .with_filters(&[Filter::standard(0x100), Filter::standard(0x200)]);
    let mut p = CAN.split(hw).map_err(|(e, _)| e)?;
    for id in [0x100, 0x200, 0x300] {
        nb::block!(p.tx.try_send(&Frame::standard(id, &[1])?))?;
    }
    CAN.hardware().unwrap().complete_all(); // the mock sends its mailboxes
    p.tx_irq.on_interrupt(); // interrupt context: settle, refill
    p.rx0_irq.on_interrupt(); // interrupt context: FIFO → ring

    // Thread context: frames by the user's filter index (0x300 matched no filter).
    let mut seen = [0u32; 2];
    let mut table: Dispatcher<[u32; 2], 2> = Dispatcher::new();
    table.set(0, |s, _: &RxFrame| s[0] += 1).unwrap();
    table.set(1, |s, _: &RxFrame| s[1] += 1).unwrap();
    while p.rx.dispatch(&mut table, &mut seen) {}
    assert_eq!(seen, [1, 1]);
    assert_eq!(CAN.traffic().sent, 3);
    Ok(())
}
