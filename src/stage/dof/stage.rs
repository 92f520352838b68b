//! The dof stage through the contract: the thin lens's blur per depth code, then the method
//! `dof.kind` names ([`super::method::Method`]: layered, luminance-aware or
//! downsample-and-blend) on the finished frame, its float reference (the same method in f64;
//! on request the per-pixel scatter and, for the layered method, the layer theorem check),
//! the stage-local comparison, the method's cycle-model tokens, cost and ROMs.

use super::downsample::{DownPlan, Downsample};
use super::layered::Layered;
use super::luminance::{LumPlan, Luma, Luminance};
use super::method::{Method, n2};
use super::potentiate::FramePotentiation;
use super::{
    DepthImage, LayerPlan, LensMap, RegionError, SIGMA_FRAC, additive_layered, depth_edge_band,
    difference_degree, edge_band, layered_f64_key, local_error, per_pixel_scatter, region_error,
    weber_linear,
};
use crate::config::{CodingKind, DofKind, HwConfig};
use crate::error::Result;
use crate::fixed::QFormat;
use crate::fnv::Fnv;
use crate::scene::{Lens, Scene};
use crate::stage::accumulate::Frame;
use crate::stage::taps::{ChannelFrames, FrameCoding, FrameTap, Taps};
use crate::stage::{
    Cost, Cx, Facts, LocalError, MemImage, Need, Notes, Pool, Stage, StageId, Tokens, memo,
};
use rayon::prelude::*;
use std::sync::Arc;

/// The plan of the configured method.
pub enum MethodPlan {
    /// `dof.kind = "layered"`.
    Layered(LayerPlan),
    /// `dof.kind = "luminance"`.
    Luminance(LumPlan),
    /// `dof.kind = "downsample"`.
    Downsample(DownPlan),
}

/// Runs `$body` with `$m` bound to the method and `$plan` to its plan.
macro_rules! with_method {
    ($mp:expr, |$m:ident, $plan:ident| $body:expr) => {
        match $mp {
            MethodPlan::Layered($plan) => {
                let $m = &Layered;
                $body
            }
            MethodPlan::Luminance($plan) => {
                let $m = &Luminance::default();
                $body
            }
            MethodPlan::Downsample($plan) => {
                let $m = &Downsample;
                $body
            }
        }
    };
}

/// What the fixed model leaves: the lens, the method's plan, the linear frame it blurred
/// and, after a log-coded frame, the potentiation LUT that made it linear.
pub struct Blurred {
    lens: LensMap,
    plan: MethodPlan,
    input: Arc<FrameTap>,
    pot: Option<FramePotentiation>,
}

impl Blurred {
    /// The float method on `value` with the input frame's depth and coverage; a colour
    /// frame's luminance-aware blur takes the luminance of the float frames, or with `local`
    /// that of the fixed input codes.
    fn float(&self, cx: &Cx, value: &[f64], local: bool) -> Vec<f64> {
        if let MethodPlan::Luminance(plan) = &self.plan
            && let Some(y) = &plan.luma
        {
            let lum = if local { &y.local } else { &y.float };
            return plan.colour_f64(cx, &self.input.frame, value, lum, &self.lens);
        }
        with_method!(&self.plan, |m, plan| m.float(
            cx,
            plan,
            &self.input.frame,
            value,
            &self.lens
        ))
    }
}

/// The dof stage.
pub struct Dof;

fn run<M: Method>(
    m: &M,
    cx: &Cx,
    frame: &Frame,
    lens: &LensMap,
    wrap: impl FnOnce(M::Plan) -> MethodPlan,
) -> Result<(MethodPlan, Vec<u32>, Facts)> {
    let (plan, out, facts) = m.fixed(cx, frame, lens)?;
    Ok((wrap(plan), out, facts))
}
impl Stage for Dof {
    type Fixed = Blurred;

    fn recycle(&self, b: Blurred, pool: &Pool) {
        if let MethodPlan::Layered(plan) = b.plan {
            pool.give(plan.index);
        }
    }

    fn id(&self) -> StageId {
        StageId::Dof
    }

    fn plan(&self, scene: &Scene, hw: &HwConfig) -> Result<Need> {
        let Lens::ThinLens {
            lens_radius,
            focus_distance,
            ..
        } = scene.camera.lens
        else {
            return Ok(Need::no("pinhole camera: everything is in focus"));
        };
        let method = match hw.dof.kind {
            DofKind::Layered => format!("layered blur of the frame, threshold P = {}", hw.dof.p),
            DofKind::Luminance => format!(
                "luminance-aware blur of the frame, pre-blur radius {}",
                hw.dof.luminance.radius
            ),
            DofKind::Downsample => format!(
                "downsample by {0}x{0}, Gaussian, blend by {1} Poisson-disc taps in the CoC",
                hw.dof.downsample.factor, hw.dof.downsample.taps
            ),
        };
        let log = if hw.coding.kind == CodingKind::LogAdd {
            " (the log-coded frame potentiated into it by a LUT)"
        } else {
            ""
        };
        Ok(Need::yes(format!(
            "thin lens (radius {lens_radius}, focus at {focus_distance}, sigma {}): {method}{log}",
            hw.dof.sigma.name()
        )))
    }

    fn key(&self, cx: &Cx) -> serde_json::Value {
        serde_json::json!({
            "dof": cx.hw.section("dof"),
            "display": cx.scene.display,
        })
    }

    fn fixed(&self, cx: &Cx, taps: &mut Taps) -> Result<(Blurred, Facts)> {
        let hw = cx.hw;
        let stored = taps
            .fixed
            .frame
            .clone()
            .expect("accumulate wrote the frame");
        let (input, pot) = linear(&stored, hw.accumulate.frame.format);
        let frame = &input.frame;
        let lens = LensMap::of(cx.scene, hw, frame.height)
            .expect("the plan runs dof for a thin lens only");
        // The output frame's depth and coverage are the input's: copied while the layers
        // run (the buffers are taken first, so the pool hands them out in a fixed order).
        let (mut depth, mut coverage) = (
            cx.pool.take(frame.depth.len()),
            cx.pool.take(frame.coverage.len()),
        );
        let channels = taps.channels.as_deref();
        let (blurred, ()) = rayon::join(
            || match hw.dof.kind {
                DofKind::Layered => run(&Layered, cx, frame, &lens, MethodPlan::Layered),
                DofKind::Luminance => {
                    let g = hw.dof.luminance.guard_bits;
                    let luma = channels.map(|ch| Arc::new(luma_of(ch, g)));
                    run(&Luminance { luma }, cx, frame, &lens, MethodPlan::Luminance)
                }
                DofKind::Downsample => run(&Downsample, cx, frame, &lens, MethodPlan::Downsample),
            },
            || {
                depth.extend_from_slice(&frame.depth);
                coverage.extend_from_slice(&frame.coverage);
            },
        );
        let (plan, out, mut facts) = blurred?;
        if let Some(pot) = &pot {
            facts.work.push(("potentiations", frame.acc.len() as u64));
            facts.signals.push(pot.stats.clone());
        }
        let (sig_min, sig_max, coc_max, in_focus) = blur_facts(&frame.depth, &lens);
        facts.note("lens", &lens);
        facts.note(
            "object_sigma_px",
            serde_json::json!({"min": sig_min, "max": sig_max, "background": lens.sigma_f64(u32::MAX)}),
        );
        facts.note("object_coc_max_px", coc_max);
        facts.note("object_pixels_in_focus", in_focus);
        let next = Frame {
            acc: out,
            depth,
            coverage,
            ..*frame
        };
        taps.fixed.frame = Some(Arc::new(FrameTap {
            frame: next,
            coding: FrameCoding::Linear,
        }));
        Ok((
            Blurred {
                lens,
                plan,
                input,
                pot,
            },
            facts,
        ))
    }

    /// (1) The same method in f64 on the float frame; with `dof_reference` also (2) the
    /// per-pixel scatter of the fixed input frame against the fixed output (split into the
    /// depth-edge band and the interior) and, for the layered method, the layer theorem's
    /// check.
    fn float(&self, cx: &Cx, b: &Blurred, taps: &mut Taps, notes: &mut Notes) -> Result<()> {
        let value = taps.float.frame();
        let (new_ref, content) = match (&b.plan, &b.pot) {
            // The layered float on a linear input frame is memoised by its input and the
            // plan's digest: a sweep of the datapath's widths runs it once per plan, and
            // what the next stages derive from it (the gamma curve's powers, the contour
            // metric's ideal image) once as well.
            (MethodPlan::Layered(plan), None) => {
                let key = Fnv::new()
                    .str("dof float")
                    .u64(cx.input_key)
                    .u64(u64::from(n2(cx)))
                    .u64(layered_f64_key(plan))
                    .finish();
                (memo(cx.memo, key, || b.float(cx, value, false)), Some(key))
            }
            _ => (Arc::new(b.float(cx, value, false)), None),
        };
        taps.float.frame_content = content;
        if cx.opts.dof_reference {
            notes.insert(
                "per_pixel_reference".into(),
                per_pixel_notes(cx, b, &taps.fixed.frame().frame.acc),
            );
        }
        taps.float.frame = Some(new_ref);
        Ok(())
    }

    /// The same method in f64 on the fixed input frame against the fixed output, code by
    /// code (and through the display: note `weber_vs_float_method`).
    fn local(
        &self,
        cx: &Cx,
        b: &Blurred,
        _: &Taps,
        out: &Taps,
        notes: &mut Notes,
    ) -> Option<LocalError> {
        let accf: Vec<f64> = b.input.frame.acc.iter().map(|&v| v as f64).collect();
        let local = b.float(cx, &accf, true);
        let white = cx.hw.accumulate.frame.format.max_code() as f64;
        let o = &out.fixed.frame().frame.acc;
        let outf: Vec<f64> = o.iter().map(|&v| v as f64).collect();
        notes.insert(
            "weber_vs_float_method".into(),
            serde_json::to_value(weber_linear(&outf, &local, white, &cx.scene.display))
                .unwrap_or_default(),
        );
        Some(local_error(o, &local, white))
    }

    /// The luminance-aware method weighs a colour frame's blur by the luminance of all
    /// three channels.
    fn reads_channels(&self, cx: &Cx) -> bool {
        cx.hw.dof.kind == DofKind::Luminance
    }

    fn tokens(&self, cx: &Cx, b: &Blurred) -> Option<Tokens> {
        Some(with_method!(&b.plan, |m, plan| m.tokens(cx, plan)))
    }

    fn cost(&self, cx: &Cx, b: &Blurred) -> Cost {
        let c = with_method!(&b.plan, |m, plan| m.cost(cx, plan, &b.lens));
        match &b.pot {
            Some(pot) => c.merge(pot.cost()),
            None => c,
        }
    }

    fn memories(&self, cx: &Cx, b: &Blurred, _: &Taps) -> Vec<MemImage> {
        let mut m = with_method!(&b.plan, |m, plan| m.memories(cx, plan, &b.lens));
        m.extend(b.pot.as_ref().map(FramePotentiation::image));
        m
    }
}

/// The frame `stored` with linear codes of the word `format`: a log-coded frame
/// potentiated by a LUT (returned for its cost and ROM image).
fn linear(stored: &Arc<FrameTap>, format: QFormat) -> (Arc<FrameTap>, Option<FramePotentiation>) {
    match &stored.coding {
        FrameCoding::Linear => (stored.clone(), None),
        FrameCoding::Log(add) => {
            let pot = FramePotentiation::build(add, format);
            let mut frame = stored.frame.clone();
            frame.acc = pot.apply(&frame.acc);
            let linear = FrameTap {
                frame,
                coding: FrameCoding::Linear,
            };
            (Arc::new(linear), Some(pot))
        }
    }
}

/// The luminance of a colour render's channel frames (each made linear first), with `g`
/// guard bits.
fn luma_of(ch: &ChannelFrames, g: u32) -> Luma {
    let codes: Vec<Arc<FrameTap>> = (0..3)
        .map(|c| linear(&ch.fixed[c], ch.formats[c]).0)
        .collect();
    Luma::of(
        ch.lane,
        std::array::from_fn(|c| codes[c].frame.acc.as_slice()),
        ch.float
            .as_ref()
            .map(|f| std::array::from_fn(|c| f[c].as_slice())),
        std::array::from_fn(|c| ch.formats[c]),
        g,
    )
}

/// The per-pixel scatter of the fixed input frame (every pixel spread with the mask of its
/// own depth, no occlusion) against the fixed output; for the layered method also the
/// theorem's additive layered sum against it.
fn per_pixel_notes(cx: &Cx, b: &Blurred, out: &[u32]) -> serde_json::Value {
    let frame = &b.input.frame;
    let p = &cx.hw.dof;
    let (w, h) = (frame.width as usize, frame.height as usize);
    let accf: Vec<f64> = frame.acc.iter().map(|&v| v as f64).collect();
    let fimg = DepthImage::of_frame(frame, &accf, n2(cx));
    let outf: Vec<f64> = out.iter().map(|&v| v as f64).collect();
    let white = cx.hw.accumulate.frame.format.max_code() as f64;
    let t = std::time::Instant::now();
    let pp = per_pixel_scatter(&fimg, &b.lens, p.k, p.kernel);
    let pp_ms = crate::stage::ms_since(t);
    let v = |x: &RegionError| serde_json::to_value(x).unwrap_or_default();
    let mut notes = serde_json::json!({
        "ms": pp_ms,
        "p": p.p,
        "weber_fixed": serde_json::to_value(weber_linear(&outf, &pp, white, &cx.scene.display)).unwrap_or_default(),
    });
    let (edge, r) = match &b.plan {
        MethodPlan::Layered(plan) => {
            let add_f = additive_layered(&fimg, plan, p.coef_bits, false);
            let add_q = additive_layered(&fimg, plan, p.coef_bits, true);
            notes["theorem_additive_float_difference_degree"] =
                difference_degree(&add_f, &pp).into();
            notes["theorem_additive_fixed_coef_difference_degree"] =
                difference_degree(&add_q, &pp).into();
            let m_max = plan.layers.iter().map(|l| l.m).max().unwrap_or(0);
            (edge_band(w, h, &plan.index, m_max), m_max)
        }
        MethodPlan::Luminance(_) => {
            // The method reaches r (pre-blur) + 1 (bleed) pixels.
            let r = p.luminance.radius as usize + 1;
            let (k, c) = (&frame.depth, &frame.coverage);
            (depth_edge_band(w, h, k, c, n2(cx), &b.lens, r), r)
        }
        MethodPlan::Downsample(plan) => {
            let r = plan.reach;
            let band = depth_edge_band(w, h, &frame.depth, &frame.coverage, n2(cx), &b.lens, r);
            (band, r)
        }
    };
    notes["composited_fixed"] = v(&region_error(&outf, &pp, &edge));
    notes["edge_band_px"] = r.into();
    notes
}

/// The blur over the frame's object pixels (depth code not `u32::MAX`): the smallest and
/// largest sigma (px), the largest circle of confusion (px) and the pixels in focus (CoC
/// within `lens.coc_px`). The sigma code is monotone in the depth code and the CoC falls
/// then rises ([`LensMap::focus_keys`]), so the extremes are those of the smallest and
/// largest depth codes, and the pixels in focus those of one range of codes: one pass of
/// minima, maxima and counts over the pixels, in chunks on the threads (the same in any
/// order).
fn blur_facts(depth: &[u32], lens: &LensMap) -> (f64, f64, f64, u64) {
    const CHUNK: usize = 1 << 14;
    let focus = lens.focus_keys();
    // An empty range counts nothing: its width is taken from a start past every code.
    let (f0, fw) = focus.map_or((u32::MAX, 0), |(a, b)| (a, b - a));
    let (lo, hi, in_focus) = depth
        .par_chunks(CHUNK)
        .map(|chunk| {
            let (mut lo, mut hi, mut n) = (u32::MAX, 0u32, 0u64);
            for &k in chunk {
                lo = lo.min(k);
                hi = hi.max(if k == u32::MAX { 0 } else { k });
                n += u64::from(k != u32::MAX && k.wrapping_sub(f0) <= fw);
            }
            (lo, hi, n)
        })
        .reduce(
            || (u32::MAX, 0, 0),
            |a, b| (a.0.min(b.0), a.1.max(b.1), a.2 + b.2),
        );
    if lo == u32::MAX {
        return (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0);
    }
    let coder = lens.sigma_coder();
    let one = (1u64 << SIGMA_FRAC) as f64;
    let sig = |k: u32| coder.code(k) as f64 / one;
    let coc_max = lens.coc_f64(lo).max(lens.coc_f64(hi));
    (sig(lo), sig(hi), coc_max, in_focus)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::SigmaForm;
    use proptest::prelude::*;

    /// [`blur_facts`] pixel by pixel: every object pixel's sigma code and CoC.
    fn every_pixel(depth: &[u32], lens: &LensMap) -> (f64, f64, f64, u64) {
        let coder = lens.sigma_coder();
        let one = (1u64 << SIGMA_FRAC) as f64;
        let (mut lo, mut hi, mut coc, mut n) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64, 0);
        for &k in depth.iter().filter(|&&k| k != u32::MAX) {
            let s = coder.code(k) as f64 / one;
            (lo, hi) = (lo.min(s), hi.max(s));
            let c = lens.coc_f64(k);
            coc = coc.max(c);
            n += u64::from(c <= lens.coc_px);
        }
        (lo, hi, coc, n)
    }

    proptest! {
        /// The blur facts from the extreme codes and the in-focus range are those of every
        /// pixel, on both embedded lenses in both sigma forms, for codes all over the depth
        /// range, around the in-focus range's ends, and the background.
        #[test]
        fn blur_facts_are_those_of_every_pixel(
            cone in any::<bool>(),
            affine in any::<bool>(),
            rom_bits in 4u32..12,
            picks in prop::collection::vec((0u8..4, any::<u32>()), 1..300),
        ) {
            let scene = Scene::embedded(if cone { "cone-focus" } else { "default" }).unwrap();
            let form = if affine { SigmaForm::Affine } else { SigmaForm::Paper };
            let lens = LensMap::from_camera(&scene.camera, 480, 24, form, rom_bits).unwrap();
            let (f0, f1) = lens.focus_keys().unwrap();
            let depth: Vec<u32> = picks
                .iter()
                .map(|&(kind, r)| match kind {
                    0 => r % (1 << 25),
                    1 => f0.wrapping_add(r % 9).wrapping_sub(4),
                    2 => f1.wrapping_add(r % 9).wrapping_sub(4),
                    _ => u32::MAX,
                })
                .collect();
            prop_assert_eq!(blur_facts(&depth, &lens), every_pixel(&depth, &lens));
        }
    }

    /// The in-focus range is that of a test of every code near its ends (codes 2^24 apart
    /// in screen z 1: the default lens).
    #[test]
    fn focus_keys_bound_the_codes_in_focus() {
        let scene = Scene::embedded("default").unwrap();
        let lens = LensMap::from_camera(&scene.camera, 480, 24, SigmaForm::Paper, 10).unwrap();
        let (f0, f1) = lens.focus_keys().unwrap();
        assert!(0 < f0 && f0 < f1 && f1 < 1 << 24, "{f0} {f1}");
        for k in f0 - 50..f1 + 50 {
            assert_eq!(
                lens.coc_f64(k) <= lens.coc_px,
                (f0..=f1).contains(&k),
                "code {k}"
            );
        }
    }
}
