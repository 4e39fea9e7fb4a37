//! Operating modes, handshakes, reset values and register access rules of the bxCAN
//! model (RM0410 40.4 "bxCAN operating modes", 40.9.2), through registers.

#[path = "model_bus.rs"]
mod bus;

use bus::*;
use twocan_bxcan::model::{BxCanModel, Mode};
use twocan_bxcan::regs::{self, btr, esr, ier, mcr, msr, tixr};
use twocan_core::Registers;
use twocan_sim::{BusNode, BusTime, TxResult};

fn mode_bits(m: &BxCanModel) -> u32 {
    m.read32(regs::MSR) & (msr::INAK | msr::SLAK)
}

#[test]
fn reset_values() {
    for m in [
        BxCanModel::can1(),
        BxCanModel::can3(),
        BxCanModel::can1_can2().1,
    ] {
        assert_eq!(m.read32(regs::MCR), 0x0001_0002);
        assert_eq!(m.read32(regs::MSR), 0x0000_0C02);
        assert_eq!(m.read32(regs::TSR), 0x1C00_0000);
        assert_eq!(m.read32(regs::RF0R), 0);
        assert_eq!(m.read32(regs::RF1R), 0);
        assert_eq!(m.read32(regs::IER), 0);
        assert_eq!(m.read32(regs::ESR), 0);
        assert_eq!(m.read32(regs::BTR), 0x0123_0000);
        assert_eq!(m.state().mode, Mode::Sleep);
    }
    for m in [BxCanModel::can1(), BxCanModel::can3()] {
        assert_eq!(m.read32(regs::FMR), 0x2A1C_0E01);
        for r in [regs::FM1R, regs::FS1R, regs::FFA1R, regs::FA1R] {
            assert_eq!(m.read32(r), 0);
        }
    }
}

#[test]
fn initialization_handshake_from_sleep() {
    let m = BxCanModel::can1();
    // INRQ while SLEEP is still set: not acknowledged (Sleep → Init needs !SLEEP).
    m.write32(regs::MCR, mcr::INRQ | mcr::SLEEP);
    assert_eq!(mode_bits(&m), msr::SLAK);
    m.write32(regs::MCR, mcr::INRQ);
    assert_eq!(mode_bits(&m), msr::INAK);
    assert_eq!(m.state().mode, Mode::Initialization);
}

#[test]
fn leaving_initialization_waits_for_11_recessive_bits() {
    let mut m = BxCanModel::can1();
    let mut bus = TinyBus::new(&[&m]);
    enter_init(&mut m);
    m.write32(regs::MCR, 0);
    assert_eq!(mode_bits(&m), msr::INAK, "INAK stays set until SYNC");
    assert!(m.state().syncing);
    bus.idle(10);
    assert_eq!(mode_bits(&m), msr::INAK);
    // Bus activity restarts the count of consecutive recessive bits.
    bus.inject(&std_frame(0x55, &[]));
    bus.idle(10);
    assert_eq!(mode_bits(&m), msr::INAK);
    bus.idle(1);
    assert_eq!(mode_bits(&m), 0);
    assert_eq!(m.state().mode, Mode::Normal);
    assert!(!m.state().syncing);
    // Back to initialization: acknowledged at once.
    m.write32(regs::MCR, mcr::INRQ);
    assert_eq!(mode_bits(&m), msr::INAK);
}

#[test]
fn sleep_handshake_and_slaki() {
    let (m, mut bus) = started(BxCanModel::can1());
    m.write32(regs::MCR, mcr::SLEEP);
    assert_eq!(mode_bits(&m), msr::SLAK);
    assert_eq!(
        m.read32(regs::MSR) & msr::SLAKI,
        0,
        "SLAKI only when SLKIE = 1"
    );
    // Leaving sleep: SLAK stays set until 11 recessive bits were seen.
    m.write32(regs::MCR, 0);
    assert_eq!(mode_bits(&m), msr::SLAK);
    bus.idle(11);
    assert_eq!(mode_bits(&m), 0);

    m.write32(regs::IER, ier::SLKIE);
    m.write32(regs::MCR, mcr::SLEEP);
    assert_ne!(m.read32(regs::MSR) & msr::SLAKI, 0);
    assert!(m.irq_lines().sce);
    // SLAKI is rc_w1 ...
    m.write32(regs::MSR, msr::SLAKI);
    assert_eq!(m.read32(regs::MSR) & msr::SLAKI, 0);
    assert!(!m.irq_lines().sce);
    // ... and cleared by hardware when SLAK clears.
    m.write32(regs::MCR, 0);
    bus.idle(11);
    m.write32(regs::MCR, mcr::SLEEP);
    assert_ne!(m.read32(regs::MSR) & msr::SLAKI, 0);
    m.write32(regs::MCR, 0);
    bus.idle(11);
    assert_eq!(m.read32(regs::MSR) & (msr::SLAK | msr::SLAKI), 0);
}

#[test]
fn sleep_to_initialization_and_back() {
    let mut m = BxCanModel::can1();
    enter_init(&mut m);
    m.write32(regs::MCR, mcr::SLEEP);
    assert_eq!(mode_bits(&m), msr::SLAK, "Init → Sleep on SLEEP · !INRQ");
    m.write32(regs::MCR, mcr::INRQ);
    assert_eq!(mode_bits(&m), msr::INAK, "Sleep → Init on INRQ · !SLEEP");
}

#[test]
fn automatic_wakeup_on_bus_activity() {
    let (mut m, mut bus) = started(BxCanModel::can1());
    m.write32(regs::IER, ier::WKUIE);
    m.write32(regs::MCR, mcr::SLEEP | mcr::AWUM);
    assert_eq!(mode_bits(&m), msr::SLAK);
    bus.inject(&std_frame(0x10, &[1]));
    assert_ne!(m.read32(regs::MSR) & msr::WKUI, 0, "SOF seen in sleep mode");
    assert!(m.irq_lines().sce);
    assert_eq!(
        m.read32(regs::MCR) & mcr::SLEEP,
        0,
        "AWUM: hardware clears SLEEP"
    );
    assert_eq!(mode_bits(&m), msr::SLAK, "still synchronising");
    bus.idle(11);
    assert_eq!(mode_bits(&m), 0);
    assert_eq!(
        receive(&mut m, 0),
        None,
        "the wake-up frame is not received"
    );
    m.write32(regs::MSR, msr::WKUI);
    assert!(!m.irq_lines().sce);
}

#[test]
fn wakeup_without_awum_needs_software() {
    let (m, mut bus) = started(BxCanModel::can1());
    m.write32(regs::MCR, mcr::SLEEP);
    bus.inject(&std_frame(0x10, &[1]));
    assert_ne!(m.read32(regs::MSR) & msr::WKUI, 0);
    assert_ne!(m.read32(regs::MCR) & mcr::SLEEP, 0);
    bus.idle(50);
    assert_eq!(mode_bits(&m), msr::SLAK);
    m.write32(regs::MCR, 0);
    bus.idle(11);
    assert_eq!(mode_bits(&m), 0);
}

#[test]
fn btr_is_writable_in_initialization_mode_only() {
    let mut m = BxCanModel::can1();
    let mut bus = TinyBus::new(&[&m]);
    m.write32(regs::BTR, 0x001C_0003);
    assert_eq!(m.read32(regs::BTR), 0x0123_0000, "sleep mode: ignored");
    enter_init(&mut m);
    m.write32(regs::BTR, u32::MAX);
    let writable = btr::BRP.mask()
        | btr::TS1.mask()
        | btr::TS2.mask()
        | btr::SJW.mask()
        | btr::LBKM
        | btr::SILM;
    assert_eq!(m.read32(regs::BTR), writable, "reserved bits ignored");
    m.write32(regs::BTR, 0x001C_0003);
    leave_init(&mut m, &mut bus);
    m.write32(regs::BTR, 0);
    assert_eq!(m.read32(regs::BTR), 0x001C_0003, "normal mode: ignored");
}

#[test]
fn reserved_bits_are_ignored() {
    let m = BxCanModel::can1();
    m.write32(regs::MCR, !mcr::RESET);
    assert_eq!(m.read32(regs::MCR), 0x0001_00FF);
    m.write32(regs::IER, u32::MAX);
    assert_eq!(m.read32(regs::IER), 0x0003_8F7F);
    m.write32(regs::ESR, u32::MAX);
    assert_eq!(m.read32(regs::ESR), esr::LEC.mask(), "only LEC is writable");
    m.write32(regs::MSR, u32::MAX);
    assert_eq!(
        m.read32(regs::MSR) & !(msr::INAK | msr::SLAK),
        msr::SAMP | msr::RX
    );
    assert_eq!(m.read32(regs::MCR + 2), 0, "unaligned offsets read 0");
    assert_eq!(m.read32(0x100), 0, "gap");
    assert_eq!(m.read32(0x1000), 0, "beyond the block");
}

#[test]
fn master_reset() {
    let (mut m, mut bus) = started(BxCanModel::can1());
    m.write32(regs::IER, ier::FMPIE0);
    m.write32(regs::MCR, mcr::TXFP | mcr::NART | mcr::TTCM);
    bus.inject(&std_frame(0x1, &[]));
    load(&mut m, 1, &std_frame(0x2, &[]));
    m.write32(regs::ESR, esr::LEC.val(7));
    assert_eq!(m.state().fifo_depth[0], 1);
    let filters = m.read32(regs::FA1R);

    m.write32(regs::MCR, mcr::RESET | mcr::INRQ);
    assert_eq!(
        m.read32(regs::MCR),
        mcr::RESET_VALUE,
        "RESET reads 0; other bits ignored"
    );
    assert_eq!(
        m.read32(regs::MSR),
        msr::RESET_VALUE,
        "sleep mode after reset"
    );
    assert_eq!(m.read32(regs::TSR), regs::tsr::RESET_VALUE);
    assert_eq!(m.read32(regs::RF0R), 0, "FMP cleared");
    assert_eq!(m.read32(regs::IER), 0);
    assert_eq!(m.read32(regs::ESR), 0);
    assert_eq!(m.read32(regs::BTR), btr::RESET_VALUE);
    assert_eq!(
        m.read32(regs::FA1R),
        filters,
        "the filter block is not reset"
    );
    assert_eq!(m.read32(regs::tixr(1)) & tixr::TXRQ, 0);
}

#[test]
fn stuck_acknowledge_never_changes_inak_or_slak() {
    let m = BxCanModel::can1();
    let mut bus = TinyBus::new(&[&m]);
    m.set_ack_stuck(true);
    m.write32(regs::MCR, mcr::INRQ);
    assert_eq!(mode_bits(&m), msr::SLAK);
    bus.idle(100);
    assert_eq!(mode_bits(&m), msr::SLAK);
    assert!(m.state().ack_stuck);
    m.set_ack_stuck(false);
    assert_eq!(
        mode_bits(&m),
        msr::INAK,
        "a pending request completes once the fault is gone"
    );

    m.set_ack_stuck(true);
    m.write32(regs::MCR, 0);
    bus.idle(100);
    assert_eq!(mode_bits(&m), msr::INAK, "no SYNC either");
    m.set_ack_stuck(false);
    bus.idle(11);
    assert_eq!(mode_bits(&m), 0);
}

#[test]
fn initialization_request_waits_for_the_end_of_a_transmission() {
    let (mut m, bus) = started(BxCanModel::can1());
    let f = std_frame(0x100, &[1]);
    load(&mut m, 0, &f);
    let now = bus.now;
    // The bus starts the frame ...
    let req = m.poll_tx(now).expect("a frame to send");
    // ... the software requests initialization mode meanwhile ...
    m.write32(regs::MCR, mcr::INRQ);
    assert_eq!(mode_bits(&m), 0, "not while transmitting");
    // ... and the frame ends (acknowledged by a node not modelled).
    m.tx_result(
        &req.frame,
        TxResult::Acked,
        BusTime {
            sof: now,
            now: now + 52,
        },
    );
    assert_eq!(mode_bits(&m), msr::INAK);
    assert_ne!(m.read32(regs::TSR) & regs::tsr::TXOK0, 0);
}

#[test]
fn no_write_panics_and_reads_are_stable() {
    let values = [0, u32::MAX, 0xAAAA_AAAA, 0x5555_5555, 0x8000_0001];
    let (can1, can2) = BxCanModel::can1_can2();
    for m in [BxCanModel::can1(), BxCanModel::can3(), can1, can2] {
        let mut bus = TinyBus::new(&[&m]);
        for round in 0..3 {
            for offset in 0..0x400 {
                for v in values {
                    m.write32(offset, v.rotate_left(round));
                    let _ = m.read32(offset);
                }
                if offset % 64 == 0 {
                    bus.idle(13);
                    bus.step();
                    bus.inject(&std_frame(0x7FF, &[0xFF; 8]));
                }
            }
        }
        let _ = m.irq_lines();
        let _ = m.state();
    }
}

#[test]
fn extreme_bus_inputs_do_not_panic() {
    use twocan_core::LastErrorCode;
    let (mut m, mut bus) = started(BxCanModel::can1());
    m.modify32(regs::MCR, |v| v | mcr::TTCM | mcr::ABOM);
    load(&mut m, 0, &std_frame(0x1, &[]));
    let f = std_frame(0x2, &[1]);
    for _ in 0..40 {
        bus.inject_error = Some(LastErrorCode::BitRecessive);
        bus.step();
    }
    m.advance(u64::MAX, true, u64::MAX);
    m.advance(u64::MAX, false, 5);
    m.rx(
        &f,
        false,
        BusTime {
            sof: u64::MAX,
            now: 0,
        },
    );
    m.rx(
        &f,
        true,
        BusTime {
            sof: 0,
            now: u64::MAX,
        },
    );
    m.rx_error(LastErrorCode::Crc, true, BusTime { sof: 7, now: 3 });
    m.tx_result(
        &f,
        TxResult::Acked,
        BusTime {
            sof: u64::MAX,
            now: u64::MAX,
        },
    );
    let _ = m.poll_tx(u64::MAX);
    let _ = m.next_wakeup(u64::MAX);
    let _ = m.state();
}

#[test]
fn tiny_bus_two_models_exchange_a_frame() {
    let (mut a, mut b, mut bus) = started_pair(BxCanModel::can3(), BxCanModel::can1());
    let f = std_frame(0x123, &[1, 2, 3]);
    load(&mut a, 0, &f);
    let slot = bus.step();
    assert_eq!(slot.frame, Some(f));
    assert!(slot.acked);
    assert_eq!(receive(&mut b, 0).map(|r| r.frame), Some(f));
    assert_eq!(
        receive(&mut a, 0),
        None,
        "no self-reception outside loop back"
    );
    assert_eq!(bus.step().frame, None);
}

#[test]
fn tiny_bus_frame_lengths() {
    assert_eq!(frame_bits(&std_frame(1, &[])), 44);
    assert_eq!(frame_bits(&std_frame(1, &[0; 8])), 108);
    assert_eq!(frame_bits(&ext_frame(1, &[])), 64);
}
