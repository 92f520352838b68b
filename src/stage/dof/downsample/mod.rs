//! `dof.kind = "downsample"`: downsample-and-blend depth of field (docs/reference.md §4,
//! docs/dof-downsample.md), in fixed point with its f64 reference.
//!
//! **Steps.** (1) The frame (linear codes, one depth code per pixel) is averaged over
//! `factor x factor` blocks into the small image (`1/16` of the area for the default
//! factor 4), with `guard_bits` extra fraction bits. (2) The small image is blurred by a
//! separable Gaussian in the layered method's mask convention (`exp(-x^2/sigma^2)`, half-size
//! `ceil(sqrt(-ln k) sigma)`, taps `UQ0.<coef_bits>` summing to `2^coef_bits`) with
//! `sigma = sigma_max / factor` small pixels, `sigma_max` the largest `|sigma|` of the
//! frame's depth codes: the blurred image stands for the frame's largest blur. (3) Every
//! pixel gathers its centre and `taps` Poisson-disc taps scaled by its CoC radius
//! `r = |sigma|`; each tap mixes the full-resolution value at its pixel and the bilinear
//! sample of the blurred image at its position by the tap's own blend factor
//! `beta = |sigma| / sigma_max`; a tap in front of the centre that is sharper than it is
//! down-weighted (`leak_guard`), and the weighted sum is divided by the weight sum.
//!
//! All coordinates clamp to the image (the small image's and the Gaussian's edge samples
//! repeat) except the sharp taps: a tap outside the frame is dropped (its weight is 0).
//!
//! Files: `plan` (the frame's largest blur, the Gaussian, the blend ROM, the [`Blur`]
//! trait), `poisson` (the tap offsets), `small` (box sums and Gaussian passes shared by both
//! models), `fixed` (the datapath), `float` (the reference), `recon` (the cubic
//! reconstructions of the blurred image, `dof.downsample.reconstruction`), `cost` (cost, ROM
//! images, tokens).

mod cost;
mod fixed;
mod float;
mod plan;
mod poisson;
mod recon;
mod small;

pub use cost::{
    BLEND_ROM, BLURRED, BOX_ROW, COEF_ROM as DOWN_COEF_ROM, LINE_BUFFERS as DOWN_LINE_BUFFERS,
    OFFSET_ROM, WINDOW, cost as downsample_cost, memories as downsample_memories,
    tokens as downsample_tokens,
};
pub use fixed::{DownWork, OverflowAt, downsample_fixed, small_format, tap_weight, tap_weight_f64};
pub use float::downsample_f64;
pub use plan::{Blur, DownPlan, ROM_QUANT, plan_downsample};
pub use poisson::{Poisson, poisson_disc};

use super::method::{Method, half_size_error};
use super::{LensMap, overflow_signal_in};
use crate::error::{Error, Result};
use crate::stage::accumulate::Frame;
use crate::stage::{Cost, Cx, Facts, MemImage, Tokens};

/// The downsample-and-blend method.
pub struct Downsample;

impl Method for Downsample {
    type Plan = DownPlan;

    fn fixed(&self, cx: &Cx, frame: &Frame, lens: &LensMap) -> Result<(DownPlan, Vec<u32>, Facts)> {
        let hw = cx.hw;
        let p = &hw.dof;
        let frame_fmt = hw.accumulate.frame.format;
        let (w, h) = (frame.width as usize, frame.height as usize);
        let mut plan =
            plan_downsample(&frame.depth, w, h, lens, p).map_err(|msg| half_size_error(cx, msg))?;
        let (out, mut work) = downsample_fixed(&frame.acc, &frame.depth, &plan, p, frame_fmt)
            .map_err(|(signal, format, value)| Error::Overflow {
                signal,
                format: format.to_string(),
                value,
                min: format.min_code(),
                max: format.max_code(),
            })?;
        plan.blurred = std::sync::Arc::new(std::mem::take(&mut work.blurred));
        let mut facts = Facts {
            work: vec![
                ("pixels", frame.acc.len() as u64),
                ("small_pixels", work.small_pixels),
                ("macs", work.macs),
                ("taps", work.taps),
                ("divides", work.divides),
                ("passthrough", work.passthrough),
            ],
            signals: vec![
                work.small,
                work.blur,
                overflow_signal_in(
                    "dof.down.tap",
                    small_format(frame_fmt, p.downsample.guard_bits),
                    work.tap_overflows,
                ),
                work.out,
            ],
            ..Facts::default()
        };
        facts.note(
            "downsample",
            serde_json::json!({
                "factor": plan.factor,
                "small_image": [plan.small_width, plan.small_height],
                "sigma_max_px": plan.sigma_max,
                "sigma_max_code_px": plan.sigma_max_code as f64 / (1u64 << super::SIGMA_FRAC) as f64,
                "scale_px": plan.scale,
                "scale_code_px": plan.scale_code as f64 / (1u64 << super::SIGMA_FRAC) as f64,
                "small_sigma": plan.small_sigma,
                "small_half_size": plan.m,
                "reach_px": plan.reach,
                "blend_rom_entries": plan.blend_rom.len(),
                "taps": &plan.taps,
            }),
        );
        Ok((plan, out, facts))
    }

    fn float(
        &self,
        cx: &Cx,
        plan: &DownPlan,
        frame: &Frame,
        value: &[f64],
        lens: &LensMap,
    ) -> Vec<f64> {
        downsample_f64(value, &frame.depth, plan, lens, &cx.hw.dof)
    }

    fn tokens(&self, _: &Cx, plan: &DownPlan) -> Tokens {
        downsample_tokens(plan)
    }

    fn cost(&self, cx: &Cx, plan: &DownPlan, _: &LensMap) -> Cost {
        downsample_cost(
            plan,
            &cx.hw.dof,
            cx.hw.accumulate.frame.format,
            cx.hw.visibility.z.format.total_bits(),
        )
    }

    fn memories(&self, cx: &Cx, plan: &DownPlan, _: &LensMap) -> Vec<MemImage> {
        downsample_memories(plan, &cx.hw.dof, cx.hw.accumulate.frame.format)
    }
}
