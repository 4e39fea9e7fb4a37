//! Shared helpers of the harness tests: where the firmware ELFs are, and running boards.
#![allow(dead_code)]

use std::path::PathBuf;

use twocan_fil::elf::Image;
use twocan_fil::profile;
use twocan_fil::world::World;

pub mod three;

/// Where `fil/build-firmware.sh` puts the ELFs (`FIL_ELF_DIR` overrides).
pub fn elf_dir() -> PathBuf {
    std::env::var_os("FIL_ELF_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/elf"))
}

/// The ELF `name` of `board` (`negative` for the bare-metal ones). Without it the test
/// fails when `FIL_REQUIRE_ELF` is set (CI) and is skipped with a note otherwise.
pub fn elf(board: &str, name: &str) -> Option<Image> {
    let path = elf_dir().join(board).join(name);
    if !path.exists() {
        if std::env::var_os("FIL_REQUIRE_ELF").is_some() {
            panic!("{} missing: run fil/build-firmware.sh", path.display());
        }
        eprintln!(
            "skipped: {} missing (run fil/build-firmware.sh)",
            path.display()
        );
        return None;
    }
    Some(Image::load(path.to_str().expect("utf-8 path")).expect("ELF"))
}

/// A world with the given boards (board name, ELF name); `None` when an ELF is missing.
pub fn world(bit_rate: u32, boards: &[(&str, &str)]) -> Option<World<'static>> {
    let mut w = World::new(bit_rate).expect("bus");
    for (board, name) in boards {
        let image = elf(board, name)?;
        w.add_board(profile::by_name(board).expect("board"), image)
            .expect("board starts");
    }
    Some(w)
}

/// Seconds to picoseconds.
pub fn secs(s: f64) -> u128 {
    (s * 1e12) as u128
}

/// A board ran cleanly: no fault, no stuck interrupt, no halt, no register the profile
/// does not know, no rule violation.
pub fn assert_clean(w: &World<'_>) {
    for m in &w.machines {
        let b = m.board();
        assert!(b.faults.is_empty(), "{}: faults {:?}", b.name, b.faults);
        assert!(b.stuck.is_empty(), "{}: stuck {:?}", b.name, b.stuck);
        assert!(
            b.livelock.is_none(),
            "{}: {}",
            b.name,
            b.livelock.as_ref().unwrap()
        );
        assert!(b.halted.is_none(), "{}: halted {:?}", b.name, b.halted);
        assert!(
            b.unknown.is_empty(),
            "{}: unknown registers {:?}",
            b.name,
            twocan_fil::machine::unknown_report(b)
        );
        assert!(b.findings.is_empty(), "{}: {:?}", b.name, b.findings);
    }
    assert!(w.clean());
}

/// The application counters of `twocan_app::AppStats` (nine `u32`, in declaration
/// order), read from a `critical_section::Mutex<RefCell<Option<…>>>` static: a
/// `RefCell` borrow flag, the `Option` tag, then the fields. `count` = 1 for
/// `Option<AppStats>`, 2 for `Option<[AppStats; 2]>`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Stats {
    pub sent: u32,
    pub tx_full: u32,
    pub heartbeats: u32,
    pub heartbeat_gaps: u32,
    pub heartbeat_duplicates: u32,
    pub measurements: u32,
    pub requests: u32,
    pub answers: u32,
    pub unhandled: u32,
}

pub fn app_stats(w: &World<'_>, board: usize, count: usize) -> Vec<Stats> {
    let bytes = w.machines[board]
        .read_static("STATS")
        .expect("STATS symbol");
    assert_eq!(bytes.len(), 8 + 36 * count, "STATS layout changed");
    let word = |i: usize| u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
    assert_eq!(word(0), 0, "RefCell not borrowed");
    assert_eq!(word(1), 1, "Option is Some: the application has stepped");
    (0..count)
        .map(|n| {
            let f = |k: usize| word(2 + 9 * n + k);
            Stats {
                sent: f(0),
                tx_full: f(1),
                heartbeats: f(2),
                heartbeat_gaps: f(3),
                heartbeat_duplicates: f(4),
                measurements: f(5),
                requests: f(6),
                answers: f(7),
                unhandled: f(8),
            }
        })
        .collect()
}

/// Wire frames sent without error (acknowledged, no error flag) that match `pred`.
pub fn wire_count(w: &World<'_>, pred: impl Fn(&twocan_core::Frame) -> bool) -> u32 {
    w.bus
        .trace()
        .records()
        .iter()
        .filter(|r| !r.internal && r.is_error_free() && pred(&r.frame))
        .count() as u32
}

/// Raw identifier and whether it is extended, through `embedded_can`.
pub fn raw_id(f: &twocan_core::Frame) -> (u32, bool) {
    match embedded_can::Frame::id(f) {
        embedded_can::Id::Standard(s) => (u32::from(s.as_raw()), false),
        embedded_can::Id::Extended(e) => (e.as_raw(), true),
    }
}

/// Whether `f` is a remote frame.
pub fn is_remote(f: &twocan_core::Frame) -> bool {
    embedded_can::Frame::is_remote_frame(f)
}
