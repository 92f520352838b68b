//! The fixed layered passes' buffers, kept between strips and layers
//! ([`super::fixed`]): a strip's input planes, window classes and line buffer, and one
//! row's horizontal and vertical sums.

use super::fast::{self, Plane, avx2_or_portable};
use super::fixed::Shares;
use super::layers::{DepthImage, LayerPlan};
use super::uniform;

/// The colour, alpha and behind planes of a row (or of rows).
type Planes<'a, P> = (&'a [P], &'a [P], &'a [P]);
/// The same, to write.
type PlanesMut<'a, P> = (&'a mut [P], &'a mut [P], &'a mut [P]);
/// A box's width and height.
type Dim = (usize, usize);
/// A rectangle `(x0, y0, width, height)`.
type Rect = (usize, usize, usize, usize);

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
        planes: Planes<P>,
        dim: (usize, usize),
        y: usize,
        class: &[u8],
    ) {
        let s = self;
        avx2_or_portable!(
            [P: Plane]
            (s: &mut RowSums, c: &[P], planes: Planes<P>, dim: Dim, y: usize, class: &[u8]) -> (),
            s.fill_in(c, planes, dim, y, class)
        )
    }

    #[inline(always)]
    fn fill_in<P: Plane>(
        &mut self,
        c: &[P],
        planes: Planes<P>,
        dim: (usize, usize),
        y: usize,
        class: &[u8],
    ) {
        for (_, xa, xb) in runs(class).filter(|r| r.0 == uniform::MIXED) {
            if self.is_wide {
                let o = &mut self.wide;
                fast::vsum_row(c, planes, dim, y, (xa, xb), (&mut o.0, &mut o.1, &mut o.2));
            } else {
                let o = &mut self.narrow;
                fast::vsum_row(c, planes, dim, y, (xa, xb), (&mut o.0, &mut o.1, &mut o.2));
            }
        }
    }

    /// The horizontal sums of one row (`planes`) at every position: a position whose row
    /// window (`class`) is [`uniform::FULL`] sums to its sample times the in-box tap sum of
    /// its column (`bsx`, no MACs), the others by their taps.
    pub(super) fn hfill<P: Plane>(
        &mut self,
        c: &[P],
        planes: Planes<P>,
        class: &[u8],
        bsx: &[u64],
    ) {
        let s = self;
        avx2_or_portable!(
            [P: Plane]
            (s: &mut RowSums, c: &[P], planes: Planes<P>, class: &[u8], bsx: &[u64]) -> (),
            s.hfill_in(c, planes, class, bsx)
        )
    }

    #[inline(always)]
    fn hfill_in<P: Plane>(&mut self, c: &[P], planes: Planes<P>, class: &[u8], bsx: &[u64]) {
        for (k, xa, xb) in runs(class) {
            let zero = k == uniform::ZERO;
            macro_rules! run {
                ($o:expr) => {{
                    let o = $o;
                    let out = (&mut o.0[..], &mut o.1[..], &mut o.2[..]);
                    if k == uniform::FULL {
                        fast::scale_run(planes, bsx, (xa, xb), out);
                    } else {
                        fast::hsum_run(c, planes, (xa, xb), zero, out);
                    }
                }};
            }
            if self.is_wide {
                run!(&mut self.wide)
            } else {
                run!(&mut self.narrow)
            }
        }
    }

    /// The row's sums into plane words: the colour saturated at `max`, alpha and behind as
    /// they are (they fit, docs/dof.md). Returns the colour sums above `max` and the largest
    /// colour or behind word written.
    pub(super) fn saturate<P: Plane>(&self, max: u128, out: PlanesMut<P>) -> (u64, u64) {
        let s = self;
        avx2_or_portable!(
            [P: Plane]
            (s: &RowSums, max: u128, out: PlanesMut<P>) -> (u64, u64),
            s.saturate_in(max, out)
        )
    }

    #[inline(always)]
    fn saturate_in<P: Plane>(&self, max: u128, (hx, ha, hd): PlanesMut<P>) -> (u64, u64) {
        let (mut over, mut top) = (0u64, 0u64);
        if self.is_wide {
            let (sx, sa, sd) = &self.wide;
            for x in 0..hx.len() {
                let v = sx[x].min(max) as u64;
                over += u64::from(sx[x] > max);
                (hx[x], ha[x], hd[x]) = (P::put(v), P::put(sa[x] as u64), P::put(sd[x] as u64));
                top = top.max(v).max(sd[x] as u64);
            }
        } else {
            // Narrow sums are below 2^64: so is the saturated colour.
            let max = max.min(u128::from(u64::MAX)) as u64;
            let (sx, sa, sd) = &self.narrow;
            let n = hx.len();
            let (sx, sa, sd) = (&sx[..n], &sa[..n], &sd[..n]);
            for x in 0..n {
                let v = sx[x].min(max);
                over += u64::from(sx[x] > max);
                (hx[x], ha[x], hd[x]) = (P::put(v), P::put(sa[x]), P::put(sd[x]));
                top = top.max(v).max(sd[x]);
            }
        }
        (over, top)
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

/// Every maximal run `(k, xa, xb)` of one class `k` in `class`, in order.
pub(super) fn runs(class: &[u8]) -> impl Iterator<Item = (u8, usize, usize)> + '_ {
    let mut x = 0;
    std::iter::from_fn(move || {
        let (&k, xa) = (class.get(x)?, x);
        x += run_len(&class[x..], k);
        Some((k, xa, x))
    })
}

/// How many bytes `s` starts with that equal `k`, eight at a time.
fn run_len(s: &[u8], k: u8) -> usize {
    let all = u64::from_ne_bytes([k; 8]);
    let mut chunks = s.chunks_exact(8);
    let mut n = 0;
    for c in chunks.by_ref() {
        let d = u64::from_le_bytes(c.try_into().expect("8 bytes")) ^ all;
        if d != 0 {
            return n + d.trailing_zeros() as usize / 8;
        }
        n += 8;
    }
    n + chunks.remainder().iter().take_while(|&&c| c == k).count()
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
    pub(super) fn input(&mut self, img: &DepthImage<u32>, plan: &LayerPlan, l: usize, r: Rect) {
        let s = self;
        avx2_or_portable!(
            [P: Plane]
            (s: &mut Scratch<P>, img: &DepthImage<u32>, plan: &LayerPlan, l: usize, r: Rect) -> (),
            s.input_in(img, plan, l, r)
        )
    }

    #[inline(always)]
    fn input_in(
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The runs cover the row in order, each maximal and of one class.
        #[test]
        fn runs_are_maximal(class in proptest::collection::vec(0u8..3, 0..40)) {
            let mut end = 0;
            for (k, xa, xb) in runs(&class) {
                prop_assert_eq!(xa, end);
                prop_assert!(xa < xb);
                prop_assert!(class[xa..xb].iter().all(|&c| c == k));
                prop_assert!(class.get(xb) != Some(&k));
                end = xb;
            }
            prop_assert_eq!(end, class.len());
        }

        /// The run-time (AVX2 where the CPU has it) and the portable builds of the row
        /// passes give the same sums, saturated words and counts.
        #[test]
        fn row_pass_builds_agree(
            row in proptest::collection::vec((0u32..1 << 20, 0u32..17, 0u32..17, 0u8..3), 1..48),
            m in 0usize..6,
            max in 0u128..1 << 40,
            wide in any::<bool>(),
        ) {
            let c: Vec<u32> = (0..=2 * m as u32).map(|t| 1 + t * 37 % 23).collect();
            let bw = row.len();
            let x: Vec<u32> = row.iter().map(|r| r.0).collect();
            let a: Vec<u32> = row.iter().map(|r| r.1).collect();
            let d: Vec<u32> = row.iter().map(|r| r.2).collect();
            let class: Vec<u8> = row.iter().map(|r| r.3).collect();
            let bsx: Vec<u64> = (0..bw).map(|i| 100 + i as u64).collect();
            let planes = (&x[..], &a[..], &d[..]);
            let run = |portable: bool| {
                let mut s = RowSums::default();
                s.reset(bw, wide);
                let (mut hx, mut ha, mut hd) = (vec![0u32; bw], vec![0u32; bw], vec![0u32; bw]);
                let counts = if portable {
                    s.hfill_in(&c, planes, &class, &bsx);
                    s.saturate_in(max, (&mut hx, &mut ha, &mut hd))
                } else {
                    s.hfill(&c, planes, &class, &bsx);
                    s.saturate(max, (&mut hx, &mut ha, &mut hd))
                };
                let sums: Vec<_> = (0..bw).map(|i| s.get(i)).collect();
                if portable {
                    s.fill_in(&c, planes, (bw, 1), 0, &class);
                } else {
                    s.fill(&c, planes, (bw, 1), 0, &class);
                }
                let vsums: Vec<_> = (0..bw).map(|i| s.get(i)).collect();
                (sums, counts, hx, ha, hd, vsums)
            };
            prop_assert_eq!(run(true), run(false));
        }
    }
}
