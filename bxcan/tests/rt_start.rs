//! The library's interrupt wiring (feature `rt`, issue 22 items 11 and 12):
//! `IrqState::start_on` installs the four handlers before it sets any priority or
//! unmasks any line; the lines get their priorities; a second state on the same
//! instance is refused; `stop_on` masks the lines before it takes the handlers back, no
//! handler runs after that, and the controller comes back, ends (master reset) and
//! begins again on the same state.
//!
//! The NVIC is the `Nvic` seam: a simulated one over the behavioural model's interrupt
//! line levels (`BxCanModel::irq_lines`), which enters the vector of every line that is
//! asserted and unmasked (as the hardware does) and records every call.
//!
//! One test function per binary: the entry points' slots are process-wide, and the
//! model (`Rc`, one thread) is shared with the "interrupt" side only on this thread.
#![cfg(all(feature = "model", feature = "rt"))]

mod common;

use std::cell::RefCell;

use common::*;
use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::rt::{self, IrqState, Line, Nvic, Priorities, StartError};
use twocan_bxcan::{Can, Instance};
use twocan_core::{FifoQueue, Frame, Registers};

/// The model's registers, declared shareable between "contexts" that are all this
/// test's one thread.
#[derive(Debug)]
struct OneThread(Clocked);

// SAFETY: the registers (an `Rc` model) are reached only from the thread that runs the
// one test of this binary: the "interrupts" are the simulated NVIC's calls on it.
unsafe impl Send for OneThread {}
// SAFETY: as above.
unsafe impl Sync for OneThread {}

impl Registers for OneThread {
    fn read32(&self, offset: usize) -> u32 {
        self.0.read32(offset)
    }
    fn write32(&self, offset: usize, value: u32) {
        self.0.write32(offset, value)
    }
}

type Wired = IrqState<OneThread, OneThread, 8, FifoQueue<4>, 8, 8>;

/// CAN1's interrupt numbers on the STM32F7 (RM0410 table 40), in `Line::ALL` order.
const CAN1_LINES: [u16; 4] = [19, 20, 21, 22];

#[derive(Debug, Clone, PartialEq)]
enum Call {
    Priority(u16, u8),
    Unmask(u16),
    Mask(u16),
}

/// A simulated NVIC: enters the vector of each asserted, unmasked line; records calls
/// with whether every handler of the state was in place at that moment.
struct SimNvic {
    model: BxCanModel,
    instance: Instance,
    lines: [u16; 4],
    unmasked: [bool; 4],
    state: &'static Wired,
    calls: Vec<(Call, [bool; 4])>,
    entered: RefCell<Vec<(Line, bool)>>,
}

impl SimNvic {
    fn new(model: BxCanModel, lines: [u16; 4], state: &'static Wired) -> Self {
        SimNvic {
            instance: model.instance(),
            model,
            lines,
            unmasked: [false; 4],
            state,
            calls: Vec::new(),
            entered: RefCell::new(Vec::new()),
        }
    }

    fn index(&self, line: u16) -> usize {
        self.lines
            .iter()
            .position(|&l| l == line)
            .expect("a line of this instance")
    }

    /// What the NVIC does between two instructions of the thread: enters the vector
    /// of every asserted, unmasked line (bounded: a line whose cause nobody clears
    /// would be entered for ever).
    fn pump(&self) {
        for _ in 0..16 {
            let l = self.model.irq_lines();
            let asserted = [l.tx, l.rx0, l.rx1, l.sce];
            let Some(i) = (0..4).find(|&i| asserted[i] && self.unmasked[i]) else {
                return;
            };
            let ran = rt::dispatch(self.instance, Line::ALL[i]);
            self.entered.borrow_mut().push((Line::ALL[i], ran));
        }
        panic!("a line stays asserted: its cause is never cleared");
    }
}

impl Nvic<u16> for SimNvic {
    fn set_priority(&mut self, line: u16, priority: u8) {
        self.calls
            .push((Call::Priority(line, priority), self.state.installed()));
    }
    fn unmask(&mut self, line: u16) {
        self.calls
            .push((Call::Unmask(line), self.state.installed()));
        let i = self.index(line);
        self.unmasked[i] = true;
        // An interrupt pending at this moment is taken at once.
        self.pump();
    }
    fn mask(&mut self, line: u16) {
        self.calls.push((Call::Mask(line), self.state.installed()));
        let i = self.index(line);
        self.unmasked[i] = false;
    }
}

fn std(id: u16) -> Frame {
    Frame::standard(id, &[id as u8]).unwrap()
}

/// CAN1 over `regs`, configured (normal mode), filters passing all, on the bus.
fn begin(regs: OneThread) -> Can<OneThread> {
    let mut init = Can::can1(regs, &config()).map_err(|f| f.error).unwrap();
    init.set_filters(&pass_all()).unwrap();
    init.enable().map_err(|f| f.error).unwrap()
}

#[test]
fn start_installs_then_unmasks_stop_masks_then_takes_and_the_controller_begins_again() {
    let bus = new_bus();
    let model = BxCanModel::can1();
    bus.borrow_mut().attach("can1", model.clone());
    let peer = twocan_sim::SimNode::new().shared();
    bus.borrow_mut().attach("peer", peer.clone());
    let can = begin(OneThread(Clocked::new(model.clone(), &bus)));

    // A frame is already waiting in FIFO 0 when the driver starts: RX0 is asserted
    // before `start_on`, so its handler must be in place when the line is unmasked.
    peer.borrow_mut().send(std(0x0F0));
    settle(&bus);
    assert!(model.irq_lines().rx0);

    let state: &'static Wired = Box::leak(Box::new(Wired::new()));
    let mut nvic = SimNvic::new(model.clone(), CAN1_LINES, state);
    let priorities = Priorities {
        tx: 0x40,
        rx0: 0x50,
        rx1: 0x60,
        sce: 0x70,
    };
    let (mut tx, mut rx) = state
        .start_on(can.into_split(), CAN1_LINES, priorities, &mut nvic)
        .map_err(|(e, _)| e)
        .unwrap();

    // Order: every handler in place before the first NVIC call; all priorities before
    // the first unmask, each line its own.
    assert!(nvic
        .calls
        .iter()
        .all(|(_, installed)| *installed == [true; 4]));
    let calls: Vec<Call> = nvic.calls.iter().map(|(c, _)| c.clone()).collect();
    assert_eq!(
        calls,
        [
            Call::Priority(19, 0x40),
            Call::Priority(20, 0x50),
            Call::Priority(21, 0x60),
            Call::Priority(22, 0x70),
            Call::Unmask(19),
            Call::Unmask(20),
            Call::Unmask(21),
            Call::Unmask(22),
        ]
    );
    assert!(rt::is_wired(Instance::Can1));
    // The waiting frame was taken by RX0's handler the moment its line was unmasked.
    assert_eq!(*nvic.entered.borrow(), [(Line::Rx0, true)]);
    assert_eq!(rx.receive().map(|f| f.frame.raw_id()).ok(), Some(0x0F0));

    // Traffic through the entry points: the NVIC enters TX and RX0.
    for id in [0x100, 0x101, 0x102] {
        tx.try_send(&std(id)).unwrap();
        peer.borrow_mut().send(std(id + 0x10));
        settle(&bus);
        nvic.pump();
    }
    let got: Vec<u32> = std::iter::from_fn(|| rx.receive().ok())
        .map(|f| f.frame.raw_id())
        .collect();
    assert_eq!(got, [0x110, 0x111, 0x112]);
    let sent: Vec<u32> = peer
        .borrow()
        .received_frames()
        .iter()
        .map(|f| f.raw_id())
        .collect();
    assert_eq!(sent, [0x100, 0x101, 0x102]);
    assert_eq!(std::iter::from_fn(|| tx.take_completion()).count(), 3);
    assert!(nvic.entered.borrow().iter().all(|&(_, ran)| ran));
    assert!(nvic.entered.borrow().iter().any(|&(l, _)| l == Line::Tx));

    // Another state on the same instance is refused, the controller handed back and
    // nothing unmasked.
    let other: &'static Wired = Box::leak(Box::new(Wired::new()));
    let bus2 = new_bus();
    let model2 = BxCanModel::can1();
    bus2.borrow_mut().attach("can1b", model2.clone());
    let can2 = begin(OneThread(Clocked::new(model2.clone(), &bus2)));
    let mut nvic2 = SimNvic::new(model2, CAN1_LINES, other);
    let Err((e, _back)) = other.start_on(
        can2.into_split(),
        CAN1_LINES,
        Priorities::all(0),
        &mut nvic2,
    ) else {
        panic!("two states wired to CAN1");
    };
    assert_eq!(e, StartError::AlreadyWired);
    assert!(nvic2.calls.is_empty(), "nothing unmasked");

    // A frame arrives while the thread stops the driver: it stays in FIFO 0, RX0
    // asserted, and the NVIC does not get to enter RX0 before `stop_on` masks it.
    peer.borrow_mut().send(std(0x200));
    settle(&bus);
    assert!(model.irq_lines().rx0);
    // A reference from `hardware()` alive: refused, the handlers put back and the
    // lines unmasked again (each after its handler is in place; the priorities stay).
    let lease = state.state().hardware().unwrap();
    nvic.calls.clear();
    let Err((e, (tx, mut rx))) = state.stop_on(tx, rx, CAN1_LINES, &mut nvic) else {
        panic!("stopped while a reference to the controller was alive");
    };
    assert_eq!(e, rt::StopError::Leased);
    drop(lease);
    let calls: Vec<Call> = nvic.calls.iter().map(|(c, _)| c.clone()).collect();
    assert_eq!(
        calls,
        [
            Call::Mask(19),
            Call::Mask(20),
            Call::Mask(21),
            Call::Mask(22),
            Call::Unmask(19),
            Call::Unmask(20),
            Call::Unmask(21),
            Call::Unmask(22),
        ]
    );
    assert!(nvic.calls[4..]
        .iter()
        .all(|(_, installed)| *installed == [true; 4]));
    // The frame waiting in FIFO 0 was taken when RX0 was unmasked again: one more.
    let waiting: Vec<u32> = std::iter::from_fn(|| rx.receive().ok())
        .map(|f| f.frame.raw_id())
        .collect();
    assert_eq!(waiting, [0x200]);
    peer.borrow_mut().send(std(0x201));
    settle(&bus);
    assert!(model.irq_lines().rx0);

    nvic.calls.clear();
    let (hw, left) = state
        .stop_on(tx, rx, CAN1_LINES, &mut nvic)
        .map_err(|(e, _)| e)
        .unwrap();
    let calls: Vec<Call> = nvic.calls.iter().map(|(c, _)| c.clone()).collect();
    assert_eq!(
        calls,
        [
            Call::Mask(19),
            Call::Mask(20),
            Call::Mask(21),
            Call::Mask(22)
        ]
    );
    assert!(
        nvic.calls
            .iter()
            .all(|(_, installed)| *installed == [true; 4]),
        "every line masked while the handlers were still in place"
    );
    assert_eq!(state.installed(), [false; 4], "handlers taken back");
    assert_eq!(left, twocan_core::Leftovers::default());
    // No handler runs after the mask: the NVIC enters nothing, and the entry point,
    // were it entered, finds no handler.
    let entered_before = nvic.entered.borrow().len();
    nvic.pump();
    assert_eq!(nvic.entered.borrow().len(), entered_before, "masked lines");
    twocan_bxcan::rt::vectors::CAN1_RX0();
    assert!(!rt::dispatch(Instance::Can1, Line::Rx0));
    assert_eq!(model.fifo_contents(0).len(), 1, "nobody read the FIFO");
    assert!(model.irq_lines().rx0);

    // End (master reset: every controller register back to reset, `CAN_IER` = 0,
    // the FIFOs released) and begin again, then start the same state again.
    let (regs, _) = hw.master_reset().map_err(|f| f.error).unwrap();
    assert!(!model.irq_lines().rx0, "reset: CAN_IER = 0");
    let can = begin(regs);
    nvic.calls.clear();
    nvic.entered.borrow_mut().clear();
    let (mut tx, mut rx) = state
        .start_on(can.into_split(), CAN1_LINES, priorities, &mut nvic)
        .map_err(|(e, _)| e)
        .unwrap();
    assert_eq!(state.installed(), [true; 4]);
    for id in [0x300, 0x301] {
        tx.try_send(&std(id)).unwrap();
        peer.borrow_mut().send(std(id + 0x10));
        settle(&bus);
        nvic.pump();
    }
    let got: Vec<u32> = std::iter::from_fn(|| rx.receive().ok())
        .map(|f| f.frame.raw_id())
        .collect();
    assert_eq!(got, [0x310, 0x311], "the begun-again controller receives");
    assert_eq!(std::iter::from_fn(|| tx.take_completion()).count(), 2);
    assert_eq!(
        state.state().traffic().sent,
        5,
        "statistics kept across the stop"
    );
}
