//! The plan and the run: scene + hardware config to DAC codes, fixed and float side by
//! side, with per-stage reports and the end-to-end comparison.
//!
//! Only what the scene needs is modelled: the pixel region is the bounding box of the
//! primitives (plus the filter apron) clipped to the screen; every pixel outside it sees
//! only the background and takes the background's code, computed once.

use crate::compare::{self, CodeCompare, DisplayModel, WeberCompare};
use crate::config::CodingKind;
use crate::config::HwConfig;
use crate::error::{FileError, Result};
use crate::fixed::SignalStats;
use crate::scene::{GuardBand, HostScene, Primitive, Scene, front_end};
use crate::stage::accumulate::{self, AccParams, AccRef, Frame, Kernel, PointFrags};
use crate::stage::dof::LayerWork;
use crate::stage::gamma::{self, GammaLut, GammaSpec};
use crate::stage::input::{self, QPrim};
use crate::stage::logdomain;
use crate::stage::raster::{
    self, FPrim, FVertex, Frag, FragF, RasterParams, RasterWork, SampleRegion,
};
use crate::stage::setup::{self, Setup, SetupWork};
use crate::stage::visibility::{self, Samples, SamplesF, VisWork, ZConvert};
use crate::stage::{Grid, LocalError, Region, StageReport, Unit, ms_since};
use serde::Serialize;
use std::time::Instant;

/// The plan: which stages run and on which region.
#[derive(Clone, Debug, Serialize)]
pub struct Plan {
    /// Stages in flow order.
    pub stages: Vec<String>,
    /// Pixels modelled (half-open); the rest is background.
    pub region: Region,
    /// Fraction of the screen modelled.
    pub region_fraction: f64,
    /// Samples per pixel along an axis.
    pub samples: u32,
    /// Gamma the LUT corrects.
    pub gamma: f64,
}

/// Scene facts for the report.
#[derive(Clone, Debug, Serialize)]
pub struct SceneInfo {
    /// Scene name.
    pub name: String,
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Host front end counts.
    pub front_end: crate::scene::FrontEndStats,
}

/// End-to-end comparison of DAC codes.
#[derive(Clone, Debug, Serialize)]
pub struct EndToEnd {
    /// Code by code.
    pub codes: CodeCompare,
    /// Through the display model.
    pub weber: WeberCompare,
}

/// Wall times.
#[derive(Clone, Debug, Serialize)]
pub struct Timing {
    /// Host front end (f64, shared by both models).
    pub host_ms: f64,
    /// Sum of the fixed stages.
    pub fixed_ms: f64,
    /// Sum of the float reference stages.
    pub float_ms: f64,
    /// Threads used.
    pub threads: usize,
}

/// The render report (`render --json`).
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Tool version.
    pub igemu_version: String,
    /// Scene.
    pub scene: SceneInfo,
    /// Hardware configuration.
    pub hardware: HwConfig,
    /// Plan.
    pub plan: Plan,
    /// Per stage, in flow order.
    pub stages: Vec<StageReport>,
    /// End-to-end comparison.
    pub end_to_end: EndToEnd,
    /// Overflows over all signals.
    pub overflows: u64,
    /// Total storage bits (RAM) and ROM bits.
    pub storage_bits: u64,
    /// Total LUT / ROM bits.
    pub lut_bits: u64,
    /// Timing.
    pub timing: Timing,
    /// Cycle model, throughput and cost summary.
    pub cycles: crate::cycles::CycleReport,
    /// Visible contours through the display model (see [`crate::perceptual`]).
    pub contours: crate::perceptual::ContourReport,
}

/// Everything a render produces.
pub struct Render {
    /// The report.
    pub report: Report,
    /// Fixed DAC codes, row-major.
    pub dac: Vec<u16>,
    /// Float reference DAC codes.
    pub dac_ref: Vec<u16>,
    /// Frame memory and per-pixel depth / coverage (fixed).
    pub frame: Frame,
    /// Frame intensity of the float reference (frame LSBs).
    pub frame_ref: Vec<f64>,
    /// DAC width.
    pub dac_bits: u32,
    /// The cycle model's token streams (to re-simulate with other timings or a VCD trace).
    pub workload: crate::cycles::Workload,
    /// Per pixel: 0 not smooth, 1 smooth, 2 next to a visible contour step.
    pub contour_map: Vec<u8>,
}

/// Options of a render.
#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    /// Run the stage-local comparisons (float stage on the fixed stage's input).
    pub stage_local: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self { stage_local: true }
    }
}

fn stage(name: &str) -> StageReport {
    StageReport {
        name: name.to_string(),
        ..Default::default()
    }
}

/// The guard band the host clips to, after checking that the coordinate format holds it.
pub fn guard_band(scene: &Scene, hw: &HwConfig) -> std::result::Result<GuardBand, FileError> {
    let gb = hw.raster.guard_band as f64;
    let (w, h) = (scene.image.width as f64, scene.image.height as f64);
    let f = hw.input.coord.format;
    let max = f.max_code() as f64 * f.lsb();
    let need = w.max(h) + gb + 1.0;
    if need > max {
        let bits = (need.log2().ceil() as u32) + 1;
        return Err(FileError {
            file: hw.name.clone(),
            line: None,
            col: None,
            field: "input.coord".into(),
            msg: format!(
                "{f} holds coordinates up to {max} px but the screen ({w}x{h}) plus the guard band ({gb} px) needs {need}; use at least {bits} integer bits"
            ),
        });
    }
    Ok(GuardBand {
        x_min: -gb,
        x_max: w + gb,
        y_min: -gb,
        y_max: h + gb,
    })
}

/// The pixel region the primitives touch (plus the filter apron), clipped to the screen.
pub fn region_of(prims: &[QPrim], hw: &HwConfig, width: u32, height: u32) -> Region {
    let s = hw.subpixel_bits();
    let (mut x0, mut y0, mut x1, mut y1) = (i64::MAX, i64::MAX, i64::MIN, i64::MIN);
    let mut add = |x: i64, y: i64, r: i64| {
        x0 = x0.min(x - r);
        y0 = y0.min(y - r);
        x1 = x1.max(x + r);
        y1 = y1.max(y + r);
    };
    for p in prims {
        match p {
            QPrim::Triangle(v) => v.iter().for_each(|v| add(v.x, v.y, 0)),
            QPrim::Line { a, b, width } => {
                add(a.x, a.y, *width);
                add(b.x, b.y, *width);
            }
            QPrim::Point { v, size } => add(v.x, v.y, *size),
        }
    }
    if x0 > x1 {
        return Region {
            x0: 0,
            y0: 0,
            x1: 0,
            y1: 0,
        };
    }
    let apron = hw.accumulate.filter.base() as i64 / 2 + 1;
    let px = |u: i64, up: bool| {
        if up {
            (u >> s) + 1 + apron
        } else {
            (u >> s) - apron
        }
    };
    let r = Region {
        x0: px(x0, false).clamp(0, width as i64) as u32,
        y0: px(y0, false).clamp(0, height as i64) as u32,
        x1: px(x1, true).clamp(0, width as i64) as u32,
        y1: px(y1, true).clamp(0, height as i64) as u32,
    };
    if r.is_empty() {
        Region {
            x0: 0,
            y0: 0,
            x1: 0,
            y1: 0,
        }
    } else {
        r
    }
}

/// Host primitive to float primitive in the fixed formats' units (no rounding).
fn fprim(p: &Primitive, white_i: f64, z_scale: f64) -> FPrim {
    let v = |v: &crate::scene::ScreenVertex| FVertex {
        x: v.x,
        y: v.y,
        z: v.z * z_scale,
        i: v.i * white_i,
    };
    match p {
        Primitive::Triangle(t) => FPrim::Triangle([v(&t[0]), v(&t[1]), v(&t[2])]),
        Primitive::Line { a, b, width } => FPrim::Line {
            a: v(a),
            b: v(b),
            width: *width,
        },
        Primitive::Point { v: c, size } => FPrim::Point {
            v: v(c),
            size: *size,
        },
    }
}

/// Merges two fragment lists sorted by sample index: coverage mismatches and attribute errors.
fn compare_frags(fx: &[Frag], fl: &[FragF], i_err: &mut LocalError, z_err: &mut LocalError) {
    let (mut a, mut b) = (0, 0);
    while a < fx.len() || b < fl.len() {
        if a < fx.len() && b < fl.len() && fx[a].s == fl[b].s {
            i_err.add(fx[a].i as f64, fl[b].i);
            z_err.add(fx[a].z as f64, fl[b].z);
            a += 1;
            b += 1;
        } else if b >= fl.len() || (a < fx.len() && fx[a].s < fl[b].s) {
            i_err.mismatched_items += 1;
            a += 1;
        } else {
            i_err.mismatched_items += 1;
            b += 1;
        }
    }
}

#[derive(Clone)]
/// Phase 1: host front end, input quantisation and the plan's region.
pub struct Front {
    /// Host scene (f64 screen-space primitives).
    pub host: HostScene,
    /// Host front-end time.
    pub host_ms: f64,
    /// Quantised primitives.
    pub qprims: Vec<QPrim>,
    /// The same primitives for the float reference (no rounding).
    pub fprims: Vec<FPrim>,
    /// Input stage report.
    pub input: StageReport,
    /// Sample grid.
    pub grid: Grid,
    /// Pixels modelled.
    pub region: Region,
    /// Filter kernel (its apron sizes the sample region).
    pub kernel: Kernel,
    /// Samples modelled.
    pub sreg: SampleRegion,
    /// Background intensity code and exact value (intensity LSBs).
    pub bg: (u32, f64),
}

/// Runs phase 1.
pub fn front(scene: &Scene, hw: &HwConfig) -> Result<Front> {
    let (width, height) = (scene.image.width, scene.image.height);
    let guard = guard_band(scene, hw)?;
    let t = Instant::now();
    let host: HostScene = front_end(scene, &guard);
    let host_ms = ms_since(t);
    let grid = Grid::new(hw.raster.samples, hw.subpixel_bits(), width, height);
    let i_fmt = hw.input.intensity.format;
    let white_i = ((1u64 << i_fmt.int_bits) - 1) as f64 * (1u64 << i_fmt.frac_bits) as f64;
    let z_scale = (1u64 << hw.input.z.format.frac_bits) as f64;

    let mut input = stage("input");
    let t = Instant::now();
    let qprims = input::quantize(&host, hw, &mut input)?;
    input.fixed_ms = ms_since(t);
    let t = Instant::now();
    let fprims: Vec<FPrim> = host
        .prims
        .iter()
        .map(|p| fprim(p, white_i, z_scale))
        .collect();
    input.float_ms = ms_since(t);

    let region = region_of(&qprims, hw, width, height);
    let kernel = Kernel::new(
        hw.accumulate.filter,
        grid.n,
        hw.accumulate.weight_bits,
        hw.accumulate.gaussian_sigma,
    );
    let sreg = if region.is_empty() {
        SampleRegion {
            c0: 0,
            k0: 0,
            c1: 0,
            k1: 0,
        }
    } else {
        accumulate::sample_region(&region, &kernel)
    };
    let bg = (
        input_background(&host, hw, white_i),
        host.background * white_i,
    );
    Ok(Front {
        host,
        host_ms,
        qprims,
        fprims,
        input,
        grid,
        region,
        kernel,
        sreg,
        bg,
    })
}

#[derive(Clone)]
/// Phase 2 output: the resolved sample buffers, fixed and float.
pub struct Geometry {
    /// Fixed sample buffer.
    pub samples: Samples,
    /// Fixed light points' visible samples.
    pub points: Vec<PointFrags<u32>>,
    /// Float sample buffer.
    pub samples_ref: SamplesF,
    /// Float light points.
    pub points_ref: Vec<PointFrags<f64>>,
    /// Setup, raster and visibility reports.
    pub reports: [StageReport; 3],
    /// Per-primitive work in processing order (the cycle model's token stream).
    pub prim_work: Vec<crate::cycles::PrimWork>,
}

/// Runs phase 2: setup, raster and visibility, fixed and float.
pub fn geometry(f: &Front, hw: &HwConfig, opts: RenderOptions) -> Result<Geometry> {
    let (grid, sreg) = (f.grid, f.sreg);
    let i_fmt = hw.input.intensity.format;
    let mut r_setup = stage("setup");
    let t = Instant::now();
    let mut sw = SetupWork::default();
    let setups: Vec<Setup> = f
        .qprims
        .iter()
        .map(|p| setup::setup(p, &grid, &mut sw))
        .collect();
    r_setup.fixed_ms = ms_since(t);
    r_setup.record_work(&[
        ("triangles", sw.triangles),
        ("degenerate", sw.degenerate),
        ("lines", sw.lines),
        ("points", sw.points),
    ]);
    let cb = hw.input.coord.format.total_bits();
    r_setup.cost.multipliers = vec![
        Unit::mul("edge start (x * dy)", 1, cb + 1, cb + 1),
        Unit::mul("edge step quotient (dx / dy)", 1, cb + 1, cb + 1),
        Unit::mul(
            "plane gradient (divide)",
            2,
            2 * cb + i_fmt.total_bits(),
            2 * cb + 2,
        ),
    ];

    let rp = RasterParams {
        grid,
        guard: hw.raster.interp_guard_bits,
        quant: hw.raster.interp_quant,
        i_max: i_fmt.max_code(),
        z_max: hw.input.z.format.max_code(),
    };
    let zc = ZConvert {
        shift: hw.input.z.format.frac_bits - hw.visibility.z.format.frac_bits,
        quant: hw.visibility.z.quant,
        max: hw.visibility.z.format.max_code() as u32,
    };
    let mut r_raster = stage("raster");
    let mut r_vis = stage("visibility");
    let mut rw = RasterWork::default();
    let mut vw = VisWork::default();
    let mut samples = Samples::new(sreg, f.bg.0);
    // Stage-local shadows: the float raster on the quantised primitives, and a float
    // z-buffer fed the fixed raster's fragments.
    let mut shadow = if opts.stage_local {
        Some(SamplesF::new(sreg, f.bg.0 as f64))
    } else {
        None
    };
    let (mut i_err, mut z_err) = (LocalError::default(), LocalError::default());
    let mut frags: Vec<Frag> = Vec::new();
    let mut ffr: Vec<FragF> = Vec::new();
    let mut exact: Vec<FragF> = Vec::new();
    let mut point_ids = Vec::new();
    let mut prim_work = Vec::with_capacity(setups.len());
    let vertices = |p: &QPrim| match p {
        QPrim::Triangle(_) => 3,
        QPrim::Line { .. } => 2,
        QPrim::Point { .. } => 1,
    };
    for (idx, s) in setups.iter().enumerate() {
        if matches!(s, Setup::Point(_)) {
            point_ids.push(idx);
            continue;
        }
        let before = (rw.samples + rw.walked, vw.tests);
        frags.clear();
        let t = Instant::now();
        raster::raster(s, &rp, &sreg, &mut frags, &mut rw);
        r_raster.fixed_ms += ms_since(t);
        let t = Instant::now();
        visibility::resolve(&frags, idx as u32 + 1, &zc, &mut samples, &mut vw);
        r_vis.fixed_ms += ms_since(t);
        prim_work.push(crate::cycles::PrimWork {
            vertices: vertices(&f.qprims[idx]),
            stepped: rw.samples + rw.walked - before.0,
            tests: vw.tests - before.1,
        });
        if let Some(sh) = shadow.as_mut() {
            ffr.clear();
            raster::raster_f64(
                &FPrim::from_q(&f.qprims[idx], grid.sub_bits),
                &grid,
                &sreg,
                &mut ffr,
            );
            // A line is two triangles: sort both lists so they merge by sample.
            frags.sort_by_key(|x| x.s);
            ffr.sort_by_key(|x| x.s);
            compare_frags(&frags, &ffr, &mut i_err, &mut z_err);
            exact.clear();
            exact.extend(frags.iter().map(|x| FragF {
                s: x.s,
                z: x.z as f64,
                i: x.i as f64,
            }));
            visibility::resolve_f64(&exact, idx as u32 + 1, sh);
        }
    }
    let mut points = Vec::new();
    for &idx in &point_ids {
        let before = (rw.samples + rw.walked, vw.point_tests);
        frags.clear();
        let t = Instant::now();
        raster::raster(&setups[idx], &rp, &sreg, &mut frags, &mut rw);
        r_raster.fixed_ms += ms_since(t);
        let t = Instant::now();
        let vis = visibility::point_visible(&frags, &zc, &samples, &mut vw);
        r_vis.fixed_ms += ms_since(t);
        prim_work.push(crate::cycles::PrimWork {
            vertices: 1,
            stepped: rw.samples + rw.walked - before.0,
            tests: vw.point_tests - before.1,
        });
        let i = match f.qprims[idx] {
            QPrim::Point { v, .. } => v.i.clamp(0, i_fmt.max_code()) as u32,
            _ => 0,
        };
        points.push(PointFrags { i, samples: vis });
    }
    r_raster.record_work(&[
        ("spans", rw.spans),
        ("samples", rw.samples),
        ("walked_samples", rw.walked),
        ("walked_rows", rw.rows_walked),
        ("reseeds", rw.reseeds),
    ]);
    let g = hw.raster.interp_guard_bits;
    r_raster.cost.adders = vec![
        Unit::adder("edge quotient/remainder", 6, cb + 2),
        Unit::adder("intensity interpolator", 2, i_fmt.total_bits() + g + 1),
        Unit::adder(
            "depth interpolator",
            2,
            hw.input.z.format.total_bits() + g + 1,
        ),
    ];
    let mut clamp_stats = SignalStats::new("raster.clamped", i_fmt);
    clamp_stats.add_overflows(rw.clamped);
    r_raster.signals.push(clamp_stats);
    if opts.stage_local {
        r_raster.local = Some(i_err.finish());
        r_raster.notes.insert(
            "depth_local".into(),
            serde_json::to_value(z_err.finish()).unwrap_or_default(),
        );
    }
    r_vis.record_work(&[
        ("tests", vw.tests),
        ("writes", vw.writes),
        ("point_tests", vw.point_tests),
        ("point_visible", vw.point_visible),
    ]);
    let zb = hw.visibility.z.format.total_bits();
    let full_samples = grid.sw() as u64 * grid.sh() as u64;
    let id_bits = (f.qprims.len() as u64 + 1)
        .next_power_of_two()
        .trailing_zeros()
        .max(1);
    r_vis.cost.storage_bits = full_samples * (zb + i_fmt.total_bits() + id_bits) as u64;
    r_vis.cost.adders = vec![Unit::adder("depth compare", 1, zb)];
    let mut zst = SignalStats::new("visibility.z", hw.visibility.z.format);
    zst.add_overflows(vw.clamped);
    r_vis.signals.push(zst);
    if let Some(sh) = &shadow {
        let mut e = LocalError::default();
        for (a, b) in samples.prim.iter().zip(&sh.prim) {
            e.values += 1;
            if a == b {
                e.identical += 1;
            } else {
                e.mismatched_items += 1;
            }
        }
        r_vis.local = Some(e);
    }
    r_vis
        .notes
        .insert("samples_in_region".into(), (sreg.len() as u64).into());

    // Float reference: the host's primitives, exact arithmetic.
    let mut samples_ref = SamplesF::new(sreg, f.bg.1);
    let mut points_ref = Vec::new();
    for (idx, p) in f.fprims.iter().enumerate() {
        if p.is_point() {
            continue;
        }
        ffr.clear();
        let t = Instant::now();
        raster::raster_f64(p, &grid, &sreg, &mut ffr);
        r_raster.float_ms += ms_since(t);
        let t = Instant::now();
        visibility::resolve_f64(&ffr, idx as u32 + 1, &mut samples_ref);
        r_vis.float_ms += ms_since(t);
    }
    for p in f.fprims.iter() {
        let FPrim::Point { v, .. } = p else { continue };
        ffr.clear();
        let t = Instant::now();
        raster::raster_f64(p, &grid, &sreg, &mut ffr);
        r_raster.float_ms += ms_since(t);
        let t = Instant::now();
        let vis = visibility::point_visible_f64(&ffr, &samples_ref);
        r_vis.float_ms += ms_since(t);
        points_ref.push(PointFrags {
            i: v.i,
            samples: vis.into_iter().map(|v| v.0).collect(),
        });
    }
    Ok(Geometry {
        samples,
        points,
        samples_ref,
        points_ref,
        reports: [r_setup, r_raster, r_vis],
        prim_work,
    })
}

#[derive(Clone)]
/// Phase 3 output: the frame memory, fixed and float.
pub struct Accumulated {
    /// Fixed frame memory, depth and coverage.
    pub frame: Frame,
    /// Float frame intensity (frame LSBs).
    pub frame_ref: Vec<f64>,
    /// Accumulate report.
    pub report: StageReport,
    /// The plan's touched tiles (the fixed model computed only these).
    pub tiles: crate::cycles::Tiles,
    /// Frame read-modify-writes per tile.
    pub tile_rmw: Vec<u64>,
}

/// Runs phase 3: filtering and accumulation, fixed and float.
pub fn accumulate_phase(
    f: &Front,
    g: &Geometry,
    hw: &HwConfig,
    opts: RenderOptions,
) -> Result<Accumulated> {
    let size = (f.grid.width, f.grid.height);
    let i_fmt = hw.input.intensity.format;
    let frame_fmt = hw.accumulate.frame.format;
    let ap = AccParams {
        kernel: f.kernel.clone(),
        i_frac: i_fmt.frac_bits,
        frame: hw.accumulate.frame,
    };
    let mut r = stage("accumulate");
    let t = Instant::now();
    let tiles = crate::cycles::Tiles::touched_by(
        hw.cycles.tile,
        &f.region,
        &f.kernel,
        &g.samples,
        &g.points,
        size.0,
        size.1,
    );
    let (frame, aw, acc_stats, tile_rmw) = accumulate::accumulate_tiles(
        &g.samples,
        &f.region,
        Some(&tiles),
        &g.points,
        &ap,
        f.bg.0,
        size,
    )?;
    r.fixed_ms = ms_since(t);
    r.record_work(&[
        ("pixels", aw.pixels),
        ("macs", aw.macs),
        ("fragments", aw.fragments),
        ("point_updates", aw.point_updates),
    ]);
    r.cost = accumulate::cost(&ap, i_fmt.total_bits(), size.0 as u64 * size.1 as u64);
    r.signals = acc_stats;
    let ar = |bg_i: f64| AccRef {
        kernel: &f.kernel,
        i_frac: i_fmt.frac_bits,
        frame_frac: frame_fmt.frac_bits,
        bg_i,
        size,
    };
    if opts.stage_local {
        let iv: Vec<f64> = g.samples.i.iter().map(|&v| v as f64).collect();
        let pts: Vec<PointFrags<f64>> = g
            .points
            .iter()
            .map(|p| PointFrags {
                i: p.i as f64,
                samples: p.samples.clone(),
            })
            .collect();
        let fl = accumulate::accumulate_f64(&iv, &f.sreg, &f.region, &pts, &ar(f.bg.0 as f64));
        let mut e = LocalError::default();
        let max = frame_fmt.max_code() as f64;
        for (&a, &b) in frame.acc.iter().zip(&fl) {
            e.add(a as f64, b.min(max));
        }
        r.local = Some(e.finish());
    }
    let t = Instant::now();
    let frame_ref = accumulate::accumulate_f64(
        &g.samples_ref.i,
        &f.sreg,
        &f.region,
        &g.points_ref,
        &ar(f.bg.1),
    );
    r.float_ms = ms_since(t);
    Ok(Accumulated {
        frame,
        frame_ref,
        report: r,
        tiles,
        tile_rmw,
    })
}

/// Phase 4 output: DAC codes, fixed and float.
pub struct Post {
    /// Fixed DAC codes.
    pub dac: Vec<u16>,
    /// Float reference DAC codes.
    pub dac_ref: Vec<u16>,
    /// Reports of the post stages (gamma).
    pub reports: Vec<StageReport>,
}

/// Runs phase 4: the gamma LUT to the DAC, fixed and float.
/// `powers` are the float frame's [`GammaSpec::power`]s ([`Reference::powers`]).
pub fn post(
    a: &Accumulated,
    scene: &Scene,
    hw: &HwConfig,
    opts: RenderOptions,
    powers: &[f64],
) -> Result<Post> {
    let frame_fmt = hw.accumulate.frame.format;
    let gamma_value = hw.gamma.gamma.unwrap_or(scene.display.gamma);
    let spec = GammaSpec::new(
        gamma_value,
        hw.gamma.correction,
        hw.gamma.dac_bits,
        hw.gamma.quant,
    );
    if hw.dither.kind != crate::config::DitherKind::None {
        let d = crate::stage::dither::post(
            &a.frame.acc,
            &a.frame_ref,
            (scene.image.width, scene.image.height),
            frame_fmt.int_bits,
            frame_fmt.frac_bits,
            &spec,
            &hw.dither,
            opts.stage_local,
            powers,
        );
        return Ok(Post {
            dac: d.dac,
            dac_ref: d.dac_ref,
            reports: d.reports,
        });
    }
    let mut r = stage("gamma");
    let t = Instant::now();
    let lut = GammaLut::build(&spec, frame_fmt.int_bits);
    let mut dac = vec![0u16; a.frame.acc.len()];
    lut.apply(&a.frame.acc, frame_fmt.frac_bits, &mut dac);
    r.fixed_ms = ms_since(t);
    r.work.insert("lookups".into(), dac.len() as u64);
    r.work.insert("lut_entries".into(), lut.table.len() as u64);
    r.cost = lut.cost();
    r.notes.insert("monotone".into(), lut.is_monotone().into());
    let unreachable = lut.unreachable_codes();
    r.notes.insert(
        "unreachable_dac_codes".into(),
        (unreachable.len() as u64).into(),
    );
    r.notes.insert(
        "first_unreachable".into(),
        serde_json::to_value(unreachable.iter().take(16).collect::<Vec<_>>()).unwrap_or_default(),
    );
    let white = frame_fmt.max_code() >> frame_fmt.frac_bits;
    if opts.stage_local {
        let mut e = LocalError::default();
        for (&acc, &d) in a.frame.acc.iter().zip(&dac) {
            e.add(
                d as f64,
                spec.ideal((acc >> frame_fmt.frac_bits) as f64 / white as f64),
            );
        }
        r.local = Some(e.finish());
    }
    let t = Instant::now();
    let mut dac_ref = vec![0u16; a.frame_ref.len()];
    gamma::apply_powers(&spec, powers, &mut dac_ref);
    r.float_ms = ms_since(t);
    Ok(Post {
        dac,
        dac_ref,
        reports: vec![r],
    })
}

/// The depth-of-field stage's report and its layers as the cycle model sees them.
type DofRun = (StageReport, Vec<LayerWork>);

/// Phase 3 followed by the depth-of-field stage (which plans itself only for a thin lens).
fn accumulate_and_dof(
    f: &Front,
    g: &Geometry,
    scene: &Scene,
    hw: &HwConfig,
    opts: RenderOptions,
    dof_reference: bool,
) -> Result<(Accumulated, Option<DofRun>)> {
    let mut a = accumulate_phase(f, g, hw, opts)?;
    let dof = crate::stage::dof::run_stage(
        scene,
        hw,
        &mut a.frame,
        &mut a.frame_ref,
        opts.stage_local,
        dof_reference,
    )?;
    Ok((a, dof))
}

/// Runs the whole pipeline, fixed and float, and compares them.
pub fn render(scene: &Scene, hw: &HwConfig, opts: RenderOptions) -> Result<Render> {
    render_ext(scene, hw, opts, false)
}

/// [`render`], with `dof_reference` also running the (slow) per-pixel DoF reference.
pub fn render_ext(
    scene: &Scene,
    hw: &HwConfig,
    opts: RenderOptions,
    dof_reference: bool,
) -> Result<Render> {
    render_cached(scene, hw, opts, dof_reference, None)
}

/// Everything a render computes before the gamma/dither post stage: the phases up to the
/// frame memory, the frame-memory and sample-buffer pack checks, the cycle model's workload
/// and its simulation. None of it depends on the `gamma` or `dither` sections, so sweeps
/// share one `Early` between configurations that differ only there
/// ([`crate::sweep::cache`]).
pub struct Early {
    /// Phase 1.
    pub front: Front,
    /// Phase 2.
    pub geometry: Geometry,
    /// Phase 3 (after depth of field for a thin lens).
    pub acc: Accumulated,
    /// The `logdomain` stage report (log codings).
    pub log_stage: Option<StageReport>,
    /// The log frame's adder (log-add coding: the post stage reads a log-coded frame).
    pub log_adder: Option<logdomain::LogAdder>,
    /// The depth-of-field stage report (thin lens).
    pub dof: Option<StageReport>,
    /// Pack checks of the frame memory and of the sample buffer.
    pub packs: [crate::cycles::cost::PackCheck; 2],
    /// The cycle model's token streams.
    pub workload: crate::cycles::Workload,
    /// The cycle simulation of `workload` and its wall time (s).
    pub sim: (crate::cycles::SimResult, f64),
    /// [`Early::reference`] computed so far, by exponent bits.
    references: std::sync::Mutex<Vec<(u64, std::sync::Arc<Reference>)>>,
}

/// The DAC-independent part of the float reference after the gamma curve, for one gamma
/// exponent: what every DAC width and dither of a sweep shares.
pub struct Reference {
    /// `clamp(frame_ref / white, 0, 1)^exponent` per pixel ([`GammaSpec::power`]): the float
    /// reference's gamma before the DAC scale.
    pub powers: Vec<f64>,
    /// The ideal image as the contour metric reads it.
    pub ideal: crate::perceptual::IdealImage,
}

impl Early {
    /// The [`Reference`] for `spec`'s exponent, computed on first use and kept.
    pub fn reference(
        &self,
        scene: &Scene,
        hw: &HwConfig,
        spec: &GammaSpec,
    ) -> std::sync::Arc<Reference> {
        use rayon::prelude::*;
        let key = spec.exponent.to_bits();
        let mut memo = self.references.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, r)) = memo.iter().find(|(k, _)| *k == key) {
            return r.clone();
        }
        let ff = hw.accumulate.frame.format;
        let white_lsb = (ff.max_code() >> ff.frac_bits) as f64 * (1u64 << ff.frac_bits) as f64;
        let powers: Vec<f64> = self
            .acc
            .frame_ref
            .par_iter()
            .map(|&v| spec.power(v / white_lsb))
            .collect();
        let display = DisplayModel::new(&scene.display, hw.gamma.dac_bits);
        let ideal = crate::perceptual::IdealImage::new(
            &powers,
            &display,
            scene.image.width,
            scene.image.height,
        );
        let r = std::sync::Arc::new(Reference { powers, ideal });
        memo.push((key, r.clone()));
        r
    }
}

/// Runs everything before the post stage (see [`Early`]).
pub fn early_phases(
    scene: &Scene,
    hw: &HwConfig,
    opts: RenderOptions,
    dof_reference: bool,
) -> Result<Early> {
    let mut f = front(scene, hw)?;
    let mut g = geometry(&f, hw, opts)?;
    // Log coding: the `logdomain` stage (encoder; potentiation LUT or log accumulation).
    let log_stage = if hw.coding.kind != CodingKind::Linear {
        Some(logdomain::encode_phase(&mut f, &mut g, scene, hw)?)
    } else {
        None
    };
    let (a, log_stage, dof, log_adder) = match (hw.coding.kind == CodingKind::LogAdd, log_stage) {
        (true, Some(mut r)) => {
            let (a, add) = logdomain::accumulate_phase(&f, &g, scene, hw, &mut r, opts)?;
            (a, Some(r), None, Some(add))
        }
        (_, r) => {
            let (a, dof) = accumulate_and_dof(&f, &g, scene, hw, opts, dof_reference)?;
            (a, r, dof, None)
        }
    };
    let (dof, dof_layers) = dof.unzip();
    let workload = crate::cycles::Workload::new(
        g.prim_work.clone(),
        &a.tiles,
        &f.region,
        f.kernel.size,
        &a.tile_rmw,
        hw.accumulate.frame.format.total_bits(),
        dof_layers.as_deref().unwrap_or_default(),
    );
    let t = Instant::now();
    let sim = crate::cycles::simulate(&workload, &hw.cycles, None);
    let sim_wall = t.elapsed().as_secs_f64();
    let packs = [
        pack_frame_memory(&a.frame, hw),
        pack_sample_buffer(f.qprims.len(), &g.samples, hw),
    ];
    Ok(Early {
        front: f,
        geometry: g,
        acc: a,
        log_stage,
        log_adder,
        dof,
        packs,
        workload,
        sim: (sim, sim_wall),
        references: Default::default(),
    })
}

/// [`render_ext`] reusing the phases up to the frame memory (front, geometry, accumulate,
/// depth of field) from `cache` when only late-only fields (gamma, dither) changed; used by
/// sweeps (see [`crate::sweep::cache`]). The result is identical to an uncached render.
pub fn render_cached(
    scene: &Scene,
    hw: &HwConfig,
    opts: RenderOptions,
    dof_reference: bool,
    cache: Option<&crate::sweep::cache::PhaseCache>,
) -> Result<Render> {
    let log_add = hw.coding.kind == CodingKind::LogAdd;
    if log_add && !matches!(scene.camera.lens, crate::scene::Lens::Pinhole) {
        return Err(FileError {
            file: hw.name.clone(),
            line: None,
            col: None,
            field: "coding.kind".into(),
            msg: format!(
                "log-add keeps a log-coded frame memory, but scene `{}` has a thin lens and depth of field needs a linear frame; use log-potentiate, or a pinhole scene (e.g. the embedded `default-pinhole`)",
                scene.name
            ),
        }
        .into());
    }
    let early = match cache {
        Some(c) if hw.coding.kind == CodingKind::Linear => {
            c.early(scene, hw, opts, dof_reference, || {
                early_phases(scene, hw, opts, dof_reference)
            })?
        }
        _ => std::sync::Arc::new(early_phases(scene, hw, opts, dof_reference)?),
    };
    let Early {
        front: f,
        geometry: g,
        acc: a,
        ..
    } = &*early;
    let spec = GammaSpec::new(
        hw.gamma.gamma.unwrap_or(scene.display.gamma),
        hw.gamma.correction,
        hw.gamma.dac_bits,
        hw.gamma.quant,
    );
    let reference = early.reference(scene, hw, &spec);
    let p = match &early.log_adder {
        Some(add) => logdomain::post(a, add, scene, hw, opts),
        None => post(a, scene, hw, opts, &reference.powers)?,
    };
    let (width, height) = (scene.image.width, scene.image.height);
    let codes = compare::codes(&p.dac, &p.dac_ref, hw.gamma.dac_bits);
    let display = DisplayModel::new(&scene.display, hw.gamma.dac_bits);
    let weber = compare::weber(&p.dac, &p.dac_ref, &display);
    let contours = crate::perceptual::contours(&p.dac, &p.dac_ref, &reference.ideal, &display);
    let mut stages = vec![f.input.clone()];
    stages.extend(g.reports.iter().cloned());
    stages.extend(early.log_stage.clone());
    if early.log_adder.is_none() {
        stages.push(a.report.clone());
    }
    stages.extend(early.dof.clone());
    stages.extend(p.reports);
    let overflows = stages
        .iter()
        .flat_map(|s| &s.signals)
        .map(|s| s.overflows)
        .sum();
    let storage_bits = stages.iter().map(|s| s.cost.storage_bits).sum();
    let lut_bits = stages.iter().map(|s| s.cost.lut_bits).sum();
    let [frame_pack, sample_pack] = early.packs.clone();
    let packed = vec![frame_pack, gamma_rom_pack(scene, hw), sample_pack];
    let planned: Vec<String> = stages.iter().map(|s| s.name.clone()).collect();
    let (sim, sim_wall) = &early.sim;
    let cycles = crate::cycles::report_simulated(
        &early.workload,
        &hw.cycles,
        &planned,
        scene.display.refresh_hz,
        crate::cycles::cost::summarize(&stages, packed),
        sim,
        *sim_wall,
    );
    let timing = Timing {
        host_ms: f.host_ms,
        fixed_ms: stages.iter().map(|s| s.fixed_ms).sum(),
        float_ms: stages.iter().map(|s| s.float_ms).sum(),
        threads: rayon::current_num_threads(),
    };
    let report = Report {
        igemu_version: env!("CARGO_PKG_VERSION").into(),
        scene: SceneInfo {
            name: scene.name.clone(),
            width,
            height,
            front_end: f.host.stats.clone(),
        },
        hardware: hw.clone(),
        plan: Plan {
            stages: stages.iter().map(|s| s.name.clone()).collect(),
            region: f.region,
            region_fraction: f.region.pixels() as f64 / (width as f64 * height as f64),
            samples: f.grid.n,
            gamma: hw.gamma.gamma.unwrap_or(scene.display.gamma),
        },
        stages,
        end_to_end: EndToEnd { codes, weber },
        overflows,
        storage_bits,
        lut_bits,
        timing,
        cycles,
        contours: contours.report,
    };
    Ok(Render {
        report,
        dac: p.dac,
        dac_ref: p.dac_ref,
        frame: a.frame.clone(),
        frame_ref: a.frame_ref.clone(),
        dac_bits: hw.gamma.dac_bits,
        workload: early.workload.clone(),
        contour_map: contours.map,
    })
}

/// Packs the frame memory with `bitvec` at its computed size and reads it back (the gamma
/// ROM and the sample buffer have their own checks below).
fn pack_frame_memory(frame: &Frame, hw: &HwConfig) -> crate::cycles::cost::PackCheck {
    let fb = hw.accumulate.frame.format.total_bits();
    crate::cycles::cost::pack(
        "frame memory",
        frame.acc.len(),
        &[fb],
        frame.acc.len() as u64 * fb as u64,
        |r, _| frame.acc[r] as u64,
    )
}

/// Packs the gamma ROM at its computed size and reads it back.
fn gamma_rom_pack(scene: &Scene, hw: &HwConfig) -> crate::cycles::cost::PackCheck {
    let spec = GammaSpec::new(
        hw.gamma.gamma.unwrap_or(scene.display.gamma),
        hw.gamma.correction,
        hw.gamma.dac_bits,
        hw.gamma.quant,
    );
    let lut = GammaLut::build(&spec, hw.accumulate.frame.format.int_bits);
    crate::cycles::cost::pack(
        "gamma ROM",
        lut.table.len(),
        &[hw.gamma.dac_bits],
        lut.cost().lut_bits,
        |r, _| lut.table[r] as u64,
    )
}

/// Packs the modelled region of the sample buffer at its computed size and reads it back.
/// An empty sample slot ("nothing", `u32::MAX` in the model) is stored as the far code (all
/// ones) with the background id.
fn pack_sample_buffer(prims: usize, s: &Samples, hw: &HwConfig) -> crate::cycles::cost::PackCheck {
    use crate::cycles::cost::pack;
    let zb = hw.visibility.z.format.total_bits();
    let ib = hw.input.intensity.format.total_bits();
    let id_bits = (prims as u64 + 1)
        .next_power_of_two()
        .trailing_zeros()
        .max(1);
    let zmax = hw.visibility.z.format.max_code() as u64;
    pack(
        "sample buffer (modelled region)",
        s.z.len(),
        &[zb, ib, id_bits],
        s.z.len() as u64 * (zb + ib + id_bits) as u64,
        |r, k| match k {
            0 => (s.z[r] as u64).min(zmax),
            1 => s.i[r] as u64,
            _ => s.prim[r] as u64,
        },
    )
}

/// The background's intensity code (quantised like a vertex intensity).
fn input_background(host: &HostScene, hw: &HwConfig, white_i: f64) -> u32 {
    let q = hw.input.intensity;
    q.quantize_f64(host.background * white_i * q.format.lsb())
        .code as u32
}
