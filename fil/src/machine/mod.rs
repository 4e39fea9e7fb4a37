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
//! - B1.5.18 WFE and SEV: the event register is set by `SEV` and by every exception
//!   return (and cleared at reset); `WFE` clears it and goes on when it is set, and
//!   otherwise sleeps as WFI does (woken by an exception that would preempt).
//!   `SCR.SEVONPEND` is not modelled (a pending interrupt that cannot preempt does not
//!   wake a WFE).
//!
//! Time: one instruction is one core clock cycle (the Cortex-M4/M7 average is close to
//! it for this code; documented in docs/fil.md).

mod exceptions;
mod peripherals;
mod ppb;
mod semihosting;

use std::collections::BTreeMap;

use unicorn_engine::unicorn_const::{Arch, HookType, MemType, Mode, Prot};
use unicorn_engine::{RegisterARM, Unicorn};

use crate::can::{self, Port};
use crate::elf::Image;
use crate::nvic::{exc, Nvic};
use crate::profile::{Ctx, Profile};

pub use exceptions::{
    exception_name, Fault, Livelock, LivelockKind, StuckIrq, LIVELOCK_PS, STUCK_ENTRIES,
};
use exceptions::{exception_return, halt, take_fault, take_pending};
use peripherals::{periph_read, periph_write};
use ppb::{ppb_read, ppb_write, Scb, SysTick};
use semihosting::semihosting_or_fault;

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
    /// The event register (ARMv7-M B1.5.18): set by SEV and exception return, consumed
    /// by WFE.
    event: bool,
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
    /// The first livelock found ([`LIVELOCK_PS`]).
    pub livelock: Option<Livelock>,
    /// Livelock watch: thread instructions, core time (ps) and exceptions taken at the
    /// last thread-mode progress.
    progress: (u64, u128, BTreeMap<u32, u64>),
    /// Entry time (ps) of each active exception's current activation.
    active_since: BTreeMap<u32, u128>,
    /// Accesses to registers the profile does not know: (address, first PC, read/write).
    pub unknown: BTreeMap<u32, (u32, &'static str, &'static str)>,
    /// Findings of the register rules.
    pub findings: Vec<String>,
    /// Semihosting console output.
    pub console: String,
    /// The `defmt` log's RTT up-channel (firmware with a `.defmt` table and
    /// `_SEGGER_RTT`).
    pub rtt: Option<crate::rtt::Rtt>,
    /// Exceptions whose next entry should be checked (something changed).
    check_irq: bool,
    /// Semihosting exit requested.
    pub exited: Option<u32>,
    /// The painted stack and its marks (`--stack`, [`Machine::paint_stack`]).
    pub stack: Option<crate::stack::StackPaint>,
    /// The CAN interrupt lines held low at the NVIC (their causes stay set in the
    /// models): a receive interrupt delayed — by a long critical section, a
    /// higher-priority handler — for as long as a test sets it.
    pub hold_can_lines: bool,
    /// A stall of the core, in ps, started when a CAN controller first joins the bus
    /// (before the firmware's next instruction): as firmware busy elsewhere between
    /// its controller going on the bus and its interrupt start-up (`split`/`start`), so
    /// that bus traffic meanwhile leaves a CAN interrupt pending when the lines are
    /// unmasked.
    pub stall_on_join_ps: Option<u128>,
    /// The end of the stall in progress (core time, ps).
    stalled_until_ps: u128,
    /// A controller of this board has joined the bus (the stall was considered).
    joined: bool,
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
    /// How many times interrupt line `irq` was taken (exception 16 + `irq`).
    pub fn irq_taken(&self, irq: u32) -> u64 {
        self.taken.get(&(16 + irq)).copied().unwrap_or(0)
    }

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

    /// A stall counts as thread progress up to its end (the firmware is busy in thread
    /// mode): the slack of one co-simulation step.
    fn quantum_hint_ps(&self) -> u128 {
        20_000_000
    }

    /// The livelock watch, called between slices of execution: thread mode progressed
    /// (or the core sleeps in thread mode, waiting as it was told to), or the time since
    /// its last progress, or since the entry of a handler still active, is checked
    /// against [`LIVELOCK_PS`] whatever exceptions ran meanwhile (SysTick included).
    pub fn watch_progress(&mut self) {
        if self.livelock.is_some() || self.halted.is_some() {
            return;
        }
        let now = self.time_ps();
        let stalled = self.stalled_until_ps > now.saturating_sub(self.quantum_hint_ps());
        if self.thread_instructions != self.progress.0
            || (self.sleeping && self.depth == 0)
            || stalled
        {
            self.progress = (self.thread_instructions, now, self.taken.clone());
            // An exception still active from before is checked below all the same.
        }
        // The innermost activation older than the bound (an outer one only waits for
        // it).
        let stuck_handler = self
            .active_since
            .iter()
            .filter(|(_, t)| now - **t > LIVELOCK_PS)
            .max_by_key(|(_, t)| **t)
            .map(|(e, t)| (*e, *t));
        let kind = match stuck_handler {
            Some((e, since)) => Some((LivelockKind::HandlerNeverReturns { exception: e }, since)),
            _ if now - self.progress.1 > LIVELOCK_PS => {
                Some((LivelockKind::NoThreadProgress, self.progress.1))
            }
            _ => None,
        };
        if let Some((kind, since)) = kind {
            let before = &self.progress.2;
            let taken = self
                .taken
                .iter()
                .map(|(e, n)| (*e, n - before.get(e).copied().unwrap_or(0)))
                .filter(|(_, n)| *n > 0)
                .collect();
            let to_ns = |ps: u128| (ps / 1000) as u64;
            let found = Livelock {
                kind,
                since_ns: to_ns(since),
                at_ns: to_ns(now),
                taken,
            };
            // The board stops there: a livelocked core would otherwise be emulated
            // instruction by instruction to the end of the run (minutes instead of
            // seconds for a suite of such runs).
            self.halted = Some(format!("livelock: {found}"));
            self.livelock = Some(found);
        }
    }

    /// Starts the stall of [`Board::stall_on_join_ps`] when a controller has just joined
    /// the bus; whether it did.
    pub fn note_join(&mut self) -> bool {
        if self.joined || !self.cans.iter().any(|p| p.model.on_bus()) {
            return false;
        }
        self.joined = true;
        let Some(stall) = self.stall_on_join_ps else {
            return false;
        };
        self.stalled_until_ps = self.time_ps() + stall;
        self.stop_now();
        true
    }

    /// Updates the NVIC levels from the CAN models' lines (held low while
    /// [`Board::hold_can_lines`]).
    pub fn refresh_can_lines(&mut self) {
        let hold = self.hold_can_lines;
        for port in &self.cans {
            for ((_, irq), level) in port.instance.irqs.iter().zip(port.model.lines()) {
                let level = level && !hold;
                if self.nvic.level(*irq) != level {
                    self.nvic.set_level(*irq, level);
                    self.check_irq = true;
                }
            }
        }
    }

    /// Gives CAN controller `i` its protocol-engine clock or takes it away, as the
    /// profile's clock tree says now (no clock: no mode handshake completes).
    fn clock_can_engine(&mut self, i: usize) {
        let port = &self.cans[i];
        let clksrc = port.model.clksrc();
        let clocked = self.profile.can_engine_clocked(&port.instance, clksrc);
        port.model.set_engine_clock(clocked);
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
            event: false,
            halted: None,
            depth: 0,
            thread_instructions: 0,
            stuck_run: (0, 0, 0),
            taken: BTreeMap::new(),
            faults: Vec::new(),
            stuck: Vec::new(),
            livelock: None,
            progress: (0, 0, BTreeMap::new()),
            active_since: BTreeMap::new(),
            unknown: BTreeMap::new(),
            findings: Vec::new(),
            console: String::new(),
            rtt: image
                .defmt
                .as_ref()
                .and(image.symbol("_SEGGER_RTT"))
                .map(|s| crate::rtt::Rtt::new(s.address)),
            check_irq: false,
            exited: None,
            stack: None,
            hold_can_lines: false,
            stall_on_join_ps: None,
            stalled_until_ps: 0,
            joined: false,
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

        for &site in &image.wfe_sites {
            uc.add_code_hook(u64::from(site), u64::from(site), |uc, addr, _| {
                if reg(uc, RegisterARM::PC) & !1 != addr as u32 {
                    return;
                }
                // Unicorn does not execute WFE: the harness does, and stops to move on.
                let b = uc.get_data_mut();
                if b.event {
                    b.event = false;
                } else {
                    b.wfi = true;
                }
                b.stop_now();
                set_reg(uc, RegisterARM::PC, (addr as u32 + 2) | 1);
                let _ = uc.emu_stop();
            })
            .map_err(|e| format!("wfe hook: {e:?}"))?;
        }
        for &site in &image.sev_sites {
            uc.add_code_hook(u64::from(site), u64::from(site), |uc, addr, _| {
                if reg(uc, RegisterARM::PC) & !1 != addr as u32 {
                    return;
                }
                let b = uc.get_data_mut();
                b.event = true;
                b.stop_now();
                set_reg(uc, RegisterARM::PC, (addr as u32 + 2) | 1);
                let _ = uc.emu_stop();
            })
            .map_err(|e| format!("sev hook: {e:?}"))?;
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

    /// Reset (B1.5.5): SP and PC from the vector table at the boot address — or where
    /// the chip's boot ROM starts the image ([`Profile::boot`]); an image the ROM refuses
    /// halts the board with the ROM's reason.
    fn reset(&mut self) -> Result<(), String> {
        let boot = {
            let uc = &self.uc;
            let read = |a: u32| read_u32(uc, a);
            uc.get_data().profile.boot(&read)
        };
        match boot {
            Ok(Some(b)) => {
                self.uc.get_data_mut().scb.vtor = b.vtor;
                set_reg(&mut self.uc, RegisterARM::MSP, b.sp);
                set_reg(&mut self.uc, RegisterARM::SP, b.sp);
                set_reg(&mut self.uc, RegisterARM::PC, b.pc | 1);
                return Ok(());
            }
            Ok(None) => {}
            Err(why) => {
                let b = self.uc.get_data_mut();
                b.halted = Some(format!("boot ROM: {why}"));
                return Ok(());
            }
        }
        let vtor = self.uc.get_data().scb.vtor;
        let sp = read_u32(&self.uc, vtor).ok_or("no vector table at the boot address")?;
        let pc = read_u32(&self.uc, vtor + 4).ok_or("no reset vector")?;
        set_reg(&mut self.uc, RegisterARM::MSP, sp);
        set_reg(&mut self.uc, RegisterARM::SP, sp);
        set_reg(&mut self.uc, RegisterARM::PC, pc | 1);
        Ok(())
    }

    /// Paints the stack (`crate::stack`): from cortex-m-rt's `_stack_end` up to the
    /// initial stack pointer reset loaded (from the vector table, or the one a boot ROM
    /// found through its image header: the i.MX RT1062's). Call before running.
    pub fn paint_stack(&mut self) -> Result<(), String> {
        let bottom = self
            .image
            .symbol("_stack_end")
            .map(|s| s.address)
            .ok_or("stack: the ELF has no `_stack_end` symbol (cortex-m-rt 0.7.4 or newer)")?;
        let top = reg(&self.uc, RegisterARM::MSP) & !7;
        if top == 0 {
            return Err("stack: no initial stack pointer".into());
        }
        let paint = crate::stack::paint(&mut self.uc, bottom, top)?;
        self.uc.get_data_mut().stack = Some(paint);
        Ok(())
    }

    /// The stack's high-water mark now (bytes), when painted.
    pub fn stack_high_water(&self) -> Option<u32> {
        let s = self.uc.get_data().stack.as_ref()?;
        Some(crate::stack::high_water(&self.uc, s))
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
            {
                let b = self.uc.get_data_mut();
                if b.stalled_until_ps > b.time_ps() {
                    // The stall: the core busy elsewhere (no instruction of the image).
                    let c = b.cycles_until(b.stalled_until_ps.min(t_ps)).max(1);
                    b.idle_cycles += c;
                    continue;
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
            // `until` is an address Unicorn stops at before executing it: none that a
            // 32-bit core can reach (0 would stop code placed at address 0, as the
            // i.MX RT's ITCM code is). The harness stops the CPU itself (`emu_stop`).
            let result = self.uc.emu_start(u64::from(pc | 1), u64::MAX, 0, 0);
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
    }

    /// Reads what the firmware wrote to its RTT up-channel since the last call (a
    /// probe's read: the channel's read offset moves on).
    pub fn drain_rtt(&mut self) {
        let Some(mut rtt) = self.uc.get_data_mut().rtt.take() else {
            return;
        };
        {
            let uc = std::cell::RefCell::new(&mut self.uc);
            rtt.drain(
                |a, n| uc.borrow().mem_read_as_vec(u64::from(a), n).ok(),
                |a, b| uc.borrow_mut().mem_write(u64::from(a), b).is_ok(),
            );
        }
        self.uc.get_data_mut().rtt = Some(rtt);
    }

    /// The `defmt` log decoded so far (empty when the firmware does not log with
    /// `defmt`).
    pub fn defmt_lines(&self) -> Vec<crate::rtt::LogLine> {
        match (&self.image.defmt, &self.board().rtt) {
            (Some(table), Some(rtt)) => crate::rtt::decode(table, &rtt.bytes),
            _ => Vec::new(),
        }
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

/// The unknown-register report lines, sorted by address.
pub fn unknown_report(b: &Board) -> Vec<String> {
    b.unknown
        .iter()
        .map(|(a, (pc, p, dir))| {
            format!("{dir} of unknown {p} register 0x{a:08X} (first at PC 0x{pc:08X})")
        })
        .collect()
}
