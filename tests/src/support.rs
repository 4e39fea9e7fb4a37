//! Helpers of the cross-controller tests: plain ISO peers, running the bus, frame sets,
//! the reference filter semantics and the expected-frames file of the candump check.

use std::cell::RefCell;
use std::fmt::Write as _;
use std::rc::Rc;

use twocan_core::{Filter, Frame, RxFrame};
use twocan_host::{Harness, Serviced};
use twocan_sim::{NodeId, SimNode, TxResult};

use crate::backend::Dut;

/// A plain ISO node shared with the bus.
pub type Peer = Rc<RefCell<SimNode>>;

/// Attaches a plain ISO node (acknowledges, retries, recovers by itself).
pub fn attach_peer(h: &Harness, name: &str) -> (Peer, NodeId) {
    attach_sim(h, name, SimNode::new())
}

/// Attaches `node` and keeps a handle on it.
pub fn attach_sim(h: &Harness, name: &str, node: SimNode) -> (Peer, NodeId) {
    let shared = node.shared();
    let id = h.bus().borrow_mut().attach(name, shared.clone());
    (shared, id)
}

/// Runs the bus for `bits` bit times, servicing `node` after every bus event.
pub fn run<N: Dut>(h: &mut Harness, node: &mut N, bits: u64) {
    h.run_for(bits, &mut [node as &mut dyn Serviced]);
}

/// Runs until every peer's queue is empty and `node` has nothing left to send (or
/// `max_bits` passed), then 200 more bit times; servicing `node` throughout.
pub fn settle<N: Dut>(h: &mut Harness, node: &mut N, peers: &[&Peer], max_bits: u64) {
    let end = h.now() + max_bits;
    while h.now() < end {
        run(h, node, 100);
        let t = node.driver_ref().traffic();
        let done = t.sent + t.failed + t.aborted >= t.queued;
        if done && peers.iter().all(|p| p.borrow().pending() == 0) {
            break;
        }
    }
    run(h, node, 200);
}

/// Every frame in the node's receive ring, oldest first.
pub fn drain<N: Dut>(node: &mut N) -> Vec<RxFrame> {
    std::iter::from_fn(|| node.driver().receive().ok()).collect()
}

/// Frames a plain node sent successfully, in order.
pub fn acked(peer: &Peer) -> Vec<Frame> {
    peer.borrow()
        .tx_reports()
        .iter()
        .filter(|r| r.result == TxResult::Acked)
        .map(|r| r.frame)
        .collect()
}

/// The index of the first filter of `filters` that accepts `frame` (the reference
/// semantics of `Filter::matches` and ACAN's first-match rule), `None` if none does.
pub fn first_match(filters: &[Filter], frame: &Frame) -> Option<u16> {
    filters
        .iter()
        .position(|f| f.matches(frame))
        .map(|i| i as u16)
}

/// A standard data frame.
pub fn std_frame(id: u16, data: &[u8]) -> Frame {
    Frame::standard(id, data).expect("standard frame")
}

/// An extended data frame.
pub fn ext_frame(id: u32, data: &[u8]) -> Frame {
    Frame::extended(id, data).expect("extended frame")
}

/// A remote frame.
pub fn remote_frame(id: u32, extended: bool, dlc: u8) -> Frame {
    Frame::remote(id, extended, dlc).expect("remote frame")
}

/// `n` bytes `seed, seed + 1, …` (wrapping).
pub fn bytes(n: usize, seed: u8) -> Vec<u8> {
    (0..n).map(|i| seed.wrapping_add(i as u8)).collect()
}

/// Data and remote frames of both formats, every DLC 0..=8, identifiers at the edges of
/// both ranges and in between.
pub fn frame_zoo() -> Vec<Frame> {
    let mut v = Vec::new();
    let std_ids = [0x000u16, 0x001, 0x123, 0x3FF, 0x400, 0x555, 0x7FE, 0x7FF];
    let ext_ids = [
        0x0000_0000u32,
        0x0000_07FF,
        0x0000_0800,
        0x0123_4567,
        0x0ABC_DEF0,
        0x1555_5555,
        0x1FFF_FFFE,
        0x1FFF_FFFF,
    ];
    for (k, &id) in std_ids.iter().enumerate() {
        let n = k % 9;
        v.push(std_frame(id, &bytes(n, k as u8 * 17)));
    }
    for (k, &id) in ext_ids.iter().enumerate() {
        let n = (k + 4) % 9;
        v.push(ext_frame(id, &bytes(n, 0x80 + k as u8)));
    }
    for dlc in 0..=8u8 {
        v.push(remote_frame(0x100 + u32::from(dlc), false, dlc));
        v.push(remote_frame(0x1234_0000 + u32::from(dlc), true, dlc));
    }
    v.push(std_frame(0x7FF, &[0xFF; 8]));
    v.push(ext_frame(0x1FFF_FFFF, &[0x00; 8]));
    v
}

/// One line of the expected-frames file of `tests/python/check_candump.py`: JSON with the
/// time stamp (seconds, microsecond resolution), identifier, format, kind, DLC and data.
pub fn json_line(micros: u64, frame: &Frame) -> String {
    let mut data = String::new();
    for b in frame.data() {
        let _ = write!(data, "{b:02x}");
    }
    format!(
        "{{\"timestamp\": {}.{:06}, \"id\": {}, \"extended\": {}, \"remote\": {}, \"dlc\": {}, \"data\": \"{}\"}}",
        micros / 1_000_000,
        micros % 1_000_000,
        frame.raw_id(),
        frame.is_extended(),
        frame.is_remote(),
        frame.dlc(),
        data
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_line_form() {
        let f = std_frame(0x123, &[0xDE, 0xAD]);
        assert_eq!(
            json_line(1_000_042, &f),
            "{\"timestamp\": 1.000042, \"id\": 291, \"extended\": false, \"remote\": false, \"dlc\": 2, \"data\": \"dead\"}"
        );
        let r = remote_frame(0x1ABC_DEF0, true, 4);
        assert!(json_line(5, &r).contains("\"remote\": true, \"dlc\": 4, \"data\": \"\""));
    }

    #[test]
    fn zoo_has_every_kind() {
        let z = frame_zoo();
        assert!(z.iter().any(|f| f.is_remote() && f.is_extended()));
        assert!(z.iter().any(|f| f.is_remote() && !f.is_extended()));
        assert!(z.iter().any(|f| !f.is_remote() && f.is_extended()));
        for dlc in 0..=8 {
            assert!(z.iter().any(|f| !f.is_remote() && f.dlc() == dlc));
        }
    }
}
