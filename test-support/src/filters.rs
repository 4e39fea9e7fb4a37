//! What the planners' property tests draw: filter lists with dense blocks, scattered
//! standard and extended identifiers, a few mask and kind-any filters, in shuffled
//! order; probe frames around every filter's identifier; and the index the planners
//! must report for a frame (the first user filter that matches it).

use std::ops::Range;

use proptest::prelude::*;
use twocan_core::{Filter, Format, Frame, FrameKind};

/// A filter list of `blocks` dense runs (standard up to 40 identifiers, extended up to
/// 24) and `scattered` single filters (standard and extended data identifiers, standard
/// remote and kind-any identifiers, standard masks of 2 to 5 low bits cleared),
/// shuffled so that blocks are not in order.
pub fn filter_list(
    blocks: Range<usize>,
    scattered: Range<usize>,
) -> impl Strategy<Value = Vec<Filter>> {
    let std_block = (0u32..0x7C0, 1u32..40).prop_map(|(start, len)| {
        (start..(start + len).min(0x800))
            .map(|i| Filter::standard(i as u16))
            .collect::<Vec<_>>()
    });
    let ext_block = (0u32..0x1FFF_FF00, 1u32..24)
        .prop_map(|(start, len)| (start..start + len).map(Filter::extended).collect());
    let single = prop::collection::vec(
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
        scattered,
    );
    (
        prop::collection::vec(prop_oneof![std_block, ext_block], blocks),
        single,
        any::<u64>(),
    )
        .prop_map(|(blocks, single, seed)| {
            let mut all: Vec<Filter> = blocks.into_iter().flatten().chain(single).collect();
            shuffle(&mut all, seed);
            all
        })
}

/// Shuffles `items` in place, deterministically from `seed` (Fisher–Yates over a
/// xorshift generator).
pub fn shuffle<T>(items: &mut [T], seed: u64) {
    let mut s = seed | 1;
    for i in (1..items.len()).rev() {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        items.swap(i, (s % (i as u64 + 1)) as usize);
    }
}

/// The index of the first filter of `filters` that matches `frame`: what a planner must
/// report for it.
pub fn first_match(filters: &[Filter], frame: &Frame) -> Option<u16> {
    filters
        .iter()
        .position(|x| x.matches(frame))
        .map(|i| i as u16)
}

/// Probe frames: each filter's identifier and its neighbours (bits 0..=6 flipped or
/// added), in both formats and both kinds, plus 200 identifiers drawn from `seed`.
pub fn probes(filters: &[Filter], seed: u32) -> Vec<Frame> {
    let mut out = Vec::new();
    let mut push = |id: u32| {
        out.push(Frame::standard((id & 0x7FF) as u16, &[]).expect("masked to 11 bits"));
        out.push(Frame::remote(id & 0x7FF, false, 0).expect("masked to 11 bits"));
        out.push(Frame::extended(id & 0x1FFF_FFFF, &[]).expect("masked to 29 bits"));
        out.push(Frame::remote(id & 0x1FFF_FFFF, true, 0).expect("masked to 29 bits"));
    };
    for f in filters {
        for d in [0u32, 1, 2, 3, 4, 8, 16, 32, 64] {
            push(f.id ^ d);
            push(f.id.wrapping_add(d));
        }
    }
    let mut s = seed | 1;
    for _ in 0..200 {
        s = s.wrapping_mul(1_103_515_245).wrapping_add(12345);
        push(s);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::strategy::ValueTree;
    use proptest::test_runner::TestRunner;

    #[test]
    fn lists_are_valid_filters_of_the_sizes_asked() {
        let mut runner = TestRunner::deterministic();
        for _ in 0..64 {
            let list = filter_list(0..3, 0..5)
                .new_tree(&mut runner)
                .unwrap()
                .current();
            assert!(list.iter().all(|f| f.check().is_ok()), "{list:?}");
            // At most 2 blocks of 40 and 4 singles.
            assert!(list.len() <= 2 * 40 + 4, "{}", list.len());
        }
    }

    #[test]
    fn shuffling_keeps_every_item() {
        let mut v: Vec<u32> = (0..100).collect();
        shuffle(&mut v, 42);
        assert_ne!(v, (0..100).collect::<Vec<_>>());
        v.sort();
        assert_eq!(v, (0..100).collect::<Vec<_>>());
    }

    #[test]
    fn probes_surround_each_identifier_and_first_match_takes_the_first() {
        let filters = [Filter::standard(0x100), Filter::pass_all()];
        let p = probes(&filters, 1);
        assert_eq!(p.len(), (filters.len() * 18 + 200) * 4);
        assert!(p.contains(&Frame::standard(0x101, &[]).unwrap()));
        assert_eq!(
            first_match(&filters, &Frame::standard(0x100, &[]).unwrap()),
            Some(0)
        );
        assert_eq!(
            first_match(&filters, &Frame::standard(0x101, &[]).unwrap()),
            Some(1)
        );
        assert_eq!(
            first_match(&filters[..1], &Frame::standard(0x101, &[]).unwrap()),
            None
        );
    }
}
