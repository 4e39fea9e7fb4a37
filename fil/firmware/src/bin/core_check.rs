//! Exercises the exception model of the core: preemption by priority, pending a lower
//! priority from a handler (taken on return, tail-chained), BASEPRI and PRIMASK masking,
//! SVCall, the DWT cycle counter, SysTick COUNTFLAG and its interrupt, WFI, WFE and SEV.
//! Each step appends a code to `LOG`; the harness test compares it with the order the
//! ARMv7-M rules give (B1.5.4, B1.5.6, B1.5.8, B1.5.18, B3.3, B3.4, C1.8).
#![no_std]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod image {
    use core::sync::atomic::{AtomicU32, Ordering};
    use twocan_fil_firmware::{idle, kinetis_watchdog_off, print, read32, write32};

    core::arch::global_asm!(
        ".section .vectors,\"a\",%progbits",
        ".word __stack_top",
        ".word reset",
        ".rept 9",
        ".word fault",
        ".endr",
        ".word svcall",
        ".word fault",
        ".word fault",
        ".word fault",
        ".word systick",
        ".word irq0",
        ".word irq1",
        ".word irq2",
        ".word irq3",
    );

    #[link_section = ".flash_config"]
    #[no_mangle]
    #[used]
    static FLASH_CONFIG: [u8; 16] = [
        0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFE, 0xFF, 0xFF,
        0xFF,
    ];

    /// The event codes, in order.
    #[no_mangle]
    static LOG: [AtomicU32; 32] = [const { AtomicU32::new(0) }; 32];
    /// Number of codes in `LOG`.
    #[no_mangle]
    static LEN: AtomicU32 = AtomicU32::new(0);

    fn push(code: u32) {
        let i = LEN.fetch_add(1, Ordering::SeqCst) as usize;
        if let Some(slot) = LOG.get(i) {
            slot.store(code, Ordering::SeqCst);
        }
    }

    const STIR: u32 = 0xE000_EF00;
    const ISER0: u32 = 0xE000_E100;
    const IPR0: u32 = 0xE000_E400;
    const SYST_CSR: u32 = 0xE000_E010;
    const SYST_RVR: u32 = 0xE000_E014;
    const SYST_CVR: u32 = 0xE000_E018;
    const DEMCR: u32 = 0xE000_EDFC;
    const DWT_CTRL: u32 = 0xE000_1000;
    const DWT_CYCCNT: u32 = 0xE000_1004;

    fn pend(irq: u32) {
        // SAFETY: the NVIC software trigger register.
        unsafe { write32(STIR, irq) };
    }

    fn basepri(v: u32) {
        // SAFETY: BASEPRI only changes which exceptions may preempt.
        unsafe { core::arch::asm!("msr basepri, {0}", "isb", in(reg) v) };
    }

    #[no_mangle]
    extern "C" fn reset() -> ! {
        // SAFETY: registers of the K66 and of the core, in an order the steps need.
        unsafe {
            kinetis_watchdog_off();
            // IRQ 0: 0x80, IRQ 1 and 2: 0x40, IRQ 3: 0xC0 (one byte each).
            write32(IPR0, 0xC040_4080);
            write32(ISER0, 0xF);
        }
        // 1. Preemption, pending from a handler, tail-chaining.
        push(1);
        pend(0);
        push(2);
        // 2. BASEPRI masks priority 0x40 and lower.
        basepri(0x40);
        pend(2);
        push(3);
        basepri(0);
        push(4);
        // 3. PRIMASK masks everything configurable.
        // SAFETY: masking and unmasking interrupts.
        unsafe { core::arch::asm!("cpsid i") };
        pend(0);
        push(5);
        // SAFETY: as above.
        unsafe { core::arch::asm!("cpsie i", "isb") };
        push(6);
        // 4. SVCall.
        // SAFETY: the SVCall handler only logs.
        unsafe { core::arch::asm!("svc 0") };
        push(7);
        // 5. DWT cycle counter.
        // SAFETY: debug and trace registers.
        let cycles = unsafe {
            write32(DEMCR, read32(DEMCR) | (1 << 24));
            write32(DWT_CTRL, read32(DWT_CTRL) | 1);
            let a = read32(DWT_CYCCNT);
            for _ in 0..50 {
                core::arch::asm!("nop");
            }
            read32(DWT_CYCCNT).wrapping_sub(a)
        };
        if (50..1000).contains(&cycles) {
            push(8);
        }
        // 6. SysTick: COUNTFLAG without interrupt, then the interrupt out of WFI.
        // SAFETY: SysTick registers.
        unsafe {
            write32(SYST_RVR, 999);
            write32(SYST_CVR, 0);
            write32(SYST_CSR, 0b101);
            if (0..10_000).any(|_| read32(SYST_CSR) & (1 << 16) != 0) {
                push(9);
            }
            write32(SYST_CSR, 0b111);
            core::arch::asm!("wfi");
        }
        push(15);
        // 7. WFE and SEV (B1.5.18): the SysTick handler's return set the event register,
        // so this WFE goes on at once; so does one after SEV; with the register clear,
        // WFE sleeps until SysTick interrupts again.
        // SAFETY: hint instructions and SysTick registers.
        unsafe {
            core::arch::asm!("wfe");
            push(16);
            core::arch::asm!("sev", "wfe");
            push(17);
            write32(SYST_CVR, 0);
            write32(SYST_CSR, 0b111);
            core::arch::asm!("wfe");
        }
        push(18);
        print(c"core-check: done\n");
        idle()
    }

    #[no_mangle]
    extern "C" fn irq0() {
        push(10);
        pend(1); // higher priority: preempts at once
        pend(3); // lower priority: waits for this handler to return
        push(12);
    }

    #[no_mangle]
    extern "C" fn irq1() {
        push(11);
    }

    #[no_mangle]
    extern "C" fn irq2() {
        push(14);
    }

    #[no_mangle]
    extern "C" fn irq3() {
        push(13);
    }

    #[no_mangle]
    extern "C" fn svcall() {
        push(20);
    }

    #[no_mangle]
    extern "C" fn systick() {
        push(30);
        // SAFETY: SysTick off: one interrupt is enough.
        unsafe { write32(SYST_CSR, 0) };
    }

    #[no_mangle]
    extern "C" fn fault() -> ! {
        print(c"core-check: fault\n");
        idle()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
