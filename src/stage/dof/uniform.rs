//! Uniform mask windows of a layer (docs/dof.md, "Uniform windows"): where every pixel of a
//! pixel's `(2M+1)^2` window (clipped to the layer's box) has full share in the layer and the
//! same value, the normalised convolution gives that value exactly, so the emulator writes
//! it without the tap passes; and the 16x16 tiles made only of such pixels, which the
//! hardware option `dof.skip_uniform_tiles` skips.

/// Side of the tiles the hardware option skips (output pixels, aligned to the image grid).
pub const UNIFORM_TILE: usize = 16;

/// A layer's uniform windows over its box (row-major, `bw x bh`); the buffers are kept
/// between layers (one allocation for the largest box).
#[derive(Default)]
pub(super) struct Windows {
    /// The horizontal window `[x-M, x+M]` of the pixel's row is uniform.
    pub hu: Vec<bool>,
    /// The whole window is uniform (`hu` on every row of `[y-M, y+M]`, same value).
    pub u: Vec<bool>,
    left: Vec<u32>,
    top: Vec<u32>,
}

const NONE: u32 = u32::MAX;

impl Windows {
    /// The uniform windows of half-size `m` over a `bw x bh` box: `full[i]` says the
    /// pixel's share in the layer is full, `val[i]` is its value (compared for equality
    /// only).
    pub(super) fn compute<T: Copy + PartialEq>(
        &mut self,
        bw: usize,
        bh: usize,
        m: usize,
        full: &[bool],
        val: &[T],
    ) {
        let n = bw * bh;
        let reset = |v: &mut Vec<bool>| {
            v.clear();
            v.resize(n, false);
        };
        reset(&mut self.hu);
        reset(&mut self.u);
        if bw == 0 || bh == 0 {
            return;
        }
        let (hu, u) = (&mut self.hu, &mut self.u);
        // Per row: the start of the run of full pixels of one value holding each pixel.
        let left = &mut self.left;
        left.clear();
        left.resize(bw, NONE);
        for y in 0..bh {
            let (f, v) = (&full[y * bw..(y + 1) * bw], &val[y * bw..(y + 1) * bw]);
            for x in 0..bw {
                left[x] = if !f[x] {
                    NONE
                } else if x > 0 && f[x - 1] && v[x - 1] == v[x] {
                    left[x - 1]
                } else {
                    x as u32
                };
            }
            let row = &mut hu[y * bw..(y + 1) * bw];
            for (x, h) in row.iter_mut().enumerate() {
                let (xl, xr) = (x.saturating_sub(m), (x + m).min(bw - 1));
                *h = f[x] && left[xr] != NONE && left[xr] as usize <= xl;
            }
        }
        // Per column: the start of the run of `hu` pixels of one value holding each pixel.
        let top = &mut self.top;
        top.clear();
        top.resize(n, NONE);
        for y in 0..bh {
            for x in 0..bw {
                let i = y * bw + x;
                top[i] = if !hu[i] {
                    NONE
                } else if y > 0 && hu[i - bw] && val[i - bw] == val[i] {
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
                u[y * bw + x] = hu[y * bw + x] && t != NONE && t as usize <= yt;
            }
        }
    }
}

/// [`Windows::compute`] into new buffers.
pub(super) fn windows<T: Copy + PartialEq>(
    bw: usize,
    bh: usize,
    m: usize,
    full: &[bool],
    val: &[T],
) -> Windows {
    let mut w = Windows::default();
    w.compute(bw, bh, m, full, val);
    w
}

/// The 16x16 image tiles (clipped to the box `(x0, y0, bw, bh)`) whose every box pixel
/// satisfies `u`: their number and the box pixels they cover.
pub(super) fn skipped_tiles(
    u: &[bool],
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
            if (ya..yb).all(|y| u[y * bw + xa..y * bw + xb].iter().all(|&b| b)) {
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
