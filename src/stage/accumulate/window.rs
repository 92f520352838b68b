//! The per-pixel window kernel of the fixed model: the exact sums `sum w * I` of each
//! primitive over a pixel's filter window, in primitive-id order, without allocation.
//!
//! The window is `base x base` blocks of `n x n` samples; which primitive owns each block
//! (or that it crosses an edge) is found once per block of a pixel row
//! ([`block_ids_n`]). A window whose blocks all belong to one primitive (most windows) is
//! one dot product. Otherwise one pass over the window finds its smallest primitive id,
//! and each further pass sums one primitive's samples (the dot product masked to them) and
//! finds the next larger id, so the primitives come out in id order. The sums are exact
//! integers, so this is the same as grouping every sample by primitive. Every pass runs
//! branch-free over a window of constant size (`n` and the base are const parameters) in a
//! [`Word`] that provably holds the sums, so the compiler vectorises it.

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
    /// [`block_ids_n`], `g` the pixel's offset in them and `cols` their columns.
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
            let (dot, _) = w.pass::<W, false>(0);
            self.frags.push((first as u32, dot.to_i64()));
            return;
        }
        // The window's primitives in increasing id order: each pass sums the current one's
        // samples and finds the next larger id (every pass reads the whole window,
        // branch-free).
        let (_, mut next) = w.pass::<W, false>(0);
        while let Some(id) = next {
            let (s, n) = w.pass::<W, true>(id);
            self.frags.push((id, s.to_i64()));
            next = n;
        }
    }
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

impl<const N: usize, const B: usize> Window<'_, N, B> {
    /// One pass over the window. `MASKED`: the sum of `w * I` over primitive `id`'s
    /// samples and the smallest id above `id` among the samples of non-zero weight;
    /// otherwise the whole window's sum and its smallest such id (`None`: no larger id, or
    /// no sample of non-zero weight).
    #[inline(always)]
    fn pass<W: Word, const MASKED: bool>(&self, id: u32) -> (W, Option<u32>) {
        let size = N * B;
        let (kw, nz) = (&self.kw[..size * size], &self.nz[..size * size]);
        let mut acc = W::default();
        let mut next = u32::MAX;
        let mut found = 0u32;
        for j in 0..size {
            let row = self.base + j * self.sw;
            let (is, ps) = (&self.inten[row..row + size], &self.prim[row..row + size]);
            let (ws, nzs) = (&kw[j * size..(j + 1) * size], &nz[j * size..(j + 1) * size]);
            for t in 0..size {
                let v = W::prod(ws[t], is[t]);
                acc = acc.add(if MASKED { v.keep(ps[t] == id) } else { v });
                // Candidates: samples of non-zero weight (above `id` when masked).
                let above = if MASKED { ps[t] > id } else { true };
                let cand = nzs[t] & 0u32.wrapping_sub(u32::from(above));
                found |= cand;
                next = next.min(ps[t] | !cand);
            }
        }
        (acc, (found != 0).then_some(next))
    }
}

/// The ids of the `n x n` blocks (`n = N`) of the windows of `pixels` pixels of one pixel
/// row: `ids[by * cols + g]` is the primitive owning all samples of block row `by`, block
/// column `g` (pixel `g - bx` of the span sees it as its block `bx`), or [`MIXED`] when the
/// block crosses an edge. `base` is the buffer index of the span's first window.
#[inline(always)]
pub(super) fn block_ids_n<const N: usize, const B: usize>(
    prim: &[u32],
    base: usize,
    sw: usize,
    pixels: usize,
    ids: &mut Vec<u64>,
) {
    let blocks = B;
    let cols = pixels + blocks - 1;
    ids.clear();
    for by in 0..blocks {
        let r0 = base + by * N * sw;
        let end = r0 + (N - 1) * sw + cols * N;
        let band = &prim[r0..end];
        for g in 0..cols {
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
            ids.push(if diff == 0 { first as u64 } else { MIXED });
        }
    }
}

/// A block id: the block's samples belong to more than one primitive.
pub(super) const MIXED: u64 = u64::MAX;

/// The product statistics of one row of pixels, recorded exactly as
/// [`SignalStats::record`] would (same values, same order of the float sums) but without
/// its optional 128-bit range per value; [`ProductStats::into_stats`] gives the
/// `SignalStats`.
pub(super) struct ProductStats {
    count: u64,
    min: i128,
    max: i128,
    err_sum: f64,
    err_sq_sum: f64,
}

impl ProductStats {
    /// Nothing recorded.
    pub fn new() -> Self {
        Self {
            count: 0,
            min: i128::MAX,
            max: i128::MIN,
            err_sum: 0.0,
            err_sq_sum: 0.0,
        }
    }

    /// Records one rounding (as `SignalStats::record(exact_lsb, rounded, false)`).
    #[inline]
    pub fn record(&mut self, exact_lsb: f64, rounded: i128) {
        self.count += 1;
        self.min = self.min.min(rounded);
        self.max = self.max.max(rounded);
        let e = rounded as f64 - exact_lsb;
        self.err_sum += e;
        self.err_sq_sum += e * e;
    }

    /// The statistics as a `SignalStats` named and formatted like `template`.
    pub fn into_stats(self, template: &SignalStats) -> SignalStats {
        let mut s = template.clone();
        s.count = self.count;
        if self.count > 0 {
            s.min = Some(self.min);
            s.max = Some(self.max);
        }
        s.err_sum = self.err_sum;
        s.err_sq_sum = self.err_sq_sum;
        s
    }
}
