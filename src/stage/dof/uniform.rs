//! Uniform mask windows of a layer (docs/dof.md, "Uniform windows"): where every pixel of a
//! pixel's `(2M+1)^2` window (clipped to the layer's box) has full share in the layer and the
//! same value, the normalised convolution gives that value exactly, so the emulator writes
//! it without the tap passes; where every pixel of the window has no share in the layer, the
//! colour and alpha sums are zero and the pixel gets nothing from the layer; and the 16x16
//! tiles made only of full windows, which the hardware option `dof.skip_uniform_tiles` skips.

use super::fast::avx2_or_portable;

/// Side of the tiles the hardware option skips (output pixels, aligned to the image grid).
pub const UNIFORM_TILE: usize = 16;

/// A pixel's share class, and a window's: shares of both kinds, or a window mixing classes
/// (or values).
pub(super) const MIXED: u8 = 0;
/// Full share (and, for a window, one value throughout).
pub(super) const FULL: u8 = 1;
/// No share.
pub(super) const ZERO: u8 = 2;

/// A layer's window classes over its box (row-major, `bw x bh`); the buffers are kept
/// between layers (one allocation for the largest box).
#[derive(Default)]
pub(super) struct Windows {
    /// The class of the horizontal window `[x-M, x+M]` of the pixel's row.
    pub hu: Vec<u8>,
    /// The class of the whole window (`hu` of that class on every row of `[y-M, y+M]`, and
    /// for [`FULL`] the same value).
    pub u: Vec<u8>,
    top: Vec<u32>,
}

const NONE: u32 = u32::MAX;

/// A box's width and height, and the mask half-size.
type Dims = (usize, usize, usize);

impl Windows {
    /// The window classes of half-size `m` over a `bw x bh` box: `class[i]` is the pixel's
    /// ([`FULL`], [`ZERO`] or [`MIXED`] for a partial share), `val[i]` its value (compared
    /// for equality only, between full pixels).
    pub(super) fn compute<T: Copy + PartialEq>(
        &mut self,
        bw: usize,
        bh: usize,
        m: usize,
        class: &[u8],
        val: &[T],
    ) {
        let w = self;
        let dims = (bw, bh, m);
        avx2_or_portable!(
            [T: Copy + PartialEq]
            (w: &mut Windows, dims: Dims, class: &[u8], val: &[T]) -> (),
            w.compute_in(dims, class, val)
        )
    }

    #[inline(always)]
    fn compute_in<T: Copy + PartialEq>(&mut self, (bw, bh, m): Dims, class: &[u8], val: &[T]) {
        let n = bw * bh;
        // Every word of the three planes is written below.
        self.hu.resize(n, MIXED);
        self.u.resize(n, MIXED);
        self.top.resize(n, NONE);
        if bw == 0 || bh == 0 {
            return;
        }
        let (hu, u, top) = (&mut self.hu, &mut self.u, &mut self.top);
        // Per row, per run of joined pixels `[a, b)` (one class, not mixed, and for full one
        // value): the pixels whose clipped window `[x-M, x+M]` lies in the run.
        for ((row, c), v) in hu
            .chunks_exact_mut(bw)
            .zip(class.chunks_exact(bw))
            .zip(val.chunks_exact(bw))
        {
            row.fill(MIXED);
            let mut a = 0;
            while a < bw {
                let k = c[a];
                let mut b = a + 1;
                while b < bw && c[b] == k && (k == ZERO || k == MIXED || v[b] == v[b - 1]) {
                    b += 1;
                }
                if k != MIXED {
                    let lo = if a == 0 { 0 } else { a + m };
                    let hi = if b == bw { bw } else { b.saturating_sub(m) };
                    if lo < hi {
                        row[lo..hi].fill(k);
                    }
                }
                a = b;
            }
        }
        // Per column: the start of the run of `hu` windows holding each pixel (the same
        // joins), row after row.
        for (x, t) in top[..bw].iter_mut().enumerate() {
            *t = if hu[x] == MIXED { NONE } else { 0 };
        }
        for y in 1..bh {
            let (o, p) = (y * bw, (y - 1) * bw);
            let (above, here) = top.split_at_mut(o);
            let (above, here) = (&above[p..], &mut here[..bw]);
            let (hp, hc) = (&hu[p..o], &hu[o..o + bw]);
            let (vp, vc) = (&val[p..o], &val[o..o + bw]);
            for x in 0..bw {
                let joins = hc[x] == hp[x] && (hc[x] == ZERO || vc[x] == vp[x]);
                here[x] = match (hc[x], joins) {
                    (MIXED, _) => NONE,
                    (_, true) => above[x],
                    _ => y as u32,
                };
            }
        }
        // A window is uniform where the run holding its bottom row starts at its top row
        // or above (`NONE` never does).
        for y in 0..bh {
            let (yt, yb) = (y.saturating_sub(m) as u32, (y + m).min(bh - 1));
            let t = &top[yb * bw..(yb + 1) * bw];
            let (h, u) = (&hu[y * bw..(y + 1) * bw], &mut u[y * bw..(y + 1) * bw]);
            for x in 0..bw {
                u[x] = if t[x] <= yt { h[x] } else { MIXED };
            }
        }
    }
}

/// [`Windows::compute`] into new buffers.
pub(super) fn windows<T: Copy + PartialEq>(
    bw: usize,
    bh: usize,
    m: usize,
    class: &[u8],
    val: &[T],
) -> Windows {
    let mut w = Windows::default();
    w.compute(bw, bh, m, class, val);
    w
}

/// The 16x16 image tiles (clipped to the box `(x0, y0, bw, bh)`) whose every box pixel
/// has a [`FULL`] window in `u`: their number and the box pixels they cover.
pub(super) fn skipped_tiles(
    u: &[u8],
    (x0, y0, bw, bh): (usize, usize, usize, usize),
) -> (u64, Vec<bool>) {
    let t = UNIFORM_TILE;
    let mut mask = vec![false; bw * bh];
    let mut tiles = 0u64;
    let mut ty = y0 / t * t;
    while ty < y0 + bh {
        let (ya, yb) = (ty.max(y0) - y0, (ty + t).min(y0 + bh) - y0);
        let mut tx = x0 / t * t;
        while tx < x0 + bw {
            let (xa, xb) = (tx.max(x0) - x0, (tx + t).min(x0 + bw) - x0);
            if (ya..yb).all(|y| u[y * bw + xa..y * bw + xb].iter().all(|&b| b == FULL)) {
                tiles += 1;
                for y in ya..yb {
                    mask[y * bw + xa..y * bw + xb].fill(true);
                }
            }
            tx += t;
        }
        ty += t;
    }
    (tiles, mask)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A window's class by its definition: every pixel of the clipped window of one class,
    /// not mixed, and for full one value.
    fn brute(
        bw: usize,
        bh: usize,
        m: usize,
        class: &[u8],
        val: &[u8],
        x: usize,
        y: usize,
    ) -> [u8; 2] {
        let of = |ys: std::ops::RangeInclusive<usize>| {
            let xs = x.saturating_sub(m)..=(x + m).min(bw - 1);
            let i = y * bw + x;
            let same = ys
                .flat_map(|yy| xs.clone().map(move |xx| yy * bw + xx))
                .all(|j| class[j] == class[i] && (class[i] == ZERO || val[j] == val[i]));
            if same { class[i] } else { MIXED }
        };
        [of(y..=y), of(y.saturating_sub(m)..=(y + m).min(bh - 1))]
    }

    proptest! {
        /// The run starts give every window's class by its definition.
        #[test]
        fn classes_match_the_definition(
            (bw, bh, cells) in (1usize..12, 1usize..12).prop_flat_map(|(w, h)| {
                (Just(w), Just(h), proptest::collection::vec((0u8..3, 0u8..2), w * h))
            }),
            m in 0usize..4,
        ) {
            let (class, val): (Vec<u8>, Vec<u8>) = cells.into_iter().unzip();
            let win = windows(bw, bh, m, &class, &val);
            for y in 0..bh {
                for x in 0..bw {
                    let i = y * bw + x;
                    prop_assert_eq!([win.hu[i], win.u[i]], brute(bw, bh, m, &class, &val, x, y));
                }
            }
        }
    }

    /// Zero windows beside full ones: a zero pixel's window is zero only where no full
    /// pixel lies within `M`, whatever the full pixels' values.
    #[test]
    fn zero_and_full_windows_side_by_side() {
        let class = [ZERO, ZERO, ZERO, FULL, FULL, FULL];
        let win = windows(6, 1, 1, &class, &[7, 8, 9, 1, 1, 1]);
        assert_eq!(win.hu, [ZERO, ZERO, MIXED, MIXED, FULL, FULL]);
        assert_eq!(win.u, win.hu);
    }
}
