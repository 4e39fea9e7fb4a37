//! A protocol adapter written against the portable traits alone ([`CanTx`], [`CanRx`]),
//! run over both backends' models on one simulated bus: through the one-struct driver
//! (one value plays both traits) and through the split halves (two values), FlexCAN and
//! bxCAN talking to each other.
//!
//! The adapter is a small ISO-TP-like segmenter (the framing of ISO 15765-2, simplified:
//! no timers, no padding rules, 12-bit lengths): a single frame carries up to 7 bytes;
//! a longer message goes as a first frame (length and 6 bytes), then consecutive frames
//! of 7 bytes numbered modulo 16, paced by flow-control frames from the receiver that
//! grant a block of [`segmenter::BLOCK`] frames at a time. It uses what a stack needs
//! from any backend: the token of each frame and the completion stream that settles it
//! (a lost frame fails the transfer), the queue figures to bound the frames in flight,
//! `available()` to bound the work per poll, the state changes (bus-off fails it), and
//! the traffic statistics to check the count.

use twocan_core::{CanRx, CanStatus, CanTx, Filter};
use twocan_host::split::{split_bx, split_flex, unsplit_bx, unsplit_flex, BxState, FlexState};
use twocan_host::{BxNode, FlexNode, Harness, Serviced};

mod segmenter {
    use twocan_core::{CanRx, CanTx, Error, ErrorState, Frame, Token, TxOutcome};

    /// Consecutive frames granted per flow-control frame.
    pub const BLOCK: u8 = 8;
    /// The longest message (12-bit length).
    pub const MAX_LEN: usize = 4095;

    /// Why a transfer failed.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum Failure {
        /// The driver refused a frame.
        Refused(Error),
        /// A frame was not sent (its completion said so).
        Lost(TxOutcome),
        /// The controller went bus-off.
        BusOff,
        /// A consecutive frame came out of sequence.
        Sequence,
    }

    struct Outgoing {
        data: Vec<u8>,
        /// Bytes handed to the driver so far.
        offset: usize,
        seq: u8,
        /// Consecutive frames the receiver's last flow control still allows.
        credit: u8,
        started: bool,
    }

    struct Incoming {
        data: Vec<u8>,
        len: usize,
        seq: u8,
        since_flow_control: u8,
    }

    /// One end of a segmented link: sends on `tx_id`, receives on `rx_id`.
    pub struct Link {
        tx_id: u16,
        rx_id: u16,
        out: Option<Outgoing>,
        inc: Option<Incoming>,
        owe_flow_control: bool,
        in_flight: Vec<Token>,
        /// Frames the driver accepted.
        pub frames_accepted: u32,
        /// Completions taken, all of them `Sent` unless `failure` says otherwise.
        pub frames_confirmed: u32,
        /// Messages whose every frame was confirmed sent.
        pub messages_sent: u32,
        /// Frames received on `rx_id`.
        pub frames_received: u32,
        /// The first failure; the link stops then.
        pub failure: Option<Failure>,
    }

    impl Link {
        pub fn new(tx_id: u16, rx_id: u16) -> Self {
            Link {
                tx_id,
                rx_id,
                out: None,
                inc: None,
                owe_flow_control: false,
                in_flight: Vec::new(),
                frames_accepted: 0,
                frames_confirmed: 0,
                messages_sent: 0,
                frames_received: 0,
                failure: None,
            }
        }

        /// Starts sending `message`; `false` when a transfer is under way or it is too
        /// long.
        pub fn send(&mut self, message: &[u8]) -> bool {
            if self.out.is_some() || message.len() > MAX_LEN {
                return false;
            }
            self.out = Some(Outgoing {
                data: message.to_vec(),
                offset: 0,
                seq: 1,
                credit: 0,
                started: false,
            });
            true
        }

        /// Nothing to send, nothing in flight, nothing owed.
        pub fn idle(&self) -> bool {
            self.out.is_none() && self.in_flight.is_empty() && !self.owe_flow_control
        }

        fn fail(&mut self, f: Failure) {
            self.failure.get_or_insert(f);
        }

        /// The receive side: takes the state changes and the frames waiting now (no
        /// more: `available()` bounds the work of one call). Returns a message when its
        /// last frame came.
        pub fn poll_rx<R: CanRx>(&mut self, rx: &mut R) -> Option<Vec<u8>> {
            while let Some(change) = rx.take_state_change() {
                if change.state == ErrorState::BusOff {
                    self.fail(Failure::BusOff);
                }
            }
            let mut done = None;
            for _ in 0..rx.available() {
                let Ok(f) = rx.receive() else { break };
                if f.frame.is_extended() || f.frame.raw_id() != u32::from(self.rx_id) {
                    continue;
                }
                self.frames_received += 1;
                if let Some(m) = self.on_frame(f.frame.data()) {
                    done = Some(m);
                }
            }
            done
        }

        fn on_frame(&mut self, d: &[u8]) -> Option<Vec<u8>> {
            let pci = *d.first()?;
            match pci >> 4 {
                0 => {
                    let len = usize::from(pci & 0xF);
                    d.get(1..1 + len).map(<[u8]>::to_vec)
                }
                1 => {
                    let len = usize::from(pci & 0xF) << 8 | usize::from(*d.get(1)?);
                    self.inc = Some(Incoming {
                        data: d[2..].to_vec(),
                        len,
                        seq: 1,
                        since_flow_control: 0,
                    });
                    self.owe_flow_control = true;
                    None
                }
                2 => {
                    let inc = self.inc.as_mut()?;
                    if pci & 0xF != inc.seq {
                        self.inc = None;
                        self.fail(Failure::Sequence);
                        return None;
                    }
                    inc.seq = (inc.seq + 1) & 0xF;
                    let take = (inc.len - inc.data.len()).min(7).min(d.len() - 1);
                    inc.data.extend_from_slice(&d[1..1 + take]);
                    if inc.data.len() == inc.len {
                        return self.inc.take().map(|i| i.data);
                    }
                    inc.since_flow_control += 1;
                    if inc.since_flow_control == BLOCK {
                        inc.since_flow_control = 0;
                        self.owe_flow_control = true;
                    }
                    None
                }
                3 => {
                    if let Some(out) = self.out.as_mut() {
                        out.credit = *d.get(1)?;
                    }
                    None
                }
                _ => None,
            }
        }

        /// The transmit side: settles the completions, sends the flow control owed and
        /// what the receiver allows, with no more frames in flight than the driver's
        /// queue holds.
        pub fn poll_tx<T: CanTx>(&mut self, tx: &mut T) {
            while let Some(c) = tx.take_completion() {
                self.in_flight.retain(|t| *t != c.token);
                self.frames_confirmed += 1;
                if c.outcome != TxOutcome::Sent {
                    self.fail(Failure::Lost(c.outcome));
                }
            }
            if self.failure.is_some() {
                for t in self.in_flight.clone() {
                    tx.abort(t);
                }
                self.out = None;
                return;
            }
            let limit = tx.tx_stats().size.max(1);
            while self.in_flight.len() < limit {
                let Some(payload) = self.next_payload() else {
                    break;
                };
                let frame = Frame::standard(self.tx_id, &payload).expect("8 bytes at most");
                match tx.try_send(&frame) {
                    Ok(token) => {
                        self.in_flight.push(token);
                        self.frames_accepted += 1;
                        self.commit();
                    }
                    Err(nb::Error::WouldBlock) => break,
                    Err(nb::Error::Other(e)) => {
                        self.fail(Failure::Refused(e));
                        return;
                    }
                }
            }
            if self
                .out
                .as_ref()
                .is_some_and(|o| o.started && o.offset == o.data.len())
                && self.in_flight.is_empty()
            {
                self.out = None;
                self.messages_sent += 1;
            }
        }

        /// The next frame's bytes, without taking it (see [`Link::commit`]).
        fn next_payload(&self) -> Option<Vec<u8>> {
            if self.owe_flow_control {
                return Some(vec![0x30, BLOCK, 0]);
            }
            let out = self.out.as_ref()?;
            let n = out.data.len();
            if !out.started {
                return Some(if n <= 7 {
                    [&[n as u8][..], &out.data].concat()
                } else {
                    [&[0x10 | (n >> 8) as u8, n as u8][..], &out.data[..6]].concat()
                });
            }
            if out.offset == n || out.credit == 0 {
                return None;
            }
            let end = (out.offset + 7).min(n);
            Some([&[0x20 | out.seq][..], &out.data[out.offset..end]].concat())
        }

        /// The frame of [`Link::next_payload`] was accepted.
        fn commit(&mut self) {
            if self.owe_flow_control {
                self.owe_flow_control = false;
                return;
            }
            let out = self.out.as_mut().expect("a payload came from it");
            let n = out.data.len();
            if !out.started {
                out.started = true;
                out.offset = if n <= 7 { n } else { 6 };
            } else {
                out.offset = (out.offset + 7).min(n);
                out.seq = (out.seq + 1) & 0xF;
                out.credit -= 1;
            }
        }
    }

    /// Frames a message of `n` bytes takes from the sender, and flow-control frames from
    /// the receiver.
    pub fn frames_for(n: usize) -> (u32, u32) {
        if n <= 7 {
            return (1, 0);
        }
        let consecutive = (n - 6).div_ceil(7) as u32;
        (1 + consecutive, 1 + (consecutive - 1) / u32::from(BLOCK))
    }
}

use segmenter::{frames_for, Link};

fn message(len: usize, salt: u8) -> Vec<u8> {
    (0..len)
        .map(|i| (i as u8).wrapping_mul(31) ^ salt)
        .collect()
}

/// Runs `step` (the applications' polls) and the bus in turns until `done` or the
/// bound; returns the bus time used.
fn run(
    h: &mut Harness,
    nodes: &mut [&mut dyn Serviced],
    mut step: impl FnMut() -> bool,
    max_bits: u64,
) -> u64 {
    let start = h.now();
    while !step() {
        assert!(h.now() - start < max_bits, "the transfer did not end");
        h.run_for(100, nodes);
    }
    h.now() - start
}

/// The messages each direction carries: a single frame, an exact block, a long one.
const LENGTHS: [(usize, usize); 3] = [(5, 62), (300, 7), (4095, 1000)];

#[test]
fn the_segmenter_runs_over_both_backends_through_the_one_struct_driver() {
    let mut h = Harness::new(500_000).unwrap();
    let mut teensy = FlexNode::teensy36_can0(&mut h, &[Filter::pass_all()]).unwrap();
    let mut stm32 = BxNode::stm32f767_can1(&mut h, &[Filter::pass_all()]).unwrap();
    for (a_len, b_len) in LENGTHS {
        let (a_msg, b_msg) = (message(a_len, 0x5A), message(b_len, 0xC3));
        let (mut a, mut b) = (Link::new(0x7E0, 0x7E8), Link::new(0x7E8, 0x7E0));
        assert!(a.send(&a_msg) && b.send(&b_msg));
        let (mut a_got, mut b_got) = (None, None);
        let before = (teensy.driver.traffic(), stm32.driver.traffic());
        run(
            &mut h,
            &mut [],
            || {
                // One value plays both traits.
                if let Some(m) = a.poll_rx(&mut teensy.driver) {
                    a_got = Some(m);
                }
                a.poll_tx(&mut teensy.driver);
                if let Some(m) = b.poll_rx(&mut stm32.driver) {
                    b_got = Some(m);
                }
                b.poll_tx(&mut stm32.driver);
                // The interrupts, as the harness would run them.
                teensy.service();
                stm32.service();
                a.idle() && b.idle() && a_got.is_some() && b_got.is_some()
            },
            20_000_000,
        );
        assert_eq!((a.failure, b.failure), (None, None));
        assert_eq!(
            b_got.as_deref(),
            Some(&a_msg[..]),
            "FlexCAN to bxCAN, {a_len} bytes"
        );
        assert_eq!(
            a_got.as_deref(),
            Some(&b_msg[..]),
            "bxCAN to FlexCAN, {b_len} bytes"
        );
        let (a_data, a_fc) = frames_for(a_len);
        let (b_data, b_fc) = frames_for(b_len);
        assert_eq!(a.frames_accepted, a_data + b_fc);
        assert_eq!(b.frames_accepted, b_data + a_fc);
        assert_eq!(a.frames_received, b.frames_accepted);
        assert_eq!((a.messages_sent, b.messages_sent), (1, 1));
        // Every accepted frame was confirmed sent, as the driver's statistics count.
        let after = (teensy.driver.traffic(), stm32.driver.traffic());
        assert_eq!(a.frames_confirmed, a.frames_accepted);
        assert_eq!(after.0.sent - before.0.sent, a.frames_accepted);
        assert_eq!(after.1.sent - before.1.sent, b.frames_accepted);
        assert_eq!(after.1.received - before.1.received, a.frames_accepted);
        // Never more in flight than the queue holds.
        let q = CanTx::tx_stats(&teensy.driver);
        assert!(q.peak <= q.size, "{q:?}");
    }
}

#[test]
fn the_segmenter_runs_over_both_backends_through_the_split_halves() {
    let mut h = Harness::new(1_000_000).unwrap();
    let teensy = FlexNode::teensy36_can0(&mut h, &[Filter::standard(0x7E8)]).unwrap();
    let stm32 = BxNode::stm32f767_can1(&mut h, &[Filter::standard(0x7E0)]).unwrap();
    let (fs, bs) = (FlexState::new(), BxState::new());
    let (mut fi, mut ftx, mut frx) = split_flex(&fs, teensy).unwrap();
    let (mut bi, mut btx, mut brx) = split_bx(&bs, stm32).unwrap();
    for (a_len, b_len) in LENGTHS {
        let (a_msg, b_msg) = (message(a_len, 0x11), message(b_len, 0x22));
        let (mut a, mut b) = (Link::new(0x7E0, 0x7E8), Link::new(0x7E8, 0x7E0));
        assert!(a.send(&a_msg) && b.send(&b_msg));
        let (mut a_got, mut b_got) = (None, None);
        run(
            &mut h,
            &mut [&mut fi, &mut bi],
            || {
                // Two values: the receive half, then the transmit half.
                if let Some(m) = a.poll_rx(&mut frx) {
                    a_got = Some(m);
                }
                a.poll_tx(&mut ftx);
                if let Some(m) = b.poll_rx(&mut brx) {
                    b_got = Some(m);
                }
                b.poll_tx(&mut btx);
                a.idle() && b.idle() && a_got.is_some() && b_got.is_some()
            },
            20_000_000,
        );
        assert_eq!((a.failure, b.failure), (None, None));
        assert_eq!(b_got.as_deref(), Some(&a_msg[..]));
        assert_eq!(a_got.as_deref(), Some(&b_msg[..]));
        assert_eq!(a.frames_received, b.frames_accepted);
        assert_eq!(b.frames_received, a.frames_accepted);
    }
    // The halves' statistics through the traits: the state's own.
    assert_eq!(CanRx::rx_stats(&brx), bs.rx_stats());
    assert_eq!(ftx.traffic(), fs.traffic());
    assert_eq!(ftx.traffic().sent, ftx.traffic().queued);
    assert_eq!(frx.error_status().counters.tec, 0);
}

#[test]
fn a_consecutive_frame_out_of_sequence_fails_the_transfer() {
    let mut h = Harness::new(500_000).unwrap();
    let mut teensy = FlexNode::teensy36_can0(&mut h, &[Filter::pass_all()]).unwrap();
    let mut stm32 = BxNode::stm32f767_can1(&mut h, &[Filter::pass_all()]).unwrap();
    let mut b = Link::new(0x7E8, 0x7E0);
    // A first frame of 20 bytes, then consecutive frame 2 where 1 was due.
    for d in [
        &[0x10, 20, 1, 2, 3, 4, 5, 6][..],
        &[0x22, 7, 8, 9, 10, 11, 12, 13],
    ] {
        let f = twocan_core::Frame::standard(0x7E0, d).unwrap();
        teensy.driver.try_send(&f).unwrap();
    }
    h.run_for(1_000, &mut [&mut teensy, &mut stm32]);
    assert_eq!(b.poll_rx(&mut stm32.driver), None);
    assert_eq!(b.failure, Some(segmenter::Failure::Sequence));
    assert_eq!(b.frames_received, 2);
}

#[test]
fn a_node_goes_back_from_the_halves_to_the_one_struct_driver() {
    let mut h = Harness::new(500_000).unwrap();
    let teensy = FlexNode::teensy36_can0(&mut h, &[Filter::pass_all()]).unwrap();
    let stm32 = BxNode::stm32f767_can1(&mut h, &[Filter::pass_all()]).unwrap();
    let (fs, bs) = (FlexState::new(), BxState::new());
    let frame = twocan_core::Frame::standard(0x321, &[9, 8, 7]).unwrap();
    let (fnode, bnode) = {
        let (mut fi, mut ftx, _frx) = split_flex(&fs, teensy).unwrap();
        let (mut bi, _btx, mut brx) = split_bx(&bs, stm32).unwrap();
        ftx.try_send(&frame).unwrap();
        h.run_for(1_000, &mut [&mut fi, &mut bi]);
        assert_eq!(brx.receive().unwrap().frame, frame);
        ((fi.model.clone(), fi.id), (bi.model.clone(), bi.id))
    };
    assert_eq!(fs.traffic().sent, 1);
    let mut teensy = unsplit_flex(fs, fnode.0, fnode.1).expect("split before");
    let mut stm32 = unsplit_bx(bs, bnode.0, bnode.1).expect("split before");
    // The controllers kept their configuration: the other way round now.
    stm32.driver.try_send(&frame).unwrap();
    h.run_for(1_000, &mut [&mut teensy, &mut stm32]);
    assert_eq!(teensy.driver.receive().unwrap().frame, frame);
    assert_eq!(stm32.driver.traffic().sent, 1, "a fresh state counts anew");
    // A state never split gives nothing back.
    assert!(unsplit_flex(FlexState::new(), teensy.model.clone(), teensy.id).is_none());
}
