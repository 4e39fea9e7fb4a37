//! The private peripheral bus: NVIC, SCB, SysTick and DWT registers (ARMv7-M ARM B3.2,
//! B3.3, B3.4, C1.8), over the board's [`crate::nvic::Nvic`] state.

use unicorn_engine::{RegisterARM, Unicorn};

use super::exceptions::halt;
use super::{reg, Board};
use crate::nvic::exc;

#[derive(Debug, Default, Clone)]
pub(super) struct SysTick {
    pub(super) csr: u32,
    pub(super) rvr: u32,
    /// Cycle at which the counter next reaches 0 (when enabled).
    pub(super) wrap_at: u64,
    /// The value CVR holds while disabled.
    pub(super) cvr_stopped: u32,
    pub(super) countflag: bool,
}

/// Core peripheral registers kept as values.
#[derive(Debug, Default, Clone)]
pub(super) struct Scb {
    pub(super) vtor: u32,
    pub(super) scr: u32,
    pub(super) ccr: u32,
    pub(super) cfsr: u32,
    pub(super) hfsr: u32,
    pub(super) bfar: u32,
    pub(super) cpacr: u32,
    pub(super) demcr: u32,
    pub(super) dwt_ctrl: u32,
    /// CYCCNT = cycles - cyccnt_base while enabled.
    pub(super) cyccnt_base: u64,
    pub(super) cyccnt_frozen: u32,
    pub(super) fpccr: u32,
}

/// Reads of the private peripheral bus.
pub(super) fn ppb_read(uc: &mut Unicorn<'_, Board>, addr: u32, size: usize) -> u64 {
    let word = ppb_read_word(uc, addr & !3);
    u64::from(crate::profile::extract(word, addr, size))
}

pub(super) fn ppb_read_word(uc: &mut Unicorn<'_, Board>, addr: u32) -> u32 {
    let ipsr = reg(uc, RegisterARM::IPSR) & 0x1FF;
    let b = uc.get_data_mut();
    let cycles = b.cycles();
    match addr {
        0xE000_E004 => (b.nvic.irq_count().div_ceil(32)).saturating_sub(1), // ICTR
        0xE000_E010 => {
            b.systick_catch_up();
            let flag = std::mem::take(&mut b.systick.countflag);
            b.systick.csr | (u32::from(flag) << 16)
        }
        0xE000_E014 => b.systick.rvr,
        0xE000_E018 => {
            if b.systick_next().is_some() {
                b.systick_catch_up();
                let d = b.systick_divider();
                (b.systick.wrap_at.saturating_sub(cycles) / d) as u32 & 0xFF_FFFF
            } else {
                b.systick.cvr_stopped
            }
        }
        0xE000_E01C => 1 << 30, // CALIB: NOREF=0? SKEW set, no TENMS
        0xE000_E100..=0xE000_E13C => b.nvic.enabled_word((addr - 0xE000_E100) / 4),
        0xE000_E180..=0xE000_E1BC => b.nvic.enabled_word((addr - 0xE000_E180) / 4),
        0xE000_E200..=0xE000_E23C => b.nvic.pending_word((addr - 0xE000_E200) / 4),
        0xE000_E280..=0xE000_E2BC => b.nvic.pending_word((addr - 0xE000_E280) / 4),
        0xE000_E300..=0xE000_E33C => b.nvic.active_word((addr - 0xE000_E300) / 4),
        0xE000_E400..=0xE000_E5EC => {
            let irq = addr - 0xE000_E400;
            (0..4).fold(0, |v, i| {
                v | u32::from(b.nvic.priority_byte(16 + irq + i)) << (8 * i)
            })
        }
        0xE000_ED00 => {
            if b.profile.cpu_model() == unicorn_engine::ArmCpuModel::CORTEX_M7 as i32 {
                0x411F_C270
            } else {
                0x410F_C241
            }
        }
        0xE000_ED04 => {
            let pend = b.nvic.pending_highest().unwrap_or(0);
            let isrpending = (16..256).any(|e| b.nvic.is_pending(e));
            let mut v = ipsr | (pend << 12) | (u32::from(isrpending) << 22);
            if b.nvic.is_pending(exc::SYSTICK) {
                v |= 1 << 26;
            }
            if b.nvic.is_pending(exc::PENDSV) {
                v |= 1 << 28;
            }
            if b.depth <= 1 {
                v |= 1 << 11; // RETTOBASE
            }
            v
        }
        0xE000_ED08 => b.scb.vtor,
        0xE000_ED0C => 0xFA05_0000 | (u32::from(b.nvic.prigroup) << 8),
        0xE000_ED10 => b.scb.scr,
        0xE000_ED14 => b.scb.ccr,
        0xE000_ED18..=0xE000_ED20 => {
            let first = 4 + (addr - 0xE000_ED18);
            (0..4).fold(0, |v, i| {
                v | u32::from(b.nvic.priority_byte(first + i)) << (8 * i)
            })
        }
        0xE000_ED24 => {
            let f = b.nvic.fault_enabled;
            (u32::from(f[0]) << 16) | (u32::from(f[1]) << 17) | (u32::from(f[2]) << 18)
        }
        0xE000_ED28 => b.scb.cfsr,
        0xE000_ED2C => b.scb.hfsr,
        0xE000_ED38 => b.scb.bfar,
        0xE000_ED88 => b.scb.cpacr,
        0xE000_EDFC => b.scb.demcr,
        0xE000_1000 => b.scb.dwt_ctrl,
        0xE000_1004 => {
            if b.scb.dwt_ctrl & 1 != 0 && b.scb.demcr & (1 << 24) != 0 {
                (cycles - b.scb.cyccnt_base) as u32
            } else {
                b.scb.cyccnt_frozen
            }
        }
        0xE000_EF34 => b.scb.fpccr,
        0xE000_ED78..=0xE000_ED84 => 0, // CLIDR/CTR/CCSIDR/CSSELR (M7 caches: reported as none)
        _ => {
            b.note_unknown(addr, "PPB", "read");
            0
        }
    }
}

pub(super) fn ppb_write(uc: &mut Unicorn<'_, Board>, addr: u32, size: usize, value: u32) {
    let b = uc.get_data_mut();
    let word_addr = addr & !3;
    // Byte writes are natural for IPR/SHPR; other registers are word registers.
    if (0xE000_E400..=0xE000_E5EF).contains(&addr) || (0xE000_ED18..=0xE000_ED23).contains(&addr) {
        let first = if addr >= 0xE000_ED18 {
            4 + (addr - 0xE000_ED18)
        } else {
            16 + (addr - 0xE000_E400)
        };
        for i in 0..size as u32 {
            b.nvic
                .set_priority_byte(first + i, (value >> (8 * i)) as u8);
        }
        b.check_irq = true;
        return;
    }
    let cycles = b.cycles();
    match word_addr {
        0xE000_E010 => {
            b.systick_catch_up();
            let was = b.systick.csr & 1 != 0;
            b.systick.csr = value & 0x7;
            if !was && value & 1 != 0 {
                let d = b.systick_divider();
                let cvr = u64::from(b.systick.cvr_stopped);
                let first = if cvr == 0 {
                    u64::from(b.systick.rvr) + 1
                } else {
                    cvr
                };
                b.systick.wrap_at = cycles + first * d;
            } else if was && value & 1 == 0 {
                let d = b.systick_divider();
                b.systick.cvr_stopped = (b.systick.wrap_at.saturating_sub(cycles) / d) as u32;
            }
            b.stop_now();
        }
        0xE000_E014 => b.systick.rvr = value & 0xFF_FFFF,
        0xE000_E018 => {
            // Any write clears CVR and COUNTFLAG; the counter reloads at the next clock.
            b.systick.countflag = false;
            b.systick.cvr_stopped = 0;
            if b.systick.csr & 1 != 0 {
                let d = b.systick_divider();
                b.systick.wrap_at = cycles + (u64::from(b.systick.rvr) + 1) * d;
                b.stop_now();
            }
        }
        0xE000_E100..=0xE000_E13C | 0xE000_E180..=0xE000_E1BC => {
            let set = word_addr < 0xE000_E180;
            let n = (word_addr & 0x7F) / 4;
            // The controllers (index bits) with a line in this write.
            let mut controllers = 0u32;
            for bit in 0..32 {
                if value & (1 << bit) != 0 {
                    b.nvic.set_irq_enabled(n * 32 + bit, set);
                    for (i, p) in b.cans.iter().enumerate().take(32) {
                        if p.instance.irqs.iter().any(|(_, irq)| *irq == n * 32 + bit) {
                            controllers |= 1 << i;
                        }
                    }
                }
            }
            b.check_irq = true;
            if set && controllers != 0 {
                // `--stack`: the configuration mark (crate::stack).
                crate::stack::mark_configuration(uc, controllers);
            }
        }
        0xE000_E200..=0xE000_E23C | 0xE000_E280..=0xE000_E2BC => {
            let set = word_addr < 0xE000_E280;
            let n = (word_addr & 0x7F) / 4;
            for bit in 0..32 {
                if value & (1 << bit) != 0 {
                    b.nvic.set_pending(16 + n * 32 + bit, set);
                }
            }
            b.check_irq = true;
        }
        0xE000_EF00 => {
            b.nvic.set_pending(16 + (value & 0x1FF), true);
            b.check_irq = true;
        }
        0xE000_ED04 => {
            if value & (1 << 28) != 0 {
                b.nvic.set_pending(exc::PENDSV, true);
            }
            if value & (1 << 27) != 0 {
                b.nvic.set_pending(exc::PENDSV, false);
            }
            if value & (1 << 26) != 0 {
                b.nvic.set_pending(exc::SYSTICK, true);
            }
            if value & (1 << 25) != 0 {
                b.nvic.set_pending(exc::SYSTICK, false);
            }
            if value & (1 << 31) != 0 {
                b.nvic.set_pending(exc::NMI, true);
            }
            b.check_irq = true;
        }
        0xE000_ED08 => b.scb.vtor = value & 0xFFFF_FF80,
        0xE000_ED0C => {
            if value >> 16 == 0x05FA {
                b.nvic.prigroup = ((value >> 8) & 7) as u8;
                if value & (1 << 2) != 0 {
                    halt(uc, "reset requested (AIRCR.SYSRESETREQ)".into());
                }
            } else {
                b.findings.push(format!(
                    "AIRCR written without VECTKEY (0x{value:08X}): ignored"
                ));
            }
        }
        0xE000_ED10 => b.scb.scr = value & 0x16,
        0xE000_ED14 => b.scb.ccr = value | (1 << 9),
        0xE000_ED24 => {
            b.nvic.fault_enabled = [
                value & (1 << 16) != 0,
                value & (1 << 17) != 0,
                value & (1 << 18) != 0,
            ];
        }
        0xE000_ED28 => b.scb.cfsr &= !value, // write-1-to-clear
        0xE000_ED2C => b.scb.hfsr &= !value,
        0xE000_ED38 => b.scb.bfar = value,
        0xE000_ED88 => b.scb.cpacr = value & (0xF << 20),
        0xE000_EDFC => b.scb.demcr = value,
        0xE000_1000 => {
            let was = b.scb.dwt_ctrl & 1 != 0;
            b.scb.dwt_ctrl = value;
            if !was && value & 1 != 0 {
                b.scb.cyccnt_base = cycles - u64::from(b.scb.cyccnt_frozen);
            } else if was && value & 1 == 0 {
                b.scb.cyccnt_frozen = (cycles - b.scb.cyccnt_base) as u32;
            }
        }
        0xE000_1004 => {
            b.scb.cyccnt_frozen = value;
            b.scb.cyccnt_base = cycles - u64::from(value);
        }
        0xE000_EF34 => b.scb.fpccr = value,
        // M7 cache maintenance (ICIALLU, DCISW, ...): no caches modelled.
        0xE000_EF50..=0xE000_EF78 | 0xE000_ED84 => {}
        _ => b.note_unknown(addr, "PPB", "write"),
    }
}
