//! The render report: the plan, every stage's report, the end-to-end comparison of DAC
//! codes (code by code, through the display model, visible contours), the cost summary with
//! the pack checks, the cycle model and the timing.

use super::cache::Cache;
use super::plan::{Plan, PlanReport};
use super::run::Step;
use crate::compare::{self, CodeCompare, DisplayModel, WeberCompare};
use crate::config::{DofSchedule, HwConfig};
use crate::cost;
use crate::cycles::{self, CycleReport, ScreenFacts, SimResult, Workload};
use crate::fnv::Fnv;
use crate::perceptual::{self, ContourReport, IdealImage};
use crate::scene::{FrontEndStats, Scene};
use crate::stage::gamma::{GammaSpec, powers, powers_key};
use crate::stage::{StageId, StageReport, memo};
use serde::Serialize;
use std::sync::Arc;
use std::time::Instant;

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
    pub front_end: FrontEndStats,
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
    /// Sum of the stage-local comparisons.
    pub local_ms: f64,
    /// Threads used.
    pub threads: usize,
    /// Peak resident memory of the process so far, bytes (where the system tells it; the
    /// plan's estimate is `plan.memory`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_memory_bytes: Option<u64>,
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
    pub plan: PlanReport,
    /// Per stage, in run order.
    pub stages: Vec<StageReport>,
    /// Stages whose result came from the cache (sweeps).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub reused: Vec<String>,
    /// End-to-end comparison.
    pub end_to_end: EndToEnd,
    /// Overflows over all signals.
    pub overflows: u64,
    /// Total storage bits (RAM), the streamed depth of field's line buffers included.
    pub storage_bits: u64,
    /// Total LUT / ROM bits.
    pub lut_bits: u64,
    /// Timing.
    pub timing: Timing,
    /// Cycle model, throughput and cost summary.
    pub cycles: CycleReport,
    /// Visible contours through the display model (see [`crate::perceptual`]).
    pub contours: ContourReport,
    /// The errors against the depth-of-field truth (`render --dof-truth`, a thin lens only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dof_truth: Option<crate::truth::TruthReport>,
    /// The channels of a colour render (`None`: grey). The figures above are channel 0's
    /// (R) except the totals (overflows, storage, LUT bits, the cost summary), which count
    /// every channel's lane.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub colour: Option<super::colour::ColourReport>,
}

/// The ideal image the contour metric reads (from the float frame before the gamma stage
/// through the gamma curve), computed once per frame and exponent.
pub(super) struct Ideal {
    pub ideal: Arc<IdealImage>,
    /// Its memo key (the float frame and the gamma spec).
    pub key: u64,
}

/// The gamma spec of a scene and hardware.
pub fn gamma_spec(scene: &Scene, hw: &HwConfig) -> GammaSpec {
    GammaSpec::new(
        hw.gamma.gamma.unwrap_or(scene.display.gamma),
        hw.gamma.correction,
        hw.gamma.dac_bits,
        hw.gamma.quant,
    )
}

/// The ideal image of the frame the gamma curve reads, memoised in `cache`.
pub(super) fn ideal(scene: &Scene, hw: &HwConfig, steps: &[Step], cache: Option<&Cache>) -> Ideal {
    let spec = gamma_spec(scene, hw);
    // The last stage before the first that writes pixels (the gamma LUT, or a dither placed
    // before it): its float frame is what the gamma curve reads.
    let before = steps
        .iter()
        .take_while(|s| s.outcome.taps.float.pixels.is_none())
        .last()
        .expect("a frame stage runs before the pixels are written");
    let frame_ref = before.outcome.taps.float.frame();
    let m: &dyn crate::stage::Memo = match cache {
        Some(c) => c,
        None => &crate::stage::NoMemo,
    };
    let pk = powers_key(before.outcome.taps.float.frame_key(before.key), &spec);
    let powers = memo(m, pk, || powers(frame_ref, hw, &spec));
    let display = DisplayModel::new(&scene.display, hw.gamma.dac_bits);
    let ik = Fnv::new().u64(pk).str("ideal image").finish();
    let ideal = memo(m, ik, || {
        IdealImage::new(
            powers.clone(),
            &display,
            scene.image.width,
            scene.image.height,
        )
    });
    Ideal { ideal, key: ik }
}

/// The DAC codes of `steps` (the last step's) against their float reference: code by code,
/// through the display model and the visible contours, memoised in `cache` by the last
/// step's key, the ideal image and the display. Two sweep rows whose outputs are the same
/// (a field the plan does not read, such as `dither.frac_bits` without a dither) compare
/// once.
pub(super) fn compare_codes(
    (dac, dac_ref): (&[u16], &[u16]),
    steps: &[Step],
    ideal: &Ideal,
    (display, bits): (&DisplayModel, u32),
    cache: Option<&Cache>,
) -> Arc<(EndToEnd, perceptual::Contours)> {
    let make = || {
        let e = EndToEnd {
            codes: compare::codes(dac, dac_ref, bits),
            weber: compare::weber(dac, dac_ref, display),
        };
        (e, perceptual::contours(dac, dac_ref, &ideal.ideal, display))
    };
    let (Some(c), Some(last)) = (cache, steps.last()) else {
        return Arc::new(make());
    };
    let d = display;
    let key = Fnv::new()
        .str("end to end")
        .u64(last.key)
        .u64(ideal.key)
        .u64(u64::from(bits))
        .u64(d.b_min.to_bits())
        .u64(d.b_max.to_bits())
        .u64(d.gamma.to_bits())
        .u64(d.weber.to_bits())
        .finish();
    memo(c, key, make)
}

/// The cycle model's workload of a run: the planned stages' tokens chained under the
/// timings `c` and the depth-of-field `schedule`.
pub fn workload(
    plan: &Plan,
    steps: &[Step],
    c: &crate::config::CyclesCfg,
    schedule: DofSchedule,
) -> Workload {
    let l = &plan.layout;
    let planned: Vec<(StageId, Option<&crate::stage::Tokens>)> = steps
        .iter()
        .map(|s| (s.id, s.outcome.tokens.as_ref()))
        .collect();
    Workload::new(
        &planned,
        c,
        ScreenFacts {
            tile_size: l.tiles.size,
            tiles_touched: l.tiles.count() as u64,
            tiles_total: l.tiles.touched.len() as u64,
            pixels_simulated: l.tiles.touched_pixels(&l.region),
            screen_pixels: l.grid.pixels(),
        },
        schedule,
    )
}

/// The simulation of `w` and its wall time, seconds (reusing a cached one).
fn cached_sim(w: &Workload, cache: Option<&Cache>) -> Arc<(SimResult, f64)> {
    let simulate = || {
        let t = Instant::now();
        let r = cycles::simulate(w, None);
        (r, t.elapsed().as_secs_f64())
    };
    match cache {
        Some(c) => c.sim(w.key(), simulate).0,
        None => Arc::new(simulate()),
    }
}

/// What the fixed model's steps give without a reference: every stage's report, the totals
/// over every channel's lane, the cycle model (reusing a cached simulation) and the timing.
pub(super) struct Totals {
    /// Channel 0's stage reports, in run order.
    pub stages: Vec<StageReport>,
    /// Each channel's streamed depth-of-field line-buffer bits (one entry for grey).
    pub lane_line_bits: Vec<u64>,
    /// The cycle model's workload of each channel lane after the first (colour).
    pub lane_workloads: Vec<Workload>,
    /// Overflows over every lane's signals.
    pub overflows: u64,
    /// RAM bits of every lane, with the streamed depth of field's line buffers.
    pub storage_bits: u64,
    /// ROM / LUT bits of every lane.
    pub lut_bits: u64,
    /// The cycle model on channel 0's steps, with the cost summary of every lane.
    pub cycles: CycleReport,
    /// Its workload.
    pub workload: Workload,
    /// Wall times.
    pub timing: Timing,
}

/// The [`Totals`] of a run's steps.
/// The totals of a run on `full` (every channel's widths; channel 0's steps run on
/// `full.channel(0)`).
pub(super) fn totals(
    scene: &Scene,
    full: &HwConfig,
    plan: &Plan,
    (steps, lanes): (&[Step], &[Vec<Step>]),
    cache: Option<&Cache>,
) -> Totals {
    let hw = &full.channel(0);
    let stages: Vec<StageReport> = steps.iter().map(|s| s.outcome.report.clone()).collect();
    // Totals over every channel's lane.
    let every: Vec<&Step> = steps.iter().chain(lanes.iter().flatten()).collect();
    let all: Vec<StageReport> = every.iter().map(|s| s.outcome.report.clone()).collect();
    let overflows = all
        .iter()
        .flat_map(|s| &s.signals)
        .map(|s| s.overflows)
        .sum();
    let lut_bits = all.iter().map(|s| s.cost.lut_bits).sum();
    let packed = every
        .iter()
        .flat_map(|s| s.outcome.packs.iter().cloned())
        .collect();
    let chosen = workload(plan, steps, &hw.cycles, hw.dof.schedule);
    let other_schedule = match hw.dof.schedule {
        DofSchedule::Stream => DofSchedule::Frame,
        DofSchedule::Frame => DofSchedule::Stream,
    };
    let other = workload(plan, steps, &hw.cycles, other_schedule);
    let workload = chosen;
    // The two schedules' simulations are independent: one on each thread. Without a
    // streaming stage the schedules chain the same stages: one simulation serves both.
    let (sim, other_sim) = if other == workload {
        let sim = cached_sim(&workload, cache);
        (sim.clone(), sim)
    } else {
        rayon::join(
            || cached_sim(&workload, cache),
            || cached_sim(&other, cache),
        )
    };
    let (sim, wall) = (&sim.0, sim.1);
    // Every channel's lane streams its own depth of field, its line buffers as wide as
    // its own frame word.
    let geometry = steps
        .iter()
        .position(|s| s.id == StageId::Visibility)
        .map_or(&steps[..0], |v| &steps[..=v]);
    let lane_workloads: Vec<Workload> = lanes
        .iter()
        .enumerate()
        .map(|(c, l)| {
            let frame: Vec<Step> = geometry.iter().chain(l).cloned().collect();
            let h = full.channel(c + 1);
            self::workload(plan, &frame, &h.cycles, h.dof.schedule)
        })
        .collect();
    let lane_line_bits: Vec<u64> = std::iter::once(workload.line_buffer_bits())
        .chain(lanes.iter().zip(&lane_workloads).map(|(l, w)| {
            if l.iter().any(|s| s.id == StageId::Dof) {
                w.line_buffer_bits()
            } else {
                0
            }
        }))
        .collect();
    let line_bits = lane_line_bits.iter().sum::<u64>();
    // The storage total holds the streamed schedule's line buffers too (the sweep's cost
    // axis reads it).
    let storage_bits = all.iter().map(|s| s.cost.storage_bits).sum::<u64>() + line_bits;
    let cycles = cycles::report(
        &workload,
        plan.order(),
        hw.cycles.clock_mhz,
        scene.display.refresh_hz,
        cost::summarize(&all, packed).with_line_buffers(line_bits),
        sim,
        wall,
        (&other, &other_sim.0),
    );
    let timing = Timing {
        host_ms: plan.host_ms,
        fixed_ms: stages.iter().map(|s| s.fixed_ms).sum(),
        float_ms: stages.iter().map(|s| s.float_ms).sum(),
        local_ms: stages.iter().map(|s| s.local_ms).sum(),
        threads: rayon::current_num_threads(),
        peak_memory_bytes: super::estimate::peak_memory(),
    };
    Totals {
        stages,
        lane_line_bits,
        lane_workloads,
        overflows,
        storage_bits,
        lut_bits,
        cycles,
        workload,
        timing,
    }
}

/// The scene facts of the report.
pub(super) fn scene_info(scene: &Scene, plan: &Plan) -> SceneInfo {
    SceneInfo {
        name: scene.name.clone(),
        width: scene.image.width,
        height: scene.image.height,
        front_end: plan.host.stats.clone(),
    }
}

/// Assembles the report and simulates the cycle model (reusing a cached simulation); also
/// returns every channel lane's workload (channel 0's first) and the contour map.
#[allow(clippy::too_many_arguments)]
pub(super) fn build(
    scene: &Scene,
    full: &HwConfig,
    plan: &Plan,
    steps_lanes: (&[Step], &[Vec<Step>]),
    dac: &[u16],
    dac_ref: &[u16],
    ideal: &Ideal,
    cache: Option<&Cache>,
    opts: crate::stage::RunOptions,
) -> (Report, Vec<Workload>, Vec<u8>) {
    let steps = steps_lanes.0;
    let hw = &full.channel(0);
    let bits = hw.gamma.dac_bits;
    let display = DisplayModel::new(&scene.display, bits);
    let compared = compare_codes((dac, dac_ref), steps, ideal, (&display, bits), cache);
    let (end_to_end, contours) = (compared.0.clone(), &compared.1);
    let t = totals(scene, full, plan, steps_lanes, cache);
    let report = Report {
        igemu_version: env!("CARGO_PKG_VERSION").into(),
        scene: scene_info(scene, plan),
        hardware: full.clone(),
        plan: plan.report(scene, hw, opts),
        stages: t.stages,
        reused: steps
            .iter()
            .filter(|s| s.reused)
            .map(|s| s.id.name().to_string())
            .collect(),
        end_to_end,
        overflows: t.overflows,
        storage_bits: t.storage_bits,
        lut_bits: t.lut_bits,
        timing: t.timing,
        cycles: t.cycles,
        contours: contours.report.clone(),
        dof_truth: None,
        colour: None,
    };
    // Every lane's workload: channel 0's (the report's) first.
    let workloads = std::iter::once(t.workload)
        .chain(t.lane_workloads)
        .collect();
    (report, workloads, contours.map.clone())
}
