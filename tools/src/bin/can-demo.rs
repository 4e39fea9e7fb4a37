//! `can-demo`: the host demonstration (for now over two mock controllers; the simulated
//! FlexCAN + bxCAN bus replaces the mocks when the backends land).

use twocan_app::App;
use twocan_core::mock::{MockController, MockFilters};
use twocan_core::{Driver, TxPolicy};

type Node = Driver<MockController<1, 6>, 32, 32>;

fn node(app: &App) -> Node {
    let mut c = MockController::new(TxPolicy::Fifo);
    let filters: MockFilters = app.filters().into_iter().collect();
    c.install_filters_for_test(&filters);
    Driver::new(c)
}

fn main() {
    let mut a = App::new(1, 2);
    let mut b = App::new(2, 1);
    let (mut da, mut db) = (node(&a), node(&b));
    for _ in 0..1000 {
        a.step(&mut da);
        b.step(&mut db);
        for _ in 0..8 {
            if let Some(f) = da.controller_mut().complete() {
                db.controller_mut().deliver(f);
            }
            if let Some(f) = db.controller_mut().complete() {
                da.controller_mut().deliver(f);
            }
            da.on_interrupt();
            db.on_interrupt();
        }
    }
    for (name, app, d) in [("node 1", &a, &da), ("node 2", &b, &db)] {
        let s = app.stats();
        println!(
            "{name}: sent {} heartbeats {} (gaps {}) measurements {} requests {} answers {} rx peak {}",
            s.sent,
            s.heartbeats,
            s.heartbeat_gaps,
            s.measurements,
            s.requests,
            s.answers,
            d.rx_stats().peak
        );
    }
}
