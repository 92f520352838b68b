//! The configured dither unit ([`Dither`]): dispatch to the ordered or error-diffusion
//! model, fixed and float, its hardware cost, and the temporal period-mean check.

use super::diffusion::{FsParams, floyd_steinberg, floyd_steinberg_f64};
use super::mask::Mask;
use super::ordered::{Input, Run, apply_ordered_f64, apply_ordered_from, ordered_code};
use crate::config::DitherCfg;
use crate::fixed::{QFormat, SignalStats};
use crate::stage::{Cost, MemImage, Memory, Unit};
use std::sync::Arc;

/// Name of the mask ROM.
pub const MASK_ROM: &str = "dither mask ROM";
/// Name of the error-diffusion line buffer.
pub const ERROR_LINE: &str = "dither error line buffer";
use serde::Serialize;

/// A configured dither: kind, mask and arithmetic.
#[derive(Clone, Debug)]
pub struct Dither {
    /// The configuration.
    pub cfg: DitherCfg,
    /// The mask (ordered and blue noise).
    pub mask: Option<Mask>,
}

impl Dither {
    /// Builds the dither (generates the mask).
    pub fn new(cfg: &DitherCfg) -> Self {
        Self {
            cfg: cfg.clone(),
            mask: Mask::of(cfg),
        }
    }

    /// Fixed model: `s`-fraction-bit codes to codes in `0..=omax`; returns the error stats
    /// (error diffusion) or the saturation count as a signal.
    pub fn apply(
        &self,
        x: &[u32],
        width: u32,
        height: u32,
        s: u32,
        omax: u32,
        out: &mut [u32],
    ) -> SignalStats {
        self.apply_with(x, (width, height), s, omax, out, Run::Parallel)
    }

    /// [`Dither::apply`] run as `run` says (error diffusion is serial anyway): the same codes
    /// and statistics.
    pub fn apply_with(
        &self,
        x: &[u32],
        (width, height): (u32, u32),
        s: u32,
        omax: u32,
        out: &mut [u32],
        run: Run,
    ) -> SignalStats {
        self.apply_from(Input::Codes(x), (width, height), s, omax, out, run)
    }

    /// [`Dither::apply_with`] on an [`Input`] (frame codes through a LUT: an ordered dither
    /// looks them up row by row in its own pass; error diffusion looks the plane up first).
    pub fn apply_from(
        &self,
        x: Input,
        (width, height): (u32, u32),
        s: u32,
        omax: u32,
        out: &mut [u32],
        run: Run,
    ) -> SignalStats {
        match &self.mask {
            Some(m) => {
                let sat = apply_ordered_from(x, width, s, omax, m, self.frame(), out, run);
                ordered_stats(omax, sat)
            }
            None => floyd_steinberg(
                &x.to_codes(run == Run::Portable),
                width,
                height,
                &FsParams {
                    s,
                    omax,
                    error: self.cfg.error,
                    serpentine: self.cfg.serpentine,
                },
                out,
            ),
        }
    }

    /// Float reference on real values in output LSBs.
    pub fn apply_f64(&self, v: &[f64], width: u32, height: u32, omax: u32) -> Vec<u32> {
        match &self.mask {
            Some(m) => apply_ordered_f64(v, width, omax, m, self.frame()),
            None => floyd_steinberg_f64(v, width, height, omax, self.cfg.serpentine),
        }
    }

    fn frame(&self) -> u32 {
        if self.cfg.temporal { self.cfg.frame } else { 0 }
    }

    /// The mask ROM's contents (ordered dithers): the ranks, row-major.
    pub fn images(&self) -> Vec<MemImage> {
        match &self.mask {
            Some(m) => vec![MemImage::table(
                MASK_ROM,
                m.bits.max(1),
                Arc::new(m.rank.clone()),
            )],
            None => vec![],
        }
    }

    /// Cost of the dither unit for an image `width` pixels wide with `s` input fraction
    /// bits and `out_bits` output bits.
    pub fn cost(&self, width: u32, s: u32, out_bits: u32) -> Cost {
        match &self.mask {
            Some(m) => {
                let mut adders = vec![
                    Unit::adder("threshold add", 1, out_bits + s + m.bits + 1),
                    Unit::adder("saturate", 1, out_bits + 1),
                ];
                if self.cfg.temporal {
                    adders.push(Unit::adder("frame counter", 1, m.bits));
                    adders.push(Unit::adder("mask offset", 2, m.bits / 2));
                }
                Cost::new(
                    vec![Memory::rom(MASK_ROM, m.period() as u64, m.bits.max(1))],
                    adders,
                    vec![],
                )
            }
            None => {
                let eb = self.cfg.error.total_bits();
                Cost::new(
                    vec![Memory::ram(ERROR_LINE, width as u64 + 2, eb)],
                    vec![
                        Unit::adder("pixel + error", 1, out_bits + self.cfg.error.frac_bits + 2),
                        Unit::adder("round and saturate", 1, out_bits + 1),
                        Unit::adder("3r, 5r, 7r (shift-add)", 3, eb + 3),
                        Unit::adder("error accumulate", 4, eb),
                    ],
                    vec![],
                )
            }
        }
    }
}

/// The ordered dither's signal: the output format and its saturations.
fn ordered_stats(omax: u32, sat: u64) -> SignalStats {
    let mut st = SignalStats::new(
        "dither.out",
        QFormat::new(false, 32 - omax.leading_zeros(), 0),
    );
    st.add_overflows(sat);
    st
}

/// The temporal-dither check: a static frame over one period of the mask.
#[derive(Clone, Debug, Serialize)]
pub struct PeriodMean {
    /// Frames in the period.
    pub period: u32,
    /// Pixels checked.
    pub pixels: u64,
    /// Pixels whose period mean equals their dither input exactly.
    pub exact_pixels: u64,
    /// Largest |period mean - input| in output LSBs.
    pub max_abs_error: f64,
    /// Whether every pixel is exact.
    pub exact: bool,
}

/// Runs the fixed dither on a static frame for every frame of the period and compares each
/// pixel's mean with its input. Over one period the offsets visit every mask position once,
/// so every pixel sees every rank once whatever its position: the period sum depends on the
/// input value alone, and pixels with the same input share one run.
pub fn period_mean(d: &Dither, x: &[u32], s: u32, omax: u32) -> Option<PeriodMean> {
    let m = d.mask.as_ref()?;
    if !d.cfg.temporal {
        return None;
    }
    let period = m.period();
    let mut res = PeriodMean {
        period,
        pixels: x.len() as u64,
        exact_pixels: 0,
        max_abs_error: 0.0,
        exact: true,
    };
    // One run per distinct input: frame t puts rank t on the pixel (the offset of frame t is
    // the position of rank t, and a shifted mask is a permutation of the ranks).
    let vmax = x.iter().copied().max().unwrap_or(0) as usize;
    let mut memo = vec![u64::MAX; vmax + 1];
    for &v in x {
        let sum = &mut memo[v as usize];
        if *sum == u64::MAX {
            *sum = (0..period)
                .map(|r| ordered_code(v, s, r, m.bits).min(omax as u64))
                .sum();
        }
        // Exact comparison: sum * 2^s == v * period.
        if (*sum << s) == v as u64 * period as u64 {
            res.exact_pixels += 1;
        } else {
            res.exact = false;
            let e = (*sum as f64 / period as f64 - v as f64 / (1u64 << s) as f64).abs();
            res.max_abs_error = res.max_abs_error.max(e);
        }
    }
    Some(res)
}
