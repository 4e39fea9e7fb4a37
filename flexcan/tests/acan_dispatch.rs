//! ACAN §14: `dispatchReceivedMessage` — call-backs chosen by the filter index of each
//! received frame (twocan-core's `Dispatcher`), with and without call-backs, and the
//! match hook.
#![cfg(feature = "model")]

mod common;

use common::*;
use twocan_core::dispatch::Dispatcher;
use twocan_core::{Filter, Format, FrameKind, RxFrame};

#[derive(Default, Debug)]
struct App {
    message_0: Vec<u32>,
    message_2: Vec<u32>,
    matches: Vec<u16>,
}

fn handle_my_message_0(app: &mut App, rx: &RxFrame) {
    app.message_0.push(rx.frame.raw_id());
}

fn handle_my_message_2(app: &mut App, rx: &RxFrame) {
    app.message_2.push(rx.frame.raw_id());
}

fn filter_match(app: &mut App, index: u16) {
    app.matches.push(index);
}

/// The §14 lists: primary #0 with a call-back, secondary #1 without, #2 with.
fn setup() -> (twocan_flexcan::model::FlexCanModel, Can<32, 16>) {
    let primary = [Filter::exact(FrameKind::Data, Format::Extended, 0x123456)];
    let secondary = [
        Filter::exact(FrameKind::Data, Format::Standard, 0x234), // Filter #1, no call-back
        Filter::exact(FrameKind::Remote, Format::Standard, 0x542),
    ];
    begin::<32, 16>(&loop_back(125_000), &primary, &secondary).unwrap()
}

fn send_all(model: &twocan_flexcan::model::FlexCanModel, can: &mut Can<32, 16>) {
    let mut bus = bus_with(125_000, &[model]);
    for f in [
        ext_data(0x123456, &[1]),
        std_data(0x234, &[2]),
        remote(0x542, false),
        std_data(0x7FF, &[]),
    ] {
        can.try_send(&f).unwrap();
        run1(&mut bus, can, 1_000);
    }
}

#[test]
fn dispatch_with_call_backs_and_a_lost_filter() {
    let (model, mut can) = setup();
    send_all(&model, &mut can);
    assert_eq!(can.rx_stats().count, 3);

    let mut d: Dispatcher<App, 32> = Dispatcher::new();
    d.set(0, handle_my_message_0).unwrap();
    d.set(2, handle_my_message_2).unwrap();
    let mut app = App::default();
    // `while (ACAN::can0.dispatchReceivedMessage ()) {}`
    let mut dispatched = 0;
    while can.dispatch(&mut d, &mut app) {
        dispatched += 1;
    }
    assert_eq!(dispatched, 3);
    assert_eq!(app.message_0, vec![0x123456]);
    assert_eq!(app.message_2, vec![0x542]);
    // Filter #1 names no call-back: its frame is lost (and counted).
    assert_eq!((d.handled(), d.unhandled()), (2, 1));
    assert!(
        !can.dispatch(&mut d, &mut app),
        "empty receive buffer: false"
    );
}

#[test]
fn dispatch_with_match_hook() {
    let (model, mut can) = setup();
    send_all(&model, &mut can);
    let mut d: Dispatcher<App, 32> = Dispatcher::new().with(0, handle_my_message_0).unwrap();
    d.set_match_hook(Some(filter_match));
    let mut app = App::default();
    while can.dispatch(&mut d, &mut app) {}
    assert_eq!(app.matches, vec![0, 1, 2]);
    assert_eq!(app.message_0, vec![0x123456]);
    assert_eq!((d.handled(), d.unhandled()), (1, 2));
}

#[test]
fn dispatch_without_any_call_back() {
    let (model, mut can) = setup();
    send_all(&model, &mut can);
    let mut d: Dispatcher<App, 32> = Dispatcher::new();
    let mut app = App::default();
    let mut n = 0;
    while can.dispatch(&mut d, &mut app) {
        n += 1;
    }
    assert_eq!(n, 3);
    assert_eq!((d.handled(), d.unhandled()), (0, 3));
    assert!(app.message_0.is_empty() && app.message_2.is_empty());
}

#[test]
fn receive_and_dispatch_share_the_ring() {
    let (model, mut can) = setup();
    send_all(&model, &mut can);
    let first = can.receive().unwrap();
    assert_eq!(first.filter, 0);
    let mut d: Dispatcher<App, 32> = Dispatcher::new().with(2, handle_my_message_2).unwrap();
    let mut app = App::default();
    while can.dispatch(&mut d, &mut app) {}
    assert_eq!(app.message_2, vec![0x542]);
    assert_eq!((d.handled(), d.unhandled()), (1, 1));
}
