//! The per-pixel window kernel of the fixed model: the exact sums `sum w * I` of each
//! primitive over a pixel's filter window, in primitive-id order, without allocation.
//!
//! The window is `base x base` blocks of `n x n` samples. A block whose samples all belong
//! to one primitive (most blocks: a block crosses an edge only near it) is one dot product
//! added to that primitive's slot; a block that crosses an edge adds its samples one by one. The slots are kept in a fixed scratch
//! reused for every pixel of a row, and sorted by id at the end (they are few). The sums
//! are exact integers, so the order of the additions does not change them: the result is
//! the same as grouping every sample by primitive.

use super::kernel::Kernel;
use crate::fixed::SignalStats;

/// Scratch of one pixel's per-primitive sums (reused across pixels).
pub(super) struct WindowSums {
    /// `(primitive id, sum of w * I)`, sorted by id after [`WindowSums::sum`].
    pub frags: Vec<(u32, i64)>,
    /// Per `n x n` block of the kernel (row-major): whether any of its weights is non-zero
    /// (a primitive gets a fragment only from samples of non-zero weight).
    block_nz: Vec<bool>,
    /// The kernel's weights block by block (each block's `n x n` weights row-major).
    wb: Vec<u32>,
}

impl WindowSums {
    /// Scratch for kernel `k`.
    pub fn new(k: &Kernel) -> Self {
        let n = k.n as usize;
        let blocks = k.size / n;
        let mut wb = Vec::with_capacity(k.size * k.size);
        for b in 0..blocks * blocks {
            let (by, bx) = (b / blocks, b % blocks);
            for e in 0..n * n {
                wb.push(k.w[(by * n + e / n) * k.size + bx * n + e % n]);
            }
        }
        Self {
            frags: Vec::with_capacity(k.size * k.size),
            block_nz: block_nz(k),
            wb,
        }
    }

    /// The slot of primitive `id`, created with a zero sum when new.
    #[inline]
    fn slot(&mut self, id: u32, last: &mut usize) -> usize {
        if *last < self.frags.len() && self.frags[*last].0 == id {
            return *last;
        }
        let at = match self.frags.iter().position(|f| f.0 == id) {
            Some(x) => x,
            None => {
                self.frags.push((id, 0));
                self.frags.len() - 1
            }
        };
        *last = at;
        at
    }

    /// The ids of the `n x n` blocks of the windows of pixels `xa..xb` of one pixel row:
    /// `ids[by * cols + g]` is the primitive owning all samples of block row `by`, block
    /// column `g` (pixel `xa + g - bx` sees it as its block `bx`), or [`MIXED`] when the
    /// block crosses an edge. `base` is the buffer index of pixel `xa`'s window.
    pub fn block_ids(
        &self,
        prim: &[u32],
        k: &Kernel,
        base: usize,
        sw: usize,
        pixels: usize,
        ids: &mut Vec<u64>,
    ) {
        match k.n {
            1 => block_ids_n::<1>(prim, k, base, sw, pixels, ids),
            2 => block_ids_n::<2>(prim, k, base, sw, pixels, ids),
            4 => block_ids_n::<4>(prim, k, base, sw, pixels, ids),
            _ => block_ids_n::<8>(prim, k, base, sw, pixels, ids),
        }
    }

    /// Sums `w * I` per primitive over the window whose first sample is at buffer index
    /// `base` (row stride `sw`) into `self.frags`, sorted by primitive id: one entry per
    /// primitive with at least one sample of non-zero weight. `ids` are the block ids of
    /// [`WindowSums::block_ids`], `g` the pixel's offset in them and `cols` their columns.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub fn sum(
        &mut self,
        prim: &[u32],
        inten: &[u32],
        k: &Kernel,
        base: usize,
        sw: usize,
        ids: &[u64],
        g: usize,
        cols: usize,
    ) {
        match k.n {
            1 => self.sum_n::<1>(prim, inten, k, base, sw, ids, g, cols),
            2 => self.sum_n::<2>(prim, inten, k, base, sw, ids, g, cols),
            4 => self.sum_n::<4>(prim, inten, k, base, sw, ids, g, cols),
            _ => self.sum_n::<8>(prim, inten, k, base, sw, ids, g, cols),
        }
    }

    /// [`WindowSums::sum`] for `n = N` (`raster.samples` is 1, 2, 4 or 8).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn sum_n<const N: usize>(
        &mut self,
        prim: &[u32],
        inten: &[u32],
        k: &Kernel,
        base: usize,
        sw: usize,
        ids: &[u64],
        g: usize,
        cols: usize,
    ) {
        self.frags.clear();
        let size = k.size;
        let blocks = size / N;
        // One primitive owns the whole window (most pixels): one dot product.
        let first = ids[g];
        let uniform = first != MIXED
            && (0..blocks).all(|by| {
                ids[by * cols + g..by * cols + g + blocks]
                    .iter()
                    .all(|&b| b == first)
            });
        if uniform {
            let mut dot = 0u64;
            for j in 0..size {
                let row = base + j * sw;
                let is = &inten[row..row + size];
                let ws = &k.w[j * size..(j + 1) * size];
                dot += ws
                    .iter()
                    .zip(is)
                    .map(|(&w, &i)| w as u64 * i as u64)
                    .sum::<u64>();
            }
            self.frags.push((first as u32, dot as i64));
            return;
        }
        let mut last = usize::MAX;
        for by in 0..blocks {
            for bx in 0..blocks {
                let b = by * blocks + bx;
                let b0 = base + by * N * sw + bx * N;
                let ws: &[u32] = &self.wb[b * N * N..(b + 1) * N * N];
                let id = ids[by * cols + g + bx];
                if id != MIXED {
                    if self.block_nz[b] {
                        let mut dot = 0u64;
                        for sy in 0..N {
                            let row = b0 + sy * sw;
                            let is: &[u32; N] = inten[row..row + N].try_into().expect("N samples");
                            let wr: &[u32; N] =
                                ws[sy * N..sy * N + N].try_into().expect("N weights");
                            for t in 0..N {
                                dot += wr[t] as u64 * is[t] as u64;
                            }
                        }
                        let s = self.slot(id as u32, &mut last);
                        self.frags[s].1 += dot as i64;
                    }
                    continue;
                }
                // A block crossing an edge mostly holds two primitives: their sums in one
                // pass, a slot lookup per primitive, not per sample.
                if let Some(two) = two_primitives::<N>(prim, inten, ws, b0, sw) {
                    for (id, sum, nz) in two {
                        if nz {
                            let s = self.slot(id, &mut last);
                            self.frags[s].1 += sum as i64;
                        }
                    }
                    continue;
                }
                for sy in 0..N {
                    let row = b0 + sy * sw;
                    for t in 0..N {
                        let w = self.wb[b * N * N + sy * N + t];
                        if w != 0 {
                            let s = self.slot(prim[row + t], &mut last);
                            self.frags[s].1 += w as i64 * inten[row + t] as i64;
                        }
                    }
                }
            }
        }
        // Insertion sort: the slots are few and mostly in order already.
        for a in 1..self.frags.len() {
            let mut b = a;
            while b > 0 && self.frags[b - 1].0 > self.frags[b].0 {
                self.frags.swap(b - 1, b);
                b -= 1;
            }
        }
    }
}

/// The sums `w * I` of an `N x N` block (first sample at `b0`, weights `ws`) held by at most
/// two primitives: per primitive (id, sum, whether a sample of non-zero weight has it; only
/// those get a fragment); `None` when a third primitive appears.
#[inline(always)]
fn two_primitives<const N: usize>(
    prim: &[u32],
    inten: &[u32],
    ws: &[u32],
    b0: usize,
    sw: usize,
) -> Option<[(u32, u64, bool); 2]> {
    let first = prim[b0];
    let mut second: Option<u32> = None;
    let (mut s1, mut s2, mut nz1, mut nz2) = (0u64, 0u64, false, false);
    for sy in 0..N {
        let row = b0 + sy * sw;
        let ids: &[u32; N] = prim[row..row + N].try_into().expect("N samples");
        let is: &[u32; N] = inten[row..row + N].try_into().expect("N samples");
        let wr: &[u32; N] = ws[sy * N..sy * N + N].try_into().expect("N weights");
        for t in 0..N {
            let v = wr[t] as u64 * is[t] as u64;
            if ids[t] == first {
                s1 += v;
                nz1 |= wr[t] != 0;
            } else if second.is_none_or(|s| s == ids[t]) {
                second = Some(ids[t]);
                s2 += v;
                nz2 |= wr[t] != 0;
            } else {
                return None;
            }
        }
    }
    Some([(first, s1, nz1), (second.unwrap_or(first), s2, nz2)])
}

/// [`WindowSums::block_ids`] for `n = N`.
#[inline(always)]
fn block_ids_n<const N: usize>(
    prim: &[u32],
    k: &Kernel,
    base: usize,
    sw: usize,
    pixels: usize,
    ids: &mut Vec<u64>,
) {
    let blocks = k.size / N;
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

/// Whether each `n x n` block of the kernel (row-major) has a non-zero weight.
fn block_nz(k: &Kernel) -> Vec<bool> {
    let n = k.n as usize;
    let blocks = k.size / n;
    (0..blocks * blocks)
        .map(|b| {
            let (by, bx) = (b / blocks, b % blocks);
            (0..n * n).any(|e| k.w[(by * n + e / n) * k.size + bx * n + e % n] != 0)
        })
        .collect()
}

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
