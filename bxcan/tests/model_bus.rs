//! A tiny stand-in for the simulated bus (`twocan-sim`'s bus is written separately) and
//! register-level helpers, shared by the `model_*` tests (`#[path]`-included; its own
//! tests are in `model_modes.rs`). As a test target of its own it has no tests.
//!
//! The bus drives the models' `BusNode` side exactly as the contract describes: at an
//! idle point it polls every node, resolves arbitration with `Priority`, reports the
//! outcome to the transmitter (`tx_result`), to the losers (`ArbitrationLost`), to the
//! listeners (`rx` / `rx_error`) and to the transmitter itself (`rx` with `own = true`);
//! nodes that do not listen see the frame as non-idle time (`advance(.., false, ..)`).
//! Frame lengths ignore stuff bits. Time passes only when a frame is sent or the test
//! calls [`TinyBus::idle`].
#![allow(dead_code)]

use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::regs::{
    self, fa1r, ffa1r, fm1r, fmr, fs1r, mcr, msr, rdtxr, rfxr, rixr, tdtxr, tixr,
};
use twocan_core::{Frame, LastErrorCode, Registers};
use twocan_sim::{BusNode, BusTime, TxRequest, TxResult};

/// Bit times of a frame without stuff bits: SOF, arbitration, control, data, CRC, ACK,
/// EOF.
pub fn frame_bits(f: &Frame) -> u64 {
    let data = if f.is_remote() { 0 } else { 8 * f.dlc() as u64 };
    let header = if f.is_extended() {
        1 + 32 + 6
    } else {
        1 + 12 + 6
    };
    header + data + 16 + 2 + 7
}

/// What happened in one bus slot.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Slot {
    /// The frame that won the bus (or was sent internally), if any.
    pub frame: Option<Frame>,
    /// Index of its transmitter in the bus's node list.
    pub from: Option<usize>,
    /// Whether the frame was acknowledged.
    pub acked: bool,
}

/// The tiny bus.
pub struct TinyBus {
    /// The bus time (bit times).
    pub now: u64,
    /// The nodes.
    pub nodes: Vec<BxCanModel>,
    /// An error to inject into the next frame sent on the wire.
    pub inject_error: Option<LastErrorCode>,
}

impl TinyBus {
    /// A bus with these nodes (handles are cloned).
    pub fn new(nodes: &[&BxCanModel]) -> Self {
        TinyBus {
            now: 0,
            nodes: nodes.iter().map(|n| (*n).clone()).collect(),
            inject_error: None,
        }
    }

    /// `bits` recessive bit times pass.
    pub fn idle(&mut self, bits: u64) {
        self.now += bits;
        for n in &mut self.nodes {
            n.advance(bits, true, self.now);
        }
    }

    fn deliver(&mut self, frame: &Frame, skip: Option<usize>, time: BusTime) {
        let bits = time.now - time.sof;
        for (i, n) in self.nodes.iter_mut().enumerate() {
            if Some(i) == skip {
                continue;
            }
            if n.listens() {
                n.rx(frame, false, time);
            } else {
                n.advance(bits, false, time.now);
            }
        }
    }

    /// One bus slot at the current time.
    pub fn step(&mut self) -> Slot {
        let now = self.now;
        let requests: Vec<Option<TxRequest>> =
            self.nodes.iter_mut().map(|n| n.poll_tx(now)).collect();
        // Internal (loop back + silent) frames: seen by their node only.
        for (i, r) in requests.iter().enumerate() {
            if let Some(r) = r.filter(|r| r.internal) {
                let time = BusTime {
                    sof: now,
                    now: now + frame_bits(&r.frame),
                };
                let n = &mut self.nodes[i];
                n.tx_result(&r.frame, TxResult::Acked, time);
                n.rx(&r.frame, true, time);
                return Slot {
                    frame: Some(r.frame),
                    from: Some(i),
                    acked: true,
                };
            }
        }
        let winner = requests
            .iter()
            .enumerate()
            .filter_map(|(i, r)| r.map(|r| (r.frame.priority(), i, r)))
            .min_by_key(|(p, i, _)| (*p, *i));
        let Some((_, w, req)) = winner else {
            return Slot {
                frame: None,
                from: None,
                acked: false,
            };
        };
        let frame = req.frame;
        let time = BusTime {
            sof: now,
            now: now + frame_bits(&frame),
        };
        self.now = time.now;
        for (i, r) in requests.iter().enumerate() {
            if i != w && r.is_some() {
                self.nodes[i].tx_result(&r.unwrap().frame, TxResult::ArbitrationLost, time);
            }
        }
        if let Some(code) = self.inject_error.take() {
            self.nodes[w].tx_result(&frame, TxResult::Error(code), time);
            for (i, n) in self.nodes.iter_mut().enumerate() {
                if i != w && n.listens() {
                    n.rx_error(code, false, time);
                }
            }
            return Slot {
                frame: Some(frame),
                from: Some(w),
                acked: false,
            };
        }
        let acked = req.self_ack
            || self
                .nodes
                .iter()
                .enumerate()
                .any(|(i, n)| i != w && n.acknowledges());
        if acked {
            self.nodes[w].tx_result(&frame, TxResult::Acked, time);
            self.nodes[w].rx(&frame, true, time);
            self.deliver(&frame, Some(w), time);
        } else {
            self.nodes[w].tx_result(&frame, TxResult::Error(LastErrorCode::Acknowledge), time);
            for (i, n) in self.nodes.iter_mut().enumerate() {
                if i != w && n.listens() {
                    n.rx_error(LastErrorCode::Form, false, time);
                }
            }
        }
        Slot {
            frame: Some(frame),
            from: Some(w),
            acked,
        }
    }

    /// Runs slots (with a 3-bit intermission after each frame) until no node transmits
    /// or `max` frames were sent; returns the frames in bus order.
    pub fn run(&mut self, max: usize) -> Vec<Frame> {
        let mut out = Vec::new();
        for _ in 0..max {
            let slot = self.step();
            let Some(f) = slot.frame else { break };
            out.push(f);
            self.idle(3);
        }
        out
    }

    /// A frame from a node that is not modelled, delivered to every listener.
    pub fn inject(&mut self, frame: &Frame) {
        let time = BusTime {
            sof: self.now,
            now: self.now + frame_bits(frame),
        };
        self.now = time.now;
        self.deliver(frame, None, time);
    }

    /// A receive error detected by every listener (another node's broken frame).
    pub fn inject_rx_error(&mut self, code: LastErrorCode, dominant_after_flag: bool) {
        let time = BusTime {
            sof: self.now,
            now: self.now + 20,
        };
        self.now = time.now;
        for n in &mut self.nodes {
            if n.listens() {
                n.rx_error(code, dominant_after_flag, time);
            } else {
                n.advance(20, false, time.now);
            }
        }
    }
}

// ------------------------------------------------------------------------------------
// Register-level helpers: what a driver would write.
// ------------------------------------------------------------------------------------

/// Requests initialization mode from reset/sleep (INRQ = 1, SLEEP = 0) and checks INAK.
pub fn enter_init(m: &mut BxCanModel) {
    let v = m.read32(regs::MCR);
    m.write32(regs::MCR, (v | mcr::INRQ) & !mcr::SLEEP);
    assert_eq!(m.read32(regs::MSR) & (msr::INAK | msr::SLAK), msr::INAK);
}

/// Leaves initialization mode and lets the bus be idle for 11 bits (SYNC).
pub fn leave_init(m: &mut BxCanModel, bus: &mut TinyBus) {
    m.modify32(regs::MCR, |v| v & !(mcr::INRQ | mcr::SLEEP));
    bus.idle(11);
    assert_eq!(m.read32(regs::MSR) & (msr::INAK | msr::SLAK), 0);
}

/// Installs filter bank `bank` as a 32-bit mask filter accepting everything into `fifo`.
pub fn accept_all(m: &mut BxCanModel, bank: usize, fifo: usize) {
    m.modify32(regs::FMR, |v| v | fmr::FINIT);
    m.modify32(regs::FS1R, |v| v | fs1r::fsc(bank));
    m.modify32(regs::FM1R, |v| v & !fm1r::fbm(bank));
    m.modify32(regs::FFA1R, |v| {
        if fifo == 1 {
            v | ffa1r::ffa(bank)
        } else {
            v & !ffa1r::ffa(bank)
        }
    });
    m.write32(regs::fir1(bank), 0);
    m.write32(regs::fir2(bank), 0);
    m.modify32(regs::FA1R, |v| v | fa1r::fact(bank));
    m.modify32(regs::FMR, |v| v & !fmr::FINIT);
}

/// Starts a model already on `bus`: initialization, an accept-all filter into FIFO 0,
/// normal mode.
pub fn start(m: &mut BxCanModel, bus: &mut TinyBus) {
    enter_init(m);
    accept_all(m, 0, 0);
    leave_init(m, bus);
}

/// A model in normal mode, accepting everything into FIFO 0, alone on a tiny bus.
pub fn started(mut m: BxCanModel) -> (BxCanModel, TinyBus) {
    let mut bus = TinyBus::new(&[&m]);
    start(&mut m, &mut bus);
    (m, bus)
}

/// Two models in normal mode accepting everything into FIFO 0, on one tiny bus
/// (node 0 = `a`, node 1 = `b`).
pub fn started_pair(mut a: BxCanModel, mut b: BxCanModel) -> (BxCanModel, BxCanModel, TinyBus) {
    let mut bus = TinyBus::new(&[&a, &b]);
    start(&mut a, &mut bus);
    start(&mut b, &mut bus);
    (a, b, bus)
}

/// The `TIxR` value of a frame (without TXRQ).
pub fn tir_of(f: &Frame) -> u32 {
    let raw = f.raw_id();
    let mut v = if f.is_extended() {
        tixr::STID.val(raw >> 18) | tixr::EXID.val(raw) | tixr::IDE
    } else {
        tixr::STID.val(raw)
    };
    if f.is_remote() {
        v |= tixr::RTR;
    }
    v
}

/// Loads `f` into transmit mailbox `x` and requests its transmission.
pub fn load(m: &mut BxCanModel, x: usize, f: &Frame) {
    let d = f.data_padded();
    m.write32(regs::tdtxr(x), tdtxr::DLC.val(f.dlc() as u32));
    m.write32(regs::tdlxr(x), u32::from_le_bytes([d[0], d[1], d[2], d[3]]));
    m.write32(regs::tdhxr(x), u32::from_le_bytes([d[4], d[5], d[6], d[7]]));
    m.write32(regs::tixr(x), tir_of(f) | tixr::TXRQ);
}

/// A message read from a FIFO output mailbox.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Received {
    /// The frame.
    pub frame: Frame,
    /// `RDTxR.FMI`.
    pub fmi: u32,
    /// `RDTxR.TIME`.
    pub time: u32,
}

/// Reads the output mailbox of FIFO `x` and releases it (RFOM), if a message is pending.
pub fn receive(m: &mut BxCanModel, x: usize) -> Option<Received> {
    if rfxr::FMP.get(m.read32(regs::rfxr(x))) == 0 {
        return None;
    }
    let rir = m.read32(regs::rixr(x));
    let rdtr = m.read32(regs::rdtxr(x));
    let mut data = [0u8; 8];
    data[..4].copy_from_slice(&m.read32(regs::rdlxr(x)).to_le_bytes());
    data[4..].copy_from_slice(&m.read32(regs::rdhxr(x)).to_le_bytes());
    let ide = rir & rixr::IDE != 0;
    let raw = if ide {
        (rixr::STID.get(rir) << 18) | rixr::EXID.get(rir)
    } else {
        rixr::STID.get(rir)
    };
    let dlc = rdtxr::DLC.get(rdtr) as u8;
    let frame = Frame::from_registers(raw, ide, rir & rixr::RTR != 0, dlc, data).unwrap();
    m.write32(regs::rfxr(x), rfxr::RFOM);
    Some(Received {
        frame,
        fmi: rdtxr::FMI.get(rdtr),
        time: rdtxr::TIME.get(rdtr),
    })
}

/// A standard data frame.
pub fn std_frame(id: u16, data: &[u8]) -> Frame {
    Frame::standard(id, data).unwrap()
}

/// An extended data frame.
pub fn ext_frame(id: u32, data: &[u8]) -> Frame {
    Frame::extended(id, data).unwrap()
}
