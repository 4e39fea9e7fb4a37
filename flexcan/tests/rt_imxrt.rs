//! The i.MX RT1062's interrupt wiring (features `rt` and `teensy40` or `teensy41`):
//! `IrqState::start` unmasks the module's one line once, at the settings' priority, and
//! the exported entry point (`CAN2` here) runs the message handlers and the status
//! handler of the module.
//!
//! As in `rt_start.rs`, the registers are a small `Sync` register file that
//! acknowledges the mode handshakes at once and clears `IFLAG1`/`ESR1` bits written 1.
//! The controller is in the RT1062 layout, as the board's `Can2::begin` gives it and
//! `rt::AcanState` holds it on a Teensy 4.
#![cfg(all(feature = "rt", any(feature = "teensy40", feature = "teensy41")))]

use twocan_core::{Frame, Registers};
use twocan_flexcan::layout::{BoardLayout, Imxrt1062};
use twocan_flexcan::options::Full;
use twocan_flexcan::regs::{self, cs, esr1, iflag1, mcr, ESR1, IFLAG1, MCR};
use twocan_flexcan::rt::{self, IrqNumber, IrqState, Nvic};
use twocan_flexcan::{rt_imxrt, Board, CanClock, FlexCan, HostSystem, Instance, Settings, Target};

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
fn can2_one_line_runs_every_handler() {
    let regs: &'static SyncRegs = Box::leak(Box::new(SyncRegs::imxrt()));
    let mut settings = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
    settings.message_irq_priority = 0x40;
    let target = Target::new(Board::Teensy41, Instance::Can2);
    let hw = FlexCan::<_, Imxrt1062>::begin_with_layout(
        regs,
        &mut HostSystem::new(),
        target,
        &settings,
        &[],
        &[],
    )
    .expect("begin")
    .into_split();
    // `rt::AcanState`'s shape, over these registers: the board's layout is the RT1062's.
    type Wired = IrqState<&'static SyncRegs, 32, twocan_core::FifoQueue<16>, 8, Full<BoardLayout>>;
    let state: &'static Wired = Box::leak(Box::new(Wired::new()));
    let mut nvic = Recorder::default();
    let (_tx, mut rx) = state.start(hw, &mut nvic).map_err(|(e, _)| e).unwrap();
    assert_eq!(
        nvic.calls,
        [("priority", 37, 0x40), ("unmask", 37, 0)],
        "CAN2's one line, once"
    );
    assert!(rt::is_wired(Instance::Can2));
    // The ERR005829 reserved mailbox (MB12 at the default RFFN 2) has no mask bit; the
    // transmit mailboxes after it (MB13–MB16) have theirs.
    assert_eq!(regs.read32(regs::IMASK1) & 1 << 12, 0);
    assert_eq!(regs.read32(regs::IMASK1) & 0xF << 13, 0xF << 13);
    assert_eq!(mcr::MAXMB.get(regs.read32(MCR)), 16);

    // A frame at the Rx FIFO output and a bus error at once: the one entry point
    // takes both.
    regs.write32(regs::mb_cs(0), cs::DLC.val(2));
    regs.write32(regs::mb_id(0), regs::id::STD.val(0x2A));
    regs.write32(regs::mb_word0(0), 0x0102_0000);
    regs.raise(IFLAG1, iflag1::BUF5I);
    regs.raise(ESR1, esr1::ERRINT | esr1::STFERR);
    rt_imxrt::can2();
    assert_eq!(regs.read32(IFLAG1) & iflag1::BUF5I, 0, "FIFO popped");
    assert_eq!(regs.read32(ESR1) & esr1::ERRINT, 0, "error flag cleared");
    let got = rx.receive().expect("a frame");
    assert_eq!(got.frame, Frame::standard(0x2A, &[1, 2]).unwrap());
    // CAN1 and CAN3 are not wired: their entry points do nothing.
    rt_imxrt::can1();
    rt_imxrt::can3();
    assert!(!rt::is_wired(Instance::Can1));
}

/// The quiet transmit mode through the entry point (`CAN3` here; `can2_one_line_runs_every_handler`, which
/// may run beside this test, calls it too: one more interrupt for this state, which
/// leaves every state checked below as it is): an `IrqState` with no
/// completion ring, the portable `Lean` features and a request-order queue runs it
/// (`State::QUIET_TX`), and the one line's handler takes the quiet path — the data
/// mailbox's enable off after the split and whenever the queue is empty, on while
/// frames wait; an end no interrupt acknowledged does not keep the next direct send
/// out; the refill from the entry point clears the data mailbox's flag before loading
/// it. The Rx FIFO's enables and the remote-frame mailboxes' are never touched.
#[test]
fn can3_entry_point_runs_the_quiet_transmit_mode() {
    use twocan_core::{FifoQueue, Lean, State};
    type H = twocan_flexcan::FlexCanHw<&'static SyncRegs, Full<BoardLayout>>;
    type Quiet = IrqState<&'static SyncRegs, 32, FifoQueue<4>, 0, Full<BoardLayout>, Lean>;
    const { assert!(State::<H, 32, FifoQueue<4>, 0, 0, Lean>::QUIET_TX) };
    let regs: &'static SyncRegs = Box::leak(Box::new(SyncRegs::imxrt()));
    let settings = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
    let target = Target::new(Board::Teensy41, Instance::Can3);
    let hw = FlexCan::<_, Imxrt1062>::begin_with_layout(
        regs,
        &mut HostSystem::new(),
        target,
        &settings,
        &[],
        &[],
    )
    .expect("begin")
    .into_split();
    let state: &'static Quiet = Box::leak(Box::new(Quiet::new()));
    let (mut tx, _rx) = state
        .start(hw, &mut Recorder::default())
        .map_err(|(e, _)| e)
        .unwrap();
    // Default RFFN 2: reserved MB12, remote-frame mailboxes MB13–MB15, data mailbox MB16.
    let data = 1u32 << 16;
    let configured = iflag1::BUF5I | iflag1::BUF7I | 0xF << 13;
    assert_eq!(
        regs.read32(regs::IMASK1),
        configured & !data,
        "split: data enable off"
    );
    let code_of = |mb| cs::CODE.get(regs.read32(regs::mb_cs(mb)));
    // The module sends the data mailbox's frame: INACTIVE, flag set (no interrupt: the
    // enable is off).
    let end = || {
        regs.write32(regs::mb_cs(16), cs::CODE.val(regs::code::TX_INACTIVE));
        regs.raise(IFLAG1, data);
    };
    let f = |k: u8| Frame::standard(0x100 + u16::from(k), &[k]).unwrap();
    tx.try_send(&f(0)).unwrap();
    assert_eq!(code_of(16), regs::code::TX_DATA);
    end();
    // Not acknowledged, yet the next direct send takes the mailbox (its flag cleared).
    tx.try_send(&f(1)).unwrap();
    assert_eq!(code_of(16), regs::code::TX_DATA);
    assert_eq!(
        regs.read32(IFLAG1) & data,
        0,
        "flag cleared before the load"
    );
    assert_eq!(tx.stats().count, 0);
    // Busy: two frames queue, the enable goes on.
    tx.try_send(&f(2)).unwrap();
    tx.try_send(&f(3)).unwrap();
    assert_eq!(tx.stats().count, 2);
    assert_eq!(
        regs.read32(regs::IMASK1),
        configured,
        "frames wait: data enable on"
    );
    // Each end runs the entry point: the refill loads the next frame.
    end();
    rt_imxrt::can3();
    assert_eq!(tx.stats().count, 1);
    assert_eq!(regs.read32(regs::mb_id(16)), regs::id::STD.val(0x102));
    assert_eq!(regs.read32(IFLAG1) & data, 0);
    assert_eq!(regs.read32(regs::IMASK1), configured);
    end();
    rt_imxrt::can3();
    assert_eq!(tx.stats().count, 0);
    assert_eq!(regs.read32(regs::mb_id(16)), regs::id::STD.val(0x103));
    assert_eq!(
        regs.read32(regs::IMASK1),
        configured & !data,
        "queue empty: off"
    );
}
