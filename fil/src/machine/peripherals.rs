//! The peripheral space: CAN windows to the models (behind their clock gates), the rest
//! to the board profile.

use unicorn_engine::Unicorn;

use super::exceptions::halt;
use super::Board;
use crate::profile::Access;

/// The peripheral bit-band alias (ARMv7-M ARM §B3.1; on the profiles that have it): one
/// word at `0x4200_0000 + 32 × byte + 4 × bit` per bit of the byte at `0x4000_0000 +
/// byte`, for the first MiB of the peripheral space.
const BIT_BAND_ALIAS: std::ops::Range<u32> = 0x4200_0000..0x4400_0000;

/// The word address and bit number a bit-band alias address stands for.
fn bit_band_target(addr: u32) -> (u32, u32) {
    let off = addr - BIT_BAND_ALIAS.start;
    let byte = 0x4000_0000 + off / 32;
    let bit = (off / 4) % 8;
    (byte & !3, (byte & 3) * 8 + bit)
}

pub(super) fn periph_read(uc: &mut Unicorn<'_, Board>, addr: u32, size: usize) -> u64 {
    if BIT_BAND_ALIAS.contains(&addr) && uc.get_data().profile.peripheral_bit_band() {
        let (word, bit) = bit_band_target(addr);
        let v = periph_read(uc, word, 4) as u32;
        return u64::from((v >> bit) & 1);
    }
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
    if BIT_BAND_ALIAS.contains(&addr) && uc.get_data().profile.peripheral_bit_band() {
        // A read-modify-write of the target word (the bus does it as one locked transfer).
        let (word, bit) = bit_band_target(addr);
        let v = periph_read(uc, word, 4) as u32;
        let v = if value & 1 != 0 {
            v | (1 << bit)
        } else {
            v & !(1 << bit)
        };
        periph_write(uc, word, 4, v);
        return;
    }
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

#[cfg(test)]
mod tests {
    use super::bit_band_target;

    #[test]
    fn bit_band_aliases_map_to_their_bit() {
        // RCC_APB1ENR (0x4002_101C) bit 25 on the F1; RCC_CR (0x4002_3800) bit 16 on the F4.
        assert_eq!(
            bit_band_target(0x4200_0000 + 0x2_101C * 32 + 25 * 4),
            (0x4002_101C, 25)
        );
        assert_eq!(
            bit_band_target(0x4200_0000 + 0x2_3800 * 32 + 16 * 4),
            (0x4002_3800, 16)
        );
        assert_eq!(bit_band_target(0x4242_0000), (0x4002_1000, 0));
    }
}
