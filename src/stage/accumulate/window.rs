//! The per-pixel window kernel of the fixed model: the exact sums `sum w * I` of each
//! primitive over a pixel's filter window, in primitive-id order, without allocation.
//!
//! The window is `base x base` blocks of `n x n` samples; which primitive owns each block
//! (or that it crosses an edge) is found once per block and kept for the windows of the
//! next pixel row that share it ([`BlockIds`]). A window whose blocks all belong to one primitive is one dot
//! product. Otherwise a first pass sums the whole window and finds its smallest and
//! largest primitive ids, and each further pass sums one primitive's samples (the dot
//! product masked to them) and finds the next larger id, so the primitives come out in id
//! order; the largest id's sum is the whole less the others' (a window of `k` primitives
//! takes `k` passes). The sums are exact integers, so this is the same as grouping every
//! sample by primitive. Every pass runs branch-free over a window of constant size (`n`
//! and the base are const parameters) in a [`Word`] that provably holds the sums, keeping
//! lane-wise partial results that are combined once per window, so the compiler
//! vectorises it.

use super::kernel::Kernel;
use crate::fixed::SignalStats;

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
            self.frags
                .push((first as u32, w.first::<W>().whole.to_i64()));
            return;
        }
        // The window's primitives in increasing id order: the first pass sums the whole
        // window and finds its smallest and largest ids; each further pass sums one
        // primitive's samples and finds the next larger id (every pass reads the whole
        // window, branch-free). The largest id's sum is what the others leave of the whole
        // (exact integers), so a window of `k` primitives takes `k` passes.
        let f = w.first::<W>();
        if !f.found {
            return;
        }
        let (mut rest, mut id) = (f.whole, f.lo);
        while id != f.hi {
            let (s, n) = w.pass::<W>(id);
            self.frags.push((id, s.to_i64()));
            rest = rest.sub(s);
            id = n.expect("the largest id lies above every other");
        }
        self.frags.push((f.hi, rest.to_i64()));
    }
}

/// What the first pass over a mixed window finds ([`Window::first`]).
struct First<W> {
    /// Sum of `w * I` over the window.
    whole: W,
    /// Whether any sample has a non-zero weight.
    found: bool,
    /// Smallest and largest ids among the samples of non-zero weight.
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

    /// The first pass over the window: its whole sum and, for a mixed window, its
    /// smallest and largest ids among the samples of non-zero weight. Partial results stay
    /// lane-wise until the window's end (the adds wrap, the min, max and or are exact, so
    /// any order gives the same values).
    #[inline(always)]
    fn first<W: Word>(&self) -> First<W> {
        let mut whole = [W::default(); LANES];
        let (mut lo, mut hi, mut found) = ([u32::MAX; LANES], [0u32; LANES], [0u32; LANES]);
        for (is, ps, ws, nzs) in self.rows() {
            for t in 0..N * B {
                let l = t % LANES;
                whole[l] = whole[l].add(W::prod(ws[t], is[t]));
                let cand = nzs[t];
                found[l] |= cand;
                lo[l] = lo[l].min(ps[t] | !cand);
                hi[l] = hi[l].max(ps[t] & cand);
            }
        }
        First {
            whole: whole.into_iter().fold(W::default(), W::add),
            found: found.into_iter().fold(0, |a, b| a | b) != 0,
            lo: lo.into_iter().fold(u32::MAX, u32::min),
            hi: hi.into_iter().fold(0, u32::max),
        }
    }

    /// One pass for primitive `id`: the sum of `w * I` over its samples and the smallest
    /// id above `id` among the samples of non-zero weight (`None`: no larger id).
    #[inline(always)]
    fn pass<W: Word>(&self, id: u32) -> (W, Option<u32>) {
        let mut acc = [W::default(); LANES];
        let (mut next, mut found) = ([u32::MAX; LANES], [0u32; LANES]);
        for (is, ps, ws, nzs) in self.rows() {
            for t in 0..N * B {
                let l = t % LANES;
                acc[l] = acc[l].add(W::prod(ws[t], is[t]).keep(ps[t] == id));
                let cand = nzs[t] & 0u32.wrapping_sub(u32::from(ps[t] > id));
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

/// The product statistics of one row of pixels, recorded exactly as
/// [`SignalStats::record`] would (same values, same order of the float sums) but without
/// its optional 128-bit range per value; [`ProductStats::into_stats`] gives the
/// `SignalStats`.
///
/// A rounding that drops `sh` bits errs by `k * 2^-sh` for an integer `|k| < 2^sh`. Where
/// every partial sum of those errors and of their squares stays below `2^53` units of
/// `2^-sh` and `2^-2sh` (the caller's bound, [`ProductStats::new`] with `exact`), each
/// float add is exact, so the float sums equal the integer sums of `k` and `k^2` scaled
/// once at the end: the same bits, without a float add per value.
pub(super) struct ProductStats {
    count: u64,
    min: i64,
    max: i64,
    err_sum: f64,
    err_sq_sum: f64,
    /// Bits the roundings recorded by [`ProductStats::record_rounding`] drop.
    sh: u32,
    /// The errors of those roundings are summed as integers in `k_sum` and `k_sq`.
    exact: bool,
    k_sum: i64,
    k_sq: u64,
}

impl ProductStats {
    /// Nothing recorded, for roundings that drop `sh` bits; `exact`: their errors are
    /// summed as integers (only where the caller proved every partial sum exact, see
    /// above).
    pub fn new(sh: u32, exact: bool) -> Self {
        Self {
            count: 0,
            min: i64::MAX,
            max: i64::MIN,
            err_sum: 0.0,
            err_sq_sum: 0.0,
            sh,
            exact,
            k_sum: 0,
            k_sq: 0,
        }
    }

    /// Records one rounding (as `SignalStats::record(exact_lsb, rounded, false)`).
    #[inline(always)]
    pub fn record(&mut self, exact_lsb: f64, rounded: i64) {
        self.count += 1;
        self.min = self.min.min(rounded);
        self.max = self.max.max(rounded);
        let e = rounded as f64 - exact_lsb;
        self.err_sum += e;
        self.err_sq_sum += e * e;
    }

    /// Records `rounded`, the rounding of `sum * 2^-sh` (`0 < sh < 63`, the statistics'
    /// `sh`): as [`ProductStats::record`] of `sum * 2^-sh` (a multiplication by the power
    /// of two, exact like the division), in integers when `exact`.
    #[inline(always)]
    pub fn record_rounding(&mut self, rounded: i64, sum: i64) {
        let sh = self.sh;
        if self.exact {
            self.count += 1;
            self.min = self.min.min(rounded);
            self.max = self.max.max(rounded);
            let k = (rounded << sh).wrapping_sub(sum);
            self.k_sum += k;
            self.k_sq += k.unsigned_abs() * k.unsigned_abs();
        } else {
            // 2^-sh from its exponent bits.
            let scale = f64::from_bits((1023 - u64::from(sh)) << 52);
            self.record(sum as f64 * scale, rounded);
        }
    }

    /// The statistics as a `SignalStats` named and formatted like `template`.
    pub fn into_stats(self, template: &SignalStats) -> SignalStats {
        let mut s = template.clone();
        s.count = self.count;
        if self.count > 0 {
            s.min = Some(self.min.into());
            s.max = Some(self.max.into());
        }
        s.err_sum = self.err_sum;
        s.err_sq_sum = self.err_sq_sum;
        if self.exact {
            let sh = self.sh;
            // Exact conversions (below 2^53) and exact power-of-two scalings.
            s.err_sum = self.k_sum as f64 * f64::from_bits((1023 - u64::from(sh)) << 52);
            s.err_sq_sum = self.k_sq as f64 * f64::from_bits((1023 - 2 * u64::from(sh)) << 52);
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::{BlockIds, ProductStats, block_ids_n};
    use crate::fixed::{QFormat, Quant, RoundShift, SignalStats};
    use proptest::prelude::*;

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
        /// The integer error sums give the float recording's bits: roundings by 1 to 15
        /// bits of sums below 2^53 in every mode, mostly near ties and near zero.
        #[test]
        fn integer_error_sums_equal_the_float_recording(
            sh in 1u32..=15,
            q in 0usize..7,
            sums in proptest::collection::vec(
                prop_oneof![
                    -(1i64 << 52)..(1i64 << 52),
                    -4096i64..4096,
                    (-(1i64 << 30)..(1i64 << 30)).prop_map(|v| v << 14),
                ],
                0..400,
            ),
        ) {
            let round = RoundShift::new(sh, Quant::ALL[q]);
            let (mut int, mut float) = (ProductStats::new(sh, true), ProductStats::new(sh, false));
            for &s in &sums {
                let v = round.apply(s);
                int.record_rounding(v, s);
                float.record_rounding(v, s);
            }
            let t = SignalStats::new("p", QFormat::new(true, 40, 0));
            let (a, b) = (int.into_stats(&t), float.into_stats(&t));
            prop_assert_eq!(a.err_sum.to_bits(), b.err_sum.to_bits());
            prop_assert_eq!(a.err_sq_sum.to_bits(), b.err_sq_sum.to_bits());
            prop_assert_eq!(format!("{a:?}"), format!("{b:?}"));
        }
    }
}
