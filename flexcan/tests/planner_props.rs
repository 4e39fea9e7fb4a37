//! Property tests of the FlexCAN planner (proptest): random identifier sets (dense
//! blocks, scattered standard and extended identifiers, a few mask and kind-any
//! filters), every configuration and "choose for me", exact and superset mode. Every
//! table must deliver exactly the requested frames with the index of the first user
//! filter that matches; in superset mode extra frames resolve to `None`. The lists and
//! probes are `twocan_test_support::filters`'.

use proptest::prelude::*;
use twocan_core::{Filter, Frame};
use twocan_flexcan::filters::{LOOKUP_KEYS, MAX_LOOKUP_KEYS};
use twocan_flexcan::planner::{plan_for, PlanError, PlanOptions};
use twocan_flexcan::Configuration;
use twocan_test_support::filters::{filter_list, first_match, probes};

/// Tables with room for every lookup key: the planner unconstrained by a driver.
type FilterTable = twocan_flexcan::FilterTable<MAX_LOOKUP_KEYS>;

fn plan(filters: &[Filter], options: PlanOptions) -> Result<FilterTable, PlanError> {
    plan_for::<MAX_LOOKUP_KEYS>(filters, options)
}

/// A filter list: up to 2 blocks (dense runs) and 20 scattered filters, some masks and
/// kind-any, shuffled.
fn list() -> impl Strategy<Value = Vec<Filter>> {
    filter_list(0..3, 0..20)
}

fn check<const K: usize>(
    filters: &[Filter],
    t: &twocan_flexcan::FilterTable<K>,
    frames: &[Frame],
) -> Result<(), TestCaseError> {
    for f in frames {
        let want = first_match(filters, f);
        match (want, t.evaluate(f)) {
            (Some(w), got) => prop_assert_eq!(got.and_then(|(_, i)| i), Some(w), "{:?}", f),
            (None, None) => {}
            (None, Some((_, i))) => {
                prop_assert!(t.superset_extra() > 0, "{:?}", f);
                prop_assert_eq!(i, None, "{:?}", f);
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn tables_are_exact_or_drop_their_extras(filters in list(), seed in any::<u32>()) {
        let frames = probes(&filters, seed);
        let choices = Configuration::ALL.map(Some);
        for configuration in choices.into_iter().chain([None]) {
            for superset in [false, true] {
                let options = PlanOptions { configuration, merge: true, superset };
                match plan(&filters, options) {
                    Ok(t) => {
                        if let Some(c) = configuration {
                            prop_assert_eq!(t.configuration(), c);
                        }
                        if !superset {
                            prop_assert_eq!(t.superset_extra(), 0);
                        }
                        check(&filters, &t, &frames)?;
                    }
                    Err(PlanError::TooManyPrimary { needed, available, .. }) => {
                        prop_assert!(needed > available as u16);
                    }
                    Err(e) => prop_assert!(false, "{:?}", e),
                }
            }
        }
    }

    /// With the default lookup capacity: exact, within the capacity, and a table
    /// whenever one element per identifier fits (that table needs no lookup key).
    #[test]
    fn default_capacity_tables_are_exact(filters in list(), seed in any::<u32>()) {
        let frames = probes(&filters, seed);
        for configuration in Configuration::ALL.map(Some).into_iter().chain([None]) {
            let options = PlanOptions { configuration, merge: true, superset: false };
            let single = plan(&filters, options.merge(false));
            match twocan_flexcan::planner::plan(&filters, options) {
                Ok(t) => {
                    prop_assert!(t.key_table().len() <= LOOKUP_KEYS);
                    check(&filters, &t, &frames)?;
                }
                Err(PlanError::TooManyLookupKeys { needed, max }) => {
                    prop_assert!(single.is_err());
                    prop_assert!(needed as usize > LOOKUP_KEYS);
                    prop_assert_eq!(max as usize, LOOKUP_KEYS);
                }
                Err(e) => prop_assert!(single.is_err(), "{:?}", e),
            }
        }
    }
}
