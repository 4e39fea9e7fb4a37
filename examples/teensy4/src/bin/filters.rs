//! The Teensy 3 `filters` example's filter lists and frames (`filters_example`, the same
//! module) on CAN1 of a Teensy 4.0 / 4.1 in loop-back: every frame reaches the call-back
//! of its filter (ACAN §14 dispatch), 0x777 none. `HITS` counts per filter, `ERRORS`
//! frames that reached the wrong one or
//! none.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::sync::atomic::{AtomicU32, Ordering};

    use twocan_core::{Dispatcher, Frame, RxFrame};
    use twocan_flexcan::layout::Imxrt1062;
    use twocan_flexcan::pin::{settings_for, Pin22, Pin23};
    use twocan_flexcan::{BeginPlan, Can1};
    use twocan_teensy4::can::{CanState, TableSlot};
    use twocan_teensy4::configs::FILTERS as SETTINGS;
    use twocan_teensy4::filters_example::{self, FILTERS};
    use twocan_teensy4::rt::{self, CAN_HALT};
    use twocan_teensy4::time::{self, Every};

    static CAN1: CanState = CanState::new();
    /// CAN1's filter table (`begin_in` compiles the list straight into it).
    static TABLE1: TableSlot = TableSlot::new_sized();

    /// Frames each filter's call-back received.
    pub static HITS: [AtomicU32; FILTERS] = [const { AtomicU32::new(0) }; FILTERS];
    /// Frames that reached a call-back they do not belong to, or none.
    pub static ERRORS: AtomicU32 = AtomicU32::new(0);

    fn frames() -> [(Result<Frame, twocan_core::FrameError>, Option<usize>); 6] {
        filters_example::frames()
    }

    fn check(expected: usize, rx: &RxFrame) {
        let ok = rx.filter as usize == expected
            && frames()
                .iter()
                .any(|(f, i)| *i == Some(expected) && f.as_ref().ok() == Some(&rx.frame));
        HITS[expected].fetch_add(1, Ordering::Relaxed);
        if !ok {
            ERRORS.fetch_add(1, Ordering::Relaxed);
        }
    }

    fn on_0(_: &mut (), rx: &RxFrame) {
        check(0, rx)
    }
    fn on_1(_: &mut (), rx: &RxFrame) {
        check(1, rx)
    }
    fn on_2(_: &mut (), rx: &RxFrame) {
        check(2, rx)
    }
    fn on_3(_: &mut (), rx: &RxFrame) {
        check(3, rx)
    }
    fn on_4(_: &mut (), rx: &RxFrame) {
        check(4, rx)
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        let primary = filters_example::primary();
        let secondary = filters_example::secondary();
        let can = Can1::take().unwrap_or_else(|| rt::halt(CAN_HALT));
        let (mut tx, mut rx) = CAN1
            .start_in_place(
                can.target(),
                |hw| {
                    can.begin_in_place(
                        hw,
                        &const {
                            BeginPlan::<Imxrt1062>::new_with_layout_or_panic(
                                Can1::TARGET,
                                &settings_for(&SETTINGS, Pin22, Pin23),
                                SETTINGS.configuration,
                            )
                        },
                        &primary,
                        &secondary,
                        TABLE1.take().unwrap_or_else(|| rt::halt(CAN_HALT)),
                    )
                },
                &mut boot.core.NVIC,
            )
            .unwrap_or_else(|_| rt::halt(CAN_HALT));
        let mut dispatcher: Dispatcher<(), FILTERS> = Dispatcher::new();
        let callbacks: [fn(&mut (), &RxFrame); FILTERS] = [on_0, on_1, on_2, on_3, on_4];
        for (i, f) in callbacks.into_iter().enumerate() {
            if dispatcher.set(i, f).is_err() {
                rt::halt(CAN_HALT);
            }
        }
        let list = frames();
        let mut next = 0;
        let mut send = Every::new(time::millis(), 100);
        let mut unhandled_seen = 0;
        loop {
            if send.due(time::millis()) {
                if let (Ok(frame), _) = &list[next] {
                    if tx.try_send(frame).is_ok() {
                        next = (next + 1) % list.len();
                    }
                }
            }
            while tx.take_completion().is_some() {}
            while rx.dispatch(&mut dispatcher, &mut ()) {}
            let unhandled = dispatcher.unhandled();
            if unhandled > unhandled_seen {
                ERRORS.fetch_add(unhandled - unhandled_seen, Ordering::Relaxed);
                unhandled_seen = unhandled;
            }
            cortex_m::asm::wfi();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("teensy4-filters: {}", twocan_teensy4::HOST_NOTE);
}
