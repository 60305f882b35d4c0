//! Sorting items by 64-bit keys (Morton codes) in linear time.
//!
//! The measurement orders its vectors, and the trees their items, by the Morton codes of
//! their positions. A least-significant-digit radix sort over the keys' 11-bit digits is
//! stable, so items of equal keys keep their order: sorting `(key, index)` pairs made in
//! index order gives exactly the order of sorting the pairs themselves.
//!
//! In place of rayon's comparison sort, callgrind (1 thread): sphere_on_plate's ball
//! verification 1,751 -> 1,725 M instructions, the dome's 1,794 -> 1,768 M; in wall time
//! on 2 threads no slower (the halves are sorted side by side, as rayon's sort also split
//! its work). One digit pass at a time (eight of 8 bits, each counted before it was
//! scattered) saved less: 1,728 M.

/// Bits per digit.
const DIGIT: u32 = 11;

/// Buckets per digit.
const BUCKETS: usize = 1 << DIGIT;

/// Digits of a 64-bit key.
const DIGITS: usize = u64::BITS.div_ceil(DIGIT) as usize;

/// Items below which [`sort_by_key`] sorts on one thread.
const SPLIT: usize = 1 << 15;

/// Sorts `items` by `key(item)`, ascending, keeping the order of equal keys (stable). Many
/// items are sorted in two halves side by side (rayon) and merged.
pub(crate) fn sort_by_key<T: Copy + Send>(items: &mut Vec<T>, key: impl Fn(&T) -> u64 + Sync) {
    if items.len() < SPLIT {
        sort_serial(items, &key);
        return;
    }
    let mut right = items.split_off(items.len() / 2);
    let mut left = std::mem::take(items);
    rayon::join(
        || sort_serial(&mut left, &key),
        || sort_serial(&mut right, &key),
    );
    // Equal keys: the left half's first, as they came.
    items.reserve_exact(left.len() + right.len());
    let (mut i, mut j) = (0, 0);
    while i < left.len() && j < right.len() {
        if key(&right[j]) < key(&left[i]) {
            items.push(right[j]);
            j += 1;
        } else {
            items.push(left[i]);
            i += 1;
        }
    }
    items.extend_from_slice(&left[i..]);
    items.extend_from_slice(&right[j..]);
}

/// [`sort_by_key`] on the calling thread: digits on which every key agrees are not
/// scattered.
fn sort_serial<T: Copy>(items: &mut Vec<T>, key: &impl Fn(&T) -> u64) {
    let n = items.len();
    if n < 2 {
        return;
    }
    let mask = (BUCKETS - 1) as u64;
    // Every digit's counts in one pass.
    let mut counts = vec![[0usize; BUCKETS]; DIGITS];
    for it in items.iter() {
        let k = key(it);
        for (d, c) in counts.iter_mut().enumerate() {
            c[((k >> (d as u32 * DIGIT)) & mask) as usize] += 1;
        }
    }
    let mut from = std::mem::take(items);
    // Every slot of `to` is written once a pass (the digit's counts sum to `n`).
    let mut to: Vec<T> = vec![from[0]; n];
    for (d, start) in counts.iter_mut().enumerate() {
        // All keys in one bucket: nothing moves.
        if start.contains(&n) {
            continue;
        }
        let mut sum = 0;
        for s in start.iter_mut() {
            (*s, sum) = (sum, sum + *s);
        }
        let shift = d as u32 * DIGIT;
        for it in &from {
            let b = ((key(it) >> shift) & mask) as usize;
            to[start[b]] = *it;
            start[b] += 1;
        }
        std::mem::swap(&mut from, &mut to);
    }
    *items = from;
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The order of a comparison sort of `(key, index)` pairs, with keys from a few
        /// values (many ties) or spread over every bit, and keys that differ in a few bits
        /// at one place only (each digit decides somewhere).
        #[test]
        fn sorts_as_the_pairs_sort(
            keys in prop_oneof![
                prop::collection::vec(prop_oneof![0u64..4, any::<u64>()], 0..600),
                (0u32..61, any::<u64>()).prop_flat_map(|(at, base)| {
                    prop::collection::vec((0u64..8).prop_map(move |k| base ^ (k << at)), 0..600)
                }),
            ],
            // Past the split into halves, in some cases.
            long in prop::bool::weighted(0.1),
        ) {
            let n = if long { SPLIT + 100 } else { keys.len() };
            let mut pairs: Vec<(u64, u32)> =
                keys.iter().cycle().take(n).zip(0u32..).map(|(&k, i)| (k, i)).collect();
            let mut expected = pairs.clone();
            expected.sort_unstable();
            sort_by_key(&mut pairs, |p| p.0);
            prop_assert_eq!(pairs, expected);
        }
    }

    #[test]
    fn equal_keys_keep_their_order() {
        let mut v = vec![
            (5u64, 'a'),
            (3, 'b'),
            (5, 'c'),
            (3, 'd'),
            (u64::MAX, 'e'),
            (0, 'f'),
        ];
        sort_by_key(&mut v, |p| p.0);
        assert_eq!(
            v,
            [
                (0, 'f'),
                (3, 'b'),
                (3, 'd'),
                (5, 'a'),
                (5, 'c'),
                (u64::MAX, 'e')
            ]
        );
    }
}
