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

use std::sync::atomic::{AtomicU32, Ordering};

use twocan_core::{Frame, Registers};
use twocan_flexcan::layout::{BoardLayout, Imxrt1062};
use twocan_flexcan::options::Full;
use twocan_flexcan::regs::{self, cs, esr1, iflag1, mcr, ESR1, IFLAG1, MCR};
use twocan_flexcan::rt::{self, IrqNumber, IrqState, Nvic};
use twocan_flexcan::{rt_imxrt, Board, CanClock, FlexCan, HostSystem, Instance, Settings, Target};

struct SyncRegs {
    words: Vec<AtomicU32>,
}

impl Registers for SyncRegs {
    fn read32(&self, offset: usize) -> u32 {
        let v = self.words[offset / 4].load(Ordering::SeqCst);
        match offset {
            MCR if v & mcr::MDIS != 0 => v | mcr::LPMACK | mcr::NOTRDY,
            MCR if v & mcr::FRZ != 0 && v & mcr::HALT != 0 => v | mcr::FRZACK | mcr::NOTRDY,
            ESR1 => v | esr1::SYNCH,
            _ => v,
        }
    }

    fn write32(&self, offset: usize, value: u32) {
        let w = &self.words[offset / 4];
        match offset {
            MCR => w.store(
                value & !(mcr::FRZACK | mcr::LPMACK | mcr::NOTRDY | mcr::SOFTRST),
                Ordering::SeqCst,
            ),
            IFLAG1 | ESR1 => {
                w.fetch_and(!value, Ordering::SeqCst);
            }
            _ => w.store(value, Ordering::SeqCst),
        }
    }
}

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
    let regs: &'static SyncRegs = Box::leak(Box::new(SyncRegs {
        words: (0..regs::IMXRT_BLOCK_END / 4)
            .map(|_| AtomicU32::new(0))
            .collect(),
    }));
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
    regs.words[IFLAG1 / 4].fetch_or(iflag1::BUF5I, Ordering::SeqCst);
    regs.words[ESR1 / 4].fetch_or(esr1::ERRINT | esr1::STFERR, Ordering::SeqCst);
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
