//! The HTML reports: `igemu render --html`, `igemu sweep --html` (and `sweep merge`) and
//! `igemu sequence --html`.
//!
//! One self-contained file each, built from `minijinja` templates (`render.html`,
//! `sweep.html`, both extending `base.html`): every picture is an inline PNG and every
//! plot an inline SVG (`data:` URIs), the only script is the sweep table's sort, and a
//! Content-Security-Policy forbids any other source, so the file can be mailed or attached
//! to a review and opens without a network. The text and JSON outputs are not changed by it.
//!
//! * [`images`]: DAC codes (grey, or RGB for a colour render), the difference heat map with
//!   its legend, the banding map, the depth-of-field layer map and the CIEDE2000 legend, as
//!   PNG data.
//! * [`colour`]: a colour render's RGB pictures, its CIEDE2000 heat map and colour figures.
//! * [`plots`]: the gamma LUT's transfer (the paper's Fig. 6), the histogram of code
//!   differences, each stage's state timeline, sigma against depth.
//! * [`timeline`]: the cycle simulation's trace binned per stage.
//! * [`render`] and [`sweep`]: what each page shows, gathered into the templates' context.

pub mod colour;
pub mod figures;
pub mod images;
pub mod plots;
pub mod render;
pub mod sequence;
pub mod sweep;
pub mod timeline;

use crate::config::HwConfig;
use crate::error::{Error, Result};
use crate::pipeline::Render;
use crate::scene::Scene;
use crate::sweep::Row;
use crate::sweep::pareto::Axis;
use minijinja::{Environment, context};

fn environment() -> Environment<'static> {
    let mut env = Environment::new();
    // Names ending in .html are auto-escaped.
    for (name, text) in [
        ("base.html", include_str!("base.html")),
        ("picture.html", include_str!("picture.html")),
        ("render.html", include_str!("render.html")),
        ("sequence.html", include_str!("sequence.html")),
        ("sweep.html", include_str!("sweep.html")),
    ] {
        env.add_template(name, text)
            .expect("the embedded templates parse (tested)");
    }
    env
}

fn page_error(path: &str, msg: impl std::fmt::Display) -> Error {
    Error::Image {
        path: path.into(),
        msg: format!("cannot build the HTML report: {msg}"),
    }
}

/// The HTML report of render `r` of `scene` on `hw`; `path` names the file in errors.
pub fn render_page(scene: &Scene, hw: &HwConfig, r: &Render, path: &str) -> Result<String> {
    let page = render::page(scene, hw, r).map_err(|m| page_error(path, m))?;
    environment()
        .get_template("render.html")
        .and_then(|t| t.render(context! { page => minijinja::value::Serde(&page) }))
        .map_err(|e| page_error(path, e))
}

/// The HTML report of sequence `r`, with its frames as an animated PNG (`apng`: the bytes,
/// width and height) when given; `path` names the file in errors.
pub fn sequence_page(
    r: &crate::sequence::SequenceReport,
    apng: Option<(&[u8], u32, u32)>,
    path: &str,
) -> Result<String> {
    let page = sequence::page(r, apng).map_err(|m| page_error(path, m))?;
    environment()
        .get_template("sequence.html")
        .and_then(|t| t.render(context! { page => minijinja::value::Serde(&page) }))
        .map_err(|e| page_error(path, e))
}

/// The HTML report of a sweep's `rows` on `axes`; `source` (the grid or the merged parts)
/// titles it and `path` names the file in errors.
pub fn sweep_page(rows: &[Row], axes: &[Axis], source: &str, path: &str) -> Result<String> {
    let svg = crate::sweep::plot::svg(rows, axes)?;
    let page = sweep::page(rows, axes, &svg, source);
    environment()
        .get_template("sweep.html")
        .and_then(|t| t.render(context! { page => minijinja::value::Serde(&page) }))
        .map_err(|e| page_error(path, e))
}
