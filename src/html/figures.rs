//! The plots of a render's HTML report, from the [`Render`]: the gamma LUT's transfer (the
//! paper's Fig. 6), the histogram of code differences, the stage timeline of the cycle
//! simulation and sigma against depth.

use super::images::{self, Picture};
use super::plots::{self, Frame, Mark, Series};
use super::render::{LayerNote, dof_layers};
use super::timeline::timeline;
use crate::config::{DofSchedule, HwConfig};
use crate::pipeline::Render;
use crate::pipeline::report::gamma_spec;
use crate::scene::Scene;
use crate::stage::StageId;
use crate::stage::dof::LensMap;
use crate::stage::logdomain::{ZERO, log_code};
use crate::stage::taps::FrameCoding;
use plotters::style::RGBColor;

/// Drawing fails only on a plotters error; the caller names the report file.
pub type Result<T> = std::result::Result<T, String>;

pub(super) fn svg_picture(title: &str, caption: String, svg: String, size: (u32, u32)) -> Picture {
    Picture {
        title: title.into(),
        caption,
        uri: images::svg_uri(&svg),
        width: size.0,
        height: size.1,
        legend: Vec::new(),
    }
}

fn plot_error(what: &str, e: String) -> String {
    format!("cannot draw the {what} plot: {e}")
}

const SIZE: (u32, u32) = (620, 400);

/// Every plot of render `r`.
pub fn plots(scene: &Scene, hw: &HwConfig, r: &Render) -> Result<Vec<Picture>> {
    let mut v = Vec::new();
    // A colour render's LUT and code differences are channel R's.
    let of_r = if r.colour.is_some() {
        "channel R: "
    } else {
        ""
    };
    // The gamma LUT transfer (the paper's Fig. 6): this render's LUT, the ideal I^(1/gamma)
    // of a linear code, and for a log code of the scene's contrast the LUT of eq. 15 with
    // the brightness its codes stand for.
    let spec = gamma_spec(scene, hw);
    let n = 256;
    let xs = (0..=n).map(|i| i as f64 / n as f64);
    let mut series = vec![Series {
        name: format!("linear code: I^(1/{})", fmt_gamma(spec.exponent)),
        colour: RGBColor(31, 119, 180),
        mark: Mark::Line,
        points: xs.clone().map(|x| (x, spec.power(x))).collect(),
    }];
    if let Ok(code) = log_code(scene, hw) {
        series.push(Series {
            name: format!(
                "{}-bit log code, K = {}: LUT ((K^L - 1)/(K - 1))^(1/gamma)",
                code.bits, code.k
            ),
            colour: RGBColor(214, 39, 40),
            mark: Mark::Line,
            points: xs
                .clone()
                .map(|l| (l, spec.power(code.linear_of_log(l))))
                .collect(),
        });
        series.push(Series {
            name: "log code: relative brightness B/Bmax".into(),
            colour: RGBColor(255, 127, 14),
            mark: Mark::Line,
            points: xs.map(|l| (l, code.linear_of_log(l))).collect(),
        });
    }
    if let Some((entries, points)) = lut_points(r) {
        series.push(Series {
            name: format!("this render's LUT ({entries} entries), DAC / max"),
            colour: RGBColor(0, 0, 0),
            mark: Mark::Dots(2),
            points,
        });
    }
    let f = Frame {
        title: "gamma LUT transfer".into(),
        x: "input: linear code / full white, or log intensity L".into(),
        y: "output / full scale".into(),
        size: SIZE,
    };
    // The curves fill the plot (steep from the left, high on the right, the brightness low
    // on the right): the legend goes under the figure.
    let svg = plots::curves(&f, &series, None).map_err(|e| plot_error("LUT", e))?;
    let mut lut = svg_picture(
        &f.title,
        format!("{of_r}the LUT's output against its input, both normalised (the paper's Fig. 6)"),
        svg,
        SIZE,
    );
    lut.legend = plots::keys(&series);
    v.push(lut);
    // The histogram of end-to-end code differences.
    let bars: Vec<(i64, u64)> = r
        .report
        .end_to_end
        .codes
        .histogram
        .iter()
        .map(|(&d, &n)| (d as i64, n))
        .collect();
    let f = Frame {
        title: "DAC code differences".into(),
        x: "fixed minus reference, codes".into(),
        y: "pixels".into(),
        size: SIZE,
    };
    let svg = plots::histogram(&f, &bars).map_err(|e| plot_error("histogram", e))?;
    v.push(svg_picture(
        &f.title,
        format!("{of_r}pixels per difference, logarithmic count"),
        svg,
        SIZE,
    ));
    v.extend(timelines(hw, r)?);
    if let Some(p) = sigma_plot(scene, hw, r)? {
        v.push(p);
    }
    Ok(v)
}

/// The stage timelines of the cycle simulation: every timed stage of the plan under the
/// chosen depth-of-field schedule and, with a stage that streams, under the other one, on
/// the same cycle axis with bins of about the same length.
fn timelines(hw: &HwConfig, r: &Render) -> Result<Vec<Picture>> {
    let first = timeline(&r.workload, 400);
    let mut runs = vec![(r.workload.clone(), first.clone())];
    if let Some(both) = &r.report.cycles.schedules {
        let (other, cycles) = match r.workload.schedule {
            DofSchedule::Stream => (DofSchedule::Frame, both.frame.cycles),
            DofSchedule::Frame => (DofSchedule::Stream, both.stream.cycles),
        };
        let w = r.workload_for(&hw.cycles, other);
        let t = timeline(&w, (cycles / first.bin) as usize + 1);
        runs.push((w, t));
    }
    let span = runs.iter().map(|(_, t)| t.total).max().unwrap_or(0);
    let mut v = Vec::new();
    for (w, t) in &runs {
        let names: Vec<String> = w.stages.iter().map(|s| s.id.name().to_string()).collect();
        let size = (1240, 90 + 46 * names.len() as u32);
        let schedule = match (&r.report.cycles.schedules, w.schedule) {
            (None, _) => String::new(),
            (Some(_), s) => format!(", dof.schedule = \"{}\"", s.name()),
        };
        let f = Frame {
            title: format!(
                "cycle simulation: stage states over the frame{schedule} ({} cycles)",
                t.total
            ),
            x: format!("cycle (bins of {})", t.bin),
            y: String::new(),
            size,
        };
        let svg = plots::timeline(&f, t, &names, span).map_err(|e| plot_error("timeline", e))?;
        v.push(svg_picture(
            &f.title,
            format!(
                "per timed stage ({}), the share of each bin's cycles busy, stalled (the next FIFO or the line buffers full), starved (waiting for input) and idle",
                names.join(", ")
            ),
            svg,
            size,
        ));
    }
    Ok(v)
}

fn fmt_gamma(exponent: f64) -> String {
    format!("{:.3}", 1.0 / exponent)
        .trim_end_matches('0')
        .trim_end_matches('.')
        .into()
}

/// The gamma stage's LUT ROM (its first memory image), if the plan has one: its size and
/// about 512 of its entries as (input, output / largest output). The input is the address
/// over full white for a linear frame, the log intensity `L` of the address for a log frame
/// (addresses below `L = 0` and the zero code left out).
fn lut_points(r: &Render) -> Option<(usize, Vec<(f64, f64)>)> {
    let i = r.steps.iter().position(|s| s.id == StageId::Gamma)?;
    let img = r.steps[i].outcome.images.first()?;
    let table: Vec<u64> = (0..img.words).map(|w| (img.get)(w, 0)).collect();
    let coding = &r.steps[i.checked_sub(1)?].outcome.taps.fixed.frame().coding;
    let last = (table.len() - 1).max(1) as f64;
    let max = table.iter().copied().max().unwrap_or(1).max(1) as f64;
    let x = |a: usize| match coding {
        FrameCoding::Linear => Some(a as f64 / last),
        FrameCoding::Log(add) => {
            let l = (a as i64 - add.off) as f64 / add.unit();
            (a as i64 != ZERO && l >= 0.0).then_some(l)
        }
    };
    let step = (table.len() / 512).max(1);
    let points = (0..table.len())
        .step_by(step)
        .filter_map(|a| Some((x(a)?, table[a] as f64 / max)))
        .collect();
    Some((table.len(), points))
}

/// Sigma against screen z: the lens's exact curve over the depths of the frame and, for a
/// layered plan, each layer's sigma over its depth range.
fn sigma_plot(scene: &Scene, hw: &HwConfig, r: &Render) -> Result<Option<Picture>> {
    if !r
        .plan
        .decisions
        .iter()
        .any(|d| d.stage == StageId::Dof && d.need.planned)
    {
        return Ok(None);
    }
    let Some(acc) = r.taps(StageId::Accumulate) else {
        return Ok(None);
    };
    let frame = &acc.fixed.frame().frame;
    let Some(lens) = LensMap::of(scene, hw, frame.height) else {
        return Ok(None);
    };
    let keys = frame.depth.iter().copied().filter(|&k| k != u32::MAX);
    let (lo, hi) = keys.fold((u32::MAX, 0), |(a, b), k| (a.min(k), b.max(k)));
    let (z0, z1) = if lo <= hi {
        (lens.z_of(lo), lens.z_of(hi))
    } else {
        (0.0, 1.0)
    };
    let pad = (z1 - z0).max(1e-3) * 0.05;
    let (z0, z1) = ((z0 - pad).max(0.0), (z1 + pad).min(1.0));
    let mut series = vec![Series {
        name: "exact sigma of the thin lens".into(),
        colour: RGBColor(31, 119, 180),
        mark: Mark::Line,
        points: (0..=400)
            .map(|i| {
                let z = z0 + (z1 - z0) * i as f64 / 400.0;
                (z, lens.sigma_z(z))
            })
            .collect(),
    }];
    if let Some(layers) = dof_layers(r) {
        let fore: Vec<&LayerNote> = layers.iter().filter(|l| l.key_far != u32::MAX).collect();
        series.push(Series {
            name: "layers: sigma over their depth range".into(),
            colour: RGBColor(214, 39, 40),
            mark: Mark::Segments,
            points: fore
                .iter()
                .flat_map(|l| [(l.z_range.0, l.sigma), (l.z_range.1, l.sigma)])
                .collect(),
        });
        series.push(Series {
            name: "layer middles".into(),
            colour: RGBColor(214, 39, 40),
            mark: Mark::Dots(4),
            points: fore.iter().map(|l| (l.z_mid, l.sigma)).collect(),
        });
    }
    let f = Frame {
        title: "depth of field: sigma against depth".into(),
        x: "screen z".into(),
        y: "sigma, pixels (negative in front of the focus)".into(),
        size: SIZE,
    };
    let at = Some(plotters::chart::SeriesLabelPosition::UpperLeft);
    let svg = plots::curves(&f, &series, at).map_err(|e| plot_error("sigma", e))?;
    Ok(Some(svg_picture(
        &f.title,
        format!(
            "over the depths of the frame (dof.sigma = {:?}); the background's sigma is that of infinity",
            format!("{:?}", hw.dof.sigma).to_lowercase()
        ),
        svg,
        SIZE,
    )))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stage::RunOptions;

    /// The LUT read back from the ROM lies on the curve of its coding: `I^(1/gamma)` of a
    /// linear code, eq. 15 of the log intensity for a log frame, within half a DAC code.
    #[test]
    fn the_lut_points_lie_on_their_coding_curve() {
        let scene = Scene::embedded("default-pinhole").unwrap();
        for (preset, log) in [("linear12", false), ("log8-logadd", true)] {
            let hw = HwConfig::preset(preset).unwrap();
            let r = crate::pipeline::render(&scene, &hw, RunOptions::FAST).unwrap();
            let spec = gamma_spec(&scene, &hw);
            let code = log_code(&scene, &hw).unwrap();
            let (entries, points) = lut_points(&r).unwrap();
            assert!(
                points.len() >= 128 && entries >= points.len(),
                "{preset}: {} points of {entries}",
                points.len()
            );
            let max = spec.dac.format.max_code() as f64;
            for &(x, y) in &points {
                let ideal = if log {
                    spec.power(code.linear_of_log(x))
                } else {
                    spec.power(x)
                };
                assert!(
                    (y - ideal).abs() <= 0.5 / max + 1e-12,
                    "{preset}: LUT at {x} is {y}, the curve {ideal}"
                );
            }
        }
    }
}
