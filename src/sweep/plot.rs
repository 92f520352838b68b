//! The Pareto plot of a sweep (`--plot F.svg` / `F.png`), drawn with `plotters`: the first
//! `--axes` axis (an error) against cost, against throughput and against every further
//! `--axes` axis (e.g. `emulator_time`), one panel each; every row a grey dot, each scene's
//! Pareto front on the panel's two axes a coloured line through its configurations, each
//! labelled `#index` (the row's configuration index, as in the table and the printed front).
//!
//! Text uses DejaVu Sans, embedded (the `dejavu` crate), so a PNG renders the same on a
//! machine without system fonts.

use super::Row;
use super::pareto::{Axis, front};
use crate::error::{Error, FileError, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Plot size in pixels (SVG user units) of the two standard panels.
pub const SIZE: (u32, u32) = (1100, 460);

/// The horizontal axes of the panels for `--axes`: cost, throughput, then every further axis
/// after the first that is not one of those.
pub fn panel_axes(axes: &[Axis]) -> Vec<Axis> {
    let mut v = vec![Axis::Cost, Axis::Throughput];
    for &a in axes.iter().skip(1) {
        if !v.contains(&a) && Some(&a) != axes.first() {
            v.push(a);
        }
    }
    v
}

/// Plot size for `panels` panels side by side.
pub fn size(panels: usize) -> (u32, u32) {
    (SIZE.0 / 2 * panels.max(1) as u32, SIZE.1)
}

/// The image formats `--plot` writes, by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlotFormat {
    /// `.svg`
    Svg,
    /// `.png`
    Png,
}

impl PlotFormat {
    /// The format of a path, by its extension.
    pub fn of(path: &str) -> std::result::Result<PlotFormat, String> {
        let lower = path.to_ascii_lowercase();
        if lower.ends_with(".svg") {
            Ok(PlotFormat::Svg)
        } else if lower.ends_with(".png") {
            Ok(PlotFormat::Png)
        } else {
            Err(format!(
                "`{path}`: give a .svg or .png file (the format follows the extension)"
            ))
        }
    }
}

fn plot_error(path: &str, e: impl std::fmt::Display) -> Error {
    Error::File(FileError {
        file: path.into(),
        line: None,
        col: None,
        field: String::new(),
        msg: format!("cannot draw the Pareto plot: {e}"),
    })
}

/// Registers the embedded font once (plotters keeps a process-wide font table).
pub(crate) fn font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // DejaVu Sans is a valid TrueType font; a failure here would leave plotters
        // without a font, which `draw` then reports as a drawing error.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

/// Writes the plot of `rows` to `path` (SVG or PNG by extension), with `axes[0]` as the
/// vertical axis and [`panel_axes`] as the panels' horizontal ones. The plot is drawn into a temporary file in the same folder (ending with the
/// same file name, so the format is the same) and renamed onto `path`: a failed or killed
/// run never leaves a half-written plot, and on an error `path` is left as it was.
pub fn write(rows: &[Row], axes: &[Axis], path: &str) -> Result<()> {
    let format = PlotFormat::of(path).map_err(|m| plot_error(path, m))?;
    let error = axes.first().copied().unwrap_or(Axis::Error);
    let xs = panel_axes(axes);
    let dims = size(xs.len());
    font();
    super::rows::write_via_temp(path, |tmp| match format {
        PlotFormat::Svg => {
            let root = SVGBackend::new(tmp, dims).into_drawing_area();
            draw(&root, rows, error, &xs).map_err(|e| plot_error(path, e))?;
            root.present().map_err(|e| plot_error(path, e))
        }
        PlotFormat::Png => {
            let root = BitMapBackend::new(tmp, dims).into_drawing_area();
            draw(&root, rows, error, &xs).map_err(|e| plot_error(path, e))?;
            root.present().map_err(|e| plot_error(path, e))
        }
    })
}

/// The plot of [`write`] as an SVG document (for the HTML report).
pub fn svg(rows: &[Row], axes: &[Axis]) -> Result<String> {
    let error = axes.first().copied().unwrap_or(Axis::Error);
    let xs = panel_axes(axes);
    font();
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size(xs.len())).into_drawing_area();
        draw(&root, rows, error, &xs).map_err(|e| plot_error("<html>", e))?;
        root.present().map_err(|e| plot_error("<html>", e))?;
    }
    Ok(text)
}

/// The range of `v` with a 5 % margin (a unit range around a single value).
pub(crate) fn padded(v: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = v
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        0.0..1.0
    } else if hi > lo {
        let m = (hi - lo) * 0.05;
        lo - m..hi + m
    } else {
        let m = if lo == 0.0 { 1.0 } else { lo.abs() * 0.05 };
        lo - m..hi + m
    }
}

/// A range with a quarter of its span added on top: room for the legend above the points.
fn headroom(r: std::ops::Range<f64>) -> std::ops::Range<f64> {
    r.start..r.end + 0.25 * (r.end - r.start)
}

/// A tick label: plain for moderate magnitudes, scientific otherwise.
pub(crate) fn tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if (0.01..1e5).contains(&a) {
        format!("{v:.3}")
            .trim_end_matches('0')
            .trim_end_matches('.')
            .into()
    } else {
        format!("{v:.2e}")
    }
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    rows: &[Row],
    error: Axis,
    xs: &[Axis],
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let panels = root.split_evenly((1, xs.len()));
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    scenes.sort_unstable();
    scenes.dedup();
    for (area, &x_axis) in panels.iter().zip(xs) {
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!("{} vs {}", error.name(), x_axis.name()),
                ("sans-serif", 18),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(
                padded(rows.iter().map(|r| x_axis.value(r))),
                headroom(padded(rows.iter().map(|r| error.value(r)))),
            )?;
        let x_mid = {
            let r = chart.x_range();
            (r.start + r.end) / 2.0
        };
        chart
            .configure_mesh()
            .x_desc(x_axis.name())
            .y_desc(error.name())
            .x_labels(6)
            .y_labels(6)
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .label_style(("sans-serif", 12))
            .draw()?;
        chart
            .draw_series(rows.iter().map(|r| {
                Circle::new(
                    (x_axis.value(r), error.value(r)),
                    3,
                    RGBColor(150, 150, 150).filled(),
                )
            }))?
            .label("configuration")
            .legend(|(x, y)| Circle::new((x + 10, y), 3, RGBColor(150, 150, 150).filled()));
        let idx = front(rows, &[error, x_axis]);
        for (k, scene) in scenes.iter().enumerate() {
            let colour = if k == 0 {
                RED.to_rgba()
            } else {
                Palette99::pick(k).to_rgba()
            };
            let mut front_rows: Vec<(f64, f64, usize)> = idx
                .iter()
                .map(|&i| &rows[i])
                .filter(|r| r.scene == *scene)
                .map(|r| (x_axis.value(r), error.value(r), r.index))
                .collect();
            front_rows.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
            let pts: Vec<(f64, f64)> = front_rows.iter().map(|p| (p.0, p.1)).collect();
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), colour.stroke_width(2)))?
                .label(format!("Pareto front: {scene}"))
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2))
                });
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, colour.filled())))?;
            // Each front point labelled with its row index (the table's `index` column).
            // Right of the point in the left half, left of it in the right half (inside the plot).
            chart.draw_series(front_rows.iter().map(|&(x, y, i)| {
                let label = format!("#{i}");
                let dx = if x > x_mid {
                    -6 - 7 * label.len() as i32
                } else {
                    6
                };
                EmptyElement::at((x, y))
                    + Text::new(
                        label,
                        (dx, -14),
                        ("sans-serif", 11).into_font().color(&colour),
                    )
            }))?;
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    }
    Ok(())
}

/// The legend of a chart's labelled series: a white box with a black border, 12-px labels,
/// at `pos` (the sweep plot and the HTML report's plots).
pub(crate) fn legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    pos: SeriesLabelPosition,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 12))
        .position(pos)
        .draw()
}
