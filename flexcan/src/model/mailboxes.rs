//! Message buffers as mailboxes: the code state machines, transmit arbitration, abort,
//! receive matching, locking and move-in ("Message buffer structure", tables "Message
//! buffer code for Rx buffers" and "Message buffer code for Tx buffers", "Arbitration
//! process", "Matching process", "Transmission abort mechanism", "Mailbox lock
//! mechanism", "Remote frames").

use twocan_core::frame::Frame;
use twocan_core::priority::Priority;

use crate::regs::{code, cs, ctrl1, ctrl2, id, mcr};

use super::codec;
use super::state::{State, MAX_MBS};

/// A frame waiting in the serial message buffer for a locked mailbox.
#[derive(Debug, Clone, Copy)]
struct Pending {
    mb: usize,
    frame: Frame,
    stamp: u16,
}

/// Per-mailbox bookkeeping the CPU cannot see directly.
#[derive(Debug)]
pub(crate) struct Mailboxes {
    /// The mailbox locked by a read of its C/S word.
    pub locked: Option<usize>,
    /// FULL/OVERRUN mailboxes read and unlocked by the CPU since their last move-in
    /// ("SRV: serviced MB"), hence free to receive again.
    serviced: [bool; MAX_MBS],
    /// The serial message buffer holding a frame for the locked mailbox.
    smb: Option<Pending>,
    /// Frames written over an unread frame (OVERRUN) or dropped from the SMB.
    pub overruns: u64,
    /// The mailbox whose frame is on the wire (from its start of frame to the outcome).
    pub in_tx: Option<usize>,
    /// ABORT was written to `in_tx` while it was being transmitted (with MCR\[AEN\]): the
    /// abort waits for the end of the transmission.
    pub abort_pending: bool,
}

/// Which mailboxes a received frame matched.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct MbScan {
    /// Lowest-numbered matching mailbox.
    pub first: Option<usize>,
    /// Lowest-numbered matching mailbox that is free to receive.
    pub first_free: Option<usize>,
    /// Highest-numbered matching mailbox.
    pub last: Option<usize>,
}

impl Mailboxes {
    pub fn new() -> Self {
        Mailboxes {
            locked: None,
            serviced: [false; MAX_MBS],
            smb: None,
            overruns: 0,
            in_tx: None,
            abort_pending: false,
        }
    }

    /// Soft reset: the lock and the serial message buffer are internal state.
    pub fn reset_locks(&mut self) {
        self.locked = None;
        self.smb = None;
        self.in_tx = None;
        self.abort_pending = false;
    }
}

/// Whether a code makes the mailbox a pending transmission (DATA/REMOTE or TANSWER).
fn is_tx_pending(c: u32) -> bool {
    c == code::TX_DATA || c == code::TX_TANSWER
}

/// Whether a code makes the mailbox take part in receive matching (BUSY variants are
/// ignored by the matching process).
fn is_rx_active(c: u32) -> bool {
    c == code::RX_EMPTY || c == code::RX_FULL || c == code::RX_OVERRUN
}

impl State {
    /// CS\[CODE\] of mailbox `n`.
    pub fn mb_code(&self, n: usize) -> u32 {
        cs::CODE.get(self.mb_word(n, 0))
    }

    fn set_mb_code(&mut self, n: usize, c: u32) {
        self.ram[4 * n] = cs::CODE.replace(self.ram[4 * n], c);
    }

    // --- transmit ------------------------------------------------------------------------

    /// The frame a transmit mailbox holds.
    pub fn mb_tx_frame(&self, n: usize) -> Option<Frame> {
        codec::decode(self.mb_words(n))
    }

    /// The mailbox that wins the internal arbitration ("Arbitration process"): with
    /// CTRL1\[LBUF\] = 1 the lowest-numbered pending mailbox; otherwise the highest-priority
    /// frame (the bus arbitration order, [`Priority`]), preceded by ID\[PRIO\] when
    /// MCR\[LPRIOEN\] = 1, ties going to the lowest-numbered mailbox.
    pub fn select_tx(&self) -> Option<usize> {
        let pending = self
            .active_mbs()
            .filter(|&n| is_tx_pending(self.mb_code(n)));
        if self.ctrl1_bit(ctrl1::LBUF) {
            return pending.into_iter().find(|&n| self.mb_tx_frame(n).is_some());
        }
        let lprio = self.mcr_bit(mcr::LPRIOEN);
        pending
            .filter_map(|n| {
                let frame = self.mb_tx_frame(n)?;
                let prio = if lprio {
                    id::PRIO.get(self.mb_word(n, 1))
                } else {
                    0
                };
                Some(((prio, Priority::of(&frame), n), n))
            })
            .min()
            .map(|(_, n)| n)
    }

    /// The pending mailbox that sent `frame`: the arbitration winner if it holds it,
    /// otherwise the first pending mailbox holding it.
    pub fn tx_mb_of(&self, frame: &Frame) -> Option<usize> {
        let holds = |n: usize| self.mb_tx_frame(n).is_some_and(|f| f == *frame);
        match self.select_tx() {
            Some(n) if holds(n) => Some(n),
            _ => self
                .active_mbs()
                .find(|&n| is_tx_pending(self.mb_code(n)) && holds(n)),
        }
    }

    /// Successful transmission from mailbox `n`: DATA → INACTIVE, REMOTE → Rx EMPTY with the
    /// same ID, TANSWER → RANSWER; the time stamp is written and IFLAG set.
    pub fn tx_done(&mut self, n: usize, stamp: u16) {
        let csw = self.mb_word(n, 0);
        let next = match cs::CODE.get(csw) {
            code::TX_TANSWER => code::RX_RANSWER,
            _ if csw & cs::RTR != 0 => code::RX_EMPTY,
            _ => code::TX_INACTIVE,
        };
        let csw = cs::TIME_STAMP.replace(cs::CODE.replace(csw, next), u32::from(stamp));
        self.ram[4 * n] = csw;
        self.mbx.serviced[n] = false;
        self.iflag |= 1 << n;
    }

    /// Software wrote the C/S word of mailbox `n`. With MCR\[AEN\] = 1, writing ABORT over a
    /// pending transmission aborts it ("Transmission abort mechanism"):
    /// - a mailbox not being transmitted is aborted at once: the code becomes ABORT and
    ///   IFLAG is set;
    /// - a mailbox whose frame is on the wire keeps transmitting; the abort request is
    ///   captured and waits: if the transmission succeeds the mailbox completes as usual
    ///   (code INACTIVE, IFLAG set: the abort was not done), if it fails or loses
    ///   arbitration the abort is done (code ABORT, IFLAG set). Until then the C/S word
    ///   keeps its transmit code (the manual only lets software read CODE after IFLAG).
    ///
    /// Without AEN the write simply replaces the code (mailbox inactivation).
    pub fn cs_write(&mut self, n: usize, value: u32) {
        let old = self.mb_code(n);
        let new = cs::CODE.get(value);
        let aen_abort = self.mcr_bit(mcr::AEN) && new == code::TX_ABORT && is_tx_pending(old);
        if aen_abort && self.mbx.in_tx == Some(n) {
            self.mbx.abort_pending = true;
            return;
        }
        self.ram[4 * n] = value;
        if aen_abort {
            self.iflag |= 1 << n;
        }
        self.mbx.serviced[n] = false;
    }

    /// A frame attempt starts with this module as a transmitter: the mailbox that wins the
    /// internal arbitration is in transmission.
    pub fn tx_started(&mut self) {
        self.mbx.in_tx = self.select_tx();
        self.mbx.abort_pending = false;
    }

    /// The transmission in progress ended without success (error or lost arbitration): a
    /// captured abort is done now (code ABORT, IFLAG set).
    pub fn tx_failed(&mut self) {
        if let Some(n) = self.mbx.in_tx.take() {
            if core::mem::replace(&mut self.mbx.abort_pending, false) {
                self.set_mb_code(n, code::TX_ABORT);
                self.mbx.serviced[n] = false;
                self.iflag |= 1 << n;
            }
        }
    }

    /// The mailbox that sent `frame` now: the one in transmission, else as
    /// [`State::tx_mb_of`] finds it. A captured abort is dropped (the frame was sent).
    pub fn tx_succeeded_mb(&mut self, frame: &Frame) -> Option<usize> {
        self.mbx.abort_pending = false;
        let n = self.mbx.in_tx.take();
        n.filter(|&n| is_tx_pending(self.mb_code(n)))
            .or_else(|| self.tx_mb_of(frame))
    }

    // --- remote request answering --------------------------------------------------------

    /// A RANSWER mailbox whose identifier equals the remote request's ("The mask registers
    /// are not used in remote frame matching, and all ID bits (except RTR) of the incoming
    /// received frame should match").
    pub fn ranswer_match(&self, frame: &Frame) -> Option<usize> {
        self.active_mbs().find(|&n| {
            if self.mb_code(n) != code::RX_RANSWER {
                return false;
            }
            let csw = self.mb_word(n, 0);
            let idw = self.mb_word(n, 1);
            let ext = csw & cs::IDE != 0;
            let raw = if ext {
                id::EXT_ID.get(idw)
            } else {
                id::STD.get(idw)
            };
            ext == frame.is_extended() && raw == frame.raw_id()
        })
    }

    /// A matching remote request turns the RANSWER mailbox into TANSWER: it joins the next
    /// arbitration as an ordinary transmit mailbox.
    pub fn ranswer_hit(&mut self, n: usize) {
        self.set_mb_code(n, code::TX_TANSWER);
    }

    // --- receive -------------------------------------------------------------------------

    /// The acceptance mask of mailbox `n`: RXIMR\[n\] with MCR\[IRMQ\] = 1; otherwise
    /// RX14MASK/RX15MASK for MB14/MB15 and RXMGMASK for the others.
    fn mb_mask(&self, n: usize) -> u32 {
        if self.irmq() {
            self.rximr[n]
        } else {
            match n {
                14 => self.rx14mask,
                15 => self.rx15mask,
                _ => self.rxmgmask,
            }
        }
    }

    /// Whether receive mailbox `n` accepts `frame`. The ID is compared under the mask
    /// (bits 28–0; standard frames bits 28–18). With CTRL2\[EACEN\] = 0 IDE is always
    /// compared and RTR never; with EACEN = 1 mask bit 31 checks RTR and bit 30 checks IDE
    /// ("the two most significant mask bits affect the fields RTR and IDE").
    fn mb_accepts(&self, n: usize, frame: &Frame) -> bool {
        if !is_rx_active(self.mb_code(n)) {
            return false;
        }
        let mask = self.mb_mask(n);
        let csw = self.mb_word(n, 0);
        let idw = self.mb_word(n, 1);
        let ext = frame.is_extended();
        let mb_ext = csw & cs::IDE != 0;
        let mb_rtr = csw & cs::RTR != 0;
        if self.ctrl2_bit(ctrl2::EACEN) {
            if mask & (1 << 30) != 0 && mb_ext != ext {
                return false;
            }
            if mask & (1 << 31) != 0 && mb_rtr != frame.is_remote() {
                return false;
            }
        } else if mb_ext != ext {
            return false;
        }
        let (fid, idmask) = if ext {
            (id::EXT_ID.val(frame.raw_id()), id::EXT_ID.mask())
        } else {
            (id::STD.val(frame.raw_id()), id::STD.mask())
        };
        (fid ^ idw) & mask & idmask == 0
    }

    /// Whether mailbox `n` is free to receive: EMPTY, or FULL/OVERRUN already serviced,
    /// and not locked.
    fn mb_free(&self, n: usize) -> bool {
        if self.mbx.locked == Some(n) {
            return false;
        }
        match self.mb_code(n) {
            code::RX_EMPTY => true,
            code::RX_FULL | code::RX_OVERRUN => self.mbx.serviced[n],
            _ => false,
        }
    }

    /// The receive mailboxes matching `frame`.
    pub fn rx_scan(&self, frame: &Frame) -> MbScan {
        let mut scan = MbScan::default();
        for n in self.active_mbs() {
            if self.mb_accepts(n, frame) {
                scan.first.get_or_insert(n);
                if self.mb_free(n) {
                    scan.first_free.get_or_insert(n);
                }
                scan.last = Some(n);
            }
        }
        scan
    }

    /// Moves a received frame into mailbox `n` ("Move-in"), or into the serial message
    /// buffer while the mailbox is locked (a second frame there replaces the first).
    pub fn mb_store(&mut self, n: usize, frame: &Frame, stamp: u16) {
        if self.mbx.locked == Some(n) {
            let old = self.mbx.smb.replace(Pending {
                mb: n,
                frame: *frame,
                stamp,
            });
            if old.is_some() {
                self.mbx.overruns += 1;
            }
            return;
        }
        self.move_in(n, frame, stamp);
    }

    fn move_in(&mut self, n: usize, frame: &Frame, stamp: u16) {
        let next = match self.mb_code(n) {
            code::RX_FULL | code::RX_OVERRUN if !self.mbx.serviced[n] => {
                self.mbx.overruns += 1;
                code::RX_OVERRUN
            }
            _ => code::RX_FULL,
        };
        let prio = id::PRIO.get(self.mb_word(n, 1));
        self.set_mb_words(n, codec::encode(frame, stamp, next, prio));
        self.mbx.serviced[n] = false;
        self.iflag |= 1 << n;
        // CTRL1[TSYN]: reception in MB0 (or the first mailbox after the Rx FIFO table)
        // resets the free-running timer.
        if self.ctrl1_bit(ctrl1::TSYN) && n == self.first_mb() {
            self.timer.set(0);
        }
    }

    /// Reading the C/S word of mailbox `n` locks it (and unlocks any other).
    pub fn lock(&mut self, n: usize) {
        if self.mbx.locked != Some(n) {
            self.unlock();
            self.mbx.locked = Some(n);
        }
    }

    /// Reading TIMER (or another C/S word) unlocks: the mailbox counts as serviced and a
    /// frame held in the serial message buffer moves in.
    pub fn unlock(&mut self) {
        if let Some(n) = self.mbx.locked.take() {
            if matches!(self.mb_code(n), code::RX_FULL | code::RX_OVERRUN) {
                self.mbx.serviced[n] = true;
            }
            if let Some(p) = self.mbx.smb.take() {
                self.move_in(p.mb, &p.frame, p.stamp);
            }
        }
    }
}
