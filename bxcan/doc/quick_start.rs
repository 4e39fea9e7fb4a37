// Quick start on the host: CAN1's behavioural model (feature `model`) in loop-back
// mode on the simulated bus; firmware runs the same code over the registers that the
// HAL hand-over gives (`twocan_bxcan::hal`). This file is the crate documentation's
// quick start and, verbatim, the workspace test `tests/tests/first_program.rs`.
use std::{cell::RefCell, rc::Rc};

use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::{BxCan, Can, Config, FifoPolicy};
use twocan_sim::{Bus, PollClock};
use twocan_core::split::State;
use twocan_core::{FifoQueue, Filter, Frame, TxOutcome};

fn main() {
    // The state the halves share: a `static` in firmware (zero-initialised, `.bss`);
    // here a local, as the model's handle is not `Sync`.
    let state: State<BxCan<PollClock<BxCanModel>>, 16, FifoQueue<8>, 16> = State::new();

    let model = BxCanModel::can1();
    let bus = Rc::new(RefCell::new(Bus::new(500_000).unwrap()));
    bus.borrow_mut().attach("can1", model.clone());
    // Bus time passes while the driver polls CAN_MSR for an acknowledge.
    let regs = PollClock::new(model.clone(), &bus, twocan_bxcan::regs::MSR);
    let config = Config::from_bitrate(54_000_000, 500_000)
        .unwrap()
        .loopback(true);
    let mut init = Can::can1(regs, &config).map_err(|f| f.error).unwrap();
    let plan = init
        .can()
        .plan(&[Filter::standard(0x123)], FifoPolicy::Fifo0)
        .unwrap();
    init.set_filters(&plan).unwrap();
    let can = init.enable().map_err(|f| f.error).unwrap(); // on the bus

    let mut parts = state.split(can.into_split()).ok().unwrap();
    let frame = Frame::standard(0x123, &[1, 2, 3]).unwrap();
    let token = parts.tx.try_send(&frame).unwrap();
    bus.borrow_mut().run_for(200); // the frame goes round the loop-back
    // The interrupt lines' handlers (TX, RX0) — in firmware, the vectors run them.
    parts.tx_irq.on_interrupt();
    parts.rx0_irq.on_interrupt();
    let rx = parts.rx.receive().unwrap();
    assert_eq!((rx.frame.raw_id(), rx.filter), (0x123, 0)); // the user's filter index
    assert_eq!(rx.frame.data(), &[1, 2, 3]);
    let done = parts.tx.take_completion().unwrap();
    assert_eq!((done.token, done.outcome), (token, TxOutcome::Sent));
}
