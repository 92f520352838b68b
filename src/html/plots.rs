//! The plots of the HTML report, drawn with `plotters` into SVG text: curves (the gamma
//! LUT's transfer, sigma against depth), the histogram of code differences and the stage
//! timeline of the cycle simulation.

use super::timeline::Timeline;
use crate::cycles::State;
use crate::sweep::plot::{font, legend, padded, tick};
use plotters::prelude::*;

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// A line through the points.
    Line,
    /// A dot of this radius per point.
    Dots(u32),
    /// A horizontal segment per pair of points (`[x0, x1]` at one height).
    Segments,
}

/// One series of a [`curves`] plot.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// Colour.
    pub colour: RGBColor,
    /// How it is drawn.
    pub mark: Mark,
    /// Points `(x, y)`.
    pub points: Vec<(f64, f64)>,
}

/// Axes and size of a plot.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Title.
    pub title: String,
    /// Horizontal axis.
    pub x: String,
    /// Vertical axis.
    pub y: String,
    /// Size in SVG user units.
    pub size: (u32, u32),
}

type DrawResult<T> = Result<T, String>;

fn err(e: impl std::fmt::Display) -> String {
    e.to_string()
}

/// An SVG of `f.size` on white: `draw` gets a chart builder with the frame's title,
/// margin and label areas (`y_area` wide on the left) and draws the chart.
fn svg(
    f: &Frame,
    y_area: u32,
    draw: impl FnOnce(ChartBuilder<'_, '_, SVGBackend<'_>>) -> DrawResult<()>,
) -> DrawResult<String> {
    font();
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, f.size).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let mut b = ChartBuilder::on(&root);
        b.caption(&f.title, ("sans-serif", 17))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(y_area);
        draw(b)?;
        root.present().map_err(err)?;
    }
    Ok(text)
}

/// The legend of `series` as the page's keys under a figure (outside the plot, so it can
/// cover no curve).
pub fn keys(series: &[Series]) -> Vec<super::images::Key> {
    series
        .iter()
        .map(|s| super::images::Key {
            colour: format!("#{:02x}{:02x}{:02x}", s.colour.0, s.colour.1, s.colour.2),
            label: s.name.clone(),
        })
        .collect()
}

/// Draws `series` into one chart (SVG text), its legend inside at `at`, or none (`None`: the
/// page shows [`keys`] under the figure instead).
pub fn curves(f: &Frame, series: &[Series], at: Option<SeriesLabelPosition>) -> DrawResult<String> {
    let all = || series.iter().flat_map(|s| s.points.iter());
    svg(f, 60, |mut b| {
        let mut chart = b
            .build_cartesian_2d(padded(all().map(|p| p.0)), padded(all().map(|p| p.1)))
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(&f.x)
            .y_desc(&f.y)
            .x_labels(6)
            .y_labels(6)
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(err)?;
        for s in series {
            let c = s.colour;
            let drawn = match s.mark {
                Mark::Line => chart
                    .draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2)))
                    .map_err(err)?,
                Mark::Dots(r) => chart
                    .draw_series(s.points.iter().map(|&p| Circle::new(p, r, c.filled())))
                    .map_err(err)?,
                Mark::Segments => chart
                    .draw_series(
                        s.points
                            .chunks_exact(2)
                            .map(|p| PathElement::new([p[0], p[1]], c.stroke_width(4))),
                    )
                    .map_err(err)?,
            };
            drawn
                .label(&s.name)
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], c.stroke_width(3)));
        }
        match at {
            Some(at) => legend(&mut chart, at).map_err(err),
            None => Ok(()),
        }
    })
}

/// The histogram of code differences (fixed minus reference) with a logarithmic count axis.
pub fn histogram(f: &Frame, bars: &[(i64, u64)]) -> DrawResult<String> {
    font();
    let lo = bars.iter().map(|b| b.0).min().unwrap_or(0) - 1;
    let hi = bars.iter().map(|b| b.0).max().unwrap_or(0) + 1;
    let top = bars.iter().map(|b| b.1).max().unwrap_or(1).max(1) as f64 * 3.0;
    svg(f, 60, |mut b| {
        let mut chart = b
            .build_cartesian_2d(lo as f64 - 0.5..hi as f64 + 0.5, (0.5f64..top).log_scale())
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(&f.x)
            .y_desc(&f.y)
            .x_labels(((hi - lo) as usize + 1).min(17))
            .x_label_formatter(&|v| format!("{:+}", v.round() as i64))
            .y_label_formatter(&|v| tick(*v))
            .label_style(("sans-serif", 12))
            .disable_x_mesh()
            .draw()
            .map_err(err)?;
        chart
            .draw_series(bars.iter().map(|&(d, n)| {
                let c = if d == 0 {
                    RGBColor(120, 120, 120)
                } else if d > 0 {
                    RGBColor(178, 24, 43)
                } else {
                    RGBColor(33, 102, 172)
                };
                Rectangle::new(
                    [(d as f64 - 0.4, 0.5), (d as f64 + 0.4, n.max(1) as f64)],
                    c.filled(),
                )
            }))
            .map_err(err)?;
        Ok(())
    })
}

/// State colours of the timeline: busy, stalled, starved, idle.
pub const STATE_COLOURS: [(State, &str, RGBColor); 4] = [
    (State::Busy, "busy", RGBColor(46, 160, 67)),
    (State::Stalled, "stalled", RGBColor(214, 39, 40)),
    (State::Starved, "starved", RGBColor(255, 170, 30)),
    (State::Idle, "idle", RGBColor(225, 225, 225)),
];

/// One band per stage (first on top); within a bin the band is split by the share of each
/// state, busy at the bottom. The cycle axis runs to `span` (at least the frame).
pub fn timeline(f: &Frame, t: &Timeline, names: &[String], span: u64) -> DrawResult<String> {
    let ns = t.counts.len();
    svg(f, 90, |mut b| {
        let mut chart = b
            .build_cartesian_2d(0f64..span.max(t.total).max(1) as f64, 0f64..ns as f64)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(&f.x)
            .x_labels(8)
            .x_label_formatter(&|v| tick(*v))
            .y_labels(ns * 2 + 1)
            .y_label_formatter(&|v| {
                // A label at the middle of each band.
                let k = v - v.floor();
                let i = v.floor() as usize;
                if (k - 0.5).abs() < 1e-6 && i < ns {
                    names[ns - 1 - i].clone()
                } else {
                    String::new()
                }
            })
            .disable_mesh()
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(err)?;
        let mut rects = Vec::new();
        for (i, bins) in t.counts.iter().enumerate() {
            let base = (ns - 1 - i) as f64 + 0.08;
            for (j, c) in bins.iter().enumerate() {
                let len = c.iter().sum::<u64>();
                if len == 0 {
                    continue;
                }
                let (x0, x1) = ((j as u64 * t.bin) as f64, (j as u64 * t.bin + len) as f64);
                let mut y = base;
                for (state, _, colour) in STATE_COLOURS {
                    let h = 0.84 * c[state as usize] as f64 / len as f64;
                    if h > 0.0 {
                        rects.push(Rectangle::new([(x0, y), (x1, y + h)], colour.filled()));
                    }
                    y += h;
                }
            }
        }
        chart.draw_series(rects).map_err(err)?;
        for (_, name, colour) in STATE_COLOURS {
            chart
                .draw_series(std::iter::empty::<Rectangle<(f64, f64)>>())
                .map_err(err)?
                .label(name)
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 14, y + 5)], colour.filled())
                });
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight).map_err(err)
    })
}
