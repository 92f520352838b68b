//! Ordered dithering with a threshold [`Mask`]: the exact fixed-point rule of one value, its
//! float reference, and the whole-image passes (see the [`dither`](super) module docs for
//! the arithmetic).

use super::mask::Mask;
use rayon::prelude::*;

/// Ordered dither of one value (fixed): `floor(x / 2^s + (m + 0.5) / 2^b)`, unsaturated.
#[inline]
pub fn ordered_code(x: u32, s: u32, rank: u32, bits: u32) -> u64 {
    (((x as u64) << (bits + 1)) + (((2 * rank + 1) as u64) << s)) >> (s + bits + 1)
}

/// Ordered dither of one value (float): `floor(v + (m + 0.5) / 2^b)`, unsaturated.
#[inline]
pub fn ordered_f64(v: f64, rank: u32, bits: u32) -> f64 {
    (v + (rank as f64 + 0.5) / (1u64 << bits) as f64).floor()
}

/// Applies an ordered mask to a `width`-wide image of `s`-fraction-bit codes; returns the
/// codes saturated to `omax` and the number of saturations.
pub fn apply_ordered(
    x: &[u32],
    width: u32,
    s: u32,
    omax: u32,
    mask: &Mask,
    frame: u32,
    out: &mut [u32],
) -> u64 {
    let off = mask.offset(frame);
    let w = width.max(1) as usize;
    out.par_chunks_mut(w)
        .zip(x.par_chunks(w))
        .enumerate()
        .map(|(y, (o, xr))| {
            let mut sat = 0;
            for (i, (o, &v)) in o.iter_mut().zip(xr).enumerate() {
                let c = ordered_code(v, s, mask.at(i as u32, y as u32, off), mask.bits);
                if c > omax as u64 {
                    sat += 1;
                }
                *o = c.min(omax as u64) as u32;
            }
            sat
        })
        .sum()
}

/// Float reference of [`apply_ordered`] on real values (output LSBs).
pub fn apply_ordered_f64(v: &[f64], width: u32, omax: u32, mask: &Mask, frame: u32) -> Vec<u32> {
    let off = mask.offset(frame);
    let w = width.max(1) as usize;
    v.par_iter()
        .enumerate()
        .map(|(i, &v)| {
            let r = mask.at((i % w) as u32, (i / w) as u32, off);
            ordered_f64(v, r, mask.bits).clamp(0.0, omax as f64) as u32
        })
        .collect()
}
