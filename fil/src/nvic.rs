//! The exception model of an ARMv7-M core that Unicorn leaves out: pending, active and
//! enabled state, priorities with grouping, and the choice of the exception to take.
//!
//! Rules from the ARMv7-M Architecture Reference Manual (DDI 0403E):
//! - B1.5.4 "Exception priorities and preemption": Reset −3, NMI −2, HardFault −1, the
//!   rest configurable; only the *group* priority (AIRCR.PRIGROUP) decides preemption;
//!   among pending exceptions of equal priority the lowest exception number goes first.
//! - B1.5.4 "Execution priority and priority boosting": the execution priority is the
//!   highest of the active exceptions' group priorities, PRIMASK (→ 0), FAULTMASK (→ −1)
//!   and BASEPRI (when not zero).
//! - B3.4 NVIC: an interrupt line is a level; a pending interrupt that is not enabled
//!   is not taken; the pending bit follows the line while the interrupt is not active
//!   and is set again at exception return while the line stays asserted.
//! - Priority registers implement the top `bits` bits of each byte (4 on the Kinetis K
//!   series and the STM32F7).

/// Exception numbers of the system exceptions used here.
pub mod exc {
    /// NMI.
    pub const NMI: u32 = 2;
    /// HardFault.
    pub const HARD_FAULT: u32 = 3;
    /// MemManage fault.
    pub const MEM_MANAGE: u32 = 4;
    /// BusFault.
    pub const BUS_FAULT: u32 = 5;
    /// UsageFault.
    pub const USAGE_FAULT: u32 = 6;
    /// SVCall.
    pub const SVCALL: u32 = 11;
    /// PendSV.
    pub const PENDSV: u32 = 14;
    /// SysTick.
    pub const SYSTICK: u32 = 15;
    /// First external interrupt (IRQ 0).
    pub const IRQ0: u32 = 16;
}

/// Number of exception numbers tracked (16 system + 240 external).
pub const EXCEPTIONS: usize = 256;

/// The priority of "no exception active, no mask": lower than any configurable one.
pub const THREAD_PRIORITY: i32 = 256;

/// NVIC and system-handler state of one core.
#[derive(Debug, Clone)]
pub struct Nvic {
    /// Implemented priority bits (upper bits of each priority byte).
    bits: u8,
    /// Number of external interrupts the chip has.
    irqs: u32,
    enabled: [bool; EXCEPTIONS],
    pending: [bool; EXCEPTIONS],
    active: [bool; EXCEPTIONS],
    level: [bool; EXCEPTIONS],
    priority: [u8; EXCEPTIONS],
    /// AIRCR.PRIGROUP.
    pub prigroup: u8,
    /// SHCSR enables of MemManage, BusFault, UsageFault.
    pub fault_enabled: [bool; 3],
}

impl Nvic {
    /// Reset state: everything disabled, not pending, priority 0.
    pub fn new(bits: u8, irqs: u32) -> Self {
        let mut n = Nvic {
            bits,
            irqs,
            enabled: [false; EXCEPTIONS],
            pending: [false; EXCEPTIONS],
            active: [false; EXCEPTIONS],
            level: [false; EXCEPTIONS],
            priority: [0; EXCEPTIONS],
            prigroup: 0,
            fault_enabled: [false; 3],
        };
        // System exceptions other than the configurable-enable faults are always enabled.
        for e in [
            exc::NMI,
            exc::HARD_FAULT,
            exc::SVCALL,
            12,
            exc::PENDSV,
            exc::SYSTICK,
        ] {
            n.enabled[e as usize] = true;
        }
        n
    }

    /// Number of external interrupts.
    pub fn irq_count(&self) -> u32 {
        self.irqs
    }

    fn valid(&self, e: u32) -> bool {
        (e as usize) < EXCEPTIONS && (e < exc::IRQ0 || e - exc::IRQ0 < self.irqs)
    }

    /// The stored priority byte of exception `e` (implemented bits only).
    pub fn priority_byte(&self, e: u32) -> u8 {
        self.priority.get(e as usize).copied().unwrap_or(0)
    }

    /// Writes a priority byte; unimplemented low bits read as zero.
    pub fn set_priority_byte(&mut self, e: u32, value: u8) {
        if self.valid(e) && e >= exc::MEM_MANAGE {
            let mask = !(0xFFu8 >> self.bits);
            self.priority[e as usize] = value & mask;
        }
    }

    /// The full priority of `e` (fixed ones negative).
    pub fn priority(&self, e: u32) -> i32 {
        match e {
            1 => -3,
            exc::NMI => -2,
            exc::HARD_FAULT => -1,
            _ => i32::from(self.priority_byte(e)),
        }
    }

    /// The group priority of a priority value (B1.5.4: subpriority bits masked).
    pub fn group(&self, priority: i32) -> i32 {
        if priority < 0 {
            return priority;
        }
        let sub_mask = (2i32 << self.prigroup) - 1;
        priority & !sub_mask
    }

    /// Enable bit (NVIC_ISER for IRQs, SHCSR for the three faults).
    pub fn is_enabled(&self, e: u32) -> bool {
        match e {
            exc::MEM_MANAGE | exc::BUS_FAULT | exc::USAGE_FAULT => {
                self.fault_enabled[(e - exc::MEM_MANAGE) as usize]
            }
            _ => self.enabled.get(e as usize).copied().unwrap_or(false),
        }
    }

    /// Sets the enable bit of external interrupt `irq`.
    pub fn set_irq_enabled(&mut self, irq: u32, on: bool) {
        let e = irq + exc::IRQ0;
        if self.valid(e) {
            self.enabled[e as usize] = on;
            self.refresh(e);
        }
    }

    /// Pending bit of `e`.
    pub fn is_pending(&self, e: u32) -> bool {
        self.pending.get(e as usize).copied().unwrap_or(false)
    }

    /// Active bit of `e`.
    pub fn is_active(&self, e: u32) -> bool {
        self.active.get(e as usize).copied().unwrap_or(false)
    }

    /// Sets or clears the pending bit of `e` (ISPR/ICPR, ICSR, STIR, internal events).
    pub fn set_pending(&mut self, e: u32, on: bool) {
        if self.valid(e) {
            self.pending[e as usize] = on;
            if !on {
                self.refresh(e);
            }
        }
    }

    /// The level of external interrupt line `irq` (a peripheral's request).
    pub fn set_level(&mut self, irq: u32, high: bool) {
        let e = irq + exc::IRQ0;
        if self.valid(e) {
            self.level[e as usize] = high;
            self.refresh(e);
        }
    }

    /// The level of external interrupt line `irq`.
    pub fn level(&self, irq: u32) -> bool {
        self.level
            .get((irq + exc::IRQ0) as usize)
            .copied()
            .unwrap_or(false)
    }

    /// A level that is high sets pending while the exception is not active.
    fn refresh(&mut self, e: u32) {
        let i = e as usize;
        if self.level[i] && !self.active[i] {
            self.pending[i] = true;
        }
    }

    /// Exception entry: active, no longer pending.
    pub fn activate(&mut self, e: u32) {
        if self.valid(e) {
            self.active[e as usize] = true;
            self.pending[e as usize] = false;
        }
    }

    /// Exception return: not active; a line still asserted pends it again.
    pub fn deactivate(&mut self, e: u32) {
        if self.valid(e) {
            self.active[e as usize] = false;
            self.refresh(e);
        }
    }

    /// Number of active exceptions.
    pub fn active_count(&self) -> usize {
        self.active.iter().filter(|a| **a).count()
    }

    /// Execution priority (B1.5.4) given the core's mask registers.
    pub fn execution_priority(&self, primask: bool, faultmask: bool, basepri: u8) -> i32 {
        let mut p = THREAD_PRIORITY;
        for (e, a) in self.active.iter().enumerate() {
            if *a {
                p = p.min(self.group(self.priority(e as u32)));
            }
        }
        if basepri != 0 {
            p = p.min(self.group(i32::from(basepri & !(0xFFu8 >> self.bits))));
        }
        if primask {
            p = p.min(0);
        }
        if faultmask {
            p = p.min(-1);
        }
        p
    }

    /// The pending, enabled exception that would preempt at `execution_priority`, if any.
    pub fn next_to_take(&self, execution_priority: i32) -> Option<u32> {
        let mut best: Option<(i32, u32)> = None;
        for (e, p) in self.pending.iter().enumerate() {
            let e = e as u32;
            if !*p || !self.is_enabled(e) {
                continue;
            }
            let prio = self.priority(e);
            if self.group(prio) >= execution_priority {
                continue;
            }
            if best.is_none_or(|(bp, _)| prio < bp) {
                best = Some((prio, e));
            }
        }
        best.map(|(_, e)| e)
    }

    /// Whether any exception is pending and enabled (a candidate, masked or not).
    pub fn any_pending_enabled(&self) -> bool {
        self.pending
            .iter()
            .enumerate()
            .any(|(e, p)| *p && self.is_enabled(e as u32))
    }

    /// The exception a fault of kind `e` (MemManage, BusFault, UsageFault) is taken as:
    /// itself when enabled and able to preempt, else HardFault (B1.5.8 escalation).
    pub fn fault_target(&self, e: u32, execution_priority: i32) -> u32 {
        if self.is_enabled(e) && self.group(self.priority(e)) < execution_priority {
            e
        } else {
            exc::HARD_FAULT
        }
    }

    /// Reads a 32-bit word of ISER/ICER (`set` = enable view), ISPR/ICPR, IABR at word `n`.
    pub fn word(&self, table: &[bool; EXCEPTIONS], n: u32) -> u32 {
        let mut v = 0;
        for b in 0..32 {
            let e = (exc::IRQ0 + n * 32 + b) as usize;
            if e < EXCEPTIONS && table[e] {
                v |= 1 << b;
            }
        }
        v
    }

    /// ISER/ICER word `n`.
    pub fn enabled_word(&self, n: u32) -> u32 {
        self.word(&self.enabled, n)
    }

    /// ISPR/ICPR word `n`.
    pub fn pending_word(&self, n: u32) -> u32 {
        self.word(&self.pending, n)
    }

    /// IABR word `n`.
    pub fn active_word(&self, n: u32) -> u32 {
        self.word(&self.active, n)
    }

    /// The lowest-numbered active exception (ICSR.VECTACTIVE shows the current one; the
    /// harness tracks that itself, this is for reports).
    pub fn pending_highest(&self) -> Option<u32> {
        self.next_to_take(THREAD_PRIORITY + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_interrupt_pends_again_at_return_while_asserted() {
        let mut n = Nvic::new(4, 100);
        n.set_irq_enabled(75, true);
        n.set_level(75, true);
        assert_eq!(n.next_to_take(THREAD_PRIORITY), Some(16 + 75));
        n.activate(16 + 75);
        assert!(!n.is_pending(16 + 75), "entry clears pending");
        n.deactivate(16 + 75);
        assert!(n.is_pending(16 + 75), "line still high: pending again");
        n.activate(16 + 75);
        n.set_level(75, false);
        n.deactivate(16 + 75);
        assert!(!n.is_pending(16 + 75));
    }

    #[test]
    fn priorities_grouping_and_masks() {
        let mut n = Nvic::new(4, 100);
        n.set_priority_byte(16 + 1, 0x47);
        assert_eq!(n.priority_byte(16 + 1), 0x40, "4 implemented bits");
        n.set_priority_byte(16 + 2, 0x20);
        for i in [1, 2] {
            n.set_irq_enabled(i, true);
            n.set_pending(16 + i, true);
        }
        assert_eq!(
            n.next_to_take(THREAD_PRIORITY),
            Some(18),
            "0x20 before 0x40"
        );
        assert_eq!(n.execution_priority(true, false, 0), 0);
        assert_eq!(n.next_to_take(0), None, "PRIMASK masks all configurable");
        assert_eq!(
            n.next_to_take(n.execution_priority(false, false, 0x30)),
            Some(18)
        );
        n.activate(18);
        assert_eq!(n.execution_priority(false, false, 0), 0x20);
        assert_eq!(n.next_to_take(0x20), None, "0x40 cannot preempt 0x20");
        // PRIGROUP 6: one group bit (bit 7): 0x20 and 0x40 are the same group.
        n.prigroup = 6;
        assert_eq!(n.group(0x40), 0);
        assert_eq!(
            n.fault_target(exc::BUS_FAULT, THREAD_PRIORITY),
            exc::HARD_FAULT
        );
    }

    #[test]
    fn equal_priority_lowest_number_first_and_disabled_not_taken() {
        let mut n = Nvic::new(4, 100);
        n.set_pending(16 + 9, true);
        assert_eq!(n.next_to_take(THREAD_PRIORITY), None, "not enabled");
        n.set_irq_enabled(9, true);
        n.set_irq_enabled(3, true);
        n.set_pending(16 + 3, true);
        n.set_pending(exc::SYSTICK, true);
        assert_eq!(n.next_to_take(THREAD_PRIORITY), Some(exc::SYSTICK));
    }
}
