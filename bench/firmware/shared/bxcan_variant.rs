//! Our bxCAN driver as the **lean** and the **full** bench firmware configure it, selected
//! by the firmware crate's cargo feature (`lean` or `full`, exactly one). Included with
//! `#[path]` by `insn-count` (QEMU, RAM stand-in) and `loopback-twocan` (STM32F7), so the
//! instruction counts and the flash figures are of the same configuration.
//!
//! - **full**: every per-frame feature on — transmit completions (a completion ring of
//!   [`DONE`] = 8), receive time stamps (`CAN_MCR.TTCM`), traffic statistics, and the
//!   filters compiled by the runtime planner (`Init::can().plan`) from a filter list;
//! - **lean**: the closest the current driver API comes to the lean driver of issue 21
//!   (const filter plan, fire-and-forget transmit, no time stamps, no statistics): no
//!   completion ring ([`DONE`] = 0), time stamps off, the one bank set by hand
//!   (`FilterPlan::manual`, the planner not linked) and a filter map with no lookup
//!   keys (`with_lookup_capacity::<0>`). The driver has no switch for its statistics
//!   yet: they stay. **Pending**: when the lean driver lands, the lean block below is
//!   the one place to switch to its types.

// Each firmware that includes this module uses a part of it.
#![allow(dead_code)]

#[cfg(all(feature = "lean", feature = "full"))]
compile_error!("features `lean` and `full` are exclusive");
#[cfg(not(any(feature = "lean", feature = "full")))]
compile_error!("enable feature `lean` or `full`");

use twocan_bxcan::{BxCan, Config, Init};
use twocan_core::split::{Parts, Rx, Rx0Irq, State, Tx, TxIrq};
use twocan_core::{Error, FifoQueue, Filter, Mmio, TxPolicy};

pub const APB1_HZ: u32 = 54_000_000;
pub const BITRATE: u32 = 500_000;

/// Receive ring (frames) of FIFO 0.
pub const RX: usize = 8;
/// Transmit queue capacity.
pub const TXQ: usize = 8;

/// The filter list of the full variant (the runtime planner compiles it): everything to
/// FIFO 0, the user's filter 0.
pub const FILTERS: [Filter; 1] = [Filter::pass_all()];

/// Loop-back, request-order transmit (TXFP = 1, the order of `FifoQueue`), time stamps
/// as the variant says.
pub const CONFIG: Config = match Config::from_bitrate(APB1_HZ, BITRATE) {
    Ok(c) => c
        .loopback(true)
        .tx_policy(TxPolicy::Fifo)
        .timestamps(TIMESTAMPS),
    Err(_) => panic!("no bit timing for 500 kbit/s from 54 MHz"),
};

// ------------------------------------------------------------------ lean

/// The variant's name in the bench output.
#[cfg(feature = "lean")]
pub const VARIANT: &str = "lean";
/// Completion ring capacity (0: completions off).
#[cfg(feature = "lean")]
pub const DONE: usize = 0;
/// Receive time stamps (`CAN_MCR.TTCM`).
#[cfg(feature = "lean")]
pub const TIMESTAMPS: bool = false;
/// Identifiers of the filter map's merged-filter lookup.
#[cfg(feature = "lean")]
pub const KEYS: usize = 0;

/// Installs the filters: one accept-all mask bank to FIFO 0, set by hand.
#[cfg(feature = "lean")]
#[inline(always)]
fn install_filters(init: &mut Init<Mmio, Mmio, KEYS>) -> Result<(), Error> {
    use twocan_bxcan::{Bank, Fifo, FilterPlan};
    let mut plan = FilterPlan::manual();
    let bank = Bank::mask32(&FILTERS[0], Fifo::Fifo0).map_err(|_| Error::InvalidArgument)?;
    plan.set_bank(0, bank)?;
    init.set_filters(&plan)
}

/// The user's filter index the one frame comes back with: the bank slot's own index
/// (`FilterPlan::slot_index`) for a plan set by hand.
#[cfg(feature = "lean")]
pub const FILTER_INDEX: u16 = twocan_bxcan::FilterPlan::slot_index(0, 0);

#[cfg(feature = "lean")]
#[inline(always)]
fn with_keys(init: Init<Mmio>) -> Init<Mmio, Mmio, KEYS> {
    init.with_lookup_capacity::<KEYS>()
}

// ------------------------------------------------------------------ full

#[cfg(feature = "full")]
pub const VARIANT: &str = "full";
#[cfg(feature = "full")]
pub const DONE: usize = 8;
#[cfg(feature = "full")]
pub const TIMESTAMPS: bool = true;
#[cfg(feature = "full")]
pub const KEYS: usize = twocan_bxcan::filters::LOOKUP_KEYS;

/// Installs the filters: [`FILTERS`] compiled by the runtime planner for this
/// instance's banks.
#[cfg(feature = "full")]
#[inline(always)]
fn install_filters(init: &mut Init<Mmio, Mmio, KEYS>) -> Result<(), Error> {
    let plan = init.can().plan(&FILTERS, twocan_bxcan::FifoPolicy::Fifo0)?;
    init.set_filters(&plan)
}

/// The user's filter index the one frame comes back with: its index in [`FILTERS`].
#[cfg(feature = "full")]
pub const FILTER_INDEX: u16 = 0;

#[cfg(feature = "full")]
#[inline(always)]
fn with_keys(init: Init<Mmio>) -> Init<Mmio, Mmio, KEYS> {
    init
}

// ------------------------------------------------------------------ both

/// The controller the split driver holds.
pub type Hw = BxCan<Mmio, Mmio, KEYS>;
/// The transmit queue.
pub type Q = FifoQueue<TXQ>;
/// The shared state a `static` holds.
pub type OurState = State<Hw, RX, Q, 0, DONE>;
/// The handles of `State::split`.
pub type OurParts = Parts<'static, Hw, RX, Q, 0, DONE>;
pub type OurTx = Tx<'static, Hw, RX, Q, 0, DONE>;
pub type OurRx = Rx<'static, Hw, RX, Q, 0, DONE>;
pub type OurTxIrq = TxIrq<'static, Hw, RX, Q, 0, DONE>;
pub type OurRxIrq = Rx0Irq<'static, Hw, RX, Q, 0, DONE>;

/// Configures CAN1 at `regs` ([`CONFIG`], the variant's filters) and starts it, ready
/// for `State::split`. `RETRIES` more attempts after a mode request that timed out (the
/// QEMU stand-in acknowledges from an interrupt whose rate follows host time; 0 on
/// hardware).
#[inline(always)]
pub fn configure<const RETRIES: u32>(regs: Mmio) -> Result<Hw, Error> {
    let mut attempt = twocan_bxcan::Can::can1(regs, &CONFIG);
    for _ in 0..RETRIES {
        match attempt {
            Err(f) if f.error == Error::Timeout => attempt = f.value.reconfigure(&CONFIG),
            _ => break,
        }
    }
    let mut init = with_keys(attempt.map_err(|f| f.error)?);
    install_filters(&mut init)?;
    let mut attempt = init.enable();
    for _ in 0..RETRIES {
        match attempt {
            Err(f) if f.error == Error::Timeout => attempt = f.value.enable(),
            _ => break,
        }
    }
    Ok(attempt.map_err(|f| f.error)?.into_split())
}
