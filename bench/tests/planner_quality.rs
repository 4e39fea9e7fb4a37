//! The planner-quality section of can-bench (`bench/src/planner.rs`) on the shipped
//! corpus: the corpus parses, merged plans never take more banks than list-only ones
//! and never fewer than the exact lower bound, and the report renders.

#[path = "../src/planner.rs"]
#[allow(dead_code)]
mod planner;

#[test]
fn corpus_plans_between_the_bound_and_the_list_only_plan() {
    let sets = planner::parse(planner::CORPUS).unwrap();
    assert!(sets.len() >= 60, "{}", sets.len());
    // Unoptimised builds (`cargo test --workspace`) check the sets of up to 100
    // identifiers; `--release` checks all of them and renders the report.
    let full = !cfg!(debug_assertions);
    let sets: Vec<_> = sets
        .into_iter()
        .filter(|s| full || s.len() <= 100)
        .collect();
    let rows = planner::bxcan_rows(&sets);
    for r in &rows {
        assert!(r.merged <= r.list_only, "{r:?}");
        assert!(r.merged >= r.bound.0, "{r:?}");
    }
    if full {
        let report = planner::report();
        println!("{report}");
        assert!(report.contains("### bxCAN (28 banks)"));
    }
}

#[test]
fn small_sets_have_exact_bounds() {
    let set = planner::IdSet {
        name: "t".into(),
        standard: (0x500..0x540).chain([0x100, 0x101, 0x102]).collect(),
        extended: vec![0x18FE_F100, 0x18FE_F101, 0x18FE_F102, 0x18FE_F103],
    };
    // One standard block (2) + three singles (3) + one extended block (4): 9 quarters.
    assert_eq!(planner::bank_bound(&set), (3, true));
}
