//! Test harness: the bxCAN model on a simulated bus, with register access that lets bus
//! time pass while the driver polls `CAN_MSR` (as real time passes while firmware waits
//! for an acknowledge bit).
#![allow(dead_code)]

use std::cell::{Cell, RefCell};
use std::rc::Rc;

use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::MSR;
use twocan_bxcan::BxCan;
use twocan_bxcan::{Can, Config, FilterPlan, Recovery};
use twocan_core::{Driver, Filter, Frame, Registers, RxFrame, TxPolicy};
use twocan_sim::{Bus, SimNode};

pub type SharedBus = Rc<RefCell<Bus>>;

/// Register access to a model; each read of `CAN_MSR` lets `bits_per_poll` bit times
/// pass on the bus while `ticking` is on.
#[derive(Clone)]
pub struct Clocked {
    pub model: BxCanModel,
    pub bus: SharedBus,
    pub ticking: Rc<Cell<bool>>,
    pub bits_per_poll: u64,
    /// Fails a test whose driver spins on a register the model never changes.
    pub watchdog: Rc<twocan_sim::SpinWatchdog>,
    /// The bus time, read also while the bus is borrowed.
    pub clock: twocan_sim::BusClock,
}

impl Clocked {
    pub fn new(model: BxCanModel, bus: &SharedBus) -> Self {
        Clocked {
            model,
            bus: bus.clone(),
            ticking: Rc::new(Cell::new(true)),
            bits_per_poll: 1,
            watchdog: Rc::default(),
            clock: bus.borrow().clock(),
        }
    }
}

/// Bus time after which a test over [`Clocked`] is taken to wait for ever (a frame that
/// never comes, through a blocking API that polls the controller while time passes):
/// 40 s at 500 kbit/s, far beyond any test of this crate.
pub const BUS_TIME_LIMIT: u64 = 20_000_000;

impl Clocked {
    fn watch(&self, what: &str, offset: usize) {
        let now = self.clock.now();
        self.watchdog.access(Some(now), what, offset);
        assert!(
            now < BUS_TIME_LIMIT,
            "the test ran {now} bit times of bus time: it waits for something that never \
             happens (last a {what} of offset 0x{offset:03X})"
        );
    }
}

impl std::fmt::Debug for Clocked {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Clocked")
            .field("ticking", &self.ticking.get())
            .finish_non_exhaustive()
    }
}

impl Registers for Clocked {
    fn read32(&self, offset: usize) -> u32 {
        self.watch("read", offset);
        if offset == MSR && self.ticking.get() {
            self.bus.borrow_mut().run_for(self.bits_per_poll);
        }
        self.model.read32(offset)
    }
    fn write32(&self, offset: usize, value: u32) {
        self.watch("write", offset);
        self.model.write32(offset, value)
    }
}

pub const BITRATE: u32 = 500_000;
pub const APB1: u32 = 54_000_000;

pub fn config() -> Config {
    Config::from_bitrate(APB1, BITRATE).unwrap()
}

pub fn loopback_config(policy: TxPolicy) -> Config {
    config().loopback(true).tx_policy(policy)
}

pub fn new_bus() -> SharedBus {
    Rc::new(RefCell::new(Bus::new(BITRATE).unwrap()))
}

/// CAN1 on a bus of its own, configured and enabled, with `plan` installed.
pub fn can1_with(config: &Config, plan: &FilterPlan) -> (Can<Clocked>, Clocked, SharedBus) {
    let bus = new_bus();
    let model = BxCanModel::can1();
    bus.borrow_mut().attach("can1", model.clone());
    let regs = Clocked::new(model, &bus);
    let mut init = Can::can1(regs.clone(), config)
        .map_err(|f| f.error)
        .unwrap();
    init.set_filters(plan).unwrap();
    let can = init.enable().map_err(|f| f.error).unwrap();
    (can, regs, bus)
}

/// CAN1 and a plain ISO node (which acknowledges) on one bus.
pub fn can1_and_peer(
    config: &Config,
    plan: &FilterPlan,
) -> (Can<Clocked>, Clocked, SharedBus, Rc<RefCell<SimNode>>) {
    let bus = new_bus();
    let model = BxCanModel::can1();
    bus.borrow_mut().attach("can1", model.clone());
    let peer = SimNode::new().shared();
    bus.borrow_mut().attach("peer", peer.clone());
    let regs = Clocked::new(model, &bus);
    let mut init = Can::can1(regs.clone(), config)
        .map_err(|f| f.error)
        .unwrap();
    init.set_filters(plan).unwrap();
    let can = init.enable().map_err(|f| f.error).unwrap();
    (can, regs, bus, peer)
}

pub fn pass_all() -> FilterPlan {
    twocan_bxcan::plan(&[Filter::pass_all()], twocan_bxcan::PlanOptions::new(14)).unwrap()
}

pub fn run(bus: &SharedBus, bits: u64) {
    bus.borrow_mut().run_for(bits);
}

pub fn settle(bus: &SharedBus) {
    let _ = bus.borrow_mut().run_until_idle(200_000);
}

/// The one-struct driver over CAN1 used by the driver tests (a receive ring per FIFO).
pub type Drv = Driver<BxCan<Clocked>, 16, 8, 16>;

/// The driver over an enabled controller.
pub fn driver(can: Can<Clocked>) -> Drv {
    Driver::new(can.into_split())
}

/// Runs every handler, then takes everything received, in order.
pub fn drain(d: &mut Drv) -> Vec<RxFrame> {
    d.on_interrupt();
    let mut v = Vec::new();
    while let Ok(f) = d.receive() {
        v.push(f);
    }
    v
}

pub fn std(id: u16) -> Frame {
    Frame::standard(id, &[id as u8]).unwrap()
}

pub fn automatic() -> Recovery {
    Recovery::Automatic
}
