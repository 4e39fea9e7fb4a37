//! Property tests of planner v2 (proptest): random identifier sets, standard and
//! extended, dense blocks, sparse sets and sets larger than the banks, with a few mask
//! and kind-any filters mixed in. Every plan must be exact (in superset mode: accept a
//! superset whose extra frames resolve to `None`), report for every delivered frame the
//! index of the first user filter that matches it, and never take more banks than the
//! list-only plan (the lists and probes are `twocan_test_support::filters`'). Plans for
//! the default driver (at most [`LOOKUP_KEYS`] lookup keys)
//! are exact too, and fit whenever the list-only plan does.

use proptest::prelude::*;
use twocan_bxcan::filters::{LOOKUP_KEYS, MAX_LOOKUP_KEYS, NO_FILTER};
use twocan_bxcan::planner::plan_for;
use twocan_bxcan::{FifoPolicy, PlanError, PlanOptions};

/// Plans with room for every lookup key: the planner unconstrained by a driver.
type FilterPlan = twocan_bxcan::FilterPlan<MAX_LOOKUP_KEYS>;

fn plan(filters: &[Filter], options: PlanOptions) -> Result<FilterPlan, PlanError> {
    plan_for::<MAX_LOOKUP_KEYS>(filters, options)
}
use twocan_core::{Filter, Frame};
use twocan_test_support::filters::{filter_list, first_match, probes};

/// A filter list: up to 3 blocks (dense runs) and 30 scattered filters, some masks and
/// kind-any, shuffled.
fn list() -> impl Strategy<Value = Vec<Filter>> {
    filter_list(0..4, 0..30)
}

fn check<const K: usize>(
    filters: &[Filter],
    p: &twocan_bxcan::FilterPlan<K>,
    frames: &[Frame],
) -> Result<(), TestCaseError> {
    for f in frames {
        let want = first_match(filters, f);
        let got = p.evaluate(f).map(|a| a.filter);
        match (want, got) {
            (Some(w), g) => prop_assert_eq!(g, Some(w), "{:?}", f),
            // Not requested: rejected by the hardware, or (superset) dropped by the
            // resolver.
            (None, None) => {}
            (None, Some(g)) => {
                prop_assert!(p.is_superset(), "{:?} accepted as {}", f, g);
                prop_assert_eq!(g, NO_FILTER, "{:?}", f);
            }
        }
    }
    Ok(())
}

fn banks(r: &Result<FilterPlan, PlanError>) -> u16 {
    match r {
        Ok(p) => p.bank_count() as u16,
        Err(PlanError::TooManyBanks { needed, .. }) => *needed,
        Err(e) => panic!("{e:?}"),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn plans_are_exact_and_never_worse_than_list_only(filters in list(), seed in any::<u32>()) {
        let merged = plan(&filters, PlanOptions::new(28).merge(true));
        let list_only = plan(&filters, PlanOptions::new(28).merge(false));
        prop_assert!(banks(&merged) <= banks(&list_only));
        let frames = probes(&filters, seed);
        if let Ok(p) = &merged {
            prop_assert!(!p.is_superset());
            check(&filters, p, &frames)?;
        }
        // For the default driver: exact, within its lookup keys, never more banks than
        // the list-only plan (which needs no key), refused only when that does not fit.
        match twocan_bxcan::plan(&filters, PlanOptions::new(28)) {
            Ok(p) => {
                prop_assert!(p.key_table().len() <= LOOKUP_KEYS);
                prop_assert!(p.bank_count() as u16 <= banks(&list_only));
                prop_assert!(p.bank_count() as u16 >= banks(&merged));
                check(&filters, &p, &frames)?;
            }
            Err(PlanError::TooManyLookupKeys { needed, max }) => {
                prop_assert!(list_only.is_err());
                prop_assert!(merged.is_ok());
                prop_assert_eq!(max as usize, LOOKUP_KEYS);
                prop_assert!(needed as usize > LOOKUP_KEYS);
            }
            Err(e) => prop_assert_eq!(Err(e), merged.map(|_| ())),
        }
        // Both FIFOs: exact, and a frame's matching entries all in one FIFO (RM0410 does
        // not say how filters of different FIFOs compare).
        if let Ok(p) = plan(&filters, PlanOptions::new(28).merge(true).fifo(FifoPolicy::Balanced)) {
            check(&filters, &p, &frames)?;
            for f in &frames {
                let (id, ext, rtr) = (f.raw_id(), f.is_extended(), f.is_remote());
                let mut fifos = p
                    .banks()
                    .iter()
                    .filter(|b| (0..b.kind.slots()).any(|s| b.slot_matches(s, id, ext, rtr)))
                    .map(|b| b.fifo);
                if let Some(first) = fifos.next() {
                    prop_assert!(fifos.all(|x| x == first), "{:?}", f);
                }
            }
        }
        // Superset mode: always a plan (the lists have few general filters), within the
        // banks, exact on the requested frames.
        for banks in [28u8, 14, 4] {
            match plan(&filters, PlanOptions::new(banks).merge(true).superset(true)) {
                Ok(p) => {
                    prop_assert!(p.bank_count() <= banks as usize);
                    check(&filters, &p, &frames)?;
                }
                Err(PlanError::TooManyBanks { needed, available }) => {
                    prop_assert_eq!(available, banks);
                    prop_assert!(needed > banks as u16);
                }
                Err(e) => prop_assert!(false, "{:?}", e),
            }
        }
    }
}
