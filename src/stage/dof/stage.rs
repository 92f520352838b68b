//! The dof stage through the contract: the thin lens's blur per depth code, the layer plan
//! grown far to near, the fixed layered convolution and compositing of the finished frame,
//! its float references (the same layers in f64; on request the per-pixel scatter and the
//! layer theorem check), the stage-local comparison, one cycle-model token per layer, the
//! cost and the coefficient ROM.

use super::{
    DepthImage, LayerPlan, LensMap, RegionError, SIGMA_FRAC, additive_layered, difference_degree,
    edge_band, layer_work, layered_f64, layered_fixed, local_error, overflow_signal,
    overflow_signal_in, per_pixel_scatter, plan_layers, region_error, weber_linear,
};
use crate::config::{CodingKind, HwConfig};
use crate::error::{Error, FileError, Result};
use crate::scene::{Lens, Scene};
use crate::stage::taps::{FrameCoding, FrameTap, Taps};
use crate::stage::{
    Cost, Cx, Facts, LocalError, MemImage, Need, Notes, Stage, StageId, TokenKind, Tokens,
};
use std::sync::Arc;

/// What the fixed model leaves: the lens, the layer plan, and the frame it blurred.
pub struct Blurred {
    lens: LensMap,
    plan: LayerPlan,
    input: Arc<FrameTap>,
}

/// The dof stage.
pub struct Dof;

fn n2(hw: &HwConfig) -> u32 {
    hw.raster.samples * hw.raster.samples
}

impl Stage for Dof {
    type Fixed = Blurred;

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
        if hw.coding.kind == CodingKind::LogAdd {
            return Err(Error::File(FileError {
                file: hw.name.clone(),
                line: None,
                col: None,
                field: "coding.kind".into(),
                msg: format!(
                    "log-add keeps a log-coded frame memory, but scene `{}` has a thin lens and depth of field needs a linear frame; use log-potentiate, or a pinhole scene (e.g. the embedded `default-pinhole`)",
                    scene.name
                ),
            }));
        }
        Ok(Need::yes(format!(
            "thin lens (radius {lens_radius}, focus at {focus_distance}): layered blur of the frame, threshold P = {}",
            hw.dof.p
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
        let input = taps
            .fixed
            .frame
            .clone()
            .expect("accumulate wrote the frame");
        let frame = &input.frame;
        let (w, h) = (frame.width as usize, frame.height as usize);
        let lens = LensMap::from_camera(
            &cx.scene.camera,
            frame.height,
            hw.visibility.z.format.frac_bits,
        )
        .expect("the plan runs dof for a thin lens only");
        let p = &hw.dof;
        let frame_fmt = hw.accumulate.frame.format;
        let plan = plan_layers(&frame.depth, &frame.coverage, n2(hw), &lens, p).map_err(|msg| {
            Error::File(FileError {
                file: hw.name.clone(),
                line: None,
                col: None,
                field: "dof.max_half_size".into(),
                msg,
            })
        })?;
        let img = DepthImage::of_frame(frame, &frame.acc, n2(hw));
        let (out, work) =
            layered_fixed(&img, &plan, p, frame_fmt).map_err(|(signal, bits)| Error::Overflow {
                signal,
                format: format!("UQ{bits}.0"),
                value: 1i128 << bits,
                min: 0,
                max: ((1u128 << bits.min(63)) - 1) as i64,
            })?;
        let mut facts = Facts {
            work: vec![
                ("layers", plan.layers.len() as u64),
                ("pixels", (w * h) as u64),
                ("macs", work.macs),
                ("divides", work.divides),
                ("composites", work.composites),
                ("passthrough", work.passthrough),
            ],
            signals: vec![
                overflow_signal("dof.line", p.line_bits, work.line_overflows),
                overflow_signal("dof.acc", p.acc_bits, work.acc_overflows),
                overflow_signal_in("dof.out", frame_fmt, work.out_overflows),
            ],
            ..Facts::default()
        };
        // Blur facts.
        let (mut sig_min, mut sig_max) = (f64::INFINITY, f64::NEG_INFINITY);
        let (mut in_focus, mut coc_max) = (0u64, 0.0f64);
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
        facts.note("lens", lens);
        facts.note("layers", &plan.layers);
        facts.note(
            "object_sigma_px",
            serde_json::json!({"min": sig_min, "max": sig_max, "background": lens.sigma_f64(u32::MAX)}),
        );
        facts.note("object_coc_max_px", coc_max);
        facts.note("object_pixels_in_focus", in_focus);
        let mut next = frame.clone();
        next.acc = out;
        taps.fixed.frame = Some(Arc::new(FrameTap {
            frame: next,
            coding: FrameCoding::Linear,
        }));
        Ok((Blurred { lens, plan, input }, facts))
    }

    /// (1) The same layers and masks in f64 on the float frame; with `dof_reference` also
    /// (2) the per-pixel scatter of the fixed input frame and the layer theorem's check.
    fn float(&self, cx: &Cx, b: &Blurred, taps: &mut Taps, notes: &mut Notes) -> Result<()> {
        let frame = &b.input.frame;
        let n2 = n2(cx.hw);
        let frame_ref = taps.float.frame();
        let rimg = DepthImage::of_frame(frame, frame_ref, n2);
        let new_ref = layered_f64(&rimg, &b.plan);
        if cx.opts.dof_reference {
            let p = &cx.hw.dof;
            let (w, h) = (frame.width as usize, frame.height as usize);
            let accf: Vec<f64> = frame.acc.iter().map(|&v| v as f64).collect();
            let fimg = DepthImage::of_frame(frame, &accf, n2);
            let out = &taps.fixed.frame().frame.acc;
            let outf: Vec<f64> = out.iter().map(|&v| v as f64).collect();
            let white = cx.hw.accumulate.frame.format.max_code() as f64;
            let t = std::time::Instant::now();
            let pp = per_pixel_scatter(&fimg, &b.lens, p.k);
            let pp_ms = crate::stage::ms_since(t);
            let m_max = b.plan.layers.iter().map(|l| l.m).max().unwrap_or(0);
            let edge = edge_band(w, h, &b.plan.index, m_max);
            let add_f = additive_layered(&fimg, &b.plan, p.coef_bits, false);
            let add_q = additive_layered(&fimg, &b.plan, p.coef_bits, true);
            let v = |x: &RegionError| serde_json::to_value(x).unwrap_or_default();
            notes.insert(
                "per_pixel_reference".into(),
                serde_json::json!({
                    "ms": pp_ms,
                    "theorem_additive_float_difference_degree": difference_degree(&add_f, &pp),
                    "theorem_additive_fixed_coef_difference_degree": difference_degree(&add_q, &pp),
                    "p": p.p,
                    "composited_fixed": v(&region_error(&outf, &pp, &edge)),
                    "weber_fixed": serde_json::to_value(weber_linear(&outf, &pp, white, &cx.scene.display)).unwrap_or_default(),
                    "edge_band_px": m_max,
                }),
            );
        }
        taps.float.frame = Some(Arc::new(new_ref));
        Ok(())
    }

    /// The same layers in f64 on the fixed input frame against the fixed output, code by
    /// code (and through the display: note `weber_vs_layered_float`).
    fn local(
        &self,
        cx: &Cx,
        b: &Blurred,
        _: &Taps,
        out: &Taps,
        notes: &mut Notes,
    ) -> Option<LocalError> {
        let frame = &b.input.frame;
        let accf: Vec<f64> = frame.acc.iter().map(|&v| v as f64).collect();
        let fimg = DepthImage::of_frame(frame, &accf, n2(cx.hw));
        let local = layered_f64(&fimg, &b.plan);
        let white = cx.hw.accumulate.frame.format.max_code() as f64;
        let o = &out.fixed.frame().frame.acc;
        let outf: Vec<f64> = o.iter().map(|&v| v as f64).collect();
        notes.insert(
            "weber_vs_layered_float".into(),
            serde_json::to_value(weber_linear(&outf, &local, white, &cx.scene.display))
                .unwrap_or_default(),
        );
        Some(local_error(o, &local, white))
    }

    /// One token per layer: the output samples of both 1-D passes over its box.
    fn tokens(&self, cx: &Cx, b: &Blurred) -> Option<Tokens> {
        let g = &cx.layout.grid;
        let layers = layer_work(&b.plan, g.width as usize, g.height as usize);
        Some(Tokens {
            kind: TokenKind::Layer,
            item: "pass outputs",
            items: layers.iter().map(|l| 2 * l.pixels).collect(),
            port_bits: vec![],
        })
    }

    fn cost(&self, cx: &Cx, b: &Blurred) -> Cost {
        let g = &cx.layout.grid;
        super::cost(
            &b.plan,
            &cx.hw.dof,
            g.width as u64,
            g.height as u64,
            cx.hw.accumulate.frame.format.total_bits(),
            n2(cx.hw),
            &b.lens,
        )
    }

    fn memories(&self, cx: &Cx, b: &Blurred, _: &Taps) -> Vec<MemImage> {
        vec![super::coefficient_image(&b.plan, &cx.hw.dof)]
    }
}
