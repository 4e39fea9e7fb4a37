//! The peripheral space: CAN windows to the models (behind their clock gates), the rest
//! to the board profile.

use unicorn_engine::Unicorn;

use super::exceptions::halt;
use super::Board;
use crate::profile::Access;

pub(super) fn periph_read(uc: &mut Unicorn<'_, Board>, addr: u32, size: usize) -> u64 {
    let b = uc.get_data_mut();
    if let Some(i) = b
        .cans
        .iter()
        .position(|p| addr >= p.instance.base && addr < p.instance.base + p.instance.size)
    {
        let gate = b.cans[i].instance.gate;
        if !b.profile.gate_open(gate) {
            let g = b.profile.gate_name(gate);
            let n = b.cans[i].instance.name;
            let mut stop = false;
            b.gated(
                &mut stop,
                format!("{n} read with its clock gated ({g} = 0)"),
                addr,
            );
            if stop {
                let _ = uc.emu_stop();
            }
            return 0;
        }
        b.clock_can_engine(i);
        let off = (addr - b.cans[i].instance.base) as usize;
        let word = b.cans[i].model.read32(off & !3);
        b.refresh_can_lines();
        if b.note_join() {
            let _ = uc.emu_stop();
        }
        return u64::from(crate::profile::extract(word, addr, size));
    }
    let ctx = b.ctx();
    match b.profile.read(addr, size, ctx) {
        Access::Known(v) => u64::from(v),
        Access::Unknown { peripheral } => {
            b.note_unknown(addr, peripheral, "read");
            0
        }
        Access::Gated { peripheral, gate } => {
            let mut stop = false;
            b.gated(
                &mut stop,
                format!("{peripheral} read with its clock gated ({gate} = 0)"),
                addr,
            );
            if stop {
                let _ = uc.emu_stop();
            }
            0
        }
        Access::Unmapped => {
            b.bus_error("BusFault: read from unmapped peripheral space".into(), addr);
            b.stop_now();
            let _ = uc.emu_stop();
            0
        }
        Access::Reset(why) => {
            halt(uc, format!("chip reset: {why}"));
            0
        }
    }
}

pub(super) fn periph_write(uc: &mut Unicorn<'_, Board>, addr: u32, size: usize, value: u32) {
    let b = uc.get_data_mut();
    if let Some(i) = b
        .cans
        .iter()
        .position(|p| addr >= p.instance.base && addr < p.instance.base + p.instance.size)
    {
        let gate = b.cans[i].instance.gate;
        if !b.profile.gate_open(gate) {
            let g = b.profile.gate_name(gate);
            let n = b.cans[i].instance.name;
            let mut stop = false;
            b.gated(
                &mut stop,
                format!("{n} written with its clock gated ({g} = 0)"),
                addr,
            );
            if stop {
                let _ = uc.emu_stop();
            }
            return;
        }
        b.clock_can_engine(i);
        let off = (addr - b.cans[i].instance.base) as usize;
        let v = if size == 4 {
            value
        } else {
            let cur = b.cans[i].model.read32(off & !3);
            crate::profile::insert(cur, addr, size, value)
        };
        b.cans[i].model.write32(off & !3, v);
        b.refresh_can_lines();
        if b.note_join() {
            let _ = uc.emu_stop();
        }
        return;
    }
    let ctx = b.ctx();
    match b.profile.write(addr, size, value, ctx) {
        Access::Known(_) => {
            b.rebase();
        }
        Access::Unknown { peripheral } => b.note_unknown(addr, peripheral, "write"),
        Access::Gated { peripheral, gate } => {
            let mut stop = false;
            b.gated(
                &mut stop,
                format!("{peripheral} written with its clock gated ({gate} = 0)"),
                addr,
            );
            if stop {
                let _ = uc.emu_stop();
            }
        }
        Access::Unmapped => {
            b.bus_error("BusFault: write to unmapped peripheral space".into(), addr);
            b.stop_now();
            let _ = uc.emu_stop();
        }
        Access::Reset(why) => halt(uc, format!("chip reset: {why}")),
    }
}
