//! The distinct depth codes of a frame, largest first (the layer plan's input): a bitmap
//! over the codes' span when it is small (the usual case: depth codes of a few dozen bits
//! at most, and a frame's objects within a part of their range), a radix sort otherwise.

use crate::stage::Pool;

/// Spans of up to this many codes go through a bitmap (8 MiB of bits).
const BITMAP_SPAN: u64 = 1 << 26;

/// The distinct keys of `lists` (any order, repeats allowed, none `u32::MAX`), and
/// `u32::MAX` first when `background`, largest first, in a buffer from `pool`.
pub(super) fn distinct_descending(lists: &[&[u32]], background: bool, pool: &Pool) -> Vec<u32> {
    let n: usize = lists.iter().map(|l| l.len()).sum();
    let mut keys: Vec<u32> = pool.take(n + 1);
    if background {
        keys.push(u32::MAX);
    }
    let all = || lists.iter().flat_map(|l| l.iter().copied());
    let Some((lo, hi)) = all().fold(None, |r: Option<(u32, u32)>, k| {
        Some(r.map_or((k, k), |(l, h)| (l.min(k), h.max(k))))
    }) else {
        return keys;
    };
    let span = u64::from(hi - lo) + 1;
    if span <= BITMAP_SPAN {
        let mut bits: Vec<u64> = pool.filled(span.div_ceil(64) as usize, 0);
        for k in all() {
            let d = (k - lo) as usize;
            bits[d >> 6] |= 1 << (d & 63);
        }
        // Words from the top, each word's bits from the top, into a buffer with room for
        // them all.
        let mut len = keys.len();
        keys.resize(len + n, 0);
        for (w, &b) in bits.iter().enumerate().rev() {
            let (mut b, base) = (b, lo + w as u32 * 64);
            while b != 0 {
                let top = 63 - b.leading_zeros();
                keys[len] = base + top;
                len += 1;
                b ^= 1 << top;
            }
        }
        keys.truncate(len);
        pool.give(bits);
    } else {
        keys.extend(all());
        let mut tmp: Vec<u32> = pool.scratch(keys.len(), 0);
        sort_descending(&mut keys, &mut tmp);
        pool.give(tmp);
        keys.dedup();
    }
    keys
}

/// Sorts `keys` largest first (LSD radix sort, 11-bit digits; `tmp` as long as `keys`).
fn sort_descending(keys: &mut [u32], tmp: &mut [u32]) {
    const BITS: u32 = 11;
    const MASK: u32 = (1 << BITS) - 1;
    let (mut src, mut dst) = (keys, tmp);
    for pass in 0..3 {
        let digit = |k: u32| (((!k) >> (pass * BITS)) & MASK) as usize;
        let mut start = [0usize; 1 << BITS];
        for &k in src.iter() {
            start[digit(k)] += 1;
        }
        let mut sum = 0;
        for s in start.iter_mut() {
            (*s, sum) = (sum, sum + *s);
        }
        for &k in src.iter() {
            let d = digit(k);
            dst[start[d]] = k;
            start[d] += 1;
        }
        std::mem::swap(&mut src, &mut dst);
    }
    // Three passes leave the sorted keys in `tmp`.
    dst.copy_from_slice(src);
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The radix sort orders any keys as the comparison sort does, largest first.
        #[test]
        fn radix_sort_is_a_descending_sort(mut keys in prop::collection::vec(any::<u32>(), 0..3000)) {
            let mut tmp = vec![0; keys.len()];
            let mut want = keys.clone();
            want.sort_unstable_by(|a, b| b.cmp(a));
            sort_descending(&mut keys, &mut tmp);
            prop_assert_eq!(keys, want);
        }

        /// The distinct keys are those of a sort and a dedup, over small spans (the bitmap)
        /// and any (the radix sort), with and without the background, split into lists
        /// anyhow; the pool's buffers kept from one call do not leak into the next.
        #[test]
        fn distinct_keys_are_sorted_and_deduplicated(
            lists in prop::collection::vec(prop::collection::vec(0u32..u32::MAX, 0..200), 0..5),
            narrow in any::<bool>(),
            background in any::<bool>(),
        ) {
            let lists: Vec<Vec<u32>> = lists
                .into_iter()
                .map(|l| l.into_iter().map(|k| if narrow { 1000 + k % 5000 } else { k }).collect())
                .collect();
            let refs: Vec<&[u32]> = lists.iter().map(|l| &l[..]).collect();
            let mut want: Vec<u32> = lists.iter().flatten().copied().collect();
            if background {
                want.push(u32::MAX);
            }
            want.sort_unstable_by(|a, b| b.cmp(a));
            want.dedup();
            let pool = Pool::new();
            for _ in 0..2 {
                prop_assert_eq!(distinct_descending(&refs, background, &pool), want.clone());
            }
        }
    }

    #[test]
    fn radix_sort_keeps_the_extremes() {
        let mut keys = vec![0, u32::MAX, 1 << 22, u32::MAX - 1, 0, 1 << 11];
        let mut tmp = vec![0; keys.len()];
        sort_descending(&mut keys, &mut tmp);
        assert_eq!(keys, [u32::MAX, u32::MAX - 1, 1 << 22, 1 << 11, 0, 0]);
    }

    /// The span's ends and a key at a word's last bit come out, on both sides of the
    /// bitmap's limit.
    #[test]
    fn extreme_spans() {
        let pool = Pool::new();
        let wide = [0, u32::MAX - 1, 63, 64];
        assert_eq!(
            distinct_descending(&[&wide], false, &pool),
            [u32::MAX - 1, 64, 63, 0]
        );
        let edge = [7, 7 + (1 << 26) - 1, 7 + 63, 7 + 64];
        assert_eq!(
            distinct_descending(&[&edge[..2], &edge[2..]], true, &pool),
            [u32::MAX, 7 + (1 << 26) - 1, 7 + 64, 7 + 63, 7]
        );
    }
}
