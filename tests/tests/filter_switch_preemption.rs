//! A filter switch with the receive interrupt preempting it at every register access, on
//! both controllers (issue 26: FlexCAN's Rx FIFO discard count of a switch could be one
//! too high; bxCAN's switch window dropped a frame of the new list).
//!
//! Five frames of the old list arrive before the switch: two already taken by the
//! receive handler into the ring, three still in the hardware FIFO (FlexCAN's Rx FIFO
//! holds six, a bxCAN FIFO three). Whatever runs between two
//! of `set_filters`' accesses, each of them must be counted exactly once in
//! `rx_dropped` (discarded from the FIFO by the switch, or dropped from the ring as an
//! old-list frame), none delivered, and a frame of the new list sent afterwards must be
//! delivered.

use twocan_bxcan::PlanOptions;
use twocan_core::txqueue::{FifoQueue, TxQueue};
use twocan_core::{Filter, Frame, Hardware, TxPolicy};
use twocan_flexcan::{FilterTable, Settings};
use twocan_tests::preempt::{bxcan_rig, flexcan_rig, Progress, Rig, BIT_RATE, PROGRESS};

const OLD: [u16; 5] = [0x100, 0x101, 0x102, 0x103, 0x104];
const NEW: u16 = 0x200;

fn std_frame(id: u16) -> Frame {
    Frame::standard(id, &[id as u8]).expect("frame")
}

/// Runs the scenario, preempting at `at`; returns (accesses of the switch, rx_dropped,
/// delivered identifiers).
fn run<H: Hardware + 'static, Q: TxQueue + 'static>(
    mut rig: Rig<H, Q>,
    table: &H::Filters,
    at: Option<(usize, Progress)>,
) -> (usize, u32, Vec<u32>) {
    let p = rig.preemption.clone();
    let bus = rig.bus.clone();
    let settle = |bus: &twocan_sim::SharedBus| {
        for _ in 0..1_000 {
            if bus.borrow_mut().step().is_none() {
                return;
            }
        }
        panic!("the bus did not go idle");
    };
    // Two frames taken by the receive handler, three left in the Rx FIFO.
    for &id in &OLD[..2] {
        rig.peer.borrow_mut().send(std_frame(id));
    }
    settle(&bus);
    assert!(p.run_handlers(), "the receive line is raised");
    for &id in &OLD[2..] {
        rig.peer.borrow_mut().send(std_frame(id));
    }
    settle(&bus);
    p.start(at);
    rig.rx.set_filters(table).expect("switch");
    let accesses = p.stop();
    p.run_handlers();
    rig.peer.borrow_mut().send(std_frame(NEW));
    for _ in 0..1_000 {
        p.run_handlers();
        if bus.borrow_mut().step().is_none() {
            p.run_handlers();
            break;
        }
    }
    let mut delivered = Vec::new();
    let mut tries = 0;
    while let Ok(f) = rig.rx.receive() {
        delivered.push(f.frame.raw_id());
        tries += 1;
        assert!(tries < 100, "the ring never empties");
    }
    (accesses, rig.state.traffic().rx_dropped, delivered)
}

fn flexcan_table() -> FilterTable {
    FilterTable::compile(
        Settings::new(BIT_RATE).configuration,
        &[Filter::standard(NEW)],
        &[],
    )
    .expect("table")
}

#[test]
fn flexcan_every_old_frame_is_counted_once_wherever_the_receive_interrupt_preempts_a_switch() {
    sweep("FlexCAN", flexcan_rig::<FifoQueue<4>>, &flexcan_table());
}

#[test]
fn bxcan_every_old_frame_is_counted_once_wherever_the_receive_interrupt_preempts_a_switch() {
    let plan = twocan_bxcan::plan(&[Filter::standard(NEW)], PlanOptions::new(14)).expect("plan");
    sweep("bxCAN", || bxcan_rig::<FifoQueue<4>>(TxPolicy::Fifo), &plan);
}

fn sweep<H: Hardware + 'static, Q: TxQueue + 'static>(
    what: &str,
    rig: impl Fn() -> Rig<H, Q>,
    table: &H::Filters,
) {
    let (n, dropped, delivered) = run(rig(), table, None);
    assert_eq!(dropped, OLD.len() as u32, "no preemption: rx_dropped");
    assert_eq!(delivered, vec![u32::from(NEW)], "no preemption: delivered");
    assert!(n > 0);
    let mut points = 0;
    for k in 0..n {
        for progress in PROGRESS {
            let (_, dropped, delivered) = run(rig(), table, Some((k, progress)));
            assert_eq!(
                dropped,
                OLD.len() as u32,
                "{what}, {progress:?} at access {k} of {n}: rx_dropped"
            );
            assert_eq!(
                delivered,
                vec![u32::from(NEW)],
                "{what}, {progress:?} at access {k} of {n}: delivered"
            );
            points += 1;
        }
    }
    println!("{what} filter switch: {n} accesses, {points} preemption points");
}
