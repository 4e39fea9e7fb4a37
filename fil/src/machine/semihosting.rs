//! ARM semihosting (`BKPT 0xAB`): console output and exit; any other breakpoint without
//! a debugger is a fault.

use unicorn_engine::{RegisterARM, Unicorn};

use super::exceptions::{halt, take_fault};
use super::{read_u32, reg, set_reg, Board};
use crate::nvic::exc;

pub(super) fn semihosting_or_fault(uc: &mut Unicorn<'_, Board>, pc: u32) {
    let bkpt = uc
        .mem_read_as_vec(u64::from(pc), 2)
        .ok()
        .map(|b| u16::from_le_bytes([b[0], b[1]]));
    if bkpt != Some(0xBEAB) {
        // A breakpoint with no debugger attached escalates to HardFault (C1.7).
        take_fault(
            uc,
            "BKPT without debugger".into(),
            exc::USAGE_FAULT,
            pc,
            None,
        );
        return;
    }
    let op = reg(uc, RegisterARM::R0);
    let arg = reg(uc, RegisterARM::R1);
    let mut result = 0u32;
    match op {
        0x03 => {
            if let Ok(b) = uc.mem_read_as_vec(u64::from(arg), 1) {
                uc.get_data_mut().console.push(b[0] as char);
            }
        }
        0x04 => {
            let mut s = Vec::new();
            let mut a = arg;
            while let Ok(b) = uc.mem_read_as_vec(u64::from(a), 1) {
                if b[0] == 0 || s.len() > 4096 {
                    break;
                }
                s.push(b[0]);
                a += 1;
            }
            uc.get_data_mut()
                .console
                .push_str(&String::from_utf8_lossy(&s));
        }
        0x05 => {
            // SYS_WRITE: [handle, buffer, length]; returns bytes not written.
            let words: Vec<u32> = (0..3).filter_map(|i| read_u32(uc, arg + 4 * i)).collect();
            if let [_, buf, len] = words[..] {
                if let Ok(b) = uc.mem_read_as_vec(u64::from(buf), len as usize) {
                    uc.get_data_mut()
                        .console
                        .push_str(&String::from_utf8_lossy(&b));
                }
            }
        }
        0x01 => result = 1, // SYS_OPEN: a handle (":tt" only)
        0x18 | 0x20 => {
            uc.get_data_mut().exited = Some(arg);
            halt(uc, "semihosting exit".into());
        }
        _ => result = u32::MAX,
    }
    set_reg(uc, RegisterARM::R0, result);
    set_reg(uc, RegisterARM::PC, (pc + 2) | 1);
}
