//! A `const` plan and the run-time planner give the same register contents (issue 21):
//! for a sample of the DBC corpus (`bench/data/dbc_ids.txt`, read by a `const fn` from
//! the same file the planner-quality report reads) and for random lists (made by a
//! `const fn` generator, so the lists are the same at compile time and at run time),
//! both backends' `const_plan!` results are compared field by field with `plan_in` on
//! the same list and options: bxCAN bank kinds, FIFOs, activation and `FiR1`/`FiR2`,
//! every slot's user index and the lookup keys; FlexCAN configuration, ID table
//! elements, individual and global masks, what each `IDHIT` means and the lookup keys.
//!
//! The DBC sample is every fifth set of up to 110 identifiers (constant evaluation of the
//! larger sets' superset plans takes minutes: see `docs/filters.md`); the plans of the
//! sets that fit no exact plan are superset plans.

use twocan_bxcan::filters::{SizedPlan, MAX_LOOKUP_KEYS};
use twocan_bxcan::planner::{plan_in as bx_plan_in, Scratch as BxScratch};
use twocan_bxcan::PlanOptions;
use twocan_core::{Filter, Format, FrameKind};
use twocan_flexcan::filters::SizedTable;
use twocan_flexcan::planner::{
    plan_in as fx_plan_in, PlanOptions as FxOptions, Scratch as FxScratch,
};

/// The corpus, as the planner-quality section reads it.
const CORPUS: &str = include_str!("../data/dbc_ids.txt");

/// bxCAN: every bank of CAN1 alone, merging, superset where the exact plan does not fit.
const BX: PlanOptions = PlanOptions::new(28).superset(true);
/// bxCAN with both FIFOs.
const BX_BALANCED: PlanOptions = PlanOptions::new(28).fifo(twocan_bxcan::FifoPolicy::Balanced);
/// FlexCAN: choose the configuration, superset where nothing fits exactly.
const FX: FxOptions = FxOptions::choose().superset(true);

/// The bytes of line `index` of the corpus's identifier sets (comments and blank lines
/// skipped), after its `:`: `(start, end)` in `CORPUS`.
const fn set_span(index: usize) -> (usize, usize) {
    let b = CORPUS.as_bytes();
    let mut at = 0;
    let mut seen = 0;
    while at < b.len() {
        let mut end = at;
        while end < b.len() && b[end] != b'\n' {
            end += 1;
        }
        if end > at && b[at] != b'#' {
            if seen == index {
                let mut colon = at;
                while b[colon] != b':' {
                    colon += 1;
                }
                return (colon + 1, end);
            }
            seen += 1;
        }
        at = end + 1;
    }
    panic!("no such set");
}

/// Calls back each identifier of set `index` of the kind asked (`extended`), in file
/// order, writing at most `N` into `out`; returns how many.
const fn read_ids<const N: usize>(
    index: usize,
    extended: bool,
    out: &mut [u32; N],
    from: usize,
) -> usize {
    let b = CORPUS.as_bytes();
    let (mut at, end) = set_span(index);
    let mut n = from;
    while at < end {
        while at < end && b[at] == b' ' {
            at += 1;
        }
        if at >= end {
            break;
        }
        let ext = b[at] == b'x';
        if ext {
            at += 1;
        }
        let mut v = 0u32;
        while at < end && b[at] != b' ' {
            let c = b[at];
            let d = match c {
                b'0'..=b'9' => c - b'0',
                b'A'..=b'F' => c - b'A' + 10,
                b'a'..=b'f' => c - b'a' + 10,
                _ => panic!("not hexadecimal"),
            };
            v = v * 16 + d as u32;
            at += 1;
        }
        if ext == extended {
            if n < N {
                out[n] = v;
            }
            n += 1;
        }
    }
    n
}

/// Number of identifiers of set `index`.
const fn set_len(index: usize) -> usize {
    let mut none = [0u32; 0];
    read_ids(index, false, &mut none, 0) + read_ids(index, true, &mut none, 0)
}

/// One exact data-frame filter per identifier of set `index`, standard first (as the
/// planner-quality report's `IdSet::filters`).
const fn set_filters<const N: usize>(index: usize) -> [Filter; N] {
    let mut ids = [0u32; N];
    let n_std = read_ids(index, false, &mut ids, 0);
    read_ids(index, true, &mut ids, n_std);
    let mut f = [Filter::pass_all(); N];
    let mut i = 0;
    while i < N {
        f[i] = if i < n_std {
            Filter::standard(ids[i] as u16)
        } else {
            Filter::extended(ids[i])
        };
        i += 1;
    }
    f
}

/// A random list (xorshift from `seed`): runs of standard and extended identifiers,
/// scattered ones of every kind, a few masks and format-free filters.
const fn random_list<const N: usize>(seed: u64) -> [Filter; N] {
    let mut s = seed | 1;
    let mut f = [Filter::pass_all(); N];
    let mut i = 0;
    while i < N {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        let r = (s >> 16) as u32;
        f[i] = match r % 10 {
            0..=3 => Filter::standard((0x100 + (r >> 8) % 0x40) as u16),
            4 => Filter::extended(0x18FE_F000 + (r >> 8) % 0x20),
            5 => Filter::exact(FrameKind::Remote, Format::Standard, 0x200 + (r >> 8) % 0x10),
            6 => Filter::exact(FrameKind::Any, Format::Standard, (r >> 8) % 0x800),
            7 => {
                let mask = 0x7FF & !((1 << ((r >> 8) % 4)) - 1);
                Filter::masked(
                    FrameKind::Data,
                    Format::Standard,
                    mask,
                    ((r >> 12) % 0x800) & mask,
                )
            }
            8 => Filter::extended((r >> 4) & 0x1FFF_FFFF),
            _ => Filter::kind_format(FrameKind::Remote, Format::Extended),
        };
        i += 1;
    }
    f
}

fn check_bx<const B: usize, const K: usize>(
    filters: &[Filter],
    options: PlanOptions,
    sized: &SizedPlan<B, K>,
) {
    let mut scratch: Box<BxScratch<MAX_LOOKUP_KEYS>> = Box::default();
    let run = bx_plan_in(filters, options, &mut scratch).expect("the const plan exists");
    assert_eq!(run.banks(), &sized.banks()[..], "bank registers");
    for b in 0..B {
        for slot in 0..4 {
            assert_eq!(
                run.slot_user(b, slot),
                sized.slot_user(b, slot),
                "bank {b} slot {slot}"
            );
        }
    }
    let (keys, users) = sized.lookup_keys();
    assert_eq!(run.key_table().keys(), &keys[..]);
    assert_eq!(run.key_table().users(), &users[..]);
    assert_eq!(run.superset_extra(), sized.superset_extra());
    assert_eq!(run.is_proven_optimal(), sized.is_proven_optimal());
    assert_eq!(run.list_only_banks(), sized.list_only_banks());
    // The same plan, through the driver's view of each.
    assert_eq!(run.as_ref(), sized.as_ref());
    // The default driver's run-time plan is the same whenever it needs few keys.
    if K <= twocan_bxcan::filters::LOOKUP_KEYS {
        let small = twocan_bxcan::plan(filters, options).unwrap();
        assert_eq!(small.as_ref(), sized.as_ref());
    }
}

fn check_fx<const E: usize, const P: usize, const K: usize>(
    filters: &[Filter],
    options: FxOptions,
    sized: &SizedTable<E, P, K>,
) {
    let mut scratch: Box<FxScratch<MAX_LOOKUP_KEYS>> = Box::default();
    let run = fx_plan_in(filters, options, &mut scratch).expect("the const table exists");
    assert_eq!(run.configuration(), sized.configuration());
    assert_eq!(run.elements(), &sized.elements()[..], "ID table");
    assert_eq!(
        run.individual_masks(),
        &sized.individual_masks()[..],
        "RXIMR"
    );
    assert_eq!(run.global_mask(), sized.global_mask(), "RXFGMASK");
    assert_eq!(run.hits(), &sized.hits()[..], "IDHIT map");
    let (keys, users) = sized.lookup_keys();
    assert_eq!(run.key_table().keys(), &keys[..]);
    assert_eq!(run.key_table().users(), &users[..]);
    assert_eq!(run.superset_extra(), sized.superset_extra());
    assert_eq!(run.rejects_all(), sized.rejects_all());
    // The driver's table built from the sized one is the run-time table.
    let back = twocan_flexcan::FilterTable::<MAX_LOOKUP_KEYS>::from_sized(sized).unwrap();
    assert_eq!(back.elements(), run.elements());
    assert_eq!(back.hits(), run.hits());
    assert_eq!(back.key_table(), run.key_table());
}

/// A test per corpus set: both backends, const against run time.
macro_rules! dbc_set {
    ($name:ident, $index:expr) => {
        #[test]
        fn $name() {
            const N: usize = set_len($index);
            const F: [Filter; N] = set_filters::<N>($index);
            check_bx(&F, BX, twocan_bxcan::const_plan!(F, BX));
            check_fx(&F, FX, twocan_flexcan::const_plan!(F, FX));
        }
    };
}

/// A test per random list: both backends (and bxCAN with both FIFOs).
macro_rules! random_list {
    ($name:ident, $n:expr, $seed:expr) => {
        #[test]
        fn $name() {
            const F: [Filter; $n] = random_list::<$n>($seed);
            check_bx(&F, BX, twocan_bxcan::const_plan!(F, BX));
            check_bx(&F, BX_BALANCED, twocan_bxcan::const_plan!(F, BX_BALANCED));
            check_fx(&F, FX, twocan_flexcan::const_plan!(F, FX));
        }
    };
}

// Every fifth set of the corpus, those of up to 110 identifiers (checked by
// `the_sample_is_every_fifth_small_set`): 15 sets of 2 to 102.
dbc_set!(dbc_set_0, 0);
dbc_set!(dbc_set_5, 5);
dbc_set!(dbc_set_10, 10);
dbc_set!(dbc_set_15, 15);
dbc_set!(dbc_set_20, 20);
dbc_set!(dbc_set_25, 25);
dbc_set!(dbc_set_30, 30);
dbc_set!(dbc_set_40, 40);
dbc_set!(dbc_set_45, 45);
dbc_set!(dbc_set_50, 50);
dbc_set!(dbc_set_55, 55);
dbc_set!(dbc_set_60, 60);
dbc_set!(dbc_set_65, 65);
dbc_set!(dbc_set_70, 70);
dbc_set!(dbc_set_75, 75);

random_list!(random_8, 8, 1);
random_list!(random_16, 16, 2);
random_list!(random_24, 24, 3);
random_list!(random_32, 32, 4);
random_list!(random_40, 40, 5);
random_list!(random_48, 48, 6);

#[path = "../src/planner.rs"]
#[allow(dead_code)]
mod planner;

/// The const reader agrees with the report's parser, and the sample is what the module
/// says.
#[test]
fn the_sample_is_every_fifth_small_set() {
    let sets = planner::parse(planner::CORPUS).unwrap();
    for (i, set) in sets.iter().enumerate() {
        assert_eq!(set_len(i), set.len(), "{}", set.name);
    }
    // A set with both formats, read as the report reads it (standard first).
    let mixed = sets
        .iter()
        .position(|s| !s.standard.is_empty() && !s.extended.is_empty())
        .unwrap();
    assert_eq!(mixed, 8);
    const N: usize = set_len(8);
    const F: [Filter; N] = set_filters::<N>(8);
    assert_eq!(&F[..], &sets[mixed].filters()[..]);
    let sample: Vec<usize> = (0..sets.len())
        .step_by(5)
        .filter(|&i| sets[i].len() <= 110)
        .collect();
    assert_eq!(
        sample,
        [0, 5, 10, 15, 20, 25, 30, 40, 45, 50, 55, 60, 65, 70, 75]
    );
}
