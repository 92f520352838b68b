//! What the HTML report of a sweep shows: the Pareto plot and every row in a sortable table,
//! the rows of the front marked.

use super::images::{self, Picture};
use crate::sweep::Row;
use crate::sweep::pareto::{Axis, front};
use serde::Serialize;

/// The sweep page's data (the template's context).
#[derive(Serialize)]
pub struct SweepPage {
    /// Page title.
    pub title: String,
    /// igemu version.
    pub version: String,
    /// One-line facts under the title.
    pub facts: Vec<(String, String)>,
    /// The Pareto plot.
    pub plot: Picture,
    /// Column headings.
    pub columns: Vec<String>,
    /// Rows: cells, and whether the row is on the front.
    pub rows: Vec<TableRow>,
}

/// One row of the table.
#[derive(Serialize)]
pub struct TableRow {
    /// Whether the row is on the Pareto front of the axes.
    pub front: bool,
    /// Cells: shown text and the sort key (a number where the column is numeric).
    pub cells: Vec<Cell>,
}

/// One cell.
#[derive(Serialize)]
pub struct Cell {
    /// Shown text.
    pub text: String,
    /// Sort key: a number, or the text.
    pub key: String,
}

fn num(v: f64, digits: usize) -> Cell {
    Cell {
        text: if v.is_finite() {
            format!("{v:.digits$}")
        } else {
            "-".into()
        },
        key: if v.is_finite() {
            format!("{v:e}")
        } else {
            "Infinity".into()
        },
    }
}

fn text(s: impl Into<String>) -> Cell {
    let s = s.into();
    Cell {
        key: s.clone(),
        text: s,
    }
}

/// Gathers the page of `rows` ranked on `axes`; `plot_svg` is the Pareto plot.
pub fn page(rows: &[Row], axes: &[Axis], plot_svg: &str, source: &str) -> SweepPage {
    let on_front = {
        let mut v = vec![false; rows.len()];
        for i in front(rows, axes) {
            v[i] = true;
        }
        v
    };
    let mut keys: Vec<&String> = rows.iter().flat_map(|r| r.config.keys()).collect();
    keys.sort();
    keys.dedup();
    let mut columns: Vec<String> = ["front", "index", "scene"].map(String::from).into();
    columns.extend(keys.iter().map(|k| k.to_string()));
    columns.extend(
        [
            "mean Weber",
            "max Weber",
            "mean |code diff|",
            "max |code diff|",
            "identical %",
            "contour steps",
            "storage + LUT bits",
            "adders",
            "multipliers",
            "fps",
            "bottleneck",
            "fixed ms",
        ]
        .map(String::from),
    );
    // A colour render's rows: their CIEDE2000 and hue shift (no columns on a grey sweep).
    let colour = rows.iter().any(|r| r.colour.is_some());
    if colour {
        columns.extend(
            [
                "mean CIEDE2000",
                "p99 CIEDE2000",
                "px over 2.3",
                "mean hue shift deg",
            ]
            .map(String::from),
        );
    }
    let extra: Vec<Axis> = axes
        .iter()
        .copied()
        .filter(|a| {
            matches!(
                a,
                Axis::Flicker | Axis::TruthTotal | Axis::TruthAlgorithm | Axis::TruthQuantisation
            )
        })
        .collect();
    columns.extend(extra.iter().map(|a| a.name().to_string()));
    let table = rows
        .iter()
        .zip(&on_front)
        .map(|(r, &f)| {
            let mut cells = vec![
                text(if f { "yes" } else { "" }),
                num(r.index as f64, 0),
                text(r.scene.clone()),
            ];
            for k in &keys {
                cells.push(match r.config.get(*k) {
                    Some(serde_json::Value::Number(n)) => {
                        let v = n.as_f64().unwrap_or(f64::NAN);
                        Cell {
                            text: n.to_string(),
                            key: format!("{v:e}"),
                        }
                    }
                    Some(serde_json::Value::String(s)) => text(s.clone()),
                    Some(v) => text(v.to_string()),
                    None => text(""),
                });
            }
            let e = &r.error;
            cells.extend([
                num(e.weber_mean, 6),
                num(e.weber_max, 4),
                num(e.mean_code_diff, 4),
                num(e.max_code_diff as f64, 0),
                num(100.0 * e.identical_fraction, 3),
                num(e.contour_steps as f64, 0),
                num((r.cost.storage_bits + r.cost.lut_bits) as f64, 0),
                num(r.cost.adders as f64, 0),
                num(r.cost.multipliers as f64, 0),
                num(r.cycles.fps, 1),
                text(r.cycles.bottleneck.clone()),
                num(r.timing.fixed_ms, 1),
            ]);
            if colour {
                cells.extend(match &r.colour {
                    Some(c) => [
                        num(c.delta_e_mean, 4),
                        num(c.delta_e_p99, 4),
                        num(c.delta_e_over_jnd as f64, 0),
                        num(c.hue_shift_mean_deg, 3),
                    ],
                    None => [f64::INFINITY; 4].map(|v| num(v, 0)),
                });
            }
            cells.extend(extra.iter().map(|a| num(a.value(r), 6)));
            TableRow { front: f, cells }
        })
        .collect();
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.sort_unstable();
    scenes.dedup();
    let plot_size = crate::sweep::plot::size(crate::sweep::plot::panel_axes(axes).len());
    let n_front = on_front.iter().filter(|&&f| f).count();
    let axis_names: Vec<&str> = axes.iter().map(|a| a.name()).collect();
    SweepPage {
        title: format!("igemu sweep: {source}"),
        version: env!("CARGO_PKG_VERSION").into(),
        facts: vec![
            ("rows".into(), rows.len().to_string()),
            ("scenes".into(), scenes.join(", ")),
            (
                "Pareto front".into(),
                format!("{n_front} rows on {}", axis_names.join(" x ")),
            ),
        ],
        plot: Picture {
            title: "Pareto fronts".into(),
            caption: format!(
                "{} against each panel's axis; grey: every row, a line per scene: its front on the panel's two axes, each point labelled #index (the table's index column)",
                axis_names.first().copied().unwrap_or("error")
            ),
            uri: images::svg_uri(plot_svg),
            width: plot_size.0,
            height: plot_size.1,
            legend: Vec::new(),
        },
        columns,
        rows: table,
    }
}
