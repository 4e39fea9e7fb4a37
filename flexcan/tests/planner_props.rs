//! Property tests of the FlexCAN planner (proptest): random identifier sets (dense
//! blocks, scattered standard and extended identifiers, a few mask and kind-any
//! filters), every configuration and "choose for me", exact and superset mode. Every
//! table must deliver exactly the requested frames with the index of the first user
//! filter that matches; in superset mode extra frames resolve to `None`.

use proptest::prelude::*;
use twocan_core::{Filter, Format, Frame, FrameKind};
use twocan_flexcan::filters::{LOOKUP_KEYS, MAX_LOOKUP_KEYS};
use twocan_flexcan::planner::{plan_for, PlanError, PlanOptions};
use twocan_flexcan::Configuration;

/// Tables with room for every lookup key: the planner unconstrained by a driver.
type FilterTable = twocan_flexcan::FilterTable<MAX_LOOKUP_KEYS>;

fn plan(filters: &[Filter], options: PlanOptions) -> Result<FilterTable, PlanError> {
    plan_for::<MAX_LOOKUP_KEYS>(filters, options)
}

fn list() -> impl Strategy<Value = Vec<Filter>> {
    let block = (0u32..0x7C0, 1u32..40).prop_map(|(start, len)| {
        (start..(start + len).min(0x800))
            .map(|i| Filter::standard(i as u16))
            .collect::<Vec<_>>()
    });
    let ext_block = (0u32..0x1FFF_FF00, 1u32..24)
        .prop_map(|(start, len)| (start..start + len).map(Filter::extended).collect());
    let scattered = prop::collection::vec(
        prop_oneof![
            (0u32..0x800).prop_map(|i| Filter::standard(i as u16)),
            (0u32..0x2000_0000).prop_map(Filter::extended),
            (0u32..0x800).prop_map(|i| Filter::exact(FrameKind::Remote, Format::Standard, i)),
            (0u32..0x800).prop_map(|i| Filter::exact(FrameKind::Any, Format::Standard, i)),
            (0u32..0x800, 0u32..4).prop_map(|(i, b)| {
                let mask = 0x7FF & !((1 << b) - 1) << 2;
                Filter::masked(FrameKind::Data, Format::Standard, mask, i & mask)
            }),
        ],
        0..20,
    );
    (
        prop::collection::vec(prop_oneof![block, ext_block], 0..3),
        scattered,
    )
        .prop_map(|(b, s)| b.into_iter().flatten().chain(s).collect())
}

fn probes(filters: &[Filter]) -> Vec<Frame> {
    let mut out = Vec::new();
    let mut push = |id: u32| {
        out.push(Frame::standard((id & 0x7FF) as u16, &[]).unwrap());
        out.push(Frame::remote(id & 0x7FF, false, 0).unwrap());
        out.push(Frame::extended(id & 0x1FFF_FFFF, &[]).unwrap());
        out.push(Frame::remote(id & 0x1FFF_FFFF, true, 0).unwrap());
    };
    for f in filters {
        for d in [0u32, 1, 2, 3, 4, 8, 16, 32, 64] {
            push(f.id ^ d);
            push(f.id.wrapping_add(d));
        }
    }
    out
}

fn check<const K: usize>(
    filters: &[Filter],
    t: &twocan_flexcan::FilterTable<K>,
    frames: &[Frame],
) -> Result<(), TestCaseError> {
    for f in frames {
        let want = filters.iter().position(|x| x.matches(f)).map(|i| i as u16);
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
    fn tables_are_exact_or_drop_their_extras(filters in list()) {
        let frames = probes(&filters);
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
    fn default_capacity_tables_are_exact(filters in list()) {
        let frames = probes(&filters);
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
