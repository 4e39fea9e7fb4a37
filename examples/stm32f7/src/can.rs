//! The split driver of a bxCAN instance as the examples use it: its shared state in a
//! `static` ([`CanState`]), its interrupt handles in the instance's [`Vectors`], which
//! the example's four vectors run (TX, RX0, RX1, SCE: one handler per line, RM0410
//! §40.8), and `start`, which puts the handles in place **before** it unmasks the lines.

use twocan_bxcan::regs::CanRegs;
use twocan_bxcan::types::{BxRx, BxRx0Irq, BxRx1Irq, BxState, BxStatusIrq, BxTx, BxTxIrq};
use twocan_core::irq_cell::IrqCell;
use twocan_core::Registers;

/// Receive ring per FIFO, transmit queue and completion ring sizes of the examples.
pub const RX: usize = twocan_bxcan::types::RX_RING;
/// See [`RX`].
pub const TX: usize = twocan_bxcan::types::TX_QUEUE;
/// See [`RX`].
pub const COMPLETIONS: usize = twocan_bxcan::types::COMPLETIONS;

/// A transmit queue in request order (`TXFP = 1`, the driver's default).
pub type Queue = twocan_bxcan::types::Queue;
/// The shared state of an instance with registers `R` and filter registers `F` (a
/// whole block by default; `ControlRegs` and `twocan_bxcan::hal::Can1Filters` for CAN1
/// and CAN2 sharing CAN1's filters).
pub type CanState<R = CanRegs, F = CanRegs> = BxState<R, F>;
/// The transmit half.
pub type CanTxHalf<R = CanRegs, F = CanRegs> = BxTx<'static, R, F>;
/// The receive half.
pub type CanRxHalf<R = CanRegs, F = CanRegs> = BxRx<'static, R, F>;

/// The interrupt handles of one bxCAN instance.
pub struct Vectors<R: Registers + 'static = CanRegs, F: Registers + 'static = CanRegs> {
    tx: IrqCell<BxTxIrq<'static, R, F>>,
    rx0: IrqCell<BxRx0Irq<'static, R, F>>,
    rx1: IrqCell<BxRx1Irq<'static, R, F>>,
    sce: IrqCell<BxStatusIrq<'static, R, F>>,
}

impl<R: Registers + 'static, F: Registers + 'static> Default for Vectors<R, F> {
    fn default() -> Self {
        Self::new()
    }
}

impl<R: Registers + 'static, F: Registers + 'static> Vectors<R, F> {
    /// Empty: the vectors do nothing until `start` fills them.
    pub const fn new() -> Self {
        Vectors {
            tx: IrqCell::new(),
            rx0: IrqCell::new(),
            rx1: IrqCell::new(),
            sce: IrqCell::new(),
        }
    }

    /// The TX line: settle ended mailboxes, refill them.
    pub fn on_tx(&self) -> bool {
        self.tx.run(|h| h.on_interrupt())
    }

    /// The RX0 line: FIFO 0 into its ring.
    pub fn on_rx0(&self) -> bool {
        self.rx0.run(|h| h.on_interrupt())
    }

    /// The RX1 line: FIFO 1 into its ring.
    pub fn on_rx1(&self) -> bool {
        self.rx1.run(|h| h.on_interrupt())
    }

    /// The SCE line: errors, state changes, wake-up.
    pub fn on_sce(&self) -> bool {
        self.sce.run(|h| h.on_interrupt())
    }
}

/// Splits `state` over `hw`, puts the interrupt handles in `vectors`, then unmasks
/// `irqs` (TX, RX0, RX1, SCE): each line only once the handle its vector runs is in
/// place (`IrqCell::put` gives the token that unmasks it). Returns the thread-side
/// halves; `None` when `state` was split already.
#[cfg(target_os = "none")]
pub fn start<R: Registers + Send + Sync + 'static, F: Registers + Send + Sync + 'static>(
    state: &'static CanState<R, F>,
    vectors: &'static Vectors<R, F>,
    hw: twocan_bxcan::BxCan<R, F>,
    irqs: [stm32f7xx_hal::pac::Interrupt; 4],
    nvic: &mut cortex_m::peripheral::NVIC,
) -> Option<(CanTxHalf<R, F>, CanRxHalf<R, F>)> {
    let parts = state.split(hw).ok()?;
    let [tx, rx0, rx1, sce] = irqs;
    let lines = &mut crate::rt::Lines(nvic);
    let priority = crate::rt::CAN_PRIORITY;
    vectors
        .tx
        .put(parts.tx_irq)
        .ok()?
        .enable(lines, &[tx], priority);
    vectors
        .rx0
        .put(parts.rx0_irq)
        .ok()?
        .enable(lines, &[rx0], priority);
    vectors
        .rx1
        .put(parts.rx1_irq)
        .ok()?
        .enable(lines, &[rx1], priority);
    vectors
        .sce
        .put(parts.status_irq)
        .ok()?
        .enable(lines, &[sce], priority);
    Some((parts.tx, parts.rx))
}
