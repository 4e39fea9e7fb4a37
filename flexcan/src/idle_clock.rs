//! Register access to the model that lets time pass while the driver waits (feature
//! `model`).
//!
//! On a Teensy, time runs while the firmware spins on a register: a mode acknowledge
//! (`MCR`) or the synchronisation to the bus after freeze (`ESR1.SYNCH`, 11 recessive
//! bits). The model's time only moves when a bus says so: [`IdleClocked`] is that bus for
//! a module the driver is bringing up on its own — each back-to-back read of `MCR` or
//! `ESR1` is one bit time of idle bus for the module. A single read (an interrupt
//! handler) does not move time. On a shared simulated bus whose time must pass for every
//! node, wrap the registers so that they run that bus instead (the host harness's
//! `Clocked` does).

extern crate std;

use core::cell::Cell;
use core::ops::Deref;

use twocan_core::Registers;
use twocan_sim::BusNode;

use crate::model::FlexCanModel;
use crate::regs::{ESR1, MCR};

/// A [`FlexCanModel`] handle whose polled registers let idle bus time pass (see the
/// module documentation). Derefs to the model.
#[derive(Debug, Clone)]
pub struct IdleClocked {
    model: FlexCanModel,
    /// Bus time this wrapper let pass.
    now: Cell<u64>,
    /// The polled register read last, if the last access was such a read.
    spinning: Cell<Option<usize>>,
}

impl IdleClocked {
    /// Wraps a handle on the module.
    pub fn new(model: FlexCanModel) -> Self {
        IdleClocked {
            model,
            now: Cell::new(0),
            spinning: Cell::new(None),
        }
    }

    /// The wrapped model handle.
    pub fn model(&self) -> &FlexCanModel {
        &self.model
    }
}

impl Deref for IdleClocked {
    type Target = FlexCanModel;
    fn deref(&self) -> &FlexCanModel {
        &self.model
    }
}

impl Registers for IdleClocked {
    fn read32(&self, offset: usize) -> u32 {
        if offset == MCR || offset == ESR1 {
            if self.spinning.replace(Some(offset)) == Some(offset) {
                let now = self.now.get().saturating_add(1);
                self.now.set(now);
                self.model.clone().advance(1, true, now);
            }
        } else {
            self.spinning.set(None);
        }
        self.model.read32(offset)
    }

    fn write32(&self, offset: usize, value: u32) {
        self.spinning.set(None);
        self.model.write32(offset, value);
    }
}
