//! One board: the Unicorn CPU running an ELF, the core peripherals Unicorn lacks (NVIC,
//! SCB, SysTick, DWT), exception entry and return, faults, WFI, and the routing of the
//! peripheral space to the board profile and the CAN models.
//!
//! ARMv7-M Architecture Reference Manual (DDI 0403E) rules implemented here:
//! - B1.5.5 reset: SP from vector 0, PC from vector 1 at VTOR (the boot address).
//! - B1.5.6 exception entry: an 8-word frame (R0–R3, R12, LR, return address, xPSR), or
//!   26 words with the FP context when CONTROL.FPCA is set (stacked eagerly, not lazily);
//!   a 4-byte pad when SP was not 8-byte aligned (CCR.STKALIGN = 1), recorded in bit 9
//!   of the stacked xPSR; LR = EXC_RETURN; IPSR = exception number; handler mode on MSP.
//! - B1.5.8 exception return: Unicorn raises its "exception exit" interrupt when the
//!   handler branches to an EXC_RETURN value; the harness unstacks there, and takes a
//!   pending exception at once when it can preempt the context returned to
//!   (tail-chaining and late arrival have the same observable result).
//! - B1.5.8 faults: a bus error on a data access or fetch is a BusFault, escalated to
//!   HardFault when BusFault is disabled (SHCSR.BUSFAULTENA = 0, the reset value) or
//!   cannot preempt; an undefined instruction is a UsageFault (same escalation); a fault
//!   in the HardFault handler is a lockup (the board stops).
//! - B3.3 SysTick (CSR, RVR, CVR, CALIB, COUNTFLAG), B3.4 NVIC (ISER, ICER, ISPR, ICPR,
//!   IABR, IPR, STIR), B3.2 SCB (CPUID, ICSR, VTOR, AIRCR, SCR, CCR, SHPR1–3, SHCSR,
//!   CFSR, HFSR, BFAR, CPACR), C1.8 DWT CYCCNT with DEMCR.TRCENA.
//! - B1.5.19 WFI: the core sleeps until an exception would preempt if PRIMASK were 0;
//!   the harness skips the idle time to the next event instead of executing it.
//!
//! Time: one instruction is one core clock cycle (the Cortex-M4/M7 average is close to
//! it for this code; documented in docs/fil.md).

use std::collections::{BTreeMap, BTreeSet};

use unicorn_engine::unicorn_const::{Arch, HookType, MemType, Mode, Prot};
use unicorn_engine::{RegisterARM, Unicorn};

use crate::can::{self, Port};
use crate::elf::Image;
use crate::nvic::{exc, Nvic, THREAD_PRIORITY};
use crate::profile::{Access, Ctx, Profile};

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

#[derive(Debug, Default, Clone)]
struct SysTick {
    csr: u32,
    rvr: u32,
    /// Cycle at which the counter next reaches 0 (when enabled).
    wrap_at: u64,
    /// The value CVR holds while disabled.
    cvr_stopped: u32,
    countflag: bool,
}

/// Core peripheral registers kept as values.
#[derive(Debug, Default, Clone)]
struct Scb {
    vtor: u32,
    scr: u32,
    ccr: u32,
    cfsr: u32,
    hfsr: u32,
    bfar: u32,
    cpacr: u32,
    demcr: u32,
    dwt_ctrl: u32,
    /// CYCCNT = cycles - cyccnt_base while enabled.
    cyccnt_base: u64,
    cyccnt_frozen: u32,
    fpccr: u32,
}

/// Everything the Unicorn hooks reach.
pub struct Board {
    /// Name in reports (board, or board#n when the same board appears twice).
    pub name: String,
    /// The chip's rules.
    pub profile: Box<dyn Profile>,
    /// The CAN controllers.
    pub cans: Vec<Port>,
    /// The exception state.
    pub nvic: Nvic,
    scb: Scb,
    systick: SysTick,
    /// Instructions executed.
    pub instructions: u64,
    /// Cycles spent asleep (WFI).
    pub idle_cycles: u64,
    /// Time base: picoseconds at `base_cycles`, and the core clock since.
    base_ps: u128,
    base_cycles: u64,
    hz: u64,
    /// The instruction count at which the code hook stops the CPU.
    stop_at: u64,
    /// Address of the instruction being executed.
    pc: u32,
    /// A bus error found by an MMIO callback, to be taken once the CPU stopped.
    pending_fault: Option<(String, u32, u32)>,
    /// Set when a WFI was reached.
    wfi: bool,
    /// Sleeping in WFI.
    pub sleeping: bool,
    /// Stopped for good (lockup, reset, unsupported).
    pub halted: Option<String>,
    /// Handler nesting depth the harness entered.
    depth: u32,
    /// Instructions executed in thread mode.
    thread_instructions: u64,
    /// (exception, consecutive entries, thread instructions at the first of them).
    stuck_run: (u32, u32, u64),
    /// Exceptions taken, by exception number.
    pub taken: BTreeMap<u32, u64>,
    /// Faults.
    pub faults: Vec<Fault>,
    /// Stuck interrupt lines.
    pub stuck: Vec<StuckIrq>,
    /// Accesses to registers the profile does not know: (address, first PC, read/write).
    pub unknown: BTreeMap<u32, (u32, &'static str, &'static str)>,
    /// Findings of the register rules.
    pub findings: Vec<String>,
    /// Semihosting console output.
    pub console: String,
    /// Exceptions whose next entry should be checked (something changed).
    check_irq: bool,
    /// Stacked EXC_RETURN values of the exceptions entered (innermost last).
    exc_stack: Vec<u32>,
    /// Semihosting exit requested.
    pub exited: Option<u32>,
}

const S_REGS: [RegisterARM; 16] = [
    RegisterARM::S0,
    RegisterARM::S1,
    RegisterARM::S2,
    RegisterARM::S3,
    RegisterARM::S4,
    RegisterARM::S5,
    RegisterARM::S6,
    RegisterARM::S7,
    RegisterARM::S8,
    RegisterARM::S9,
    RegisterARM::S10,
    RegisterARM::S11,
    RegisterARM::S12,
    RegisterARM::S13,
    RegisterARM::S14,
    RegisterARM::S15,
];

const PERIPH_BASE: u64 = 0x4000_0000;
const PERIPH_SIZE: u64 = 0x2000_0000;
const PPB_BASE: u64 = 0xE000_0000;
const PPB_SIZE: u64 = 0x0010_0000;

/// An emulated board running one firmware.
pub struct Machine<'a> {
    /// The CPU with the board state as its data.
    pub uc: Unicorn<'a, Board>,
    /// The firmware.
    pub image: Image,
}

impl Board {
    /// Address of the last instruction executed.
    pub fn last_pc(&self) -> u32 {
        self.pc
    }

    /// Cycles since reset (executed plus slept).
    pub fn cycles(&self) -> u64 {
        self.instructions + self.idle_cycles
    }

    /// Core time since reset (ps).
    pub fn time_ps(&self) -> u128 {
        self.base_ps
            + u128::from(self.cycles() - self.base_cycles) * 1_000_000_000_000 / u128::from(self.hz)
    }

    /// Core time since reset (ns).
    pub fn time_ns(&self) -> u64 {
        (self.time_ps() / 1000) as u64
    }

    /// Re-bases the time line when the core clock may have changed.
    fn rebase(&mut self) {
        let hz = self.profile.core_hz().max(1);
        if hz != self.hz {
            self.base_ps = self.time_ps();
            self.base_cycles = self.cycles();
            self.hz = hz;
        }
    }

    /// Cycles from now until `t_ps` at the current clock (rounded up).
    fn cycles_until(&self, t_ps: u128) -> u64 {
        let now = self.time_ps();
        if t_ps <= now {
            return 0;
        }
        ((t_ps - now) * u128::from(self.hz)).div_ceil(1_000_000_000_000) as u64
    }

    fn ctx(&self) -> Ctx {
        Ctx {
            cycles: self.cycles(),
        }
    }

    /// The next cycle at which SysTick reaches zero, if counting.
    fn systick_next(&self) -> Option<u64> {
        (self.systick.csr & 1 != 0 && self.systick.rvr != 0).then_some(self.systick.wrap_at)
    }

    fn systick_divider(&self) -> u64 {
        if self.systick.csr & 4 != 0 {
            1
        } else {
            self.profile.systick_external_divider().unwrap_or(1)
        }
    }

    /// Processes SysTick wraps up to the current cycle.
    fn systick_catch_up(&mut self) {
        let now = self.cycles();
        while let Some(at) = self.systick_next() {
            if at > now {
                break;
            }
            self.systick.countflag = true;
            self.systick.wrap_at = at + (u64::from(self.systick.rvr) + 1) * self.systick_divider();
            if self.systick.csr & 2 != 0 {
                self.nvic.set_pending(exc::SYSTICK, true);
                self.check_irq = true;
            }
        }
    }

    /// Updates the NVIC levels from the CAN models' lines.
    pub fn refresh_can_lines(&mut self) {
        for port in &self.cans {
            for ((_, irq), level) in port.instance.irqs.iter().zip(port.model.lines()) {
                if self.nvic.level(*irq) != level {
                    self.nvic.set_level(*irq, level);
                    self.check_irq = true;
                }
            }
        }
    }

    fn note_unknown(&mut self, addr: u32, peripheral: &'static str, dir: &'static str) {
        let pc = self.pc;
        self.unknown.entry(addr).or_insert((pc, peripheral, dir));
    }

    fn bus_error(&mut self, what: String, addr: u32) {
        if self.pending_fault.is_none() {
            self.pending_fault = Some((what, self.pc, addr));
        }
    }

    /// An access the chip answers without an exception but that firmware must not make
    /// (a peripheral whose clock is off, on a chip where that reads as 0).
    fn silent_fault(&mut self, kind: String, addr: u32) {
        let at_ns = self.time_ns();
        self.faults.push(Fault {
            kind,
            pc: self.pc,
            address: Some(addr),
            taken_as: None,
            silent: true,
            at_ns,
        });
    }

    /// A gated access: a bus error where the chip gives one, else recorded only.
    fn gated(&mut self, uc_stop: &mut bool, what: String, addr: u32) {
        if self.profile.gated_access_is_bus_error() {
            self.bus_error(format!("BusFault: {what}"), addr);
            self.stop_now();
            *uc_stop = true;
        } else {
            self.silent_fault(format!("clock-gated access: {what}"), addr);
        }
    }

    fn stop_now(&mut self) {
        self.stop_at = self.instructions;
    }
}

fn reg(uc: &Unicorn<'_, Board>, r: RegisterARM) -> u32 {
    uc.reg_read(r).unwrap_or(0) as u32
}

fn set_reg(uc: &mut Unicorn<'_, Board>, r: RegisterARM, v: u32) {
    let _ = uc.reg_write(r, u64::from(v));
}

fn read_u32(uc: &Unicorn<'_, Board>, addr: u32) -> Option<u32> {
    let mut b = [0u8; 4];
    uc.mem_read(u64::from(addr), &mut b).ok()?;
    Some(u32::from_le_bytes(b))
}

fn write_u32(uc: &mut Unicorn<'_, Board>, addr: u32, v: u32) -> bool {
    uc.mem_write(u64::from(addr), &v.to_le_bytes()).is_ok()
}

/// The execution priority now.
fn execution_priority(uc: &Unicorn<'_, Board>) -> i32 {
    let primask = reg(uc, RegisterARM::PRIMASK) & 1 != 0;
    let faultmask = reg(uc, RegisterARM::FAULTMASK) & 1 != 0;
    let basepri = reg(uc, RegisterARM::BASEPRI) as u8;
    uc.get_data()
        .nvic
        .execution_priority(primask, faultmask, basepri)
}

/// Exception entry (B1.5.6) with `ret` as the stacked return address.
fn enter(uc: &mut Unicorn<'_, Board>, e: u32, ret: u32) -> Result<(), String> {
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
    b.exc_stack.push(exc_return);
    *b.taken.entry(e).or_insert(0) += 1;
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
fn take_pending(uc: &mut Unicorn<'_, Board>, ret: u32) -> bool {
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

fn halt(uc: &mut Unicorn<'_, Board>, why: String) {
    let b = uc.get_data_mut();
    if b.halted.is_none() {
        b.halted = Some(why);
    }
    b.stop_now();
    let _ = uc.emu_stop();
}

/// Exception return (B1.5.8), from Unicorn's exception-exit interrupt.
fn exception_return(uc: &mut Unicorn<'_, Board>) {
    let pc = reg(uc, RegisterARM::PC);
    let exc_return = pc | 0xF000_0000 | 1;
    let e = reg(uc, RegisterARM::IPSR) & 0x1FF;
    {
        let b = uc.get_data_mut();
        b.nvic.deactivate(e);
        b.depth = b.depth.saturating_sub(1);
        b.exc_stack.pop();
        b.check_irq = true;
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
fn take_fault(uc: &mut Unicorn<'_, Board>, kind: String, fault: u32, pc: u32, addr: Option<u32>) {
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

impl<'a> Machine<'a> {
    /// A board running `image`, out of reset.
    pub fn new(name: &str, profile: Box<dyn Profile>, image: Image) -> Result<Self, String> {
        let cans = can::ports(&profile.can_instances());
        let nvic = Nvic::new(profile.priority_bits(), profile.irq_count());
        let hz = profile.core_hz().max(1);
        let memory = profile.memory();
        let cpu_model = profile.cpu_model();
        let boot = profile.boot_address();
        let board = Board {
            name: name.to_string(),
            profile,
            cans,
            nvic,
            scb: Scb {
                vtor: boot,
                ccr: 1 << 9, // STKALIGN
                ..Scb::default()
            },
            systick: SysTick::default(),
            instructions: 0,
            idle_cycles: 0,
            base_ps: 0,
            base_cycles: 0,
            hz,
            stop_at: 0,
            pc: 0,
            pending_fault: None,
            wfi: false,
            sleeping: false,
            halted: None,
            depth: 0,
            thread_instructions: 0,
            stuck_run: (0, 0, 0),
            taken: BTreeMap::new(),
            faults: Vec::new(),
            stuck: Vec::new(),
            unknown: BTreeMap::new(),
            findings: Vec::new(),
            console: String::new(),
            check_irq: false,
            exc_stack: Vec::new(),
            exited: None,
        };
        let mut uc = Unicorn::new_with_data(Arch::ARM, Mode::THUMB | Mode::MCLASS, board)
            .map_err(|e| format!("unicorn: {e:?}"))?;
        uc.ctl_set_cpu_model(cpu_model)
            .map_err(|e| format!("cpu model: {e:?}"))?;

        // Memory: flash and RAM from the profile; the load image into every region that
        // holds it (and into the aliases).
        for m in &memory {
            let perms = if m.writable {
                Prot::ALL
            } else {
                Prot::READ | Prot::EXEC
            };
            uc.mem_map(u64::from(m.base), u64::from(m.size), perms)
                .map_err(|e| format!("map {}: {e:?}", m.name))?;
        }
        for seg in &image.segments {
            let mut placed = false;
            for m in &memory {
                let origin = m.alias_of.unwrap_or(m.base);
                let end = u64::from(origin) + u64::from(m.size);
                if u64::from(seg.address) >= u64::from(origin)
                    && u64::from(seg.address) + seg.data.len() as u64 <= end
                {
                    let at = seg.address - origin + m.base;
                    uc.mem_write(u64::from(at), &seg.data)
                        .map_err(|e| format!("load 0x{:08X}: {e:?}", seg.address))?;
                    placed = true;
                }
            }
            if !placed {
                return Err(format!(
                    "ELF segment at 0x{:08X} ({} bytes) is outside the board's memory",
                    seg.address,
                    seg.data.len()
                ));
            }
        }

        // Peripheral space and the private peripheral bus: callbacks.
        uc.mmio_map(
            PERIPH_BASE,
            PERIPH_SIZE,
            Some(|uc: &mut Unicorn<'_, Board>, off: u64, size: usize| {
                periph_read(uc, (PERIPH_BASE + off) as u32, size)
            }),
            Some(
                |uc: &mut Unicorn<'_, Board>, off: u64, size: usize, value: u64| {
                    periph_write(uc, (PERIPH_BASE + off) as u32, size, value as u32)
                },
            ),
        )
        .map_err(|e| format!("mmio: {e:?}"))?;
        uc.mmio_map(
            PPB_BASE,
            PPB_SIZE,
            Some(|uc: &mut Unicorn<'_, Board>, off: u64, size: usize| {
                ppb_read(uc, (PPB_BASE + off) as u32, size)
            }),
            Some(
                |uc: &mut Unicorn<'_, Board>, off: u64, size: usize, value: u64| {
                    ppb_write(uc, (PPB_BASE + off) as u32, size, value as u32)
                },
            ),
        )
        .map_err(|e| format!("ppb: {e:?}"))?;

        // Every instruction: count, stop at deadlines, take pending exceptions.
        uc.add_code_hook(1, 0, |uc, addr, _size| {
            let b = uc.get_data_mut();
            b.pc = addr as u32;
            b.instructions += 1;
            if b.depth == 0 {
                b.thread_instructions += 1;
            }
            if b.instructions >= b.stop_at {
                let _ = uc.emu_stop();
                return;
            }
            if b.check_irq {
                b.check_irq = false;
                if b.nvic.any_pending_enabled() {
                    // Re-check at the next instruction while something stays pending
                    // (a mask may be lifted by MSR/CPS, which has no hook).
                    uc.get_data_mut().check_irq = true;
                    if take_pending(uc, addr as u32) {
                        let b = uc.get_data_mut();
                        b.instructions -= 1;
                    }
                }
            }
        })
        .map_err(|e| format!("code hook: {e:?}"))?;

        for &site in &image.wfi_sites {
            uc.add_code_hook(u64::from(site), u64::from(site), |uc, addr, _| {
                // The instruction hook may just have taken an exception here (PC moved to
                // the handler): the WFI then runs after the handler returns.
                if reg(uc, RegisterARM::PC) & !1 != addr as u32 {
                    return;
                }
                let b = uc.get_data_mut();
                b.wfi = true;
                b.stop_now();
                set_reg(uc, RegisterARM::PC, (addr as u32 + 2) | 1);
                let _ = uc.emu_stop();
            })
            .map_err(|e| format!("wfi hook: {e:?}"))?;
        }

        uc.add_intr_hook(|uc, intno| {
            let pc = uc.get_data().pc;
            match intno {
                8 => exception_return(uc),
                2 => {
                    // SVC: SVCall with the next instruction as return address.
                    uc.get_data_mut().nvic.set_pending(exc::SVCALL, true);
                    let next = reg(uc, RegisterARM::PC);
                    take_pending(uc, next);
                }
                7 => semihosting_or_fault(uc, pc),
                1 | 17 | 18 | 22 => take_fault(
                    uc,
                    format!("UsageFault (exception {intno} from the CPU)"),
                    exc::USAGE_FAULT,
                    pc,
                    None,
                ),
                other => halt(
                    uc,
                    format!("unsupported CPU exception {other} at 0x{pc:08X}"),
                ),
            }
        })
        .map_err(|e| format!("intr hook: {e:?}"))?;

        uc.add_mem_hook(
            HookType::MEM_INVALID,
            1,
            0,
            |uc, kind, addr, _size, _value| {
                let b = uc.get_data_mut();
                let what = match kind {
                    MemType::FETCH_UNMAPPED | MemType::FETCH_PROT => {
                        "instruction fetch from unmapped space"
                    }
                    MemType::WRITE_PROT => "write to read-only memory",
                    MemType::WRITE_UNMAPPED => "write to unmapped space",
                    _ => "read from unmapped space",
                };
                b.bus_error(format!("BusFault: {what}"), addr as u32);
                false
            },
        )
        .map_err(|e| format!("mem hook: {e:?}"))?;

        let mut machine = Machine { uc, image };
        machine.reset()?;
        Ok(machine)
    }

    /// Reset (B1.5.5): SP and PC from the vector table at the boot address.
    fn reset(&mut self) -> Result<(), String> {
        let vtor = self.uc.get_data().scb.vtor;
        let sp = read_u32(&self.uc, vtor).ok_or("no vector table at the boot address")?;
        let pc = read_u32(&self.uc, vtor + 4).ok_or("no reset vector")?;
        set_reg(&mut self.uc, RegisterARM::MSP, sp);
        set_reg(&mut self.uc, RegisterARM::SP, sp);
        set_reg(&mut self.uc, RegisterARM::PC, pc | 1);
        Ok(())
    }

    /// The board state.
    pub fn board(&self) -> &Board {
        self.uc.get_data()
    }

    /// The board state, mutable.
    pub fn board_mut(&mut self) -> &mut Board {
        self.uc.get_data_mut()
    }

    /// Runs until the core time reaches `t_ps` (or the board halts).
    pub fn run_until(&mut self, t_ps: u128) {
        loop {
            {
                let b = self.uc.get_data_mut();
                b.systick_catch_up();
                if let Some((at, why)) = b.profile.reset_deadline() {
                    if b.cycles() >= at && b.halted.is_none() {
                        let at_ns = b.time_ns();
                        let pc = b.pc;
                        b.faults.push(Fault {
                            kind: why.clone(),
                            pc,
                            address: None,
                            taken_as: None,
                            silent: false,
                            at_ns,
                        });
                        b.halted = Some(why);
                    }
                }
                if b.halted.is_some() || b.time_ps() >= t_ps {
                    if b.halted.is_some() && b.time_ps() < t_ps {
                        let c = b.cycles_until(t_ps);
                        b.idle_cycles += c;
                    }
                    return;
                }
            }
            if self.uc.get_data().sleeping {
                self.sleep_until(t_ps);
                continue;
            }
            let pc = reg(&self.uc, RegisterARM::PC);
            // Take what is pending before running (interrupts that arrived between slices).
            if self.uc.get_data().nvic.any_pending_enabled() {
                take_pending(&mut self.uc, pc);
            }
            let pc = reg(&self.uc, RegisterARM::PC);
            {
                let b = self.uc.get_data_mut();
                let mut budget = b.cycles_until(t_ps).max(1);
                if let Some(at) = b.systick_next() {
                    budget = budget.min(at.saturating_sub(b.cycles()).max(1));
                }
                if let Some((at, _)) = b.profile.reset_deadline() {
                    budget = budget.min(at.saturating_sub(b.cycles()).max(1));
                }
                b.stop_at = b.instructions + budget;
                b.wfi = false;
                b.check_irq = true;
            }
            let result = self.uc.emu_start(u64::from(pc | 1), 0, 0, 0);
            self.uc.get_data_mut().rebase();
            let pending = self.uc.get_data_mut().pending_fault.take();
            if let Some((kind, fpc, addr)) = pending {
                let is_fetch = kind.contains("fetch");
                take_fault(
                    &mut self.uc,
                    kind,
                    exc::BUS_FAULT,
                    fpc,
                    (!is_fetch).then_some(addr),
                );
                continue;
            }
            if let Err(e) = result {
                let fpc = self.uc.get_data().pc;
                halt(&mut self.uc, format!("CPU error {e:?} at 0x{fpc:08X}"));
                continue;
            }
            if self.uc.get_data().wfi {
                self.uc.get_data_mut().sleeping = true;
            }
            let findings = self.uc.get_data_mut().profile.take_findings();
            self.uc.get_data_mut().findings.extend(findings);
        }
    }

    /// WFI: skip to the next event (SysTick, or `t_ps` where the bus may raise a line).
    fn sleep_until(&mut self, t_ps: u128) {
        let wake_prio = {
            // WFI wakes on an exception that would preempt with PRIMASK = 0.
            let faultmask = reg(&self.uc, RegisterARM::FAULTMASK) & 1 != 0;
            let basepri = reg(&self.uc, RegisterARM::BASEPRI) as u8;
            self.uc
                .get_data()
                .nvic
                .execution_priority(false, faultmask, basepri)
        };
        let b = self.uc.get_data_mut();
        if b.nvic.next_to_take(wake_prio).is_some() {
            b.sleeping = false;
            return;
        }
        let mut until = b.cycles() + b.cycles_until(t_ps).max(1);
        if let Some(at) = b.systick_next() {
            until = until.min(at.max(b.cycles() + 1));
        }
        if let Some((at, _)) = b.profile.reset_deadline() {
            until = until.min(at.max(b.cycles() + 1));
        }
        b.idle_cycles += until - b.cycles();
        b.systick_catch_up();
        if b.nvic.next_to_take(wake_prio).is_some() {
            b.sleeping = false;
        }
        let _ = THREAD_PRIORITY;
    }

    /// Reads `len` bytes of target memory.
    pub fn read_memory(&self, addr: u32, len: usize) -> Option<Vec<u8>> {
        self.uc.mem_read_as_vec(u64::from(addr), len).ok()
    }

    /// Reads a firmware static by the last components of its demangled symbol name
    /// (e.g. `SENT`).
    pub fn read_static(&self, name: &str) -> Option<Vec<u8>> {
        let sym = self.image.symbol(name)?;
        self.read_memory(sym.address, sym.size as usize)
    }

    /// A `u32` static.
    pub fn read_u32_static(&self, name: &str) -> Option<u32> {
        let b = self.read_static(name)?;
        Some(u32::from_le_bytes(b.get(..4)?.try_into().ok()?))
    }
}

fn semihosting_or_fault(uc: &mut Unicorn<'_, Board>, pc: u32) {
    let bkpt = uc
        .mem_read_as_vec(u64::from(pc), 2)
        .ok()
        .map(|b| u16::from_le_bytes([b[0], b[1]]));
    if bkpt != Some(0xBEAB) {
        // A breakpoint with no debugger attached escalates to HardFault (C1.7).
        let prio = execution_priority(uc);
        let _ = prio;
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

fn periph_read(uc: &mut Unicorn<'_, Board>, addr: u32, size: usize) -> u64 {
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
        let off = (addr - b.cans[i].instance.base) as usize;
        let word = b.cans[i].model.read32(off & !3);
        b.refresh_can_lines();
        return u64::from(crate::profile::extract(word, addr, size));
    }
    let ctx = b.ctx();
    match b.profile.read(addr, size, ctx) {
        Access::Known(v) => u64::from(v),
        Access::Unknown { peripheral } => {
            b.note_unknown(addr, peripheral, "read");
            let _ = &b;
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

fn periph_write(uc: &mut Unicorn<'_, Board>, addr: u32, size: usize, value: u32) {
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
        let off = (addr - b.cans[i].instance.base) as usize;
        let v = if size == 4 {
            value
        } else {
            let cur = b.cans[i].model.read32(off & !3);
            crate::profile::insert(cur, addr, size, value)
        };
        b.cans[i].model.write32(off & !3, v);
        b.refresh_can_lines();
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

/// Reads of the private peripheral bus.
fn ppb_read(uc: &mut Unicorn<'_, Board>, addr: u32, size: usize) -> u64 {
    let word = ppb_read_word(uc, addr & !3);
    u64::from(crate::profile::extract(word, addr, size))
}

fn ppb_read_word(uc: &mut Unicorn<'_, Board>, addr: u32) -> u32 {
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

fn ppb_write(uc: &mut Unicorn<'_, Board>, addr: u32, size: usize, value: u32) {
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
            for bit in 0..32 {
                if value & (1 << bit) != 0 {
                    b.nvic.set_irq_enabled(n * 32 + bit, set);
                }
            }
            b.check_irq = true;
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

/// The unknown-register report lines, sorted by address.
pub fn unknown_report(b: &Board) -> Vec<String> {
    let mut seen = BTreeSet::new();
    b.unknown
        .iter()
        .filter(|(a, _)| seen.insert(**a))
        .map(|(a, (pc, p, dir))| {
            format!("{dir} of unknown {p} register 0x{a:08X} (first at PC 0x{pc:08X})")
        })
        .collect()
}
