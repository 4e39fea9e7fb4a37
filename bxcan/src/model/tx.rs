//! The three transmit mailboxes and `CAN_TSR` (RM0410 40.7.1 "Transmission handling";
//! notes "The bxCAN Transmission Handling", "The bxCAN Transmit Mailbox States").
//!
//! Rules modelled:
//! - Software loads an empty mailbox (`TIxR`, `TDTxR`, `TDLxR`, `TDHxR`) and sets `TXRQ`;
//!   once the mailbox has left the empty state its registers are no longer writable
//!   (writes are ignored). Setting `TXRQ` clears `RQCPx` and with it `TXOKx`, `ALSTx`,
//!   `TERRx` ("cleared by hardware on transmission request").
//! - States: empty → pending → scheduled (the highest-priority pending mailbox) →
//!   transmit (offered to the bus) → empty. Priority: `MCR.TXFP = 0` by identifier —
//!   the arbitration key [`Priority`], equal keys → lower mailbox number; `TXFP = 1` by
//!   request order.
//! - Each attempt sets `TXOKx`/`ALSTx`/`TERRx` to describe that attempt ("the previous
//!   TX"); a successful one sets `RQCPx` and empties the mailbox. A failed one: with
//!   `MCR.NART = 1` (or a pending abort) the request completes (`RQCPx`, `TXOKx = 0`,
//!   empty); otherwise the mailbox is scheduled again (automatic retransmission).
//! - `ABRQx` on a pending or scheduled mailbox aborts it at once (`RQCPx = 1`,
//!   `TXOKx = 0`, empty). On a mailbox in transmit state the abort waits: a successful
//!   transmission completes with `TXOKx = 1`, a failed one is aborted. `ABRQx` reads 1
//!   until then. On an empty mailbox it has no effect.
//! - `RQCPx`, `TXOKx`, `ALSTx`, `TERRx` are `rc_w1`; writing 1 to `RQCPx` clears the
//!   other three as well.
//! - `TMEx` = mailbox empty. `CODE` = the lowest-numbered empty mailbox, or, when all
//!   three are full, the lowest-priority one. `LOWx` = mailbox x has the lowest priority
//!   while more than one mailbox is pending (RM0410 40.9.2 "CAN transmit status
//!   register").
//! - `TGT` (time-triggered mode, DLC = 8): the time stamp of the start of frame replaces
//!   data bytes 6 (`TIME[15:8]`) and 7 (`TIME[7:0]`) on the bus. RM0410 40.7.7 asks for
//!   the DLC "programmed as 8": a code of 9..15 sends no time stamp.
//! - A DLC code of 9..15 is sent as written, with eight data bytes (ISO 11898-1).

use twocan_core::{Frame, MailboxState, Priority};

use crate::regs::{tdtxr, tixr, tsr, TX_MAILBOXES};

const TDTR_WRITABLE: u32 = tdtxr::DLC.mask() | tdtxr::TGT | tdtxr::TIME.mask();

/// How one transmission attempt ended for its mailbox.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Attempt {
    /// Sent and acknowledged.
    Ok,
    /// Arbitration lost.
    ArbitrationLost,
    /// An error was detected.
    Error,
}

#[derive(Debug, Clone, Copy, Default)]
struct Mailbox {
    /// `[TIxR, TDTxR, TDLxR, TDHxR]`; `TXRQ` is kept in `requested`.
    regs: [u32; 4],
    requested: bool,
    /// Request order, for `TXFP = 1`.
    seq: u64,
    /// An abort requested while the mailbox was in transmit state.
    abort: bool,
}

/// The transmit side of a controller.
#[derive(Debug, Clone, Default)]
pub(crate) struct TxUnit {
    boxes: [Mailbox; TX_MAILBOXES],
    /// `RQCPx`, `TXOKx`, `ALSTx`, `TERRx` bits of `CAN_TSR`.
    status: u32,
    next_seq: u64,
    /// The mailbox last offered to the bus by `poll_tx`: in transmit state until the bus
    /// reports the attempt's end or idle time.
    offered: Option<usize>,
}

fn status_bits(x: usize) -> u32 {
    tsr::rqcp(x) | tsr::txok(x) | tsr::alst(x) | tsr::terr(x)
}

impl TxUnit {
    /// Three empty mailboxes.
    pub(crate) fn new() -> Self {
        Self::default()
    }

    /// Register `reg` (0 = TIxR, 1 = TDTxR, 2 = TDLxR, 3 = TDHxR) of mailbox `x`.
    pub(crate) fn read(&self, x: usize, reg: usize) -> u32 {
        match self.boxes.get(x) {
            Some(b) if reg == 0 => b.regs[0] | if b.requested { tixr::TXRQ } else { 0 },
            Some(b) if reg < 4 => b.regs[reg],
            _ => 0,
        }
    }

    /// A software write to register `reg` of mailbox `x`: accepted only while empty.
    pub(crate) fn write(&mut self, x: usize, reg: usize, value: u32) {
        let Some(b) = self.boxes.get_mut(x) else {
            return;
        };
        if b.requested || reg >= 4 {
            return;
        }
        match reg {
            0 => {
                b.regs[0] = value & !tixr::TXRQ;
                if value & tixr::TXRQ != 0 {
                    b.requested = true;
                    b.abort = false;
                    b.seq = self.next_seq;
                    self.next_seq += 1;
                    self.status &= !status_bits(x);
                }
            }
            1 => b.regs[1] = value & TDTR_WRITABLE,
            _ => b.regs[reg] = value,
        }
    }

    /// Whether mailbox `x` holds a transmit request.
    pub(crate) fn is_requested(&self, x: usize) -> bool {
        self.boxes.get(x).is_some_and(|b| b.requested)
    }

    /// The mailbox in transmit state, if any.
    pub(crate) fn offered(&self) -> Option<usize> {
        self.offered
    }

    /// Marks mailbox `x` as offered to the bus (transmit state).
    pub(crate) fn set_offered(&mut self, x: usize) {
        self.offered = Some(x);
    }

    fn priority(&self, x: usize) -> Priority {
        let tir = self.boxes[x].regs[0];
        let ide = tir & tixr::IDE != 0;
        Priority::from_raw(raw_id(tir), ide, tir & tixr::RTR != 0)
    }

    /// The requested mailboxes, highest priority first.
    fn order(&self, txfp: bool) -> ([usize; TX_MAILBOXES], usize) {
        let mut list = [0usize; TX_MAILBOXES];
        let mut n = 0;
        for x in 0..TX_MAILBOXES {
            if self.boxes[x].requested {
                list[n] = x;
                n += 1;
            }
        }
        let slice = &mut list[..n];
        if txfp {
            slice.sort_by_key(|&x| self.boxes[x].seq);
        } else {
            slice.sort_by_key(|&x| (self.priority(x), x));
        }
        (list, n)
    }

    /// The mailbox the controller would transmit next (the scheduled one).
    pub(crate) fn next(&self, txfp: bool) -> Option<usize> {
        let (list, n) = self.order(txfp);
        (n > 0).then_some(list[0])
    }

    /// The frame mailbox `x` sends with `timestamp` as its start-of-frame time stamp.
    pub(crate) fn frame(&self, x: usize, timestamp: u16, ttcm: bool) -> Option<Frame> {
        let b = self.boxes.get(x)?;
        let [tir, tdtr, tdlr, tdhr] = b.regs;
        let dlc = tdtxr::DLC.get(tdtr) as u8;
        let mut data = [0u8; 8];
        data[..4].copy_from_slice(&tdlr.to_le_bytes());
        data[4..].copy_from_slice(&tdhr.to_le_bytes());
        if ttcm && tdtr & tdtxr::TGT != 0 && dlc == 8 {
            data[6] = (timestamp >> 8) as u8;
            data[7] = timestamp as u8;
        }
        let ide = tir & tixr::IDE != 0;
        Frame::from_registers(raw_id(tir), ide, tir & tixr::RTR != 0, dlc, data).ok()
    }

    /// Writes the start-of-frame time stamp into `TDTxR.TIME` of mailbox `x`.
    pub(crate) fn stamp(&mut self, x: usize, time: u16) {
        if let Some(b) = self.boxes.get_mut(x) {
            b.regs[1] = tdtxr::TIME.set(b.regs[1], time as u32);
        }
    }

    /// `CAN_TSR` as read.
    pub(crate) fn tsr(&self, txfp: bool) -> u32 {
        let mut v = self.status;
        let mut code = None;
        for (x, b) in self.boxes.iter().enumerate() {
            if !b.requested {
                v |= tsr::tme(x);
                code = code.or(Some(x));
            }
            if b.abort {
                v |= tsr::abrq(x);
            }
        }
        let (list, n) = self.order(txfp);
        if n > 1 {
            v |= tsr::low(list[n - 1]);
        }
        let code = code.unwrap_or(list[n.saturating_sub(1)]);
        v | tsr::CODE.val(code as u32)
    }

    /// A software write to `CAN_TSR`: `rc_w1` status bits and `ABRQx`.
    pub(crate) fn write_tsr(&mut self, value: u32) {
        for x in 0..TX_MAILBOXES {
            if value & tsr::rqcp(x) != 0 {
                self.status &= !status_bits(x);
            }
            self.status &= !(value & (tsr::txok(x) | tsr::alst(x) | tsr::terr(x)));
            if value & tsr::abrq(x) != 0 && self.boxes[x].requested {
                if self.offered == Some(x) {
                    self.boxes[x].abort = true;
                } else {
                    self.finish(x);
                }
            }
        }
    }

    /// Ends the request of mailbox `x`: empty, `RQCPx` set.
    fn finish(&mut self, x: usize) {
        let b = &mut self.boxes[x];
        b.requested = false;
        b.abort = false;
        self.status |= tsr::rqcp(x);
        if self.offered == Some(x) {
            self.offered = None;
        }
    }

    /// The end of a transmission attempt of mailbox `x`.
    pub(crate) fn complete(&mut self, x: usize, attempt: Attempt, nart: bool) {
        self.offered = None;
        if !self.is_requested(x) {
            return;
        }
        self.status &= !(tsr::txok(x) | tsr::alst(x) | tsr::terr(x));
        self.status |= match attempt {
            Attempt::Ok => tsr::txok(x),
            Attempt::ArbitrationLost => tsr::alst(x),
            Attempt::Error => tsr::terr(x),
        };
        if attempt == Attempt::Ok || nart || self.boxes[x].abort {
            self.finish(x);
        }
    }

    /// The bus stayed idle after an offer: nothing was started, so the mailbox in
    /// transmit state falls back to scheduled, and an abort waiting for it takes effect.
    pub(crate) fn bus_idle(&mut self) {
        if let Some(x) = self.offered.take() {
            if self.boxes[x].abort {
                self.finish(x);
            }
        }
    }

    /// The state of each mailbox (notes: "The bxCAN Transmit Mailbox States").
    pub(crate) fn states(&self, txfp: bool) -> [MailboxState; TX_MAILBOXES] {
        let mut out = [MailboxState::Empty; TX_MAILBOXES];
        let (list, n) = self.order(txfp);
        let mut scheduled = false;
        for &x in &list[..n] {
            out[x] = if self.offered == Some(x) {
                MailboxState::Transmitting
            } else if !scheduled {
                scheduled = true;
                MailboxState::Scheduled
            } else {
                MailboxState::Pending
            };
        }
        out
    }
}

/// The identifier held by a `TIxR` value.
fn raw_id(tir: u32) -> u32 {
    if tir & tixr::IDE != 0 {
        (tixr::STID.get(tir) << 18) | tixr::EXID.get(tir)
    } else {
        tixr::STID.get(tir)
    }
}
