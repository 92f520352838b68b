//! `dof.kind = "luminance"`: the luminance-aware blur (docs/reference.md §4, after Zhao et al.
//! 2012 §3.3-3.4; docs/dof-luminance.md) in fixed point, with its float reference.
//!
//! A grey frame is one intensity channel, so a pixel's luminance is its code; a colour
//! frame's luminance is the BT.601 `Y` of its R, G and B ([`luma`]), whose pre-blurred image
//! gives the bleed weights of every channel (each channel is pre-blurred, bled with those
//! weights and blended by itself). Per pixel:
//! 1. **mean pre-blur** `P`: the mean of the `(2r+1)^2` window inside the image (border
//!    renormalised by the in-image count), `r = dof.luminance.radius`;
//! 2. **bleed** (eq. 8): over the 8 neighbours i, `Δ_i = P_c - P_i`; a neighbour counts only
//!    when brighter (`Δ_i < 0`), with the weight `|Δ_i| / sum |Δ_j|`:
//!    `blur = sum |Δ_i| P_i / sum |Δ_i|`, and `blur = P_c` when no neighbour is brighter;
//! 3. **blend** (eq. 9): `out = x + alpha (blur - x)` with `x` the sharp frame code and
//!    `alpha` the normalised blur factor of the pixel's depth: `min(1, C / C_max)`, C the thin
//!    lens's circle of confusion there and `C_max` the larger of those at the near and far
//!    clip planes (docs/reference.md §2b), times `focus_scale` (2/3) inside the depth-of-field
//!    band `[U - deep, U + deep]`, the factor ramping linearly back to 1 over `ramp` pixels
//!    of circle of confusion beyond the band's edge.
//!
//! **Fixed point** ([`fixed`]): the window sum `UQ<pre_bits>.0` (SAT or ERROR, signal
//! `dof.lum.pre`); `P` and `blur` in the frame format with `guard_bits` more fraction bits,
//! each one integer divide rounded with `dof.quant` ([`div_round`]); exact integer weights
//! and sums in between; alpha `UQ1.<alpha_bits>` from a ROM indexed by the top
//! `alpha_rom_bits` of the depth code plus an entry for infinity, rounded to nearest
//! ([`AlphaMap`]); the blend exact and rounded with `dof.quant` to the frame format, SAT
//! (signal `dof.lum.out`). A flat field is bit-identical at any depths (`P = blur = x`).
//!
//! **Float reference** ([`float`]): the same steps in f64 with exact divides and the exact
//! alpha of each depth code.
//!
//! Files: `alpha` (alpha per depth code, the ROM), `luma` (the luminance of a colour frame),
//! `fixed`, `float`, `cost` (cost, the ROM image).

mod alpha;
mod cost;
mod fixed;
mod float;
mod luma;

pub use alpha::{AlphaMap, ROM_QUANT};
pub use cost::{
    ALPHA_LINES, ALPHA_ROM, BLEED_LINES, LUMA_BLEED_LINES, LUMA_PRE_LINES, PRE_LINES, alpha_image,
    cost,
};
pub use fixed::{
    LumParams, LumWork, NEIGHBOURS, bleed_fixed, bleed_fixed_by, blend_fixed, div_round,
    luminance_colour_fixed, luminance_fixed, pre_blur_fixed,
};
pub use float::{bleed_f64, bleed_f64_by, luminance_colour_f64, luminance_f64, pre_blur_f64};
pub use luma::{BT601, Luma};

use super::LensMap;
use super::method::Method;
use crate::error::Result;
use crate::stage::accumulate::Frame;
use crate::stage::{Cost, Cx, Facts, MemImage, TokenKind, Tokens};
use serde::Serialize;
use std::sync::Arc;

/// The luminance-aware method; on a colour frame with the frame's luminance.
#[derive(Default)]
pub struct Luminance {
    /// The luminance of a colour frame (`None`: a grey frame, its own luminance).
    pub luma: Option<Arc<Luma>>,
}

/// What the fixed model leaves: the alpha map (and ROM) of the run's lens and, for a
/// colour frame, its luminance.
#[derive(Clone, Debug)]
pub struct LumPlan {
    /// Alpha per depth code.
    pub alpha: AlphaMap,
    /// The colour frame's luminance.
    pub luma: Option<Arc<Luma>>,
}

impl LumPlan {
    /// The exact alpha of every pixel of `frame`.
    fn alpha_f64(&self, frame: &Frame, lens: &LensMap) -> Vec<f64> {
        frame
            .depth
            .iter()
            .map(|&k| self.alpha.alpha_f64(lens, k))
            .collect()
    }

    /// The float reference of a colour frame's channel: `value` (frame LSBs) with the
    /// luminance `lum` (of the float frames, or of the fixed codes as reals for the
    /// stage-local comparison).
    pub fn colour_f64(
        &self,
        cx: &Cx,
        frame: &Frame,
        value: &[f64],
        lum: &[f64],
        lens: &LensMap,
    ) -> Vec<f64> {
        let a = self.alpha_f64(frame, lens);
        let (w, h) = (frame.width as usize, frame.height as usize);
        luminance_colour_f64(value, lum, &a, w, h, cx.hw.dof.luminance.radius as usize)
    }
}

/// Alpha over a frame, for the report.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct AlphaStats {
    /// `C_max`, pixels.
    pub c_max_px: f64,
    /// Entries of the ROM (including infinity's).
    pub rom_entries: usize,
    /// Smallest alpha read.
    pub min: f64,
    /// Largest alpha read.
    pub max: f64,
    /// Mean alpha read.
    pub mean: f64,
    /// Pixels with alpha 0 (left sharp).
    pub zero_pixels: u64,
    /// Pixels whose depth lies in the depth-of-field band (alpha scaled by `focus_scale`).
    pub band_pixels: u64,
    /// Pixels on the ramp beyond the band (factor strictly between `focus_scale` and 1).
    pub ramp_pixels: u64,
    /// Largest |ROM alpha - exact alpha| over the frame's pixels.
    pub max_rom_error: f64,
}

impl AlphaStats {
    /// Statistics of the alpha codes `codes` read for the depth codes `keys`.
    pub fn of(alpha: &AlphaMap, lens: &LensMap, keys: &[u32], codes: &[u32]) -> Self {
        let one = f64::from(alpha.one());
        let mut s = Self {
            c_max_px: alpha.c_max,
            rom_entries: alpha.rom.len(),
            min: f64::INFINITY,
            max: 0.0,
            ..Self::default()
        };
        let mut sum = 0.0;
        for (&k, &c) in keys.iter().zip(codes) {
            let a = f64::from(c) / one;
            s.min = s.min.min(a);
            s.max = s.max.max(a);
            sum += a;
            s.zero_pixels += u64::from(c == 0);
            let f = alpha.factor(lens, k);
            if AlphaMap::in_band(lens, k) {
                s.band_pixels += 1;
            } else if f < 1.0 {
                s.ramp_pixels += 1;
            }
            s.max_rom_error = s.max_rom_error.max((a - alpha.alpha_f64(lens, k)).abs());
        }
        if !keys.is_empty() {
            s.mean = sum / keys.len() as f64;
        } else {
            s.min = 0.0;
        }
        s
    }
}

impl Method for Luminance {
    type Plan = LumPlan;

    fn fixed(&self, cx: &Cx, frame: &Frame, lens: &LensMap) -> Result<(LumPlan, Vec<u32>, Facts)> {
        let (w, h) = (frame.width as usize, frame.height as usize);
        let p = LumParams::of(&cx.hw.dof, cx.hw.accumulate.frame.format);
        let alpha = AlphaMap::new(lens, &cx.hw.dof.luminance);
        let codes: Vec<u32> = frame.depth.iter().map(|&k| alpha.code(k)).collect();
        let (out, work, luma_work) = match &self.luma {
            None => {
                let (out, work) = luminance_fixed(&frame.acc, &codes, w, h, &p)?;
                (out, work, None)
            }
            Some(y) => {
                let (out, work, lw) =
                    luminance_colour_fixed(&frame.acc, &y.fixed, y.format, &codes, w, h, &p)?;
                (out, work, Some(lw).filter(|_| y.charges()))
            }
        };
        let mut facts = Facts {
            work: vec![
                ("pixels", work.pixels),
                ("pre_adds", work.pre_adds),
                ("macs", work.macs),
                ("divides", work.divides),
                ("rom_reads", work.rom_reads),
                ("bleeding", work.bleeding),
            ],
            ..Facts::default()
        };
        facts.note("alpha", AlphaStats::of(&alpha, lens, &frame.depth, &codes));
        facts.signals = vec![work.pre, work.mean, work.blur, work.out];
        if let Some(lw) = luma_work {
            // The shared luminance unit: three constant multiplies per pixel and its
            // pre-blur, counted by lane 0.
            facts.work.push(("luma_macs", 3 * work.pixels));
            facts.work.push(("luma_pre_adds", lw.pre_adds));
            facts.signals.extend([lw.pre, lw.mean]);
        }
        let luma = self.luma.clone();
        Ok((LumPlan { alpha, luma }, out, facts))
    }

    fn float(
        &self,
        cx: &Cx,
        plan: &LumPlan,
        frame: &Frame,
        value: &[f64],
        lens: &LensMap,
    ) -> Vec<f64> {
        let a = plan.alpha_f64(frame, lens);
        let (w, h) = (frame.width as usize, frame.height as usize);
        luminance_f64(value, &a, w, h, cx.hw.dof.luminance.radius as usize)
    }

    /// One token per screen row: two pass outputs per pixel (the pre-blur's and the bleed
    /// and blend's), so the default two lanes stream one pixel per clock.
    fn tokens(&self, cx: &Cx, _: &LumPlan) -> Tokens {
        let g = &cx.layout.grid;
        Tokens {
            kind: TokenKind::Row,
            item: "pass outputs",
            items: vec![2 * u64::from(g.width); g.height as usize],
            port_bits: vec![],
            rows: vec![],
            stream: None,
        }
    }

    fn cost(&self, cx: &Cx, plan: &LumPlan, _: &LensMap) -> Cost {
        let p = LumParams::of(&cx.hw.dof, cx.hw.accumulate.frame.format);
        cost(
            &plan.alpha,
            &p,
            plan.luma.as_deref(),
            u64::from(cx.layout.grid.width),
        )
    }

    fn memories(&self, _: &Cx, plan: &LumPlan, _: &LensMap) -> Vec<MemImage> {
        vec![alpha_image(&plan.alpha)]
    }
}
