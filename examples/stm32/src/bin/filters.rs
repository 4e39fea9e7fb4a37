//! The bxCAN filter planner with both receive FIFOs, in loop-back mode (no transceiver).
//!
//! Six portable filters are compiled by `twocan_bxcan::planner` with
//! `FifoPolicy::Balanced`: the fewest filter banks (RM0008 §24.7.4, RM0390 §30.7.4 "Identifier
//! filtering": 32-/16-bit, mask/list banks), spread over FIFO 0 and FIFO 1 without
//! separating overlapping filters. Received frames come back with the user's filter
//! index (not the hardware's FMI) and `dispatch` hands them to one call-back per filter:
//! - #0, #1: standard frames 0x100 and 0x101 (an identifier list);
//! - #2: the standard remote frame 0x542;
//! - #3: standard data frames 0x300–0x30F (a mask);
//! - #4: the extended frame 0x123456;
//! - #5: extended data frames 0x18FF_xx00 (a mask).
//!
//! Every 100 ms the next frame of a list that hits each filter once, plus one (0x777)
//! that none accepts, is sent. `HITS` counts per filter, `ERRORS` counts frames at the
//! wrong call-back, `BANKS` how many banks each FIFO got. The LED toggles at each
//! complete, correct round.
//!
//! Blink codes when it stops: 5 bxCAN configuration, 6 panic.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::sync::atomic::{AtomicU32, Ordering};

    use twocan_bxcan::{const_plan, BxCan, FifoPolicy, Instance};
    use twocan_core::{Dispatcher, Filter, Format, Frame, FrameKind, RxFrame};
    use twocan_stm32::board::CAN1_BANKS;
    use twocan_stm32::can::{self, CanRxHalf, CanState, CanTxHalf};
    use twocan_stm32::rt::{self, CAN_BLINKS};
    use twocan_stm32::time::{self, Every};

    const FILTERS: usize = 6;

    static CAN1: CanState = CanState::new();
    twocan_stm32::can1_vectors!();

    /// Frames per filter index.
    pub static HITS: [AtomicU32; FILTERS] = [const { AtomicU32::new(0) }; FILTERS];
    /// Frames that reached a call-back they do not belong to.
    pub static ERRORS: AtomicU32 = AtomicU32::new(0);
    /// Filter banks of the plan assigned to FIFO 0 and FIFO 1.
    pub static BANKS: [AtomicU32; 2] = [const { AtomicU32::new(0) }; 2];

    const LIST: [Filter; FILTERS] = [
        Filter::exact(FrameKind::Data, Format::Standard, 0x100),
        Filter::exact(FrameKind::Data, Format::Standard, 0x101),
        Filter::exact(FrameKind::Remote, Format::Standard, 0x542),
        Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, 0x300),
        Filter::exact(FrameKind::Data, Format::Extended, 0x12_3456),
        Filter::masked(FrameKind::Data, Format::Extended, 0x1FFF_00FF, 0x18FF_0000),
    ];

    /// The frames sent, in order (the first six hit filters #0..#5, the last none).
    fn frames() -> [Result<Frame, twocan_core::FrameError>; 7] {
        [
            Frame::standard(0x100, &[0]),
            Frame::standard(0x101, &[1]),
            Frame::remote(0x542, false, 2),
            Frame::standard(0x30A, &[3; 3]),
            Frame::extended(0x12_3456, &[4; 4]),
            Frame::extended(0x18FF_5A00, &[5; 8]),
            Frame::standard(0x777, &[6]),
        ]
    }

    fn on_frame(_: &mut (), rx: &RxFrame) {
        let index = rx.filter as usize;
        if index < FILTERS {
            HITS[index].fetch_add(1, Ordering::Relaxed);
        }
        let expected = frames().get(index).and_then(|f| f.ok());
        if index >= FILTERS || expected.as_ref() != Some(&rx.frame) {
            ERRORS.fetch_add(1, Ordering::Relaxed);
        }
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut boot = rt::boot();
        // The hand-over from the board's HAL: CAN1's PAC singleton and pins by value
        // (`twocan_bxcan::hal::f1::can`, `hal::f4::can1`), its clock enabled; the bit
        // timing solved for the APB1 frequency of the HAL's clocks, for the board's part.
        let can1 = boot.can.can1();
        let config = can1
            .config(125_000)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS))
            .loopback(true);
        // The registers for the in-place constructor (nothing configured yet): the
        // controller is configured in place in `CAN1` (`BxCan::can1_in`), so no
        // controller, filter map or plan moves through `main`.
        let regs = can1
            .into_registers(&config)
            .unwrap_or_else(|_| rt::halt(CAN_BLINKS));
        // Planned at build time (`const_plan!`, see `stm32-loopback`).
        let plan = const_plan!(LIST, CAN1_BANKS.fifo(FifoPolicy::Balanced));
        for bank in plan.banks() {
            BANKS[bank.fifo.index()].fetch_add(1, Ordering::Relaxed);
        }
        let (tx, rx) = can::start(
            &CAN1,
            Instance::Can1,
            |slot| BxCan::can1_in(slot, regs, &config, plan).map_err(|f| f.error),
            rt::CAN1_IRQS,
            &mut boot.core.NVIC,
        )
        .unwrap_or_else(|| rt::halt(CAN_BLINKS));

        run(tx, rx, boot.led)
    }

    /// The application after the configuration, in a function of its own (not
    /// inlined): its state (the dispatcher, the frame list) takes stack only once the
    /// configuration is done.
    #[inline(never)]
    fn run(mut tx: CanTxHalf, mut rx: CanRxHalf, mut led: rt::Led) -> ! {
        let mut dispatcher: Dispatcher<(), FILTERS> = Dispatcher::new();
        for i in 0..FILTERS {
            if dispatcher.set(i, on_frame).is_err() {
                rt::halt(CAN_BLINKS);
            }
        }

        let list = frames();
        let mut next = 0;
        let mut send = Every::new(time::millis(), 100);
        let mut rounds_seen = 0;
        loop {
            if send.due(time::millis()) {
                if let Ok(frame) = &list[next] {
                    if tx.try_send(frame).is_ok() {
                        next = (next + 1) % list.len();
                    }
                }
            }
            while tx.take_completion().is_some() {}
            while rx.dispatch(&mut dispatcher, &mut ()) {}
            let rounds = HITS
                .iter()
                .map(|h| h.load(Ordering::Relaxed))
                .min()
                .unwrap_or(0);
            let errors = ERRORS.load(Ordering::Relaxed) + dispatcher.unhandled();
            if rounds > rounds_seen && errors == 0 {
                rounds_seen = rounds;
                led.toggle();
            }
            cortex_m::asm::wfi();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("stm32-filters: {}", twocan_stm32::HOST_NOTE);
}
