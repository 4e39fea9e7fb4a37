//! The fast path of a frame attempt: a single transmitter, no injected fault, and an
//! acknowledgement (some receiver acknowledges, or the transmitter acknowledges its own
//! frame). Then nothing can go wrong — no node can detect an error: the wire is the
//! transmitter's stuffed bits, the ACK slot, the recessive delimiters and end of frame —
//! and the outcome is known without playing the bits: every participant completes at the
//! end of the end of frame, exactly as the bit-level engine (`engine::resolve_with`) would find.
//!
//! Everything else (arbitration ties, faults, an attempt nobody acknowledges, which ends
//! in an acknowledge error) goes through the bit-level engine. `sim_fast_path.rs` checks
//! that both give the same traces and counters on random seeded traffic.

use super::bits::FrameBits;
use super::engine::{PartOutcome, Resolution};
#[cfg(test)]
use super::engine::{RxSpec, TxSpec};

/// Whether an attempt with a single transmitter and no fault can take the fast path:
/// `Some(acked)` if some receiver acknowledges (`any_ack`) or the transmitter acknowledges
/// its own frame (`self_ack`), `None` otherwise (it ends in an acknowledge error: the
/// bit-level engine plays it).
pub(crate) const fn decide(self_ack: bool, any_ack: bool) -> Option<bool> {
    if any_ack || self_ack {
        Some(any_ack)
    } else {
        None
    }
}

/// [`decide`] for attempts described as the engine's specs.
#[cfg(test)]
fn applies(txs: &[TxSpec<'_>], rxs: &[RxSpec]) -> Option<bool> {
    let [tx] = txs else {
        return None;
    };
    if !tx.faults.is_empty() || rxs.iter().any(|r| !r.faults.is_empty()) {
        return None;
    }
    decide(tx.self_ack, rxs.iter().any(|r| r.acks))
}

/// The resolution of a fault-free, acknowledged attempt of a frame laid out as `bits`
/// whose stuffed bits are `stream` (taken as the start of the wire), with `receivers`
/// receivers.
pub(crate) fn resolve(
    bits: FrameBits,
    acked: bool,
    receivers: usize,
    mut stream: Vec<bool>,
) -> Resolution {
    let ce = bits.crc_end;
    let total = ce + 10;
    stream.resize(ce as usize, true);
    // CRC delimiter, ACK slot, ACK delimiter, 7 bits of end of frame.
    stream.push(true);
    stream.push(!acked);
    stream.resize(total as usize, true);
    let last_dominant_end = if acked {
        ce + 2
    } else {
        stream.iter().rposition(|&b| !b).map_or(0, |i| i as u32 + 1)
    };
    let done = PartOutcome::Ok { done: total };
    Resolution {
        tx: vec![done],
        rx: vec![done; receivers],
        observer_ok: true,
        acked,
        end: total,
        last_dominant_end,
        wire: stream,
        reference: 0,
        tx_penalties: Vec::new(),
        rx_penalties: Vec::new(),
        rx_more_errors: Vec::new(),
        missed: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bits::wire_bits;
    use crate::engine;
    use twocan_core::frame::Frame;

    #[test]
    fn same_resolution_as_the_bit_level_engine() {
        let mut x = 0x2545_F491_4F6C_DD1Du64;
        let mut rnd = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let mut fast_count = 0;
        for _ in 0..2_000 {
            let len = (rnd() % 9) as usize;
            let data: Vec<u8> = (0..len).map(|_| rnd() as u8).collect();
            let frame = if rnd() % 2 == 0 {
                Frame::standard((rnd() % 0x800) as u16, &data).unwrap()
            } else {
                Frame::extended((rnd() % 0x2000_0000) as u32, &data).unwrap()
            };
            let w = wire_bits(&frame);
            let txs = [TxSpec {
                stream: &w.0,
                bits: w.1,
                self_ack: rnd() % 4 == 0,
                active: rnd() % 2 == 0,
                faults: Vec::new(),
            }];
            let rxs: Vec<RxSpec> = (0..rnd() % 4)
                .map(|_| {
                    let acks = rnd() % 3 != 0;
                    RxSpec {
                        acks,
                        active: acks && rnd() % 2 == 0,
                        faults: Vec::new(),
                    }
                })
                .collect();
            let slow = engine::resolve(&txs, &rxs);
            match applies(&txs, &rxs) {
                Some(acked) => {
                    fast_count += 1;
                    let fast = resolve(w.1, acked, rxs.len(), w.0.clone());
                    assert_eq!(fast, slow, "{frame:?}");
                }
                None => assert!(!txs[0].self_ack && rxs.iter().all(|r| !r.acks)),
            }
        }
        assert!(fast_count > 1_000);
    }
}
