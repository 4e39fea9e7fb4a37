//! The in-place configuration under the library's interrupts (issue 21):
//! `IrqState::start_in_place` claims the module's entry points, lets the configuration
//! write the controller straight into the state's storage (`FlexCan::begin_in_place`
//! with a `static` table, `FlexCan::begin_checked_in_place` with a compile-time plan),
//! installs the handlers, then unmasks the lines at the settings' priority; its errors
//! leave nothing wired, and `FlexCanHw::end` gives the registers and the table back.
//!
//! A test binary of its own: the entry points of FlexCAN0 and FlexCAN1 are process-wide.
#![cfg(feature = "rt")]

use twocan_core::{Error, Filter, Frame, Registers};
use twocan_flexcan::filters::TableSlot;
use twocan_flexcan::options::{FullInSlot, Lean};
use twocan_flexcan::planner::PlanOptions;
use twocan_flexcan::regs::{self, cs, iflag1, mcr, IFLAG1, MCR};
use twocan_flexcan::rt::{self, InPlaceError, IrqNumber, IrqState, Line, Nvic, StartError};
use twocan_flexcan::{
    const_plan, BeginError, BeginPlan, Board, FlexCan, HostSystem, Instance, Settings, Target,
};

#[path = "common/sync_regs.rs"]
mod sync_regs;
use sync_regs::SyncRegs;

type Regs = &'static SyncRegs;
type InSlot = IrqState<Regs, 32, twocan_core::FifoQueue<16>, 8, FullInSlot>;
type LeanState = IrqState<Regs, 8, twocan_core::FifoQueue<4>, 0, Lean, twocan_core::Lean>;

/// Records the NVIC calls; at each unmask, runs that line's entry point and notes
/// whether a handler ran.
struct Recorder {
    instance: Instance,
    unmasked: Vec<(u16, u8)>,
    handled_at_unmask: Vec<bool>,
    priorities: std::collections::HashMap<u16, u8>,
    masked: Vec<u16>,
}

impl Recorder {
    fn new(instance: Instance) -> Self {
        Recorder {
            instance,
            unmasked: Vec::new(),
            handled_at_unmask: Vec::new(),
            priorities: Default::default(),
            masked: Vec::new(),
        }
    }
}

impl Nvic for Recorder {
    fn set_priority(&mut self, irq: IrqNumber, priority: u8) {
        self.priorities.insert(irq.number(), priority);
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
        self.unmasked
            .push((irq, self.priorities.get(&irq).copied().unwrap_or(0xFF)));
    }

    fn mask(&mut self, irq: IrqNumber) {
        self.masked.push(irq.number());
    }
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

const T36_CAN0: Target = Target::new(Board::Teensy36, Instance::Can0);
const T36_CAN1: Target = Target::new(Board::Teensy36, Instance::Can1);

#[test]
fn full_in_slot_configured_in_place_then_wired_and_back() {
    static TABLE: TableSlot = TableSlot::new();
    let regs: Regs = leak(SyncRegs::new());
    let state: &'static InSlot = leak(InSlot::new());
    let mut settings = Settings::new(500_000);
    settings.message_irq_priority = 0x40;
    let checked = BeginPlan::new(T36_CAN0, &settings, settings.configuration).unwrap();
    let mut slot = TABLE.take();

    // A list the partition cannot hold: `init`'s own error, the table's slot back,
    // nothing wired, the state still empty.
    let too_many = [Filter::standard(0x100); 40];
    let mut nvic = Recorder::new(Instance::Can0);
    let e = state
        .start_in_place(
            T36_CAN0,
            |hw| {
                FlexCan::begin_in_place(
                    hw,
                    regs,
                    &mut HostSystem::new(),
                    &checked,
                    &too_many,
                    &[],
                    slot.take().unwrap(),
                )
                .map_err(|(e, back)| {
                    slot = Some(back);
                    e
                })
            },
            &mut nvic,
        )
        .map(|_| ())
        .unwrap_err();
    assert!(
        matches!(e, InPlaceError::Init(BeginError::Config(_))),
        "{e:?}"
    );
    assert!(slot.is_some(), "the table comes back");
    assert!(nvic.unmasked.is_empty() && !rt::is_wired(Instance::Can0));
    assert!(state.state().hardware().is_none());

    // A controller of another module than the one claimed: refused, nothing wired.
    let other = leak(SyncRegs::new());
    let checked1 = BeginPlan::new(T36_CAN1, &settings, settings.configuration).unwrap();
    static OTHER_TABLE: TableSlot = TableSlot::new();
    let e = state
        .start_in_place(
            T36_CAN0,
            |hw| {
                FlexCan::begin_in_place(
                    hw,
                    other,
                    &mut HostSystem::new(),
                    &checked1,
                    &[Filter::pass_all()],
                    &[],
                    OTHER_TABLE.take().unwrap(),
                )
                .map_err(|(e, _)| e)
            },
            &mut nvic,
        )
        .map(|_| ())
        .unwrap_err();
    assert_eq!(
        e,
        InPlaceError::Start(StartError::Split(Error::InvalidArgument))
    );
    assert!(nvic.unmasked.is_empty() && !rt::is_wired(Instance::Can0));

    // Configured in place: handlers in place at every unmask, each line at the
    // settings' priority (Teensy 3.6 FlexCAN0: 75-79).
    let table_at = slot.as_deref().map(|t| t as *const _).unwrap();
    let (mut tx, mut rx) = state
        .start_in_place(
            T36_CAN0,
            |hw| {
                FlexCan::begin_in_place(
                    hw,
                    regs,
                    &mut HostSystem::new(),
                    &checked,
                    &[Filter::pass_all()],
                    &[],
                    slot.take().unwrap(),
                )
                .map_err(|(e, _)| e)
            },
            &mut nvic,
        )
        .unwrap();
    assert_eq!(
        nvic.unmasked,
        [(75, 0x40), (76, 0x40), (77, 0x40), (78, 0x40), (79, 0x40)]
    );
    assert_eq!(nvic.handled_at_unmask, [true; 5]);
    assert!(rt::is_wired(Instance::Can0));
    frame_arrives(regs, 0x123, &[1, 2]);
    rt::can0_ored_message_buffer();
    let got = rx.receive().expect("a frame");
    assert_eq!(got.frame, Frame::standard(0x123, &[1, 2]).unwrap());
    assert!(got.timestamp.is_some(), "every feature: time stamps");
    tx.try_send(&Frame::standard(0x10, &[1]).unwrap()).unwrap();
    assert_eq!(regs::id::STD.get(regs.read32(regs::mb_id(15))), 0x10);

    // The way back: the lines masked, the module ended, the registers and the very
    // table of the slot back.
    let (hw, _) = state.stop(tx, rx, &mut nvic).map_err(|(e, _)| e).unwrap();
    assert_eq!(nvic.masked, [75, 76, 77, 78, 79]);
    let (_, table) = hw.end(&mut HostSystem::new()).map_err(|(_, e)| e).unwrap();
    assert_eq!(table as *const _, table_at);
    assert_ne!(regs.read32(MCR) & mcr::MDIS, 0, "module disabled");
}

#[test]
fn lean_configured_in_place_from_a_compile_time_plan() {
    const SETTINGS: Settings = {
        let mut s = Settings::new(500_000);
        s.loop_back = true;
        s.self_reception = true;
        s
    };
    const CHECKED: BeginPlan = BeginPlan::new_or_panic(T36_CAN1, &SETTINGS, SETTINGS.configuration);
    const FILTERS: [Filter; 1] = [Filter::standard(0x321)];
    let table = const_plan!(FILTERS, PlanOptions::new(SETTINGS.configuration)).planned();
    let regs: Regs = leak(SyncRegs::new());
    let state: &'static LeanState = leak(LeanState::new());
    let mut nvic = Recorder::new(Instance::Can1);
    let (mut tx, mut rx) = state
        .start_in_place(
            T36_CAN1,
            |hw| FlexCan::begin_checked_in_place(hw, regs, &mut HostSystem::new(), &CHECKED, table),
            &mut nvic,
        )
        .unwrap();
    // Teensy 3.6 FlexCAN1: 94-98.
    assert_eq!(
        nvic.unmasked.iter().map(|u| u.0).collect::<Vec<_>>(),
        [94, 95, 96, 97, 98]
    );
    assert_eq!(nvic.handled_at_unmask, [true; 5]);
    frame_arrives(regs, 0x321, &[7]);
    assert!(rt::dispatch(Instance::Can1, Line::Message));
    let got = rx.receive().expect("a frame");
    assert_eq!(got.frame, Frame::standard(0x321, &[7]).unwrap());
    assert_eq!(got.filter, 0);
    assert_eq!(got.timestamp, None, "lean: no time stamps");
    // Fire and forget: accepted, loaded into MB15, no completion ring.
    tx.try_send(&Frame::standard(0x20, &[2]).unwrap()).unwrap();
    assert_eq!(regs::id::STD.get(regs.read32(regs::mb_id(15))), 0x20);
    assert!(tx.take_completion().is_none());
    assert_eq!(state.state().traffic().received, 0, "lean: no statistics");
}
