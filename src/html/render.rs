//! What the HTML report of one render shows, gathered from the [`Render`]: the pictures,
//! the plan, the per-stage table with each stage's signals, the cycle summary and the plots.

use super::colour::{self, ColourSection};
use super::figures;
use super::images::{self, LayerKey, Picture};
use crate::analysis::ranges::narrowest;
use crate::config::HwConfig;
use crate::perceptual::banding_image;
use crate::pipeline::Render;
use crate::scene::Scene;
use crate::stage::StageId;
use serde::{Deserialize, Serialize};

/// The report page's data (the template's context).
#[derive(Serialize)]
pub struct RenderPage {
    /// Page title.
    pub title: String,
    /// igemu version.
    pub version: String,
    /// One-line facts under the title.
    pub facts: Vec<(String, String)>,
    /// Images side by side.
    pub pictures: Vec<Picture>,
    /// A colour render's CIEDE2000 map and colour figures (`None`: a grey render).
    pub colour: Option<ColourSection>,
    /// Plan: stages in run order.
    pub plan_line: String,
    /// Every stage in or out, with why.
    pub decisions: Vec<DecisionRow>,
    /// Plan notes.
    pub plan_notes: Vec<String>,
    /// Stage table.
    pub stages: Vec<StageRow>,
    /// Totals row: fixed ms, float ms, overflows.
    pub totals: (String, String, u64),
    /// Cycle summary lines (as the text report prints them).
    pub cycles: Vec<String>,
    /// Cycle table rows.
    pub cycle_rows: Vec<Vec<String>>,
    /// Plots.
    pub plots: Vec<Picture>,
    /// With `--dof-truth`: the errors against the truth split into algorithm and quantisation.
    pub truth: Option<TruthSection>,
}

/// The depth-of-field truth's table: what the text report prints under `depth-of-field truth`.
#[derive(Serialize)]
pub struct TruthSection {
    /// The truth's lens points, time and noise.
    pub note: String,
    /// Column headings after the part's name: whole image, depth-edge band, interior.
    pub columns: [String; 3],
    /// (part, whole, edge band, interior): `mean |diff| / RMS / max, mean Weber`.
    pub rows: Vec<[String; 4]>,
}

/// The truth section of a render with `--dof-truth`.
fn truth_section(t: &crate::truth::TruthReport) -> TruthSection {
    TruthSection {
        note: format!(
            "{}. Each cell: DAC codes mean |diff| / RMS / max, mean Weber; total = algorithm + quantisation per pixel (signed).",
            t.summary()
        ),
        columns: [
            "whole image".into(),
            format!(
                "depth-edge band ({} px, {} px wide)",
                t.edge_pixels, t.edge_band_px
            ),
            "interior".into(),
        ],
        rows: t
            .rows()
            .iter()
            .map(|(name, s)| {
                [
                    name.to_string(),
                    s.whole.brief(),
                    s.edge.brief(),
                    s.interior.brief(),
                ]
            })
            .collect(),
    }
}

/// One stage of the plan.
#[derive(Serialize)]
pub struct DecisionRow {
    /// Stage.
    pub stage: String,
    /// In the plan.
    pub planned: bool,
    /// Why.
    pub reason: String,
}

/// One row of the stage table and its signals.
#[derive(Serialize)]
pub struct StageRow {
    /// Stage name (also the anchor of its signals).
    pub name: String,
    /// Fixed model, ms.
    pub fixed_ms: String,
    /// Float reference, ms.
    pub float_ms: String,
    /// Stage-local max |error| and mean error, output LSBs (`-`: none compared).
    pub max_err: String,
    /// Mean error.
    pub mean_err: String,
    /// Overflows over its signals.
    pub overflows: u64,
    /// Work items.
    pub work: String,
    /// RAM and ROM bits, adders, multipliers.
    pub cost: String,
    /// Its signals.
    pub signals: Vec<SignalRow>,
}

/// One instrumented signal and its range.
#[derive(Serialize)]
pub struct SignalRow {
    /// Name.
    pub name: String,
    /// Configured format and its code range.
    pub format: String,
    /// Code range of the format.
    pub range: String,
    /// Values recorded (`-` for an overflow counter, which records none).
    pub count: String,
    /// Smallest and largest value seen (LSBs).
    pub seen: String,
    /// Narrowest format holding what was seen.
    pub narrowest: String,
    /// Overflows.
    pub overflows: u64,
    /// Mean and RMS quantisation error, LSBs.
    pub error: String,
}

/// A depth-of-field layer as the stage's notes list it.
#[derive(Deserialize)]
pub(super) struct LayerNote {
    pub key_far: u32,
    pub key_near: u32,
    pub z_range: (f64, f64),
    pub z_mid: f64,
    pub sigma: f64,
    pub pixels: u64,
}

fn ms(v: f64) -> String {
    format!("{v:.2}")
}

/// Gathers the page of render `r` of `scene` on `hw`.
pub fn page(scene: &Scene, hw: &HwConfig, r: &Render) -> figures::Result<RenderPage> {
    let rep = &r.report;
    let (w, h) = (rep.scene.width, rep.scene.height);
    let e = &rep.end_to_end;
    // A colour render's end-to-end figures are channel R's (the colour section has each
    // channel's).
    let of_r = |k: &str| match rep.colour {
        Some(_) => format!("{k}, channel R"),
        None => k.to_string(),
    };
    let mut facts = vec![
        ("scene".into(), format!("{} {w}x{h}", rep.scene.name)),
        ("hardware".into(), rep.hardware.name.clone()),
        (
            of_r("identical DAC codes"),
            format!("{:.4}%", 100.0 * e.codes.identical_fraction),
        ),
        (of_r("max |diff|"), e.codes.max_abs_diff.to_string()),
        (of_r("mean diff"), format!("{:+.5}", e.codes.mean_diff)),
        (
            of_r("visible (Weber > delta)"),
            format!("{:.4}% of pixels", 100.0 * e.weber.over_delta_fraction),
        ),
        (
            of_r("visible contours"),
            format!(
                "{} steps (float reference {})",
                rep.contours.contour_steps, rep.contours.contour_steps_reference
            ),
        ),
        ("overflows".into(), rep.overflows.to_string()),
        (
            "frame".into(),
            format!(
                "{} cycles, {:.1} fps at {} MHz",
                rep.cycles.total_cycles, rep.cycles.throughput.fps, rep.cycles.throughput.clock_mhz
            ),
        ),
    ];
    if let Some(c) = &rep.colour {
        facts.insert(2, ("colour".into(), colour::headline(c)));
    }
    let plan = &rep.plan;
    Ok(RenderPage {
        title: format!("igemu render: {} on {}", rep.scene.name, rep.hardware.name),
        version: rep.igemu_version.clone(),
        facts,
        pictures: pictures(r, w, h),
        colour: colour::section(r, (w, h)),
        plan_line: format!(
            "{} | region x {}..{} y {}..{} ({:.1}% of the screen) | tiles {}x{} px: {} of {} binned | {}x{} samples/pixel",
            plan.stages.join(" -> "),
            plan.region.x0,
            plan.region.x1,
            plan.region.y0,
            plan.region.y1,
            100.0 * plan.region_fraction,
            plan.tiles.size,
            plan.tiles.size,
            plan.tiles.binned,
            plan.tiles.cols * plan.tiles.rows,
            plan.samples,
            plan.samples,
        ),
        decisions: plan
            .decisions
            .iter()
            .map(|d| DecisionRow {
                stage: d.stage.name().into(),
                planned: d.need.planned,
                reason: d.need.reason.clone(),
            })
            .collect(),
        plan_notes: plan.notes.clone(),
        stages: rep.stages.iter().map(stage_row).collect(),
        totals: (
            ms(rep.timing.fixed_ms),
            ms(rep.timing.float_ms),
            rep.overflows,
        ),
        cycles: rep.cycles.summary_lines(),
        cycle_rows: rep
            .cycles
            .stages
            .iter()
            .map(|s| {
                [
                    s.name.clone(),
                    s.item.clone(),
                    s.lanes.to_string(),
                    s.tokens.to_string(),
                    s.items.to_string(),
                    s.busy.to_string(),
                    s.stalled.to_string(),
                    s.starved.to_string(),
                    s.fifo_max.to_string(),
                ]
                .into()
            })
            .collect(),
        plots: figures::plots(scene, hw, r)?,
        truth: rep.dof_truth.as_ref().map(truth_section),
    })
}

fn pictures(r: &Render, w: u32, h: u32) -> Vec<Picture> {
    let (bits, size) = (r.dac_bits, (w, h));
    let levels = format!("{bits}-bit DAC codes as grey levels");
    let grey = |title: &str, codes: &[u16]| {
        let px = images::grey(codes, bits);
        Picture::png(title, levels.clone(), &px, size, false, Vec::new())
    };
    let mut v = match &r.colour {
        Some(c) => colour::pictures(c, size),
        None => {
            let band = banding_image(&r.dac, &r.contour_map, (1u32 << bits) - 1);
            let (band_caption, band_legend) = images::banding_legend(
                "the output dimmed, smooth regions lifted, visible contour steps white",
                r.contour_map.iter().filter(|&&m| m == 2).count(),
            );
            vec![
                grey("fixed pipeline", &r.dac),
                grey("float reference", &r.dac_ref),
                Picture::diff(
                    "difference",
                    |max| {
                        format!(
                            "fixed minus reference, DAC codes (largest |diff| {max}): red where the fixed pipeline is brighter"
                        )
                    },
                    &r.dac,
                    &r.dac_ref,
                    size,
                ),
                Picture::png("banding map", band_caption, &band, size, false, band_legend),
            ]
        }
    };
    if let Some(t) = &r.truth_dac {
        v.push(grey("depth-of-field truth", t));
        v.push(Picture::diff(
            "difference to the truth",
            |max| format!("fixed minus truth, DAC codes (largest |diff| {max})"),
            &r.dac,
            t,
            size,
        ));
    }
    if let (Some(layers), Some(acc)) = (dof_layers(r), r.taps(StageId::Accumulate)) {
        let keys: Vec<LayerKey> = layers
            .iter()
            .map(|l| LayerKey {
                keys: (l.key_near, l.key_far),
                label: if l.key_far == u32::MAX {
                    format!("background: sigma {:.2} px, {} px", l.sigma, l.pixels)
                } else {
                    format!(
                        "z {:.4}..{:.4}: sigma {:+.2} px, {} px",
                        l.z_range.0, l.z_range.1, l.sigma, l.pixels
                    )
                },
            })
            .collect();
        let (rgb, legend) = images::layer_map(&acc.fixed.frame().frame.depth, &keys);
        v.push(Picture::png(
            "depth-of-field layers",
            "each pixel in the colour of the layer its nearest depth falls in".into(),
            &rgb,
            size,
            true,
            legend,
        ));
    }
    v
}

/// The layers of a layered depth-of-field plan (from the stage's notes).
pub(super) fn dof_layers(r: &Render) -> Option<Vec<LayerNote>> {
    let dof = r.report.stages.iter().find(|s| s.name == "dof")?;
    serde_json::from_value(dof.notes.get("layers")?.clone()).ok()
}

fn stage_row(s: &crate::stage::StageReport) -> StageRow {
    let (max_err, mean_err) = match &s.local {
        Some(l) if l.values > 0 => (
            format!("{:.3}", l.max_abs_lsb),
            format!("{:+.4}", l.mean_lsb),
        ),
        _ => ("-".into(), "-".into()),
    };
    let c = &s.cost;
    StageRow {
        name: s.name.clone(),
        fixed_ms: ms(s.fixed_ms),
        float_ms: ms(s.float_ms),
        max_err,
        mean_err,
        overflows: s.signals.iter().map(|g| g.overflows).sum(),
        work: s
            .work
            .iter()
            .filter(|&(_, &v)| v > 0)
            .map(|(k, v)| format!("{k} {v}"))
            .collect::<Vec<_>>()
            .join(", "),
        cost: format!(
            "RAM {} b, ROM {} b, {} adders, {} multipliers",
            c.storage_bits,
            c.lut_bits,
            c.adders.iter().map(|u| u.count as u64).sum::<u64>(),
            c.multipliers.iter().map(|u| u.count as u64).sum::<u64>()
        ),
        signals: s
            .signals
            .iter()
            .map(|g| {
                let f = g.format;
                SignalRow {
                    name: g.name.clone(),
                    format: f.to_string(),
                    range: code_range(f),
                    count: if g.overflow_only {
                        "-".into()
                    } else {
                        g.count.to_string()
                    },
                    seen: match (g.min, g.max) {
                        (Some(a), Some(b)) => format!("{a}..{b}"),
                        _ if g.overflow_only => "not recorded: an overflow counter (this datapath counts the values its overflow mode acts on, not every value, to stay fast)".into(),
                        _ => "none: the stage recorded no value of this signal on this run".into(),
                    },
                    narrowest: match (g.min, g.max) {
                        (Some(a), Some(b)) => narrowest(a, b, f.frac_bits).to_string(),
                        _ => "-".into(),
                    },
                    overflows: g.overflows,
                    error: if g.count > 0 {
                        format!("{:+.4} / {:.4}", g.mean_error(), g.rms_error())
                    } else {
                        "-".into()
                    },
                }
            })
            .collect(),
    }
}

/// The codes a format holds (`0..4095`); a wide accumulator's label (`UQ40.0`) as its
/// width, where the codes would not fit an `i64`.
fn code_range(f: crate::fixed::QFormat) -> String {
    match f.total_bits() {
        1..=62 => format!("{}..{}", f.min_code(), f.max_code()),
        w => format!("a {w}-bit word"),
    }
}

#[cfg(test)]
mod tests {
    use super::code_range;
    use crate::fixed::QFormat;

    #[test]
    fn code_ranges_of_narrow_and_wide_formats() {
        assert_eq!(code_range(QFormat::new(false, 12, 0)), "0..4095");
        assert_eq!(code_range(QFormat::new(true, 4, 4)), "-128..127");
        assert_eq!(code_range(QFormat::new(false, 96, 0)), "a 96-bit word");
    }
}
