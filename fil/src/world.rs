//! Several boards and plain simulated nodes on one simulated bus, advanced together.
//!
//! Each step of `quantum` simulated time: every board runs its CPU up to the step's end,
//! then the bus plays its frames up to the same time, then every board's CAN interrupt
//! lines are sampled into its NVIC. An interrupt a frame raises is therefore seen by the
//! CPU at most one quantum late (20 µs by default, a tenth of a frame at 500 kbit/s).
//!
//! Bit timing: the bus has one nominal bit rate. A controller whose programmed bit rate
//! (decoded from its timing register and its clock) differs from it by more than the
//! 1.58 % that ISO 11898-1 allows for the oscillator tolerance cannot sample the other
//! nodes' frames, nor they its frames: from the moment it joins the bus, every frame it
//! receives gives it a stuff error, and every frame it sends gives the others one.

use std::cell::RefCell;
use std::rc::Rc;

use twocan_core::Frame;
use twocan_sim::{Bus, Fault, NodeId, Receivers, SimNode};

use crate::can::Model;
use crate::elf::Image;
use crate::machine::Machine;
use crate::profile::Profile;

/// Largest bit-rate deviation a controller may have from the bus (ISO 11898-1 oscillator
/// tolerance, at best 1.58 %).
pub const TOLERANCE: f64 = 0.0158;

/// An error-state change seen on a controller.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StateChange {
    /// Simulated time (µs).
    pub at_us: u64,
    /// Node name.
    pub node: String,
    /// Old state.
    pub from: &'static str,
    /// New state.
    pub to: &'static str,
}

/// ISO 11898-1 fault-confinement state of the counters.
pub fn error_state(tec: u16, rec: u16) -> &'static str {
    if tec >= 256 {
        "bus-off"
    } else if tec >= 128 || rec >= 128 {
        "error-passive"
    } else {
        "error-active"
    }
}

/// A board's controller attached to the bus.
#[derive(Debug, Clone)]
pub struct Attached {
    /// Board index.
    pub board: usize,
    /// Port index on the board.
    pub port: usize,
    /// Bus node.
    pub node: NodeId,
    /// Name on the bus (`teensy36/CAN0`).
    pub name: String,
    /// Programmed bit rate, once decoded.
    pub bit_rate: Option<u64>,
    /// Found out of tolerance.
    pub misclocked: bool,
    state: &'static str,
}

/// A plain simulated node: optional periodic traffic, its own bit rate.
#[derive(Debug)]
pub struct PlainNode {
    /// Name on the bus.
    pub name: String,
    /// Bus node.
    pub node: NodeId,
    /// The node (for assertions on what it saw).
    pub sim: Rc<RefCell<SimNode>>,
    /// Its bit rate (the bus's unless it is meant to be wrong).
    pub bit_rate: u32,
    /// Frames it sends in turn, one per `period_ps`.
    pub traffic: Vec<Frame>,
    /// Period of the traffic.
    pub period_ps: u128,
    next_ps: u128,
    sent: usize,
    checked: bool,
    /// Found out of tolerance.
    pub misclocked: bool,
    state: &'static str,
}

/// Boards and nodes on one bus.
pub struct World<'a> {
    /// The boards.
    pub machines: Vec<Machine<'a>>,
    /// The bus.
    pub bus: Bus,
    /// Board controllers on the bus.
    pub attached: Vec<Attached>,
    /// Plain simulated nodes.
    pub nodes: Vec<PlainNode>,
    /// Error-state changes.
    pub changes: Vec<StateChange>,
    /// Simulated time reached (ps).
    pub now_ps: u128,
    /// Step length (ps).
    pub quantum_ps: u128,
}

impl<'a> World<'a> {
    /// An empty bus at `bit_rate`.
    pub fn new(bit_rate: u32) -> Result<Self, String> {
        let mut bus = Bus::new(bit_rate).map_err(|e| e.to_string())?;
        bus.set_tracing(true);
        Ok(World {
            machines: Vec::new(),
            bus,
            attached: Vec::new(),
            nodes: Vec::new(),
            changes: Vec::new(),
            now_ps: 0,
            quantum_ps: 20_000_000,
        })
    }

    /// Adds a board running `image`; its CAN controllers join the bus.
    pub fn add_board(&mut self, profile: Box<dyn Profile>, image: Image) -> Result<usize, String> {
        let same = self
            .machines
            .iter()
            .filter(|m| m.board().profile.name() == profile.name())
            .count();
        let name = if same == 0 {
            profile.name().to_string()
        } else {
            format!("{}#{}", profile.name(), same + 1)
        };
        let machine = Machine::new(&name, profile, image)?;
        let index = self.machines.len();
        for (p, port) in machine.board().cans.iter().enumerate() {
            let node_name = format!("{name}/{}", port.instance.name);
            let node = match &port.model {
                Model::FlexCan(m) => self.bus.attach(&node_name, m.clone()),
                Model::BxCan(m) => self.bus.attach(&node_name, m.clone()),
            };
            self.attached.push(Attached {
                board: index,
                port: p,
                node,
                name: node_name,
                bit_rate: None,
                misclocked: false,
                state: "error-active",
            });
        }
        self.machines.push(machine);
        Ok(index)
    }

    /// Adds a plain simulated node sending `traffic` in turn every `period_ps` (none if
    /// empty) at `bit_rate`, the first one `period_ps` after time 0.
    pub fn add_node(
        &mut self,
        name: &str,
        node: SimNode,
        bit_rate: u32,
        traffic: Vec<Frame>,
        period_ps: u128,
    ) -> Rc<RefCell<SimNode>> {
        self.add_node_from(name, node, bit_rate, traffic, period_ps, period_ps)
    }

    /// Like [`World::add_node`], the first frame at `first_ps`. A frame due at `t` is
    /// handed to the node at the end of the step that reaches `t`, and the bus plays that
    /// step from its start: it starts on the wire at the start of that step.
    pub fn add_node_from(
        &mut self,
        name: &str,
        node: SimNode,
        bit_rate: u32,
        traffic: Vec<Frame>,
        period_ps: u128,
        first_ps: u128,
    ) -> Rc<RefCell<SimNode>> {
        let shared = node.shared();
        let id = self.bus.attach(name, shared.clone());
        self.nodes.push(PlainNode {
            name: name.to_string(),
            node: id,
            sim: shared.clone(),
            bit_rate,
            traffic,
            period_ps: period_ps.max(1),
            next_ps: first_ps,
            sent: 0,
            checked: false,
            misclocked: false,
            state: "error-active",
        });
        shared
    }

    fn queue_traffic(&mut self, t: u128) {
        for n in &mut self.nodes {
            while !n.traffic.is_empty() && n.next_ps <= t {
                let f = n.traffic[n.sent % n.traffic.len()];
                n.sim.borrow_mut().send(f);
                n.sent += 1;
                n.next_ps += n.period_ps;
            }
        }
    }

    /// Arms the faults of a node out of tolerance: every frame it receives gives it a
    /// stuff error, every frame it sends gives the others one.
    fn arm_mismatch(&mut self, me: NodeId) {
        self.bus.inject_from(
            me,
            u32::MAX,
            Fault::Stuff {
                who: Receivers::All,
                at: None,
            },
        );
        let others: Vec<NodeId> = self
            .attached
            .iter()
            .map(|o| o.node)
            .chain(self.nodes.iter().map(|n| n.node))
            .filter(|n| *n != me)
            .collect();
        for o in others {
            self.bus.inject_from(
                o,
                u32::MAX,
                Fault::Stuff {
                    who: Receivers::Node(me),
                    at: None,
                },
            );
        }
    }

    /// Runs every board and the bus for `ps` picoseconds more.
    pub fn run_for(&mut self, ps: u128) {
        let end = self.now_ps + ps;
        while self.now_ps < end {
            let t = (self.now_ps + self.quantum_ps).min(end);
            for m in &mut self.machines {
                m.run_until(t);
                m.board_mut().watch_progress();
                m.drain_rtt();
            }
            self.check_bit_rates();
            self.queue_traffic(t);
            let bits = (t * u128::from(self.bus.bit_rate()) / 1_000_000_000_000) as u64;
            while self.bus.step_until(bits).is_some() {}
            for m in &mut self.machines {
                let b = m.board_mut();
                b.refresh_can_lines();
                b.note_join();
            }
            self.sample_states();
            self.now_ps = t;
        }
    }

    fn on_bus(model: &Model) -> bool {
        model.on_bus()
    }

    /// Decodes each controller's bit rate when it joins the bus; arms the mismatch
    /// faults for one out of tolerance.
    fn check_bit_rates(&mut self) {
        let nominal = f64::from(self.bus.bit_rate());
        for i in 0..self.attached.len() {
            if self.attached[i].bit_rate.is_some() {
                continue;
            }
            let a = &self.attached[i];
            let board = self.machines[a.board].board();
            let port = &board.cans[a.port];
            if !Self::on_bus(&port.model) || port.model.internal_loop_back() {
                continue;
            }
            let can_hz = board.profile.can_clock_hz(&port.instance);
            let bus_hz = board.profile.can_bus_clock_hz(&port.instance);
            let Some(rate) = port.model.programmed_bit_rate(can_hz, bus_hz) else {
                continue;
            };
            let pins = board.profile.can_pins(&port.instance);
            let name = port.instance.name;
            if let Err(missing) = pins {
                self.machines[a.board].board_mut().findings.push(format!(
                    "{name} joined the bus with its pins not routed to it: {missing}"
                ));
            }
            self.attached[i].bit_rate = Some(rate);
            let (board, port) = (self.attached[i].board, self.attached[i].port);
            let b = self.machines[board].board_mut();
            let instance = b.cans[port].instance.clone();
            b.profile.can_joined(&instance);
            if (rate as f64 - nominal).abs() / nominal > TOLERANCE {
                self.attached[i].misclocked = true;
                let me = self.attached[i].node;
                self.arm_mismatch(me);
            }
        }
        for i in 0..self.nodes.len() {
            if self.nodes[i].checked {
                continue;
            }
            self.nodes[i].checked = true;
            let rate = f64::from(self.nodes[i].bit_rate);
            if (rate - nominal).abs() / nominal > TOLERANCE {
                self.nodes[i].misclocked = true;
                let me = self.nodes[i].node;
                self.arm_mismatch(me);
            }
        }
    }

    fn sample_states(&mut self) {
        let at_us = (self.now_ps / 1_000_000) as u64;
        for a in &mut self.attached {
            let (tec, rec) = self.machines[a.board].board().cans[a.port].model.counters();
            let s = error_state(tec, rec);
            if s != a.state {
                self.changes.push(StateChange {
                    at_us,
                    node: a.name.clone(),
                    from: a.state,
                    to: s,
                });
                a.state = s;
            }
        }
        for n in &mut self.nodes {
            let c = n.sim.borrow().counters();
            let s = error_state(c.tec, c.rec);
            if s != n.state {
                self.changes.push(StateChange {
                    at_us,
                    node: n.name.clone(),
                    from: n.state,
                    to: s,
                });
                n.state = s;
            }
        }
    }

    /// Whether every board ran without a fault, stuck interrupt, livelock or halt.
    pub fn clean(&self) -> bool {
        self.machines.iter().all(|m| {
            let b = m.board();
            b.faults.is_empty() && b.stuck.is_empty() && b.livelock.is_none() && b.halted.is_none()
        })
    }

    /// The bus in candump format.
    pub fn candump(&self) -> String {
        let mut out = Vec::new();
        let _ = self.bus.trace().write_candump_with_errors(&mut out, "can0");
        String::from_utf8_lossy(&out).into_owned()
    }
}
