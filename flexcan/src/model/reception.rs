//! Where a received frame goes ("Matching process", table "Matching possibilities and
//! resulting reception structures"; "Remote frames"; CTRL2\[MRP\], CTRL2\[RRS\], MCR\[IRMQ\]).
//!
//! - A remote request with CTRL2\[RRS\] = 0 is not stored in a mailbox: if it matches a FIFO
//!   filter it goes to the FIFO ("FlexCAN will not generate an automatic response for
//!   remote request frames that match the FIFO filtering criteria"), otherwise it turns a
//!   RANSWER mailbox with the same identifier into TANSWER, otherwise it is dropped. With
//!   RRS = 1 it is matched like a data frame.
//! - The mailbox winner is, with IRMQ = 1, the first matching mailbox free to receive, or
//!   else the last matching one (overrun); with IRMQ = 0 the first matching mailbox.
//! - With the FIFO enabled: MRP = 0 tries the FIFO first (stored if it matched and is not
//!   full; if full the mailbox winner takes the frame, or it is lost as FIFO overflow);
//!   MRP = 1 tries the mailboxes first (a free mailbox takes it; with IRMQ = 1 and only
//!   non-free matches the FIFO takes it if it matched and is not full, else the last
//!   mailbox is overrun; with IRMQ = 0 any match takes it).
//! - A frame that matches nothing is discarded.

use twocan_core::frame::Frame;

use crate::regs::{ctrl2, RX_FIFO_DEPTH};

use super::state::State;

/// The FIFO's answer to a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum FifoHit {
    /// No filter matched (as if there were no FIFO).
    None,
    /// Matched filter `idhit`, room to store.
    NotFull(u16),
    /// Matched, but six frames are waiting.
    Full,
}

impl State {
    /// Delivers a correctly received frame (from the bus or self-received).
    pub fn accept_frame(&mut self, frame: &Frame, stamp: u16) {
        let fifo = if self.rfen() {
            match self.fifo_match(frame) {
                None => FifoHit::None,
                Some(_) if self.fifo.len() >= RX_FIFO_DEPTH => FifoHit::Full,
                Some(idhit) => FifoHit::NotFull(idhit),
            }
        } else {
            FifoHit::None
        };

        if frame.is_remote() && !self.ctrl2_bit(ctrl2::RRS) {
            match fifo {
                FifoHit::NotFull(idhit) => self.fifo_store(frame, stamp, idhit),
                FifoHit::Full => self.fifo_store(frame, stamp, 0),
                FifoHit::None => match self.ranswer_match(frame) {
                    Some(n) => self.ranswer_hit(n),
                    None => self.discarded += 1,
                },
            }
            return;
        }

        let scan = self.rx_scan(frame);
        let irmq = self.irmq();
        let mb_winner = if irmq {
            scan.first_free.or(scan.last)
        } else {
            scan.first
        };
        let to_fifo = |s: &mut State| match fifo {
            FifoHit::NotFull(idhit) => s.fifo_store(frame, stamp, idhit),
            // `fifo_store` on a full FIFO counts the overflow.
            FifoHit::Full => s.fifo_store(frame, stamp, 0),
            FifoHit::None => s.discarded += 1,
        };

        if fifo == FifoHit::None {
            match mb_winner {
                Some(n) => self.mb_store(n, frame, stamp),
                None => self.discarded += 1,
            }
            return;
        }
        if !self.ctrl2_bit(ctrl2::MRP) {
            match (fifo, mb_winner) {
                (FifoHit::NotFull(_), _) | (_, None) => to_fifo(self),
                (_, Some(n)) => self.mb_store(n, frame, stamp),
            }
            return;
        }
        // MRP = 1: mailboxes first.
        if irmq {
            if let Some(n) = scan.first_free {
                self.mb_store(n, frame, stamp);
            } else if let (Some(n), FifoHit::Full) = (scan.last, fifo) {
                self.mb_store(n, frame, stamp);
            } else {
                to_fifo(self);
            }
        } else {
            match scan.first {
                Some(n) => self.mb_store(n, frame, stamp),
                None => to_fifo(self),
            }
        }
    }
}
