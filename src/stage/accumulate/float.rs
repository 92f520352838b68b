//! The float reference of the stage: exact kernel weights, no rounding, no saturation.

use super::kernel::Kernel;
use super::points::{PointFrags, point_weights};
use crate::stage::Region;
use crate::stage::raster::SampleRegion;
use rayon::prelude::*;

/// Parameters of the float reference.
#[derive(Clone, Copy, Debug)]
pub struct AccRef<'a> {
    /// Kernel (its exact weights are used).
    pub kernel: &'a Kernel,
    /// Fraction bits of the intensity codes the input is expressed in.
    pub i_frac: u32,
    /// Fraction bits of the frame format the output is expressed in.
    pub frame_frac: u32,
    /// Background intensity (intensity LSBs).
    pub bg_i: f64,
    /// Image size.
    pub size: (u32, u32),
}

/// Float reference: exact weights, no rounding, no saturation. `i` holds each sample's
/// intensity in intensity-format LSBs; the result is in frame-format LSBs.
pub fn accumulate_f64(
    i: &[f64],
    reg: &SampleRegion,
    region: &Region,
    points: &[PointFrags<f64>],
    p: &AccRef<'_>,
) -> Vec<f64> {
    let (width, height) = p.size;
    let k = p.kernel;
    let scale = 2f64.powi(p.frame_frac as i32 - p.i_frac as i32);
    let mut acc = vec![p.bg_i * scale; width as usize * height as usize];
    let sw = reg.width();
    let rows: Vec<Vec<f64>> = (region.y0..region.y1)
        .into_par_iter()
        .map(|py| {
            (region.x0..region.x1)
                .map(|px| {
                    let c0 = (px as i64 * k.n as i64 - k.off - reg.c0) as usize;
                    let r0 = (py as i64 * k.n as i64 - k.off - reg.k0) as usize;
                    let mut sum = 0.0;
                    for j in 0..k.size {
                        let row = &i[(r0 + j) * sw + c0..(r0 + j) * sw + c0 + k.size];
                        let wrow = &k.wf[j * k.size..(j + 1) * k.size];
                        sum += row.iter().zip(wrow).map(|(a, b)| a * b).sum::<f64>();
                    }
                    sum * scale
                })
                .collect()
        })
        .collect();
    for (py, r) in (region.y0..region.y1).zip(rows) {
        let base = py as usize * width as usize + region.x0 as usize;
        acc[base..base + r.len()].copy_from_slice(&r);
    }
    for pt in points {
        for (px, py, s) in point_weights(pt, reg, region, k, |e| k.wf[e]) {
            acc[py as usize * width as usize + px as usize] += pt.i * s * scale;
        }
    }
    acc
}
