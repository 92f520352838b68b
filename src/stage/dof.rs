//! Depth of field: layered adaptive convolution of the depth image (REFERENCE §2, §3).
//!
//! **Blur per pixel.** With the thin lens (lens radius R, focus distance U) the blur of a
//! point at view depth D is `sigma = R V0 (1/U - 1/D)` on the image plane (REFERENCE §2a,
//! `V0 = F U / (U - F)`). The image plane `V0` behind the lens spans `2 V0 tan(fov/2)` units
//! over the image height H, so in pixels `sigma_px = K (1/U - 1/D)` with
//! `K = R H / (2 tan(fov/2))`: V0 and F cancel, and the scene's length unit is the unit of
//! R and U. Screen z is affine in 1/D (`1/D = 1/near - z (1/near - 1/far)`), so sigma is
//! affine in the pixel's depth code: `sigma = G (z - z_e)` with `G = K (1/near - 1/far)`;
//! one multiplier per pixel. The in-focus band `[U - deep, U + deep]` has sigma = 0; outside
//! it the depth is shifted to the band's edge *in inverse depth* (`z_e` is the screen z of
//! `U + deep` behind the band and of `U - deep` in front of it), which keeps sigma
//! continuous and affine in z. The circle of confusion (REFERENCE §2b) of the same lens is
//! `C = F^2/(U - F) |L - U| / (N L)` = `2 |sigma|` before the band, in the same units.
//!
//! **Mask.** The paper's Gaussian is read as `exp(-(x^2 + y^2) / sigma^2)`, the form for which
//! its cut rule (edge/centre = k) gives exactly `M = ceil(sqrt(-ln k) |sigma|)` (1.731 sigma
//! for k = 0.05). The 1-D taps are quantised to `coef_bits` fraction bits by largest
//! remainder so they sum to exactly `2^f`: the separable 2-D mask sums to `2^2f`, DC gain 1.
//!
//! **Layers.** The distinct depth codes are sorted far to near; a layer grows from its
//! farthest code while the difference degree `S(A, B) = sum|A - B| / sum(|A| + |B|)`
//! between the 2-D masks of its ends, and between each end and the mask of the layer's
//! middle depth (and sigma = 0 when the layer straddles the focus) stays below P. Each layer
//! is convolved with the mask of its middle depth.
//!
//! **Fixed-point datapath** (per layer, only over the layer's bounding box plus M):
//! * input planes: premultiplied intensity `x * m` and alpha `m`, with `m` the pixel's
//!   coverage in `1/n^2` units; the uncovered share `n^2 - coverage` of every pixel goes to
//!   the background layer (the farthest layer, depth "infinity"), so the shares sum to the
//!   pixel's value exactly;
//! * horizontal pass into the line buffer and vertical pass into the accumulator, exact
//!   integer sums (`line_bits`, `acc_bits` wide; a sum that does not fit is saturated and
//!   counted, or stops the run with overflow mode ERROR);
//! * the layer's colour `C = round(F 2^g / A)` (normalised convolution: one divide per
//!   pixel, renormalises image borders and holes left by nearer layers alike);
//! * its alpha `a = round(A 2^q / (n^2 Wx Wy))` with `Wx Wy` the in-image tap sum (border
//!   renormalisation), `q = alpha_bits`;
//! * back-to-front "over": `out = round((C a + out (2^q - a)) / 2^q)`, i.e.
//!   `f = f_front + f_back (1 - a_front)` with the back already opaque; the farthest layer
//!   covering a pixel initialises it. A flat field of any code is therefore bit-identical
//!   at any depths, and a sigma = 0 layer passes its pixels through untouched.
//! * the result is rounded (`quant`) to the frame format and saturated to full white.
//!
//! **Float references.** (1) [`layered_f64`]: the same layers and masks (untruncated
//! coefficients), f64. (2) [`per_pixel_scatter`]: every source pixel spreads its value with
//! the mask of its own depth, restricted to the image and renormalised (energy preserving),
//! summed; cost `O(N^2 M^2)`. [`additive_layered`] is the theorem's form: every pixel
//! spread with its layer's middle mask, summed, no compositing.

use super::{Cost, LocalError, Unit};
use crate::config::{DofCfg, MAX_HALF_SIZE_LIMIT};
use crate::fixed::{Overflow, QFormat, Quant, SignalStats, round_shift};
use crate::scene::{Camera, Lens, screen_z};
use serde::Serialize;

/// Fraction bits of the per-pixel sigma code (pixels): `sigma = code * 2^-8`.
pub const SIGMA_FRAC: u32 = 8;
/// Fraction bits of the slope constant G (pixels per unit of screen z).
pub const G_FRAC: u32 = 16;

/// The thin-lens blur as a function of the depth code: `sigma = G (z - z_e)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LensMap {
    /// Pixels of sigma per unit of screen z.
    pub g: f64,
    /// Screen z of the far edge of the in-focus band.
    pub z_far_edge: f64,
    /// Screen z of the near edge of the in-focus band.
    pub z_near_edge: f64,
    /// Screen z of infinity (the background), `> 1`.
    pub z_inf: f64,
    /// Fraction bits of the depth codes (`u32::MAX` = background).
    pub z_frac: u32,
    /// Permissible circle of confusion in pixels (REFERENCE §2b), for the in-focus count.
    pub coc_px: f64,
}

impl LensMap {
    /// From a thin-lens camera and the image height; `None` for a pinhole camera.
    pub fn from_camera(cam: &Camera, height: u32, z_frac: u32) -> Option<Self> {
        let Lens::ThinLens {
            focal_length,
            lens_radius,
            focus_distance,
            deep,
            coc,
        } = cam.lens
        else {
            return None;
        };
        let tan = (cam.fov_y_deg.to_radians() / 2.0).tan();
        let k = lens_radius * height as f64 / (2.0 * tan);
        let g = k * (1.0 / cam.near - 1.0 / cam.far);
        let v0 = focal_length * focus_distance / (focus_distance - focal_length);
        Some(Self {
            g,
            z_far_edge: screen_z(cam, focus_distance + deep),
            z_near_edge: screen_z(cam, (focus_distance - deep).max(cam.near)).max(0.0),
            z_inf: 1.0 / (1.0 - cam.near / cam.far),
            z_frac,
            coc_px: coc * height as f64 / (2.0 * v0 * tan),
        })
    }

    /// Screen z of a depth code.
    pub fn z_of(&self, key: u32) -> f64 {
        if key == u32::MAX {
            self.z_inf
        } else {
            key as f64 / (1u64 << self.z_frac) as f64
        }
    }

    /// Exact sigma (pixels, signed: negative in front of the focus) at screen z.
    pub fn sigma_z(&self, z: f64) -> f64 {
        if z > self.z_far_edge {
            self.g * (z - self.z_far_edge)
        } else if z < self.z_near_edge {
            self.g * (z - self.z_near_edge)
        } else {
            0.0
        }
    }

    /// Exact sigma of a depth code.
    pub fn sigma_f64(&self, key: u32) -> f64 {
        self.sigma_z(self.z_of(key))
    }

    /// Circle of confusion in pixels at a depth code, without the in-focus band: `2 |sigma|`.
    pub fn coc_f64(&self, key: u32) -> f64 {
        2.0 * self.g * (self.z_of(key) - (self.z_far_edge + self.z_near_edge) / 2.0).abs()
    }

    fn code(&self, z: f64) -> i64 {
        (z * (1u64 << self.z_frac) as f64).round() as i64
    }

    /// Fixed-point sigma code (`SIGMA_FRAC` fraction bits): one `z x G` multiply and a
    /// round-to-nearest shift, with the constants quantised once.
    pub fn sigma_code(&self, key: u32) -> i64 {
        let z = if key == u32::MAX {
            self.code(self.z_inf)
        } else {
            key as i64
        };
        let (zf, zn) = (self.code(self.z_far_edge), self.code(self.z_near_edge));
        let d = if z > zf {
            z - zf
        } else if z < zn {
            z - zn
        } else {
            return 0;
        };
        let g = (self.g * (1u64 << G_FRAC) as f64).round() as i128;
        round_shift(d as i128 * g, self.z_frac + G_FRAC - SIGMA_FRAC, Quant::Rnd) as i64
    }

    /// Width of the G constant in bits (integer + `G_FRAC`).
    pub fn g_bits(&self) -> u32 {
        (self.g.max(1.0).log2().floor() as u32 + 1) + G_FRAC
    }
}

/// Half-size M of the mask for |sigma| (pixels): `ceil(sqrt(-ln k) |sigma|)`.
pub fn half_size(sigma: f64, k: f64) -> usize {
    ((-k.ln()).sqrt() * sigma.abs() - 1e-9).ceil().max(0.0) as usize
}

/// Normalised 1-D taps `exp(-x^2 / sigma^2)`, `|x| <= M` (sum 1); `[1]` for sigma = 0.
pub fn taps_f64(sigma: f64, k: f64) -> Vec<f64> {
    let m = half_size(sigma, k);
    if m == 0 {
        return vec![1.0];
    }
    let s2 = sigma * sigma;
    let t: Vec<f64> = (-(m as i64)..=m as i64)
        .map(|x| (-(x * x) as f64 / s2).exp())
        .collect();
    let sum: f64 = t.iter().sum();
    t.into_iter().map(|v| v / sum).collect()
}

/// Taps quantised to `f` fraction bits with their sum exactly `2^f` (largest remainder,
/// ties to the centre-most tap: symmetric masks stay symmetric when the leftover is even).
pub fn taps_fixed(tf: &[f64], f: u32) -> Vec<u64> {
    let one = (1u64 << f) as f64;
    let mut fl: Vec<(usize, u64, f64)> = tf
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            let s = v * one;
            (i, s.floor() as u64, s - s.floor())
        })
        .collect();
    let sum: u64 = fl.iter().map(|x| x.1).sum();
    let mut left = (1u64 << f).saturating_sub(sum);
    let c = tf.len() / 2;
    let mut order: Vec<usize> = (0..fl.len()).collect();
    order.sort_by(|&a, &b| {
        fl[b]
            .2
            .partial_cmp(&fl[a].2)
            .unwrap_or(std::cmp::Ordering::Equal)
            .then(a.abs_diff(c).cmp(&b.abs_diff(c)))
            .then(a.cmp(&b))
    });
    for i in order {
        if left == 0 {
            break;
        }
        fl[i].1 += 1;
        left -= 1;
    }
    fl.into_iter().map(|x| x.1).collect()
}

/// Difference degree of the 2-D separable masks of two sigmas (REFERENCE §3, eq. 6).
pub fn mask_difference(s1: f64, s2: f64, k: f64) -> f64 {
    let (a, b) = (taps_f64(s1, k), taps_f64(s2, k));
    let m = a.len().max(b.len()) / 2;
    let get = |t: &[f64], i: usize| {
        let h = t.len() / 2;
        let off = i as i64 - m as i64 + h as i64;
        if off < 0 || off >= t.len() as i64 {
            0.0
        } else {
            t[off as usize]
        }
    };
    let n = 2 * m + 1;
    let mut d = 0.0;
    for y in 0..n {
        let (ay, by) = (get(&a, y), get(&b, y));
        for x in 0..n {
            d += (ay * get(&a, x) - by * get(&b, x)).abs();
        }
    }
    d / 2.0
}

/// Difference degree of two images, `sum|A - B| / sum(|A| + |B|)`.
pub fn difference_degree(a: &[f64], b: &[f64]) -> f64 {
    let (mut d, mut s) = (0.0, 0.0);
    for (&x, &y) in a.iter().zip(b) {
        d += (x - y).abs();
        s += x.abs() + y.abs();
    }
    if s == 0.0 { 0.0 } else { d / s }
}

/// One depth layer.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Layer {
    /// Farthest depth code in the layer (`u32::MAX` = background).
    pub key_far: u32,
    /// Nearest depth code in the layer.
    pub key_near: u32,
    /// Screen z range (near, far).
    pub z_range: (f64, f64),
    /// Screen z of the middle depth.
    pub z_mid: f64,
    /// Sigma of the middle depth (pixels, from its fixed code).
    pub sigma: f64,
    /// Mask half-size.
    pub m: usize,
    /// Pixels whose depth falls in the layer.
    pub pixels: u64,
    /// Quantised 1-D taps (sum `2^coef_bits`).
    #[serde(skip)]
    pub coef: Vec<u64>,
    /// Float 1-D taps (sum 1).
    #[serde(skip)]
    pub coef_f: Vec<f64>,
}

/// A depth image: values, depth codes (`u32::MAX` = background), coverage of `n2` samples.
#[derive(Clone, Copy, Debug)]
pub struct DepthImage<'a, T> {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// Values (frame codes or frame LSBs), row-major.
    pub value: &'a [T],
    /// Depth codes.
    pub key: &'a [u32],
    /// Covered samples per pixel.
    pub cov: &'a [u16],
    /// Samples per pixel.
    pub n2: u32,
}

impl<'a, T> DepthImage<'a, T> {
    /// The frame memory's depth and coverage with `value` (fixed frame codes, or the same
    /// frame as reals) as the values.
    pub fn of_frame(frame: &'a super::accumulate::Frame, value: &'a [T], n2: u32) -> Self {
        Self {
            width: frame.width as usize,
            height: frame.height as usize,
            value,
            key: &frame.depth,
            cov: &frame.coverage,
            n2,
        }
    }
}

/// The layer plan: layers far to near and each pixel's layer.
#[derive(Clone, Debug)]
pub struct LayerPlan {
    /// Layers, far to near.
    pub layers: Vec<Layer>,
    /// Layer index of each pixel.
    pub index: Vec<u16>,
    /// Index of the layer holding the background (uncovered shares), if any.
    pub background: Option<usize>,
}

/// Grows the layers far to near (see the module notes). Errors name the limit exceeded.
pub fn plan_layers(
    key: &[u32],
    cov: &[u16],
    n2: u32,
    lens: &LensMap,
    p: &DofCfg,
) -> Result<LayerPlan, String> {
    let mut keys: Vec<u32> = key.to_vec();
    if cov.iter().any(|&c| (c as u32) < n2) {
        keys.push(u32::MAX);
    }
    keys.sort_unstable_by(|a, b| b.cmp(a));
    keys.dedup();
    let sig = |k: u32| lens.sigma_code(k) as f64 / (1u64 << SIGMA_FRAC) as f64;
    let mid_sigma = |far: u32, near: u32| {
        let zm = (lens.z_of(far) + lens.z_of(near)) / 2.0;
        // The middle depth as a code (the background's z_inf is exact): sigma from its code.
        let code = (zm * (1u64 << lens.z_frac) as f64).round();
        let c = if code >= u32::MAX as f64 {
            u32::MAX
        } else {
            code as u32
        };
        (zm, sig(c))
    };
    let mut layers: Vec<Layer> = Vec::new();
    let mut i = 0;
    while i < keys.len() {
        let far = keys[i];
        let s_far = sig(far);
        let mut j = i;
        while j + 1 < keys.len() {
            let near = keys[j + 1];
            let s_near = sig(near);
            let (_, s_mid) = mid_sigma(far, near);
            let mut ok = mask_difference(s_far, s_near, p.k) < p.p
                && mask_difference(s_mid, s_far, p.k) < p.p
                && mask_difference(s_mid, s_near, p.k) < p.p;
            if ok && (s_far.signum() * s_near.signum() < 0.0) {
                ok = mask_difference(s_mid, 0.0, p.k) < p.p;
            }
            if !ok {
                break;
            }
            j += 1;
        }
        let near = keys[j];
        let (z_mid, sigma) = mid_sigma(far, near);
        let m = half_size(sigma, p.k);
        if m > p.max_half_size as usize {
            return Err(format!(
                "a layer at screen z {z_mid:.4} needs sigma {sigma:.2} px, a mask half-size M = {m} > dof.max_half_size = {}; raise dof.max_half_size (at most {MAX_HALF_SIZE_LIMIT}) or reduce the lens radius",
                p.max_half_size
            ));
        }
        let coef_f = taps_f64(sigma, p.k);
        let coef = taps_fixed(&coef_f, p.coef_bits);
        layers.push(Layer {
            key_far: far,
            key_near: near,
            z_range: (lens.z_of(near), lens.z_of(far)),
            z_mid,
            sigma,
            m,
            pixels: 0,
            coef,
            coef_f,
        });
        i = j + 1;
    }
    let find = |k: u32| -> usize {
        // layers are ordered by descending key ranges
        layers.partition_point(|l| l.key_near > k)
    };
    let index: Vec<u16> = key.iter().map(|&k| find(k) as u16).collect();
    for &l in &index {
        layers[l as usize].pixels += 1;
    }
    let background = if keys.first() == Some(&u32::MAX) {
        Some(0)
    } else {
        None
    };
    Ok(LayerPlan {
        layers,
        index,
        background,
    })
}

/// Work and overflow counts of the fixed model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct DofWork {
    /// Multiply-accumulates (both passes, intensity and alpha planes).
    pub macs: u64,
    /// Layer colour divides.
    pub divides: u64,
    /// Composite (over) operations.
    pub composites: u64,
    /// Pixel-layer pairs passed through (sigma = 0 layers).
    pub passthrough: u64,
    /// Line-buffer overflows.
    pub line_overflows: u64,
    /// Accumulator overflows.
    pub acc_overflows: u64,
}

/// One layer as the cycle model sees it: the pixels of its box (both passes produce one
/// output sample per box pixel; a sigma = 0 layer passes its box through) and its taps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct LayerWork {
    /// Pixels of the layer's box (input widened by M, clipped to the image).
    pub pixels: u64,
    /// Mask taps `2M + 1` (1: passed through).
    pub taps: u32,
}

/// The layers [`layered_fixed`] processes, in its order, with their boxes.
pub fn layer_work(plan: &LayerPlan, width: usize, height: usize) -> Vec<LayerWork> {
    plan.layers
        .iter()
        .enumerate()
        .filter_map(|(l, layer)| {
            let all = plan.background == Some(l);
            let (x0, y0, x1, y1) = layer_box(width, height, &plan.index, l, layer.m, all)?;
            Some(LayerWork {
                pixels: ((x1 - x0) * (y1 - y0)) as u64,
                taps: 2 * layer.m as u32 + 1,
            })
        })
        .collect()
}

/// Bounding box (x0, y0, x1, y1 exclusive) of a layer's input, widened by M and clipped.
fn layer_box(
    w: usize,
    h: usize,
    idx: &[u16],
    l: usize,
    m: usize,
    all: bool,
) -> Option<(usize, usize, usize, usize)> {
    if all {
        return Some((0, 0, w, h));
    }
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
    for y in 0..h {
        for x in 0..w {
            if idx[y * w + x] as usize == l {
                x0 = x0.min(x);
                y0 = y0.min(y);
                x1 = x1.max(x + 1);
                y1 = y1.max(y + 1);
            }
        }
    }
    if x0 == usize::MAX {
        return None;
    }
    Some((
        x0.saturating_sub(m),
        y0.saturating_sub(m),
        (x1 + m).min(w),
        (y1 + m).min(h),
    ))
}

/// In-image tap sums along one axis of length `n` for taps `c`.
fn border_sums<T: Copy + Default + std::ops::AddAssign>(c: &[T], n: usize) -> Vec<T> {
    (0..n).map(|x| border_sum(c, x, n)).collect()
}

/// The in-line tap sum at position `x` of a line of length `n` (the border renormalisation
/// weight `Wx` or `Wy`): the sum of the taps `c[t]` whose sample `x + t - M` lies in
/// `[0, n)`, `M = c.len() / 2`.
pub fn border_sum<T: Copy + Default + std::ops::AddAssign>(c: &[T], x: usize, n: usize) -> T {
    let m = c.len() / 2;
    let mut s = T::default();
    for (t, &v) in c.iter().enumerate() {
        let xi = x as i64 + t as i64 - m as i64;
        if xi >= 0 && (xi as usize) < n {
            s += v;
        }
    }
    s
}

/// One output sample of a 1-D pass (see [`row_mac`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MacOut {
    /// Colour sum `sum c_t x_t`, saturated to the word's maximum.
    pub x: u128,
    /// Alpha sum `sum c_t a_t` (exact).
    pub a: u128,
    /// The colour sum did not fit the word (counted; stops the run with overflow ERROR).
    pub overflow: bool,
}

/// One output sample of the horizontal or vertical pass: over the taps `t` whose sample
/// `pos + t - M` lies on the line `[0, len)` (`M = coef.len() / 2`; samples off the line are
/// zero), the colour sum saturated to `max` (the line-buffer or accumulator word) and the
/// exact alpha sum. `sample(i)` gives the (colour, alpha) samples at line position `i`.
/// The HDL model `hdl-models/rtl/dof_row_mac.v` is this function.
#[inline(always)]
pub fn row_mac(
    coef: &[u64],
    pos: usize,
    len: usize,
    max: u128,
    sample: impl Fn(usize) -> (u128, u128),
) -> MacOut {
    let m = coef.len() / 2;
    let t0 = m.saturating_sub(pos);
    let t1 = coef.len().min((len + m).saturating_sub(pos));
    let (mut sx, mut sa) = (0u128, 0u128);
    for (t, &cv) in coef.iter().enumerate().take(t1).skip(t0) {
        let (x, a) = sample(pos + t - m);
        sx += cv as u128 * x;
        sa += cv as u128 * a;
    }
    MacOut {
        x: sx.min(max),
        a: sa,
        overflow: sx > max,
    }
}

/// One layer's planes after the horizontal pass, over the layer's box (for the HDL vectors).
#[derive(Clone, Copy, Debug)]
pub struct LayerPlanes<'a> {
    /// Layer index.
    pub layer: usize,
    /// Box origin in the image.
    pub x0: usize,
    /// Box origin in the image.
    pub y0: usize,
    /// Box width.
    pub bw: usize,
    /// Box height.
    pub bh: usize,
    /// Input colour plane `x * m` (row-major over the box).
    pub xi: &'a [u128],
    /// Input alpha plane `m`.
    pub ai: &'a [u128],
    /// Line buffer: horizontal colour sums (saturated).
    pub hx: &'a [u128],
    /// Line buffer: horizontal alpha sums.
    pub ha: &'a [u128],
}

/// The pixel's share in a layer (in `1/n2` units).
#[inline]
fn share(plan: &LayerPlan, img_key: u32, cov: u16, idx: u16, l: usize, n2: u32) -> u32 {
    let own = if img_key == u32::MAX { 0 } else { cov as u32 };
    let mut m = if idx as usize == l && img_key != u32::MAX {
        own
    } else {
        0
    };
    if plan.background == Some(l) {
        m += n2 - own.min(n2);
    }
    m
}

/// The fixed-point layered DoF. Returns the output codes and the work counts; `Err` names
/// the overflowing signal when the overflow mode is ERROR.
pub fn layered_fixed(
    img: &DepthImage<u32>,
    plan: &LayerPlan,
    p: &DofCfg,
    frame_fmt: QFormat,
) -> Result<(Vec<u32>, DofWork), (String, u32)> {
    layered_fixed_observed(img, plan, p, frame_fmt, |_| {})
}

/// [`layered_fixed`], showing `observe` each blurred layer's planes after its horizontal
/// pass (the HDL bench's scene taps).
pub fn layered_fixed_observed(
    img: &DepthImage<u32>,
    plan: &LayerPlan,
    p: &DofCfg,
    frame_fmt: QFormat,
    mut observe: impl FnMut(&LayerPlanes),
) -> Result<(Vec<u32>, DofWork), (String, u32)> {
    let (w, h) = (img.width, img.height);
    let f = p.coef_bits;
    let (q, g) = (p.alpha_bits, p.guard_bits);
    let line_max: u128 = (1u128 << p.line_bits) - 1;
    let acc_max: u128 = (1u128 << p.acc_bits) - 1;
    let mut work = DofWork::default();
    let mut out = vec![0u128; w * h];
    let mut def = vec![false; w * h];
    let one_q = 1u128 << q;
    for (l, layer) in plan.layers.iter().enumerate() {
        let all = plan.background == Some(l);
        let Some((x0, y0, x1, y1)) = layer_box(w, h, &plan.index, l, layer.m, all) else {
            continue;
        };
        let (bw, bh) = (x1 - x0, y1 - y0);
        let c = &layer.coef;
        let wx = border_sums(c, w);
        let wy = border_sums(c, h);
        // Input planes over the box.
        let mut xi = vec![0u128; bw * bh];
        let mut ai = vec![0u128; bw * bh];
        for y in 0..bh {
            for x in 0..bw {
                let pi = (y + y0) * w + x + x0;
                let s = share(plan, img.key[pi], img.cov[pi], plan.index[pi], l, img.n2);
                xi[y * bw + x] = img.value[pi] as u128 * s as u128;
                ai[y * bw + x] = s as u128;
            }
        }
        if layer.m == 0 {
            // sigma = 0: the mask is the identity; pass through.
            for y in 0..bh {
                for x in 0..bw {
                    let (a, v) = (ai[y * bw + x], xi[y * bw + x]);
                    if a == 0 {
                        continue;
                    }
                    let pi = (y + y0) * w + x + x0;
                    work.passthrough += 1;
                    let col = round_shift(((v << g) / a) as i128, 0, p.quant) as u128;
                    let aq = (a << q) / img.n2 as u128;
                    composite(&mut out[pi], &mut def[pi], col, aq, one_q, q, p.quant);
                    work.composites += 1;
                }
            }
            continue;
        }
        // Horizontal pass into the line buffer.
        let mut hx = vec![0u128; bw * bh];
        let mut ha = vec![0u128; bw * bh];
        for y in 0..bh {
            let (rx, ra) = (&xi[y * bw..(y + 1) * bw], &ai[y * bw..(y + 1) * bw]);
            for x in 0..bw {
                let r = row_mac(c, x, bw, line_max, |i| (rx[i], ra[i]));
                work.macs += 2 * c.len() as u64;
                if r.overflow {
                    work.line_overflows += 1;
                    if p.overflow == Overflow::Error {
                        return Err(("dof.line".into(), p.line_bits));
                    }
                }
                hx[y * bw + x] = r.x;
                ha[y * bw + x] = r.a;
            }
        }
        observe(&LayerPlanes {
            layer: l,
            x0,
            y0,
            bw,
            bh,
            xi: &xi,
            ai: &ai,
            hx: &hx,
            ha: &ha,
        });
        // Vertical pass, colour, alpha, composite.
        for y in 0..bh {
            for x in 0..bw {
                let r = row_mac(c, y, bh, acc_max, |i| (hx[i * bw + x], ha[i * bw + x]));
                work.macs += 2 * c.len() as u64;
                if r.overflow {
                    work.acc_overflows += 1;
                    if p.overflow == Overflow::Error {
                        return Err(("dof.acc".into(), p.acc_bits));
                    }
                }
                let (sx, sa) = (r.x, r.a);
                if sa == 0 {
                    continue;
                }
                let pi = (y + y0) * w + x + x0;
                work.divides += 1;
                // colour = round(F 2^g / A): half-up integer divide
                let col = ((sx << (g + 1)) / sa).div_ceil(2);
                let ws = wx[x + x0] as u128 * wy[y + y0] as u128 * img.n2 as u128;
                let aq = (((sa << (q + 1)) / ws).div_ceil(2)).min(one_q);
                let _ = f;
                composite(&mut out[pi], &mut def[pi], col, aq, one_q, q, p.quant);
                work.composites += 1;
            }
        }
    }
    let max = frame_fmt.max_code() as u128;
    let res = out
        .iter()
        .map(|&v| (round_shift(v as i128, g, p.quant) as u128).min(max) as u32)
        .collect();
    Ok((res, work))
}

#[inline]
fn composite(o: &mut u128, d: &mut bool, col: u128, aq: u128, one: u128, q: u32, quant: Quant) {
    if !*d {
        *o = col;
        *d = true;
    } else {
        let num = col * aq + *o * (one - aq);
        *o = round_shift(num as i128, q, quant) as u128;
    }
}

/// Float reference (1): the same layers and masks (float taps), f64 arithmetic.
pub fn layered_f64(img: &DepthImage<f64>, plan: &LayerPlan) -> Vec<f64> {
    let (w, h) = (img.width, img.height);
    let mut out = vec![0.0f64; w * h];
    let mut def = vec![false; w * h];
    for (l, layer) in plan.layers.iter().enumerate() {
        let all = plan.background == Some(l);
        let Some((x0, y0, x1, y1)) = layer_box(w, h, &plan.index, l, layer.m, all) else {
            continue;
        };
        let (bw, bh) = (x1 - x0, y1 - y0);
        let c = &layer.coef_f;
        let m = layer.m as i64;
        let wx = border_sums(c, w);
        let wy = border_sums(c, h);
        let mut xi = vec![0.0; bw * bh];
        let mut ai = vec![0.0; bw * bh];
        for y in 0..bh {
            for x in 0..bw {
                let pi = (y + y0) * w + x + x0;
                let s = share(plan, img.key[pi], img.cov[pi], plan.index[pi], l, img.n2) as f64
                    / img.n2 as f64;
                xi[y * bw + x] = img.value[pi] * s;
                ai[y * bw + x] = s;
            }
        }
        let pass = |src: &[f64], horizontal: bool| -> Vec<f64> {
            let mut dst = vec![0.0; bw * bh];
            for y in 0..bh {
                for x in 0..bw {
                    let mut s = 0.0;
                    for (t, &cv) in c.iter().enumerate() {
                        let (xx, yy) = if horizontal {
                            (x as i64 + t as i64 - m, y as i64)
                        } else {
                            (x as i64, y as i64 + t as i64 - m)
                        };
                        if xx < 0 || yy < 0 || xx >= bw as i64 || yy >= bh as i64 {
                            continue;
                        }
                        s += cv * src[yy as usize * bw + xx as usize];
                    }
                    dst[y * bw + x] = s;
                }
            }
            dst
        };
        let fx = pass(&pass(&xi, true), false);
        let fa = pass(&pass(&ai, true), false);
        for y in 0..bh {
            for x in 0..bw {
                let a = fa[y * bw + x];
                if a <= 0.0 {
                    continue;
                }
                let pi = (y + y0) * w + x + x0;
                let col = fx[y * bw + x] / a;
                let an = (a / (wx[x + x0] * wy[y + y0])).min(1.0);
                if !def[pi] {
                    out[pi] = col;
                    def[pi] = true;
                } else {
                    out[pi] = col * an + out[pi] * (1.0 - an);
                }
            }
        }
    }
    out
}

/// Scatters `v` at `(px, py)` with separable taps, restricted to the image and renormalised.
#[inline]
fn scatter(out: &mut [f64], w: usize, h: usize, px: usize, py: usize, v: f64, c: &[f64]) {
    let m = (c.len() / 2) as i64;
    let (xa, xb) = ((px as i64 - m).max(0), (px as i64 + m).min(w as i64 - 1));
    let (ya, yb) = ((py as i64 - m).max(0), (py as i64 + m).min(h as i64 - 1));
    let sx: f64 = (xa..=xb).map(|x| c[(x - px as i64 + m) as usize]).sum();
    let sy: f64 = (ya..=yb).map(|y| c[(y - py as i64 + m) as usize]).sum();
    let v = v / (sx * sy);
    for y in ya..=yb {
        let vy = v * c[(y - py as i64 + m) as usize];
        let row = &mut out[y as usize * w..];
        for x in xa..=xb {
            row[x as usize] += vy * c[(x - px as i64 + m) as usize];
        }
    }
}

/// Float reference (2): the per-pixel scatter filter. Every pixel spreads its value with the
/// mask of its own depth (`sigma` = exact float sigma of its depth code), energy preserving.
pub fn per_pixel_scatter(img: &DepthImage<f64>, lens: &LensMap, k: f64) -> Vec<f64> {
    let (w, h) = (img.width, img.height);
    let mut out = vec![0.0; w * h];
    let mut cache: std::collections::HashMap<u32, Vec<f64>> = Default::default();
    for y in 0..h {
        for x in 0..w {
            let pi = y * w + x;
            let c = cache
                .entry(img.key[pi])
                .or_insert_with(|| taps_f64(lens.sigma_f64(img.key[pi]), k));
            scatter(&mut out, w, h, x, y, img.value[pi], c);
        }
    }
    out
}

/// The theorem's form: every pixel spread (energy preserving) with its layer's middle mask,
/// summed, no compositing. `quantised` uses the fixed coefficients (`coef / 2^f`).
pub fn additive_layered(
    img: &DepthImage<f64>,
    plan: &LayerPlan,
    coef_bits: u32,
    quantised: bool,
) -> Vec<f64> {
    let (w, h) = (img.width, img.height);
    let taps: Vec<Vec<f64>> = plan
        .layers
        .iter()
        .map(|l| {
            if quantised {
                l.coef
                    .iter()
                    .map(|&c| c as f64 / (1u64 << coef_bits) as f64)
                    .collect()
            } else {
                l.coef_f.clone()
            }
        })
        .collect();
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let pi = y * w + x;
            scatter(
                &mut out,
                w,
                h,
                x,
                y,
                img.value[pi],
                &taps[plan.index[pi] as usize],
            );
        }
    }
    out
}

/// Pixels within `r` of a pixel of another layer (the depth-edge band).
pub fn edge_band(w: usize, h: usize, index: &[u16], r: usize) -> Vec<bool> {
    let mut edge = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let l = index[y * w + x];
            let right = x + 1 < w && index[y * w + x + 1] != l;
            let down = y + 1 < h && index[(y + 1) * w + x] != l;
            if right || down {
                edge[y * w + x] = true;
            }
        }
    }
    // dilate by r (square), separably
    let mut tmp = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let (a, b) = (x.saturating_sub(r), (x + r + 1).min(w));
            tmp[y * w + x] = edge[y * w + a..y * w + b].iter().any(|&e| e);
        }
    }
    for y in 0..h {
        for x in 0..w {
            let (a, b) = (y.saturating_sub(r), (y + r + 1).min(h));
            edge[y * w + x] = (a..b).any(|yy| tmp[yy * w + x]);
        }
    }
    edge
}

/// Error of an image against a reference, overall and split into depth-edge band and interior.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RegionError {
    /// Difference degree over the whole image.
    pub difference_degree: f64,
    /// Largest |a - b| (frame LSBs).
    pub max_abs: f64,
    /// Mean |a - b| (frame LSBs).
    pub mean_abs: f64,
    /// Pixels in the depth-edge band.
    pub edge_pixels: u64,
    /// Difference degree inside the depth-edge band.
    pub edge_difference_degree: f64,
    /// Largest |a - b| in the band.
    pub edge_max_abs: f64,
    /// Difference degree in the interior.
    pub interior_difference_degree: f64,
    /// Largest |a - b| in the interior.
    pub interior_max_abs: f64,
}

/// Compares `a` with the reference `b` overall and by region.
pub fn region_error(a: &[f64], b: &[f64], edge: &[bool]) -> RegionError {
    let mut r = RegionError {
        difference_degree: difference_degree(a, b),
        ..Default::default()
    };
    let (mut ed, mut es, mut id, mut is) = (0.0, 0.0, 0.0, 0.0);
    let mut sum = 0.0;
    for i in 0..a.len() {
        let d = (a[i] - b[i]).abs();
        sum += d;
        r.max_abs = r.max_abs.max(d);
        if edge[i] {
            r.edge_pixels += 1;
            ed += d;
            es += a[i].abs() + b[i].abs();
            r.edge_max_abs = r.edge_max_abs.max(d);
        } else {
            id += d;
            is += a[i].abs() + b[i].abs();
            r.interior_max_abs = r.interior_max_abs.max(d);
        }
    }
    if !a.is_empty() {
        r.mean_abs = sum / a.len() as f64;
    }
    r.edge_difference_degree = if es > 0.0 { ed / es } else { 0.0 };
    r.interior_difference_degree = if is > 0.0 { id / is } else { 0.0 };
    r
}

/// Stage-local comparison of fixed codes with a float image in the same units.
pub fn local_error(fixed: &[u32], float: &[f64], max: f64) -> LocalError {
    let mut e = LocalError::default();
    for (&a, &b) in fixed.iter().zip(float) {
        e.add(a as f64, b.min(max));
    }
    e.finish()
}

/// Cost of the datapath: line buffers for the largest mask, the composite buffer, the
/// coefficient ROM and the arithmetic units by width.
pub fn cost(
    plan: &LayerPlan,
    p: &DofCfg,
    width: u64,
    height: u64,
    code_bits: u32,
    n2: u32,
    lens: &LensMap,
) -> Cost {
    let m_max = plan.layers.iter().map(|l| l.m).max().unwrap_or(0) as u64;
    let a_bits = n2.next_power_of_two().trailing_zeros() + 1;
    let alpha_line = a_bits + p.coef_bits + 1;
    let line = (2 * m_max + 1) * width * (p.line_bits + alpha_line) as u64;
    let composite = width * height * (code_bits + p.guard_bits) as u64;
    let rom: u64 = plan
        .layers
        .iter()
        .map(|l| (l.m as u64 + 1) * (p.coef_bits + 1) as u64)
        .sum();
    let taps = (2 * m_max + 1) as u32;
    let xm_bits = code_bits + a_bits;
    Cost {
        storage_bits: line + composite,
        lut_bits: rom,
        adders: vec![
            Unit::adder("horizontal tap sum (intensity)", taps, p.line_bits),
            Unit::adder("vertical tap sum (intensity)", taps, p.acc_bits),
            Unit::adder("alpha tap sums", 2 * taps, 2 * p.coef_bits + a_bits + 1),
            Unit::adder(
                "composite (over)",
                1,
                code_bits + p.guard_bits + p.alpha_bits,
            ),
        ],
        multipliers: vec![
            Unit::mul("sigma = G (z - z_e)", 1, lens.z_frac + 1, lens.g_bits()),
            Unit::mul("premultiply x * coverage", 1, code_bits, a_bits),
            Unit::mul("horizontal taps", taps, xm_bits, p.coef_bits + 1),
            Unit::mul("vertical taps", taps, p.line_bits, p.coef_bits + 1),
            Unit::mul("alpha taps", 2 * taps, alpha_line, p.coef_bits + 1),
            Unit::mul(
                "layer colour (divide acc / alpha)",
                1,
                p.acc_bits + p.guard_bits,
                2 * p.coef_bits + a_bits + 1,
            ),
            Unit::mul(
                "composite (colour x alpha, back x (1-alpha))",
                2,
                code_bits + p.guard_bits,
                p.alpha_bits + 1,
            ),
        ],
    }
}

/// Stats record for an overflow count.
pub fn overflow_signal(name: &str, bits: u32, n: u64) -> SignalStats {
    let mut s = SignalStats::new(name, QFormat::new(false, bits.min(32), 0));
    s.add_overflows(n);
    s
}

/// Weber error of linear frame intensities through the display (the gamma LUT makes the
/// displayed luminance linear in the frame code: `B = B_min + (B_max - B_min) v / white`).
pub fn weber_linear(
    a: &[f64],
    b: &[f64],
    white: f64,
    d: &crate::scene::Display,
) -> crate::compare::WeberCompare {
    let (lo, hi) = (d.b_min(), d.b_max);
    let lum = |v: f64| lo + (hi - lo) * (v / white).clamp(0.0, 1.0);
    crate::compare::weber_of(a.iter().zip(b).map(|(&x, &y)| (lum(x), lum(y))), d.weber)
}

/// Runs the dof stage inside the pipeline: replaces the frame codes and the float frame with
/// the depth-of-field results. `None` (and nothing changed) for a pinhole camera.
/// `per_pixel` also runs the per-pixel scatter reference and the theorem check.
pub fn run_stage(
    scene: &crate::scene::Scene,
    hw: &crate::config::HwConfig,
    frame: &mut super::accumulate::Frame,
    frame_ref: &mut Vec<f64>,
    stage_local: bool,
    per_pixel: bool,
) -> crate::error::Result<Option<(super::StageReport, Vec<LayerWork>)>> {
    use super::ms_since;
    use crate::error::{Error, FileError};
    use std::time::Instant;
    let (w, h) = (frame.width as usize, frame.height as usize);
    let Some(lens) = LensMap::from_camera(
        &scene.camera,
        frame.height,
        hw.visibility.z.format.frac_bits,
    ) else {
        return Ok(None);
    };
    let p = &hw.dof;
    let n2 = hw.raster.samples * hw.raster.samples;
    let frame_fmt = hw.accumulate.frame.format;
    let mut r = super::StageReport {
        name: "dof".into(),
        ..Default::default()
    };
    let t = Instant::now();
    let plan = plan_layers(&frame.depth, &frame.coverage, n2, &lens, p).map_err(|msg| {
        Error::File(FileError {
            file: hw.name.clone(),
            line: None,
            col: None,
            field: "dof.max_half_size".into(),
            msg,
        })
    })?;
    let img = DepthImage::of_frame(frame, &frame.acc, n2);
    let (out, work) =
        layered_fixed(&img, &plan, p, frame_fmt).map_err(|(signal, bits)| Error::Overflow {
            signal,
            format: format!("UQ{bits}.0"),
            value: 1i128 << bits,
            min: 0,
            max: ((1u128 << bits.min(63)) - 1) as i64,
        })?;
    r.fixed_ms = ms_since(t);
    let accf: Vec<f64> = frame.acc.iter().map(|&v| v as f64).collect();
    let fimg = DepthImage::of_frame(frame, &accf, n2);
    let white = frame_fmt.max_code() as f64;
    let outf: Vec<f64> = out.iter().map(|&v| v as f64).collect();
    if stage_local {
        let local = layered_f64(&fimg, &plan);
        r.local = Some(local_error(&out, &local, white));
        r.notes.insert(
            "weber_vs_layered_float".into(),
            serde_json::to_value(weber_linear(&outf, &local, white, &scene.display))
                .unwrap_or_default(),
        );
    }
    let t = Instant::now();
    let rimg = DepthImage {
        value: &frame_ref[..],
        ..fimg
    };
    let new_ref = layered_f64(&rimg, &plan);
    r.float_ms = ms_since(t);
    if per_pixel {
        let t = Instant::now();
        let pp = per_pixel_scatter(&fimg, &lens, p.k);
        let pp_ms = ms_since(t);
        let m_max = plan.layers.iter().map(|l| l.m).max().unwrap_or(0);
        let edge = edge_band(w, h, &plan.index, m_max);
        let add_f = additive_layered(&fimg, &plan, p.coef_bits, false);
        let add_q = additive_layered(&fimg, &plan, p.coef_bits, true);
        let v = |x: &RegionError| serde_json::to_value(x).unwrap_or_default();
        let pp_json = serde_json::json!({
            "ms": pp_ms,
            "theorem_additive_float_difference_degree": difference_degree(&add_f, &pp),
            "theorem_additive_fixed_coef_difference_degree": difference_degree(&add_q, &pp),
            "p": p.p,
            "composited_fixed": v(&region_error(&outf, &pp, &edge)),
            "weber_fixed": serde_json::to_value(weber_linear(&outf, &pp, white, &scene.display)).unwrap_or_default(),
            "edge_band_px": m_max,
        });
        r.notes.insert("per_pixel_reference".into(), pp_json);
    }
    // Blur facts.
    let mut sig_min = f64::INFINITY;
    let mut sig_max = f64::NEG_INFINITY;
    let mut in_focus = 0u64;
    let mut coc_max = 0.0f64;
    for &k in &frame.depth {
        if k == u32::MAX {
            continue;
        }
        let s = lens.sigma_code(k) as f64 / (1u64 << SIGMA_FRAC) as f64;
        sig_min = sig_min.min(s);
        sig_max = sig_max.max(s);
        let c = lens.coc_f64(k);
        coc_max = coc_max.max(c);
        if c <= lens.coc_px {
            in_focus += 1;
        }
    }
    r.notes.insert(
        "lens".into(),
        serde_json::to_value(lens).unwrap_or_default(),
    );
    r.notes.insert(
        "layers".into(),
        serde_json::to_value(&plan.layers).unwrap_or_default(),
    );
    r.notes.insert(
        "object_sigma_px".into(),
        serde_json::json!({"min": sig_min, "max": sig_max, "background": lens.sigma_f64(u32::MAX)}),
    );
    r.notes.insert("object_coc_max_px".into(), coc_max.into());
    r.notes
        .insert("object_pixels_in_focus".into(), in_focus.into());
    r.record_work(&[
        ("layers", plan.layers.len() as u64),
        ("pixels", (w * h) as u64),
        ("macs", work.macs),
        ("divides", work.divides),
        ("composites", work.composites),
        ("passthrough", work.passthrough),
    ]);
    r.cost = cost(
        &plan,
        p,
        w as u64,
        h as u64,
        frame_fmt.total_bits(),
        n2,
        &lens,
    );
    r.signals.push(overflow_signal(
        "dof.line",
        p.line_bits,
        work.line_overflows,
    ));
    r.signals
        .push(overflow_signal("dof.acc", p.acc_bits, work.acc_overflows));
    frame.acc = out;
    *frame_ref = new_ref;
    let layers = layer_work(&plan, w, h);
    Ok(Some((r, layers)))
}
