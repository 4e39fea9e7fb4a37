//! Issue 6, item 2: one conformance suite, run on both controllers.
//!
//! Every test is a generic function over [`Backend`] (FlexCAN can0 of a Teensy 3.6, FlexCAN
//! CAN3 of a Teensy 4.1 (i.MX RT1062, issue 24) and bxCAN CAN1 of an STM32F767, each the
//! real driver over its peripheral model on the simulated bus); the `suite!` macro at the
//! end instantiates each for the three. The other
//! side of the bus is a plain ISO node ([`SimNode`]), which counts on its own what it sent
//! and received. Expected values come from the CAN rules (ISO 11898-1 counters, frame
//! format), from the hardware manuals (FIFO depth, filter capacity) or from a hand-written
//! table cross-checked with the reference filter semantics — never from the drivers.

use twocan_core::timestamp::{bit_times_to_micros, COUNTER_PERIOD};
use twocan_core::timing::{cia_sample_point, Limits, Timing, TimingError};
use twocan_core::{
    BusMode, BusOffRecovery, Error, ErrorCounters, ErrorState, Filter, FilterError, Format, Frame,
    FrameError, FrameKind, Hardware, LastErrorCode, Mode, Timestamp,
};
use twocan_host::Harness;
use twocan_sim::{Fault, NodeId, Receivers, SimNode};
use twocan_tests::backend::{
    harness_at, Backend, BxCanBackend, Dut, FlexCanBackend, ManualRecoveryCount, NodeOptions,
    Recovery, Refused, Rt1062Backend, TimingRefused,
};
use twocan_tests::support::{
    attach_peer, attach_sim, bytes, drain, ext_frame, first_match, frame_zoo, remote_frame, run,
    settle, std_frame, Peer,
};

const RATE: u32 = 500_000;

fn setup<B: Backend>(opts: &NodeOptions) -> (Harness, B::Node, Peer) {
    let (h, dut, peer, _) = setup_with_id::<B>(opts);
    (h, dut, peer)
}

fn setup_with_id<B: Backend>(opts: &NodeOptions) -> (Harness, B::Node, Peer, NodeId) {
    let mut h = Harness::new(RATE).unwrap();
    let dut = B::attach(&mut h, opts).unwrap_or_else(|e| panic!("{}: {e:?}", B::NAME));
    let (peer, id) = attach_peer(&h, "peer");
    // A little idle bus before traffic. Not needed for synchronisation: both drivers
    // return from start-up on the bus (FlexCAN waits for `ESR1.SYNCH`, bxCAN for `INAK`
    // to clear; `flexcan_is_on_the_bus_when_set_mode_returns` and its bxCAN twin check it).
    let mut dut = dut;
    run(&mut h, &mut dut, 20);
    (h, dut, peer, id)
}

// ---------------------------------------------------------------------------------------

fn data_frames_both_ways<B: Backend>() {
    let (mut h, mut dut, peer) = setup::<B>(&NodeOptions::pass_all());
    let frames: Vec<Frame> = frame_zoo().into_iter().filter(|f| !f.is_remote()).collect();
    assert!(frames.len() > 16);
    // Out: in the order handed to try_send (both backends are set up for FIFO order).
    for f in &frames {
        dut.driver().try_send(f).unwrap();
    }
    settle(&mut h, &mut dut, &[&peer], 100_000);
    assert_eq!(peer.borrow().received_frames(), frames, "{}", B::NAME);
    let t = dut.driver_ref().traffic();
    assert_eq!(
        (t.queued, t.sent),
        (frames.len() as u32, frames.len() as u32)
    );
    // In: every identifier, format, DLC and byte intact, in order, filter 0.
    for f in &frames {
        peer.borrow_mut().send(*f);
    }
    settle(&mut h, &mut dut, &[&peer], 100_000);
    let got = drain(&mut dut);
    assert_eq!(
        got.iter().map(|r| r.frame).collect::<Vec<_>>(),
        frames,
        "{}",
        B::NAME
    );
    assert!(got.iter().all(|r| r.filter == 0));
    for (r, f) in got.iter().zip(&frames) {
        assert_eq!(r.frame.data(), f.data());
        assert_eq!(r.frame.is_extended(), f.is_extended());
    }
    assert_eq!(dut.hw_lost(), 0);
    assert_eq!(dut.driver_ref().traffic().received, frames.len() as u32);
}

fn remote_frames_both_ways<B: Backend>() {
    let (mut h, mut dut, peer) = setup::<B>(&NodeOptions::pass_all());
    let remotes: Vec<Frame> = frame_zoo().into_iter().filter(|f| f.is_remote()).collect();
    assert_eq!(remotes.len(), 18);
    // Out, one at a time (FlexCAN sends remote frames from their own mailboxes, which
    // compete by identifier: ACAN keeps no order between them).
    for f in &remotes {
        dut.driver().try_send(f).unwrap();
        settle(&mut h, &mut dut, &[&peer], 20_000);
    }
    let seen = peer.borrow().received_frames();
    assert_eq!(seen, remotes, "{}", B::NAME);
    assert!(seen.iter().all(|f| f.is_remote() && f.data().is_empty()));
    // In: the DLC of the request comes through, no data.
    for f in &remotes {
        peer.borrow_mut().send(*f);
    }
    settle(&mut h, &mut dut, &[&peer], 100_000);
    let got: Vec<Frame> = drain(&mut dut).iter().map(|r| r.frame).collect();
    assert_eq!(got, remotes, "{}", B::NAME);
    for (g, f) in got.iter().zip(&remotes) {
        assert!(g.is_remote());
        assert_eq!(g.dlc(), f.dlc());
        assert!(g.data().is_empty());
    }
}

/// Issue 17: a DLC code of 9..=15 is kept as written (ISO 11898-1: eight data bytes).
/// The driver writes the code into its mailbox, the model sends it in the four DLC bits,
/// the plain ISO node sees it; and a code the node sends comes back out of the driver.
fn dlc_codes_above_eight_both_ways<B: Backend>() {
    let (mut h, mut dut, peer) = setup::<B>(&NodeOptions::pass_all());
    let eight = [0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88];
    let mut twelve = ext_frame(0x1234_5678, &eight);
    twelve.set_dlc(12).unwrap();
    dut.driver().try_send(&twelve).unwrap();
    settle(&mut h, &mut dut, &[&peer], 20_000);
    let seen = peer.borrow().received_frames();
    assert_eq!(seen.len(), 1, "{}", B::NAME);
    assert_eq!(
        (seen[0].dlc(), seen[0].data()),
        (12, &eight[..]),
        "{}",
        B::NAME
    );
    assert_eq!(seen[0], twelve);
    // In: DLC 15 on a standard data frame, DLC 9 on an extended one, DLC 13 on a
    // remote frame (it asks for 8 bytes).
    let mut fifteen = std_frame(0x321, &eight);
    fifteen.set_dlc(15).unwrap();
    let mut nine = ext_frame(0x1ABC_DEF0, &[1, 2, 3, 4, 5, 6, 7, 8]);
    nine.set_dlc(9).unwrap();
    let mut remote = remote_frame(0x55, false, 8);
    remote.set_dlc(13).unwrap();
    let sent = [fifteen, nine, remote];
    for f in &sent {
        peer.borrow_mut().send(*f);
    }
    settle(&mut h, &mut dut, &[&peer], 50_000);
    let got: Vec<Frame> = drain(&mut dut).iter().map(|r| r.frame).collect();
    assert_eq!(got, sent, "{}", B::NAME);
    assert_eq!(
        got.iter()
            .map(|f| (f.dlc(), f.data().len()))
            .collect::<Vec<_>>(),
        [(15, 8), (9, 8), (13, 0)],
        "{}",
        B::NAME
    );
    assert_eq!(dut.hw_lost(), 0);
}

/// The filter list of the filter tests: exact and masked, both formats, data, remote and
/// any kind, with an overlap (filter 5 contains 0x123 of filter 0).
fn filter_list() -> Vec<Filter> {
    vec![
        Filter::standard(0x123),
        Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, 0x340),
        Filter::extended(0x0123_4567),
        Filter::masked(FrameKind::Any, Format::Extended, 0x1FFF_FF00, 0x0ABC_DE00),
        Filter::exact(FrameKind::Remote, Format::Standard, 0x555),
        Filter::masked(FrameKind::Data, Format::Standard, 0x700, 0x100),
    ]
}

/// Frames sent at [`filter_list`] with the filter that must take each (first match in
/// list order), written by hand from the filter definitions.
fn filter_cases() -> Vec<(Frame, Option<u16>)> {
    vec![
        (std_frame(0x123, &[1]), Some(0)),
        (remote_frame(0x123, false, 1), None), // data-only filters refuse remote frames
        (ext_frame(0x123, &[2]), None),        // wrong format
        (std_frame(0x124, &[3]), Some(5)),     // 0x124 & 0x700 == 0x100
        (std_frame(0x223, &[4]), None),
        (std_frame(0x340, &[5]), Some(1)),
        (std_frame(0x34F, &[6, 6]), Some(1)),
        (std_frame(0x350, &[7]), None),
        (std_frame(0x33F, &[8]), None),
        (remote_frame(0x345, false, 2), None),
        (ext_frame(0x0123_4567, &bytes(8, 9)), Some(2)),
        (ext_frame(0x0123_4566, &[10]), None),
        (remote_frame(0x0123_4567, true, 8), None),
        (std_frame(0x567, &[11]), None),
        (ext_frame(0x0ABC_DE00, &[12]), Some(3)),
        (ext_frame(0x0ABC_DEFF, &[13]), Some(3)),
        (remote_frame(0x0ABC_DE42, true, 3), Some(3)),
        (ext_frame(0x0ABC_DF00, &[14]), None),
        (std_frame(0x0DE, &[15]), None),
        (remote_frame(0x555, false, 0), Some(4)),
        (std_frame(0x555, &[16]), None), // remote-only filter refuses data frames
        (remote_frame(0x555, true, 0), None),
        (std_frame(0x1FF, &[17]), Some(5)),
        (std_frame(0x200, &[18]), None),
    ]
}

/// Sends `cases` from the peer and gives what the node received, with filter indices,
/// and how many frames its hardware refused. The application drains the receive ring
/// as it goes (every 100 bit times).
fn run_cases<N: Dut>(
    h: &mut Harness,
    dut: &mut N,
    peer: &Peer,
    cases: &[(Frame, Option<u16>)],
) -> (Vec<(Frame, u16)>, u64) {
    let refused_before = dut.filtered_out();
    for (f, _) in cases {
        peer.borrow_mut().send(*f);
    }
    let mut got = Vec::new();
    let end = h.now() + 200_000;
    while h.now() < end && peer.borrow().pending() > 0 {
        run(h, dut, 100);
        got.extend(drain(dut).iter().map(|r| (r.frame, r.filter)));
    }
    run(h, dut, 200);
    got.extend(drain(dut).iter().map(|r| (r.frame, r.filter)));
    assert_eq!(dut.driver_ref().traffic().rx_ring_overflows, 0);
    assert_eq!(dut.hw_lost(), 0);
    (got, dut.filtered_out() - refused_before)
}

fn expected_cases(cases: &[(Frame, Option<u16>)]) -> (Vec<(Frame, u16)>, u64) {
    let accepted = cases
        .iter()
        .filter_map(|(f, i)| i.map(|i| (*f, i)))
        .collect();
    let refused = cases.iter().filter(|(_, i)| i.is_none()).count() as u64;
    (accepted, refused)
}

fn filters_accept_exactly_their_frames<B: Backend>() {
    let filters = filter_list();
    let cases = filter_cases();
    // The table agrees with the reference semantics (Filter::matches, first match).
    for (f, i) in &cases {
        assert_eq!(first_match(&filters, f), *i, "{f:?}");
    }
    let (mut h, mut dut, peer) = setup::<B>(&NodeOptions::filters(&filters));
    let got = run_cases(&mut h, &mut dut, &peer, &cases);
    assert_eq!(got, expected_cases(&cases), "{}", B::NAME);
    // The peer's frames were all acknowledged (by the node under test: refusing a frame
    // in the filters does not refuse it on the bus).
    assert_eq!(peer.borrow().pending(), 0);
}

fn invalid_filters_are_refused<B: Backend>() {
    let bad = [
        (Filter::standard(0x800), FilterError::IdOutOfRange),
        (
            Filter::masked(FrameKind::Data, Format::Standard, 0x7F0, 0x001),
            FilterError::AcceptanceOutsideMask,
        ),
        (
            Filter::masked(FrameKind::Data, Format::Extended, 0x3FFF_FFFF, 0),
            FilterError::MaskOutOfRange,
        ),
        (
            Filter::masked(FrameKind::Any, Format::Any, 1, 1),
            FilterError::AnyFormatWithIdentifier,
        ),
    ];
    for (f, why) in bad {
        assert_eq!(f.check(), Err(why));
        let list = [Filter::standard(0x10), Filter::extended(0x20), f];
        let mut h = Harness::new(RATE).unwrap();
        match B::attach(&mut h, &NodeOptions::filters(&list)) {
            Err(Refused::FilterNotConform { index }) => {
                assert!(
                    index.is_none() || index == Some(2),
                    "{}: {index:?}",
                    B::NAME
                )
            }
            Err(e) => panic!("{}: {f:?}: {e:?}", B::NAME),
            Ok(_) => panic!("{}: {f:?} accepted", B::NAME),
        }
    }
}

fn filter_capacity<B: Backend>() {
    let n = B::MAX_EXACT_STD_FILTERS;
    // Identifiers 3 apart: no two differ in one bit only, so no planner can merge them
    // into masks, and each takes its own hardware entry.
    let id = |i: usize| 0x100 + 3 * i as u16;
    let filters: Vec<Filter> = (0..n).map(|i| Filter::standard(id(i))).collect();
    let (mut h, mut dut, peer) = setup::<B>(&NodeOptions::filters(&filters));
    // Every one of them is live and reports its own index; others are refused.
    let mut cases: Vec<(Frame, Option<u16>)> = (0..n)
        .rev()
        .map(|i| (std_frame(id(i), &[i as u8]), Some(i as u16)))
        .collect();
    cases.push((std_frame(id(n), &[]), None));
    cases.push((std_frame(0x0FF, &[]), None));
    cases.push((remote_frame(0x100, false, 0), None));
    let (got, refused) = run_cases(&mut h, &mut dut, &peer, &cases);
    let (want, want_refused) = expected_cases(&cases);
    for (k, (g, w)) in got.iter().zip(&want).enumerate() {
        assert_eq!(g, w, "{}: frame {k}", B::NAME);
    }
    assert_eq!(
        (got.len(), refused),
        (want.len(), want_refused),
        "{}",
        B::NAME
    );
    // One more does not fit: a typed error, not a silently dropped filter.
    let more: Vec<Filter> = (0..=n).map(|i| Filter::standard(id(i))).collect();
    let mut h = Harness::new(RATE).unwrap();
    assert_eq!(
        B::attach(&mut h, &NodeOptions::filters(&more)).err(),
        Some(Refused::TooManyFilters),
        "{}",
        B::NAME
    );
}

fn bit_rate_limits<B: Backend>() {
    // The fastest and the slowest rates the backend accepts (hardware facts, the
    // backend's constants) are accepted as a wished rate; one bit per second beyond, and
    // twice or half of them, are refused with the same error on both backends (FlexCAN:
    // the fastest is the Kinetis manual's, 16 bus clocks per bit; 2 Mbit/s, 8 quanta,
    // is beyond it from the default 16 MHz bus clock; ACAN's 3.2 Mbit/s, 5 quanta,
    // further still).
    let fastest = B::FASTEST_BITRATE;
    assert_eq!(B::check_timing(fastest, 750), Ok(fastest), "{}", B::NAME);
    let five_quanta = B::CLOCK_HZ / 5; // ACAN's fastest on FlexCAN; in range on bxCAN
    for beyond in [fastest + 1, 2 * fastest, five_quanta]
        .into_iter()
        .filter(|&r| r > fastest)
    {
        assert_eq!(
            B::check_timing(beyond, 750),
            Err(TimingRefused::TooHigh),
            "{} {beyond}",
            B::NAME
        );
    }
    let slowest = B::SLOWEST_BITRATE;
    assert_eq!(B::check_timing(slowest, 875), Ok(slowest), "{}", B::NAME);
    for below in [slowest - 1, slowest / 2] {
        assert_eq!(
            B::check_timing(below, 875),
            Err(TimingRefused::TooLow),
            "{} {below}",
            B::NAME
        );
    }
    assert_eq!(B::check_timing(0, 750), Err(TimingRefused::Zero));
    // The sample point must lie strictly between 50 % and 100 % of the bit.
    for sp in [0, 500, 1000, 1200] {
        assert_eq!(
            B::check_timing(500_000, sp),
            Err(TimingRefused::SamplePoint),
            "{} {sp}",
            B::NAME
        );
    }
    // The usual rates are exact from both clocks.
    for rate in [125_000, 250_000, 500_000, 1_000_000] {
        assert_eq!(B::check_timing(rate, 875), Ok(rate), "{} {rate}", B::NAME);
    }
}

/// Steps the bus one event at a time, servicing the node, until `done` or `max_bits`;
/// gives (TEC, REC, state) after every event that changed them.
fn watch<N: Dut>(
    h: &mut Harness,
    dut: &mut N,
    max_bits: u64,
    mut done: impl FnMut(&mut N) -> bool,
) -> Vec<(u16, u16, ErrorState)> {
    let end = h.now() + max_bits;
    let c = dut.driver_ref().counters();
    let mut seen = vec![(c.tec, c.rec, dut.driver().state())];
    while h.now() < end && !done(dut) {
        run(h, dut, 1);
        let c = dut.driver_ref().counters();
        if std::env::var("DBG").is_ok() {
            eprintln!("{} {:?}", h.now(), c);
        }
        let s = dut.driver().state();
        if seen.last() != Some(&(c.tec, c.rec, s)) {
            seen.push((c.tec, c.rec, s));
        }
    }
    seen
}

fn state_and_counters_follow_iso_rules<B: Backend>() {
    let (mut h, mut dut, peer, peer_bus_id) = setup_with_id::<B>(&NodeOptions::pass_all());
    assert_eq!(dut.driver().state(), ErrorState::Active);
    assert_eq!(
        dut.driver_ref().counters(),
        ErrorCounters { tec: 0, rec: 0 }
    );
    assert_eq!(dut.driver_ref().last_error(), LastErrorCode::None);
    // Twelve bit errors on our transmissions: TEC + 8 each (ISO 11898-1 rule 3) up to 96,
    // the warning level; the thirteenth attempt succeeds: TEC - 1 (rule 7).
    let me = dut.bus_id();
    h.bus()
        .borrow_mut()
        .inject_from(me, 12, Fault::Bit { at: None });
    let f = std_frame(0x2A0, &[0xAA]);
    dut.driver().try_send(&f).unwrap();
    let seen = watch(&mut h, &mut dut, 20_000, |d| {
        d.driver_ref().traffic().sent == 1
    });
    let mut expected: Vec<(u16, u16, ErrorState)> = (0..=12u16)
        .map(|k| {
            let tec = 8 * k;
            let state = if tec >= 96 {
                ErrorState::Warning
            } else {
                ErrorState::Active
            };
            (tec, 0, state)
        })
        .collect();
    expected.push((95, 0, ErrorState::Active));
    assert_eq!(seen, expected, "{}", B::NAME);
    assert_eq!(dut.driver_ref().error_stats().bit, 12, "{}", B::NAME);
    // Exactly two changes: active → warning at TEC 96, warning → active at 95.
    assert_eq!(dut.driver_ref().traffic().state_changes, 2, "{}", B::NAME);
    assert_eq!(peer.borrow().received_frames(), vec![f]);
    // Receive errors: the node alone detects a CRC error in the peer's next three frames
    // (REC + 1 each, rule 1; its error flag starts after the ACK delimiter, so the next
    // bit is not dominant and rule 2's + 8 does not apply); a witness acknowledges.
    let (witness, _) = attach_sim(&h, "witness", SimNode::new());
    h.bus().borrow_mut().inject_from(
        peer_bus_id,
        3,
        Fault::Crc {
            who: Receivers::Node(me),
        },
    );
    peer.borrow_mut().send(std_frame(0x2B0, &[1, 2]));
    settle(&mut h, &mut dut, &[&peer], 20_000);
    let got: Vec<Frame> = drain(&mut dut).iter().map(|r| r.frame).collect();
    assert_eq!(got, vec![std_frame(0x2B0, &[1, 2])], "{}", B::NAME);
    assert_eq!(witness.borrow().received_frames().len(), 1);
    // REC: per attempt + 1 for the CRC error (rule 1) and + 8 for the dominant bit that
    // follows its own error flag (rule 2: the other nodes see the flag as a form error in
    // EOF and start theirs one bit later); then - 1 for the good frame (rule 8):
    // 3 × 9 - 1 = 26.
    assert_eq!(
        dut.driver_ref().counters().rec,
        3 * (1 + 8) - 1,
        "{}",
        B::NAME
    );
    assert_eq!(dut.driver_ref().error_stats().crc, 3, "{}", B::NAME);
}

fn last_error_survives_the_interrupt<B: Backend>() {
    // `Driver::last_error` is "the last error code the controller latched": after an
    // acknowledge error has been serviced, thread code must still be able to read it.
    let mut h = Harness::new(RATE).unwrap();
    let mut dut = B::attach(&mut h, &NodeOptions::pass_all()).unwrap();
    dut.driver().try_send(&std_frame(0x10, &[])).unwrap();
    run(&mut h, &mut dut, 2_000); // alone: acknowledge errors, serviced
    assert!(dut.driver_ref().error_stats().acknowledge > 0);
    assert_eq!(
        dut.driver_ref().last_error(),
        LastErrorCode::Acknowledge,
        "{}",
        B::NAME
    );
}

fn filters_survive_stop_and_start<B: Backend>() {
    let filters = filter_list();
    let cases = filter_cases();
    let (mut h, mut dut, peer) = setup::<B>(&NodeOptions::filters(&filters));
    let (witness, _) = attach_sim(&h, "witness", SimNode::new());
    let before = run_cases(&mut h, &mut dut, &peer, &cases);
    assert_eq!(before, expected_cases(&cases));
    dut.driver().set_mode(Mode::Stopped).unwrap();
    assert_eq!(dut.driver().state(), ErrorState::Stopped);
    // Stopped: off the bus, nothing received (the witness acknowledges).
    let received = dut.driver_ref().traffic().received;
    let refused = dut.filtered_out();
    peer.borrow_mut().send(std_frame(0x123, &[9]));
    settle(&mut h, &mut dut, &[&peer], 10_000);
    assert_eq!(
        witness.borrow().received_frames().last(),
        Some(&std_frame(0x123, &[9]))
    );
    assert_eq!(dut.driver_ref().traffic().received, received, "{}", B::NAME);
    assert_eq!(dut.filtered_out(), refused);
    assert!(drain(&mut dut).is_empty());
    dut.driver().set_mode(Mode::Normal).unwrap();
    assert_eq!(dut.driver().state(), ErrorState::Active);
    run(&mut h, &mut dut, 20); // synchronise (see `flexcan_is_on_the_bus_when_set_mode_returns`)
    let after = run_cases(&mut h, &mut dut, &peer, &cases);
    assert_eq!(after, before, "{}", B::NAME);
}

fn filters_survive_a_bit_rate_change<B: Backend>() {
    let filters = filter_list();
    let cases = filter_cases();
    let opts = NodeOptions::filters(&filters);
    let (mut h, mut dut, peer) = setup::<B>(&opts);
    assert_eq!(dut.bitrate_in_registers(), RATE, "{}", B::NAME);
    let before = run_cases(&mut h, &mut dut, &peer, &cases);
    assert_eq!(before, expected_cases(&cases));
    // A new bus at 250 kbit/s at the same time; the peer and the node move to it.
    let mut h2 = harness_at(250_000, h.now());
    h2.bus().borrow_mut().attach("peer", peer.clone());
    drop(h);
    let (mut dut, how) = B::change_bitrate(dut, &opts, &mut h2).unwrap();
    assert_eq!(dut.bitrate_in_registers(), 250_000, "{}", B::NAME);
    run(&mut h2, &mut dut, 20); // synchronise
    println!("{}: bit rate change: {how:?}", B::NAME);
    // Observable: every frame a filter accepts is delivered with that filter's index,
    // every other one is refused, as before the change.
    let after = run_cases(&mut h2, &mut dut, &peer, &cases);
    assert_eq!(after, expected_cases(&cases), "{}", B::NAME);
}

// --- issue 12: one portable behaviour --------------------------------------------------

/// Capabilities: every figure is a fact of the manuals for the configuration the node
/// was brought up with (the backend's constants), not read back from the driver.
fn capabilities_are_the_hardware_facts<B: Backend>() {
    let (_h, dut, _peer) = setup::<B>(&NodeOptions::pass_all());
    let caps = dut.driver_ref().capabilities();
    assert_eq!(caps.clock_hz, B::CLOCK_HZ, "{}", B::NAME);
    assert_eq!(caps.timing_limits, B::LIMITS, "{}", B::NAME);
    assert_eq!(caps.peripheral_clock, B::PERIPHERAL_CLOCK, "{}", B::NAME);
    // FlexCAN: at least 8 quanta per bit (Kinetis RM), not the CTRL1 fields' 5.
    // FlexCAN clocks: the Kinetis 16 MHz oscillator, the RT1062's 24 MHz root.
    let fewest_quanta = match B::CLOCK_HZ {
        16_000_000 | 24_000_000 => 8,
        _ => 3,
    };
    assert_eq!(
        caps.timing_limits.min_quanta(),
        fewest_quanta,
        "{}",
        B::NAME
    );
    // Slowest: largest prescaler × most quanta (25 for both), rounded down (bxCAN:
    // 2,109.375 bit/s); fastest: bxCAN prescaler 1 and the fewest quanta (1 + 1 + 1);
    // FlexCAN the manuals' rule with the bus clock taken equal to the CAN clock
    // ("Arbitration and matching timing": at least 8 quanta, and a least number of bus
    // clocks per bit set by the message buffers in matching and arbitration), below
    // the register ranges' 5 quanta (ACAN §16.1).
    let (slowest, fastest) = match B::CLOCK_HZ {
        // Kinetis, ACAN's layout (16 buffers): 16 MHz / 16 bus clocks = 1 Mbit/s.
        16_000_000 => (16_000_000 / (256 * 25), 1_000_000),
        // The RT1062 in its layout (IMXRT1060RM, table "Minimum ratio between
        // peripheral clock frequency and CAN bit rate"): MAXMB 16 (the ERR005829
        // reserved mailbox moves the transmit mailboxes up by one), 17 buffers with the
        // Rx FIFO, 17 bus clocks per bit: 24 MHz / 17, rounded down.
        24_000_000 => (24_000_000 / (256 * 25), 24_000_000 / 17),
        54_000_000 => (54_000_000 / (1024 * 25), 18_000_000),
        c => panic!("unexpected clock {c}"),
    };
    assert_eq!(
        (caps.min_bitrate, caps.max_bitrate),
        (slowest, fastest),
        "{}",
        B::NAME
    );
    // What the backend asserts elsewhere as accepted (its limits, from the driver's rule
    // for its layout) is what the driver reports.
    assert_eq!(
        (caps.min_bitrate, caps.max_bitrate),
        (B::SLOWEST_BITRATE, B::FASTEST_BITRATE),
        "{}",
        B::NAME
    );
    assert_eq!(caps.modes, B::MODES, "{}", B::NAME);
    assert_eq!(
        (caps.max_standard_filters, caps.max_extended_filters),
        B::FILTERS_STD_EXT,
        "{}",
        B::NAME
    );
    assert_eq!(caps.tx_mailboxes, B::TX_MAILBOXES, "{}", B::NAME);
    assert_eq!(caps.rx_queues, B::RX_QUEUES, "{}", B::NAME);
    assert_eq!(caps.rx_fifo_depth as usize, B::RX_FIFO_DEPTH, "{}", B::NAME);
    assert_eq!(caps.timestamp_bits, B::TIMESTAMP_BITS, "{}", B::NAME);
    assert_eq!(caps.wakeup_events, B::WAKEUP_EVENTS, "{}", B::NAME);
    assert_eq!(dut.driver_ref().wakeups(), 0, "{}", B::NAME);
    // The capacity is real: exactly this many exact standard filters (identifiers 3
    // apart, so no planner merges them) can be installed in the node's current
    // partition, and one more is refused.
    let exact =
        |n: u16| -> Vec<Filter> { (0..n).map(|i| Filter::standard(0x100 + 3 * i)).collect() };
    let mut dut = dut;
    assert_eq!(
        B::set_filters(&mut dut, &exact(caps.max_standard_filters)),
        Ok(()),
        "{}",
        B::NAME
    );
    assert_eq!(
        B::set_filters(&mut dut, &exact(caps.max_standard_filters + 1)),
        Err(Refused::TooManyFilters),
        "{}",
        B::NAME
    );
    // The same rule as `Limits::check_bitrate`, and usable to compute a timing.
    assert!(caps.bitrate_in_range(fastest) && !caps.bitrate_in_range(fastest + 1));
    assert!(caps.bitrate_in_range(slowest) && !caps.bitrate_in_range(slowest - 1));
    assert_eq!(
        caps.timing_for(fastest + 1, 750),
        Err(TimingError::BitrateTooHigh)
    );
    assert_eq!(
        caps.timing_for(500_000, 875).map(|t| t.actual_bitrate()),
        Ok(500_000)
    );
    assert_eq!(dut.driver_ref().bus_mode(), BusMode::Normal);
}

/// 32 bit errors on the node's own frame: TEC + 8 each (ISO 11898-1 rule 3) through
/// warning (96) and passive (128) to bus-off (> 255). Gives the bus time of bus-off and
/// checks every (TEC, REC, state) step on the way.
fn to_bus_off<N: Dut>(h: &mut Harness, dut: &mut N, f: &Frame, name: &str) -> u64 {
    let me = dut.bus_id();
    h.bus()
        .borrow_mut()
        .inject_from(me, 32, Fault::Bit { at: None });
    dut.driver().try_send(f).unwrap();
    let seen = watch(h, dut, 20_000, |d| {
        d.driver_ref().error_status().state == ErrorState::BusOff
    });
    let mut expected: Vec<(u16, u16, ErrorState)> = (0..32u16)
        .map(|k| {
            let c = ErrorCounters { tec: 8 * k, rec: 0 };
            (c.tec, 0, ErrorState::from_counters(c))
        })
        .collect();
    expected.push((256, 0, ErrorState::BusOff));
    assert_eq!(seen, expected, "{name}");
    h.now()
}

fn bus_off_recovery_both_modes<B: Backend>() {
    const RECOVERY_BITS: u64 = 128 * 11;
    for recovery in [Recovery::Automatic, Recovery::Manual] {
        let opts = NodeOptions::pass_all().recovery(recovery);
        let (mut h, mut dut, peer) = setup::<B>(&opts);
        let what = format!("{} {recovery:?}", B::NAME);
        let expected = match recovery {
            Recovery::Automatic => BusOffRecovery::Automatic,
            Recovery::Manual => BusOffRecovery::Manual,
        };
        assert_eq!(dut.driver_ref().hardware().bus_off_recovery(), expected);
        // Not bus-off: automatic refuses (nothing could ever be started), manual has
        // nothing to do.
        let not_needed = dut.driver().recover();
        match recovery {
            Recovery::Automatic => assert_eq!(not_needed, Err(Error::WrongMode), "{what}"),
            Recovery::Manual => assert_eq!(not_needed, Ok(()), "{what}"),
        }
        let f = std_frame(0x0B0, &[1, 2]);
        let t_off = to_bus_off(&mut h, &mut dut, &f, &what);
        assert_eq!(dut.driver_ref().error_stats().bus_off, 1, "{what}");
        assert_eq!(dut.driver_ref().error_stats().bit, 32, "{what}");
        // Bus-off: nothing new is accepted; the frame in flight waits.
        let g = std_frame(0x0B1, &[3]);
        assert_eq!(
            dut.driver().try_send(&g),
            Err(nb::Error::Other(Error::BusOff)),
            "{what}"
        );
        let t_request = match recovery {
            Recovery::Automatic => {
                assert_eq!(dut.driver().recover(), Err(Error::WrongMode), "{what}");
                t_off
            }
            Recovery::Manual => {
                // Three times the recovery time: still bus-off without software.
                let seen = watch(&mut h, &mut dut, 3 * RECOVERY_BITS, |d| {
                    d.driver_ref().error_status().state != ErrorState::BusOff
                });
                assert_eq!(
                    seen.iter().map(|s| s.2).collect::<Vec<_>>(),
                    vec![ErrorState::BusOff],
                    "{what}: recovered without software"
                );
                assert_eq!(dut.driver_ref().counters().tec, 256, "{what}");
                dut.driver().recover().unwrap();
                h.now()
            }
        };
        // Back to error-active, counters 0, after the 128 × 11 recessive bits.
        let seen = watch(&mut h, &mut dut, RECOVERY_BITS + 200, |d| {
            d.driver_ref().error_status().state != ErrorState::BusOff
        });
        let t_back = h.now();
        assert_eq!(
            seen.last(),
            Some(&(0, 0, ErrorState::Active)),
            "{what}: {seen:?}"
        );
        let (from, at_least, at_most) = match (recovery, B::MANUAL_RECOVERY_COUNT) {
            (Recovery::Automatic, _) | (_, ManualRecoveryCount::FromRequest) => {
                // The node's own error delimiter and intermission may count as the
                // first sequence.
                (t_request, RECOVERY_BITS - 11 - 20, RECOVERY_BITS + 100)
            }
            // The 128 × 11 were seen long before the request: 11 recessive bits to
            // re-synchronise, then on the bus.
            (Recovery::Manual, ManualRecoveryCount::FromBusOff) => (t_request, 0, 11),
        };
        let took = t_back - from;
        assert!(
            (at_least..=at_most).contains(&took),
            "{what}: back after {took} bits"
        );
        // Every state change in order, with the counters at each.
        let changes: Vec<(ErrorState, u16)> =
            std::iter::from_fn(|| dut.driver().take_state_change())
                .map(|c| (c.state, c.counters.tec))
                .collect();
        assert_eq!(
            changes.iter().map(|c| c.0).collect::<Vec<_>>(),
            vec![
                ErrorState::Warning,
                ErrorState::Passive,
                ErrorState::BusOff,
                ErrorState::Active
            ],
            "{what}"
        );
        assert_eq!(changes[2].1, 256, "{what}");
        assert_eq!(changes[3].1, 0, "{what}");
        // The frame that waited goes out, once; the node accepts frames again.
        settle(&mut h, &mut dut, &[&peer], 10_000);
        dut.driver().try_send(&g).unwrap();
        settle(&mut h, &mut dut, &[&peer], 10_000);
        assert_eq!(peer.borrow().received_frames(), vec![f, g], "{what}");
        assert_eq!(dut.driver_ref().traffic().sent, 2, "{what}");
        assert_eq!(
            dut.driver_ref().counters(),
            ErrorCounters { tec: 0, rec: 0 },
            "{what}"
        );
    }
}

/// Stop → change the bus mode → start, and stop → change the bit rate → start, through
/// the portable API; the installed filters and their indices stay.
fn retiming_and_mode_changes_keep_the_filters<B: Backend>() {
    let filters = filter_list();
    let cases = filter_cases();
    let opts = NodeOptions::filters(&filters);
    let (mut h, mut dut, peer) = setup::<B>(&opts);
    let (witness, _) = attach_sim(&h, "witness", SimNode::new());
    let before = run_cases(&mut h, &mut dut, &peer, &cases);
    assert_eq!(before, expected_cases(&cases), "{}", B::NAME);
    // On the bus: refused, nothing changed.
    assert_eq!(
        dut.driver().set_bus_mode(BusMode::LoopBack),
        Err(Error::WrongMode)
    );
    assert_eq!(
        dut.driver().set_bitrate(250_000, 875),
        Err(Error::WrongMode)
    );
    assert_eq!(dut.bitrate_in_registers(), RATE, "{}", B::NAME);

    // Loop-back: the node receives its own frames through the same filters.
    dut.driver().set_mode(Mode::Stopped).unwrap();
    dut.driver().set_bus_mode(BusMode::LoopBack).unwrap();
    assert_eq!(dut.driver_ref().bus_mode(), BusMode::LoopBack);
    dut.driver().set_mode(Mode::Normal).unwrap();
    run(&mut h, &mut dut, 20);
    let own = [
        (std_frame(0x123, &[0xA]), Some(0u16)),
        (std_frame(0x223, &[0xB]), None),
        (ext_frame(0x0ABC_DE01, &[0xC]), Some(3)),
    ];
    let sent_before = dut.driver_ref().traffic().sent;
    for (f, _) in &own {
        dut.driver().try_send(f).unwrap();
    }
    for _ in 0..50 {
        run(&mut h, &mut dut, 100);
    }
    assert_eq!(
        dut.driver_ref().traffic().sent - sent_before,
        own.len() as u32,
        "{}: loop-back acknowledges its own frames",
        B::NAME
    );
    let got: Vec<(Frame, u16)> = drain(&mut dut)
        .iter()
        .map(|r| (r.frame, r.filter))
        .collect();
    let want: Vec<(Frame, u16)> = own.iter().filter_map(|(f, i)| i.map(|i| (*f, i))).collect();
    assert_eq!(got, want, "{}: loop-back", B::NAME);

    // Listen-only: receives through the same filters, never transmits.
    dut.driver().set_mode(Mode::Stopped).unwrap();
    dut.driver().set_bus_mode(BusMode::ListenOnly).unwrap();
    dut.driver().set_mode(Mode::Normal).unwrap();
    run(&mut h, &mut dut, 20);
    assert_eq!(dut.driver_ref().bus_mode(), BusMode::ListenOnly);
    assert_eq!(
        dut.driver().try_send(&std_frame(0x10, &[])),
        Err(nb::Error::Other(Error::WrongMode)),
        "{}",
        B::NAME
    );
    let acked_by_witness = witness.borrow().received_frames().len();
    let listening = run_cases(&mut h, &mut dut, &peer, &cases);
    assert_eq!(listening, before, "{}: listen-only", B::NAME);
    // Nobody but the witness acknowledged (the node never drives the bus).
    assert_eq!(
        witness.borrow().received_frames().len() - acked_by_witness,
        cases.len(),
        "{}",
        B::NAME
    );

    // Back to normal, then a new bit rate (stop → set_bitrate → start).
    dut.driver().set_mode(Mode::Stopped).unwrap();
    dut.driver().set_bus_mode(BusMode::Normal).unwrap();
    // A rate out of reach is a typed error and changes nothing.
    assert_eq!(
        dut.driver().set_bitrate(B::CLOCK_HZ, 875),
        Err(Error::Timing(TimingError::BitrateTooHigh))
    );
    assert_eq!(dut.bitrate_in_registers(), RATE, "{}", B::NAME);
    dut.driver().set_mode(Mode::Normal).unwrap();
    let mut h2 = harness_at(250_000, h.now());
    h2.bus().borrow_mut().attach("peer", peer.clone());
    drop(h);
    let (mut dut, _how) = B::change_bitrate(dut, &opts, &mut h2).unwrap();
    assert_eq!(dut.bitrate_in_registers(), 250_000, "{}", B::NAME);
    assert_eq!(dut.driver_ref().bus_mode(), BusMode::Normal);
    run(&mut h2, &mut dut, 20);
    let after = run_cases(&mut h2, &mut dut, &peer, &cases);
    assert_eq!(after, before, "{}: after the bit-rate change", B::NAME);
}

/// Re-timing a stopped node applies the rule `begin` applies: twice the fastest rate
/// is refused with the same error on both backends (bxCAN: above 54 MHz / 3 quanta;
/// FlexCAN: above the Kinetis manual's 16 bus clocks per bit, though within the register
/// ranges), nothing is written, and the fastest rate itself is accepted.
fn retiming_refuses_what_begin_refuses<B: Backend>() {
    let (_h, mut dut, _peer) = setup::<B>(&NodeOptions::pass_all());
    // `begin` refuses twice the fastest rate.
    assert!(
        B::check_timing(B::FASTEST_BITRATE * 2, 750).is_err(),
        "{}",
        B::NAME
    );
    dut.driver().set_mode(Mode::Stopped).unwrap();
    assert_eq!(
        dut.driver().set_bitrate(B::FASTEST_BITRATE * 2, 750),
        Err(Error::Timing(TimingError::BitrateTooHigh)),
        "{}",
        B::NAME
    );
    assert_eq!(dut.bitrate_in_registers(), RATE, "{}", B::NAME);
    let t = dut
        .driver()
        .set_bitrate(B::FASTEST_BITRATE, 750)
        .unwrap_or_else(|e| panic!("{}: {e:?}", B::NAME));
    assert_eq!(t.actual_bitrate(), B::FASTEST_BITRATE, "{}", B::NAME);
    assert_eq!(
        dut.bitrate_in_registers(),
        B::FASTEST_BITRATE,
        "{}",
        B::NAME
    );
    assert_eq!(
        dut.driver_ref().capabilities().max_bitrate,
        B::FASTEST_BITRATE,
        "{}",
        B::NAME
    );
}

/// An empty list receives nothing; `Filter::pass_all` everything; a new list replaces
/// the old one atomically.
fn filter_list_semantics<B: Backend>() {
    let probe = [
        std_frame(0x100, &[1]),
        ext_frame(0x0010_0000, &[2]),
        remote_frame(0x200, false, 1),
        remote_frame(0x1234, true, 0),
    ];
    let (mut h, mut dut, peer) = setup::<B>(&NodeOptions::filters(&[]));
    let cases: Vec<(Frame, Option<u16>)> = probe.iter().map(|f| (*f, None)).collect();
    let got = run_cases(&mut h, &mut dut, &peer, &cases);
    assert_eq!(got, (vec![], probe.len() as u64), "{}: empty list", B::NAME);
    // The node acknowledged them all (filtering is not refusing on the bus).
    assert_eq!(peer.borrow().pending(), 0);

    B::set_filters(&mut dut, &[Filter::pass_all()]).unwrap();
    let cases: Vec<(Frame, Option<u16>)> = probe.iter().map(|f| (*f, Some(0))).collect();
    let got = run_cases(&mut h, &mut dut, &peer, &cases);
    assert_eq!(got, expected_cases(&cases), "{}: pass-all", B::NAME);

    // Old list A; frames it accepted wait in the ring (serviced, not taken) and in the
    // hardware FIFO (not serviced).
    let a = [Filter::standard(0x100), Filter::standard(0x200)];
    B::set_filters(&mut dut, &a).unwrap();
    let dropped_before = dut.driver_ref().traffic().rx_dropped;
    for id in [0x100, 0x200] {
        peer.borrow_mut().send(std_frame(id, &[0xA]));
    }
    settle(&mut h, &mut dut, &[&peer], 10_000);
    assert_eq!(dut.driver_ref().available(), 2, "{}", B::NAME);
    for id in [0x200, 0x100] {
        peer.borrow_mut().send(std_frame(id, &[0xB]));
    }
    h.bus().borrow_mut().run_until_idle(10_000).unwrap();
    assert_eq!(peer.borrow().pending(), 0);
    // New list B: the same identifiers under other indices, and one more.
    let b = [
        Filter::standard(0x200),
        Filter::standard(0x300),
        Filter::standard(0x100),
    ];
    B::set_filters(&mut dut, &b).unwrap();
    // No frame with an index of list A after the call: the two in the hardware FIFO were
    // discarded while the controller was off the bus for the switch (counted by the
    // switch), the two in the ring are dropped when taken (counted then): four dropped.
    assert_eq!(
        dut.driver_ref().traffic().rx_dropped - dropped_before,
        2,
        "{}: discarded from the hardware FIFO by the switch",
        B::NAME
    );
    run(&mut h, &mut dut, 100);
    let stale: Vec<(Frame, u16)> = drain(&mut dut)
        .iter()
        .map(|r| (r.frame, r.filter))
        .collect();
    assert_eq!(stale, vec![], "{}: frames of the old list", B::NAME);
    assert_eq!(
        dut.driver_ref().traffic().rx_dropped - dropped_before,
        4,
        "{}",
        B::NAME
    );
    let cases = [
        (std_frame(0x100, &[0xC]), Some(2)),
        (std_frame(0x300, &[0xD]), Some(1)),
        (std_frame(0x200, &[0xE]), Some(0)),
        (std_frame(0x400, &[0xF]), None),
    ];
    let got = run_cases(&mut h, &mut dut, &peer, &cases);
    assert_eq!(got, expected_cases(&cases), "{}: new list", B::NAME);
}

// --- issue 22: what is reported is what is accepted --------------------------------------

/// A consistent timing of `clocks_per_bit` clocks with `quanta` quanta within the
/// register fields of `limits` (whatever the manual's quanta rule says), wished at its
/// own rate; `None` when the fields cannot hold it.
fn register_timing(
    clock_hz: u32,
    limits: &Limits,
    clocks_per_bit: u32,
    quanta: u32,
) -> Option<Timing> {
    if quanta < 3 || !clocks_per_bit.is_multiple_of(quanta) {
        return None;
    }
    let p = clocks_per_bit / quanta;
    if !limits.prescaler.contains(p as u16) {
        return None;
    }
    let rate = clock_hz / clocks_per_bit;
    (1..quanta - 1)
        .map(|t2| {
            let t1 = quanta - 1 - t2;
            Timing::from_tsegs(clock_hz, rate, limits, p as u16, t1 as u8, t2 as u8)
        })
        .find(|t| t.consistency().is_ok())
}

/// Items 5, 6, 7: the fastest and the slowest timings the capabilities report are
/// accepted by every entry point — as counts (configuration: FlexCAN `begin`, bxCAN
/// `Config::from_timing`; `set_timing`; `Capabilities::check_timing`) and as a wished
/// rate (configuration: FlexCAN `Settings` + `begin`, bxCAN `Config::from_bitrate_with`;
/// `Capabilities::timing_for`; `set_bitrate`); one bit per second beyond is refused by
/// every one, as is a timing one clock per bit faster, or one quantum shorter, than
/// what the capabilities name, where the registers hold one.
fn reported_timings_are_accepted_by_every_entry_point<B: Backend>() {
    let (_h, mut dut, _peer) = setup::<B>(&NodeOptions::pass_all());
    let caps = dut.driver_ref().capabilities();
    let fastest = caps.fastest_timing().expect("a fastest timing");
    let slowest = caps.slowest_timing().expect("a slowest timing");
    assert_eq!(
        (caps.min_bitrate, caps.max_bitrate),
        (B::SLOWEST_BITRATE, B::FASTEST_BITRATE),
        "{}",
        B::NAME
    );
    assert_eq!(fastest.actual_bitrate(), caps.max_bitrate);
    assert_eq!(slowest.actual_bitrate(), caps.min_bitrate);
    let l = caps.timing_limits;
    for t in [fastest, slowest] {
        assert!(
            l.min_quanta() <= t.quanta() && t.quanta() <= l.max_quanta(),
            "{}: {t:?}",
            B::NAME
        );
    }
    dut.driver().set_mode(Mode::Stopped).unwrap();
    let cases = [
        (fastest, caps.max_bitrate + 1, TimingError::BitrateTooHigh),
        (slowest, caps.min_bitrate - 1, TimingError::BitrateTooLow),
    ];
    for (t, beyond, error) in cases {
        let rate = t.actual_bitrate();
        let refused = match error {
            TimingError::BitrateTooHigh => TimingRefused::TooHigh,
            _ => TimingRefused::TooLow,
        };
        // As counts.
        assert_eq!(caps.check_timing(&t), Ok(()), "{} {rate}", B::NAME);
        assert_eq!(B::check_given_timing(&t), Ok(rate), "{} {rate}", B::NAME);
        assert_eq!(dut.driver().set_timing(&t), Ok(()), "{} {rate}", B::NAME);
        assert_eq!(dut.bitrate_in_registers(), rate, "{}", B::NAME);
        // As a wished rate.
        let sp = cia_sample_point(rate);
        assert!(caps.bitrate_in_range(rate));
        assert_eq!(B::check_timing(rate, sp), Ok(rate), "{} {rate}", B::NAME);
        assert_eq!(
            caps.timing_for(rate, sp).map(|t| t.actual_bitrate()),
            Ok(rate)
        );
        dut.driver().set_bitrate(RATE, 875).unwrap();
        assert_eq!(
            dut.driver()
                .set_bitrate(rate, sp)
                .map(|t| t.actual_bitrate()),
            Ok(rate),
            "{} {rate}",
            B::NAME
        );
        assert_eq!(dut.bitrate_in_registers(), rate, "{}", B::NAME);
        // One bit per second beyond, as a wished rate (the solver would find the
        // extreme timing within the tolerance: still refused), and as the wished rate
        // of the extreme timing's counts.
        assert!(!caps.bitrate_in_range(beyond));
        assert_eq!(
            B::check_timing(beyond, sp),
            Err(refused),
            "{} {beyond}",
            B::NAME
        );
        assert_eq!(caps.timing_for(beyond, sp), Err(error), "{}", B::NAME);
        assert_eq!(
            dut.driver().set_bitrate(beyond, sp),
            Err(Error::Timing(error)),
            "{} {beyond}",
            B::NAME
        );
        assert_eq!(
            dut.bitrate_in_registers(),
            rate,
            "{}: nothing written",
            B::NAME
        );
        let wished_beyond = Timing {
            bitrate: beyond,
            ..t
        };
        assert_eq!(
            B::check_given_timing(&wished_beyond),
            Err(refused),
            "{}",
            B::NAME
        );
    }
    // Timings beyond the reported ones that the registers still hold: one clock per bit
    // faster than the fastest (FlexCAN: 15 clocks, below 16 bus clocks per bit; bxCAN's
    // registers hold nothing faster than 3 clocks), and one quantum fewer than the
    // reported minimum at a rate in range (FlexCAN: 7 quanta; bxCAN: none below 3).
    let n = fastest.clocks_per_bit() as u32 - 1;
    let faster = (l.min_quanta().saturating_sub(3)..=l.max_quanta())
        .rev()
        .find_map(|q| register_timing(B::CLOCK_HZ, &l, n, q));
    let short_q = l.min_quanta() - 1;
    let short = (1..=l.prescaler.max as u32)
        .map(|p| p * short_q)
        .filter(|&n| n >= fastest.clocks_per_bit() as u32)
        .find_map(|n| register_timing(B::CLOCK_HZ, &l, n, short_q));
    let beyond: Vec<Timing> = faster.into_iter().chain(short).collect();
    let expected = match B::CLOCK_HZ {
        16_000_000 | 24_000_000 => 2,
        _ => 0,
    };
    assert_eq!(beyond.len(), expected, "{}: {beyond:?}", B::NAME);
    for t in beyond {
        assert_eq!(
            caps.check_timing(&t),
            Err(TimingError::ForbiddenByManual),
            "{}: {t:?}",
            B::NAME
        );
        assert_eq!(
            dut.driver().set_timing(&t),
            Err(Error::Timing(TimingError::ForbiddenByManual)),
            "{}: {t:?}",
            B::NAME
        );
        assert!(B::check_given_timing(&t).is_err(), "{}: {t:?}", B::NAME);
    }
    dut.driver().set_bitrate(RATE, 875).unwrap();
    dut.driver().set_mode(Mode::Normal).unwrap();
}

/// Item 9: the receive ring figures are those of the rings frames arrive in. The peer
/// sends more frames than the reported size while the node's interrupts are serviced
/// and nothing is taken: exactly `size` frames are held, the rest are counted as
/// overflows, and `size` frames come out. Each ring reports what it holds: the one the
/// filters feed (bxCAN FIFO 0 with the backend's plan; FlexCAN's one FIFO) is full, a
/// ring they do not feed holds nothing.
fn rx_ring_figures_are_what_arrives<B: Backend>() {
    let (mut h, mut dut, peer) = setup::<B>(&NodeOptions::pass_all());
    let size = dut.driver_ref().rx_stats().size;
    let ring0 = dut.driver_ref().rx_ring_stats(0).unwrap();
    assert_eq!(size, ring0.size, "{}: the fed ring only", B::NAME);
    let sent = size + 10;
    for i in 0..sent {
        peer.borrow_mut()
            .send(std_frame(0x100 + (i % 0x400) as u16, &[i as u8]));
    }
    settle(&mut h, &mut dut, &[&peer], 400_000);
    assert_eq!(peer.borrow().pending(), 0);
    let s = dut.driver_ref().rx_stats();
    assert_eq!(
        (s.count, s.overflows as usize),
        (size, sent - size),
        "{}: {s:?}",
        B::NAME
    );
    let per_ring: Vec<(usize, u32)> = (0..B::RX_QUEUES as usize)
        .map(|q| {
            let r = dut.driver_ref().rx_ring_stats(q).unwrap();
            (r.count, r.overflows)
        })
        .collect();
    let mut want = vec![(size, (sent - size) as u32)];
    want.resize(B::RX_QUEUES as usize, (0, 0));
    assert_eq!(per_ring, want, "{}", B::NAME);
    assert_eq!(
        dut.driver_ref().rx_ring_stats(B::RX_QUEUES as usize),
        None,
        "{}",
        B::NAME
    );
    assert_eq!(drain(&mut dut).len(), size, "{}", B::NAME);
    assert_eq!(dut.hw_lost(), 0, "{}", B::NAME);
}

/// Item 10: one DLC rule. A remote frame with each code 0..=15, built by `Frame::remote`
/// (the constructor that refused 9..=15 before), leaves with that code; the same code
/// sent by the peer comes out of the driver equal to what `Frame::remote` and
/// `set_dlc` build.
fn remote_dlc_codes_are_one_rule_both_ways<B: Backend>() {
    let (mut h, mut dut, peer) = setup::<B>(&NodeOptions::pass_all());
    let built: Vec<Frame> = (0..=15u8)
        .map(|code| Frame::remote(0x240 + code as u32, code % 2 == 1, code).unwrap())
        .collect();
    for f in &built {
        let mut by_set = remote_frame(f.raw_id(), f.is_extended(), 0);
        by_set.set_dlc(f.dlc()).unwrap();
        assert_eq!(by_set, *f);
    }
    for f in &built {
        dut.driver().try_send(f).unwrap();
        settle(&mut h, &mut dut, &[&peer], 20_000);
    }
    assert_eq!(peer.borrow().received_frames(), built, "{}", B::NAME);
    for f in &built {
        peer.borrow_mut().send(*f);
    }
    settle(&mut h, &mut dut, &[&peer], 50_000);
    let got: Vec<Frame> = drain(&mut dut).iter().map(|r| r.frame).collect();
    assert_eq!(got, built, "{}", B::NAME);
}

/// Item 9, bxCAN with both FIFOs fed (`FifoPolicy::Balanced`: the standard filter's bank
/// to one FIFO, the extended filters' bank to the other): the reported size is both
/// rings, and that many frames arrive, each ring holding its own.
#[test]
fn bxcan_ring_figures_with_both_fifos_fed() {
    let mut h = Harness::new(RATE).unwrap();
    let config = twocan_tests::backend::bxcan_config(RATE, Recovery::Automatic).unwrap();
    let filters = [
        Filter::standard(0x123),
        Filter::extended(0x0123_4567),
        Filter::extended(0x0ABC_DEF0),
    ];
    let mut bx = twocan_host::BxNode::with_config(
        &mut h,
        &config,
        &filters,
        twocan_bxcan::FifoPolicy::Balanced,
    )
    .unwrap();
    let (peer, _) = attach_peer(&h, "peer");
    run(&mut h, &mut bx, 20);
    let d = bx.driver_ref();
    let (r0, r1) = (d.rx_ring_stats(0).unwrap(), d.rx_ring_stats(1).unwrap());
    assert_eq!(d.rx_stats().size, r0.size + r1.size);
    let extra = 5;
    for i in 0..r0.size + r1.size + 2 * extra {
        let f = if i % 2 == 0 {
            std_frame(0x123, &[i as u8])
        } else {
            ext_frame(0x0123_4567, &[i as u8])
        };
        peer.borrow_mut().send(f);
    }
    settle(&mut h, &mut bx, &[&peer], 400_000);
    let d = bx.driver_ref();
    let s = d.rx_stats();
    assert_eq!(s.count, s.size, "{s:?}");
    let (r0, r1) = (d.rx_ring_stats(0).unwrap(), d.rx_ring_stats(1).unwrap());
    assert_eq!((r0.count, r1.count), (r0.size, r1.size));
    assert_eq!((r0.overflows, r1.overflows), (extra as u32, extra as u32));
}

// ---------------------------------------------------------------------------------------

#[test]
fn frames_that_break_the_format_are_typed_errors() {
    assert_eq!(
        Frame::standard(0x800, &[]),
        Err(FrameError::StandardIdOutOfRange(0x800))
    );
    assert_eq!(
        Frame::extended(0x2000_0000, &[]),
        Err(FrameError::ExtendedIdOutOfRange(0x2000_0000))
    );
    assert_eq!(
        Frame::standard(0x7FF, &[0; 9]),
        Err(FrameError::TooMuchData(9))
    );
    assert_eq!(
        Frame::remote(0x10, false, 16),
        Err(FrameError::DlcTooLarge(16))
    );
    let mut r = remote_frame(0x10, false, 4);
    assert_eq!(r.set_data(&[1]), Err(FrameError::DataOnRemoteFrame));
    // The largest legal values are accepted.
    assert!(Frame::standard(0x7FF, &[0; 8]).is_ok());
    assert!(Frame::extended(0x1FFF_FFFF, &[0; 8]).is_ok());
    assert!(Frame::remote(0x1FFF_FFFF, true, 8).is_ok());
}

// The bit-rate change through the portable API (stop → `Driver::set_bitrate` → start,
// filters kept) is checked on both backends by what the node delivers afterwards:
// `filters_survive_a_bit_rate_change` and `retiming_and_mode_changes_keep_the_filters`.

#[test]
fn capabilities_follow_the_current_configuration() {
    // FlexCAN 14/18 partition (more than 12 filters): 14 + 18 elements, MB15 and MB14
    // (ACAN §11 table 4).
    let mut h = Harness::new(RATE).unwrap();
    let many: Vec<Filter> = (0..20).map(|i| Filter::standard(0x100 + 3 * i)).collect();
    let flex = FlexCanBackend::attach(&mut h, &NodeOptions::filters(&many)).unwrap();
    let caps = flex.driver_ref().capabilities();
    assert_eq!(
        (
            caps.max_standard_filters,
            caps.max_extended_filters,
            caps.tx_mailboxes
        ),
        (32, 32, 2)
    );
    // bxCAN CAN1 with CAN2SB = 14: banks 0..13 (RM0410 §40.7.4); with TTCM: 16-bit
    // time stamps (§40.7.8).
    let config = twocan_tests::backend::bxcan_config(RATE, Recovery::Automatic)
        .unwrap()
        .can2_start_bank(14)
        .unwrap()
        .timestamps(true);
    let bx = twocan_host::BxNode::with_config(
        &mut h,
        &config,
        &[Filter::pass_all()],
        twocan_bxcan::FifoPolicy::Fifo0,
    )
    .unwrap();
    let caps = bx.driver_ref().capabilities();
    assert_eq!(
        (caps.max_standard_filters, caps.max_extended_filters),
        (14 * 4, 14 * 2)
    );
    assert_eq!(caps.timestamp_bits, Some(16));
    assert_eq!(caps.clock_hz, 54_000_000);
}

/// The RT1062 backend is begun in the RT1062 layout, as every Teensy 4
/// program begins it, in both configurations the backend uses (ACAN's 12/12 and, with
/// more than 12 filters, 14/18): `MCR[MAXMB]` is the layout's data mailbox, one above
/// ACAN's; the reserved ERR005829 mailbox (i.MX RT1060 chip errata, ERR005829; the
/// first valid mailbox after the Rx FIFO area) reads INACTIVE after data and remote
/// frames both ways, its interrupt flag never raised, its identifier none the node sent;
/// the peripheral-clock rule the node reports is that of `MAXMB` + 1 buffers, and the
/// backend's limits are the ones the node reports. In ACAN's layout the mailbox after
/// the Rx FIFO area is a transmit mailbox and `MAXMB` is 15: the test fails.
#[test]
fn flexcan_rt1062_is_begun_in_the_rt1062_layout() {
    use twocan_flexcan::layout::{Imxrt1062, Kinetis, Layout};
    use twocan_flexcan::regs::{self, code, cs, mcr};
    use twocan_flexcan::Configuration;

    let many: Vec<Filter> = (0..20).map(|i| Filter::standard(0x100 + 3 * i)).collect();
    let lists = [
        (vec![Filter::pass_all()], Configuration::Filters12_12),
        (many, Configuration::Filters14_18),
    ];
    for (filters, configuration) in lists {
        let (mut h, mut dut, peer) = setup::<Rt1062Backend>(&NodeOptions::filters(&filters));
        let c = dut.driver_ref().hardware().configuration();
        assert_eq!(c, configuration);
        let reserved = Imxrt1062::reserved_mailbox(c).expect("the RT1062 layout reserves one");
        assert_eq!(reserved, c.reserved_mailbox());
        let maxmb = mcr::MAXMB.get(dut.model.peek32(regs::MCR));
        assert_eq!(maxmb, u32::from(Imxrt1062::data_mailbox(c)), "{c:?}");
        assert_eq!(maxmb, u32::from(Kinetis::data_mailbox(c)) + 1, "{c:?}");
        // The rule of MAXMB + 1 buffers with the Rx FIFO: 17 bus clocks per bit.
        let caps = dut.driver_ref().capabilities();
        let rule = caps
            .peripheral_clock
            .expect("FlexCAN has a peripheral-clock rule");
        assert_eq!(
            Imxrt1062::message_buffers_used(c),
            usize::from(Imxrt1062::data_mailbox(c)) + 1
        );
        assert_eq!(rule.min_clocks_per_bit, 17, "{c:?}");
        assert_eq!(Some(rule), Rt1062Backend::PERIPHERAL_CLOCK, "{c:?}");
        assert_eq!(caps.max_bitrate, Rt1062Backend::FASTEST_BITRATE, "{c:?}");
        assert_eq!(caps.max_bitrate, rule.peripheral_hz / 17, "{c:?}");

        // Traffic both ways, every transmit mailbox busy: data and remote frames out,
        // data frames in (identifiers the filters pass).
        // Identifiers both lists pass (the 14/18 list holds 0x100 + 3 i, i < 20).
        let ids: Vec<u16> = (0..8).map(|i| 0x100 + 3 * i).collect();
        let sent: Vec<Frame> = (0..24u16)
            .map(|i| {
                let id = 0x7A0 + i;
                if i % 3 == 2 {
                    remote_frame(u32::from(id), false, 4)
                } else {
                    std_frame(id, &[i as u8; 8])
                }
            })
            .collect();
        for f in &sent {
            dut.driver().try_send(f).unwrap();
        }
        for &id in &ids {
            peer.borrow_mut().send(std_frame(id, &[0xA5]));
        }
        settle(&mut h, &mut dut, &[&peer], 100_000);
        assert_eq!(peer.borrow().received_frames(), sent, "{c:?}");
        assert_eq!(drain(&mut dut).len(), ids.len(), "{c:?}");

        let mb = usize::from(reserved);
        let code_of = |m: usize| cs::CODE.get(dut.model.peek32(regs::mb_cs(m)));
        assert_eq!(code_of(mb), code::TX_INACTIVE, "{c:?} MB{mb}");
        assert_eq!(
            dut.model.peek32(regs::IFLAG1) & (1 << mb),
            0,
            "{c:?} MB{mb}"
        );
        let id_word = dut.model.peek32(regs::mb_id(mb));
        assert!(
            sent.iter().all(|f| (id_word >> 18) & 0x7FF != f.raw_id()),
            "{c:?}: MB{mb} was loaded ({id_word:#x})"
        );
        // The transmit mailboxes lie above it.
        assert_eq!(Imxrt1062::first_remote_mailbox(c), reserved + 1, "{c:?}");
    }
}

#[test]
fn flexcan_last_error_survives_the_interrupt() {
    last_error_survives_the_interrupt::<FlexCanBackend>();
}

#[test]
fn bxcan_last_error_survives_the_interrupt() {
    last_error_survives_the_interrupt::<BxCanBackend>();
}

/// `set_mode(Normal)` promises "on the bus": a frame the peer starts right after it
/// returns must be received (a witness acknowledges it, so the peer does not retry).
fn on_the_bus_when_set_mode_returns<B: Backend>() {
    let (mut h, mut dut, peer) = setup::<B>(&NodeOptions::pass_all());
    let (witness, _) = attach_sim(&h, "witness", SimNode::new());
    dut.driver().set_mode(Mode::Stopped).unwrap();
    run(&mut h, &mut dut, 100);
    dut.driver().set_mode(Mode::Normal).unwrap();
    let f = std_frame(0x321, &[3, 2, 1]);
    peer.borrow_mut().send(f);
    settle(&mut h, &mut dut, &[&peer], 10_000);
    assert_eq!(witness.borrow().received_frames(), vec![f]);
    let got: Vec<Frame> = drain(&mut dut).iter().map(|r| r.frame).collect();
    assert_eq!(
        got,
        vec![f],
        "{}: frame missed right after set_mode(Normal)",
        B::NAME
    );
}

#[test]
fn bxcan_is_on_the_bus_when_set_mode_returns() {
    on_the_bus_when_set_mode_returns::<BxCanBackend>();
}

#[test]
fn flexcan_is_on_the_bus_when_set_mode_returns() {
    on_the_bus_when_set_mode_returns::<FlexCanBackend>();
}

// ---------------------------------------------------------------------------------------
// Issue 12: time stamps an application can use.

/// The distance a widening that sees no counter reading reports for a true distance of
/// `bits` (docs/architecture.md "Time stamps": the value within −32,768..=32,767 bit
/// times congruent to it modulo 65,536).
fn nearest_in_half_period(bits: i64) -> i64 {
    (bits + 32_768).rem_euclid(65_536) - 32_768
}

fn signed_ticks(t: Timestamp) -> i64 {
    t.ticks() as i64
}

/// Receive and transmit-completion stamps, widened past the 16-bit counter, against the
/// start-of-frame times the simulated bus reports for the same frames: every distance
/// between stamps equals the distance between the frames on the bus, in bit times (both
/// controllers stamp at a fixed point of the frame's start: Kinetis RM "start of the
/// identifier field", RM0410 "sample point of the Start Of Frame bit"), across three
/// wraps, with a receive interrupt handled 45,000 bit times after a frame's stamp. A
/// quiet bus of 200,000 bit times then shows what each controller can do: with a
/// readable counter (FlexCAN) and a refresh every 40,000 bit times the distance stays
/// exact; without
/// (bxCAN) it is known modulo 65,536 only, as documented.
fn time_stamps_extend_beyond_the_counter<B: Backend>() {
    let (mut h, mut dut, peer) = setup::<B>(&NodeOptions::pass_all().timestamps(true));
    // 1. Eight received frames, 20,000 bit times apart, handled as they come.
    for i in 0..8u8 {
        peer.borrow_mut()
            .send(std_frame(0x100 + u16::from(i), &[i]));
        run(&mut h, &mut dut, 20_000);
    }
    // 2. Two more, 20,000 bit times apart, whose receive interrupt is served 25,000 bit
    // times after the second: 45,000 bit times after the first frame's stamp, and after
    // a refresh (a periodic task's) that read the counter while they waited.
    peer.borrow_mut().send(std_frame(0x108, &[8]));
    h.run_for(20_000, &mut []);
    peer.borrow_mut().send(std_frame(0x109, &[9]));
    h.run_for(20_000, &mut []);
    dut.driver().refresh_timestamps();
    h.run_for(5_000, &mut []);
    assert!(dut.irq_pending(), "{}", B::NAME);
    run(&mut h, &mut dut, 0);
    // 3. Four transmitted frames, 20,000 bit times apart; then one more received.
    for i in 0..4u8 {
        dut.driver()
            .try_send(&std_frame(0x200 + u16::from(i), &[i]))
            .unwrap();
        run(&mut h, &mut dut, 20_000);
    }
    peer.borrow_mut().send(std_frame(0x10A, &[10]));
    run(&mut h, &mut dut, 20_000);

    // Bus times of the frames (start-of-frame bit), from the peer's own records.
    let sent_by_peer: Vec<(Frame, u64)> = peer
        .borrow()
        .tx_reports()
        .iter()
        .map(|r| (r.frame, r.time.sof))
        .collect();
    let received_by_peer: Vec<(Frame, u64)> = peer
        .borrow()
        .received()
        .iter()
        .map(|r| (r.frame, r.time.sof))
        .collect();
    let rx: Vec<_> = drain(&mut dut)
        .into_iter()
        .filter(|r| r.frame.raw_id() < 0x200)
        .collect();
    let done: Vec<_> = std::iter::from_fn(|| dut.driver().take_completion()).collect();
    assert_eq!(rx.len(), 11, "{}", B::NAME);
    assert_eq!(done.len(), 4, "{}", B::NAME);
    assert_eq!(sent_by_peer.len(), 11);
    assert_eq!(received_by_peer.len(), 4);

    let mut events: Vec<(u64, Timestamp)> = Vec::new();
    for (r, (f, sof)) in rx.iter().zip(&sent_by_peer) {
        assert_eq!(r.frame, *f);
        events.push((*sof, r.timestamp.expect("receive stamp")));
    }
    for (c, (f, sof)) in done.iter().zip(&received_by_peer) {
        assert_eq!(f.raw_id(), 0x200 + c.token.0);
        events.push((*sof, c.timestamp.expect("completion stamp")));
    }
    events.sort_by_key(|e| e.0);
    let (first, last) = (events[0], events[events.len() - 1]);
    let span = last.0 - first.0;
    assert!(span > 3 * COUNTER_PERIOD, "{span}: three wraps at least");
    for w in events.windows(2) {
        let (bus, stamps) = (w[1].0 - w[0].0, w[1].1.bit_times_since(w[0].1));
        assert_eq!(stamps, Some(bus), "{}: {w:?}", B::NAME);
    }
    // Microseconds from the bit rate: 2 µs a bit at 500 kbit/s.
    let stamped = last.1.bit_times_since(first.1).unwrap();
    assert_eq!(bit_times_to_micros(stamped, RATE), Ok(2 * span));
    assert_eq!(
        last.1.as_micros(RATE).unwrap() - first.1.as_micros(RATE).unwrap(),
        2 * span
    );

    // 4. A quiet bus for 200,000 bit times (refreshed every 40,000, the last reading
    // having been made 20,000 before), then one frame.
    let before = h.now();
    for _ in 0..5 {
        h.run_for(40_000, &mut []);
        dut.driver().refresh_timestamps();
    }
    assert_eq!(h.now(), before + 200_000);
    peer.borrow_mut().send(std_frame(0x10B, &[11]));
    run(&mut h, &mut dut, 1_000);
    let quiet = drain(&mut dut);
    assert_eq!(quiet.len(), 1, "{}", B::NAME);
    let sof = peer.borrow().tx_reports().last().unwrap().time.sof;
    let bus = (sof - last.0) as i64;
    assert!(bus > 200_000);
    let stamped = signed_ticks(quiet[0].timestamp.unwrap()) - signed_ticks(last.1);
    if B::TIMESTAMP_COUNTER_READABLE {
        assert_eq!(stamped, bus, "{}", B::NAME);
    } else {
        assert_eq!(stamped, nearest_in_half_period(bus), "{}", B::NAME);
        assert_eq!((bus - stamped) % COUNTER_PERIOD as i64, 0);
    }
}

/// Without TTCM bxCAN records no time stamp: the driver says `None`, never a made-up
/// value; FlexCAN always stamps.
fn time_stamps_only_where_the_hardware_records_them<B: Backend>() {
    let (mut h, mut dut, peer) = setup::<B>(&NodeOptions::pass_all());
    peer.borrow_mut().send(std_frame(0x100, &[]));
    dut.driver().try_send(&std_frame(0x200, &[])).unwrap();
    settle(&mut h, &mut dut, &[&peer], 10_000);
    let rx = drain(&mut dut);
    let done = dut.driver().take_completion().unwrap();
    let has = B::TIMESTAMP_COUNTER_READABLE; // FlexCAN: always; bxCAN: TTCM off here.
    assert!(!rx.is_empty());
    assert!(
        rx.iter().all(|r| r.timestamp.is_some() == has),
        "{}",
        B::NAME
    );
    assert_eq!(done.timestamp.is_some(), has, "{}", B::NAME);
}

macro_rules! suite {
    ($module:ident, $backend:ty) => {
        mod $module {
            use super::*;

            #[test]
            fn data_frames_both_ways() {
                super::data_frames_both_ways::<$backend>();
            }
            #[test]
            fn remote_frames_both_ways() {
                super::remote_frames_both_ways::<$backend>();
            }
            #[test]
            fn dlc_codes_above_eight_both_ways() {
                super::dlc_codes_above_eight_both_ways::<$backend>();
            }
            #[test]
            fn filters_accept_exactly_their_frames() {
                super::filters_accept_exactly_their_frames::<$backend>();
            }
            #[test]
            fn invalid_filters_are_refused() {
                super::invalid_filters_are_refused::<$backend>();
            }
            #[test]
            fn filter_capacity() {
                super::filter_capacity::<$backend>();
            }
            #[test]
            fn bit_rate_limits() {
                super::bit_rate_limits::<$backend>();
            }
            #[test]
            fn state_and_counters_follow_iso_rules() {
                super::state_and_counters_follow_iso_rules::<$backend>();
            }
            #[test]
            fn filters_survive_stop_and_start() {
                super::filters_survive_stop_and_start::<$backend>();
            }
            #[test]
            fn filters_survive_a_bit_rate_change() {
                super::filters_survive_a_bit_rate_change::<$backend>();
            }
            #[test]
            fn time_stamps_extend_beyond_the_counter() {
                super::time_stamps_extend_beyond_the_counter::<$backend>();
            }
            #[test]
            fn time_stamps_only_where_the_hardware_records_them() {
                super::time_stamps_only_where_the_hardware_records_them::<$backend>();
            }
            #[test]
            fn capabilities_are_the_hardware_facts() {
                super::capabilities_are_the_hardware_facts::<$backend>();
            }
            #[test]
            fn bus_off_recovery_both_modes() {
                super::bus_off_recovery_both_modes::<$backend>();
            }
            #[test]
            fn retiming_and_mode_changes_keep_the_filters() {
                super::retiming_and_mode_changes_keep_the_filters::<$backend>();
            }
            #[test]
            fn retiming_refuses_what_begin_refuses() {
                super::retiming_refuses_what_begin_refuses::<$backend>();
            }
            #[test]
            fn filter_list_semantics() {
                super::filter_list_semantics::<$backend>();
            }
            #[test]
            fn reported_timings_are_accepted_by_every_entry_point() {
                super::reported_timings_are_accepted_by_every_entry_point::<$backend>();
            }
            #[test]
            fn remote_dlc_codes_are_one_rule_both_ways() {
                super::remote_dlc_codes_are_one_rule_both_ways::<$backend>();
            }
            #[test]
            fn rx_ring_figures_are_what_arrives() {
                super::rx_ring_figures_are_what_arrives::<$backend>();
            }
        }
    };
}

suite!(flexcan, FlexCanBackend);
suite!(flexcan_rt1062, Rt1062Backend);
suite!(bxcan, BxCanBackend);
