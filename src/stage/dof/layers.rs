//! Depth layers (docs/reference.md §3): the depth image, the layer plan grown far to near,
//! and each layer's bounding box and work for the cycle model.

use super::kernel::{KernelDifferences, Mask2, kernel_half_size, kernel_taps_f64};
use super::keys::distinct_descending;
use super::lens::{LensMap, SIGMA_FRAC};
use super::mask::taps_fixed;
use crate::config::{AlphaNorm, DofKernel};
use crate::config::{DofCfg, MAX_HALF_SIZE_LIMIT};
use crate::fixed::Quant;
use crate::stage::Pool;
use rayon::prelude::*;
use serde::Serialize;
use std::sync::OnceLock;

/// Pixels per chunk of the layer index's parallel pass.
const INDEX_CHUNK: usize = 1 << 14;

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
    /// Quantised 1-D taps (sum `2^coef_bits`; empty for a 2-D mask).
    #[serde(skip)]
    pub coef: Vec<u64>,
    /// Float 1-D taps (sum 1; empty for a 2-D mask).
    #[serde(skip)]
    pub coef_f: Vec<f64>,
    /// The 2-D mask of a `disc` kernel with `M > 0` (a direct 2-D filter, docs/dof.md
    /// "Kernel shape"); `None` for the separable kernels and the identity.
    #[serde(skip)]
    pub disc: Option<Mask2>,
}

impl Layer {
    /// The layer's masks for `sigma`: separable taps, or the disc's 2-D mask.
    fn masks(kernel: DofKernel, sigma: f64, p: &DofCfg) -> (Vec<u64>, Vec<f64>, Option<Mask2>) {
        let m = kernel_half_size(kernel, sigma, p.k);
        if kernel == DofKernel::Disc && m > 0 {
            return (vec![], vec![], Some(Mask2::disc(sigma, 2 * p.coef_bits)));
        }
        let coef_f = kernel_taps_f64(kernel, sigma, p.k);
        (taps_fixed(&coef_f, p.coef_bits), coef_f, None)
    }
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
    pub fn of_frame(frame: &'a crate::stage::accumulate::Frame, value: &'a [T], n2: u32) -> Self {
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
    /// Per layer, the box pixels in uniform tiles the hardware skips
    /// (`dof.skip_uniform_tiles`; set by the fixed run, empty otherwise).
    pub skipped: Vec<u64>,
    /// What each layer's alpha is normalised by (`dof.alpha_norm`).
    pub alpha_norm: AlphaNorm,
    /// The layers' boxes ([`layer_boxes`]) for the image size they were found for: the
    /// fixed run and the cycle model's work and row stream of one frame read them.
    pub(super) boxes: OnceLock<SizedBoxes>,
}

/// A box `(x0, y0, x1, y1)`, `x1` and `y1` exclusive.
pub(super) type LayerBox = (usize, usize, usize, usize);

/// Every layer's box and the image size `(w, h)` they were found for.
pub(super) type SizedBoxes = ((usize, usize), Vec<Option<LayerBox>>);

impl LayerPlan {
    /// How far a layer's box reaches past its pixels, in mask half-sizes: `M` for its
    /// blurred planes; with [`AlphaNorm::Behind`] `2 M`, because the coverage behind it is
    /// read `M` further out than its own pixels reach.
    pub fn margin(&self, m: usize) -> usize {
        match self.alpha_norm {
            AlphaNorm::Behind => 2 * m,
            AlphaNorm::Image => m,
        }
    }
}

/// Grows the layers far to near (see the module notes). Errors name the limit exceeded.
pub fn plan_layers(
    key: &[u32],
    cov: &[u16],
    n2: u32,
    lens: &LensMap,
    p: &DofCfg,
) -> Result<LayerPlan, String> {
    plan_layers_in(key, cov, n2, lens, p, &Pool::new())
}

/// [`plan_layers`] with its planes (the depth codes sorted, the layer index) from `pool`.
pub fn plan_layers_in(
    key: &[u32],
    cov: &[u16],
    n2: u32,
    lens: &LensMap,
    p: &DofCfg,
    pool: &Pool,
) -> Result<LayerPlan, String> {
    // The background code (most pixels of a typical frame) is added once, not sorted; nor
    // is a pixel repeating its left neighbour's code (within a chunk: the codes are sorted
    // and deduplicated next, so where the chunks start does not matter). In chunks on the
    // threads, each also telling whether it shows the background.
    debug_assert_eq!(key.len(), cov.len());
    let parts: Vec<(Vec<u32>, bool)> = key
        .par_chunks(INDEX_CHUNK)
        .zip(cov.par_chunks(INDEX_CHUNK))
        .map(|(kc, cc)| {
            let mut v = Vec::new();
            let mut before = u32::MAX;
            for &k in kc {
                if k != before && k != u32::MAX {
                    v.push(k);
                }
                before = k;
            }
            let bg = kc.contains(&u32::MAX) || cc.iter().any(|&c| u32::from(c) < n2);
            (v, bg)
        })
        .collect();
    let lists: Vec<&[u32]> = parts.iter().map(|p| &p.0[..]).collect();
    let keys = distinct_descending(&lists, parts.iter().any(|p| p.1), pool);
    let coder = lens.sigma_coder();
    let sig = |k: u32| coder.code(k) as f64 / (1u64 << SIGMA_FRAC) as f64;
    // Every layer's mask lies between the masks of its ends (sigma is monotone in depth),
    // so the largest mask over the depth codes present bounds them all: check it before any
    // mask is built (a huge lens would otherwise allocate huge masks), and name it, so that
    // raising the limit to it is enough.
    let mut sigs: Vec<f64> = pool.take(keys.len());
    keys.par_iter().map(|&k| sig(k)).collect_into_vec(&mut sigs);
    if let Some((&worst, &s)) = keys
        .iter()
        .zip(&sigs)
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
    {
        let m = kernel_half_size(p.kernel, s, p.k);
        if m > p.max_half_size as usize {
            let z = lens.z_of(worst);
            let advice = if m <= MAX_HALF_SIZE_LIMIT as usize {
                format!("raise dof.max_half_size to {m} (at most {MAX_HALF_SIZE_LIMIT})")
            } else {
                format!(
                    "that is beyond the largest configurable half-size {MAX_HALF_SIZE_LIMIT}: reduce camera.lens.lens_radius (or raise f_number) or move the focus"
                )
            };
            return Err(format!(
                "the largest blur in the frame (screen z {z:.4}) is sigma {:.2} px, a mask half-size M = {m} > dof.max_half_size = {}; {advice}",
                s.abs(),
                p.max_half_size
            ));
        }
    }
    let zq = lens.z_quantizer();
    // Two depth codes' middle is exact in binary: with the constants' rounding (RND_INF,
    // ties away from zero) and no saturation it is `(far + near + 1) / 2`, as the
    // quantiser gives it (tests/dof.rs checks the two agree).
    let exact_mid = zq.format.frac_bits == lens.z_frac && zq.quant == Quant::RndInf;
    let zq_max = zq.format.max_code();
    // The middle depth and its sigma; the sigma alone where the middle code is exact (the
    // layer's growth asks for it at every depth code).
    let mid_sig = |far: u32, near: u32, zm: Option<f64>| {
        let sum = i64::from(far) + i64::from(near) + 1;
        if exact_mid && far != u32::MAX && sum / 2 <= zq_max {
            return sig((sum / 2) as u32);
        }
        // The middle depth as a code (the background's z_inf is exact): sigma from its code
        // (`lens.z_code`, its quantiser built once).
        let zm = zm.unwrap_or_else(|| (lens.z_of(far) + lens.z_of(near)) / 2.0);
        let code = zq.quantize_f64(zm).code;
        let c = if code >= i64::from(u32::MAX) {
            u32::MAX
        } else {
            code.max(0) as u32
        };
        sig(c)
    };
    let mid_sigma = |far: u32, near: u32| {
        let zm = (lens.z_of(far) + lens.z_of(near)) / 2.0;
        (zm, mid_sig(far, near, Some(zm)))
    };
    let mut diffs = KernelDifferences::new(p.kernel);
    let mut mask_difference = |a: f64, b: f64, k: f64| diffs.get(a, b, k);
    let mut layers: Vec<Layer> = Vec::new();
    let mut i = 0;
    while i < keys.len() {
        let (far, s_far) = (keys[i], sigs[i]);
        let mut j = i;
        // Neighbouring depth codes mostly share their sigma codes: the test depends only on
        // (sigma far, sigma near, sigma middle), so a repeat of the last accepted pair is
        // accepted without looking the differences up.
        let mut accepted: Option<(u64, u64)> = None;
        while j + 1 < keys.len() {
            let (near, s_near) = (keys[j + 1], sigs[j + 1]);
            let s_mid = mid_sig(far, near, None);
            let pair = (s_near.to_bits(), s_mid.to_bits());
            if accepted != Some(pair) {
                let mut ok = mask_difference(s_far, s_near, p.k) < p.p
                    && mask_difference(s_mid, s_far, p.k) < p.p
                    && mask_difference(s_mid, s_near, p.k) < p.p;
                if ok && (s_far.signum() * s_near.signum() < 0.0) {
                    ok = mask_difference(s_mid, 0.0, p.k) < p.p;
                }
                if !ok {
                    break;
                }
                accepted = Some(pair);
            }
            j += 1;
        }
        let near = keys[j];
        let (z_mid, sigma) = mid_sigma(far, near);
        let m = kernel_half_size(p.kernel, sigma, p.k);
        if m > p.max_half_size as usize {
            return Err(format!(
                "a layer at screen z {z_mid:.4} needs sigma {:.2} px, a mask half-size M = {m} > dof.max_half_size = {}; raise dof.max_half_size (at most {MAX_HALF_SIZE_LIMIT}) or reduce the lens radius",
                sigma.abs(),
                p.max_half_size
            ));
        }
        let (coef, coef_f, disc) = Layer::masks(p.kernel, sigma, p);
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
            disc,
        });
        i = j + 1;
    }
    let find = |k: u32| -> usize {
        // layers are ordered by descending key ranges
        layers.partition_point(|l| l.key_near > k)
    };
    // Runs of one depth code are common: the layer is searched once per run. Chunks of
    // pixels on the threads, their counts summed (integers: the same on any thread count).
    let mut index: Vec<u16> = pool.scratch(key.len(), 0);
    let counts = index
        .par_chunks_mut(INDEX_CHUNK)
        .zip(key.par_chunks(INDEX_CHUNK))
        .map(|(out, key)| {
            let mut counts = vec![0u64; layers.len()];
            let mut last = (u32::MAX, find(u32::MAX) as u16);
            for (o, &k) in out.iter_mut().zip(key) {
                if k != last.0 {
                    last = (k, find(k) as u16);
                }
                *o = last.1;
                counts[last.1 as usize] += 1;
            }
            counts
        })
        .reduce(
            || vec![0u64; layers.len()],
            |mut a, b| {
                a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
                a
            },
        );
    for (layer, n) in layers.iter_mut().zip(counts) {
        layer.pixels = n;
    }
    let background = if keys.first() == Some(&u32::MAX) {
        Some(0)
    } else {
        None
    };
    pool.give(keys);
    pool.give(sigs);
    Ok(LayerPlan {
        layers,
        index,
        background,
        skipped: Vec::new(),
        alpha_norm: p.alpha_norm,
        boxes: OnceLock::new(),
    })
}

/// One layer as the cycle model sees it: the pixels of its box (both passes produce one
/// output sample per box pixel; a sigma = 0 layer passes its box through) and its taps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct LayerWork {
    /// Pixels of the layer's box (input widened by [`LayerPlan::margin`], clipped to the image).
    pub pixels: u64,
    /// Mask taps `2M + 1` (1: passed through).
    pub taps: u32,
    /// Pixels of the box in skipped uniform tiles (`dof.skip_uniform_tiles`; else 0).
    pub skipped: u64,
}

/// The layers [`layered_fixed`](super::layered_fixed) processes, in its order, with their boxes.
pub fn layer_work(plan: &LayerPlan, width: usize, height: usize) -> Vec<LayerWork> {
    layer_boxes(width, height, plan)
        .into_iter()
        .enumerate()
        .filter_map(|(l, b)| {
            let (x0, y0, x1, y1) = b?;
            Some(LayerWork {
                pixels: ((x1 - x0) * (y1 - y0)) as u64,
                taps: 2 * plan.layers[l].m as u32 + 1,
                skipped: plan.skipped.get(l).copied().unwrap_or(0),
            })
        })
        .collect()
}

/// The bounding box (x0, y0, x1, y1 exclusive) of every layer's input in one pass over the
/// index image, widened by the layer's [`LayerPlan::margin`] and clipped (the whole image
/// for the background's layer; `None` for a layer without pixels). Found once per plan
/// and image size.
pub(super) fn layer_boxes(w: usize, h: usize, plan: &LayerPlan) -> Vec<Option<LayerBox>> {
    let (size, boxes) = plan.boxes.get_or_init(|| ((w, h), find_boxes(w, h, plan)));
    if *size == (w, h) {
        boxes.clone()
    } else {
        find_boxes(w, h, plan)
    }
}

/// [`layer_boxes`], found.
fn find_boxes(w: usize, h: usize, plan: &LayerPlan) -> Vec<Option<LayerBox>> {
    let n = plan.layers.len();
    let mut b = vec![(usize::MAX, usize::MAX, 0usize, 0usize); n];
    // A row is taken in runs of one layer (most of a row is): a box grows once per run.
    for (y, row) in plan.index.chunks_exact(w.max(1)).take(h).enumerate() {
        let mut x = 0;
        while x < row.len() {
            let l = row[x];
            let end = row[x..]
                .iter()
                .position(|&v| v != l)
                .map_or(row.len(), |k| x + k);
            if let Some(e) = b.get_mut(l as usize) {
                e.0 = e.0.min(x);
                e.1 = e.1.min(y);
                e.2 = e.2.max(end);
                e.3 = e.3.max(y + 1);
            }
            x = end;
        }
    }
    b.into_iter()
        .zip(&plan.layers)
        .enumerate()
        .map(|(l, ((x0, y0, x1, y1), layer))| {
            if plan.background == Some(l) {
                Some((0, 0, w, h))
            } else if x0 == usize::MAX {
                None
            } else {
                let m = plan.margin(layer.m);
                Some((
                    x0.saturating_sub(m),
                    y0.saturating_sub(m),
                    (x1 + m).min(w),
                    (y1 + m).min(h),
                ))
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The boxes are found once per plan and image size: a second call gives the first
    /// call's boxes, and another size finds its own.
    #[test]
    fn layer_boxes_are_kept_per_size() {
        let layer = |m| Layer {
            key_far: 0,
            key_near: 0,
            z_range: (0.0, 0.0),
            z_mid: 0.0,
            sigma: 0.0,
            m,
            pixels: 0,
            coef: vec![],
            coef_f: vec![],
            disc: None,
        };
        // 6 x 4 pixels: layer 1 in columns 2..4 of rows 1..3, layer 0 elsewhere.
        let (w, h) = (6, 4);
        let index = (0..w * h)
            .map(|i| u16::from((1..3).contains(&(i / w)) && (2..4).contains(&(i % w))))
            .collect();
        let plan = LayerPlan {
            layers: vec![layer(0), layer(1)],
            index,
            background: Some(0),
            skipped: vec![],
            alpha_norm: AlphaNorm::Image,
            boxes: OnceLock::new(),
        };
        let want = vec![Some((0, 0, 6, 4)), Some((1, 0, 5, 4))];
        assert_eq!(layer_boxes(w, h, &plan), want);
        assert_eq!(layer_boxes(w, h, &plan), want);
        assert_eq!(plan.boxes.get(), Some(&((w, h), want)));
        // Read as 4 x 6: layer 1 is in columns 0..4 of rows 2..6, the box one wider.
        assert_eq!(layer_boxes(4, 6, &plan), find_boxes(4, 6, &plan));
        assert_ne!(find_boxes(4, 6, &plan), find_boxes(w, h, &plan));
    }
}
