//! The HTML report of `igemu sequence --html`: the frames as an animated PNG, the cycles of
//! every frame against the period, the error and the excess flicker per frame, the small
//! objects' displayed luminance over time, and the per-frame table.

use super::figures::svg_picture;
use super::images::Picture;
use super::plots::{self, Frame, Mark, Series};
use crate::sequence::SequenceReport;
use plotters::style::RGBColor;
use serde::Serialize;

const SIZE: (u32, u32) = (620, 360);
const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(23, 190, 207),
];

/// What the sequence page shows.
#[derive(Serialize)]
pub struct SequencePage {
    /// Heading.
    pub title: String,
    /// Tool version.
    pub version: String,
    /// The headline figures.
    pub facts: Vec<(String, String)>,
    /// The frames (an APNG), if written.
    pub animation: Option<Picture>,
    /// The plots.
    pub plots: Vec<Picture>,
    /// The per-frame table's headings.
    pub columns: Vec<String>,
    /// Its rows.
    pub rows: Vec<Vec<String>>,
}

fn plot(f: &Frame, series: &[Series], caption: String) -> Result<Picture, String> {
    let svg = plots::curves(f, series, None)
        .map_err(|e| format!("cannot draw the {} plot: {e}", f.title))?;
    let mut p = svg_picture(&f.title, caption, svg, f.size);
    p.legend = plots::keys(series);
    Ok(p)
}

fn frame(title: &str, y: &str) -> Frame {
    Frame {
        title: title.into(),
        x: "frame".into(),
        y: y.into(),
        size: SIZE,
    }
}

/// The page of sequence report `r`; `apng`: the animated PNG's bytes and its size.
pub fn page(r: &SequenceReport, apng: Option<(&[u8], u32, u32)>) -> Result<SequencePage, String> {
    let s = &r.summary;
    let t = &r.temporal;
    let opt = |v: Option<f64>, d: usize| v.map_or("-".to_string(), |x| format!("{x:.d$}"));
    let facts = vec![
        ("scene".into(), r.scene.clone()),
        (
            "hardware".into(),
            format!("{} (filter {})", r.hardware, r.filter),
        ),
        (
            "frames".into(),
            format!(
                "{}..{} of {}",
                r.first,
                r.first + s.frames,
                r.sequence_frames
            ),
        ),
        (
            "rate".into(),
            format!(
                "{} Hz = {:.0} cycles at {} MHz",
                s.rate_hz, s.period_cycles, s.clock_mhz
            ),
        ),
        (
            "worst frame".into(),
            format!(
                "{} ({} cycles, {:.3} ms)",
                s.worst_frame, s.worst_cycles, s.worst_frame_ms
            ),
        ),
        (
            "frames missing the period".into(),
            format!("{} of {}", s.missed, s.frames),
        ),
        (
            "cycles p50 / p95 / p99".into(),
            format!("{} / {} / {}", s.p50_cycles, s.p95_cycles, s.p99_cycles),
        ),
        (
            "excess flicker max / mean (Weber)".into(),
            format!(
                "{} / {}",
                opt(t.max_excess_weber, 3),
                opt(t.mean_excess_weber, 5)
            ),
        ),
        (
            "reuse".into(),
            format!(
                "{} stages reused, {} emulated, {} frames fully reused",
                r.reuse.stages_reused, r.reuse.stages_emulated, r.reuse.frames_fully_reused
            ),
        ),
        (
            "tile rows after the first frame".into(),
            match &r.reuse.tile_rows_off {
                Some(why) => format!("not reused: {why}"),
                None => format!(
                    "{} emulated, {} reused ({} rows of {} px per frame)",
                    r.reuse.tile_rows_emulated,
                    r.reuse.tile_rows_reused,
                    r.reuse.tile_rows,
                    r.reuse.tile_size
                ),
            },
        ),
    ];
    let animation = apng.map(|(bytes, w, h)| Picture {
        title: "the frames, at the sequence's rate".into(),
        caption: if r.reference {
            "left: the fixed output; right: its difference to the float reference (128 grey = identical, 32 grey levels per DAC code)".into()
        } else {
            "the fixed output (no float reference ran)".into()
        },
        uri: format!(
            "data:image/png;base64,{}",
            base64::Engine::encode(&base64::engine::general_purpose::STANDARD, bytes)
        ),
        width: w,
        height: h,
        legend: Vec::new(),
    });
    let x = |f: u32| f as f64;
    let mut v = Vec::new();
    v.push(plot(
        &frame("cycles per frame", "cycles"),
        &[
            Series {
                name: "cycles of the frame".into(),
                colour: COLOURS[0],
                mark: Mark::Line,
                points: r
                    .frames
                    .iter()
                    .map(|f| (x(f.frame), f.cycles as f64))
                    .collect(),
            },
            Series {
                name: format!("period: {:.0} cycles ({} Hz)", s.period_cycles, s.rate_hz),
                colour: COLOURS[1],
                mark: Mark::Line,
                points: r
                    .frames
                    .iter()
                    .map(|f| (x(f.frame), s.period_cycles))
                    .collect(),
            },
        ],
        format!(
            "each frame's cycles against the display period; worst frame {}",
            s.worst_frame
        ),
    )?);
    if r.reference {
        v.push(plot(
            &frame("error per frame", "largest |fixed - reference|, DAC codes"),
            &[Series {
                name: "largest code difference".into(),
                colour: COLOURS[0],
                mark: Mark::Line,
                points: r
                    .frames
                    .iter()
                    .map(|f| (x(f.frame), f64::from(f.max_abs_diff.unwrap_or(0))))
                    .collect(),
            }],
            "the fixed output against the float reference, frame by frame".into(),
        )?);
        v.push(plot(
            &frame("excess flicker per frame pair", "Weber units"),
            &[
                Series {
                    name: "largest per-pixel excess".into(),
                    colour: COLOURS[1],
                    mark: Mark::Line,
                    points: t.per_pair.iter().map(|p| (x(p.frame), p.max_weber)).collect(),
                },
                Series {
                    name: "1 = a just visible step".into(),
                    colour: COLOURS[2],
                    mark: Mark::Line,
                    points: t.per_pair.iter().map(|p| (x(p.frame), 1.0)).collect(),
                },
            ],
            "the fixed output's frame-to-frame change minus the reference's, in Weber steps of the pixel's luminance".into(),
        )?);
    }
    if !t.objects.is_empty() {
        let mut series = Vec::new();
        for (k, o) in t.objects.iter().enumerate() {
            let colour = COLOURS[k % COLOURS.len()];
            let rel = |v: &[f64]| -> Vec<(f64, f64)> {
                let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
                let first = r.first;
                v.iter()
                    .enumerate()
                    .map(|(i, &y)| (x(first + i as u32), if mean > 0.0 { y / mean } else { 0.0 }))
                    .collect()
            };
            series.push(Series {
                name: format!("object {} ({}): fixed", o.object, o.kind),
                colour,
                mark: Mark::Line,
                points: rel(&o.total_fixed),
            });
            if !o.total_reference.is_empty() {
                series.push(Series {
                    name: format!("object {} ({}): reference", o.object, o.kind),
                    colour,
                    mark: Mark::Dots(2),
                    points: rel(&o.total_reference),
                });
            }
        }
        v.push(plot(
            &frame("small-object flicker", "displayed luminance / its mean"),
            &series,
            "each small moving object's total displayed luminance above the background, over its mean: a flat line does not flicker".into(),
        )?);
    }
    let columns = [
        "frame",
        "cycles",
        "ms",
        "fps",
        "misses",
        "identical",
        "max diff",
        "Weber max",
        "reused",
        "emulated",
        "tile rows emulated",
    ]
    .map(String::from)
    .to_vec();
    let rows = r
        .frames
        .iter()
        .map(|f| {
            vec![
                f.frame.to_string(),
                f.cycles.to_string(),
                format!("{:.3}", f.frame_ms),
                format!("{:.1}", f.fps),
                if f.misses_period {
                    "MISS".into()
                } else {
                    String::new()
                },
                opt(f.identical_fraction, 4),
                f.max_abs_diff.map_or("-".into(), |d| d.to_string()),
                opt(f.weber_max, 3),
                f.reused_stages.to_string(),
                f.emulated_stages.to_string(),
                format!(
                    "{}/{}",
                    f.tile_rows_emulated,
                    f.tile_rows_emulated + f.tile_rows_reused
                ),
            ]
        })
        .collect();
    Ok(SequencePage {
        title: format!("igemu sequence: {} on {}", r.scene, r.hardware),
        version: r.igemu_version.clone(),
        facts,
        animation,
        plots: v,
        columns,
        rows,
    })
}
