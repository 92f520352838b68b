//! The dof stage in the pipeline: plan, fixed run, float references, report.

use super::{
    DepthImage, LayerWork, LensMap, RegionError, SIGMA_FRAC, additive_layered, cost,
    difference_degree, edge_band, layer_work, layered_f64, layered_fixed, local_error,
    overflow_signal, overflow_signal_in, per_pixel_scatter, plan_layers, region_error,
    weber_linear,
};

/// Runs the dof stage inside the pipeline: replaces the frame codes and the float frame with
/// the depth-of-field results. `None` (and nothing changed) for a pinhole camera.
/// `per_pixel` also runs the per-pixel scatter reference and the theorem check.
pub fn run_stage(
    scene: &crate::scene::Scene,
    hw: &crate::config::HwConfig,
    frame: &mut crate::stage::accumulate::Frame,
    frame_ref: &mut Vec<f64>,
    stage_local: bool,
    per_pixel: bool,
) -> crate::error::Result<Option<(crate::stage::StageReport, Vec<LayerWork>)>> {
    use crate::error::{Error, FileError};
    use crate::stage::ms_since;
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
    let mut r = crate::stage::StageReport {
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
    r.signals
        .push(overflow_signal_in("dof.out", frame_fmt, work.out_overflows));
    frame.acc = out;
    *frame_ref = new_ref;
    let layers = layer_work(&plan, w, h);
    Ok(Some((r, layers)))
}
