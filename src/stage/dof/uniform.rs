//! Uniform mask windows of a layer (docs/dof.md, "Uniform windows"): where every pixel of a
//! pixel's `(2M+1)^2` window (clipped to the layer's box) has full share in the layer and the
//! same value, the normalised convolution gives that value exactly, so the emulator writes
//! it without the tap passes; where every pixel of the window has no share in the layer, the
//! colour and alpha sums are zero and the pixel gets nothing from the layer; and the 16x16
//! tiles made only of full windows, which the hardware option `dof.skip_uniform_tiles` skips.

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
    left: Vec<u32>,
    top: Vec<u32>,
}

const NONE: u32 = u32::MAX;

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
        let n = bw * bh;
        let reset = |v: &mut Vec<u8>| {
            v.clear();
            v.resize(n, MIXED);
        };
        reset(&mut self.hu);
        reset(&mut self.u);
        if bw == 0 || bh == 0 {
            return;
        }
        let (hu, u) = (&mut self.hu, &mut self.u);
        // Two neighbours continue a run: one class, not mixed, and for full one value.
        let joins = |c: u8, d: u8, i: usize, j: usize| c == d && (c == ZERO || val[i] == val[j]);
        // Per row: the start of the run holding each pixel.
        let left = &mut self.left;
        left.clear();
        left.resize(bw, NONE);
        for y in 0..bh {
            let (o, c) = (y * bw, &class[y * bw..(y + 1) * bw]);
            for x in 0..bw {
                left[x] = if c[x] == MIXED {
                    NONE
                } else if x > 0 && joins(c[x - 1], c[x], o + x - 1, o + x) {
                    left[x - 1]
                } else {
                    x as u32
                };
            }
            let row = &mut hu[o..o + bw];
            for (x, h) in row.iter_mut().enumerate() {
                let (xl, xr) = (x.saturating_sub(m), (x + m).min(bw - 1));
                if left[xr] != NONE && left[xr] as usize <= xl {
                    *h = c[x];
                }
            }
        }
        // Per column: the start of the run of `hu` windows holding each pixel.
        let top = &mut self.top;
        top.clear();
        top.resize(n, NONE);
        for y in 0..bh {
            for x in 0..bw {
                let i = y * bw + x;
                top[i] = if hu[i] == MIXED {
                    NONE
                } else if y > 0 && joins(hu[i - bw], hu[i], i - bw, i) {
                    top[i - bw]
                } else {
                    y as u32
                };
            }
        }
        for y in 0..bh {
            let (yt, yb) = (y.saturating_sub(m), (y + m).min(bh - 1));
            for x in 0..bw {
                let t = top[yb * bw + x];
                if t != NONE && t as usize <= yt {
                    u[y * bw + x] = hu[y * bw + x];
                }
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
