//! Operating modes and their handshakes (RM0410 40.4 "bxCAN operating modes", figure
//! "bxCAN operating modes").
//!
//! ```text
//! Reset → Sleep (SLAK = 1, INAK = 0)
//! Sleep  → Init    on  INRQ · !SLEEP · ACK
//! Sleep  → Normal  on !INRQ · !SLEEP · SYNC
//! Init   → Sleep   on  SLEEP · !INRQ · ACK
//! Init   → Normal  on !INRQ · !SLEEP · SYNC
//! Normal → Init    on  INRQ · ACK
//! Normal → Sleep   on  SLEEP · !INRQ · ACK
//! ```
//!
//! ACK is the hardware acknowledging a request (setting `INAK` or `SLAK`); the model
//! acknowledges at once, except that from normal mode it first lets a transmission in
//! progress end ("waits until the current CAN activity is completed"). SYNC is waiting
//! for 11 consecutive recessive bits on CANRX (bus idle), counted from the request;
//! bus activity restarts the count. With `INRQ` and `SLEEP` both set in normal mode the
//! model goes to initialization mode (RM0410 does not order the two requests).
//!
//! The fault injection "acknowledge stuck" freezes the machine: no transition completes.

/// Recessive bits that make the bus idle (SYNC).
pub(crate) const SYNC_BITS: u64 = 11;

/// A bxCAN operating mode (`MSR.INAK`, `MSR.SLAK`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Sleep mode (`SLAK = 1`): the state after reset.
    Sleep,
    /// Initialization mode (`INAK = 1`): off the bus, configurable.
    Initialization,
    /// Normal mode (`INAK = 0`, `SLAK = 0`): on the bus.
    Normal,
}

/// The inputs of the mode machine: `MCR.INRQ`, `MCR.SLEEP`, and whether the controller
/// is transmitting.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Requests {
    /// `MCR.INRQ`.
    pub inrq: bool,
    /// `MCR.SLEEP`.
    pub sleep: bool,
    /// A transmission is in progress (acknowledgements from normal mode wait).
    pub busy: bool,
}

/// The mode state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ModeMachine {
    mode: Mode,
    /// Consecutive recessive bits seen while waiting for SYNC, if waiting.
    sync: Option<u64>,
}

impl ModeMachine {
    /// The state after reset: sleep mode.
    pub(crate) fn new() -> Self {
        ModeMachine {
            mode: Mode::Sleep,
            sync: None,
        }
    }

    /// The current mode.
    pub(crate) fn mode(&self) -> Mode {
        self.mode
    }

    /// Whether a SYNC (11 recessive bits) is awaited to reach normal mode.
    pub(crate) fn syncing(&self) -> bool {
        self.sync.is_some()
    }

    fn wants_sync(&self, r: Requests) -> bool {
        self.mode != Mode::Normal && !r.inrq && !r.sleep
    }

    /// Takes every acknowledged transition the requests allow; returns the mode left and
    /// the mode entered, if the mode changed. Starts (or abandons) waiting for SYNC.
    pub(crate) fn step(&mut self, r: Requests, stuck: bool) -> Option<(Mode, Mode)> {
        if stuck {
            return None;
        }
        let next = match self.mode {
            Mode::Sleep if r.inrq && !r.sleep => Some(Mode::Initialization),
            Mode::Initialization if r.sleep && !r.inrq => Some(Mode::Sleep),
            Mode::Normal if r.inrq && !r.busy => Some(Mode::Initialization),
            Mode::Normal if r.sleep && !r.busy => Some(Mode::Sleep),
            _ => None,
        };
        let from = self.mode;
        if let Some(to) = next {
            self.mode = to;
            self.sync = None;
        }
        match (self.wants_sync(r), self.sync) {
            (true, None) => self.sync = Some(0),
            (false, Some(_)) => self.sync = None,
            _ => {}
        }
        next.map(|to| (from, to))
    }

    /// `bits` recessive bits monitored. Returns the transition to normal mode if SYNC
    /// completed, and how many of the bits came after it (monitored in normal mode).
    pub(crate) fn recessive(&mut self, bits: u64, stuck: bool) -> (Option<(Mode, Mode)>, u64) {
        if self.mode == Mode::Normal {
            return (None, bits);
        }
        let Some(run) = self.sync else {
            return (None, 0);
        };
        if stuck {
            return (None, 0);
        }
        let run = run.saturating_add(bits);
        if run >= SYNC_BITS {
            let from = self.mode;
            self.mode = Mode::Normal;
            self.sync = None;
            (Some((from, Mode::Normal)), run - SYNC_BITS)
        } else {
            self.sync = Some(run);
            (None, 0)
        }
    }

    /// Recessive bits still needed to complete SYNC, if waiting for it.
    pub(crate) fn sync_left(&self) -> Option<u64> {
        self.sync.map(|run| SYNC_BITS.saturating_sub(run).max(1))
    }

    /// Bus activity (a dominant bit): the run of recessive bits restarts.
    pub(crate) fn activity(&mut self) {
        if let Some(run) = self.sync.as_mut() {
            *run = 0;
        }
    }
}
