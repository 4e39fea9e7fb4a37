//! The library's interrupt wiring (feature `rt`, issue 17): `IrqState::start` installs
//! the handlers before it unmasks each line, gives every line the settings'
//! `message_irq_priority`, refuses a second wiring with a typed error, and the exported
//! entry points (`CAN0_ORED_MESSAGE_BUFFER` ...) run the split driver's handlers.
//!
//! The NVIC is the `Nvic` seam: a recorder that, at each `unmask`, calls the entry
//! point of that line and notes whether a handler ran. The registers are a small
//! `Sync` register file (the split state lives in a `static`-like leaked box and is
//! shared with interrupt context, which the behavioural model, single-threaded, is not):
//! it acknowledges the mode handshakes at once (Kinetis RM, FlexCAN "Modes of
//! operation") and clears `IFLAG1`/`ESR1` bits written 1.
#![cfg(feature = "rt")]

use twocan_core::{Frame, Registers};
use twocan_flexcan::regs::{self, cs, iflag1, mcr, IFLAG1, MCR};
use twocan_flexcan::rt::{self, IrqNumber, IrqState, Line, Nvic, StartError};
use twocan_flexcan::{Board, FlexCan, HostSystem, Instance, Settings, Target};

#[path = "common/sync_regs.rs"]
mod sync_regs;
use sync_regs::SyncRegs;

type Regs = &'static SyncRegs;
type Wired = IrqState<Regs, 32, twocan_core::FifoQueue<16>, 8>;

/// Records the NVIC calls; at each unmask, runs that line's entry point as the
/// hardware would if the cause were pending, and notes whether a handler ran.
struct Recorder {
    instance: Instance,
    calls: Vec<(&'static str, u16, u8)>,
    handled_at_unmask: Vec<bool>,
    priorities: std::collections::HashMap<u16, u8>,
    /// The state whose handlers `mask` looks at (`stop`'s order).
    watch: Option<&'static Wired>,
    /// At each mask: whether the state's handlers were still in place.
    installed_at_mask: Vec<[bool; 2]>,
}

impl Recorder {
    fn new(instance: Instance) -> Self {
        Recorder {
            instance,
            calls: Vec::new(),
            handled_at_unmask: Vec::new(),
            priorities: Default::default(),
            watch: None,
            installed_at_mask: Vec::new(),
        }
    }
}

impl Nvic for Recorder {
    fn set_priority(&mut self, irq: IrqNumber, priority: u8) {
        let irq = irq.number();
        self.priorities.insert(irq, priority);
        self.calls.push(("priority", irq, priority));
    }

    fn unmask(&mut self, irq: IrqNumber) {
        let irq = irq.number();
        let message = Target::new(Board::Teensy36, self.instance)
            .irqs()
            .unwrap()
            .message;
        let line = if irq == message {
            Line::Message
        } else {
            Line::Status
        };
        self.handled_at_unmask
            .push(rt::dispatch(self.instance, line));
        let p = self.priorities.get(&irq).copied();
        self.calls.push(("unmask", irq, p.unwrap_or(0xFF)));
    }

    fn mask(&mut self, irq: IrqNumber) {
        self.calls.push(("mask", irq.number(), 0));
        if let Some(state) = self.watch {
            self.installed_at_mask.push(state.installed());
        }
    }
}

fn begin(regs: Regs, instance: Instance, priority: u8) -> FlexCan<Regs> {
    let mut settings = Settings::new(500_000);
    settings.message_irq_priority = priority;
    FlexCan::begin(
        regs,
        &mut HostSystem::new(),
        Target::new(Board::Teensy36, instance),
        &settings,
        &[],
        &[],
    )
    .expect("begin")
}

fn leak<T>(t: T) -> &'static T {
    Box::leak(Box::new(t))
}

/// Puts one standard frame in the Rx FIFO output (MB0) and raises `BUF5I`.
fn frame_arrives(regs: &SyncRegs, id: u16, data: &[u8]) {
    let mut bytes = [0u8; 8];
    bytes[..data.len()].copy_from_slice(data);
    regs.write32(regs::mb_cs(0), cs::DLC.val(data.len() as u32));
    regs.write32(regs::mb_id(0), regs::id::STD.val(id as u32));
    regs.write32(
        regs::mb_word0(0),
        u32::from_be_bytes(bytes[..4].try_into().unwrap()),
    );
    regs.write32(
        regs::mb_word1(0),
        u32::from_be_bytes(bytes[4..].try_into().unwrap()),
    );
    regs.write32(regs::RXFIR, 0);
    regs.raise(IFLAG1, iflag1::BUF5I);
}

#[test]
fn can0_handlers_installed_before_each_line_is_unmasked_at_the_settings_priority() {
    // Nothing wired yet: the entry points do nothing.
    assert!(!rt::dispatch(Instance::Can0, Line::Message));
    assert!(!rt::is_wired(Instance::Can0));

    let regs: Regs = leak(SyncRegs::new());
    let state: &'static Wired = leak(Wired::new());
    let mut nvic = Recorder::new(Instance::Can0);
    let hw = begin(regs, Instance::Can0, 0x30).into_split();
    let (mut tx, mut rx) = state.start(hw, &mut nvic).map_err(|(e, _)| e).unwrap();

    // Teensy 3.6 FlexCAN0: message 75, bus off 76, error 77, Tx/Rx warning 78/79.
    let unmasked: Vec<_> = nvic
        .calls
        .iter()
        .filter(|c| c.0 == "unmask")
        .map(|c| (c.1, c.2))
        .collect();
    assert_eq!(
        unmasked,
        [(75, 0x30), (76, 0x30), (77, 0x30), (78, 0x30), (79, 0x30)],
        "each line gets its priority before it is unmasked: {:?}",
        nvic.calls
    );
    assert_eq!(
        nvic.handled_at_unmask, [true; 5],
        "a handler at every unmask"
    );
    assert!(rt::is_wired(Instance::Can0));

    // The exported entry point runs the receive handler: the frame reaches `rx`.
    frame_arrives(regs, 0x123, &[1, 2, 3]);
    rt::can0_ored_message_buffer();
    assert_eq!(regs.read32(IFLAG1) & iflag1::BUF5I, 0, "FIFO popped");
    let got = rx.receive().expect("a frame");
    assert_eq!(got.frame, Frame::standard(0x123, &[1, 2, 3]).unwrap());

    // ... and the transmit handler: a frame queued behind a busy MB15 goes out once
    // the entry point settles MB15.
    tx.try_send(&Frame::standard(0x10, &[1]).unwrap()).unwrap();
    tx.try_send(&Frame::standard(0x11, &[2]).unwrap()).unwrap();
    let mb15_id = || regs::id::STD.get(regs.read32(regs::mb_id(15)));
    assert_eq!(mb15_id(), 0x10);
    // MB15 sent: the hardware writes code INACTIVE and raises its flag.
    regs.write32(regs::mb_cs(15), cs::CODE.val(regs::code::TX_INACTIVE));
    regs.raise(IFLAG1, iflag1::buf(15));
    rt::can0_ored_message_buffer();
    assert_eq!(mb15_id(), 0x11, "the transmit handler refilled MB15");
    for entry in [
        rt::can0_bus_off,
        rt::can0_error,
        rt::can0_tx_warning,
        rt::can0_rx_warning,
    ] {
        entry();
    }
    assert!(rt::dispatch(Instance::Can0, Line::Status));

    // A second wiring of FlexCAN0 is refused, with the controller back and nothing
    // unmasked.
    let other: &'static Wired = leak(Wired::new());
    let mut nvic2 = Recorder::new(Instance::Can0);
    let hw = begin(leak(SyncRegs::new()), Instance::Can0, 0x30).into_split();
    let (e, hw) = other.start(hw, &mut nvic2).map(|_| ()).unwrap_err();
    assert_eq!(e, StartError::AlreadyWired);
    assert!(nvic2.calls.is_empty());
    assert_eq!(hw.target().instance, Instance::Can0);
}

#[test]
fn can1_errors_leave_the_slot_free() {
    let state: &'static Wired = leak(Wired::new());
    let regs: Regs = leak(SyncRegs::new());
    let mut nvic = Recorder::new(Instance::Can1);
    let controller = FlexCan::begin(
        regs,
        &mut HostSystem::new(),
        Target::new(Board::Teensy36, Instance::Can1),
        &Settings::new(500_000),
        &[],
        &[],
    )
    .unwrap();
    let hw = controller.into_split();
    // A state split already (here: by another controller) refuses, and the slot
    // stays free for the next try.
    let used: &'static Wired = leak(Wired::new());
    let parts = used
        .state()
        .split(begin(leak(SyncRegs::new()), Instance::Can1, 0).into_split());
    assert!(parts.is_ok());
    let (e, hw) = used.start(hw, &mut nvic).map(|_| ()).unwrap_err();
    assert_eq!(e, StartError::AlreadySplit);
    let _: &dyn core::error::Error = &e;
    assert_eq!(e.to_string(), "the state holds a controller already");
    assert!(nvic.calls.is_empty());
    assert!(!rt::is_wired(Instance::Can1));

    let (tx, rx) = state.start(hw, &mut nvic).map_err(|(e, _)| e).unwrap();
    assert!(rt::is_wired(Instance::Can1));
    assert_eq!(nvic.handled_at_unmask, [true; 5]);
    let unmasked: Vec<_> = nvic
        .calls
        .iter()
        .filter(|c| c.0 == "unmask")
        .map(|c| c.1)
        .collect();
    assert_eq!(unmasked, [94, 95, 96, 97, 98]);
    assert!(nvic
        .calls
        .iter()
        .all(|c| c.2 == twocan_flexcan::settings::DEFAULT_IRQ_PRIORITY));
    stop_end_begin_start_again(state, regs, nvic, (tx, rx));
}

type Halves = twocan_flexcan::rt::Halves<Regs, 32, twocan_core::FifoQueue<16>, 8>;

/// Issue 22 item 11: the way back. `stop` masks the five lines while the handlers are
/// still in place, then takes them back (the entry points do nothing from then on: a
/// frame that arrives stays in the FIFO) and gives the controller back; it ends
/// (module disabled, flags cleared, clock gate and pins released) and begins again,
/// and the same state starts again over it.
fn stop_end_begin_start_again(
    state: &'static Wired,
    regs: Regs,
    mut nvic: Recorder,
    (mut tx, mut rx): Halves,
) {
    use twocan_flexcan::rt::StopError;

    nvic.watch = Some(state);
    // (`rt::can1_ored_message_buffer` exists with `teensy36` only; it runs this.)
    frame_arrives(regs, 0x55, &[5]);
    assert!(rt::dispatch(Instance::Can1, Line::Message));
    assert_eq!(rx.receive().map(|f| f.frame.raw_id()).ok(), Some(0x55));
    tx.try_send(&Frame::standard(0x66, &[6]).unwrap()).unwrap();

    // A reference from `hardware()` alive: refused, the handlers put back, the lines
    // unmasked again.
    let lease = state.state().hardware().unwrap();
    nvic.calls.clear();
    let Err((e, (tx, rx))) = state.stop(tx, rx, &mut nvic) else {
        panic!("stopped while a reference to the controller was alive");
    };
    assert_eq!(e, StopError::Leased);
    assert_eq!(state.installed(), [true; 2]);
    assert_eq!(
        nvic.calls.iter().filter(|c| c.0 == "unmask").count(),
        5,
        "{:?}",
        nvic.calls
    );
    drop(lease);

    nvic.calls.clear();
    nvic.installed_at_mask.clear();
    let (hw, left) = state.stop(tx, rx, &mut nvic).map_err(|(e, _)| e).unwrap();
    let masked: Vec<u16> = nvic.calls.iter().map(|c| c.1).collect();
    assert_eq!(masked, [94, 95, 96, 97, 98], "{:?}", nvic.calls);
    assert!(nvic.calls.iter().all(|c| c.0 == "mask"));
    assert_eq!(
        nvic.installed_at_mask, [[true; 2]; 5],
        "every line masked while its handler was in place"
    );
    assert_eq!(state.installed(), [false; 2]);
    assert_eq!(left.queued, 0, "0x66 went to MB15 at once");
    // No handler runs after the mask: a frame arriving now stays in the FIFO.
    frame_arrives(regs, 0x77, &[7]);
    assert!(!rt::dispatch(Instance::Can1, Line::Message));
    assert!(!rt::dispatch(Instance::Can1, Line::Status));
    assert_ne!(
        regs.read32(IFLAG1) & iflag1::BUF5I,
        0,
        "nobody read the FIFO"
    );

    // End: module disabled, interrupt flags cleared.
    let regs_back = hw
        .into_controller()
        .end(&mut HostSystem::new())
        .map_err(|(_, e)| e)
        .unwrap();
    assert!(core::ptr::eq(regs_back, regs));
    assert_ne!(regs.read32(MCR) & mcr::MDIS, 0, "module disabled");
    assert_eq!(regs.read32(IFLAG1) & iflag1::BUF5I, 0, "flags cleared");

    // Begin again, start the same state again: the entry points run it.
    nvic.calls.clear();
    nvic.handled_at_unmask.clear();
    let hw = begin(regs_back, Instance::Can1, 0x20).into_split();
    let (_tx, mut rx) = state.start(hw, &mut nvic).map_err(|(e, _)| e).unwrap();
    assert_eq!(nvic.handled_at_unmask, [true; 5]);
    assert!(nvic
        .calls
        .iter()
        .filter(|c| c.0 == "unmask")
        .all(|c| c.2 == 0x20));
    frame_arrives(regs, 0x88, &[8]);
    assert!(rt::dispatch(Instance::Can1, Line::Message));
    assert_eq!(rx.receive().map(|f| f.frame.raw_id()).ok(), Some(0x88));
}
