//! The fixed layered passes' buffers, kept between strips and layers
//! ([`super::fixed`]): a strip's input planes, window classes and line buffer, and one
//! row's horizontal and vertical sums.

use super::fast::{self, Plane};
use super::fixed::Shares;
use super::layers::{DepthImage, LayerPlan};
use super::uniform;

/// One row's exact tap sums (of the horizontal pass, or the vertical) over the positions
/// whose window needs them.
#[derive(Default)]
pub(super) struct RowSums {
    narrow: (Vec<u64>, Vec<u64>, Vec<u64>),
    wide: (Vec<u128>, Vec<u128>, Vec<u128>),
    is_wide: bool,
}

impl RowSums {
    /// Sums of `bw` columns, in `u128` words when `is_wide`.
    pub(super) fn reset(&mut self, bw: usize, is_wide: bool) {
        self.is_wide = is_wide;
        if is_wide {
            self.wide.0.resize(bw, 0);
            self.wide.1.resize(bw, 0);
            self.wide.2.resize(bw, 0);
        } else {
            self.narrow.0.resize(bw, 0);
            self.narrow.1.resize(bw, 0);
            self.narrow.2.resize(bw, 0);
        }
    }

    /// The vertical sums of row `y` at every run of columns whose window is
    /// [`uniform::MIXED`].
    pub(super) fn fill<P: Plane>(
        &mut self,
        c: &[P],
        planes: (&[P], &[P], &[P]),
        dim: (usize, usize),
        y: usize,
        class: &[u8],
    ) {
        for_runs(class, |k, xa, xb| {
            if k != uniform::MIXED {
                return;
            }
            if self.is_wide {
                let o = &mut self.wide;
                fast::vsum_row(c, planes, dim, y, (xa, xb), (&mut o.0, &mut o.1, &mut o.2));
            } else {
                let o = &mut self.narrow;
                fast::vsum_row(c, planes, dim, y, (xa, xb), (&mut o.0, &mut o.1, &mut o.2));
            }
        });
    }

    /// The horizontal sums of one row (`planes`) at every position whose row window
    /// (`class`) is not [`uniform::FULL`].
    pub(super) fn hfill<P: Plane>(&mut self, c: &[P], planes: (&[P], &[P], &[P]), class: &[u8]) {
        for_runs(class, |k, xa, xb| {
            if k == uniform::FULL {
                return;
            }
            let zero = k == uniform::ZERO;
            if self.is_wide {
                let o = &mut self.wide;
                fast::hsum_run(c, planes, (xa, xb), zero, (&mut o.0, &mut o.1, &mut o.2));
            } else {
                let o = &mut self.narrow;
                fast::hsum_run(c, planes, (xa, xb), zero, (&mut o.0, &mut o.1, &mut o.2));
            }
        });
    }

    pub(super) fn get(&self, x: usize) -> (u128, u128, u128) {
        if self.is_wide {
            (self.wide.0[x], self.wide.1[x], self.wide.2[x])
        } else {
            let n = &self.narrow;
            (n.0[x] as u128, n.1[x] as u128, n.2[x] as u128)
        }
    }
}

/// `f(k, xa, xb)` for every maximal run `xa..xb` of one class `k` in `class`, in one scan.
fn for_runs(class: &[u8], mut f: impl FnMut(u8, usize, usize)) {
    let mut x = 0;
    while x < class.len() {
        let (k, xa) = (class[x], x);
        while x < class.len() && class[x] == k {
            x += 1;
        }
        f(k, xa, x);
    }
}

/// A layer's planes over a strip of its box, kept between strips and layers (one
/// allocation for the largest): the input colour `x * m`, alpha `m`, behind share and value, the
/// share classes, the window classes, the line buffer and one row's horizontal and vertical
/// sums, in [`Plane`] words.
pub(super) struct Scratch<P> {
    pub xi: Vec<P>,
    pub ai: Vec<P>,
    pub di: Vec<P>,
    pub val: Vec<u32>,
    pub class: Vec<u8>,
    pub win: uniform::Windows,
    pub hx: Vec<P>,
    pub ha: Vec<P>,
    pub hd: Vec<P>,
    pub hrow: RowSums,
    pub rows: RowSums,
}

impl<P: Plane> Scratch<P> {
    pub(super) fn new() -> Self {
        Self {
            xi: Vec::new(),
            ai: Vec::new(),
            di: Vec::new(),
            val: Vec::new(),
            class: Vec::new(),
            win: uniform::Windows::default(),
            hx: Vec::new(),
            ha: Vec::new(),
            hd: Vec::new(),
            hrow: RowSums::default(),
            rows: RowSums::default(),
        }
    }

    /// Layer `l`'s input planes and share classes over the rectangle `(x0, y0, bw, bh)`.
    pub(super) fn input(
        &mut self,
        img: &DepthImage<u32>,
        plan: &LayerPlan,
        l: usize,
        (x0, y0, bw, bh): (usize, usize, usize, usize),
    ) {
        let n = bw * bh;
        self.xi.resize(n, P::default());
        self.ai.resize(n, P::default());
        self.di.resize(n, P::default());
        self.val.resize(n, 0);
        self.class.resize(n, uniform::MIXED);
        let shares = Shares::new(plan, l, img.n2);
        for (yy, y) in (y0..y0 + bh).enumerate() {
            let r = y * img.width + x0..y * img.width + x0 + bw;
            let (key, cov) = (&img.key[r.clone()], &img.cov[r.clone()]);
            let (idx, value) = (&plan.index[r.clone()], &img.value[r]);
            let o = yy * bw..(yy + 1) * bw;
            let (xi, ai) = (&mut self.xi[o.clone()], &mut self.ai[o.clone()]);
            let (di, val) = (&mut self.di[o.clone()], &mut self.val[o.clone()]);
            let class = &mut self.class[o];
            val.copy_from_slice(value);
            for x in 0..bw {
                let (s, d) = shares.of(key[x], cov[x], idx[x]);
                xi[x] = P::put(u64::from(value[x]) * u64::from(s));
                ai[x] = P::put(u64::from(s));
                di[x] = P::put(u64::from(d));
                class[x] = match s {
                    0 => uniform::ZERO,
                    s if s == img.n2 => uniform::FULL,
                    _ => uniform::MIXED,
                };
            }
        }
    }
}
