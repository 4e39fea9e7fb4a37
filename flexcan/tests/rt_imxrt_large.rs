//! The i.MX RT1062's interrupt wiring with the RT1062 layout
//! ([`twocan_flexcan::layout::Imxrt1062`], features `rt` and `teensy40` or `teensy41`):
//! the exported entry point (`CAN3` here) settles a transmit mailbox above MB31 from its
//! `IFLAG2` flag (IMXRT1060RM "Interrupt Flags 2 register") and takes a frame from the Rx
//! FIFO, whose flags stay in `IFLAG1`. A test binary of its own: the entry points'
//! state is per process.
//!
//! As in `rt_imxrt.rs`, the registers are a small `Sync` register file that
//! acknowledges the mode handshakes at once and clears `IFLAG1`/`IFLAG2`/`ESR1` bits
//! written 1.
#![cfg(all(feature = "rt", any(feature = "teensy40", feature = "teensy41")))]

use twocan_core::{Frame, Registers};
use twocan_flexcan::layout::{Imxrt1062, Layout};
use twocan_flexcan::options::Full;
use twocan_flexcan::regs::{self, code, cs, iflag1, IFLAG1, IFLAG2, IMASK2};
use twocan_flexcan::rt::{self, IrqNumber, IrqState, Nvic};
use twocan_flexcan::{
    rt_imxrt, Board, CanClock, Configuration, FlexCan, HostSystem, Instance, Settings, Target,
};

#[path = "common/sync_regs.rs"]
mod sync_regs;
use sync_regs::SyncRegs;

#[derive(Default)]
struct Recorder {
    calls: Vec<(&'static str, u16, u8)>,
}

impl Nvic for Recorder {
    fn set_priority(&mut self, irq: IrqNumber, priority: u8) {
        self.calls.push(("priority", irq.number(), priority));
    }

    fn unmask(&mut self, irq: IrqNumber) {
        self.calls.push(("unmask", irq.number(), 0));
    }

    fn mask(&mut self, irq: IrqNumber) {
        self.calls.push(("mask", irq.number(), 0));
    }
}

#[test]
fn can3_settles_a_mailbox_above_mb31_from_iflag2() {
    let regs: &'static SyncRegs = Box::leak(Box::new(SyncRegs::imxrt()));
    let mut settings = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
    settings.configuration = Configuration::Filters32_96;
    let target = Target::new(Board::Teensy41, Instance::Can3);
    let hw = FlexCan::<_, Imxrt1062>::begin_with_layout(
        regs,
        &mut HostSystem::new(),
        target,
        &settings,
        &[twocan_core::Filter::pass_all()],
        &[],
    )
    .expect("begin")
    .into_split();
    // After the ERR005829 reserved mailbox (MB38): MB39–MB45 remote, MB46 data.
    let data = usize::from(Imxrt1062::data_mailbox(Configuration::Filters32_96));
    assert_eq!(data, 46);
    assert_ne!(
        regs.read32(IMASK2) & 1 << (data - 32),
        0,
        "MB46's interrupt on"
    );
    type Wired = IrqState<&'static SyncRegs, 32, twocan_core::FifoQueue<16>, 8, Full<Imxrt1062>>;
    let state: &'static Wired = Box::leak(Box::new(Wired::new()));
    let mut nvic = Recorder::default();
    let (mut tx, mut rx) = state.start(hw, &mut nvic).map_err(|(e, _)| e).unwrap();
    assert!(rt::is_wired(Instance::Can3));

    // A data frame goes to MB46; the module "sends" it: INACTIVE, IFLAG2 bit 14.
    let frame = Frame::standard(0x123, &[7]).unwrap();
    let token = tx.try_send(&frame).unwrap();
    assert_eq!(cs::CODE.get(regs.read32(regs::mb_cs(data))), code::TX_DATA);
    // The ERR005829 reserved mailbox (MB38): INACTIVE after the activation, masked.
    assert_eq!(
        cs::CODE.get(regs.read32(regs::mb_cs(38))),
        code::TX_INACTIVE
    );
    assert_eq!(regs.read32(IMASK2) & 1 << (38 - 32), 0);
    regs.write32(regs::mb_cs(data), cs::CODE.val(code::TX_INACTIVE));
    regs.raise(IFLAG2, 1 << (data - 32));
    // And a frame at the Rx FIFO output (IFLAG1) in the same interrupt.
    regs.write32(regs::mb_cs(0), cs::DLC.val(1));
    regs.write32(regs::mb_id(0), regs::id::STD.val(0x2A));
    regs.write32(regs::mb_word0(0), 0x0900_0000);
    regs.raise(IFLAG1, iflag1::BUF5I);
    rt_imxrt::can3();
    assert_eq!(regs.read32(IFLAG2), 0, "MB46's flag acknowledged in IFLAG2");
    assert_eq!(regs.read32(IFLAG1) & iflag1::BUF5I, 0, "FIFO popped");
    let done = tx.take_completion().expect("one completion");
    assert_eq!(
        (done.token, done.outcome),
        (token, twocan_core::TxOutcome::Sent)
    );
    assert!(tx.take_completion().is_none(), "exactly one");
    let got = rx.receive().expect("a frame");
    assert_eq!(got.frame, Frame::standard(0x2A, &[9]).unwrap());
    // The data mailbox is free again.
    tx.try_send(&frame).unwrap();
    assert_eq!(cs::CODE.get(regs.read32(regs::mb_cs(data))), code::TX_DATA);
}
