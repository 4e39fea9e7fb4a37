//! The raw filter match index of a received frame, for users who want the hardware's
//! number next to the portable user index ([`twocan_core::RxFrame::filter`]).
//!
//! bxCAN stores with every received frame the number of the filter that accepted it,
//! `CAN_RDTxR.FMI` (RM0410 §40.9.3; numbering per FIFO over the active banks assigned
//! to that FIFO, notes "Filter match index"), and the FIFO follows from the mailbox
//! it was read from. The backend carries both in [`twocan_core::RxFrame::hw_match`]:
//! FMI in bits 0..=7, the FIFO number in bit 8. [`fmi`] decodes it.

use twocan_core::RxFrame;

use crate::filters::Fifo;

/// Bit of [`RxFrame::hw_match`] holding the FIFO number (bxCAN backend).
pub const HW_MATCH_FIFO_BIT: u16 = 1 << 8;

/// The receive FIFO and raw filter match index (`CAN_RDTxR.FMI`) of a frame read by the
/// bxCAN backend, decoded from [`RxFrame::hw_match`].
///
/// `None` when `hw_match` has bits above the FIFO bit set: the frame did not come from a
/// bxCAN controller (another backend's match index, e.g. FlexCAN's `RXFIR.IDHIT`, is a
/// different number).
///
/// The number is the hardware's: filters of both FIFOs are numbered separately, a
/// 32-bit list bank takes two numbers, a 16-bit list bank four, whether or not the
/// planner filled every slot ([`crate::FilterPlan::fmi_of`] gives the number of a bank
/// slot of a plan; [`crate::FilterPlan::user_index`] maps it back).
///
/// ```
/// use std::{cell::RefCell, rc::Rc};
///
/// use twocan_bxcan::model::BxCanModel;
/// use twocan_bxcan::{fmi, BxCan, Can, Config, Fifo, FifoPolicy};
/// use twocan_sim::{Bus, PollClock};
/// use twocan_core::split::State;
/// use twocan_core::{FifoQueue, Filter, Frame};
///
/// let state: State<BxCan<PollClock<BxCanModel>>, 8, FifoQueue<4>, 8> = State::new();
/// let model = BxCanModel::can1();
/// let bus = Rc::new(RefCell::new(Bus::new(500_000).unwrap()));
/// bus.borrow_mut().attach("can1", model.clone());
/// let regs = PollClock::new(model.clone(), &bus, twocan_bxcan::regs::MSR);
/// let config = Config::from_bitrate(54_000_000, 500_000).unwrap().loopback(true);
/// let mut init = Can::can1(regs, &config).map_err(|f| f.error).unwrap();
/// // Two identifiers, both in FIFO 1: one 16-bit list bank, slots 0 and 1.
/// let filters = [Filter::standard(0x123), Filter::standard(0x456)];
/// let plan = init.can().plan(&filters, FifoPolicy::Fifo1).unwrap();
/// assert_eq!(plan.fmi_of(0, 1), Some((Fifo::Fifo1, 1)));
/// init.set_filters(&plan).unwrap();
/// let can = init.enable().map_err(|f| f.error).unwrap();
///
/// let mut parts = state.split(can.into_split()).ok().unwrap();
/// parts.tx.try_send(&Frame::standard(0x456, &[9]).unwrap()).unwrap();
/// bus.borrow_mut().run_for(200); // round the loop-back
/// parts.rx1_irq.on_interrupt();
/// let rx = parts.rx.receive().unwrap();
/// assert_eq!(rx.filter, 1); // the portable user index
/// assert_eq!(fmi(&rx), Some((Fifo::Fifo1, 1))); // the hardware's FIFO and FMI
/// ```
pub const fn fmi(rx: &RxFrame) -> Option<(Fifo, u8)> {
    decode(rx.hw_match)
}

/// [`fmi`] on the raw [`RxFrame::hw_match`] value.
pub const fn decode(hw_match: u16) -> Option<(Fifo, u8)> {
    if hw_match > (HW_MATCH_FIFO_BIT | 0xFF) {
        return None;
    }
    let fifo = if hw_match & HW_MATCH_FIFO_BIT != 0 {
        Fifo::Fifo1
    } else {
        Fifo::Fifo0
    };
    Some((fifo, hw_match as u8))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_fifo_and_index() {
        assert_eq!(decode(0), Some((Fifo::Fifo0, 0)));
        assert_eq!(decode(0x0A), Some((Fifo::Fifo0, 10)));
        assert_eq!(decode(0x100 | 0x37), Some((Fifo::Fifo1, 0x37)));
        assert_eq!(decode(0x1FF), Some((Fifo::Fifo1, 0xFF)));
        // Bits above the FIFO bit: not a bxCAN match index.
        assert_eq!(decode(0x200), None);
        assert_eq!(decode(0xFFFF), None);
    }
}
