//! ACAN §8.2–8.5 and §10.1–10.4: the driver's transmit and receive buffers (sizes,
//! counts, peak counts), the exact overflow accounting of a flood larger than the
//! receive ring, and the Rx FIFO overflow of the hardware.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_core::BufferStats;
use twocan_flexcan::Settings;
use twocan_sim::SimNode;

#[test]
fn flood_larger_than_the_receive_ring() {
    const RX: usize = 8;
    let (model, mut can) = begin::<RX, 16>(&loop_back(500_000), &[], &[]).unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    let n = 20u16;
    for i in 0..n {
        can.try_send(&std_data(0x100 + i, &i.to_le_bytes()))
            .unwrap();
        // The interrupt moves each frame from the Rx FIFO into the ring at once, so
        // the hardware FIFO never overflows: every loss is the ring's.
        run1(&mut bus, &mut can, 300);
    }
    let t = can.traffic();
    assert_eq!(t.sent, n as u32);
    assert_eq!(t.received, n as u32);
    assert_eq!(t.rx_ring_overflows, (n as usize - RX) as u32);
    // ACAN §10.4: after an overflow the peak count is size + 1.
    assert_eq!(
        can.rx_stats(),
        BufferStats {
            size: RX,
            count: RX,
            peak: RX + 1,
            overflows: 12
        }
    );
    assert_eq!(can.error_stats().hardware_overruns, 0);
    assert_eq!(model.fifo_overflows(), 0);
    // The ring kept the oldest frames, in order.
    let ids: Vec<u32> = drain(&mut can).iter().map(|rx| rx.frame.raw_id()).collect();
    assert_eq!(ids, (0x100..0x108).collect::<Vec<u32>>());
    assert_eq!(can.rx_stats().count, 0);
}

#[test]
fn receive_peak_without_overflow() {
    let (model, mut can) = begin::<32, 16>(&loop_back(500_000), &[], &[]).unwrap();
    let mut bus = bus_with(500_000, &[&model]);
    for i in 0..5u16 {
        can.try_send(&std_data(i, &[])).unwrap();
    }
    run1(&mut bus, &mut can, 2_000);
    assert_eq!(
        can.rx_stats(),
        BufferStats {
            size: 32,
            count: 5,
            peak: 5,
            overflows: 0
        }
    );
    can.receive().unwrap();
    assert_eq!(can.rx_stats().count, 4);
    assert_eq!(can.rx_stats().peak, 5);
}

#[test]
fn transmit_buffer_size_count_and_peak_8_3_to_8_5() {
    const TX: usize = 4;
    let (_model, mut can) = begin::<32, TX>(&loop_back(500_000), &[], &[]).unwrap();
    // No bus runs: the first frame goes to MB15, the next TX wait in the ring.
    for i in 0..=TX as u16 {
        can.try_send(&std_data(i, &[])).unwrap();
    }
    assert_eq!(
        can.tx_stats(),
        BufferStats {
            size: TX,
            count: TX,
            peak: TX,
            overflows: 0
        }
    );
    // Full: tryToSend fails, and the peak becomes size + 1 (ACAN §8.5).
    assert!(matches!(
        can.try_send(&std_data(0x7FF, &[])),
        Err(nb::Error::WouldBlock)
    ));
    assert_eq!(
        can.tx_stats(),
        BufferStats {
            size: TX,
            count: TX,
            peak: TX + 1,
            overflows: 1
        }
    );
}

#[test]
fn hardware_fifo_overflow_is_reported() {
    // Another node sends 10 frames while the driver does not service its interrupt:
    // the six-frame Rx FIFO keeps the first six, and IFLAG1.BUF7I says frames were lost.
    let (model, mut can) = begin::<32, 16>(&Settings::new(500_000), &[], &[]).unwrap();
    let other = SimNode::new().shared();
    let mut bus = bus_with(500_000, &[&model]);
    bus.attach("other", other.clone());
    bus.run_for(20);
    for i in 0..10u16 {
        other.borrow_mut().send(std_data(0x200 + i, &[i as u8]));
    }
    bus.run_for(2_000);
    assert_eq!(model.fifo_len(), 6);
    assert_eq!(model.fifo_overflows(), 4);
    can.on_interrupt();
    let ids: Vec<u32> = drain(&mut can).iter().map(|rx| rx.frame.raw_id()).collect();
    assert_eq!(ids, (0x200..0x206).collect::<Vec<u32>>());
    // FlexCAN flags an overflow without counting the frames: one overrun event.
    assert_eq!(can.error_stats().hardware_overruns, 1);
    assert_eq!(can.traffic().received, 6);
}
