//! The portable application over two mock controllers wired back to back.

use twocan_app::App;
use twocan_core::mock::MockHardware;
use twocan_core::Driver;

type Node = Driver<MockHardware, 16, 16>;

fn node(app: &App) -> Node {
    Driver::new(MockHardware::new(1).with_filters(&app.filters()))
}

#[test]
fn two_apps_exchange_every_frame_kind() {
    let mut a = App::new(1, 2);
    let mut b = App::new(2, 1);
    let (mut da, mut db) = (node(&a), node(&b));
    for _ in 0..100 {
        a.step(&mut da);
        b.step(&mut db);
        // Play a bus: every pending frame of each node reaches the other.
        for _ in 0..8 {
            if let Some(f) = da.hardware().complete() {
                db.hardware().deliver(f);
            }
            if let Some(f) = db.hardware().complete() {
                da.hardware().deliver(f);
            }
            da.on_interrupt();
            db.on_interrupt();
        }
    }
    for app in [&a, &b] {
        let s = app.stats();
        assert!(s.heartbeats >= 95, "{s:?}");
        assert_eq!(s.heartbeat_gaps, 0, "{s:?}");
        assert!(s.measurements >= 20, "{s:?}");
        assert!(s.requests >= 9, "{s:?}");
        assert!(s.answers >= 9, "{s:?}");
        assert_eq!(s.unhandled, 0);
    }
}
