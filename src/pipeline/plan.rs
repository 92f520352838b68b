//! The plan: built from the scene and the hardware before any stage runs, and then data
//! (printed, in the JSON report, the source of the cycle chains).
//!
//! * **Stages.** Every stage says whether this scene and hardware need it and why
//!   ([`crate::stage::Stage::plan`]); the planned ones run in flow order, except a stage that
//!   asks to run before another (the dither placed before the gamma LUT).
//! * **Region.** The host front end (f64: tessellation, transform, projection, shading;
//!   not a modelled stage) gives the screen-space primitives; their vertex coordinates
//!   quantised with `input.coord` (exactly as the input stage will) bound each primitive,
//!   widened by the filter's apron. The union, clipped to the screen, is the region: every
//!   pixel outside it sees only background samples and takes the background code.
//! * **Tiles.** Each primitive is binned to the `cycles.tile`-sized tiles it can reach
//!   inside the region (as a tiling rasteriser bins at setup): a triangle to the tiles whose
//!   pixels' filter windows hold a sample centre it meets (a separating-axis test on its
//!   quantised vertices), a line or a light point to the tiles of its box. The accumulate
//!   stage computes the pixels of binned tiles only; the cycle model has one pixel-chain
//!   token per binned tile. A binned tile may hold only background samples (a sliver that
//!   covers no sample centre, a hidden light point); it is computed anyway, like the
//!   hardware would, and its pixels come out as the background code.

use crate::config::HwConfig;
use crate::error::{FileError, Result};
use crate::fnv::Fnv;
use crate::scene::{GuardBand, HostScene, Scene, front_end_in};
use crate::stage::accumulate::{Kernel, kernel, regions};
use crate::stage::{self, Grid, Layout, Need, Pool, Region, StageId, Tiles, input, ms_since};
use rayon::prelude::*;
use serde::Serialize;
use std::sync::Arc;
use std::time::Instant;

/// One stage's entry in the plan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Decision {
    /// The stage.
    pub stage: StageId,
    /// Whether it runs, why, and where.
    #[serde(flatten)]
    pub need: Need,
}

/// The plan of a render.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Every stage in flow order, in or out, with the reason.
    pub decisions: Vec<Decision>,
    /// The screen layout and the planned stages in run order.
    pub layout: Layout,
    /// The host front end's output.
    pub host: Arc<HostScene>,
    /// Host front-end wall time, ms.
    pub host_ms: f64,
    /// Key of the plan's input (the scene), the root of every stage's key.
    pub key: u64,
    /// What the memory estimate counts of the host's primitives on this layout, summed
    /// once: their covered samples (float fragments) and the fixed raster's runs.
    pub footprint: super::estimate::Footprint,
}

/// The guard band the host clips to, after checking that the coordinate format holds it.
pub fn guard_band(scene: &Scene, hw: &HwConfig) -> std::result::Result<GuardBand, FileError> {
    let gb = hw.raster.guard_band as f64;
    let (w, h) = (scene.image.width as f64, scene.image.height as f64);
    let f = hw.input.coord.format;
    let max = f.max_code() as f64 * f.lsb();
    let need = w.max(h) + gb + 1.0;
    if need > max {
        return Err(too_narrow(scene, hw, max, need));
    }
    Ok(GuardBand {
        x_min: -gb,
        x_max: w + gb,
        y_min: -gb,
        y_max: h + gb,
    })
}

/// The refusal of an `input.coord` that cannot hold the screen plus the guard band (up to
/// `max` px, `need` needed): a check across two files, so it names each of the three fields
/// with where its value comes from (file:line, or the preset), says the fix, and is located
/// at `input.coord` when the hardware file gives it, else at the scene's larger side.
fn too_narrow(scene: &Scene, hw: &HwConfig, max: f64, need: f64) -> FileError {
    let (w, h) = (scene.image.width, scene.image.height);
    let (f, gb) = (hw.input.coord.format, hw.raster.guard_band);
    let side = if h > w { "image.height" } else { "image.width" };
    let src = &hw.source;
    let (coord_at, gb_at) = (
        src.origin("input.coord", &hw.name),
        src.origin("raster.guard_band", &hw.name),
    );
    let side_at = scene.source.origin(side, &scene.name);
    let bits = (need.log2().ceil() as u32) + 1;
    let wide = crate::fixed::QFormat::new(true, bits, f.frac_bits);
    let fix = match (src.file_name(), src.base()) {
        // examples/q15-4.toml: linear12 with Q15.4 (holds 8192 px plus the largest band).
        (None, Some(b)) if b == crate::config::PRESETS[0] && f.frac_bits == 4 && bits <= 15 => {
            format!(": --hw examples/q15-4.toml is {b} with input.coord = \"Q15.4\"")
        }
        (None, Some(b)) => {
            format!(": a hardware file with preset = \"{b}\" and [input] coord = \"{wide}\"")
        }
        (Some(file), _) => format!(", e.g. input.coord = \"{wide}\" in {file}"),
        (None, None) => format!(", e.g. \"{wide}\""),
    };
    let fit = (max - gb as f64 - 1.0).floor();
    let fit = if fit >= 1.0 {
        format!("; or image.width and image.height in 1..={fit} with this hardware")
    } else {
        String::new()
    };
    let msg = format!(
        "the {w}x{h} screen ({side}, {side_at}) plus the guard band of {gb} px (raster.guard_band, {gb_at}) needs coordinates up to {need} px, but input.coord = {f} ({coord_at}) holds up to {max} px; give input.coord at least {bits} integer bits{fix}{fit}"
    );
    if src.locate("input.coord").is_none() && scene.source.locate(side).is_some() {
        scene.error(side, msg)
    } else {
        hw.error("input.coord", msg)
    }
}

/// Intensity channels of a render: 3 (R, G, B) for a colour scene or for hardware with
/// per-channel word widths, else 1 (grey).
pub fn channels(scene: &Scene, hw: &HwConfig) -> usize {
    if scene.channels() == 3 || hw.per_channel() {
        3
    } else {
        1
    }
}

/// Which stages run, in which order, with every decision.
pub fn decide(scene: &Scene, hw: &HwConfig) -> Result<(Vec<Decision>, Vec<StageId>)> {
    let mut decisions = Vec::new();
    for id in StageId::ALL {
        decisions.push(Decision {
            stage: id,
            need: stage::get(id).plan(scene, hw)?,
        });
    }
    let mut order: Vec<StageId> = decisions
        .iter()
        .filter(|d| d.need.planned && d.need.before.is_none())
        .map(|d| d.stage)
        .collect();
    for d in decisions.iter().filter(|d| d.need.planned) {
        if let Some(b) = d.need.before {
            let at = order.iter().position(|&s| s == b).unwrap_or(order.len());
            order.insert(at, d.stage);
        }
    }
    Ok((decisions, order))
}

/// Primitives per part of the tile binning on the threads.
const BIN_PART: usize = 1024;

/// Builds the plan: decisions, host front end, region and tiles.
pub fn build(scene: &Scene, hw: &HwConfig) -> Result<Plan> {
    build_in(scene, hw, &Pool::new())
}

/// [`build`] with the host front end's primitive list from `pool` (a run of frames).
pub fn build_in(scene: &Scene, hw: &HwConfig, pool: &Pool) -> Result<Plan> {
    let (width, height) = (scene.image.width, scene.image.height);
    let guard = guard_band(scene, hw)?;
    let (decisions, order) = decide(scene, hw)?;
    let t = Instant::now();
    let mut parts = pool.take_lists();
    let host = front_end_in(
        scene,
        &guard,
        None,
        (pool.take(0), &mut parts),
        Some(pool.meshes()),
    );
    pool.give(parts);
    let host_ms = ms_since(t);
    let grid = Grid::new(hw.raster.samples, hw.subpixel_bits(), width, height);
    let prints = input::footprints(&host, hw);
    let screen = Region::screen(width, height);
    let kernel = kernel(hw);
    let (region, samples) = regions(&prints, &kernel, width, height);
    let mut tiles = Tiles::new(hw.cycles.tile, width, height);
    // On the threads, a map of binned tiles per part of the primitives, merged: a tile is
    // binned when any primitive bins it, whatever the parts.
    let bin = |prints: &[input::Footprint]| {
        let mut part = Tiles::new(hw.cycles.tile, width, height);
        for f in prints {
            let b = Region::of_box(&f.pixels, &screen);
            match &f.triangle {
                // A triangle bins only to the tiles whose filter windows' samples it meets.
                Some(t) => {
                    let window = |r: &Region| sample_window(r, &grid, &kernel);
                    part.bin_if(&b, &region, |r| input::triangle_meets(t, window(r)));
                }
                None => part.bin(&b, &region),
            }
        }
        part.touched
    };
    tiles.touched = prints.par_chunks(BIN_PART).map(bin).reduce(
        || tiles.touched.clone(),
        |mut a, b| {
            a.iter_mut().zip(b).for_each(|(a, b)| *a |= b);
            a
        },
    );
    let key = Fnv::new()
        .str(env!("CARGO_PKG_VERSION"))
        .str(&serde_json::to_string(scene).unwrap_or_default())
        .finish();
    let layout = Layout {
        grid,
        region,
        samples,
        tiles,
        order,
        band: None,
        channels: channels(scene, hw),
    };
    Ok(Plan {
        decisions,
        footprint: super::estimate::Footprint::of(&layout, &host),
        layout,
        host: Arc::new(host),
        host_ms,
        key,
    })
}

/// The rectangle `[x0, y0, x1, y1]` (coordinate units, closed) of the sample centres the
/// filter windows of the pixels of `r` read.
fn sample_window(r: &Region, g: &Grid, k: &Kernel) -> [i64; 4] {
    let n = g.n as i64;
    let centre = |c: i64| (2 * c + 1) * g.h;
    let first = |p: u32| p as i64 * n - k.off;
    let last = |p: u32| (p as i64 - 1) * n - k.off + k.size as i64 - 1;
    [
        centre(first(r.x0)),
        centre(first(r.y0)),
        centre(last(r.x1)),
        centre(last(r.y1)),
    ]
}

/// The plan as the report shows it.
#[derive(Clone, Debug, Serialize)]
pub struct PlanReport {
    /// Planned stages in run order.
    pub stages: Vec<String>,
    /// Every stage, in or out, with the reason.
    pub decisions: Vec<Decision>,
    /// Pixels modelled (half-open); the rest is background.
    pub region: Region,
    /// Fraction of the screen modelled.
    pub region_fraction: f64,
    /// Samples per pixel along an axis.
    pub samples: u32,
    /// Gamma the LUT corrects.
    pub gamma: f64,
    /// The tile map.
    pub tiles: TileReport,
    /// The memory estimate, made before any stage ran.
    pub memory: super::estimate::Estimate,
    /// What the user should know about this plan (options without effect, edge effects).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// The tile map in the report.
#[derive(Clone, Debug, Serialize)]
pub struct TileReport {
    /// Tile side, pixels.
    pub size: u32,
    /// Tile columns.
    pub cols: u32,
    /// Tile rows.
    pub rows: u32,
    /// Binned tiles.
    pub binned: u64,
    /// Pixels of binned tiles inside the region.
    pub binned_pixels: u64,
}

impl Plan {
    /// The memory estimate of running the plan with `opts`.
    pub fn memory(&self, opts: crate::stage::RunOptions) -> super::estimate::Estimate {
        super::estimate::estimate(self, opts)
    }
    /// The planned stages in run order.
    pub fn order(&self) -> &[StageId] {
        &self.layout.order
    }
    /// The report form.
    pub fn report(
        &self,
        scene: &Scene,
        hw: &HwConfig,
        opts: crate::stage::RunOptions,
    ) -> PlanReport {
        let l = &self.layout;
        PlanReport {
            stages: l.order.iter().map(|s| s.name().to_string()).collect(),
            decisions: self.decisions.clone(),
            region: l.region,
            region_fraction: l.region.pixels() as f64 / l.grid.pixels().max(1) as f64,
            samples: l.grid.n,
            gamma: hw.gamma.gamma.unwrap_or(scene.display.gamma),
            tiles: TileReport {
                size: l.tiles.size,
                cols: l.tiles.cols,
                rows: l.tiles.rows,
                binned: l.tiles.count() as u64,
                binned_pixels: l.tiles.touched_pixels(&l.region),
            },
            memory: self.memory(opts),
            notes: self.notes(hw, opts),
        }
    }

    /// Notes on the plan: an option that has no effect on it, and a guard band narrower
    /// than the filter's reach beyond the screen's edge (the edge pixels then read
    /// background samples where geometry was clipped away).
    pub fn notes(&self, hw: &HwConfig, opts: crate::stage::RunOptions) -> Vec<String> {
        let mut notes = Vec::new();
        if !self.layout.has(StageId::Dof) {
            let flags = [
                (opts.dof_reference, "--dof-reference"),
                (opts.dof_truth_samples > 0, "--dof-truth"),
            ];
            for (_, flag) in flags.iter().filter(|(on, _)| *on) {
                notes.push(format!(
                    "{flag} has no effect: the plan has no dof stage (a pinhole camera)"
                ));
            }
        }
        if self.layout.has(StageId::Dof) && hw.dof.kind == crate::config::DofKind::Layered {
            let n2 = hw.raster.samples * hw.raster.samples;
            notes.extend(stage::dof::width_note(
                hw.accumulate.frame.format,
                n2,
                &hw.dof,
            ));
        }
        let k = kernel(hw);
        let n = k.n as i64;
        let reach = k.off.max(k.size as i64 - n - k.off);
        let reach_px = (reach + n - 1) / n;
        if (hw.raster.guard_band as i64) < reach_px {
            notes.push(format!(
                "raster.guard_band = {} px is narrower than the {:?} filter's reach of {reach_px} px beyond the screen: the outermost {reach_px} pixel rows and columns read background samples where geometry was clipped away (they fade toward the background); use a guard band of at least {reach_px} px",
                hw.raster.guard_band, hw.accumulate.filter
            ));
        }
        notes
    }
}
