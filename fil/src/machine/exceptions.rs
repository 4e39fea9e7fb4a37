//! Exception entry, return and faults (ARMv7-M ARM B1.5.6, B1.5.8), and the stuck-line
//! detector.

use unicorn_engine::{RegisterARM, Unicorn};

use super::{read_u32, reg, set_reg, write_u32, Board, S_REGS};
use crate::nvic::exc;

/// Consecutive entries of one interrupt with no thread-mode progress that count as a
/// stuck interrupt line.
pub const STUCK_ENTRIES: u32 = 10_000;

/// A fault the firmware ran into.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Fault {
    /// What happened.
    pub kind: String,
    /// The program counter of the faulting instruction.
    pub pc: u32,
    /// The address accessed, if any.
    pub address: Option<u32>,
    /// The exception it was taken as (3 = HardFault, 5 = BusFault, ...), or `None` when
    /// the board stopped (lockup) or the chip raises no exception for it.
    pub taken_as: Option<u32>,
    /// `true` when the chip raises no exception for it (an STM32 peripheral without
    /// clock reads as 0 and ignores writes): reported all the same.
    pub silent: bool,
    /// Core time of the fault (ns).
    pub at_ns: u64,
}

impl std::fmt::Display for Fault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} at PC 0x{:08X}", self.kind, self.pc)?;
        if let Some(a) = self.address {
            write!(f, ", address 0x{a:08X}")?;
        }
        match self.taken_as {
            Some(exc::HARD_FAULT) => write!(f, " -> HardFault handler")?,
            Some(e) => write!(f, " -> exception {e} handler")?,
            None if self.silent => write!(
                f,
                " -> no exception on this chip (read as 0, write ignored)"
            )?,
            None => write!(f, " -> board stopped")?,
        }
        write!(f, " (t = {} us)", self.at_ns / 1000)
    }
}

/// A stuck interrupt line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StuckIrq {
    /// Exception number.
    pub exception: u32,
    /// Core time (ns) when it was detected.
    pub at_ns: u64,
}

/// Simulated time without thread-mode progress (no instruction executed in thread mode,
/// and the core not asleep in thread mode) after which a board is in a livelock, and the
/// longest one activation of an exception handler may last. 20 ms: thousands of frame
/// times at 500 kbit/s, twenty SysTick periods at 1 kHz; no example handler comes near
/// it.
pub const LIVELOCK_PS: u128 = 20_000_000_000;

/// Why a board made no progress (see [`LIVELOCK_PS`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LivelockKind {
    /// Thread mode ran no instruction (exceptions kept preempting it, whichever they
    /// were: a line whose cause is never cleared, interleaved with SysTick or not).
    NoThreadProgress,
    /// An activation of this exception handler did not return.
    HandlerNeverReturns {
        /// Exception number.
        exception: u32,
    },
}

/// A livelock: what the board did over the window without progress.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Livelock {
    /// What was found.
    pub kind: LivelockKind,
    /// Core time (ns) of the last progress (or of the handler's entry).
    pub since_ns: u64,
    /// Core time (ns) when it was detected.
    pub at_ns: u64,
    /// Exceptions taken over the window, by exception number.
    pub taken: Vec<(u32, u64)>,
}

impl std::fmt::Display for Livelock {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.kind {
            LivelockKind::NoThreadProgress => write!(f, "no thread-mode progress")?,
            LivelockKind::HandlerNeverReturns { exception } => write!(
                f,
                "the {} handler never returned",
                exception_name(*exception)
            )?,
        }
        write!(
            f,
            " from t = {} us to t = {} us; exceptions taken meanwhile: ",
            self.since_ns / 1000,
            self.at_ns / 1000
        )?;
        if self.taken.is_empty() {
            return write!(f, "none");
        }
        let list: Vec<String> = self
            .taken
            .iter()
            .map(|(e, n)| format!("{} x{n}", exception_name(*e)))
            .collect();
        write!(f, "{}", list.join(", "))
    }
}

/// The execution priority now.
pub(super) fn execution_priority(uc: &Unicorn<'_, Board>) -> i32 {
    let primask = reg(uc, RegisterARM::PRIMASK) & 1 != 0;
    let faultmask = reg(uc, RegisterARM::FAULTMASK) & 1 != 0;
    let basepri = reg(uc, RegisterARM::BASEPRI) as u8;
    uc.get_data()
        .nvic
        .execution_priority(primask, faultmask, basepri)
}

/// Exception entry (B1.5.6) with `ret` as the stacked return address.
pub(super) fn enter(uc: &mut Unicorn<'_, Board>, e: u32, ret: u32) -> Result<(), String> {
    let control = reg(uc, RegisterARM::CONTROL);
    let ipsr = reg(uc, RegisterARM::IPSR) & 0x1FF;
    let thread = ipsr == 0;
    let psp = thread && control & 2 != 0;
    let fpca = control & 4 != 0;
    let sp = reg(uc, RegisterARM::SP);
    let size = if fpca { 0x68 } else { 0x20 };
    let align = sp & 4 != 0;
    let frame = (sp - size) & !4;
    let xpsr = reg(uc, RegisterARM::XPSR) | (u32::from(align) << 9);
    let regs = [
        reg(uc, RegisterARM::R0),
        reg(uc, RegisterARM::R1),
        reg(uc, RegisterARM::R2),
        reg(uc, RegisterARM::R3),
        reg(uc, RegisterARM::R12),
        reg(uc, RegisterARM::LR),
        ret & !1,
        xpsr,
    ];
    for (i, v) in regs.iter().enumerate() {
        if !write_u32(uc, frame + 4 * i as u32, *v) {
            return Err(format!("stacking fault: SP 0x{sp:08X}"));
        }
    }
    if fpca {
        for i in 0..16u32 {
            let s = reg(uc, S_REGS[i as usize]);
            write_u32(uc, frame + 0x20 + 4 * i, s);
        }
        let fpscr = reg(uc, RegisterARM::FPSCR);
        write_u32(uc, frame + 0x60, fpscr);
    }
    set_reg(uc, RegisterARM::SP, frame);
    let mut exc_return = if !thread {
        0xFFFF_FFF1
    } else if psp {
        0xFFFF_FFFD
    } else {
        0xFFFF_FFF9
    };
    if fpca {
        exc_return &= !0x10;
    }
    if psp || fpca {
        set_reg(uc, RegisterARM::CONTROL, control & !(2 | 4));
    }
    set_reg(uc, RegisterARM::LR, exc_return);
    set_reg(uc, RegisterARM::IPSR, e);
    // EPSR: Thumb, no IT state.
    set_reg(uc, RegisterARM::EPSR, 1 << 24);
    let vtor = uc.get_data().scb.vtor;
    let handler = read_u32(uc, vtor + 4 * e).ok_or_else(|| format!("vector {e} unreadable"))?;
    set_reg(uc, RegisterARM::PC, handler | 1);
    let b = uc.get_data_mut();
    b.nvic.activate(e);
    b.depth += 1;
    *b.taken.entry(e).or_insert(0) += 1;
    let now = b.time_ps();
    b.active_since.insert(e, now);
    // Stuck-line detection: the same exception again and again, no thread progress.
    let (last, count, thread_at) = b.stuck_run;
    if last == e && b.thread_instructions == thread_at {
        b.stuck_run.1 = count + 1;
        if count + 1 == STUCK_ENTRIES {
            let at_ns = b.time_ns();
            b.stuck.push(StuckIrq {
                exception: e,
                at_ns,
            });
        }
    } else {
        b.stuck_run = (e, 1, b.thread_instructions);
    }
    Ok(())
}

/// Takes the most urgent pending exception if it can preempt now.
pub(super) fn take_pending(uc: &mut Unicorn<'_, Board>, ret: u32) -> bool {
    let prio = execution_priority(uc);
    let Some(e) = uc.get_data().nvic.next_to_take(prio) else {
        return false;
    };
    if let Err(what) = enter(uc, e, ret) {
        halt(uc, what);
        return false;
    }
    true
}

pub(super) fn halt(uc: &mut Unicorn<'_, Board>, why: String) {
    let b = uc.get_data_mut();
    if b.halted.is_none() {
        b.halted = Some(why);
    }
    b.stop_now();
    let _ = uc.emu_stop();
}

/// Exception return (B1.5.8), from Unicorn's exception-exit interrupt.
pub(super) fn exception_return(uc: &mut Unicorn<'_, Board>) {
    let pc = reg(uc, RegisterARM::PC);
    let exc_return = pc | 0xF000_0000 | 1;
    let e = reg(uc, RegisterARM::IPSR) & 0x1FF;
    {
        let b = uc.get_data_mut();
        b.nvic.deactivate(e);
        b.active_since.remove(&e);
        b.depth = b.depth.saturating_sub(1);
        b.check_irq = true;
        // ARMv7-M B1.5.18: an exception return sets the event register.
        b.event = true;
    }
    let to_psp = exc_return & 0xF == 0xD;
    let fp = exc_return & 0x10 == 0;
    let frame = if to_psp {
        reg(uc, RegisterARM::PSP)
    } else {
        reg(uc, RegisterARM::MSP)
    };
    let mut w = [0u32; 8];
    for (i, v) in w.iter_mut().enumerate() {
        *v = read_u32(uc, frame + 4 * i as u32).unwrap_or(0);
    }
    let xpsr = w[7];
    let mut size = if fp { 0x68 } else { 0x20 };
    if xpsr & (1 << 9) != 0 {
        size += 4;
    }
    if fp {
        for i in 0..16u32 {
            let s = read_u32(uc, frame + 0x20 + 4 * i).unwrap_or(0);
            set_reg(uc, S_REGS[i as usize], s);
        }
        let fpscr = read_u32(uc, frame + 0x60).unwrap_or(0);
        set_reg(uc, RegisterARM::FPSCR, fpscr);
    }
    let regs = [
        RegisterARM::R0,
        RegisterARM::R1,
        RegisterARM::R2,
        RegisterARM::R3,
        RegisterARM::R12,
        RegisterARM::LR,
    ];
    for (r, v) in regs.iter().zip(w) {
        set_reg(uc, *r, v);
    }
    let to_thread = exc_return & 0xF != 0x1;
    let ipsr = if to_thread { 0 } else { xpsr & 0x1FF };
    // Restore the SP of the frame, then mode and stack selection.
    if to_psp {
        set_reg(uc, RegisterARM::PSP, frame + size);
    } else {
        set_reg(uc, RegisterARM::SP, frame + size);
    }
    set_reg(uc, RegisterARM::XPSR, (xpsr & !0x1FF & !(1 << 9)) | ipsr);
    set_reg(uc, RegisterARM::IPSR, ipsr);
    let control = reg(uc, RegisterARM::CONTROL);
    let mut new_control = control;
    if to_psp {
        new_control |= 2;
    }
    if fp {
        new_control |= 4;
    } else {
        new_control &= !4;
    }
    if new_control != control {
        set_reg(uc, RegisterARM::CONTROL, new_control);
    }
    let ret = w[6];
    set_reg(uc, RegisterARM::PC, ret | 1);
    uc.get_data_mut().refresh_can_lines();
    take_pending(uc, ret);
}

/// A fault of kind `fault` (BusFault or UsageFault) at `pc`.
pub(super) fn take_fault(
    uc: &mut Unicorn<'_, Board>,
    kind: String,
    fault: u32,
    pc: u32,
    addr: Option<u32>,
) {
    let prio = execution_priority(uc);
    let target = uc.get_data().nvic.fault_target(fault, prio);
    let at_ns = uc.get_data().time_ns();
    if target == exc::HARD_FAULT && prio <= -1 {
        let b = uc.get_data_mut();
        b.faults.push(Fault {
            kind: format!("{kind} in the HardFault handler (lockup)"),
            pc,
            address: addr,
            taken_as: None,
            silent: false,
            at_ns,
        });
        halt(uc, "lockup".into());
        return;
    }
    {
        let b = uc.get_data_mut();
        if fault == exc::BUS_FAULT {
            // CFSR.BFSR: PRECISERR (bit 9) with BFARVALID (bit 15), or IBUSERR (bit 8).
            match addr {
                Some(a) if a != pc => {
                    b.scb.cfsr |= (1 << 9) | (1 << 15);
                    b.scb.bfar = a;
                }
                _ => b.scb.cfsr |= 1 << 8,
            }
        } else {
            b.scb.cfsr |= 1 << 16; // UNDEFINSTR
        }
        if target == exc::HARD_FAULT {
            b.scb.hfsr |= 1 << 30; // FORCED
        }
        b.faults.push(Fault {
            kind,
            pc,
            address: addr,
            taken_as: Some(target),
            silent: false,
            at_ns,
        });
    }
    if let Err(what) = enter(uc, target, pc) {
        halt(uc, what);
    }
}

/// Names of the exceptions in reports.
pub fn exception_name(e: u32) -> String {
    match e {
        exc::NMI => "NMI".into(),
        exc::HARD_FAULT => "HardFault".into(),
        exc::MEM_MANAGE => "MemManage".into(),
        exc::BUS_FAULT => "BusFault".into(),
        exc::USAGE_FAULT => "UsageFault".into(),
        exc::SVCALL => "SVCall".into(),
        exc::PENDSV => "PendSV".into(),
        exc::SYSTICK => "SysTick".into(),
        e if e >= exc::IRQ0 => format!("IRQ {}", e - exc::IRQ0),
        e => format!("exception {e}"),
    }
}
