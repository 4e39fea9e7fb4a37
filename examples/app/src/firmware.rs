//! The application loop every firmware example runs, one copy for every board.
//!
//! A firmware keeps three `static`s that the firmware-in-the-loop tests and a debugger
//! read by symbol (their names and types are fixed: `can-fil` finds them in the ELF):
//! `STATS: Mutex<RefCell<Option<AppStats>>>`, `STATE_CHANGES: AtomicU32` and
//! `WORST_STATE: AtomicU32`. [`Published`] names them; [`FirmwareLoop::step`] runs one
//! period of the application over the driver's halves and updates them; what the board
//! logs and which LED it toggles stay in the board's code.
//!
//! ```
//! use core::cell::RefCell;
//! use core::sync::atomic::AtomicU32;
//! use critical_section::Mutex;
//! use twocan_app::firmware::{FirmwareLoop, Published};
//! use twocan_app::{App, AppStats};
//! use twocan_core::mock::MockHardware;
//! use twocan_core::Driver;
//!
//! static STATS: Mutex<RefCell<Option<AppStats>>> = Mutex::new(RefCell::new(None));
//! static STATE_CHANGES: AtomicU32 = AtomicU32::new(0);
//! static WORST_STATE: AtomicU32 = AtomicU32::new(0);
//! static OVERRUNS: AtomicU32 = AtomicU32::new(0);
//! static FIFO_WARNINGS: AtomicU32 = AtomicU32::new(0);
//! let published = Published {
//!     stats: &STATS,
//!     state_changes: &STATE_CHANGES,
//!     worst_state: &WORST_STATE,
//!     overruns: &OVERRUNS,
//!     fifo_warnings: &FIFO_WARNINGS,
//! };
//!
//! let mut driver: Driver<MockHardware, 8, 4> = Driver::new(MockHardware::new(3));
//! let mut app = App::new(1, 2);
//! let mut main_loop = FirmwareLoop::new();
//! let step = main_loop.step(&mut app, &mut driver, &published, |_| {});
//! assert_eq!(step.steps, 1);
//! assert!(step.stats.sent > 0, "the first period publishes");
//! assert_eq!(critical_section::with(|cs| *STATS.borrow_ref(cs)), Some(step.stats));
//! ```

use core::cell::RefCell;
use core::sync::atomic::{AtomicU32, Ordering};

use critical_section::Mutex;
use twocan_core::{CanRx, CanTx, ErrorState, ErrorStatistics, StateChange};

use crate::{App, AppStats};

/// A progress line every this many periods.
pub const LOG_EVERY: u32 = 100;
/// The LED toggles every this many heartbeats from the peer.
pub const BLINK_EVERY: u32 = 50;

/// The `static`s a firmware publishes (see the [module docs](self)).
#[derive(Clone, Copy)]
pub struct Published<'a> {
    /// The application's counters, copied after each period (`None` before the first).
    pub stats: &'a Mutex<RefCell<Option<AppStats>>>,
    /// Error-state changes the driver reported (`take_state_change`).
    pub state_changes: &'a AtomicU32,
    /// The worst fault-confinement state reported so far: 0 error active, 1 warning,
    /// 2 error passive, 3 bus-off (`ErrorState` in declaration order).
    pub worst_state: &'a AtomicU32,
    /// The driver's hardware receive FIFO overruns
    /// ([`ErrorStatistics::hardware_overruns`](twocan_core::ErrorStatistics)).
    pub overruns: &'a AtomicU32,
    /// The driver's hardware receive FIFO warnings
    /// ([`ErrorStatistics::hardware_fifo_warnings`](twocan_core::ErrorStatistics)).
    pub fifo_warnings: &'a AtomicU32,
}

/// What one period did, for the board's log and LED.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Period {
    /// Periods run so far (wrapping).
    pub steps: u32,
    /// The application's counters after this period.
    pub stats: AppStats,
    /// Whether this period is one of every [`LOG_EVERY`]: the board logs `stats`.
    pub log: bool,
    /// Whether [`BLINK_EVERY`] more heartbeats came in: the board toggles its LED.
    pub blink: bool,
}

/// The state of a firmware's main loop (periods run, heartbeats at the last blink).
#[derive(Debug, Default)]
pub struct FirmwareLoop {
    steps: u32,
    shown: u32,
}

impl FirmwareLoop {
    /// Nothing run yet.
    pub const fn new() -> Self {
        FirmwareLoop { steps: 0, shown: 0 }
    }

    /// One period: the application handles what `driver` received and publishes
    /// ([`App::handle`], [`App::publish`]), the completions are taken (the application
    /// does not follow them), each error-state change is counted in `published`, its
    /// worst state kept and handed to `on_change` (the board logs it), and the counters
    /// are copied into `published.stats`.
    pub fn step<D: CanTx + CanRx>(
        &mut self,
        app: &mut App,
        driver: &mut D,
        published: &Published<'_>,
        mut on_change: impl FnMut(&StateChange),
    ) -> Period {
        app.handle(driver);
        app.publish(driver);
        while driver.take_completion().is_some() {}
        while let Some(c) = driver.take_state_change() {
            record(published, &c);
            on_change(&c);
        }
        publish_errors(published, driver.error_stats());
        self.finish(app, published)
    }

    /// [`FirmwareLoop::step`] over the split driver's two halves.
    pub fn step_split<T: CanTx, R: CanRx>(
        &mut self,
        app: &mut App,
        tx: &mut T,
        rx: &mut R,
        published: &Published<'_>,
        mut on_change: impl FnMut(&StateChange),
    ) -> Period {
        app.handle(rx);
        app.publish(tx);
        while tx.take_completion().is_some() {}
        while let Some(c) = rx.take_state_change() {
            record(published, &c);
            on_change(&c);
        }
        publish_errors(published, rx.error_stats());
        self.finish(app, published)
    }

    fn finish(&mut self, app: &App, published: &Published<'_>) -> Period {
        let stats = app.stats();
        critical_section::with(|cs| *published.stats.borrow_ref_mut(cs) = Some(stats));
        self.steps = self.steps.wrapping_add(1);
        let blink = stats.heartbeats >= self.shown.wrapping_add(BLINK_EVERY);
        if blink {
            self.shown = stats.heartbeats;
        }
        Period {
            steps: self.steps,
            stats,
            log: self.steps.is_multiple_of(LOG_EVERY),
            blink,
        }
    }
}

/// Counts `c` and keeps the worst state.
fn record(published: &Published<'_>, c: &StateChange) {
    published.state_changes.fetch_add(1, Ordering::Relaxed);
    if c.state <= ErrorState::BusOff {
        published
            .worst_state
            .fetch_max(c.state as u32, Ordering::Relaxed);
    }
}

/// Copies the driver's receive FIFO event counts into `published`.
fn publish_errors(published: &Published<'_>, e: ErrorStatistics) {
    published
        .overruns
        .store(e.hardware_overruns, Ordering::Relaxed);
    published
        .fifo_warnings
        .store(e.hardware_fifo_warnings, Ordering::Relaxed);
}
