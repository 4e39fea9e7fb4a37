//! The host simulation: the real FlexCAN and bxCAN drivers over their behavioural models,
//! both attached to one simulated bus, with their interrupts serviced between bus events.
//!
//! [`Harness`] owns the bus; [`FlexNode`] (a Teensy 3.6's can0) and [`BxNode`] (an
//! STM32F767's CAN1) each own a model handle and the portable [`twocan_core::Driver`] over
//! it (its per-line handlers run when the model raises that line). The demo (`can-demo`)
//! and the cross-controller tests use it.
//!
//! ```
//! use twocan_host::{Harness, FlexNode, BxNode};
//! use twocan_core::{Filter, Frame};
//! let mut h = Harness::new(500_000).unwrap();
//! let mut teensy = FlexNode::teensy36_can0(&mut h, &[Filter::pass_all()]).unwrap();
//! let mut stm32 = BxNode::stm32f767_can1(&mut h, &[Filter::pass_all()]).unwrap();
//! teensy.driver.try_send(&Frame::standard(0x123, &[1, 2, 3]).unwrap()).unwrap();
//! h.run_for(1_000, &mut [&mut teensy, &mut stm32]);
//! assert_eq!(stm32.driver.receive().unwrap().frame, Frame::standard(0x123, &[1, 2, 3]).unwrap());
//! ```
#![deny(missing_docs)]

pub mod executor;
pub mod split;

use std::cell::RefCell;
use std::rc::Rc;

use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::{BxCan, Can, Config as BxConfig, FifoPolicy};
use twocan_core::{Driver, ErrorState, Filter};
use twocan_flexcan::layout::{Imxrt1062, Kinetis, Layout};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::options::Full;
use twocan_flexcan::{Board, FlexCan, FlexCanHw, HostSystem, Instance, Settings, Target};
use twocan_sim::{Bus, BusNode, NodeId, SimError};

/// The simulated bus, shared with the register wrappers that let time pass while a driver
/// waits for an acknowledge bit.
pub use twocan_sim::SharedBus;

/// Register access to a model that lets bus time pass while a driver spins on a poll
/// register ([`twocan_sim::PollClock`]).
pub type Clocked<R> = twocan_sim::PollClock<R>;

/// Receive ring size of the simulated nodes.
pub const RX_RING: usize = 64;
/// Transmit queue size of the simulated nodes.
pub const TX_RING: usize = 32;
/// The APB1 clock of the simulated STM32F767 (216 MHz core, APB1 = /4).
pub const STM32F767_APB1_HZ: u32 = 54_000_000;

/// Why a node could not be brought up.
#[derive(Debug)]
pub enum SetupError {
    /// The bus refused the bit rate.
    Bus(SimError),
    /// FlexCAN `begin` failed.
    FlexCan(twocan_flexcan::BeginError),
    /// bxCAN configuration failed.
    BxCanConfig(twocan_bxcan::ConfigError),
    /// bxCAN filter planning failed.
    BxCanPlan(twocan_bxcan::PlanError),
    /// A driver operation failed.
    Driver(twocan_core::Error),
}

/// Something on the bus whose interrupts the harness services.
pub trait Serviced {
    /// Runs the driver's interrupt handler if the model raises an interrupt line;
    /// returns whether it did.
    fn service(&mut self) -> bool;
}

/// The simulated bus and its clock.
pub struct Harness {
    bus: SharedBus,
}

impl Harness {
    /// A bus at `bit_rate`.
    pub fn new(bit_rate: u32) -> Result<Self, SetupError> {
        let bus = Bus::new(bit_rate).map_err(SetupError::Bus)?;
        Ok(Harness {
            bus: Rc::new(RefCell::new(bus)),
        })
    }

    /// The bus (borrow it only between runs).
    pub fn bus(&self) -> &SharedBus {
        &self.bus
    }

    /// The current time in bit times.
    pub fn now(&self) -> u64 {
        self.bus.borrow().now()
    }

    /// Runs the bus for `bits` bit times, servicing every node after each bus event.
    pub fn run_for(&mut self, bits: u64, nodes: &mut [&mut dyn Serviced]) {
        let until = self.now() + bits;
        self.run_until(until, nodes);
    }

    /// Runs the bus until time `until`, servicing every node after each bus event.
    pub fn run_until(&mut self, until: u64, nodes: &mut [&mut dyn Serviced]) {
        loop {
            for n in nodes.iter_mut() {
                n.service();
            }
            let event = self.bus.borrow_mut().step_until(until);
            if event.is_none() {
                break;
            }
        }
        for n in nodes.iter_mut() {
            n.service();
        }
    }
}

/// Attaches a node as it is (the default of [`FlexNode::begin_via`] and
/// [`BxNode::with_config_via`]).
pub fn attach_plain(bus: &mut Bus, name: &str, node: Box<dyn BusNode>) -> NodeId {
    bus.attach_boxed(name, node)
}

/// The FlexCAN driver over its model with the message-buffer layout `L`
/// ([`twocan_flexcan::layout`]).
pub type FlexDriverOf<L> =
    Driver<FlexCanHw<Clocked<FlexCanModel>, Full<L>>, RX_RING, TX_RING, RX_RING>;
/// The FlexCAN driver over its model, as used by the host nodes (ACAN's layout,
/// [`Kinetis`], the default options: the Teensy 3.x).
pub type FlexDriver = FlexDriverOf<Kinetis>;
/// The FlexCAN driver over its model with the RT1062 layout ([`Imxrt1062`]: the
/// ERR005829 reserved mailbox after the Rx FIFO area, the transmit mailboxes after it),
/// the layout every Teensy 4 program uses.
pub type Rt1062Driver = FlexDriverOf<Imxrt1062>;
/// The bxCAN driver over its model, as used by the host nodes (a receive ring per
/// FIFO; the FlexCAN one has the same shape, its second ring stays unused).
pub type BxDriver = Driver<BxCan<Clocked<BxCanModel>>, RX_RING, TX_RING, RX_RING>;

/// A FlexCAN node on the bus whose controller uses the message-buffer layout `L`.
pub struct FlexNodeOf<L: Layout = Kinetis> {
    /// The peripheral model (for inspection and fault injection).
    pub model: FlexCanModel,
    /// The portable driver over the real FlexCAN backend.
    pub driver: FlexDriverOf<L>,
    /// Its place on the bus.
    pub id: NodeId,
}

/// A Teensy 3.x FlexCAN node on the bus (ACAN's layout, [`Kinetis`]).
pub type FlexNode = FlexNodeOf<Kinetis>;

/// A Teensy 4.x FlexCAN node on the bus, begun in the RT1062 layout ([`Imxrt1062`])
/// as a Teensy 4 program begins it.
pub type Rt1062Node = FlexNodeOf<Imxrt1062>;

/// The model of `target` attached by `attach`, and its registers with the bus time
/// passing while the driver polls MCR (mode acknowledges) and ESR1 (synchronisation
/// after freeze).
fn flex_model_via(
    h: &mut Harness,
    target: Target,
    attach: impl FnOnce(&mut Bus, &str, Box<dyn BusNode>) -> NodeId,
) -> (FlexCanModel, Clocked<FlexCanModel>, NodeId) {
    let model = FlexCanModel::new(target.model_chip());
    let name = format!("{:?}-{:?}", target.board, target.instance).to_lowercase();
    let id = attach(&mut h.bus.borrow_mut(), &name, Box::new(model.clone()));
    let regs = Clocked::with_poll_registers(
        model.clone(),
        &h.bus,
        &[twocan_flexcan::regs::MCR, twocan_flexcan::regs::ESR1],
    );
    (model, regs, id)
}

impl FlexNode {
    /// can0 of a Teensy 3.6 with `filters` as ACAN primary filters (up to 14 by
    /// configuration) and the bus's bit rate.
    pub fn teensy36_can0(h: &mut Harness, filters: &[Filter]) -> Result<Self, SetupError> {
        let bit_rate = h.bus.borrow().bit_rate();
        Self::begin(
            h,
            Target::new(Board::Teensy36, Instance::Can0),
            &Settings::new(bit_rate),
            filters,
            &[],
        )
    }
}

impl<L: Layout> FlexNodeOf<L> {
    /// Any instance with explicit settings and primary / secondary filters, begun in the
    /// layout `L` (`FlexCan::<_, L>::begin_with_layout`; [`FlexNode`]: ACAN's,
    /// `FlexCan::begin`; [`Rt1062Node`]: the RT1062's, as a Teensy 4 program begins it).
    pub fn begin(
        h: &mut Harness,
        target: Target,
        settings: &Settings,
        primary: &[Filter],
        secondary: &[Filter],
    ) -> Result<Self, SetupError> {
        Self::begin_via(h, target, settings, primary, secondary, attach_plain)
    }

    /// Like [`FlexNodeOf::begin`], but `attach` puts the model on the bus: a test can
    /// wrap the model in its own [`BusNode`] (to watch or act on every bus event) before
    /// it attaches it. `attach` gets the bus, the node's name and the model handle.
    pub fn begin_via(
        h: &mut Harness,
        target: Target,
        settings: &Settings,
        primary: &[Filter],
        secondary: &[Filter],
        attach: impl FnOnce(&mut Bus, &str, Box<dyn BusNode>) -> NodeId,
    ) -> Result<Self, SetupError> {
        let (model, regs, id) = flex_model_via(h, target, attach);
        let controller = FlexCan::<_, L>::begin_with_layout(
            regs,
            &mut HostSystem::new(),
            target,
            settings,
            primary,
            secondary,
        )
        .map_err(SetupError::FlexCan)?;
        Ok(FlexNodeOf {
            model,
            driver: Driver::new(controller.into_split()),
            id,
        })
    }
}

impl<L: Layout> FlexNodeOf<L> {
    /// Frames the hardware received but no filter accepted.
    pub fn filtered_out(&self) -> u64 {
        self.model.frames_discarded()
    }

    /// Frames lost in hardware (Rx FIFO overflow) plus in the receive ring.
    pub fn lost(&self) -> u64 {
        self.model.frames_lost() + self.driver.traffic().rx_ring_overflows as u64
    }
}

impl<L: Layout> Serviced for FlexNodeOf<L> {
    fn service(&mut self) -> bool {
        if self.model.irq_pending() {
            self.driver.on_interrupt();
            true
        } else {
            false
        }
    }
}

/// An STM32F7 bxCAN node on the bus.
pub struct BxNode {
    /// The peripheral model (for inspection and fault injection).
    pub model: BxCanModel,
    /// The portable driver over the real bxCAN backend.
    pub driver: BxDriver,
    /// Its place on the bus.
    pub id: NodeId,
}

impl BxNode {
    /// CAN1 of an STM32F767 (APB1 54 MHz) at the bus's bit rate, FIFO transmit order,
    /// automatic bus-off recovery, `filters` compiled by the planner.
    pub fn stm32f767_can1(h: &mut Harness, filters: &[Filter]) -> Result<Self, SetupError> {
        let bit_rate = h.bus.borrow().bit_rate();
        let config = BxConfig::from_bitrate(STM32F767_APB1_HZ, bit_rate)
            .map_err(SetupError::BxCanConfig)?
            .tx_policy(twocan_core::TxPolicy::Fifo)
            .recovery(twocan_bxcan::Recovery::Automatic)
            .interrupts(
                twocan_bxcan::regs::ier::TMEIE
                    | twocan_bxcan::regs::ier::FMPIE0
                    | twocan_bxcan::regs::ier::FMPIE1
                    | twocan_bxcan::regs::ier::FOVIE0
                    | twocan_bxcan::regs::ier::FOVIE1
                    | twocan_bxcan::regs::ier::ERRIE
                    | twocan_bxcan::regs::ier::EWGIE
                    | twocan_bxcan::regs::ier::EPVIE
                    | twocan_bxcan::regs::ier::BOFIE
                    | twocan_bxcan::regs::ier::LECIE,
            );
        Self::with_config(h, &config, filters, FifoPolicy::Balanced)
    }

    /// CAN1 with an explicit configuration and FIFO policy for the planner.
    pub fn with_config(
        h: &mut Harness,
        config: &BxConfig,
        filters: &[Filter],
        fifos: FifoPolicy,
    ) -> Result<Self, SetupError> {
        Self::with_config_via(h, config, filters, fifos, attach_plain)
    }

    /// Like [`BxNode::with_config`], but `attach` puts the model on the bus (see
    /// [`FlexNode::begin_via`]).
    pub fn with_config_via(
        h: &mut Harness,
        config: &BxConfig,
        filters: &[Filter],
        fifos: FifoPolicy,
        attach: impl FnOnce(&mut Bus, &str, Box<dyn BusNode>) -> NodeId,
    ) -> Result<Self, SetupError> {
        let model = BxCanModel::can1();
        let id = attach(
            &mut h.bus.borrow_mut(),
            "stm32f767-can1",
            Box::new(model.clone()),
        );
        let regs = Clocked::new(model.clone(), &h.bus, twocan_bxcan::regs::MSR);
        let mut init = Can::can1(regs, config).map_err(|f| SetupError::Driver(f.error))?;
        let plan = init
            .can()
            .plan(filters, fifos)
            .map_err(SetupError::BxCanPlan)?;
        init.set_filters(&plan).map_err(SetupError::Driver)?;
        let can = init.enable().map_err(|f| SetupError::Driver(f.error))?;
        Ok(BxNode {
            model,
            driver: Driver::new(can.into_split()),
            id,
        })
    }

    /// Frames the hardware received but no filter accepted.
    pub fn filtered_out(&self) -> u64 {
        self.model.state().dropped
    }

    /// Frames lost in hardware (FIFO overruns) plus in the receive ring.
    pub fn lost(&self) -> u64 {
        let s = self.model.state();
        s.overruns[0] + s.overruns[1] + self.driver.traffic().rx_ring_overflows as u64
    }
}

impl Serviced for BxNode {
    fn service(&mut self) -> bool {
        // One handler per line, as the four vectors of the chip run them.
        let l = self.model.irq_lines();
        if l.tx {
            self.driver.on_tx();
        }
        if l.rx0 {
            self.driver.on_rx(0);
        }
        if l.rx1 {
            self.driver.on_rx(1);
        }
        if l.sce {
            self.driver.on_status();
        }
        l.tx || l.rx0 || l.rx1 || l.sce
    }
}

/// A short name for an error state, for reports.
pub fn state_name(s: ErrorState) -> &'static str {
    match s {
        ErrorState::Active => "error-active",
        ErrorState::Warning => "error-warning",
        ErrorState::Passive => "error-passive",
        ErrorState::BusOff => "bus-off",
        ErrorState::Stopped => "stopped",
        ErrorState::Sleeping => "sleeping",
    }
}
