//! Light points and the sample region: a light point's visible samples, the summed filter
//! weight it gives each pixel it touches, and the sample region a pixel region needs.

use super::kernel::Kernel;
use crate::stage::Region;
use crate::stage::raster::SampleRegion;

/// A light point's visible samples and intensity, for the additive pass.
#[derive(Clone, Debug, PartialEq)]
pub struct PointFrags<T> {
    /// Intensity (code or float).
    pub i: T,
    /// Visible sample indices in the sample region.
    pub samples: Vec<u32>,
}

/// The sample region the filter windows of a pixel region read: pixel `p`'s window is the
/// samples `[p n - off, p n - off + size)`. The window reaches `off` samples before the
/// pixel's own and `size - n - off` after them: the same when `(base - 1) n` is even, one
/// more after when it is odd (a tent over one sample per pixel).
pub fn sample_region(r: &Region, k: &Kernel) -> SampleRegion {
    let n = k.n as i64;
    let after = k.size as i64 - n - k.off;
    SampleRegion {
        c0: r.x0 as i64 * n - k.off,
        k0: r.y0 as i64 * n - k.off,
        c1: r.x1 as i64 * n + after,
        k1: r.y1 as i64 * n + after,
    }
}

/// The pixel region the primitives' footprints touch on a `width x height` screen (their
/// union, clipped to it; empty when none) and the sample region its filter windows read.
pub fn regions(
    prints: &[crate::stage::input::Footprint],
    k: &Kernel,
    width: u32,
    height: u32,
) -> (Region, SampleRegion) {
    let boxes: Vec<[i64; 4]> = prints.iter().map(|f| f.pixels).collect();
    let region = Region::bounding(&boxes, &Region::screen(width, height));
    let samples = if region.is_empty() {
        SampleRegion::default()
    } else {
        sample_region(&region, k)
    };
    (region, samples)
}

/// For a light point: each pixel of the region it touches with the summed filter weight
/// `S` of its visible samples (`weight(e)` gives the kernel entry `e`).
pub fn point_weights(
    pt: &PointFrags<impl Copy>,
    reg: &SampleRegion,
    region: &Region,
    k: &Kernel,
    weight: impl Fn(usize) -> f64,
) -> Vec<(u32, u32, f64)> {
    let mut out = Vec::new();
    if pt.samples.is_empty() {
        return out;
    }
    let sw = reg.width() as i64;
    let n = k.n as i64;
    let coords: Vec<(i64, i64)> = pt
        .samples
        .iter()
        .map(|&s| (reg.c0 + s as i64 % sw, reg.k0 + s as i64 / sw))
        .collect();
    let (cmin, cmax) = coords
        .iter()
        .fold((i64::MAX, i64::MIN), |a, c| (a.0.min(c.0), a.1.max(c.0)));
    let (kmin, kmax) = coords
        .iter()
        .fold((i64::MAX, i64::MIN), |a, c| (a.0.min(c.1), a.1.max(c.1)));
    // Pixels whose window [p n - off, p n - off + size) meets the samples.
    let px0 = (cmin + k.off - k.size as i64 + 1)
        .div_euclid(n)
        .max(region.x0 as i64);
    let px1 = ((cmax + k.off).div_euclid(n) + 1).min(region.x1 as i64);
    let py0 = ((kmin + k.off - k.size as i64 + 1).div_euclid(n)).max(region.y0 as i64);
    let py1 = ((kmax + k.off).div_euclid(n) + 1).min(region.y1 as i64);
    for py in py0..py1 {
        for px in px0..px1 {
            let (wc, wk) = (px * n - k.off, py * n - k.off);
            let mut sum = 0.0;
            for &(c, kk) in &coords {
                let (i, j) = (c - wc, kk - wk);
                if (0..k.size as i64).contains(&i) && (0..k.size as i64).contains(&j) {
                    sum += weight(j as usize * k.size + i as usize);
                }
            }
            if sum != 0.0 {
                out.push((px as u32, py as u32, sum));
            }
        }
    }
    out
}
