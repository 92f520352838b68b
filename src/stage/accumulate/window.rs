//! The per-pixel window kernel of the fixed model: the exact sums `sum w * I` of each
//! primitive over a pixel's filter window, in primitive-id order, without allocation.
//!
//! The window is `base x base` blocks of `n x n` samples; which primitive owns each block
//! (or that it crosses an edge) is found once per block and kept for the windows of the
//! next pixel row that share it ([`BlockIds`]). A window whose blocks all belong to one
//! primitive is one dot product. Otherwise a first pass sums the whole window and the
//! samples of the primitive under the kernel's largest weight (it surely has a fragment),
//! and finds the smallest and largest of the other primitive ids; each further pass sums
//! one other primitive's samples (the dot product masked to them) and finds the next
//! larger other id, so the primitives come out in id order; the largest other id's sum is
//! the whole less the rest (a window of `k >= 2` primitives takes `k - 1` passes: one
//! across an edge between two). The sums are exact integers, so this is the same as grouping
//! every sample by primitive. Every pass runs branch-free over a window of constant size
//! (`n` and the base are const parameters) in a [`Word`] that provably holds the sums,
//! keeping lane-wise partial results that are combined once per window, so the compiler
//! vectorises it.

use super::kernel::Kernel;

/// The word the window sums are computed in: `u32` when every sum provably fits (the
/// kernel's weights, which sum to `2^f`, all non-negative, times the largest intensity
/// code, below `2^32`), else `u64`. Exact either way, so the arithmetic wraps only where it
/// cannot overflow; a signed kernel's sums are two's complement in the `u64` word (exact
/// modulo `2^64`, read back as `i64`).
pub(super) trait Word: Copy + Default {
    /// `w * I`.
    fn prod(w: i32, i: u32) -> Self;
    /// `self + o`.
    fn add(self, o: Self) -> Self;
    /// `self - o`.
    fn sub(self, o: Self) -> Self;
    /// `self` where `on`, else zero.
    fn keep(self, on: bool) -> Self;
    /// The sum as the rounding's input.
    fn to_i64(self) -> i64;
}

/// `Word` for an unsigned type at least 32 bits wide (`w * I` of an `i32` and a `u32` is
/// exact modulo `2^64` in `u64`; in `u32` only where the caller proved it fits and the
/// weights are non-negative, see [`sums_fit_u32`]). `$w` is the weight's two's complement
/// in the word.
macro_rules! word {
    ($t:ty, $w:ty) => {
        impl Word for $t {
            #[inline(always)]
            fn prod(w: i32, i: u32) -> Self {
                (w as $w as $t).wrapping_mul(<$t>::from(i))
            }
            #[inline(always)]
            fn add(self, o: Self) -> Self {
                self.wrapping_add(o)
            }
            #[inline(always)]
            fn sub(self, o: Self) -> Self {
                self.wrapping_sub(o)
            }
            #[inline(always)]
            fn keep(self, on: bool) -> Self {
                self & <$t>::from(on).wrapping_neg()
            }
            #[inline(always)]
            fn to_i64(self) -> i64 {
                self as i64
            }
        }
    };
}
word!(u32, u32);
word!(u64, i64);

/// Whether the window sums of kernel `k` over intensity codes up to `imax` fit a `u32`
/// (never for a signed kernel: its sums are read back as signed from the `u64` word).
pub(super) fn sums_fit_u32(k: &Kernel, imax: u32) -> bool {
    !k.signed()
        && (k.pos as u64)
            .checked_mul(u64::from(imax))
            .is_some_and(|m| m <= u64::from(u32::MAX))
}

/// Scratch of one pixel's per-primitive sums (reused across pixels).
pub(super) struct WindowSums {
    /// `(primitive id, sum of w * I)`, sorted by id after [`WindowSums::sum_nb`].
    pub frags: Vec<(u32, i64)>,
    /// Per kernel weight (row-major): all ones where it is non-zero (a primitive gets a
    /// fragment only from samples of non-zero weight), else zero.
    nz: Vec<u32>,
    /// Offset in the window (row-major, `size` per row) of the sample of the largest
    /// weight magnitude (the first such): non-zero, so its primitive has a fragment.
    peak_at: (usize, usize),
}

impl WindowSums {
    /// Scratch for kernel `k`.
    pub fn new(k: &Kernel) -> Self {
        Self {
            frags: Vec::with_capacity(k.size * k.size),
            nz: k
                .w
                .iter()
                .map(|&w| if w != 0 { u32::MAX } else { 0 })
                .collect(),
            peak_at: {
                let e = (0..k.w.len())
                    .max_by_key(|&e| (k.w[e].unsigned_abs(), std::cmp::Reverse(e)))
                    .unwrap_or(0);
                (e / k.size, e % k.size)
            },
        }
    }

    /// Sums `w * I` per primitive over the window whose first sample is at buffer index
    /// `base` (row stride `sw`) into `self.frags`, sorted by primitive id: one entry per
    /// primitive with at least one sample of non-zero weight. `n = N`, the window is
    /// `B x B` blocks, `kw` the kernel's weights (row-major); `ids` are the block ids of
    /// [`BlockIds`], `g` the pixel's offset in them and `cols` their columns.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn sum_nb<const N: usize, const B: usize, W: Word>(
        &mut self,
        prim: &[u32],
        inten: &[u32],
        kw: &[i32],
        base: usize,
        sw: usize,
        ids: &[u64],
        g: usize,
        cols: usize,
    ) {
        self.frags.clear();
        let w = Window::<N, B> {
            prim,
            inten,
            kw,
            nz: &self.nz,
            base,
            sw,
        };
        let first = ids[g];
        let mut uniform = first != MIXED;
        for by in 0..B {
            for bx in 0..B {
                uniform &= ids[by * cols + g + bx] == first;
            }
        }
        if uniform {
            self.frags.push((first as u32, w.whole::<W>().to_i64()));
            return;
        }
        // The window's primitives in increasing id order. The first pass sums the whole
        // window and the samples of `g`, the primitive of the sample of the largest weight
        // (so `g` has a fragment), and finds the smallest and largest of the other ids;
        // each further pass sums one other primitive's samples and finds the next larger
        // id other than `g`. The largest other id's sum is what the rest leave of the whole
        // (exact integers), so a window of `k` primitives takes `k - 1` passes.
        let g = prim[base + self.peak_at.0 * sw + self.peak_at.1];
        let f = w.first_with::<W>(g);
        let mut g_left = true;
        let mut push = |frags: &mut Vec<(u32, i64)>, id: u32, s: W| {
            if g_left && g < id {
                frags.push((g, f.g_sum.to_i64()));
                g_left = false;
            }
            frags.push((id, s.to_i64()));
        };
        if f.others {
            let (mut rest, mut id) = (f.whole.sub(f.g_sum), f.lo);
            while id != f.hi {
                let (s, n) = w.pass_without::<W>(id, g);
                push(&mut self.frags, id, s);
                rest = rest.sub(s);
                id = n.expect("the largest other id lies above every other");
            }
            push(&mut self.frags, f.hi, rest);
        }
        if g_left {
            self.frags.push((g, f.g_sum.to_i64()));
        }
    }
}

/// What the first pass over a mixed window finds ([`Window::first_with`]).
struct First<W> {
    /// Sum of `w * I` over the window.
    whole: W,
    /// Sum of `w * I` over the samples of the given primitive `g`.
    g_sum: W,
    /// Whether a sample of non-zero weight belongs to another primitive.
    others: bool,
    /// Smallest and largest ids other than `g` among the samples of non-zero weight.
    lo: u32,
    hi: u32,
}

/// One pixel's window: `N x N`-sample blocks, `B x B` of them, first sample at `base`.
struct Window<'a, const N: usize, const B: usize> {
    prim: &'a [u32],
    inten: &'a [u32],
    kw: &'a [i32],
    nz: &'a [u32],
    base: usize,
    sw: usize,
}

impl<'a, const N: usize, const B: usize> Window<'a, N, B> {
    /// The window's sample rows: each row's intensities, ids, weights and non-zero masks.
    #[inline(always)]
    fn rows(&self) -> impl Iterator<Item = (&'a [u32], &'a [u32], &'a [i32], &'a [u32])> {
        let size = N * B;
        let (inten, prim, kw, nz) = (self.inten, self.prim, self.kw, self.nz);
        let (base, sw) = (self.base, self.sw);
        (0..size).map(move |j| {
            let row = base + j * sw;
            let k = j * size..(j + 1) * size;
            (
                &inten[row..row + size],
                &prim[row..row + size],
                &kw[k.clone()],
                &nz[k],
            )
        })
    }

    /// The sum of `w * I` over the window, lane-wise until the window's end (the adds wrap,
    /// so any order gives the same value).
    #[inline(always)]
    fn whole<W: Word>(&self) -> W {
        let mut whole = [W::default(); LANES];
        for (is, _, ws, _) in self.rows() {
            for t in 0..N * B {
                let l = t % LANES;
                whole[l] = whole[l].add(W::prod(ws[t], is[t]));
            }
        }
        whole.into_iter().fold(W::default(), W::add)
    }

    /// The first pass over a mixed window: its whole sum, the sum over the samples of
    /// primitive `g`, and the smallest and largest other ids among the samples of non-zero
    /// weight. Partial results stay lane-wise until the window's end (the adds wrap, the
    /// min and max are exact, so any order gives the same values).
    #[inline(always)]
    fn first_with<W: Word>(&self, g: u32) -> First<W> {
        let (mut whole, mut g_sum) = ([W::default(); LANES], [W::default(); LANES]);
        let (mut lo, mut hi) = ([u32::MAX; LANES], [0u32; LANES]);
        for (is, ps, ws, nzs) in self.rows() {
            for t in 0..N * B {
                let l = t % LANES;
                let v = W::prod(ws[t], is[t]);
                let is_g = ps[t] == g;
                whole[l] = whole[l].add(v);
                g_sum[l] = g_sum[l].add(v.keep(is_g));
                let cand = nzs[t] & 0u32.wrapping_sub(u32::from(!is_g));
                lo[l] = lo[l].min(ps[t] | !cand);
                hi[l] = hi[l].max(ps[t] & cand);
            }
        }
        let lo = lo.into_iter().fold(u32::MAX, u32::min);
        let hi = hi.into_iter().fold(0, u32::max);
        First {
            whole: whole.into_iter().fold(W::default(), W::add),
            g_sum: g_sum.into_iter().fold(W::default(), W::add),
            // Without another id the extremes stay `u32::MAX` and 0; with one, they
            // bracket it.
            others: lo <= hi,
            lo,
            hi,
        }
    }

    /// One pass for primitive `id`: the sum of `w * I` over its samples and the smallest
    /// id above `id` other than `g` among the samples of non-zero weight (`None`: none).
    #[inline(always)]
    fn pass_without<W: Word>(&self, id: u32, g: u32) -> (W, Option<u32>) {
        let mut acc = [W::default(); LANES];
        let (mut next, mut found) = ([u32::MAX; LANES], [0u32; LANES]);
        for (is, ps, ws, nzs) in self.rows() {
            for t in 0..N * B {
                let l = t % LANES;
                acc[l] = acc[l].add(W::prod(ws[t], is[t]).keep(ps[t] == id));
                let above = ps[t] > id && ps[t] != g;
                let cand = nzs[t] & 0u32.wrapping_sub(u32::from(above));
                found[l] |= cand;
                next[l] = next[l].min(ps[t] | !cand);
            }
        }
        let sum = acc.into_iter().fold(W::default(), W::add);
        let next = next.into_iter().fold(u32::MAX, u32::min);
        let found = found.into_iter().fold(0, |a, b| a | b);
        (sum, (found != 0).then_some(next))
    }
}

/// Lanes of a window pass's partial results (one AVX2 register of 32-bit values).
const LANES: usize = 8;

/// The ids of the `n x n` blocks (`n = N`) of one span's windows, kept for the span of the
/// same pixels on the next pixel row: its windows start `N` sample rows lower, so their
/// first `B - 1` block rows are this row's last `B - 1`.
#[derive(Debug, Default)]
pub(super) struct BlockIds {
    /// `ids[by * cols + g]`: the primitive owning all samples of block row `by`, block
    /// column `g` (pixel `g - bx` of the span sees it as its block `bx`), or [`MIXED`] when
    /// the block crosses an edge.
    pub ids: Vec<u64>,
    /// The buffer index of the first window and the pixels they were found for (`None`:
    /// none yet).
    at: Option<(usize, usize)>,
}

impl BlockIds {
    /// The block ids of the windows of `pixels` pixels whose first window starts at buffer
    /// index `base` (row stride `sw`): the last `B - 1` block rows of the previous call
    /// moved up when it was the same span one pixel row higher, and only the rows not
    /// found yet scanned. The same values as finding them all afresh every time.
    #[inline(always)]
    pub fn find<const N: usize, const B: usize>(
        &mut self,
        prim: &[u32],
        base: usize,
        sw: usize,
        pixels: usize,
    ) {
        let cols = pixels + B - 1;
        let kept = if B > 1
            && self
                .at
                .is_some_and(|(b, p)| p == pixels && b + N * sw == base)
        {
            self.ids.copy_within(cols.., 0);
            B - 1
        } else {
            self.ids.clear();
            self.ids.resize(B * cols, MIXED);
            0
        };
        block_rows_n::<N, B>(prim, base, sw, pixels, kept, &mut self.ids);
        self.at = Some((base, pixels));
    }
}

/// Every block id of the windows of `pixels` pixels of one pixel row found afresh (laid out
/// as [`BlockIds::ids`]; `base` is the buffer index of the span's first window): what
/// [`BlockIds::find`] must give, in the tests.
#[cfg(test)]
pub(super) fn block_ids_n<const N: usize, const B: usize>(
    prim: &[u32],
    base: usize,
    sw: usize,
    pixels: usize,
    ids: &mut Vec<u64>,
) {
    ids.clear();
    ids.resize(B * (pixels + B - 1), MIXED);
    block_rows_n::<N, B>(prim, base, sw, pixels, 0, ids);
}

/// Block rows `from..B` of the ids of [`BlockIds::find`] into `ids` (sized `B * cols`).
#[inline(always)]
fn block_rows_n<const N: usize, const B: usize>(
    prim: &[u32],
    base: usize,
    sw: usize,
    pixels: usize,
    from: usize,
    ids: &mut [u64],
) {
    let cols = pixels + B - 1;
    for (by, out) in ids.chunks_exact_mut(cols).enumerate().skip(from) {
        let r0 = base + by * N * sw;
        let end = r0 + (N - 1) * sw + cols * N;
        let band = &prim[r0..end];
        for (g, id) in out.iter_mut().enumerate() {
            let first = band[g * N];
            let mut diff = 0u32;
            for sy in 0..N {
                let row: &[u32; N] = band[sy * sw + g * N..sy * sw + g * N + N]
                    .try_into()
                    .expect("N samples");
                for &id in row {
                    diff |= id ^ first;
                }
            }
            *id = if diff == 0 { first as u64 } else { MIXED };
        }
    }
}

/// A block id: the block's samples belong to more than one primitive.
pub(super) const MIXED: u64 = u64::MAX;

#[cfg(test)]
mod tests {
    use super::{BlockIds, WindowSums, block_ids_n};
    use crate::config::FilterKind;
    use crate::stage::accumulate::Kernel;
    use proptest::prelude::*;
    use std::collections::BTreeMap;

    /// A window's sums as the definition groups them: per primitive with a sample of
    /// non-zero weight, the exact sum of `w * I` over all its samples, in id order.
    fn grouped(k: &Kernel, prim: &[u32], inten: &[u32], sw: usize) -> Vec<(u32, i64)> {
        let mut sums: BTreeMap<u32, (i64, bool)> = BTreeMap::new();
        for e in 0..k.size * k.size {
            let at = e / k.size * sw + e % k.size;
            let v = sums.entry(prim[at]).or_default();
            v.0 += i64::from(k.w[e]) * i64::from(inten[at]);
            v.1 |= k.w[e] != 0;
        }
        sums.into_iter()
            .filter(|(_, (_, nz))| *nz)
            .map(|(id, (s, _))| (id, s))
            .collect()
    }

    /// [`WindowSums::sum_nb`] of one window (at the buffer's origin) against [`grouped`].
    fn window_is_grouped<const N: usize, const B: usize>(
        kind: FilterKind,
        prim: &[u32],
        inten: &[u32],
    ) -> Result<(), TestCaseError> {
        let k = Kernel::new(kind, N as u32, 12, 0.5);
        let sw = N * B;
        let mut ids = Vec::new();
        block_ids_n::<N, B>(prim, 0, sw, 1, &mut ids);
        let mut ws = WindowSums::new(&k);
        ws.sum_nb::<N, B, u64>(prim, inten, &k.w, 0, sw, &ids, 0, B);
        let want = grouped(&k, prim, inten, sw);
        prop_assert_eq!(&ws.frags, &want, "{:?} N={} B={}", kind, N, B);
        if !k.signed() {
            ws.sum_nb::<N, B, u32>(prim, inten, &k.w, 0, sw, &ids, 0, B);
            prop_assert_eq!(&ws.frags, &want, "{:?} N={} B={} u32", kind, N, B);
        }
        Ok(())
    }

    /// Block ids kept from the row above are those found afresh: a span walked down
    /// every pixel row (one block row scanned per row when `B > 1`), interrupted by a
    /// span of other pixels and by a jump of rows, for every sample count and base.
    fn kept_block_ids_are_found_afresh<const N: usize, const B: usize>() {
        let (sw, rows) = (61, 50);
        // Patches of 3x2 samples, a third of them split by an edge.
        let prim: Vec<u32> = (0..sw * rows)
            .map(|e| {
                let (r, c) = (e / sw, e % sw);
                let h = (r / 2 * 31 + c / 3 * 17) % 7;
                if h == 0 { (r + c) as u32 % 2 } else { h as u32 }
            })
            .collect();
        let mut kept = BlockIds::default();
        let mut fresh = Vec::new();
        let mut check = |base: usize, pixels: usize| {
            kept.find::<N, B>(&prim, base, sw, pixels);
            block_ids_n::<N, B>(&prim, base, sw, pixels, &mut fresh);
            assert_eq!(kept.ids, fresh, "N={N} B={B} base={base} pixels={pixels}");
        };
        let pixels = (sw - N * B) / N;
        let last = rows - N * B;
        for start in [0, 1] {
            for y in (start..=last).step_by(N) {
                check(y * sw + start, pixels);
                if y == N {
                    check(y * sw + 2, pixels - 1);
                }
            }
        }
        check(5, pixels);
        check(5 + 3 * N * sw, pixels);
    }

    #[test]
    fn kept_block_ids_are_those_found_afresh() {
        kept_block_ids_are_found_afresh::<1, 1>();
        kept_block_ids_are_found_afresh::<1, 4>();
        kept_block_ids_are_found_afresh::<2, 2>();
        kept_block_ids_are_found_afresh::<2, 3>();
        kept_block_ids_are_found_afresh::<4, 2>();
        kept_block_ids_are_found_afresh::<4, 4>();
        kept_block_ids_are_found_afresh::<8, 1>();
        kept_block_ids_are_found_afresh::<8, 2>();
    }

    proptest! {
        /// A window's per-primitive sums are the samples grouped by primitive, in id order:
        /// windows of one to six primitives (some background), every filter, mixed and
        /// uniform blocks.
        #[test]
        fn window_sums_group_the_samples_by_primitive(
            kind in 0usize..FilterKind::ALL.len(),
            n in prop_oneof![Just(1usize), Just(2), Just(4)],
            ids in proptest::collection::vec(0u32..6, 128),
            spread in 1u32..40,
            one in proptest::bool::weighted(0.1),
            inten in proptest::collection::vec(0u32..65_536, 256),
        ) {
            let kind = FilterKind::ALL[kind];
            let size = n * kind.base() as usize;
            // Ids in patches of two samples, scaled apart so they are not consecutive (or
            // one primitive over the window).
            let prim: Vec<u32> = (0..size * size)
                .map(|e| if one { ids[0] } else { ids[e / 2] * spread })
                .collect();
            let inten = &inten[..size * size];
            match (n, kind.base()) {
                (1, 1) => window_is_grouped::<1, 1>(kind, &prim, inten)?,
                (1, 2) => window_is_grouped::<1, 2>(kind, &prim, inten)?,
                (1, 3) => window_is_grouped::<1, 3>(kind, &prim, inten)?,
                (1, _) => window_is_grouped::<1, 4>(kind, &prim, inten)?,
                (2, 1) => window_is_grouped::<2, 1>(kind, &prim, inten)?,
                (2, 2) => window_is_grouped::<2, 2>(kind, &prim, inten)?,
                (2, 3) => window_is_grouped::<2, 3>(kind, &prim, inten)?,
                (2, _) => window_is_grouped::<2, 4>(kind, &prim, inten)?,
                (_, 1) => window_is_grouped::<4, 1>(kind, &prim, inten)?,
                (_, 2) => window_is_grouped::<4, 2>(kind, &prim, inten)?,
                (_, 3) => window_is_grouped::<4, 3>(kind, &prim, inten)?,
                _ => window_is_grouped::<4, 4>(kind, &prim, inten)?,
            }
        }
    }
}
