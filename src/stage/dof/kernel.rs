//! The mask shape of a blur radius (`dof.kernel`, docs/dof.md "Kernel shape"): the
//! separable Gaussians' sigma, every kernel's half-size and difference degree, and the
//! lens's disc as a 2-D mask of pixel-area weights, quantised with the equal-energy
//! property (the weights sum exactly to `2^(2 coef_bits)`, the scale of a separable pair).

use super::mask::{MaskDifferences, half_size, taps_f64};
use crate::config::DofKernel;
use std::collections::HashMap;

/// `fitted_gaussian`: the 1/e radius of the Gaussian, as a fraction of the disc radius,
/// whose edge profile differs least (at most, over the edge) from the disc's: 2.94 % of
/// the step at 0.743 (the paper's Gaussian, 1.0, differs by 8 %; docs/dof.md).
pub const FITTED_SCALE: f64 = 0.743;

/// The sigma of the Gaussian that stands for a kernel of blur radius `sigma`: itself for
/// `gaussian`, the fitted `FITTED_SCALE sigma` for `fitted_gaussian` and `disc` (the
/// downsample method's separable copy with `disc`; the layered method filters the disc
/// itself).
pub fn gaussian_sigma(kernel: DofKernel, sigma: f64) -> f64 {
    match kernel {
        DofKernel::FittedGaussian | DofKernel::Disc => FITTED_SCALE * sigma,
        DofKernel::Gaussian => sigma,
    }
}

/// Half-size M of the mask of blur radius `sigma` (pixels): the Gaussians' cut at `k`, or
/// the disc's reach (the pixels it overlaps: `|x| - 1/2 < |sigma|`).
pub fn kernel_half_size(kernel: DofKernel, sigma: f64, k: f64) -> usize {
    match kernel {
        DofKernel::Disc => disc_half_size(sigma),
        _ => half_size(gaussian_sigma(kernel, sigma), k),
    }
}

/// Half-size of the disc of radius `|r|`: `ceil(|r| - 1/2)`, 0 while the disc stays inside
/// its own pixel.
pub fn disc_half_size(r: f64) -> usize {
    (r.abs() - 0.5 - 1e-9).ceil().max(0.0) as usize
}

/// The disc's area over `[x0, x1] x [y0, y1]` (radius `r`, centred at the origin):
/// composite Simpson over x of the chord's overlap with `[y0, y1]` (64 intervals).
fn disc_area(r: f64, (x0, x1): (f64, f64), (y0, y1): (f64, f64)) -> f64 {
    let chord = |x: f64| {
        let h = (r * r - x * x).max(0.0).sqrt();
        (y1.min(h) - y0.max(-h)).max(0.0)
    };
    let (a, b) = (x0.max(-r), x1.min(r));
    if b <= a {
        return 0.0;
    }
    let n = 64;
    let step = (b - a) / n as f64;
    let mut s = chord(a) + chord(b);
    for i in 1..n {
        s += chord(a + i as f64 * step) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * step / 3.0
}

/// A 2-D mask: `(2M + 1)^2` weights, row-major, centre at `(M, M)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Mask2 {
    /// Half-size M.
    pub m: usize,
    /// Quantised weights (`UQ0.<2 coef_bits>`, sum `2^(2 coef_bits)`).
    pub w: Vec<u64>,
    /// Float weights (sum 1).
    pub wf: Vec<f64>,
}

impl Mask2 {
    /// The disc of radius `|r|` with `bits` fraction bits.
    pub fn disc(r: f64, bits: u32) -> Self {
        let wf = disc_f64(r);
        let w = weights_fixed(&wf, bits);
        let m = disc_half_size(r);
        Self { m, w, wf }
    }

    /// Taps per side, `2M + 1`.
    pub fn side(&self) -> usize {
        2 * self.m + 1
    }

    /// Non-zero quantised weights (the multipliers of a direct 2-D filter).
    pub fn nonzero(&self) -> usize {
        self.w.iter().filter(|&&v| v != 0).count()
    }
}

/// The disc of radius `|r|` as pixel-area weights over `(2M + 1)^2` pixels, sum 1 (`[1]`
/// for a disc inside its pixel).
pub fn disc_f64(r: f64) -> Vec<f64> {
    let r = r.abs();
    let m = disc_half_size(r) as i64;
    if m == 0 {
        return vec![1.0];
    }
    let span = |i: i64| (i as f64 - 0.5, i as f64 + 0.5);
    let mut v: Vec<f64> = (-m..=m)
        .flat_map(|y| (-m..=m).map(move |x| (x, y)))
        // Both integration orders averaged: the mask is symmetric in x and y exactly.
        .map(|(x, y)| 0.5 * (disc_area(r, span(x), span(y)) + disc_area(r, span(y), span(x))))
        .collect();
    let sum: f64 = v.iter().sum();
    v.iter_mut().for_each(|a| *a /= sum);
    v
}

/// 2-D weights (sum 1, odd square side) quantised to `bits` fraction bits with their sum
/// exactly `2^bits`: floors, then the largest remainders get one more, ties to the tap
/// nearest the centre, then in raster order.
pub fn weights_fixed(wf: &[f64], bits: u32) -> Vec<u64> {
    let n = (wf.len() as f64).sqrt().round() as usize;
    let m = (n / 2) as i64;
    let one = (1u64 << bits) as f64;
    let mut w: Vec<u64> = wf.iter().map(|&v| (v * one).floor() as u64).collect();
    let mut left = (1u64 << bits).saturating_sub(w.iter().sum());
    let r2 = |i: usize| {
        let (x, y) = ((i % n) as i64 - m, (i / n) as i64 - m);
        x * x + y * y
    };
    let rem = |i: usize| wf[i] * one - w[i] as f64;
    let mut order: Vec<usize> = (0..wf.len()).collect();
    order.sort_by(|&a, &b| {
        rem(b)
            .total_cmp(&rem(a))
            .then(r2(a).cmp(&r2(b)))
            .then(a.cmp(&b))
    });
    for i in order {
        if left == 0 {
            break;
        }
        w[i] += 1;
        left -= 1;
    }
    w
}

/// Difference degree of two 2-D masks (centred, zero outside their own support).
fn mask2_difference(a: &[f64], b: &[f64]) -> f64 {
    let side = |v: &[f64]| (v.len() as f64).sqrt().round() as usize;
    let (na, nb) = (side(a), side(b));
    let n = na.max(nb);
    let get = |v: &[f64], nv: usize, x: usize, y: usize| {
        let o = (n - nv) / 2;
        if x < o || y < o || x >= o + nv || y >= o + nv {
            0.0
        } else {
            v[(y - o) * nv + x - o]
        }
    };
    let mut d = 0.0;
    for y in 0..n {
        for x in 0..n {
            d += (get(a, na, x, y) - get(b, nb, x, y)).abs();
        }
    }
    d / 2.0
}

/// The layer plan's difference degree of two blur radii's masks for a kernel, remembered
/// (the plan asks for the same few sigmas once per depth code pair).
pub(super) struct KernelDifferences {
    kernel: DofKernel,
    gauss: MaskDifferences,
    discs: HashMap<u64, std::rc::Rc<Vec<f64>>>,
    diff: HashMap<(u64, u64), f64>,
}

impl KernelDifferences {
    pub(super) fn new(kernel: DofKernel) -> Self {
        Self {
            kernel,
            gauss: MaskDifferences::default(),
            discs: HashMap::new(),
            diff: HashMap::new(),
        }
    }

    /// The difference degree of the masks of `s1` and `s2` (`k` the same on every call).
    pub(super) fn get(&mut self, s1: f64, s2: f64, k: f64) -> f64 {
        if self.kernel != DofKernel::Disc {
            let g = |s| gaussian_sigma(self.kernel, s);
            return self.gauss.get(g(s1), g(s2), k);
        }
        let key = (s1.abs().to_bits(), s2.abs().to_bits());
        if let Some(&d) = self.diff.get(&key) {
            return d;
        }
        let mut disc = |s: f64| {
            self.discs
                .entry(s.abs().to_bits())
                .or_insert_with(|| std::rc::Rc::new(disc_f64(s)))
                .clone()
        };
        let (a, b) = (disc(s1), disc(s2));
        let d = mask2_difference(&a, &b);
        self.diff.insert(key, d);
        d
    }
}

/// The separable taps of a Gaussian kernel (unused for the disc: `[1]`).
pub fn kernel_taps_f64(kernel: DofKernel, sigma: f64, k: f64) -> Vec<f64> {
    match kernel {
        DofKernel::Disc => vec![1.0],
        _ => taps_f64(gaussian_sigma(kernel, sigma), k),
    }
}
