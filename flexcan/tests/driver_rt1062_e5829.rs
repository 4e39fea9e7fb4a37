//! The workaround of erratum ERR005829 (i.MX RT1060 chip errata: "FlexCAN does not
//! transmit a message that is enabled to be transmitted in a specific moment during the
//! arbitration process") with the RT1062 layout ([`Imxrt1062`], `Layout::E5829`): the
//! real driver over the FlexCAN model, its register writes traced through the
//! [`Registers`] seam.
//!
//! The model does not reproduce the erratum (`docs/models.md`, shared assumptions): these
//! tests show the workaround's writes and that it costs nothing else — the reserved
//! mailbox (the first valid one after the Rx FIFO area) is never loaded, reads INACTIVE,
//! is masked and lies inside `MCR[MAXMB]`; each transmit activation is followed by
//! exactly two INACTIVE writes into its control/status word; every accepted frame, data
//! and remote, completes exactly once and in order; aborts work; the mailbox count the
//! capabilities report is the one the driver uses. The default layout ([`Kinetis`])
//! writes none of it.

mod common;

use std::cell::RefCell;
use std::rc::Rc;

use common::*;
use twocan_core::{
    AbortRequest, Driver, FifoQueue, Filter, Frame, Hardware, Lean, MailboxId, MailboxState,
    Registers, State, Token, TxOutcome,
};
use twocan_flexcan::layout::{Imxrt1062, Kinetis, Layout};
use twocan_flexcan::options::Full;
use twocan_flexcan::regs::{self, code, cs, mcr};
use twocan_flexcan::{
    Board, CanClock, Configuration, FlexCan, FlexCanHw, HostSystem, Instance, Settings, Target,
};

/// The model's registers with every write recorded (offset, value), in order.
struct Traced {
    inner: Ticking,
    log: Log,
}

impl core::fmt::Debug for Traced {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Traced").finish_non_exhaustive()
    }
}

impl Registers for Traced {
    fn read32(&self, offset: usize) -> u32 {
        self.inner.read32(offset)
    }
    fn write32(&self, offset: usize, value: u32) {
        self.log.borrow_mut().push((offset, value));
        self.inner.write32(offset, value)
    }
}

type Rt<L> = Driver<FlexCanHw<Traced, Full<L>>, 32, 16>;

impl<L: Layout> Service for Rt<L> {
    fn service(&mut self) {
        if self.hardware().registers().inner.model().irq_pending() {
            self.on_interrupt();
        }
    }
}

const T41: Target = Target::new(Board::Teensy41, Instance::Can1);

/// RFFN 0, 3, 8, 0xB, 0xC and 0xF: ACAN's first and last, the two whose transmit
/// mailboxes jump to MB32 (8, 0xB), the first above MB31 and the largest.
const CONFIGURATIONS: [Configuration; 6] = [
    Configuration::Filters8_0,
    Configuration::Filters14_18,
    Configuration::Filters24_48,
    Configuration::Filters30_66,
    Configuration::Filters32_72,
    Configuration::Filters32_96,
];

fn settings(c: Configuration, loop_back: bool) -> Settings {
    let mut s = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
    s.configuration = c;
    s.loop_back = loop_back;
    s.self_reception = loop_back;
    s
}

/// The register writes, in order.
type Log = Rc<RefCell<Vec<(usize, u32)>>>;

/// `begin` with layout `L` over a fresh model of CAN1 whose message-buffer RAM holds
/// garbage, every write traced.
fn begin_traced<L: Layout>(
    c: Configuration,
    loop_back: bool,
) -> (twocan_flexcan::model::FlexCanModel, Log, Rt<L>) {
    let (model, log, controller) = begin_traced_with::<L>(c, loop_back, &[Filter::pass_all()]);
    (model, log, Driver::new(controller.into_split()))
}

/// [`begin_traced`]'s controller, not yet split, with the filter list `filters`.
fn begin_traced_with<L: Layout>(
    c: Configuration,
    loop_back: bool,
    filters: &[Filter],
) -> (twocan_flexcan::model::FlexCanModel, Log, FlexCan<Traced, L>) {
    let model = model_of(T41);
    model.scramble_ram(0x000E_5829);
    let log = Rc::new(RefCell::new(Vec::new()));
    let regs = Traced {
        inner: Ticking::new(model.clone()),
        log: log.clone(),
    };
    let controller = FlexCan::<_, L>::begin_with_layout(
        regs,
        &mut HostSystem::new(),
        T41,
        &settings(c, loop_back),
        filters,
        &[],
    )
    .unwrap_or_else(|e| panic!("{c:?}: {e:?}"));
    (model, log, controller)
}

fn code_of(model: &twocan_flexcan::model::FlexCanModel, mb: usize) -> u32 {
    cs::CODE.get(model.read32(regs::mb_cs(mb)))
}

/// The interrupt mask bit of `mb` (`IMASK1`, or `IMASK2` above MB31).
fn masked_in(model: &twocan_flexcan::model::FlexCanModel, mb: usize) -> bool {
    let (reg, bit) = if mb < 32 {
        (regs::IMASK1, mb)
    } else {
        (regs::IMASK2, mb - 32)
    };
    model.read32(reg) & 1 << bit != 0
}

/// The message-buffer word `offset` belongs to: (MB, word index 0 = C/S … 3).
fn mb_word(offset: usize) -> Option<(usize, usize)> {
    let first = regs::mb_cs(0);
    let end = regs::mb_cs(64);
    (first..end)
        .contains(&offset)
        .then(|| ((offset - first) / 16, (offset - first) % 16 / 4))
}

/// The transmit activations in `log` (a write of code DATA into the C/S word of one of
/// the mailboxes `tx`), each with the writes that follow it up to the next one.
fn activations(
    log: &[(usize, u32)],
    tx: core::ops::RangeInclusive<usize>,
) -> Vec<(usize, Vec<(usize, u32)>)> {
    let mut out: Vec<(usize, Vec<(usize, u32)>)> = Vec::new();
    for &(offset, value) in log {
        match mb_word(offset) {
            Some((mb, 0)) if tx.contains(&mb) && cs::CODE.get(value) == code::TX_DATA => {
                out.push((mb, Vec::new()));
            }
            _ => {
                if let Some((_, after)) = out.last_mut() {
                    after.push((offset, value));
                }
            }
        }
    }
    out
}

#[test]
fn the_reserved_mailbox_is_the_first_valid_one_inactive_masked_and_inside_maxmb() {
    for c in CONFIGURATIONS {
        let (model, _log, can) = begin_traced::<Imxrt1062>(c, true);
        let reserved = usize::from(c.reserved_mailbox());
        let (first, data) = (
            usize::from(Imxrt1062::first_remote_mailbox(c)),
            usize::from(Imxrt1062::data_mailbox(c)),
        );
        // The first message buffer after the FIFO and its table.
        assert_eq!(
            reserved,
            regs::rx_fifo_occupied_mbs(u32::from(c.rffn())),
            "{c:?}"
        );
        assert_eq!(Imxrt1062::reserved_mailbox(c), Some(c.reserved_mailbox()));
        assert!(reserved < first && first <= data, "{c:?}");
        let maxmb = mcr::MAXMB.get(model.read32(regs::MCR)) as usize;
        assert_eq!(maxmb, data, "{c:?}: MAXMB is the data mailbox");
        // INACTIVE (over the garbage `begin` found), interrupt masked — and so are the
        // buffers between it and MB32 when the transmit mailboxes start there.
        for mb in reserved..first {
            assert_eq!(code_of(&model, mb), code::TX_INACTIVE, "{c:?} MB{mb}");
            assert!(!masked_in(&model, mb), "{c:?} MB{mb}");
        }
        for mb in first..=data {
            assert!(masked_in(&model, mb), "{c:?} MB{mb}");
        }
        // What the driver reports is what it uses: the data mailbox and as many
        // remote-frame mailboxes as without the reservation.
        let count = 1 + c.remote_mailbox_count();
        assert_eq!(
            usize::from(can.hardware().mailbox_count()),
            usize::from(count)
        );
        assert_eq!(can.capabilities().tx_mailboxes, count, "{c:?}");
        assert_eq!(usize::from(count), data + 1 - first);
        // The timing rule counts the reserved buffer too (MAXMB + 1 buffers: 17
        // peripheral clocks per bit up to 32, 30 above; IMXRT1060RM "Arbitration and
        // matching timing").
        let clocks = can
            .capabilities()
            .peripheral_clock
            .map(|r| r.min_clocks_per_bit);
        let expected = if Imxrt1062::message_buffers_used(c) > 32 {
            30
        } else {
            17
        };
        assert_eq!(clocks, Some(expected), "{c:?}");
    }
}

#[test]
fn each_activation_is_followed_by_two_inactive_writes_and_every_frame_completes_once_in_order() {
    for c in CONFIGURATIONS {
        let (model, log, mut can) = begin_traced::<Imxrt1062>(c, true);
        let reserved = usize::from(c.reserved_mailbox());
        let tx = usize::from(Imxrt1062::first_remote_mailbox(c))
            ..=usize::from(Imxrt1062::data_mailbox(c));
        log.borrow_mut().clear();
        let mut bus = bus_with(500_000, &[&model]);
        // Data and remote frames through the queue, in request order.
        let frames: Vec<Frame> = (0..12u16)
            .map(|i| {
                if i % 3 == 2 {
                    remote(0x300 + u32::from(i), i % 2 == 0)
                } else {
                    std_data(0x100 + i, &[i as u8, 0xA5])
                }
            })
            .collect();
        let tokens: Vec<Token> = frames.iter().map(|f| can.try_send(f).unwrap()).collect();
        run(&mut bus, &mut [&mut can], 200 * frames.len() as u64 + 500);
        let got: Vec<Frame> = std::iter::from_fn(|| can.receive().ok())
            .map(|r| r.frame)
            .collect();
        assert_eq!(got, frames, "{c:?}: every frame, in order");
        let done: Vec<_> = std::iter::from_fn(|| can.take_completion()).collect();
        assert_eq!(
            done.iter().map(|d| d.token).collect::<Vec<_>>(),
            tokens,
            "{c:?}: one completion per frame, in order"
        );
        assert!(done.iter().all(|d| d.outcome == TxOutcome::Sent));
        // Remote frames straight into their mailboxes too (all at once).
        let n = c.remote_mailbox_count();
        let now: Vec<Token> = (0..n)
            .map(|i| {
                can.try_send_now(&remote(0x600 - u32::from(i), false))
                    .unwrap()
            })
            .collect();
        run(&mut bus, &mut [&mut can], 2_000);
        let mut seen: Vec<Token> = std::iter::from_fn(|| can.take_completion())
            .map(|d| {
                assert_eq!(d.outcome, TxOutcome::Sent);
                d.token
            })
            .collect();
        seen.sort_by_key(|t| t.0);
        assert_eq!(seen, now, "{c:?}: each remote frame once");
        assert_eq!(
            std::iter::from_fn(|| can.receive().ok()).count(),
            usize::from(n)
        );

        // The trace: one activation per frame, each followed at once by exactly two
        // INACTIVE writes into the reserved mailbox's C/S word.
        let log = log.borrow();
        let acts = activations(&log, tx.clone());
        assert_eq!(acts.len(), frames.len() + usize::from(n), "{c:?}");
        let inactive = cs::CODE.val(code::TX_INACTIVE);
        let pair = [(regs::mb_cs(reserved), inactive); 2];
        for (mb, after) in &acts {
            assert!(tx.contains(mb));
            assert_eq!(after.get(..2), Some(&pair[..]), "{c:?}: after MB{mb}");
            assert_ne!(
                after.get(2).map(|w| w.0),
                Some(regs::mb_cs(reserved)),
                "{c:?}: exactly two"
            );
        }
        // The reserved mailbox is never loaded: only those INACTIVE writes reach it.
        let to_reserved: Vec<&(usize, u32)> = log
            .iter()
            .filter(|(o, _)| mb_word(*o).map(|w| w.0) == Some(reserved))
            .collect();
        assert_eq!(to_reserved.len(), 2 * acts.len(), "{c:?}");
        assert!(to_reserved.iter().all(|w| **w == pair[0]));
        // ... and reads INACTIVE after the traffic, its flag never raised.
        assert_eq!(code_of(&model, reserved), code::TX_INACTIVE, "{c:?}");
        let flags =
            u64::from(model.read32(regs::IFLAG1)) | u64::from(model.read32(regs::IFLAG2)) << 32;
        assert_eq!(flags & 1 << reserved, 0, "{c:?}");
    }
}

#[test]
fn aborts_work_beside_the_reserved_mailbox() {
    for c in [Configuration::Filters8_0, Configuration::Filters32_72] {
        // Normal mode, alone on the bus: nothing leaves the mailboxes.
        let (model, log, mut can) = begin_traced::<Imxrt1062>(c, false);
        let reserved = usize::from(c.reserved_mailbox());
        let data = can.try_send(&std_data(0x123, &[1])).unwrap();
        let rtr = can.try_send_now(&remote(0x42, false)).unwrap();
        assert_eq!(can.mailbox_state(MailboxId(0)), MailboxState::Pending);
        assert_eq!(can.mailbox_state(MailboxId(1)), MailboxState::Pending);
        assert_eq!(can.abort(data), AbortRequest::Requested);
        assert_eq!(can.abort(rtr), AbortRequest::Requested);
        can.on_interrupt();
        let done: Vec<_> = std::iter::from_fn(|| can.take_completion())
            .map(|d| (d.token, d.outcome))
            .collect();
        assert_eq!(
            done,
            vec![(data, TxOutcome::Aborted), (rtr, TxOutcome::Aborted)],
            "{c:?}"
        );
        for m in 0..can.hardware().mailbox_count() {
            assert_eq!(can.mailbox_state(MailboxId(m)), MailboxState::Empty);
        }
        // The aborts wrote nothing into the reserved mailbox; it stays INACTIVE.
        assert_eq!(code_of(&model, reserved), code::TX_INACTIVE);
        let before = log.borrow().len();
        // The data mailbox is usable again, with the workaround's two writes.
        can.try_send(&std_data(0x124, &[])).unwrap();
        assert_eq!(can.mailbox_state(MailboxId(0)), MailboxState::Pending);
        let log = log.borrow();
        let tail = &log[before..];
        let inactive = cs::CODE.val(code::TX_INACTIVE);
        assert_eq!(
            &tail[tail.len() - 3..],
            &[
                (
                    regs::mb_cs(usize::from(Imxrt1062::data_mailbox(c))),
                    tail[tail.len() - 3].1
                ),
                (regs::mb_cs(reserved), inactive),
                (regs::mb_cs(reserved), inactive),
            ],
            "{c:?}"
        );
        assert_eq!(cs::CODE.get(tail[tail.len() - 3].1), code::TX_DATA);
    }
}

/// `end` leaves the reserved mailbox INACTIVE, and `begin` again on the same registers
/// finds it so (and rewrites it).
#[test]
fn end_and_begin_leave_the_reserved_mailbox_inactive() {
    let c = Configuration::Filters32_96;
    let (model, _log, mut can) = begin_traced::<Imxrt1062>(c, true);
    let mut bus = bus_with(500_000, &[&model]);
    can.try_send(&std_data(0x55, &[5])).unwrap();
    run(&mut bus, &mut [&mut can], 500);
    assert_eq!(
        can.take_completion().map(|d| d.outcome),
        Some(TxOutcome::Sent)
    );
    let hw = can.release();
    let (regs, _table) = hw.end(&mut HostSystem::new()).map_err(|(_, e)| e).unwrap();
    assert_eq!(code_of(&model, 38), code::TX_INACTIVE);
    let c = Configuration::Filters14_18;
    let controller = FlexCan::<_, Imxrt1062>::begin_with_layout(
        regs,
        &mut HostSystem::new(),
        T41,
        &settings(c, true),
        &[Filter::pass_all()],
        &[],
    )
    .unwrap();
    // RFFN 3: MB14 reserved, MB15 remote, MB16 data; MB38 is beyond MAXMB now.
    assert_eq!(code_of(&model, 14), code::TX_INACTIVE);
    assert_eq!(mcr::MAXMB.get(model.read32(regs::MCR)), 16);
    let mut can: Rt<Imxrt1062> = Driver::new(controller.into_split());
    let token = can.try_send(&remote(0x77, false)).unwrap();
    run(&mut bus, &mut [&mut can], 500);
    let d = can.take_completion().unwrap();
    assert_eq!((d.token, d.outcome), (token, TxOutcome::Sent));
    assert_eq!(code_of(&model, 14), code::TX_INACTIVE);
}

/// The default layout has no reserved mailbox (its first remote-frame mailbox is the
/// first valid one, MB8 at RFFN 0), so it is not the RT1062's: `begin` refuses it on a
/// Teensy 4 module with a typed error, before any register write.
#[test]
fn the_kinetis_layout_is_refused_on_the_rt1062() {
    let c = Configuration::Filters8_0;
    assert_eq!(Kinetis::reserved_mailbox(c), None);
    let model = model_of(T41);
    let log = Rc::new(RefCell::new(Vec::new()));
    let regs = Traced {
        inner: Ticking::new(model.clone()),
        log: log.clone(),
    };
    let mut sys = HostSystem::new();
    let e = FlexCan::<_, Kinetis>::begin_with_layout(
        regs,
        &mut sys,
        T41,
        &settings(c, true),
        &[Filter::pass_all()],
        &[],
    )
    .map(|_| ())
    .unwrap_err();
    assert_eq!(
        e,
        twocan_flexcan::BeginError::Config(twocan_flexcan::ConfigErrors::LAYOUT_NOT_FOR_CHIP)
    );
    assert!(log.borrow().is_empty(), "no register written");
    assert!(sys.written().is_empty());
}

/// The split driver in the quiet transmit mode over the traced RT1062 layout: no
/// completion ring, `Lean`, request order.
type QuietState = State<QuietHw, 32, FifoQueue<8>, 0, 0, Lean>;
/// The controller [`QuietState`] holds.
type QuietHw = FlexCanHw<Traced, Full<Imxrt1062>>;

/// The message-buffer line as `rt_imxrt` runs it (transmit handler, then the Rx FIFO's),
/// counting the entries.
struct QuietLine {
    model: twocan_flexcan::model::FlexCanModel,
    tx_irq: twocan_core::split::TxIrq<'static, QuietHw, 32, FifoQueue<8>, 0, 0, Lean>,
    rx_irq: twocan_core::split::Rx0Irq<'static, QuietHw, 32, FifoQueue<8>, 0, 0, Lean>,
    entries: usize,
}

impl Service for QuietLine {
    fn service(&mut self) {
        if self.model.irq_pending() {
            self.entries += 1;
            self.tx_irq.on_interrupt();
            self.rx_irq.on_interrupt();
        }
    }
}

/// In the quiet transmit mode the data mailbox is loaded again while the end of its last
/// frame is not acknowledged (no transmit interrupt ran: its flag is still set). Each
/// such load clears the flag first (Kinetis RM / IMXRT1060RM, "Transmit process", step
/// 1: the write just before the identifier word), and each activation — direct or from
/// the queue, data or remote — is still followed at once by exactly the two INACTIVE
/// writes of the ERR005829 workaround. A direct send raises no interrupt; frames that
/// had to queue are refilled from the interrupt, whose data-mailbox enable is off again
/// once the queue is empty.
#[test]
fn the_quiet_mode_clears_the_flag_before_each_activation_and_keeps_the_e5829_writes() {
    use twocan_core::{Format, FrameKind};
    const { assert!(QuietState::QUIET_TX) };
    for c in [
        Configuration::Filters8_0,
        Configuration::Filters24_48,
        Configuration::Filters32_96,
    ] {
        // Loop-back; the filter takes 0x200–0x2FF only, so the direct frames (0x1xx)
        // raise no Rx FIFO interrupt either.
        let accept = Filter::masked(FrameKind::Data, Format::Standard, 0x700, 0x200);
        let (model, log, controller) = begin_traced_with::<Imxrt1062>(c, true, &[accept]);
        let reserved = usize::from(c.reserved_mailbox());
        let data = usize::from(Imxrt1062::data_mailbox(c));
        let tx = usize::from(Imxrt1062::first_remote_mailbox(c))..=data;
        let (flags, mask, bit) = if data < 32 {
            (regs::IFLAG1, regs::IMASK1, 1u32 << data)
        } else {
            (regs::IFLAG2, regs::IMASK2, 1u32 << (data - 32))
        };
        let state: &'static QuietState = Box::leak(Box::new(State::new()));
        let parts = state
            .split(controller.into_split())
            .map_err(|(e, _)| e)
            .unwrap();
        let mut tx_half = parts.tx;
        let mut rx_half = parts.rx;
        let mut line = QuietLine {
            model: model.clone(),
            tx_irq: parts.tx_irq,
            rx_irq: parts.rx0_irq,
            entries: 0,
        };
        assert_eq!(
            model.read32(mask) & bit,
            0,
            "{c:?}: split with the data mailbox's interrupt off"
        );
        log.borrow_mut().clear();
        let mut bus = bus_with(500_000, &[&model]);

        // Direct sends, the bus idle in between: no interrupt, the end never acknowledged.
        for k in 0..4u8 {
            tx_half
                .try_send(&std_data(0x100 + u16::from(k), &[k]))
                .unwrap();
            run(&mut bus, &mut [&mut line], 300);
            assert_eq!(line.entries, 0, "{c:?}: frame {k} raised an interrupt");
            assert_ne!(
                model.read32(flags) & bit,
                0,
                "{c:?}: frame {k} ended, not acknowledged"
            );
            assert_eq!(code_of(&model, data), code::TX_INACTIVE);
        }
        // A remote frame straight into its mailbox (its interrupt stays on: it is made
        // inactive again), then a burst through the queue.
        tx_half.try_send_now(&remote(0x2F0, false)).unwrap();
        let burst: Vec<Frame> = (0..8u16).map(|i| std_data(0x200 + i, &[i as u8])).collect();
        for f in &burst {
            tx_half.try_send(f).unwrap();
        }
        assert_ne!(
            model.read32(mask) & bit,
            0,
            "{c:?}: frames wait: the interrupt is on"
        );
        run(&mut bus, &mut [&mut line], 300 * 12);
        assert!(line.entries > 0);
        assert_eq!(tx_half.stats().count, 0);
        assert_eq!(
            model.read32(mask) & bit,
            0,
            "{c:?}: queue empty: the interrupt is off"
        );
        let got: Vec<Frame> = std::iter::from_fn(|| rx_half.receive().ok())
            .map(|r| r.frame)
            .collect();
        assert_eq!(got, burst, "{c:?}: the burst, in order");

        // The trace: the data mailbox's flag cleared right before each of its loads (the
        // write before the identifier word), two INACTIVE writes after each activation.
        let log = log.borrow();
        let acts = activations(&log, tx.clone());
        assert_eq!(acts.len(), 4 + 1 + burst.len(), "{c:?}");
        let inactive = cs::CODE.val(code::TX_INACTIVE);
        let pair = [(regs::mb_cs(reserved), inactive); 2];
        for (mb, after) in &acts {
            assert_eq!(after.get(..2), Some(&pair[..]), "{c:?}: after MB{mb}");
            assert_ne!(after.get(2).map(|w| w.0), Some(regs::mb_cs(reserved)));
        }
        let mut loads = 0;
        for (i, &(offset, _)) in log.iter().enumerate() {
            if offset == regs::mb_id(data) {
                loads += 1;
                assert_eq!(
                    log[i - 1],
                    (flags, bit),
                    "{c:?}: the data mailbox's flag cleared before load {loads}"
                );
            }
        }
        assert_eq!(loads, 4 + burst.len(), "{c:?}");
        assert_eq!(code_of(&model, reserved), code::TX_INACTIVE, "{c:?}");
    }
}

/// `unsplit` leaves the controller as a driver with completions expects it: the end the
/// quiet mode left unacknowledged is acknowledged (its flag clear, so the next driver
/// reports no completion for it) and the interrupt masks are `begin`'s again (the data
/// mailbox's enable back on). A driver with completions over it then reports exactly
/// its own frame.
#[test]
fn unsplit_after_the_quiet_mode_gives_back_the_masks_and_no_stale_end() {
    for c in [Configuration::Filters8_0, Configuration::Filters24_48] {
        let (model, _log, controller) =
            begin_traced_with::<Imxrt1062>(c, true, &[Filter::pass_all()]);
        let data = usize::from(Imxrt1062::data_mailbox(c));
        let (flags, bit) = if data < 32 {
            (regs::IFLAG1, 1u32 << data)
        } else {
            (regs::IFLAG2, 1u32 << (data - 32))
        };
        let masks = (model.read32(regs::IMASK1), model.read32(regs::IMASK2));
        let state: &'static QuietState = Box::leak(Box::new(State::new()));
        let mut parts = state
            .split(controller.into_split())
            .map_err(|(e, _)| e)
            .unwrap();
        assert_ne!(
            (model.read32(regs::IMASK1), model.read32(regs::IMASK2)),
            masks
        );
        let mut bus = bus_with(500_000, &[&model]);
        parts.tx.try_send(&std_data(0x300, &[3])).unwrap();
        // The bus alone (the frame comes back through the Rx FIFO; no handler runs).
        bus.run_bits(300);
        assert_ne!(
            model.read32(flags) & bit,
            0,
            "{c:?}: ended, not acknowledged"
        );
        let (hw, left) = state.unsplit(parts).map_err(|(e, _)| e).unwrap();
        assert_eq!(left.completions, 0);
        assert_eq!(
            model.read32(flags) & bit,
            0,
            "{c:?}: acknowledged by unsplit"
        );
        assert_eq!(
            (model.read32(regs::IMASK1), model.read32(regs::IMASK2)),
            masks,
            "{c:?}: begin's masks"
        );
        let mut can: Rt<Imxrt1062> = Driver::new(hw.into_controller().into_split());
        let token = can.try_send(&std_data(0x301, &[4])).unwrap();
        run(&mut bus, &mut [&mut can], 500);
        let done: Vec<_> = std::iter::from_fn(|| can.take_completion())
            .map(|d| (d.token, d.outcome))
            .collect();
        assert_eq!(done, vec![(token, TxOutcome::Sent)], "{c:?}");
    }
}
