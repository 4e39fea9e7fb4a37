//! Primary and secondary filters with call-backs (ACAN manual §12–§14) on FlexCAN0, in
//! loop-back with self reception (no transceiver needed).
//!
//! Filters, numbered as ACAN numbers them (primary first, then secondary). A secondary
//! filter shares the global mask, so it must be exact or pass-all (ACAN §13.4): masked
//! filters are primary.
//! - #0 primary: standard data frames 0x300–0x30F (with a mask, ACAN §12.2);
//! - #1 primary: any extended data frame 0x18FF_xx00 (a masked extended filter);
//! - #2 primary: standard data frame 0x234;
//! - #3 secondary: extended data frame 0x123456 (ACAN §13.2);
//! - #4 secondary: standard remote frame 0x542.
//!
//! Every 100 ms the example sends the next frame of a list that hits each filter once and
//! one frame (0x777) that no filter accepts; each filter's call-back counts its frames
//! (`HITS`), `dispatch` hands frames to them by filter index. The LED toggles each time
//! a complete round arrived with the counts as expected; it stays still (and `ERRORS`
//! counts) when a frame reaches the wrong call-back or a rejected frame gets through.
//!
//! Blink codes when it stops: 2–4 clock start-up, 5 FlexCAN `begin`, 6 panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::sync::atomic::{AtomicU32, Ordering};

    use twocan_core::{Dispatcher, Frame, RxFrame};
    use twocan_flexcan::pin::{settings_for, Pin3, Pin4};
    use twocan_flexcan::{BeginPlan, Can0, Settings};
    use twocan_teensy::can::{CanState, TableSlot};
    use twocan_teensy::filters_example::{self, FILTERS};
    use twocan_teensy::rt::{self, CAN_BLINKS};
    use twocan_teensy::time::{self, Every};

    static CAN0: CanState = CanState::new();
    /// CAN0's filter table (`begin_in` compiles the list straight into it).
    static TABLE0: TableSlot = TableSlot::new();

    /// Frames per filter index.
    pub static HITS: [AtomicU32; FILTERS] = [const { AtomicU32::new(0) }; FILTERS];
    /// Frames that reached a call-back they do not belong to (frames of a filter without
    /// call-back are counted by the dispatcher).
    pub static ERRORS: AtomicU32 = AtomicU32::new(0);

    /// Computed at compile time (the bit-timing solver is `const`), so the solver is
    /// not in the image.
    const SETTINGS: Settings = filters_example::SETTINGS;

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
        let token = Can0::take().unwrap_or_else(|| rt::halt(CAN_BLINKS));
        let (mut tx, mut rx) = CAN0
            .start_in_place(
                token.target(),
                |hw| {
                    token.begin_in_place(
                        hw,
                        &const {
                            BeginPlan::new_or_panic(
                                Can0::TARGET,
                                &settings_for(&SETTINGS, Pin3, Pin4),
                                SETTINGS.configuration,
                            )
                        },
                        &primary,
                        &secondary,
                        TABLE0.take().unwrap_or_else(|| rt::halt(CAN_BLINKS)),
                    )
                },
                &mut boot.core.NVIC,
            )
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));

        let mut dispatcher: Dispatcher<(), FILTERS> = Dispatcher::new();
        let callbacks: [fn(&mut (), &RxFrame); FILTERS] = [on_0, on_1, on_2, on_3, on_4];
        for (i, f) in callbacks.into_iter().enumerate() {
            if dispatcher.set(i, f).is_err() {
                rt::halt(CAN_BLINKS);
            }
        }

        let list = frames();
        let mut next = 0;
        let mut send = Every::new(time::millis(), 100);
        let mut rounds_seen = 0;
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
            // A round is complete when every filter saw one more frame.
            let rounds = HITS
                .iter()
                .map(|h| h.load(Ordering::Relaxed))
                .min()
                .unwrap_or(0);
            let errors = ERRORS.load(Ordering::Relaxed) + dispatcher.unhandled();
            if rounds > rounds_seen && errors == 0 {
                rounds_seen = rounds;
                boot.led.toggle();
            }
            cortex_m::asm::wfi();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("teensy-filters: {}", twocan_teensy::HOST_NOTE);
}
